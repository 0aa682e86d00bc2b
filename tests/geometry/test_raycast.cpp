// Tests of src/geometry/raycast.cpp: regression tests named after the degenerate cases the
// book's code gets wrong, a watertightness test on closed meshes, and seeded property tests
// against the exact CGAL oracle (crux::exact) in an integer-grid and a general-position family.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <crux/geometry/raycast.hpp>
#include <cstdio>
#include <cstdlib>
#include <exact/exact.hpp>

#include "geometry/ray_triangle.hpp"
#include "mesh/ray_kernel.hpp"
#include <iomanip>
#include <limits>
#include <optional>
#include <type_traits>
#include <utility>
#include <random>
#include <sstream>
#include <string>
#include <vector>
#include <crux/precondition.hpp>
#include "geometry/unchecked.hpp"
#include "support/bad_inputs.hpp"
#include "support/test_scale.hpp"  // CRUX_TEST_SCALE: fewer cases in the sanitizer stage

namespace crux {
namespace {

constexpr Real kEps = std::numeric_limits<Real>::epsilon();
using exact::Vec3d;

// ---------------------------------------------------------------------------------------------
// Printing (17 significant digits: every case printed on a failure can be pasted back).

std::string str(const Vec3& v) {
  std::ostringstream os;
  os.precision(17);
  os << "Vec3(" << double(v.x()) << ", " << double(v.y()) << ", " << double(v.z()) << ")";
  return os.str();
}
std::string str(double x) {
  std::ostringstream os;
  os.precision(17);
  os << x;
  return os.str();
}
std::string str(const Ray& r) { return "Ray{" + str(r.origin) + ", " + str(r.dir) + "}"; }
std::string str(const Segment& s) { return "Segment{" + str(s.start) + ", " + str(s.end) + "}"; }
std::string str(const Triangle& t) {
  return "Triangle{" + str(t.a) + ", " + str(t.b) + ", " + str(t.c) + "}";
}
std::string str(const Sphere& s) { return "Sphere{" + str(s.center) + ", " + str(double(s.radius)) + "}"; }
std::string str(const Aabb& b) { return "Aabb{" + str(b.min) + ", " + str(b.max) + "}"; }
std::string str(const Plane& p) { return "Plane{" + str(p.normal) + ", " + str(double(p.d)) + "}"; }
std::string str(const Obb& b) {
  return "Obb{" + str(b.center) + ", " + str(b.half) + ", axes " + str(Vec3(b.axes.col(0))) + " " +
         str(Vec3(b.axes.col(1))) + " " + str(Vec3(b.axes.col(2))) + "}";
}
std::string str(const std::optional<RayHit>& h) {
  if (!h) return "miss";
  return "hit t=" + str(double(h->t)) + " point " + str(h->point) + " normal " + str(h->normal);
}
std::string str(const std::optional<double>& t) { return t ? "hit t=" + str(*t) : "miss"; }

// ---------------------------------------------------------------------------------------------
// Checks shared by regression and property tests.

/// Invariants every reported hit must satisfy: finite, t >= 0, unit normal facing the origin
/// (normal·dir <= 0 up to rounding), point = origin + t·dir/|dir|.
::testing::AssertionResult wellFormed(const Ray& r, const RayHit& h, Real scale) {
  const Vec3 u = r.dir.normalized();
  const Real tol = 64 * kEps * (scale + h.t);
  if (!std::isfinite(h.t) || !h.point.allFinite() || !h.normal.allFinite())
    return ::testing::AssertionFailure() << "non-finite hit";
  if (h.t < 0) return ::testing::AssertionFailure() << "negative t " << h.t;
  if (std::abs(h.normal.norm() - 1) > 64 * kEps) return ::testing::AssertionFailure() << "normal not unit";
  if (h.normal.dot(u) > 64 * kEps)
    return ::testing::AssertionFailure() << "normal faces away from the origin";
  if ((r.origin + h.t * u - h.point).norm() > tol)
    return ::testing::AssertionFailure() << "point is not origin + t dir/|dir|";
  return ::testing::AssertionSuccess();
}

// ---------------------------------------------------------------------------------------------
// Regression tests (errata of the book's ray tests).

Triangle tri(Vec3 a, Vec3 b, Vec3 c) { return {a, b, c}; }

TEST(RaycastTriangle, RayAtSharedEdgeHitsOneOfTwoTriangles) {
  // Two planar quads (one axis-aligned, one tilted: exact integer corners on x + 2y + 3z = 6),
  // each split along its diagonal a-c. Rays are aimed at points of the shared diagonal from
  // random origins on both sides; the crossing point lies (up to rounding of dir) on the
  // diagonal, deep inside the quad, so one of the two triangles must report a hit. The book's
  // plane + barycentric test lost about 6% of such rays.
  struct Quad {
    Vec3 a, b, c, d;
  };
  const Quad quads[] = {
      {Vec3(0, 0, 0), Vec3(64, 0, 0), Vec3(64, 64, 0), Vec3(0, 64, 0)},
      {Vec3(6, 0, 0), Vec3(0, 3, 0), Vec3(-6, 0, 4), Vec3(0, -3, 4)},
  };
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> along(0.02, 0.98), pos(-100, 100);
  int rays = 0, misses = 0, both = 0;
  for (const Quad& q : quads) {
    const Triangle t1{q.a, q.b, q.c}, t2{q.a, q.c, q.d};
    const Vec3 n = (q.b - q.a).cross(q.c - q.a).normalized();
    for (int i = 0; i < 20000; ++i) {
      const Vec3 target = q.a + Real(along(rng)) * (q.c - q.a);
      Vec3 origin(Real(pos(rng)), Real(pos(rng)), Real(pos(rng)));
      if (std::abs((origin - target).normalized().dot(n)) < Real(0.05)) continue;  // grazing
      const Ray ray{origin, target - origin};
      const auto h1 = raycast(ray, t1), h2 = raycast(ray, t2);
      ++rays;
      if (!h1 && !h2) {
        ++misses;
        if (misses <= 5)
          ADD_FAILURE() << "both triangles missed: " << str(ray) << " " << str(t1) << " " << str(t2);
      }
      both += h1 && h2;
    }
  }
  EXPECT_GT(rays, 30000);
  EXPECT_EQ(misses, 0) << "of " << rays << " rays";
  // Integer-exact rays through grid points of the diagonal of the first quad hit both.
  for (int k = 1; k < 64; ++k) {
    const Vec3 target = Vec3(Real(k), Real(k), 0);
    const Ray ray{Vec3(Real(k % 7), Real(-(k % 5)), 9), target - Vec3(Real(k % 7), Real(-(k % 5)), 9)};
    EXPECT_TRUE(raycast(ray, tri(quads[0].a, quads[0].b, quads[0].c)).has_value()) << str(ray);
    EXPECT_TRUE(raycast(ray, tri(quads[0].a, quads[0].c, quads[0].d)).has_value()) << str(ray);
  }
}

TEST(RaycastTriangle, RayFromBehindHitsBackFace) {
  const Triangle t = tri(Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0));  // CCW normal +z
  const Ray fromBelow{Vec3(Real(0.5), Real(0.5), -3), Vec3(0, 0, 2)};
  const auto back = raycast(fromBelow, t);
  ASSERT_TRUE(back.has_value());
  EXPECT_EQ(back->t, 3);
  EXPECT_EQ(back->point, Vec3(Real(0.5), Real(0.5), 0));
  EXPECT_EQ(back->normal, Vec3(0, 0, -1));  // faces the origin
  const Ray fromAbove{Vec3(Real(0.5), Real(0.5), 3), Vec3(0, 0, -1)};
  const auto front = raycast(fromAbove, t);
  ASSERT_TRUE(front.has_value());
  EXPECT_EQ(front->t, 3);
  EXPECT_EQ(front->normal, Vec3(0, 0, 1));
  // Pointing away from the triangle: the plane is behind the origin.
  EXPECT_FALSE(raycast(Ray{Vec3(Real(0.5), Real(0.5), -3), Vec3(0, 0, -1)}, t).has_value());
}

TEST(RaycastTriangle, RayStartingOnTrianglePlane) {
  const Triangle t = tri(Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(0, 4, 0));
  // On the triangle (interior, edge, vertex): t = 0 whatever the direction.
  for (const Vec3& o : {Vec3(1, 1, 0), Vec3(2, 0, 0), Vec3(0, 4, 0)}) {
    for (const Vec3& d : {Vec3(0, 0, 1), Vec3(0, 0, -1), Vec3(1, 2, 3), Vec3(1, 0, 0)}) {
      const auto h = raycast(Ray{o, d}, t);
      ASSERT_TRUE(h.has_value()) << str(Ray{o, d});
      EXPECT_EQ(h->t, 0);
      EXPECT_EQ(h->point, o);
    }
  }
  // In the plane but outside the triangle, leaving the plane: miss.
  EXPECT_FALSE(raycast(Ray{Vec3(5, 5, 0), Vec3(0, 0, 1)}, t).has_value());
  EXPECT_FALSE(raycast(Ray{Vec3(-1, 1, 0), Vec3(1, 0, 1)}, t).has_value());
  // Segment starting on the plane outside the triangle and leaving it: no intersection.
  EXPECT_FALSE(intersects(Segment{Vec3(5, 5, 0), Vec3(-1, -1, 3)}, t));
  EXPECT_TRUE(intersects(Segment{Vec3(1, 1, 0), Vec3(-1, -1, 3)}, t));
}

TEST(RaycastTriangle, RayInTrianglePlane) {
  const Triangle t = tri(Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(0, 4, 0));
  // Enters across the edge x = 0 at (0, 1, 0).
  auto h = raycast(Ray{Vec3(-2, 1, 0), Vec3(3, 0, 0)}, t);
  ASSERT_TRUE(h.has_value());
  EXPECT_EQ(h->t, 2);
  EXPECT_EQ(h->point, Vec3(0, 1, 0));
  EXPECT_EQ(std::abs(h->normal.z()), 1);  // the plane normal, either side
  // Along the edge y = 0 from outside: first point is the vertex (0, 0, 0).
  h = raycast(Ray{Vec3(-3, 0, 0), Vec3(1, 0, 0)}, t);
  ASSERT_TRUE(h.has_value());
  EXPECT_EQ(h->t, 3);
  // Along the hypotenuse x + y = 4 from (-1, 5): first point is the vertex (0, 4, 0).
  h = raycast(Ray{Vec3(-1, 5, 0), Vec3(1, -1, 0)}, t);
  ASSERT_TRUE(h.has_value());
  EXPECT_NEAR(h->t, std::sqrt(Real(2)), 4 * kEps);
  // Touching only the vertex (4, 0, 0).
  h = raycast(Ray{Vec3(6, 1, 0), Vec3(-2, -1, 0)}, t);
  ASSERT_TRUE(h.has_value());
  EXPECT_NEAR(h->t, std::sqrt(Real(5)), 8 * kEps);
  EXPECT_EQ(h->point, Vec3(4, 0, 0));
  // Missing the triangle in its plane, and pointing away from it.
  EXPECT_FALSE(raycast(Ray{Vec3(-2, 5, 0), Vec3(1, 0, 0)}, t).has_value());
  EXPECT_FALSE(raycast(Ray{Vec3(-2, 1, 0), Vec3(-1, 0, 0)}, t).has_value());
  // From (6, -2) (on the hypotenuse's line) the triangle spans the directions (-1, 1)..(-3, 1).
  EXPECT_TRUE(raycast(Ray{Vec3(6, -2, 0), Vec3(-1, Real(0.5), 0)}, t).has_value());
  EXPECT_FALSE(raycast(Ray{Vec3(6, -2, 0), Vec3(-1, Real(1.5), 0)}, t).has_value());
  EXPECT_FALSE(raycast(Ray{Vec3(6, -2, 0), Vec3(-1, Real(0.2), 0)}, t).has_value());
  // A segment in the plane stopping short of the triangle / reaching its edge.
  EXPECT_FALSE(intersects(Segment{Vec3(-2, 1, 0), Vec3(-1, 1, 0)}, t));
  EXPECT_TRUE(intersects(Segment{Vec3(-2, 1, 0), Vec3(0, 1, 0)}, t));
}

TEST(RaycastTriangle, RayThroughDegenerateTriangleSegment) {
  const Triangle seg = tri(Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(4, 0, 0));  // the segment [0, 4] on x
  auto h = raycast(Ray{Vec3(1, -3, 0), Vec3(0, 1, 0)}, seg);
  ASSERT_TRUE(h.has_value());
  EXPECT_EQ(h->t, 3);
  EXPECT_EQ(h->point, Vec3(1, 0, 0));
  EXPECT_TRUE(wellFormed(Ray{Vec3(1, -3, 0), Vec3(0, 1, 0)}, *h, 4));
  EXPECT_FALSE(raycast(Ray{Vec3(1, -3, 1), Vec3(0, 1, 0)}, seg).has_value());  // skew
  EXPECT_FALSE(raycast(Ray{Vec3(5, -3, 0), Vec3(0, 1, 0)}, seg).has_value());  // beyond the end
  h = raycast(Ray{Vec3(-2, 0, 0), Vec3(1, 0, 0)}, seg);                        // along it
  ASSERT_TRUE(h.has_value());
  EXPECT_EQ(h->t, 2);
  h = raycast(Ray{Vec3(3, 0, 0), Vec3(0, 0, 1)}, seg);  // origin on it
  ASSERT_TRUE(h.has_value());
  EXPECT_EQ(h->t, 0);
  // The middle corner must not matter (c between a and b, repeated corners).
  EXPECT_TRUE(raycast(Ray{Vec3(4, -1, 0), Vec3(0, 1, 0)}, tri(Vec3(2, 0, 0), Vec3(4, 0, 0), Vec3(0, 0, 0)))
                  .has_value());
  EXPECT_TRUE(raycast(Ray{Vec3(4, -1, 0), Vec3(0, 1, 0)}, tri(Vec3(4, 0, 0), Vec3(4, 0, 0), Vec3(0, 0, 0)))
                  .has_value());
  // A triangle collapsed to a point.
  const Triangle pt = tri(Vec3(1, 1, 1), Vec3(1, 1, 1), Vec3(1, 1, 1));
  h = raycast(Ray{Vec3(0, 0, 0), Vec3(2, 2, 2)}, pt);
  ASSERT_TRUE(h.has_value());
  EXPECT_NEAR(h->t, std::sqrt(Real(3)), 4 * kEps);
  EXPECT_FALSE(raycast(Ray{Vec3(0, 0, 0), Vec3(1, 1, 2)}, pt).has_value());
  EXPECT_FALSE(raycast(Ray{Vec3(0, 0, 0), Vec3(-1, -1, -1)}, pt).has_value());
  // Segments against degenerate triangles.
  EXPECT_TRUE(intersects(Segment{Vec3(1, -1, 0), Vec3(1, 1, 0)}, seg));
  EXPECT_FALSE(intersects(Segment{Vec3(1, -1, 0), Vec3(1, -Real(0.5), 0)}, seg));
  EXPECT_TRUE(intersects(Segment{Vec3(1, 1, 1), Vec3(1, 1, 1)}, pt));
  EXPECT_TRUE(intersects(Segment{Vec3(0, 0, 0), Vec3(3, 3, 3)}, pt));
}

TEST(RaycastTriangle, SegmentWithCoincidentEndpointsIsAPointTest) {
  const Triangle t = tri(Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(0, 4, 0));
  EXPECT_TRUE(intersects(Segment{Vec3(1, 1, 0), Vec3(1, 1, 0)}, t));
  EXPECT_TRUE(intersects(Segment{Vec3(2, 2, 0), Vec3(2, 2, 0)}, t));  // on the hypotenuse
  EXPECT_FALSE(intersects(Segment{Vec3(3, 3, 0), Vec3(3, 3, 0)}, t));
  EXPECT_FALSE(intersects(Segment{Vec3(1, 1, 1), Vec3(1, 1, 1)}, t));
  // A segment ending exactly on the triangle touches it.
  EXPECT_TRUE(intersects(Segment{Vec3(1, 1, 5), Vec3(1, 1, 0)}, t));
  EXPECT_FALSE(intersects(Segment{Vec3(1, 1, 5), Vec3(1, 1, 1)}, t));
}

TEST(RaycastSphere, RayBehindSphereMisses) {
  const Sphere s{Vec3(0, 0, -5), 1};
  EXPECT_FALSE(raycast(Ray{Vec3(0, 0, 0), Vec3(0, 0, 1)}, s).has_value());
  EXPECT_FALSE(raycast(Ray{Vec3(0, 0, -3), Vec3(0, 0, 1)}, s).has_value());  // just left it
  const auto h = raycast(Ray{Vec3(0, 0, 0), Vec3(0, 0, -1)}, s);
  ASSERT_TRUE(h.has_value());
  EXPECT_EQ(h->t, 4);
  EXPECT_EQ(h->normal, Vec3(0, 0, 1));
  // Tangent ray: touching counts.
  const auto tangent = raycast(Ray{Vec3(1, 0, 0), Vec3(0, 0, -3)}, s);
  ASSERT_TRUE(tangent.has_value());
  EXPECT_EQ(tangent->t, 5);
  EXPECT_FALSE(raycast(Ray{Vec3(1, 0, 0), Vec3(0, 0, 3)}, s).has_value());
}

TEST(RaycastSphere, RayOriginInsideSphereHitsAtZero) {
  const Sphere s{Vec3(1, 2, 3), 2};
  for (const Vec3& o : {Vec3(1, 2, 3), Vec3(2, 2, 3), Vec3(1, 2, 5) /* on the surface */}) {
    const Ray r{o, Vec3(0, 0, 2)};
    const auto h = raycast(r, s);
    ASSERT_TRUE(h.has_value());
    EXPECT_EQ(h->t, 0);
    EXPECT_EQ(h->point, o);
    EXPECT_EQ(h->normal, Vec3(0, 0, -1));
  }
  // A point sphere (radius 0) is hit only by rays through its centre.
  const Sphere p{Vec3(3, 0, 0), 0};
  const auto h = raycast(Ray{Vec3(0, 0, 0), Vec3(1, 0, 0)}, p);
  ASSERT_TRUE(h.has_value());
  EXPECT_EQ(h->t, 3);
  EXPECT_FALSE(raycast(Ray{Vec3(0, 0, 0), Vec3(1, Real(1e-3), 0)}, p).has_value());
}

TEST(RaycastAabb, ParallelRayJustOutsideSlabMisses) {
  const Aabb box{Vec3(0, 0, 0), Vec3(1, 1, 1)};
  // The book replaces the zero component by +1e-5: a ray 1e-4 above the slab then "hits".
  EXPECT_FALSE(raycast(Ray{Vec3(-1, Real(1.0001), Real(0.5)), Vec3(1, 0, 0)}, box).has_value());
  EXPECT_FALSE(raycast(Ray{Vec3(-1, Real(-0.0001), Real(0.5)), Vec3(1, 0, 0)}, box).has_value());
  EXPECT_FALSE(intersects(Segment{Vec3(-1, Real(1.0001), Real(0.5)), Vec3(2, Real(1.0001), Real(0.5))}, box));
  // On the slab boundary: touching hits.
  const auto h = raycast(Ray{Vec3(-1, 1, Real(0.5)), Vec3(2, 0, 0)}, box);
  ASSERT_TRUE(h.has_value());
  EXPECT_EQ(h->t, 1);
  EXPECT_EQ(h->normal, Vec3(-1, 0, 0));
  // Flat box (zero extent in z) hit by a ray in its plane and by one crossing it.
  const Aabb flat{Vec3(0, 0, 2), Vec3(1, 1, 2)};
  EXPECT_TRUE(raycast(Ray{Vec3(-1, Real(0.5), 2), Vec3(1, 0, 0)}, flat).has_value());
  const auto cross = raycast(Ray{Vec3(Real(0.5), Real(0.5), 0), Vec3(0, 0, 1)}, flat);
  ASSERT_TRUE(cross.has_value());
  EXPECT_EQ(cross->t, 2);
  EXPECT_EQ(cross->normal, Vec3(0, 0, -1));
  // The same ray against an OBB whose slab it runs parallel to.
  const Obb obb{Vec3(Real(0.5), Real(0.5), Real(0.5)), Vec3(Real(0.5), Real(0.5), Real(0.5)),
                Mat3::Identity()};
  EXPECT_FALSE(raycast(Ray{Vec3(-1, Real(1.0001), Real(0.5)), Vec3(1, 0, 0)}, obb).has_value());
  EXPECT_TRUE(raycast(Ray{Vec3(-1, 1, Real(0.5)), Vec3(1, 0, 0)}, obb).has_value());
}

TEST(RaycastAabb, SegmentInsideBoxIntersects) {
  const Aabb box{Vec3(0, 0, 0), Vec3(1, 1, 1)};
  const Segment inside{Vec3(Real(0.2), Real(0.3), Real(0.4)), Vec3(Real(0.8), Real(0.7), Real(0.6))};
  EXPECT_TRUE(intersects(inside, box));
  EXPECT_TRUE(intersects(Segment{inside.start, inside.start}, box));  // a point inside
  EXPECT_FALSE(intersects(Segment{Vec3(2, 2, 2), Vec3(2, 2, 2)}, box));
  EXPECT_FALSE(intersects(Segment{Vec3(2, 2, 2), Vec3(3, 0, 0)}, box));
  EXPECT_TRUE(intersects(Segment{Vec3(2, 2, 2), Vec3(1, 1, 1)}, box));  // ends on a corner
  // Rotated box (45° about z): a segment wholly inside it.
  Obb obb;
  obb.center = Vec3(5, 5, 5);
  obb.half = Vec3(2, 1, 1);
  obb.axes = Quat(Eigen::AngleAxis<Real>(Real(EIGEN_PI / 4), Vec3::UnitZ())).toRotationMatrix();
  const Segment in{obb.center - Real(0.5) * obb.axes.col(0), obb.center + Real(0.5) * obb.axes.col(0)};
  EXPECT_TRUE(intersects(in, obb));
  EXPECT_TRUE(raycast(Ray{in.start, in.end - in.start}, obb).has_value());
  EXPECT_EQ(raycast(Ray{in.start, in.end - in.start}, obb)->t, 0);
}

TEST(RaycastPlane, RayInPlaneHitsAtZero) {
  const Plane p{Vec3(0, 0, 2), 4};  // z = 2
  auto h = raycast(Ray{Vec3(1, 1, 2), Vec3(1, 0, 0)}, p);
  ASSERT_TRUE(h.has_value());
  EXPECT_EQ(h->t, 0);
  EXPECT_FALSE(raycast(Ray{Vec3(1, 1, 3), Vec3(1, 0, 0)}, p).has_value());  // parallel, off the plane
  EXPECT_FALSE(raycast(Ray{Vec3(1, 1, 3), Vec3(0, 0, 1)}, p).has_value());  // receding
  h = raycast(Ray{Vec3(1, 1, 5), Vec3(0, 0, -2)}, p);
  ASSERT_TRUE(h.has_value());
  EXPECT_EQ(h->t, 3);
  EXPECT_EQ(h->normal, Vec3(0, 0, 1));
  h = raycast(Ray{Vec3(1, 1, -1), Vec3(0, 0, 1)}, p);  // from the other side
  ASSERT_TRUE(h.has_value());
  EXPECT_EQ(h->normal, Vec3(0, 0, -1));
  EXPECT_TRUE(intersects(Segment{Vec3(0, 0, 2), Vec3(0, 0, 2)}, p));
  EXPECT_TRUE(intersects(Segment{Vec3(0, 0, 0), Vec3(0, 0, 2)}, p));
  EXPECT_FALSE(intersects(Segment{Vec3(0, 0, 0), Vec3(0, 0, 1)}, p));
}

TEST(Raycast, HitsBeyondMaxTAreMisses) {
  const Triangle t = tri(Vec3(-1, -1, 5), Vec3(3, -1, 5), Vec3(-1, 3, 5));
  const Ray r{Vec3(0, 0, 0), Vec3(0, 0, 1)};
  EXPECT_TRUE(raycast(r, t, 5).has_value());
  EXPECT_FALSE(raycast(r, t, Real(4.5)).has_value());
  const Sphere s{Vec3(0, 0, 6), 1};
  EXPECT_TRUE(raycast(r, s, 5).has_value());
  EXPECT_FALSE(raycast(r, s, Real(4.99)).has_value());
  const Aabb b{Vec3(-1, -1, 5), Vec3(1, 1, 6)};
  EXPECT_TRUE(raycast(r, b, 5).has_value());
  EXPECT_FALSE(raycast(r, b, Real(4.99)).has_value());
  const Obb o{Vec3(0, 0, Real(5.5)), Vec3(1, 1, Real(0.5)), Mat3::Identity()};
  EXPECT_TRUE(raycast(r, o, 5).has_value());
  EXPECT_FALSE(raycast(r, o, Real(4.99)).has_value());
  const Plane p{Vec3(0, 0, 1), 5};
  EXPECT_TRUE(raycast(r, p, 5).has_value());
  EXPECT_FALSE(raycast(r, p, Real(4.99)).has_value());
  // t at the origin passes maxT = 0.
  EXPECT_TRUE(raycast(Ray{Vec3(0, 0, 5), Vec3(1, 0, 0)}, p, 0).has_value());
}

TEST(Raycast, TinyAndHugeInputsGiveFiniteAnswers) {
  // Coordinates 1e-20 and 1e18 apart: v - o rounds the tiny shapes to single points, and the
  // answer must still be the (rounded) hit, never NaN or a spurious hit at the origin.
  const Real tiny = Real(1e-20), huge = Real(1e18);
  const Triangle t = tri(Vec3(0, 0, 0), Vec3(tiny, 0, 0), Vec3(0, tiny, 0));
  const Sphere s{Vec3::Zero(), tiny};
  const Aabb b{Vec3::Zero(), Vec3::Constant(tiny)};
  const Plane p{Vec3(tiny, tiny, 1), 0};
  const Ray down{Vec3(tiny / 4, tiny / 4, 1), Vec3(0, 0, -huge)};  // hits everything at t = 1
  const Ray far{Vec3(huge, huge, huge), Vec3(-1, -1, -1)};         // hits everything at t = huge·√3
  for (const auto& [ray, expected] : {std::pair<Ray, Real>{down, 1}, {far, huge * std::sqrt(Real(3))}}) {
    const Real tol = 8 * kEps * expected;
    const std::optional<RayHit> hits[] = {raycast(ray, t), raycast(ray, s), raycast(ray, b), raycast(ray, p)};
    for (const auto& h : hits) {
      ASSERT_TRUE(h.has_value()) << str(ray);
      EXPECT_NEAR(h->t, expected, tol) << str(ray);
      EXPECT_TRUE(wellFormed(ray, *h, 4 * huge)) << str(ray);
    }
  }
  // A grazing ray through the tiny triangle's edge: whatever rounding decides, no NaN.
  const Ray grazing{Vec3(-1, Real(0.5) * tiny, tiny), Vec3(1, 0, -tiny)};
  if (const auto h = raycast(grazing, t)) EXPECT_TRUE(wellFormed(grazing, *h, 4));
}

TEST(Raycast, DirectionsAndNormalsBeyondTheSquareRootOfWideStayFinite) {
  // |d|² and |(b − a) × (c − a)|² overflow Wide when components pass ~√max Wide (double builds):
  // the length and the normal are taken after a power-of-two scaling, so a long direction still
  // gives the world distance and a triangle far out a unit normal. In float builds every
  // Real is far below √max Wide; the checks hold there too.
  const Real big = std::sqrt(std::numeric_limits<Real>::max()) * 4;  // big² overflows Real
  const Triangle t = tri(Vec3(-10, -10, 0), Vec3(30, -10, 0), Vec3(-10, 30, 0));
  // (a direction whose |d|² underflows is refused by validate(Ray): no parameter is meaningful)
  for (const Real length : {big, Real(-big)}) {
    const Ray ray{Vec3(0, 0, 5), Vec3(length, 0, -big)};
    for (const auto& h : {raycast(ray, t), raycast(ray, Plane{Vec3(0, 0, 1), 0}),
                          raycast(ray, Aabb{Vec3(-10, -10, -1), Vec3(10, 10, 0)})}) {
      ASSERT_TRUE(h.has_value()) << str(ray);
      EXPECT_NEAR(h->t, 5 * std::sqrt(Real(2)), 8 * kEps * 10) << str(ray);
      EXPECT_EQ(h->normal, Vec3(0, 0, 1)) << str(ray) << " normal " << str(h->normal);
    }
  }
  // A triangle whose edges are ~max/8: (b − a) × (c − a) overflows any Wide; the hit's normal is
  // still the unit plane normal, facing the ray.
  const Real m = std::numeric_limits<Real>::max() / 8;
  const Triangle far = tri(Vec3(-m, -m, 1), Vec3(m, -m, 1), Vec3(-m, m, 1));
  const auto h = raycast(Ray{Vec3(0, 0, 3), Vec3(0, 0, -1)}, far);
  ASSERT_TRUE(h.has_value());
  EXPECT_EQ(h->t, 2);
  EXPECT_EQ(h->normal, Vec3(0, 0, 1)) << str(h->normal);
}

// ---------------------------------------------------------------------------------------------
// Watertightness on closed meshes.

struct Mesh {
  std::vector<Vec3> v;
  std::vector<std::array<int, 3>> f;
  Triangle triangle(std::size_t i) const { return {v[f[i][0]], v[f[i][1]], v[f[i][2]]}; }
};

/// The cube [-n, n]³ with each face cut into n×n squares of side 2 and each square into two
/// triangles, alternating diagonals: every interior vertex has valence 4 or 8.
Mesh subdividedCube(int n) {
  Mesh m;
  auto vertex = [&](const Vec3& p) {
    for (std::size_t i = 0; i < m.v.size(); ++i)
      if (m.v[i] == p) return int(i);
    m.v.push_back(p);
    return int(m.v.size() - 1);
  };
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = -1; side <= 1; side += 2) {
      const int u = (axis + 1) % 3, w = (axis + 2) % 3;
      auto at = [&](int i, int j) {
        Vec3 p;
        p[axis] = Real(side * n);
        p[u] = Real(-n + 2 * i);
        p[w] = Real(-n + 2 * j);
        return vertex(p);
      };
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
          const int a = at(i, j), b = at(i + 1, j), c = at(i + 1, j + 1), d = at(i, j + 1);
          if ((i + j) % 2 == 0) {
            m.f.push_back({a, b, c});
            m.f.push_back({a, c, d});
          } else {
            m.f.push_back({a, b, d});
            m.f.push_back({b, c, d});
          }
        }
      }
    }
  }
  return m;
}

