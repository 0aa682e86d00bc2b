#pragma once
/// @file math.hpp  Scalar and linear-algebra types of crux (Eigen underneath).

#include <crux/config.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace crux {

#if CRUX_DOUBLE_PRECISION_ENABLED
/// The scalar of every public crux type: double (CRUX_DOUBLE_PRECISION=ON).
using Real = double;
#else
/// The scalar of every public crux type: float (the default, like Bullet and Jolt).
using Real = float;
#endif

/// Scalar in which boolean predicates are evaluated. Every Real converts to it exactly, and
/// the integer-grid guarantee (|coordinates| <= 64 give exact answers) rests on its 53-bit
/// mantissa holding each predicate's polynomial exactly (see docs/geometry.md).
using Wide = double;

using Vec3 = Eigen::Matrix<Real, 3, 1>;
using Mat3 = Eigen::Matrix<Real, 3, 3>;
using Quat = Eigen::Quaternion<Real>;
using WVec3 = Eigen::Matrix<Wide, 3, 1>;

/// Converts a Vec3 to the predicate scalar (exact).
inline WVec3 wide(const Vec3& v) { return v.cast<Wide>(); }

/// A rigid transform: x -> rotation * x + translation. `rotation` is a unit quaternion.
struct Transform {
  Quat rotation = Quat::Identity();
  Vec3 translation = Vec3::Zero();

  /// The identity transform.
  static Transform identity() { return {}; }
  /// Maps a point.
  Vec3 apply(const Vec3& p) const { return rotation * p + translation; }
  /// Maps a direction (rotation only).
  Vec3 applyVector(const Vec3& v) const { return rotation * v; }
  /// The inverse transform.
  Transform inverse() const {
    Transform t;
    t.rotation = rotation.conjugate();
    t.translation = -(t.rotation * translation);
    return t;
  }
  /// Composition: (a * b).apply(x) == a.apply(b.apply(x)) (b applied first).
  friend Transform operator*(const Transform& a, const Transform& b) {
    Transform t;
    t.rotation = (a.rotation * b.rotation).normalized();
    t.translation = a.rotation * b.translation + a.translation;
    return t;
  }
};

}  // namespace crux
