#pragma once
/// @file axis_aligned.hpp  The 24 axis-aligned rotations (those mapping coordinate axes to signed
/// coordinate axes), recognised from their quaternions and applied exactly as signed
/// permutation matrices. Used wherever a rotation is applied to integer-grid data that must stay
/// exact: the model layer (placing meshes) and the mesh layer (mesh vs mesh relative frames).
///
/// A quaternion within kAxisAlignedRotationTolerance per component of one of these rotations is
/// taken as that rotation (its components in {0, ±½, ±√½, ±1} are not all representable, so a
/// quarter turn typed as (√½, √½, 0, 0) is never exactly one otherwise).

#include <crux/math.hpp>

#include <limits>
#include <optional>

namespace crux {

/// Per-component distance (in units of |q| = 1) within which a unit quaternion is taken as one
/// of the 24 axis-aligned rotations: 4 ulps of Real, i.e. below the rounding of the rotation
/// itself (a rotation by 4 ulps moves a point by less than rotating it rounds).
inline constexpr Real kAxisAlignedRotationTolerance = 4 * std::numeric_limits<Real>::epsilon();

/// If q is within kAxisAlignedRotationTolerance (per component) of the quaternion of one of the
/// 24 axis-aligned rotations, returns that quaternion with correctly rounded components (in
/// {0, ±½, ±√½, ±1}, same signs as q); else nothing (also for NaN).
std::optional<Quat> snapAxisAligned(const Quat& q);

/// The exact signed-permutation matrix of a quaternion returned by snapAxisAligned.
Mat3 signedPermutation(const Quat& snapped);

}  // namespace crux