/// The octahedron with vertices ±r on each axis (8 faces).
Mesh octahedron(int r) {
  Mesh m;
  for (int axis = 0; axis < 3; ++axis)
    for (int s = -1; s <= 1; s += 2) {
      Vec3 p = Vec3::Zero();
      p[axis] = Real(s * r);
      m.v.push_back(p);
    }
  for (int sx = 0; sx < 2; ++sx)
    for (int sy = 0; sy < 2; ++sy)
      for (int sz = 0; sz < 2; ++sz) m.f.push_back({sx, 2 + sy, 4 + sz});
  return m;
}

bool hitsMesh(const Mesh& m, const Ray& r) {
  for (std::size_t i = 0; i < m.f.size(); ++i)
    if (raycast(r, m.triangle(i))) return true;
  return false;
}

/// Every vertex and every edge midpoint of the mesh (the points where leaks happen).
std::vector<Vec3> vertexAndEdgeTargets(const Mesh& m) {
  std::vector<Vec3> targets = m.v;
  for (const auto& f : m.f)
    for (int k = 0; k < 3; ++k) targets.push_back((m.v[f[k]] + m.v[f[(k + 1) % 3]]) / 2);
  return targets;
}

TEST(RaycastTriangle, WatertightOnClosedIntegerMeshes) {
  const Mesh meshes[] = {subdividedCube(4), octahedron(8)};
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<int> coord(-16, 16);
  std::uniform_real_distribution<double> inner(-0.9, 0.9);
  for (const Mesh& m : meshes) {
    const std::vector<Vec3> targets = vertexAndEdgeTargets(m);  // integer (even coordinates)
    const Real radius = m.v[0].cwiseAbs().maxCoeff();
    int rays = 0;
    for (const Vec3& target : targets) {
      // Exact integer rays from origins outside and inside the mesh (all on the grid, so the
      // direction target - origin is exact and the ray passes exactly through the target).
      for (int k = 0; k < 24; ++k) {
        const Vec3 o(Real(coord(rng)), Real(coord(rng)), Real(coord(rng)));
        if (o == target) continue;
        const Ray r{o, target - o};
        ++rays;
        EXPECT_TRUE(hitsMesh(m, r)) << "ray through a mesh vertex/edge missed: " << str(r);
      }
      // Rays from random interior points (not on the grid, so the direction is rounded): a ray
      // leaving a closed mesh's interior must cross it, wherever rounding moved it.
      for (int k = 0; k < 16; ++k) {
        const Vec3 o = Real(0.3) * radius * Vec3(Real(inner(rng)), Real(inner(rng)), Real(inner(rng)));
        const Ray r{o, target - o};
        ++rays;
        EXPECT_TRUE(hitsMesh(m, r)) << "ray from inside a closed mesh missed: " << str(r);
      }
    }
    EXPECT_GE(rays, 30 * int(targets.size()));
  }
}

