/// Tests of src/geometry/triangle_overlap.cpp: named regressions for the book's errata and
/// degenerate cases, and seeded property tests against the exact CGAL oracle.

#include <crux/geometry/overlap.hpp>
#include <crux/geometry/predicates.hpp>
#include <crux/precondition.hpp>

#include "exact/exact.hpp"
#include "geometry/unchecked.hpp"
#include "support/bad_inputs.hpp"
#include "support/test_scale.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <utility>

namespace {

using crux::Aabb;
using crux::Mat3;
using crux::Obb;
using crux::Plane;
using crux::Real;
using crux::Sphere;
using crux::Triangle;
using crux::Vec3;

// ---- printing (17 significant digits: round-trip exact) ----------------------------------

std::string str(const Vec3& v) {
  std::ostringstream s;
  s << std::setprecision(17) << "[" << double(v.x()) << ", " << double(v.y()) << ", "
    << double(v.z()) << "]";
  return s.str();
}
std::string str(const Triangle& t) {
  return "[" + str(t.a) + ", " + str(t.b) + ", " + str(t.c) + "]";
}
std::string str(const Sphere& s) {
  std::ostringstream o;
  o << std::setprecision(17) << "{\"center\": " << str(s.center)
    << ", \"radius\": " << double(s.radius) << "}";
  return o.str();
}
std::string str(const Aabb& b) {
  return "{\"min\": " + str(b.min) + ", \"max\": " + str(b.max) + "}";
}
std::string str(const Obb& b) {
  return "{\"center\": " + str(b.center) + ", \"half\": " + str(b.half) + ", \"axes\": [" +
         str(b.axes.col(0)) + ", " + str(b.axes.col(1)) + ", " + str(b.axes.col(2)) + "]}";
}
std::string str(const Plane& p) {
  std::ostringstream o;
  o << std::setprecision(17) << "{\"normal\": " << str(p.normal) << ", \"d\": " << double(p.d)
    << "}";
  return o.str();
}

// ---- seeded generation (portable: no std distributions) -----------------------------------

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}
  /// Uniform integer in [lo, hi].
  int integer(int lo, int hi) { return lo + int(engine_() % std::uint64_t(hi - lo + 1)); }
  /// Uniform double in [lo, hi).
  double uniform(double lo, double hi) {
    return lo + (hi - lo) * double(engine_() >> 11) * 0x1.0p-53;
  }
  bool percent(int p) { return integer(0, 99) < p; }

 private:
  std::mt19937_64 engine_;
};

// Generators draw each random number in its own statement (or a braced list) so the sequence
// is the same with every compiler: a case printed on failure can be regenerated anywhere.

/// Integer vector with coordinates in [lo, hi].
Vec3 gridVector(Rng& r, int lo, int hi) {
  const int x = r.integer(lo, hi);
  const int y = r.integer(lo, hi);
  const int z = r.integer(lo, hi);
  return Vec3(Real(x), Real(y), Real(z));
}
Vec3 gridPoint(Rng& r, int m) { return gridVector(r, -m, m); }

/// An integer lattice plane {o + i u + j v}: triangles drawn from one frame are coplanar
/// (u, v may be parallel or zero: then the points are collinear or coincide).
struct Frame {
  Vec3 o, u, v;
  Vec3 point(Rng& r, int m) const {
    const int i = r.integer(-m, m);
    const int j = r.integer(-m, m);
    return o + Real(i) * u + Real(j) * v;
  }
  Triangle triangle(Rng& r, int m) const { return {point(r, m), point(r, m), point(r, m)}; }
};

Frame gridFrame(Rng& r) { return Frame{gridPoint(r, 2), gridPoint(r, 1), gridPoint(r, 1)}; }

/// A grid triangle: usually three random lattice points; often collinear or with repeated
/// corners (the degenerate triangles every test must treat as segments/points).
Triangle gridTriangle(Rng& r, int m) {
  const int kind = r.integer(0, 9);
  if (kind == 0) {  // collinear, possibly with repeated corners
    const Vec3 a = gridPoint(r, m - 2), d = gridPoint(r, 1);
    return {a + Real(r.integer(-2, 2)) * d, a + Real(r.integer(-2, 2)) * d,
            a + Real(r.integer(-2, 2)) * d};
  }
  if (kind == 1) {  // a repeated corner or a single point
    const Vec3 a = gridPoint(r, m), b = r.percent(50) ? gridPoint(r, m) : a;
    switch (r.integer(0, 2)) {
      case 0:
        return {a, a, b};
      case 1:
        return {a, b, a};
      default:
        return {b, a, a};
    }
  }
  return {gridPoint(r, m), gridPoint(r, m), gridPoint(r, m)};
}

Triangle rotated(const Triangle& t, int k) {
  return k == 0 ? t : (k == 1 ? Triangle{t.b, t.c, t.a} : Triangle{t.c, t.a, t.b});
}
Triangle reversed(const Triangle& t) { return {t.a, t.c, t.b}; }

/// Random floats in [-1, 1]³ scaled by s.
Vec3 floatVector(Rng& r, double lo, double hi) {
  const double x = r.uniform(lo, hi);
  const double y = r.uniform(lo, hi);
  const double z = r.uniform(lo, hi);
  return Vec3(Real(x), Real(y), Real(z));
}
Vec3 floatPoint(Rng& r, double s) { return floatVector(r, -s, s); }
Triangle floatTriangle(Rng& r, double s) {
  return {floatPoint(r, s), floatPoint(r, s), floatPoint(r, s)};
}

/// A uniformly random point of the triangle plus a random offset of size up to s: shapes
/// placed there meet the triangle about half of the time.
Vec3 nearTriangle(Rng& r, const Triangle& t, double s) {
  double u = r.uniform(0, 1), w = r.uniform(0, 1);
  if (u + w > 1) u = 1 - u, w = 1 - w;
  const Vec3 onTriangle = t.a + Real(u) * (t.b - t.a) + Real(w) * (t.c - t.a);
  return onTriangle + floatPoint(r, s);
}

/// A scale spanning millimetres to kilometres, so no absolute tolerance could pass.
double randomScale(Rng& r) {
  static constexpr double kScales[] = {1e-3, 1e-2, 0.1, 1, 10, 1e3};
  return kScales[r.integer(0, 5)];
}

/// Random rotation matrix (normalised random quaternion), columns orthonormal to Real
/// precision.
Mat3 randomRotation(Rng& r) {
  const double w = r.uniform(-1, 1);
  const Eigen::Vector3d xyz = floatVector(r, -1, 1).cast<double>();
  Eigen::Quaternion<double> q(w, xyz.x(), xyz.y(), xyz.z());
  if (q.norm() < 1e-3) q = Eigen::Quaternion<double>::Identity();
  return q.normalized().toRotationMatrix().cast<Real>();
}

