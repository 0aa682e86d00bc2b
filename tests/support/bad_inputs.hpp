#pragma once
/// @file bad_inputs.hpp  Inputs that break the queries' cheap preconditions (queryable(...),
/// precondition.hpp), for the tests that every family answers them with nothing, never UB.

#include <crux/geometry/convex.hpp>
#include <crux/geometry/shapes.hpp>
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

/// Points with one non-finite coordinate.
inline std::vector<Vec3> badPoints() {
  std::vector<Vec3> out;
  for (const Real bad : nonFiniteValues())
    for (int i = 0; i < 3; ++i) {
      Vec3 v(Real(0.2), Real(0.3), Real(0.1));
      v[i] = bad;
      out.push_back(v);
    }
  return out;
}

/// Each primitive shape broken in each of its ways (precondition.hpp's rule::kPrimitive): a
/// non-finite coordinate or radius, a zero ray direction or plane normal, a negative radius or
/// half extent, min > max. For the primitive layer's tests: its answers to these are unspecified,
/// but never undefined behaviour.
struct BadPrimitives {
  std::vector<Ray> rays;
  std::vector<Segment> segments;
  std::vector<Sphere> spheres;
  std::vector<Aabb> aabbs;
  std::vector<Obb> obbs;
  std::vector<Plane> planes;
  std::vector<Triangle> triangles;
  std::vector<Vec3> points = badPoints();
};

inline BadPrimitives badPrimitives() {
  BadPrimitives b;
  const Vec3 o(Real(0.2), Real(0.2), 2), down(0, 0, -1);
  for (const Vec3& v : b.points) {
    b.rays.push_back(Ray{v, down});
    b.rays.push_back(Ray{o, v});
    b.segments.push_back(Segment{v, Vec3(Real(0.2), Real(0.2), -2)});
    b.spheres.push_back(Sphere{v, Real(0.5)});
    b.aabbs.push_back(Aabb{Vec3::Zero(), v});
    b.obbs.push_back(Obb{v, Vec3::Constant(Real(0.5)), Mat3::Identity()});
    b.obbs.push_back(Obb{Vec3::Zero(), v, Mat3::Identity()});
    b.planes.push_back(Plane{v, 0});
    b.triangles.push_back(Triangle{Vec3::Zero(), Vec3(1, 0, 0), v});
  }
  for (const Real bad : nonFiniteValues()) {
    b.spheres.push_back(Sphere{Vec3::Zero(), bad});
    b.planes.push_back(Plane{Vec3(0, 0, 1), bad});
    Obb axes{Vec3::Zero(), Vec3::Constant(Real(0.5)), Mat3::Identity()};
    axes.axes(1, 2) = bad;
    b.obbs.push_back(axes);
  }
  b.rays.push_back(Ray{o, Vec3::Zero()});
  b.spheres.push_back(Sphere{Vec3::Zero(), -1});
  b.aabbs.push_back(Aabb{Vec3(1, 0, 0), Vec3(0, 1, 1)});
  b.obbs.push_back(Obb{Vec3::Zero(), Vec3(Real(0.5), Real(-0.5), Real(0.5)), Mat3::Identity()});
  b.planes.push_back(Plane{Vec3::Zero(), 0});
  return b;
}

}  // namespace crux::test_support