TEST(RaycastTriangle, WatertightOnClosedMeshesWithRandomVertices) {
  // The same closed meshes with every vertex moved by a random non-grid offset (shared vertices
  // stay shared): rays from interior points aimed at vertices and edge midpoints pass within
  // rounding of them, where the edge functions of all incident triangles are nearly zero.
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> jitter(-0.4, 0.4), inner(-0.25, 0.25);
  const Mesh meshes[] = {subdividedCube(4), octahedron(8)};
  for (Mesh m : meshes) {
    for (Vec3& v : m.v) v += Vec3(Real(jitter(rng)), Real(jitter(rng)), Real(jitter(rng)));
    const Real radius = 4;
    int rays = 0, misses = 0;
    for (const Vec3& target : vertexAndEdgeTargets(m)) {
      for (int k = 0; k < 16; ++k) {
        const Vec3 o = radius * Vec3(Real(inner(rng)), Real(inner(rng)), Real(inner(rng)));
        const Ray r{o, target - o};
        ++rays;
        if (!hitsMesh(m, r) && ++misses <= 5)
          ADD_FAILURE() << "ray from inside a closed mesh missed: " << str(r);
      }
    }
    EXPECT_EQ(misses, 0) << "of " << rays << " rays";
  }
}

// ---------------------------------------------------------------------------------------------
// Property tests against the exact oracle.

