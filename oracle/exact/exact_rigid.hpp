#pragma once
/// @file exact_rigid.hpp  Internal: rigid transforms with exact (rational) coefficients, for
/// placing model meshes exactly. Included only by oracle/exact/*.cpp.
///
/// A rotation is kept as a quaternion q = (w, x, y, z) with exact components, not necessarily
/// unit: its matrix M(q)/|q|², whose entries are quadratic in q divided by |q|², is exactly
/// orthogonal in the rationals (it is the rotation q/|q| denotes), so no square root is ever
/// taken. Composition multiplies the quaternions exactly (Hamilton product) and adds the exactly
/// rotated translation.
///
/// Axis-aligned snapping, the documented rule of crux's model layer (model_query.hpp): a unit
/// quaternion within kAxisAlignedRotationTolerance per component (in Real, after normalising in
/// Real) of one of the 24 rotations that map coordinate axes to signed coordinate axes is that
/// rotation. Its quaternion's non-zero components all have the same magnitude (1, √½ or ½), so
/// the exact rotation is the one of the sign quaternion (components in {0, ±1}), scaled freely.
/// The rule is applied to every local transform and, as crux's compose() does, to every
/// composed world rotation (judged on its double approximation); a snapped rotation is then an
/// exact signed permutation, as in crux. (The correctly rounded quaternion of one of the 24 has
/// equal non-zero components, so q/|q| is exact already; snapping matters for components rounded
/// differently, e.g. (0.70710677, 0, 0, 0.70710683), which crux takes as the quarter turn.)

#include "exact/exact_kernel.hpp"

#include <crux/math.hpp>

#include <array>
#include <optional>

namespace crux::exact::detail {

/// If the quaternion (w, x, y, z), normalised in Real, snaps to one of the 24 axis-aligned
/// rotations by crux's rule, the sign quaternion of that rotation (components in {0, ±1}).
std::optional<std::array<int, 4>> snapAxisAligned(const Real (&q)[4]);

/// x -> R x + t with R = M(q)/|q|² exactly.
class ExactRigid {
 public:
  /// The identity.
  ExactRigid();
  /// How a crux transform's rotation is read.
  enum class Rotation {
    Snapped,  ///< snapped when axis-aligned (the model layer's rule)
    AsGiven,  ///< the rotation of q/|q| exactly, never snapped
  };
  /// A crux transform taken exactly.
  explicit ExactRigid(const Transform& tf, Rotation rotation = Rotation::Snapped);

  /// a ∘ b (b applied first), exactly; the product rotation snapped like crux's compose().
  static ExactRigid compose(const ExactRigid& a, const ExactRigid& b);

  Point apply(const Point& p) const;
  Point apply(const Vec3& p) const { return apply(toPoint(p)); }
  /// Whether the rotation is an exact signed permutation (snapped).
  bool axisAligned() const { return axisAligned_; }
  /// Interval enclosures (CGAL::to_interval) of R's entries, [rLo, rHi], and of t's, [tLo, tHi]:
  /// for conservative double bounds of placed points (LazyPlaced in exact_distance.cpp).
  void enclosures(double rLo[3][3], double rHi[3][3], double tLo[3], double tHi[3]) const;

 private:
  void setRotation(const std::array<FT, 4>& q);

  std::array<FT, 4> q_;  ///< (w, x, y, z), not necessarily unit
  FT r_[3][3];           ///< M(q)/|q|²
  FT t_[3];
  bool axisAligned_ = true;
};

}  // namespace crux::exact::detail
