#pragma once
/// @file bad_inputs.hpp  Inputs that break the queries' cheap preconditions (queryable(...),
/// precondition.hpp), for the tests that every family answers them with nothing, never UB.

#include <crux/geometry/convex.hpp>
#include <crux/math.hpp>

#include <limits>
#include <vector>

namespace crux::test_support {

/// NaN, +inf and -inf.
inline std::vector<Real> nonFiniteValues() {
  return {std::numeric_limits<Real>::quiet_NaN(), std::numeric_limits<Real>::infinity(),
          -std::numeric_limits<Real>::infinity()};
}

/// Poses with a non-finite translation or rotation component, and a zero rotation.
inline std::vector<Transform> badPoses() {
  std::vector<Transform> out;
  for (const Real bad : nonFiniteValues())
    for (int i = 0; i < 3; ++i) {
      Transform t;
      t.translation[i] = bad;
      out.push_back(t);
      Transform r;
      r.rotation.coeffs()[i] = bad;
      out.push_back(r);
    }
  Transform zero;
  zero.rotation.coeffs().setZero();
  out.push_back(zero);
  return out;
}

/// Shapes with a non-finite coordinate or radius, a negative radius or half extent.
inline std::vector<ConvexShape> badShapes() {
  std::vector<ConvexShape> out;
  for (const Real bad : nonFiniteValues()) {
    out.push_back(Sphere{Vec3(bad, 0, 0), Real(0.5)});
    out.push_back(Sphere{Vec3::Zero(), bad});
    out.push_back(Capsule{Vec3::Zero(), Vec3(0, bad, 0), Real(0.2)});
    out.push_back(Obb{Vec3::Zero(), Vec3(Real(0.5), bad, Real(0.5)), Mat3::Identity()});
    Obb axes{Vec3::Zero(), Vec3::Constant(Real(0.5)), Mat3::Identity()};
    axes.axes(1, 2) = bad;
    out.push_back(axes);
    out.push_back(Triangle{Vec3::Zero(), Vec3(1, 0, 0), Vec3(0, 0, bad)});
  }
  out.push_back(Sphere{Vec3::Zero(), -1});
  out.push_back(Obb{Vec3::Zero(), Vec3(Real(0.5), Real(-0.5), Real(0.5)), Mat3::Identity()});
  return out;
}

}  // namespace crux::test_support