/// Axes that are a random signed permutation of the unit vectors (exact).
Mat3 signedPermutation(Rng& r) {
  static constexpr int kPerms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2},
                                       {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  const int* p = kPerms[r.integer(0, 5)];
  Mat3 m = Mat3::Zero();
  for (int c = 0; c < 3; ++c) m(p[c], c) = r.percent(50) ? Real(1) : Real(-1);
  return m;
}

/// The affine map x -> 7x + o with |o| <= 36 takes the [-4, 4] grid to coordinates up to 64
/// (the bound of the exactness guarantee) with longer mantissas; applied to both shapes of a
/// case it keeps the configuration (touching stays touching).
struct Magnify {
  Real k = 7;
  Vec3 o;
  Vec3 point(const Vec3& x) const { return k * x + o; }
  Triangle operator()(const Triangle& t) const { return {point(t.a), point(t.b), point(t.c)}; }
  Sphere operator()(const Sphere& s) const { return {point(s.center), k * s.radius}; }
  Aabb operator()(const Aabb& b) const { return {point(b.min), point(b.max)}; }
  Obb operator()(const Obb& b) const { return {point(b.center), k * b.half, b.axes}; }
  Plane operator()(const Plane& p) const { return {p.normal, k * p.d + p.normal.dot(o)}; }
};

/// Largest coordinate magnitude of a shape's points.
Real reach(const Vec3& p) { return p.cwiseAbs().maxCoeff(); }
Real reach(const Triangle& t) { return std::max({reach(t.a), reach(t.b), reach(t.c)}); }
Real reach(const Sphere& s) { return reach(s.center) + s.radius; }
Real reach(const Aabb& b) { return std::max(reach(b.min), reach(b.max)); }
Real reach(const Obb& b) { return reach(b.center) + b.half.sum(); }
Real reach(const Plane&) { return 0; }

/// Every fifth grid case is magnified, with an offset that keeps every coordinate <= 64.
template <class S>
void maybeMagnify(Rng& r, int index, Triangle& t, S& s) {
  if (index % 5 != 4) return;
  const int room = std::min(36, int(64 - 7 * std::max(reach(t), reach(s))));
  if (room < 0) return;
  const Magnify m{7, gridPoint(r, room)};
  t = m(t);
  s = m(s);
}

// ---- the property-test driver -------------------------------------------------------------

struct Tally {
  int cases = 0, hits = 0, mismatches = 0;
};

/// Compares crux with the exact oracle on one case; prints the case on a mismatch.
template <class S>
void compare(const char* family, int index, const Triangle& t, const S& s, Tally& tally) {
  const bool got = crux::overlaps(t, s);
  const bool want = crux::exact::overlaps(t, s);
  ++tally.cases;
  tally.hits += want ? 1 : 0;
  if (got != want && ++tally.mismatches <= 10) {
    ADD_FAILURE() << family << " case " << index << ": crux says " << got << ", CGAL says " << want
                  << "\n  triangle " << str(t) << "\n  other " << str(s);
  }
}

void report(const char* family, const Tally& tally) {
  const double rate = double(tally.hits) / tally.cases;
  std::cout << "[ property ] " << family << ": " << tally.cases << " cases, hit rate "
            << std::setprecision(3) << 100 * rate << "%, mismatches " << tally.mismatches << "\n";
  EXPECT_EQ(tally.mismatches, 0) << family;
  EXPECT_GE(rate, 0.2) << family << ": generator too sparse";
  EXPECT_LE(rate, 0.8) << family << ": generator too dense";
}

const int kCases = crux::test::scaledCases(100000);  // CRUX_TEST_SCALE (support/test_scale.hpp)

bool coplanar(const Triangle& a, const Triangle& b) {
  using crux::wide;
  for (const Vec3* p : {&b.a, &b.b, &b.c}) {
    if (crux::predicates::orient3d(wide(a.a), wide(a.b), wide(a.c), wide(*p)) != 0) return false;
  }
  return true;
}

/// Triangle–triangle cases also check symmetry and invariance under reordering corners.
void compareTriangles(const char* family, int index, const Triangle& a, const Triangle& b,
                      Tally& tally, int& asymmetries) {
  compare(family, index, a, b, tally);
  const bool ab = crux::overlaps(a, b);
  const bool ba = crux::overlaps(b, a);
  const bool permuted =
      crux::overlaps(reversed(rotated(b, index % 3)), rotated(a, (index / 3) % 3));
  if ((ab != ba || ab != permuted) && ++asymmetries <= 10) {
    ADD_FAILURE() << family << " case " << index << ": overlaps(a,b)=" << ab
                  << " overlaps(b,a)=" << ba << " permuted=" << permuted << "\n  a " << str(a)
                  << "\n  b " << str(b);
  }
}

// ---- named regressions --------------------------------------------------------------------

/// Checks crux (both argument orders) and the oracle against an answer derived by hand.
template <class S>
void expectOverlap(const Triangle& t, const S& s, bool expected) {
  EXPECT_EQ(crux::overlaps(t, s), expected) << str(t) << " vs " << str(s);
  EXPECT_EQ(crux::overlaps(s, t), expected) << str(s) << " vs " << str(t);
  EXPECT_EQ(crux::exact::overlaps(t, s), expected) << "oracle: " << str(t) << " vs " << str(s);
}