/// Family of generated cases: integer grid (exact answers required, frequent touching,
/// coplanar and degenerate cases) or general position (random floats).
enum class Family { Grid, General };

struct Rng {
  std::mt19937_64 gen;
  explicit Rng(std::uint64_t seed) : gen(seed) {}
  int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(gen); }
  Real real(double lo, double hi) { return Real(std::uniform_real_distribution<double>(lo, hi)(gen)); }
  bool chance(double p) { return std::uniform_real_distribution<double>(0, 1)(gen) < p; }
  Vec3 gridPoint(int r) { return Vec3(Real(integer(-r, r)), Real(integer(-r, r)), Real(integer(-r, r))); }
  Vec3 point(double r) { return Vec3(real(-r, r), real(-r, r), real(-r, r)); }
  /// A random signed permutation matrix (orthonormal, exact).
  Mat3 signedPermutation() {
    int p[3] = {0, 1, 2};
    std::shuffle(p, p + 3, gen);
    Mat3 m = Mat3::Zero();
    for (int i = 0; i < 3; ++i) m(p[i], i) = chance(0.5) ? Real(1) : Real(-1);
    return m;
  }
  Mat3 rotation() {
    Eigen::Quaternion<double> q(
        std::normal_distribution<double>()(gen), std::normal_distribution<double>()(gen),
        std::normal_distribution<double>()(gen), std::normal_distribution<double>()(gen));
    return q.normalized().toRotationMatrix().cast<Real>();
  }
};

