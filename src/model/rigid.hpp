#pragma once
/// @file rigid.hpp  Internal: rigid maps between a model's mesh space and the world, exact for
/// the 24 axis-aligned rotations, and transform composition built on them.

#include <crux/geometry/axis_aligned.hpp>
#include <crux/math.hpp>

#include <optional>

namespace crux::model_detail {

// The 24 axis-aligned rotations live in the geometry layer (axis_aligned.hpp).
using crux::signedPermutation;
using crux::snapAxisAligned;

/// A rigid transform prepared for mapping many points: the rotation as a matrix (the exact
/// signed permutation when the rotation is axis-aligned).
class RigidFrame {
 public:
  explicit RigidFrame(const Transform& t);

  /// Rotation axis-aligned and translation exactly zero: the mapping is skipped.
  bool identity() const { return identity_; }
  /// The rotation is a signed permutation: mapping is exact up to the rounding of p - t.
  bool axisAligned() const { return aligned_; }
  const Mat3& rotation() const { return r_; }
  const Vec3& translation() const { return t_; }

  /// World point to mesh space: Rᵀ(p - t).
  Vec3 toMesh(const Vec3& p) const { return r_.transpose() * (p - t_); }
  /// World direction to mesh space: Rᵀv.
  Vec3 toMeshVector(const Vec3& v) const { return r_.transpose() * v; }
  /// Mesh point to world: R p + t.
  Vec3 toWorld(const Vec3& p) const { return r_ * p + t_; }
  /// Mesh direction to world: R v.
  Vec3 toWorldVector(const Vec3& v) const { return r_ * v; }

 private:
  Mat3 r_;
  Vec3 t_;
  bool aligned_ = false;
  bool identity_ = false;
};

/// a ∘ b (b applied first), with the rotation renormalised and snapped to the exact
/// axis-aligned quaternion when within tolerance, and b's translation rotated exactly when a's
/// rotation is axis-aligned.
Transform compose(const Transform& a, const Transform& b);

/// a⁻¹ ∘ b: b expressed in a's frame (exact under the same conditions as compose).
Transform relative(const Transform& a, const Transform& b);

/// The rotation normalised and snapped (as compose does), for storing user input.
Quat canonicalRotation(const Quat& q);

/// a + b rounded towards -inf / +inf (TwoSum error term decides the direction).
Real addDown(Real a, Real b);
Real addUp(Real a, Real b);

}  // namespace crux::model_detail