const Triangle kUnit{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
const Aabb kUnitBox{Vec3(0, 0, 0), Vec3(1, 1, 1)};

Vec3 v(double x, double y, double z) { return Vec3(Real(x), Real(y), Real(z)); }

TEST(TriangleTriangle, CoplanarSeparatedTriangles) {
  // The book's 11-axis SAT reports every coplanar pair as intersecting.
  expectOverlap(kUnit, Triangle{v(1, 1, 0), v(2, 1, 0), v(1, 2, 0)}, false);
  expectOverlap(kUnit, Triangle{v(-1, -1, 0), v(-3, 0, 0), v(0, -3, 0)}, false);
  expectOverlap(kUnit, Triangle{v(0.6, 0.6, 0), v(5, 0.5, 0), v(0.5, 5, 0)}, false);
}

TEST(TriangleTriangle, CoplanarTrianglesSharingAnEdge) {
  expectOverlap(kUnit, Triangle{v(1, 0, 0), v(0, 1, 0), v(1, 1, 0)}, true);
  expectOverlap(kUnit, Triangle{v(0, 1, 0), v(0, 0, 0), v(-1, 0.5, 0)}, true);
}

TEST(TriangleTriangle, CoplanarTrianglesSharingAVertex) {
  expectOverlap(kUnit, Triangle{v(1, 0, 0), v(2, 0, 0), v(2, 1, 0)}, true);
  expectOverlap(kUnit, Triangle{v(0, 0, 0), v(-1, -1, 0), v(0, -2, 0)}, true);
}

TEST(TriangleTriangle, CoplanarTrianglesTouchingVertexToEdge) {
  expectOverlap(kUnit, Triangle{v(0.5, 0.5, 0), v(2, 1, 0), v(1, 2, 0)}, true);
  expectOverlap(kUnit, Triangle{v(0.5, 0.5001, 0), v(2, 1, 0), v(1, 2, 0)}, false);
}

TEST(TriangleTriangle, CoplanarTriangleInsideAnother) {
  expectOverlap(Triangle{v(-4, -4, 2), v(8, -4, 2), v(-4, 8, 2)},
                Triangle{v(0, 0, 2), v(1, 0, 2), v(0, 1, 2)}, true);
}

TEST(TriangleTriangle, NonCoplanarTrianglesSharingAnEdge) {
  expectOverlap(kUnit, Triangle{v(1, 0, 0), v(0, 1, 0), v(0, 0, 1)}, true);
}

TEST(TriangleTriangle, TriangleTouchingAnotherAtOneVertex) {
  expectOverlap(kUnit, Triangle{v(0.25, 0.25, 0), v(0, 0, 1), v(1, 1, 1)}, true);
  expectOverlap(kUnit, Triangle{v(0.25, 0.25, 0.001), v(0, 0, 1), v(1, 1, 1)}, false);
}

TEST(TriangleTriangle, MillimetreScaleTriangles) {
  // Millimetre triangles 0.1 mm apart: the book's |cross|² < FLT_EPSILON test calls every
  // cross axis parallel and reports a collision.
  const Triangle a{v(0, 0, 0), v(0.001, 0, 0), v(0, 0.001, 0)};
  expectOverlap(
      a, Triangle{v(0.0002, 0.0002, 0.0001), v(0.0008, 0.0002, 0.0001), v(0.0005, 0.0003, 0.0009)},
      false);
  expectOverlap(
      a, Triangle{v(0.0002, 0.0002, -0.0001), v(0.0008, 0.0002, 0.0001), v(0.0005, 0.0003, 0.0009)},
      true);
  expectOverlap(a,
                Triangle{v(0.0006, 0.0006, -0.0005), v(0.0006, 0.0006, 0.0005), v(0.002, 0.002, 0)},
                false);
  expectOverlap(a, Triangle{v(0, 0, 0.0001), v(0.001, 0, 0.0001), v(0, 0.001, 0.0001)}, false);
}

TEST(TriangleTriangle, DegenerateTriangleIsItsSegment) {
  // Collinear corners given in an order where the segment is spanned by the first and last.
  const Triangle big{v(-1, -1, 0), v(2, -1, 0), v(-1, 2, 0)};
  expectOverlap(big, Triangle{v(0, 0, 1), v(0, 0, 2), v(0, 0, -1)}, true);
  expectOverlap(big, Triangle{v(0, 0, 1), v(0, 0, 2), v(0, 0, 3)}, false);
  expectOverlap(big, Triangle{v(3, 3, -1), v(3, 3, 1), v(3, 3, 0)}, false);
  expectOverlap(big, Triangle{v(2, -1, 0), v(3, -1, 0), v(4, -1, 0)}, true);  // touches a corner
  expectOverlap(big, Triangle{v(1, 1, 0), v(2, 2, 0), v(3, 3, 0)}, false);    // in plane, outside
  expectOverlap(kUnit, Triangle{v(-1, -1, 0), v(-2, 0, 0), v(0, -2, 0)},
                false);  // parallel to an edge
  // Segment against segment: crossing, collinear overlapping, collinear apart, skew.
  const Triangle seg{v(0, 0, 0), v(2, 2, 0), v(2, 2, 0)};
  expectOverlap(seg, Triangle{v(0, 2, 0), v(2, 0, 0), v(1, 1, 0)}, true);
  expectOverlap(seg, Triangle{v(2, 2, 0), v(3, 3, 0), v(4, 4, 0)}, true);
  expectOverlap(seg, Triangle{v(3, 3, 0), v(4, 4, 0), v(5, 5, 0)}, false);
  expectOverlap(seg, Triangle{v(0, 2, 1), v(2, 0, 1), v(1, 1, 1)}, false);
  expectOverlap(seg, Triangle{v(0, 2, 0), v(1, 1.0001, 0), v(0.5, 1.5, 0)}, false);
  // The segment against the other shapes.
  expectOverlap(Triangle{v(0, 0, 0), v(0, 0, 0), v(0, 0, 0)}, Sphere{v(0, 0, 0), 0}, true);
  expectOverlap(Triangle{v(0, 0, 5), v(0, 0, -5), v(0, 0, 0)}, Plane{v(0, 0, 1), 0}, true);
  expectOverlap(Triangle{v(0, 0, 5), v(0, 0, -5), v(0, 0, 0)}, Sphere{v(1, 0, 3), 1}, true);
  expectOverlap(Triangle{v(0, 0, 5), v(0, 0, -5), v(0, 0, 0)}, Sphere{v(1, 0, 6), 1}, false);
  expectOverlap(Triangle{v(0, 0, 5), v(0, 0, -5), v(0, 0, 0)}, Aabb{v(-1, -1, 5), v(1, 1, 6)},
                true);
  expectOverlap(Triangle{v(0, 0, 5), v(0, 0, -5), v(0, 0, 0)}, Aabb{v(-1, -1, 5.5), v(1, 1, 6)},
                false);
}

TEST(TriangleTriangle, DegenerateTriangleIsItsPoint) {
  expectOverlap(kUnit, Triangle{v(0.25, 0.25, 0), v(0.25, 0.25, 0), v(0.25, 0.25, 0)}, true);
  expectOverlap(kUnit, Triangle{v(0.5, 0.5, 0), v(0.5, 0.5, 0), v(0.5, 0.5, 0)},
                true);  // on the edge
  expectOverlap(kUnit, Triangle{v(0.25, 0.25, 0.5), v(0.25, 0.25, 0.5), v(0.25, 0.25, 0.5)}, false);
  expectOverlap(kUnit, Triangle{v(2, 0, 0), v(2, 0, 0), v(2, 0, 0)}, false);  // on an edge's line
  const Triangle p{v(1, 1, 1), v(1, 1, 1), v(1, 1, 1)};
  expectOverlap(p, Triangle{v(1, 1, 1), v(1, 1, 1), v(1, 1, 1)}, true);
  expectOverlap(p, Triangle{v(1, 1, 2), v(1, 1, 2), v(1, 1, 2)}, false);
  expectOverlap(p, Triangle{v(0, 0, 0), v(2, 2, 2), v(3, 3, 3)}, true);
  expectOverlap(p, Triangle{v(2, 2, 2), v(3, 3, 3), v(4, 4, 4)}, false);  // on the line, outside
  expectOverlap(p, Triangle{v(-2, -2, -2), v(-1, -1, -1), v(0, 0, 0)}, false);
  expectOverlap(p, Sphere{v(1, 1, 3), 2}, true);
  expectOverlap(p, Sphere{v(1, 1, 3), 1.5}, false);
  expectOverlap(p, kUnitBox, true);
  expectOverlap(p, Aabb{v(1, 1, 1.5), v(2, 2, 2)}, false);
  expectOverlap(p, Plane{v(1, 1, 1), 3}, true);
  expectOverlap(p, Plane{v(1, 1, 1), 2}, false);
}

// ---- sphere -------------------------------------------------------------------------------

TEST(TriangleSphere, SphereTouchingAVertexInTieRegion) {
  // The centre (2, -0.5, 0) is in the Voronoi region of (1, 0, 0), where the book's edge
  // distances tie and it returns (0, 0, 0) instead: the distance is sqrt(1.25) ≈ 1.118.
  expectOverlap(kUnit, Sphere{v(2, -0.5, 0), 1.2}, true);
  expectOverlap(kUnit, Sphere{v(2, -0.5, 0), 1.1}, false);
  expectOverlap(kUnit, Sphere{v(2, -0.5, 0), 1}, false);
  // The same region with an exact touch: |(4, -4, 0) - (1, 0, 0)| = 5.
  expectOverlap(kUnit, Sphere{v(4, -4, 0), 5}, true);
  expectOverlap(kUnit, Sphere{v(4, -4, 0), 4.999}, false);
}

TEST(TriangleSphere, SphereTouchingEdgeAndFace) {
  expectOverlap(kUnit, Sphere{v(1, 1, 0), 0.5}, false);     // distance to the edge is sqrt(0.5)
  expectOverlap(kUnit, Sphere{v(1, 1, 1), 1.25}, true);     // distance sqrt(1.5) ≈ 1.22
  expectOverlap(kUnit, Sphere{v(0.25, 0.25, 2), 2}, true);  // touches the face
  expectOverlap(kUnit, Sphere{v(0.25, 0.25, -2), 1.999}, false);
  expectOverlap(kUnit, Sphere{v(0.5, -3, 4), 5}, true);  // touches the edge y = 0 at (0.5, 0, 0)
}

TEST(TriangleSphere, ZeroRadiusSphereIsAPoint) {
  expectOverlap(kUnit, Sphere{v(0.5, 0, 0), 0}, true);
  expectOverlap(kUnit, Sphere{v(0.5, 0.5, 0), 0}, true);
  expectOverlap(kUnit, Sphere{v(0.5, 0.5001, 0), 0}, false);
  expectOverlap(kUnit, Sphere{v(0.2, 0.2, 0.0001), 0}, false);
}

// ---- boxes --------------------------------------------------------------------------------

TEST(TriangleAabb, TriangleTouchingABoxFace) {
  expectOverlap(Triangle{v(1, 0.5, 0.5), v(2, 0, 0), v(2, 1, 1)}, kUnitBox, true);
  expectOverlap(Triangle{v(1.001, 0.5, 0.5), v(2, 0, 0), v(2, 1, 1)}, kUnitBox, false);
}

TEST(TriangleAabb, TriangleTouchingABoxEdge) {
  // Edge against the box edge x = y = 1 at z = 0.5; only the cross axis (1, 1, 0) separates
  // the shifted copy.
  expectOverlap(Triangle{v(2, 0, 0), v(0, 2, 1), v(3, 3, 0.5)}, kUnitBox, true);
  expectOverlap(Triangle{v(2.1, 0, 0), v(0, 2.1, 1), v(3, 3, 0.5)}, kUnitBox, false);
  expectOverlap(Triangle{v(2, 0, 0.5), v(0, 2, 0.5), v(3, 3, 0.5)}, kUnitBox, true);
}

TEST(TriangleAabb, TriangleTouchingABoxCorner) {
  expectOverlap(Triangle{v(3, 0, 0), v(0, 3, 0), v(0, 0, 3)}, kUnitBox, true);
  expectOverlap(Triangle{v(3.1, 0, 0), v(0, 3.1, 0), v(0, 0, 3.1)}, kUnitBox, false);
}

TEST(TriangleAabb, TriangleLyingInABoxFace) {
  expectOverlap(Triangle{v(0.2, 0.2, 1), v(0.8, 0.2, 1), v(0.5, 0.8, 1)}, kUnitBox, true);
  expectOverlap(Triangle{v(-5, -5, 1), v(10, -5, 1), v(-5, 10, 1)}, kUnitBox, true);
  expectOverlap(Triangle{v(2, 2, 1), v(3, 2, 1), v(2, 3, 1)}, kUnitBox, false);
  expectOverlap(Triangle{v(1.5, 0, 1), v(0, 1.5, 1), v(2, 2, 1)}, kUnitBox,
                true);  // covers a corner
}

TEST(TriangleAabb, TriangleInsideTheBox) {
  expectOverlap(Triangle{v(0.2, 0.2, 0.2), v(0.8, 0.2, 0.5), v(0.5, 0.8, 0.7)}, kUnitBox, true);
  expectOverlap(Triangle{v(-1, -1, 0.5), v(5, -1, 0.5), v(-1, 5, 0.5)}, kUnitBox,
                true);  // slices it
}

TEST(TriangleAabb, FlatAndPointBoxes) {
  const Aabb flat{v(0, 0, 0.5), v(1, 1, 0.5)};
  expectOverlap(Triangle{v(0.5, 0.5, 0), v(0.6, 0.5, 1), v(0.5, 0.6, 1)}, flat, true);
  expectOverlap(Triangle{v(0.5, 0.5, 0.6), v(0.6, 0.5, 1), v(0.5, 0.6, 1)}, flat, false);
  expectOverlap(Triangle{v(0.5, 0.5, 0.5), v(0.6, 0.5, 1), v(0.5, 0.6, 1)}, flat, true);
  const Aabb point{v(0.25, 0.25, 0), v(0.25, 0.25, 0)};
  expectOverlap(kUnit, point, true);
  expectOverlap(kUnit, Aabb{v(0.75, 0.75, 0), v(0.75, 0.75, 0)}, false);
  const Aabb stick{v(0.25, 0.25, -1), v(0.25, 0.25, 1)};
  expectOverlap(kUnit, stick, true);
  expectOverlap(kUnit, Aabb{v(0.75, 0.75, -1), v(0.75, 0.75, 1)}, false);
}

TEST(TriangleObb, AxisPermutedBoxTouching) {
  // Axes: local x = world y, local y = -world x: the box is [-2, 2] x [-1, 1] x [-0.5, 0.5].
  Obb box;
  box.center = v(0, 0, 0);
  box.half = v(1, 2, 0.5);
  box.axes << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  expectOverlap(Triangle{v(2, 0, 0), v(3, 1, 0), v(3, -1, 0)}, box, true);
  expectOverlap(Triangle{v(2.25, 0, 0), v(3, 1, 0), v(3, -1, 0)}, box, false);
  expectOverlap(Triangle{v(0, 1, 0.5), v(1, 2, 2), v(-1, 2, 2)}, box, true);  // touches an edge
  expectOverlap(Triangle{v(0, 1.25, 0.5), v(1, 2, 2), v(-1, 2, 2)}, box, false);
  box.half = v(1, 2, 0);  // flat
  expectOverlap(Triangle{v(0, 0, -1), v(0.1, 0, 1), v(0, 0.1, 1)}, box, true);
  expectOverlap(Triangle{v(0, 0, 0.1), v(0.1, 0, 1), v(0, 0.1, 1)}, box, false);
}

TEST(TriangleObb, RotatedBoxIsNotItsBounds) {
  // A cube rotated 45° about z: (1.2, 1.2) is inside its bounding square but outside the cube.
  Obb box;
  box.center = v(0, 0, 0);
  box.half = v(1, 1, 1);
  const double s = std::sqrt(0.5);
  box.axes << Real(s), Real(-s), 0, Real(s), Real(s), 0, 0, 0, 1;
  expectOverlap(Triangle{v(1.2, 1.2, 0), v(2, 1.2, 0), v(1.2, 2, 0)}, box, false);
  expectOverlap(Triangle{v(1.3, 0, 0), v(2, 0.5, 0), v(2, -0.5, 0)}, box, true);
  expectOverlap(Triangle{v(0.1, 0.1, 0.1), v(0.2, 0.1, 0.1), v(0.1, 0.2, 0.1)}, box, true);
}

// ---- plane --------------------------------------------------------------------------------

TEST(TrianglePlane, TriangleTouchingAPlaneAtAVertex) {
  for (const Plane& z1 : {Plane{v(0, 0, 1), 1}, Plane{v(0, 0, 2), 2}, Plane{v(0, 0, -3), -3}}) {
    expectOverlap(Triangle{v(0, 0, 1), v(1, 0, 2), v(0, 1, 2)}, z1, true);
    expectOverlap(Triangle{v(0, 0, 1.001), v(1, 0, 2), v(0, 1, 2)}, z1, false);
    expectOverlap(Triangle{v(0, 0, 1), v(1, 0, 1), v(0, 1, 1)}, z1, true);         // lies in it
    expectOverlap(Triangle{v(0, 0, 0.5), v(1, 0, 0.5), v(0, 1, 0.5)}, z1, false);  // parallel
    expectOverlap(Triangle{v(0, 0, 0), v(1, 0, 2), v(0, 1, 2)}, z1, true);         // crosses
  }
}

// ---- consistency between the box tests ----------------------------------------------------

TEST(TriangleBox, AabbAndObbAgreeOnAxisAlignedBoxes) {
  Rng r(0xB0C5);
  for (int i = 0; i < kCases; ++i) {
    const Triangle t = gridTriangle(r, 4);
    const Vec3 lo = gridPoint(r, 4);
    const Vec3 hi = lo + gridVector(r, 0, 3);
    const Aabb box{lo, hi};
    Obb obb;
    obb.center = box.center();
    obb.half = box.half();
    obb.axes = signedPermutation(r);
    obb.half = obb.axes.transpose().cwiseAbs() * obb.half;  // the same box in permuted axes
    ASSERT_EQ(crux::overlaps(t, box), crux::overlaps(t, obb))
        << str(t) << " " << str(box) << " " << str(obb);
  }
}

TEST(TriangleBox, ExactOracleAabbAgreesWithParallelepiped) {
  // The oracle's AABB path (Iso_cuboid_3) and OBB path (tetrahedra, triangles, segments,
  // points) are different CGAL code; on flat and zero boxes they must agree.
  Rng r(0x0BB0);
  for (int i = 0; i < 5000; ++i) {
    const Triangle t = gridTriangle(r, 3);
    const Vec3 lo = gridPoint(r, 3);
    const Vec3 hi = lo + gridVector(r, 0, 2);
    const Aabb box{lo, hi};
    Obb obb;
    obb.center = box.center();
    obb.half = box.half();
    ASSERT_EQ(crux::exact::overlaps(t, box), crux::exact::overlaps(t, obb))
        << str(t) << " " << str(box);
  }
}

// ---- property tests against the exact oracle ----------------------------------------------

TEST(TriangleTriangleProperty, IntegerGridMatchesExactOracle) {
  Rng r(0x7717);
  Tally tally;
  int asymmetries = 0, degenerates = 0, coplanars = 0;
  for (int i = 0; i < kCases; ++i) {
    Triangle a, b;
    const Frame f = gridFrame(r);
    switch (i % 7) {
      case 0:  // independent
        a = gridTriangle(r, 3), b = gridTriangle(r, 3);
        break;
      case 1:  // coplanar (a common lattice plane)
        a = f.triangle(r, 3), b = f.triangle(r, 3);
        break;
      case 2:  // a shared corner
        a = gridTriangle(r, 3), b = gridTriangle(r, 3);
        b.a = a[r.integer(0, 2)];
        b = rotated(b, r.integer(0, 2));
        break;
      case 3:  // a shared edge, the third corners anywhere or in the common plane
        a = f.triangle(r, 2);
        b = {a[1], a[0], r.percent(50) ? f.point(r, 3) : gridPoint(r, 3)};
        b = rotated(b, r.integer(0, 2));
        break;
      case 4:  // corners of one placed in the plane of the other
        a = f.triangle(r, 3);
        b = {f.point(r, 3), gridPoint(r, 3), r.percent(50) ? f.point(r, 3) : gridPoint(r, 3)};
        break;
      case 5: {  // corners on one lattice line: collinear segments, points, touching ends
        const Vec3 o = gridPoint(r, 2), d = gridPoint(r, 1), off = gridPoint(r, 2);
        const Vec3 third = r.percent(50) ? Vec3(o + off) : Vec3(o + Real(r.integer(-3, 3)) * d);
        a = {o + Real(r.integer(-3, 3)) * d, o + Real(r.integer(-3, 3)) * d, third};
        b = {o + Real(r.integer(-3, 3)) * d, o + Real(r.integer(-3, 3)) * d,
             o + Real(r.integer(-3, 3)) * d};
        break;
      }
      default:  // dense: many touching and degenerate configurations
        a = gridTriangle(r, 2), b = gridTriangle(r, 2);
        break;
    }
    if (r.percent(50)) std::swap(a, b);
    maybeMagnify(r, i, a, b);
    const bool degenerate =
        crux::predicates::classify(a).kind != crux::predicates::TriangleKind::Triangle ||
        crux::predicates::classify(b).kind != crux::predicates::TriangleKind::Triangle;
    degenerates += degenerate ? 1 : 0;
    coplanars += !degenerate && coplanar(a, b) ? 1 : 0;
    compareTriangles("tri-tri grid", i, a, b, tally, asymmetries);
  }
  std::cout << "[ property ] tri-tri grid: " << degenerates << " cases with a degenerate triangle, "
            << coplanars << " coplanar proper pairs\n";
  EXPECT_GE(degenerates, kCases / 10);
  EXPECT_GE(coplanars, kCases / 10);
  EXPECT_EQ(asymmetries, 0);
  report("tri-tri grid", tally);
}

TEST(TriangleTriangleProperty, GeneralPositionMatchesExactOracle) {
  Rng r(0x7718);
  Tally tally;
  int asymmetries = 0;
  for (int i = 0; i < kCases; ++i) {
    const double s = randomScale(r);
    const Triangle a = floatTriangle(r, s);
    const Vec3 shift = nearTriangle(r, a, 0.4 * s);
    Triangle b = floatTriangle(r, 0.6 * s);
    b = {b.a + shift, b.b + shift, b.c + shift};
    compareTriangles("tri-tri general", i, a, b, tally, asymmetries);
  }
  EXPECT_EQ(asymmetries, 0);
  report("tri-tri general", tally);
}

TEST(TriangleSphereProperty, IntegerGridMatchesExactOracle) {
  Rng r(0x5F1);
  Tally tally;
  for (int i = 0; i < kCases; ++i) {
    Triangle t = (i % 3 == 0) ? gridFrame(r).triangle(r, 2) : gridTriangle(r, 3);
    Sphere s;
    if (i % 2 == 0) {
      s.center = gridPoint(r, 4);
      s.radius = Real(r.integer(0, 6)) / 2;
    } else {  // near a corner or an edge midpoint, offset by a Pythagorean vector
      static constexpr int kOffsets[][4] = {{0, 0, 1, 1}, {0, 0, 2, 2}, {0, 3, 4, 5}, {1, 2, 2, 3},
                                            {2, 3, 6, 7}, {0, 1, 1, 1}, {1, 1, 1, 2}};
      const int* o = kOffsets[r.integer(0, 6)];
      const Vec3 base = r.percent(50) ? t[r.integer(0, 2)] : (t.a + t.b) / 2;
      Vec3 off = Vec3(Real(o[0]), Real(o[1]), Real(o[2]));
      for (int k = 0; k < 3; ++k) off[k] *= r.percent(50) ? 1 : -1;
      const int swapA = r.integer(0, 2);
      const int swapB = r.integer(0, 2);
      std::swap(off[swapA], off[swapB]);
      s.center = base + off;
      s.radius = Real(o[3]) + Real(r.integer(-1, 1)) / 2;
      if (s.radius < 0) s.radius = 0;
    }
    maybeMagnify(r, i, t, s);
    compare("tri-sphere grid", i, t, s, tally);
  }
  report("tri-sphere grid", tally);
}

TEST(TriangleSphereProperty, GeneralPositionMatchesExactOracle) {
  Rng r(0x5F2);
  Tally tally;
  for (int i = 0; i < kCases; ++i) {
    const double scale = randomScale(r);
    const Triangle t = floatTriangle(r, scale);
    const Sphere s{nearTriangle(r, t, 0.6 * scale), Real(scale * r.uniform(0, 0.5))};
    compare("tri-sphere general", i, t, s, tally);
  }
  report("tri-sphere general", tally);
}

TEST(TriangleAabbProperty, IntegerGridMatchesExactOracle) {
  Rng r(0xAABB);
  Tally tally;
  for (int i = 0; i < kCases; ++i) {
    const Vec3 lo = gridVector(r, -3, 1);
    Vec3 ext;
    for (int k = 0; k < 3; ++k) ext[k] = r.percent(25) ? Real(0) : Real(r.integer(1, 4));
    Aabb box{lo, lo + ext};
    Triangle t = gridTriangle(r, 3);
    if (i % 4 == 0) {  // in the plane of a face
      const int axis = r.integer(0, 2);
      const Real level = r.percent(50) ? box.min[axis] : box.max[axis];
      for (Vec3* p : {&t.a, &t.b, &t.c}) (*p)[axis] = level;
    }
    maybeMagnify(r, i, t, box);
    compare("tri-aabb grid", i, t, box, tally);
  }
  report("tri-aabb grid", tally);
}

TEST(TriangleAabbProperty, GeneralPositionMatchesExactOracle) {
  Rng r(0xAABC);
  Tally tally;
  for (int i = 0; i < kCases; ++i) {
    const double scale = randomScale(r);
    const Triangle t = floatTriangle(r, scale);
    const Vec3 ext = floatVector(r, 0, scale);
    const Vec3 lo = nearTriangle(r, t, 0.5 * scale) - ext / 2;
    compare("tri-aabb general", i, t, Aabb{lo, lo + ext}, tally);
  }
  report("tri-aabb general", tally);
}

TEST(TriangleObbProperty, IntegerGridMatchesExactOracle) {
  Rng r(0x0BB1);
  Tally tally;
  for (int i = 0; i < kCases; ++i) {
    Obb box;
    box.center = gridPoint(r, 3);
    box.center += gridVector(r, 0, 1) / 2;
    for (int k = 0; k < 3; ++k) box.half[k] = r.percent(20) ? Real(0) : Real(r.integer(1, 5)) / 2;
    box.axes = signedPermutation(r);
    Triangle t = gridTriangle(r, 4);
    if (i % 4 == 0) {  // in the plane of a face
      const int axis = r.integer(0, 2);
      const Real level = box.center[axis] +
                         (r.percent(50) ? 1 : -1) * (box.axes.row(axis).cwiseAbs() * box.half)(0);
      for (Vec3* p : {&t.a, &t.b, &t.c}) (*p)[axis] = level;
    }
    maybeMagnify(r, i, t, box);
    compare("tri-obb grid", i, t, box, tally);
  }
  report("tri-obb grid", tally);
}

TEST(TriangleObbProperty, GeneralPositionMatchesExactOracle) {
  Rng r(0x0BB2);
  Tally tally;
  for (int i = 0; i < kCases; ++i) {
    const double scale = randomScale(r);
    const Triangle t = floatTriangle(r, scale);
    Obb box;
    box.center = nearTriangle(r, t, 0.5 * scale);
    box.half = floatVector(r, 0, 0.6 * scale);
    box.axes = randomRotation(r);
    compare("tri-obb general", i, t, box, tally);
  }
  report("tri-obb general", tally);
}

/// Axes that are not orthonormal (what rounding a rotation to Real gives, here magnified to
/// ~2e-5, so the two readings of "an OBB with these axes" differ visibly): crux tests the box
/// as {x : |u_i·(x − c)| <= h_i} (the axes as slab normals), and so must the exact oracle
/// (exact.hpp); the parallelepiped the axes span differs from it by ~2e-5 × the extents. Small
/// triangles are placed across the slab boundary, within ±3e-6 of it, where the readings part.
/// Found by `crux diff`: two float-build `triangle_obb` cases, a flat box (a
/// segment) lying in a triangle's plane 1e-8 off it, crux "hit", the oracle (then reading the
/// span) "no" — both exact, for different sets.
TEST(TriangleObbProperty, NonOrthonormalAxesNearTheBoundaryMatchExactOracle) {
  Rng r(0x0BB3);
  Tally tally;
  for (int i = 0; i < kCases / 4; ++i) {
    Obb box;
    box.center = floatPoint(r, 1);
    box.half = floatVector(r, 0.2, 1);
    if (i % 5 == 0) box.half[r.integer(0, 2)] = 0;  // flat boxes too
    Eigen::Matrix3d u = randomRotation(r).cast<double>();
    for (int k = 0; k < 3; ++k) u.col(k) += 2e-5 * Eigen::Vector3d(r.uniform(-1, 1), r.uniform(-1, 1), r.uniform(-1, 1));
    box.axes = u.cast<Real>();
    // a point on the slab boundary: box coordinates s with |s_k| = 1 on one axis, through the
    // axes' dual basis (u_i·e_j = δ_ij, in double), moved by ±3e-6 along that slab's normal
    const Eigen::Matrix3d e = box.axes.cast<double>().inverse().transpose();
    const int k = r.integer(0, 2);
    Eigen::Vector3d sCoord(r.uniform(-1, 1), r.uniform(-1, 1), r.uniform(-1, 1));
    sCoord[k] = r.percent(50) ? 1 : -1;
    Eigen::Vector3d x = box.center.cast<double>();
    for (int j = 0; j < 3; ++j) x += sCoord[j] * double(box.half[j]) * e.col(j);
    x += sCoord[k] * r.uniform(-3e-6, 3e-6) * box.axes.col(k).cast<double>().normalized();
    // a small triangle through x, tilted at random (a segment or a point now and then)
    const Vec3 p = x.cast<Real>();
    Triangle t{p, p + floatPoint(r, 1e-3), p + floatPoint(r, 1e-3)};
    if (i % 7 == 0) t.c = t.b;
    if (i % 11 == 0) t.b = t.c = t.a;
    compare("tri-obb non-orthonormal", i, t, box, tally);
  }
  report("tri-obb non-orthonormal", tally);
}

TEST(TrianglePlaneProperty, IntegerGridMatchesExactOracle) {
  Rng r(0x9A7E);
  Tally tally;
  for (int i = 0; i < kCases; ++i) {
    Vec3 n = gridPoint(r, 2);
    if (n.isZero()) n = Vec3::UnitX();
    const Triangle t = gridTriangle(r, 3);
    // Often through a corner of the triangle (an exact touch unless the others straddle).
    Triangle tm = t;
    Plane plane{n, r.percent(30) ? n.dot(t[r.integer(0, 2)]) : Real(r.integer(-12, 12))};
    maybeMagnify(r, i, tm, plane);
    compare("tri-plane grid", i, tm, plane, tally);
  }
  report("tri-plane grid", tally);
}

TEST(TrianglePlaneProperty, GeneralPositionMatchesExactOracle) {
  Rng r(0x9A7F);
  Tally tally;
  for (int i = 0; i < kCases; ++i) {
    const double scale = randomScale(r);
    const Triangle t = floatTriangle(r, scale);
    const Vec3 n = floatPoint(r, 1);
    compare("tri-plane general", i, t, Plane{n, Real(scale * r.uniform(-1.5, 1.5))}, tally);
  }
  report("tri-plane general", tally);
}

}  // namespace