/// Tolerance on |t_crux - t_exact| for one case:
///   kDistanceUlps · eps(Real) · (S + t) · cond,  S = |o| + |dir| + extent of the shape.
/// Justification: rounding t to Real costs eps(Real)·t/2, and t is a difference of points
/// whose coordinates are bounded by S; the exact oracle's own double rounding is a few ulps of
/// double. On the integer grid crux's fraction num/den is exact and only the final
/// division, sqrt and product round, so cond = 1. In general position the inputs themselves
/// are rounded in Wide arithmetic (backward error ~eps·S per coordinate), and moving a surface
/// by δ moves the first hit by δ/cos θ (θ = angle between the ray and the surface normal at
/// the exact hit), so cond = 1/cos θ, the condition number of the hit distance.
constexpr Real kDistanceUlps = 4;

Real extent(const Triangle& t) { return (std::max)({t.a.norm(), t.b.norm(), t.c.norm()}); }
Real extent(const Sphere& s) { return s.center.norm() + s.radius; }
Real extent(const Aabb& b) { return (std::max)(b.min.norm(), b.max.norm()); }
Real extent(const Obb& b) { return b.center.norm() + b.half.norm(); }
Real extent(const Plane& p) { return std::abs(p.d) / p.normal.norm(); }

/// cos θ at the exact hit point q (see kDistanceUlps); 1 for hits at t = 0. (The triangle's
/// normal in long double: a flat cap's edges are nearly antiparallel, and their cross product in
/// double builds' Real would tilt it by ~eps·L/h.)
double cosAtHit(const Ray& r, const Triangle& t, const Vec3d&) {
  using L3 = Eigen::Matrix<long double, 3, 1>;
  const L3 n = (t.b.cast<long double>() - t.a.cast<long double>()).cross(t.c.cast<long double>() - t.a.cast<long double>());
  return double(std::abs(n.normalized().dot(r.dir.cast<long double>().normalized())));
}
double cosAtHit(const Ray& r, const Sphere& s, const Vec3d& q) {
  const Vec3d n = q - s.center.cast<double>();
  return std::abs(n.normalized().dot(r.dir.cast<double>().normalized()));
}
double slabCos(const Vec3d& dir, const Vec3d& local, const Vec3d& lo, const Vec3d& hi) {
  int best = 0;
  double bestGap = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    const double gap = (std::min)(std::abs(local[i] - lo[i]), std::abs(local[i] - hi[i]));
    if (gap < bestGap) bestGap = gap, best = i;
  }
  return std::abs(dir.normalized()[best]);
}
double cosAtHit(const Ray& r, const Aabb& b, const Vec3d& q) {
  return slabCos(r.dir.cast<double>(), q, b.min.cast<double>(), b.max.cast<double>());
}
double cosAtHit(const Ray& r, const Obb& b, const Vec3d& q) {
  const Eigen::Matrix3d a = b.axes.cast<double>();
  const Vec3d local = a.transpose() * (q - b.center.cast<double>());
  return slabCos(a.transpose() * r.dir.cast<double>(), local, -b.half.cast<double>(), b.half.cast<double>());
}
double cosAtHit(const Ray& r, const Plane& p, const Vec3d&) {
  return std::abs(p.normal.cast<double>().normalized().dot(r.dir.cast<double>().normalized()));
}

struct Stats {
  int cases = 0, hits = 0, mismatches = 0, distanceFailures = 0, malformed = 0;
  double worstRatio = 0;  ///< max |t - t_exact| / tolerance
};

constexpr int kMaxReported = 5;

/// Compares crux and the exact oracle on n generated ray cases.
template <class Shape, class Gen>
Stats compareRays(Family family, std::uint64_t seed, int n, Gen gen) {
  Rng rng(seed);
  Stats st;
  for (int i = 0; i < n; ++i) {
    Ray ray;
    Shape shape;
    gen(rng, ray, shape);
    validate(ray);
    validate(shape);
    const auto got = raycast(ray, shape);
    const auto want = exact::raycast(ray, shape);
    ++st.cases;
    st.hits += want.has_value();
    auto what = [&] {
      return "case " + std::to_string(i) + ": " + str(ray) + " vs " + str(shape) + "\n  crux: " + str(got) +
             "\n  exact: " + str(want);
    };
    if (got.has_value() != want.has_value()) {
      if (++st.mismatches <= kMaxReported) ADD_FAILURE() << "hit/miss mismatch, " << what();
      continue;
    }
    if (!got) continue;
    const Real scale = ray.origin.norm() + ray.dir.norm() + extent(shape);
    if (!wellFormed(ray, *got, scale)) {
      if (++st.malformed <= kMaxReported)
        ADD_FAILURE() << wellFormed(ray, *got, scale).message() << ", " << what();
    }
    double cond = 1;
    if (family == Family::General && *want > 0) {
      const Vec3d q = ray.origin.cast<double>() + *want * ray.dir.cast<double>().normalized();
      cond = 1 / cosAtHit(ray, shape, q);
    }
    const double tol = double(kDistanceUlps) * double(kEps) * (double(scale) + *want) * cond;
    const double err = std::abs(double(got->t) - *want);
    st.worstRatio = (std::max)(st.worstRatio, err / tol);
    if (!(err <= tol)) {
      if (++st.distanceFailures <= kMaxReported)
        ADD_FAILURE() << "distance off by " << str(err) << " > tolerance " << str(tol) << ", " << what();
    }
  }
  return st;
}