// ---- Defects found by the model-layer property tests (double build), fixed ------------------

// A sliver (rounding-level non-collinear) triangle: RTCD's region classification and the
// plane-distance shortcut used a normal that is rounding noise and rejected a sphere that
// touches it. Now measured by its edges.
TEST(TriangleSphere, SliverTriangleIsMeasuredByItsEdges) {
  const Triangle t{Vec3(Real(-2.8926843790454511), Real(-0.70199343488746058), Real(1.1455606737941069)),
                   Vec3(Real(-2.6212904977943592), Real(-0.56899390054496957), Real(0.93524714693770716)),
                   Vec3(Real(-2.3498966165432669), Real(-0.43599436620247872), Real(0.72493362008130746))};
  const Sphere s{Vec3(Real(-2.3900854007255905), Real(-0.40613728528036508), Real(0.91365837721576804)),
                 Real(0.15229573833426094)};
  EXPECT_EQ(overlaps(t, s), crux::exact::overlaps(t, s));
  EXPECT_TRUE(overlaps(t, s));  // squared distance ~0.0221 < r² ~0.0232: not a near-tie
}

// An exactly collinear triangle mapped into a rotated box's frame: its computed normal there is
// rounding noise and used to separate wrongly. Degenerate triangles now skip the normal axis.
TEST(TriangleObb, CollinearTriangleAgainstRotatedBoxes) {
  std::mt19937_64 rng(0xC011);
  std::uniform_real_distribution<double> u(-1, 1);
  int hits = 0, cases = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vec3 a(Real(std::ldexp(std::round(u(rng) * 1024), -10)), Real(std::ldexp(std::round(u(rng) * 1024), -10)),
                 Real(std::ldexp(std::round(u(rng) * 1024), -10)));
    const Vec3 d(Real(std::ldexp(std::round(u(rng) * 64), -6)), Real(std::ldexp(std::round(u(rng) * 64), -6)),
                 Real(std::ldexp(std::round(u(rng) * 64), -6)));
    const Triangle t{a, Vec3(a + d), Vec3(a + 2 * d)};  // dyadic corners and steps: exactly collinear
    if (crux::predicates::classify(t).kind == crux::predicates::TriangleKind::Triangle) continue;
    Obb b;
    b.center = Vec3(a + d + Vec3(Real(0.6 * u(rng)), Real(0.6 * u(rng)), Real(0.6 * u(rng))));
    b.half = Vec3(Real(0.2 + 0.3 * std::abs(u(rng))), Real(0.2 + 0.3 * std::abs(u(rng))),
                  Real(0.2 + 0.3 * std::abs(u(rng))));
    b.axes = Eigen::Quaternion<Real>(Real(u(rng)), Real(u(rng)), Real(u(rng)), Real(u(rng)))
                 .normalized()
                 .toRotationMatrix();
    const bool got = overlaps(t, b), want = crux::exact::overlaps(t, b);
    ++cases;
    hits += want;
    ASSERT_EQ(got, want) << "case " << i;
  }
  EXPECT_GT(cases, 10000);
  EXPECT_GE(hits, cases / 5);
  EXPECT_LE(hits, cases * 4 / 5);
}