/// Compares crux and the exact oracle on n generated segment cases.
template <class Shape, class Gen>
Stats compareSegments(std::uint64_t seed, int n, Gen gen) {
  Rng rng(seed);
  Stats st;
  for (int i = 0; i < n; ++i) {
    Segment seg;
    Shape shape;
    gen(rng, seg, shape);
    validate(seg);
    validate(shape);
    const bool got = intersects(seg, shape);
    const bool want = exact::intersects(seg, shape);
    ++st.cases;
    st.hits += want;
    if (got != want && ++st.mismatches <= kMaxReported)
      ADD_FAILURE() << "mismatch, case " << i << ": " << str(seg) << " vs " << str(shape)
                    << "\n  crux: " << got << "  exact: " << want;
  }
  return st;
}

void expectGood(const Stats& st, const char* name) {
  const double rate = double(st.hits) / st.cases;
  std::printf("  %-34s %7d cases, hit rate %5.1f%%, mismatches %d, worst |dt|/tol %.3g\n", name, st.cases,
              100 * rate, st.mismatches, st.worstRatio);
  EXPECT_EQ(st.mismatches, 0) << name;
  EXPECT_EQ(st.distanceFailures, 0) << name;
  EXPECT_EQ(st.malformed, 0) << name;
  EXPECT_GE(rate, 0.2) << name << ": generator too sparse";
  EXPECT_LE(rate, 0.8) << name << ": generator too dense";
}

/// Cases per family and op (each op gets kCases grid + kCases general-position cases);
/// the environment variable CRUX_RAYCAST_CASES overrides it for longer (or quicker) runs.
constexpr int kCases = 100000;

int casesPerFamily() {
  const char* env = std::getenv("CRUX_RAYCAST_CASES");
  return env ? std::atoi(env) : kCases;
}

// ---- generators -------------------------------------------------------------------------

/// A direction from o towards an integer combination of the points (weights in [-1, 2],
/// sum w >= 1): d = Σ w_i p_i - (Σ w_i) o passes exactly through the rational point
/// Σ w_i p_i / Σ w_i (a vertex, an edge point, an interior or a nearby outside point).
Vec3 nonZero(Rng& rng, int r);

Vec3 aimAt(Rng& rng, const Vec3& o, const Vec3* p, int n) {
  for (int attempt = 0; attempt < 16; ++attempt) {
    Vec3 sum = Vec3::Zero();
    int w = 0;
    for (int i = 0; i < n; ++i) {
      const int k = rng.integer(-1, 2);
      sum += Real(k) * p[i];
      w += k;
    }
    if (w < 1) continue;
    const Vec3 d = sum - Real(w) * o;
    if (!d.isZero(0)) return d;
  }
  return nonZero(rng, 4);  // o is the only point aimed at (a point triangle)
}

Vec3 nonZero(Rng& rng, int r) {
  for (;;) {
    const Vec3 v = rng.gridPoint(r);
    if (!v.isZero(0)) return v;
  }
}

/// Integer triangle in [-4, 4]³; 10% collinear (segment) and 3% single-point triangles.
Triangle gridTriangle(Rng& rng) {
  Triangle t{rng.gridPoint(4), rng.gridPoint(4), rng.gridPoint(4)};
  const double kind = std::uniform_real_distribution<double>(0, 1)(rng.gen);
  if (kind < 0.10)
    t.c = t.a + Real(rng.integer(-1, 2)) * (t.b - t.a);
  else if (kind < 0.13)
    t.b = t.c = t.a;
  return t;
}

Triangle generalTriangle(Rng& rng) { return {rng.point(4), rng.point(4), rng.point(4)}; }

void gridRayTriangle(Rng& rng, Ray& r, Triangle& t) {
  t = gridTriangle(rng);
  const Vec3 e1 = t.b - t.a, e2 = t.c - t.a;
  if (rng.chance(0.2)) {
    // In the triangle's plane (coplanar ray), origin at an integer combination of the edges.
    r.origin = t.a + Real(rng.integer(-2, 2)) * e1 + Real(rng.integer(-2, 2)) * e2;
    r.dir = Real(rng.integer(-2, 2)) * e1 + Real(rng.integer(-2, 2)) * e2;
    if (r.dir.isZero(0)) r.dir = nonZero(rng, 3);
    return;
  }
  r.origin = rng.gridPoint(6);
  const Vec3 p[3] = {t.a, t.b, t.c};
  r.dir = rng.chance(0.85) ? aimAt(rng, r.origin, p, 3) : nonZero(rng, 4);
}

void generalRayTriangle(Rng& rng, Ray& r, Triangle& t) {
  t = generalTriangle(rng);
  r.origin = rng.point(8);
  // Aim at a random point of the triangle's plane around it (barycentrics in [-0.1, 1]).
  const Real u = rng.real(-0.1, 1), v = rng.real(-0.1, 1);
  r.dir = t.a + u * (t.b - t.a) + v * (t.c - t.a) - r.origin;
}

/// A flat cap (as `crux diff`'s sliver family): corners a, b in [-4, 4]³ and their midpoint
/// moved, in half of the cases 1-4 ulps of Real along one axis (height ~1e-7 of the longest
/// edge in float builds, ~1e-16 in double ones), in the others by 10^-k |b − a| (k uniform in
/// [1, 15]) in a random direction; corners in a random order; the ray from a random origin aimed
/// at a random point of the cap (its direction rounded: many miss the thinnest caps).
void flatCapRayTriangle(Rng& rng, Ray& r, Triangle& t) {
  const Vec3 a = rng.point(4), b = rng.point(4);
  Vec3 m = Real(0.5) * (a + b);
  if (rng.chance(0.5)) {
    const int axis = rng.integer(0, 2);
    const Real toward = rng.chance(0.5) ? std::numeric_limits<Real>::infinity() : -std::numeric_limits<Real>::infinity();
    for (int i = rng.integer(1, 4); i > 0; --i) m[axis] = std::nextafter(m[axis], toward);
  } else {
    m += rng.point(1).normalized() * Real(std::pow(10.0, -double(rng.real(1, 15)))) * (b - a).norm();
  }
  switch (rng.integer(0, 2)) {
    case 0: t = {a, b, m}; break;
    case 1: t = {b, m, a}; break;
    default: t = {m, a, b};
  }
  r.origin = rng.point(8);
  Real u = rng.real(0, 1), v = rng.real(0, 1);
  if (u + v > 1) u = 1 - u, v = 1 - v;
  r.dir = t.a + u * (t.b - t.a) + v * (t.c - t.a) - r.origin;
}

void gridRaySphere(Rng& rng, Ray& r, Sphere& s) {
  s.center = rng.gridPoint(4);
  s.radius = Real(rng.integer(0, 4));
  r.origin = rng.gridPoint(8);
  const int k = (std::max)(int(s.radius), 1);
  do r.dir = s.center + rng.gridPoint(k) - r.origin;
  while (r.dir.isZero(0));
}

void generalRaySphere(Rng& rng, Ray& r, Sphere& s) {
  s.center = rng.point(4);
  s.radius = rng.real(0.1, 4);
  r.origin = rng.point(8);
  r.dir = s.center + rng.point(1.4 * s.radius) - r.origin;
}