// Found by fuzz_geometry (tests/fuzz/corpus/geometry/crash-triangle-triangle-asymmetric-*):
// off the exact integer grid, the two argument orders of the triangle–triangle test rounded
// differently (overlaps(A, B) = false, overlaps(B, A) = true). The pair is now evaluated in one
// canonical order, so the answer is symmetric for every input.
TEST(TriangleTriangle, SymmetricOffTheExactGrid) {
  const Triangle cases[][2] = {
      {{Vec3(4, 0, 4), Vec3(-64, -64, Real(0.50110244750976562)), Vec3(-2, -3, 1)},
       {Vec3(62000, 62000, 62000), Vec3(62000, 62000, Real(-63999999167430656.0)), Vec3(0, -2, 4)}},
      {{Vec3(4, 0, 4), Vec3(-64, -27, Real(-6.1999999589629901e-14)), Vec3(33, -64, 1)},
       {Vec3(Real(5.6454718835268037e-37), 32, Real(0.03125)),
        Vec3(3, Real(-3.4028234663852886e+38), Real(1.8446652226174869e+34)), Vec3(2, 16, -64)}},
      // Two segments sharing the endpoint (62000, 62000, 62000), off the grid: the coplanarity
      // sign rounds (see docs/fuzzing.md, "Findings"); the answer must at least not depend on order.
      {{Vec3(Real(4.1999999666586518e-05), 36, 62000), Vec3(62000, 62000, 62000), Vec3(62000, 62000, 62000)},
       {Vec3(62000, 62000, 63000), Vec3(62000, 62000, 62000), Vec3(62000, 62000, 62000)}},
      {{Vec3(4, 0, 4), Vec3(-1, -2, Real(2.0000000072549875e-15)), Vec3(Real(3.8815967461797433e-43), -64, -64)},
       {Vec3(Real(8.0161123275756836), -3, -1), Vec3(4, 0, -43), Vec3(0, -64, -3)}},
  };
  for (const auto& c : cases) {
    const bool ab = overlaps(c[0], c[1]), ba = overlaps(c[1], c[0]);
    EXPECT_EQ(ab, ba) << std::setprecision(17) << "A = " << c[0].a.transpose() << " | " << c[0].b.transpose()
                      << " | " << c[0].c.transpose() << ", B = " << c[1].a.transpose() << " | "
                      << c[1].b.transpose() << " | " << c[1].c.transpose();
  }
}

// Non-queryable inputs (precondition.hpp, rule::kPrimitive): the routines behind the public entries
// (geometry/unchecked.hpp, what those entries run in release builds and the mesh, scene and contact
// layers call) give an unspecified answer, but return without undefined behaviour, which the
// sanitizer stage checks here.
TEST(TriangleOverlapPreconditions, NonQueryableInputsReturnWithoutUndefinedBehaviour) {
  const crux::test_support::BadPrimitives bad = crux::test_support::badPrimitives();
  const Triangle tri{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  const Sphere sphere{Vec3::Zero(), 1};
  const Aabb box{Vec3::Constant(-1), Vec3::Constant(1)};
  const Obb obb{Vec3::Zero(), Vec3::Ones(), Mat3::Identity()};
  const Plane plane{};
  int calls = 0;
  const auto all = [&](const Triangle& t) {
    calls += 7;
    (void)crux::unchecked::overlaps(t, tri), (void)crux::unchecked::overlaps(t, sphere), (void)crux::unchecked::overlaps(t, box);
    (void)crux::unchecked::overlaps(t, obb), (void)crux::unchecked::overlaps(t, plane);
    (void)crux::unchecked::withinDistance(t, Vec3::Zero(), 1, 0), (void)crux::unchecked::withinDistance(t, Vec3::Zero(), Vec3::Ones(), 1, 0);
  };
  for (const Triangle& t : bad.triangles) all(t);
  for (const Sphere& s : bad.spheres) (void)crux::unchecked::overlaps(tri, s), ++calls;
  for (const Aabb& b : bad.aabbs) (void)crux::unchecked::overlaps(tri, b), ++calls;
  for (const Obb& b : bad.obbs) (void)crux::unchecked::overlaps(tri, b), ++calls;
  for (const Plane& p : bad.planes) (void)crux::unchecked::overlaps(tri, p), ++calls;
  for (const Vec3& p : bad.points) {
    (void)crux::unchecked::withinDistance(tri, p, 1, 0), (void)crux::unchecked::withinDistance(tri, Vec3::Zero(), p, 1, 0);
    calls += 2;
  }
  for (const crux::Real r : crux::test_support::nonFiniteValues()) (void)crux::unchecked::withinDistance(tri, Vec3::Zero(), r, 0), ++calls;
  EXPECT_GT(calls, 120);
  EXPECT_TRUE(crux::unchecked::overlaps(tri, sphere) && crux::unchecked::overlaps(tri, box) && crux::unchecked::overlaps(tri, obb) && crux::unchecked::overlaps(tri, plane));
}

// In debug builds (CRUX_CHECK_PRIMITIVE_PRECONDITIONS, on without NDEBUG) a non-queryable input
// aborts with a message naming the query.
TEST(TriangleOverlapPreconditions, DebugBuildsAbortNamingTheQuery) {
  if (!CRUX_CHECK_PRIMITIVE_PRECONDITIONS)
    GTEST_SKIP() << "the primitive check is off in this build (NDEBUG)";
  const crux::Triangle tri{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  EXPECT_DEATH((void)crux::withinDistance(tri, Vec3::Zero(), -1, 0),
               "precondition violated in withinDistance\\(Triangle, point\\)");
  const crux::Real inf = std::numeric_limits<crux::Real>::infinity();
  EXPECT_DEATH((void)crux::overlaps(tri, crux::Triangle{Vec3::Zero(), Vec3::Ones(), Vec3(inf, 0, 0)}),
               "precondition violated in overlaps\\(Triangle, Triangle\\)");
}