void gridRayAabb(Rng& rng, Ray& r, Aabb& b) {
  b.min = rng.gridPoint(4);
  b.max = b.min;
  for (int i = 0; i < 3; ++i) b.max[i] += Real(rng.chance(0.15) ? 0 : rng.integer(1, 4));
  r.origin = rng.gridPoint(8);
  do {
    Vec3 target;
    const int margin = rng.chance(0.3) ? 0 : 1;  // target in the box, or around it
    for (int i = 0; i < 3; ++i) target[i] = Real(rng.integer(int(b.min[i]) - margin, int(b.max[i]) + margin));
    r.dir = target - r.origin;
  } while (r.dir.isZero(0));
}

void generalRayAabb(Rng& rng, Ray& r, Aabb& b) {
  const Vec3 c = rng.point(4), h(rng.real(0.05, 3), rng.real(0.05, 3), rng.real(0.05, 3));
  b = {c - h, c + h};
  r.origin = rng.point(8);
  r.dir = c + Vec3(rng.real(-1.6, 1.6) * h.x(), rng.real(-1.6, 1.6) * h.y(), rng.real(-1.6, 1.6) * h.z()) -
          r.origin;
}

void gridRayObb(Rng& rng, Ray& r, Obb& b) {
  b.center = rng.gridPoint(4);
  for (int i = 0; i < 3; ++i) b.half[i] = Real(rng.chance(0.1) ? 0 : rng.integer(1, 3));
  b.axes = rng.signedPermutation();
  r.origin = rng.gridPoint(8);
  do {
    Vec3 local;
    const int margin = rng.chance(0.3) ? 0 : 1;  // target in the box, or around it
    for (int i = 0; i < 3; ++i)
      local[i] = Real(rng.integer(-int(b.half[i]) - margin, int(b.half[i]) + margin));
    r.dir = b.center + b.axes * local - r.origin;
  } while (r.dir.isZero(0));
}

void generalRayObb(Rng& rng, Ray& r, Obb& b) {
  b.center = rng.point(4);
  b.half = Vec3(rng.real(0.05, 3), rng.real(0.05, 3), rng.real(0.05, 3));
  b.axes = rng.rotation();
  r.origin = rng.point(8);
  const Vec3 local(rng.real(-1.6, 1.6) * b.half.x(), rng.real(-1.6, 1.6) * b.half.y(),
                   rng.real(-1.6, 1.6) * b.half.z());
  r.dir = b.center + b.axes * local - r.origin;
}

void gridRayPlane(Rng& rng, Ray& r, Plane& p) {
  p.normal = nonZero(rng, 3);
  const Vec3 q = rng.gridPoint(4);
  p.d = p.normal.dot(q);
  const Vec3 inPlane = p.normal.cross(nonZero(rng, 2));
  r.origin = rng.chance(0.15) ? Vec3(q + Real(rng.integer(-2, 2)) * inPlane) : rng.gridPoint(8);
  r.dir = rng.chance(0.15) && !inPlane.isZero(0) ? inPlane : nonZero(rng, 4);
}

void generalRayPlane(Rng& rng, Ray& r, Plane& p) {
  p.normal = rng.point(3);
  p.d = p.normal.dot(rng.point(4));
  r.origin = rng.point(8);
  r.dir = rng.point(8) - r.origin;
}

/// Segment generators: the ray generator's origin as start; the end at parameter 1 or 2 of
/// its direction (which passes through the aimed point, on the shape's boundary for a share
/// of the grid cases), or 1/2 (stopping short); 5% zero-length segments.
template <class Shape, class RayGen>
auto segmentFrom(RayGen rayGen, bool grid) {
  return [rayGen, grid](Rng& rng, Segment& s, Shape& shape) {
    Ray r;
    rayGen(rng, r, shape);
    s.start = r.origin;
    if (rng.chance(0.05)) {
      s.end = s.start;
      return;
    }
    const Real k = grid ? Real(rng.integer(1, 2)) : rng.real(0.5, 3);
    s.end = (grid && rng.chance(0.3)) ? Vec3(r.origin + r.dir / 2) : Vec3(r.origin + k * r.dir);
  };
}

// ---- the property tests -----------------------------------------------------------------

template <class Shape, class G1, class G2>
void rayProperty(const char* name, std::uint64_t seed, G1 grid, G2 general) {
  const auto t0 = std::chrono::steady_clock::now();
  expectGood(compareRays<Shape>(Family::Grid, seed, casesPerFamily(), grid),
             (std::string(name) + " (grid)").c_str());
  expectGood(compareRays<Shape>(Family::General, seed + 1, casesPerFamily(), general),
             (std::string(name) + " (general)").c_str());
  std::printf("  %s: %.2f s\n", name,
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
}

template <class Shape, class G1, class G2>
void segmentProperty(const char* name, std::uint64_t seed, G1 grid, G2 general) {
  const auto t0 = std::chrono::steady_clock::now();
  expectGood(compareSegments<Shape>(seed, casesPerFamily(), segmentFrom<Shape>(grid, true)),
             (std::string(name) + " (grid)").c_str());
  expectGood(compareSegments<Shape>(seed + 1, casesPerFamily(), segmentFrom<Shape>(general, false)),
             (std::string(name) + " (general)").c_str());
  std::printf("  %s: %.2f s\n", name,
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
}

TEST(RaycastProperty, RayTriangleMatchesExact) {
  rayProperty<Triangle>("ray-triangle", 1001, gridRayTriangle, generalRayTriangle);
}
// Flat caps: the plane from the cross product of two nearly antiparallel edges is tilted by
// ~eps·L/h, so a hit parameter from it (the filter stage's n·a / n·d) can miss the exact one by
// far more than the tolerance in double builds (found by `crux diff`'s sliver family, session
// 11: 2-4x the native backend's τ). The filter's error bound on that ratio sends such hits to
// the exact stage (raycast.cpp, kRayParameterUlps).
TEST(RaycastProperty, RayFlatCapMatchesExact) {
  expectGood(compareRays<Triangle>(Family::General, 1011, casesPerFamily(), flatCapRayTriangle),
             "ray-triangle (flat caps)");
}

TEST(RaycastProperty, RaySphereMatchesExact) {
  rayProperty<Sphere>("ray-sphere", 1003, gridRaySphere, generalRaySphere);
}
TEST(RaycastProperty, RayAabbMatchesExact) {
  rayProperty<Aabb>("ray-aabb", 1005, gridRayAabb, generalRayAabb);
}
TEST(RaycastProperty, RayObbMatchesExact) { rayProperty<Obb>("ray-obb", 1007, gridRayObb, generalRayObb); }
TEST(RaycastProperty, RayPlaneMatchesExact) {
  rayProperty<Plane>("ray-plane", 1009, gridRayPlane, generalRayPlane);
}
TEST(RaycastProperty, SegmentTriangleMatchesExact) {
  segmentProperty<Triangle>("segment-triangle", 2001, gridRayTriangle, generalRayTriangle);
}
TEST(RaycastProperty, SegmentSphereMatchesExact) {
  segmentProperty<Sphere>("segment-sphere", 2003, gridRaySphere, generalRaySphere);
}
TEST(RaycastProperty, SegmentAabbMatchesExact) {
  segmentProperty<Aabb>("segment-aabb", 2005, gridRayAabb, generalRayAabb);
}
TEST(RaycastProperty, SegmentObbMatchesExact) {
  segmentProperty<Obb>("segment-obb", 2007, gridRayObb, generalRayObb);
}
TEST(RaycastProperty, SegmentPlaneMatchesExact) {
  segmentProperty<Plane>("segment-plane", 2009, gridRayPlane, generalRayPlane);
}

// Found by fuzz_geometry (tests/fuzz/corpus/geometry/crash-ray-plane-infinite-t): a ray almost
// parallel to a plane meets it so far away that t overflows Real; it was reported as a hit at
// t = inf with an infinite point. Such a hit is beyond every representable point: a miss.
// properRayTriangleCrossing (the mesh kernel's certified path, static error bounds) against
// raycast's exact decision: for the lines the mesh kernel's float filter proves to cross a
// triangle's interior (its contract) it either defers (-1) or decides hit or miss exactly, with
// a parameter within raycast's accuracy rule (kRayParameterUlps ulps of Real × (S + t) / cos θ)
// of the exact one. (Not always raycast's bits: where raycast's filter stage is unsure of
// another sign, raycast takes its exact stage, which may round the parameter differently.)
// The cases press on its bounds (in double builds: a float origin is never that near a plane): origins a hair off the plane on either side, near-grazing directions, far origins, large and
// tiny coordinates, long thin triangles.
TEST(RaycastProperty, CertifiedCrossingIsRaycastsOwnAnswerOrDefers) {
  std::mt19937_64 rng(20261129);
  std::uniform_real_distribution<double> unit(-1, 1), weight(0.05, 1);
  const double scales[] = {1e-6, 1, 1e3, 1e6};
  int decided = 0, deferred = 0;
  const int cases = test::scaledCases(100000, 20000);
  for (int i = 0; i < cases; ++i) {
    const double scale = scales[i % 4];
    const Vec3 base(Real(unit(rng) * scale), Real(unit(rng) * scale), Real(unit(rng) * scale));
    auto corner = [&](double size) {
      return Vec3(base + Vec3(Real(unit(rng) * size), Real(unit(rng) * size), Real(unit(rng) * size)));
    };
    const double size = scale * (i % 3 == 0 ? 1e-3 : 0.3);
    const Triangle t{corner(size), corner(size), i % 5 == 0 ? corner(size * 1e-3) : corner(size)};
    // a point well inside, in Wide: its rounding moves it by far less than its margin
    const double w0 = weight(rng), w1 = weight(rng), w2 = weight(rng), sum = w0 + w1 + w2;
    const WVec3 inside = (wide(t.a) * w0 + wide(t.b) * w1 + wide(t.c) * w2) / sum;
    const WVec3 n = (wide(t.b) - wide(t.a)).cross(wide(t.c) - wide(t.a));
    if (!(n.norm() > 1e-3 * (wide(t.b) - wide(t.a)).squaredNorm())) continue;  // not a sliver
    WVec3 dir(unit(rng), unit(rng), unit(rng));
    if (i % 7 == 0) dir = dir - n * (dir.dot(n) / n.squaredNorm()) * (1 - 1e-6);  // near grazing
    const Vec3 d = dir.cast<Real>();
    // origin at parameter -s along d from the inside point: in front (s > 0), behind (s < 0),
    // far, or a hair off the plane
    const double choices[] = {1, -1, 1e3, -1e3, 1e-7, -1e-7, 1e-15, -1e-15, 1e-17, -1e-17};
    const double sParam = choices[i % 10] * size / wide(d).norm();
    const Vec3 origin = (inside - wide(d) * sParam).cast<Real>();
    const Ray ray{origin, d};
    using Filter = mesh_detail::RayTriangleFilter;
    const Filter::Verdict proof = Filter(ray).classify(t);
    if (proof != Filter::kCrossesBack && proof != Filter::kCrossesFront) continue;
    geometry_detail::RayCrossing certified;
    const int verdict = geometry_detail::properRayTriangleCrossing(ray, t, proof == Filter::kCrossesBack ? 1 : -1, certified);
    if (verdict < 0) {
      ++deferred;
      continue;
    }
    ++decided;
    const std::optional<double> exactT = exact::raycast(ray, t);
    const auto where = [&] {
      return "case " + std::to_string(i) + ": " + str(t.a) + str(t.b) + str(t.c) + ", origin " + str(origin) +
             ", direction " + str(d);
    };
    ASSERT_EQ(verdict == 1, exactT.has_value()) << where();
    if (exactT) {
      const double length = wide(d).norm(), tCertified = certified.s * length;
      const double S = std::max(wide(origin).cwiseAbs().maxCoeff(), wide(t.a).cwiseAbs().maxCoeff());
      const double cosine = std::abs(n.dot(wide(d))) / (n.norm() * length);
      ASSERT_LE(std::abs(tCertified - *exactT), kRayParameterUlps * double(kEps) * (S + *exactT) / cosine) << where();
      ASSERT_LT(certified.normal.dot(wide(d)), 0) << "the normal faces the origin: " << where();
    }
  }
  // (in double builds most origins 1e-15 and 1e-17 off the plane are deferred, rightly)
  EXPECT_GT(decided, 2 * deferred) << "the certified path defers too often";
  EXPECT_GT(decided, cases / 2);
}

TEST(RaycastPlane, HitBeyondTheRepresentableRangeIsAMiss) {
  const Ray ray{Vec3(4, 0, 0), Vec3(2, 1, 5)};
  const Plane plane{Vec3(-1, 2, std::numeric_limits<Real>::min()), 4};  // n·dir = 5·min
  const std::optional<RayHit> hit = raycast(ray, plane);
  if (hit) {
    EXPECT_TRUE(std::isfinite(hit->t)) << std::setprecision(17) << "t " << hit->t;
    EXPECT_TRUE(hit->point.allFinite()) << std::setprecision(17) << hit->point.transpose();
  }
  if constexpr (std::is_same_v<Real, float>) EXPECT_FALSE(hit) << "t = 8/(5·FLT_MIN)·|dir| overflows float";
}

// Non-queryable inputs (precondition.hpp, rule::kPrimitive): the routines behind the public entries
// (geometry/unchecked.hpp, what those entries run in release builds and the mesh, scene and contact
// layers call) give an unspecified answer, but return without undefined behaviour, which the
// sanitizer stage checks here.
TEST(RaycastPreconditions, NonQueryableInputsReturnWithoutUndefinedBehaviour) {
  const test_support::BadPrimitives bad = test_support::badPrimitives();
  const Triangle tri{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  const Sphere sphere{Vec3::Zero(), 1};
  const Aabb box{Vec3::Constant(-1), Vec3::Constant(1)};
  const Obb obb{Vec3::Zero(), Vec3::Ones(), Mat3::Identity()};
  const Plane plane{};
  const Ray ray{Vec3(Real(0.2), Real(0.2), 2), Vec3(0, 0, -1)};
  const Segment seg{Vec3(Real(0.2), Real(0.2), 2), Vec3(Real(0.2), Real(0.2), -2)};
  int calls = 0;
  const auto both = [&](const auto& shape) {
    calls += 2;
    (void)unchecked::raycast(ray, shape);
    (void)unchecked::intersects(seg, shape);
  };
  for (const Ray& r : bad.rays) {
    (void)unchecked::raycast(r, tri), (void)unchecked::raycast(r, sphere), (void)unchecked::raycast(r, box), (void)unchecked::raycast(r, obb), (void)unchecked::raycast(r, plane);
    calls += 5;
  }
  for (const Segment& s : bad.segments) {
    (void)unchecked::intersects(s, tri), (void)unchecked::intersects(s, sphere), (void)unchecked::intersects(s, box), (void)unchecked::intersects(s, obb);
    (void)unchecked::intersects(s, plane);
    calls += 5;
  }
  for (const Triangle& t : bad.triangles) both(t);
  for (const Sphere& s : bad.spheres) both(s);
  for (const Aabb& b : bad.aabbs) both(b);
  for (const Obb& b : bad.obbs) both(b);
  for (const Plane& p : bad.planes) both(p);
  EXPECT_GT(calls, 150);
  // the good inputs hit: the bad ones went through the same entry points
  EXPECT_TRUE(unchecked::raycast(ray, tri) && unchecked::raycast(ray, sphere) && unchecked::raycast(ray, box) && unchecked::raycast(ray, obb) && unchecked::raycast(ray, plane));
  EXPECT_TRUE(unchecked::intersects(seg, tri) && unchecked::intersects(seg, sphere) && unchecked::intersects(seg, box) && unchecked::intersects(seg, obb));
}

// In debug builds (CRUX_CHECK_PRIMITIVE_PRECONDITIONS, on without NDEBUG) a non-queryable input
// aborts with a message naming the query.
TEST(RaycastPreconditions, DebugBuildsAbortNamingTheQuery) {
  if (!CRUX_CHECK_PRIMITIVE_PRECONDITIONS)
    GTEST_SKIP() << "the primitive check is off in this build (NDEBUG)";
  const Triangle tri{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  EXPECT_DEATH((void)raycast(Ray{Vec3::Zero(), Vec3::Zero()}, tri),
               "precondition violated in raycast\\(Ray, Triangle\\)");
  const Real nan = std::numeric_limits<Real>::quiet_NaN();
  EXPECT_DEATH((void)intersects(Segment{Vec3(nan, 0, 0), Vec3::Ones()}, tri),
               "precondition violated in intersects\\(Segment, Triangle\\)");
}

}  // namespace
}  // namespace crux
