// The exact distances and contacts of oracle/exact/exact_distance.cpp, and crux's narrow phase
// against them ("contacts and distances vs the exact backend").
//
// 1. Hand-made cases whose answers follow from the geometry (integer grids): boxes at known gaps,
//    touching and penetrating; spheres; crossing capsules; degenerate triangles; coplanar hulls;
//    a cube mesh against a sphere, a box and another cube.
// 2. Native vs exact on seeded random pairs in the diff fuzzer's families (general, grid,
//    touching, degenerate, tiny, huge): crux::distance of convex pairs (gjk.hpp), convex vs mesh
//    (mesh_contact.hpp), mesh vs mesh (mesh_distance.hpp): the distance within
//    kRelative·|d| + the scale term below, the points on both shapes (their exact distance to the
//    shape's surface within the same bound) and realising the distance, and in general position
//    the points and normal themselves; contacts (adjacency off): every native point's triangle is
//    exactly within the margin (+ tolerance), no point is deeper than its triangle's exact signed
//    distance, the deepest native point is the exact deepest, and native reports contacts when
//    the exact set is non-empty away from the margin. Integer-grid mesh pairs that touch: 0 in both.
//
// Tolerance: relative kRelative = 1e-6 (the bar) + 4·kGjkScaleTolerance·S + 16 ulps of
// Real·S, S = the pair's length scale (sizes + offset): docs/narrowphase.md's documented accuracy
// (float builds: the same computation on float-rounded inputs, hence the ulps of Real).
// CRUX_TEST_SCALE scales the case counts.

#include <gtest/gtest.h>

#include <crux/error.hpp>
#include <crux/geometry/gjk.hpp>
#include <crux/geometry/overlap.hpp>
#include <crux/mesh/mesh_contact.hpp>
#include <crux/mesh/mesh_distance.hpp>
#include <exact/exact.hpp>
#include <support/grid_touching.hpp>
#include <support/test_scale.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

namespace crux {
namespace {

using Vec3d = Eigen::Vector3d;

constexpr double kRelative = 1e-6;
constexpr double kScaleUlps = 16.0 * std::numeric_limits<Real>::epsilon();

double tolerance(double d, double scale) {
  return kRelative * std::abs(d) + 4 * kGjkScaleTolerance * scale + kScaleUlps * scale;
}

std::string str(double x) {
  std::ostringstream os;
  os.precision(17);
  os << x;
  return os.str();
}
template <class V>
std::string str(const V& v) {
  return "[" + str(double(v.x())) + ", " + str(double(v.y())) + ", " + str(double(v.z())) + "]";
}
std::string str(const Transform& t) {
  return "{t " + str(t.translation) + " q [" + str(double(t.rotation.w())) + ", " + str(double(t.rotation.x())) +
         ", " + str(double(t.rotation.y())) + ", " + str(double(t.rotation.z())) + "]}";
}

// ---- shapes with owned hulls ------------------------------------------------------------------

/// A convex operand of the tests: the crux shape (a hull is owned here) and its description.
struct Shape {
  std::variant<Sphere, Obb, Capsule, Triangle, std::shared_ptr<ConvexHull>> s;
  std::vector<Vec3> hullPoints;
  ConvexShape view() const {
    return std::visit(
        [](const auto& x) -> ConvexShape {
          if constexpr (std::is_same_v<std::decay_t<decltype(x)>, std::shared_ptr<ConvexHull>>) return ConvexShape(*x);
          else return ConvexShape(x);
        },
        s);
  }
  double size() const { return double(view().size()); }
  std::string describe() const {
    std::ostringstream os;
    std::visit(
        [&](const auto& x) {
          using T = std::decay_t<decltype(x)>;
          if constexpr (std::is_same_v<T, Sphere>) os << "sphere{c " << str(x.center) << " r " << str(double(x.radius)) << "}";
          else if constexpr (std::is_same_v<T, Obb>)
            os << "box{c " << str(x.center) << " h " << str(x.half) << " axes " << str(Vec3(x.axes.col(0))) << " "
               << str(Vec3(x.axes.col(1))) << " " << str(Vec3(x.axes.col(2))) << "}";
          else if constexpr (std::is_same_v<T, Capsule>)
            os << "capsule{" << str(x.a) << " " << str(x.b) << " r " << str(double(x.radius)) << "}";
          else if constexpr (std::is_same_v<T, Triangle>) os << "triangle{" << str(x.a) << " " << str(x.b) << " " << str(x.c) << "}";
          else {
            os << "hull{";
            for (const Vec3& p : hullPoints) os << str(p) << " ";
            os << "}";
          }
        },
        s);
    return os.str();
  }
};

Shape hullOf(std::vector<Vec3> pts) {
  Shape s;
  s.hullPoints = pts;
  s.s = std::make_shared<ConvexHull>(ConvexHull::build(pts));
  return s;
}

Transform pose(Vec3 t, Quat q = Quat::Identity()) {
  Transform x;
  x.translation = t;
  x.rotation = q;
  return x;
}

Obb box(Vec3 c, Vec3 half) {
  Obb b;
  b.center = c;
  b.half = half;
  b.axes = Mat3::Identity();
  return b;
}

/// The unit cube [0,1]³ as 12 outward triangles.
Mesh cubeMesh(Vec3 lo = Vec3::Zero(), Real size = 1) {
  std::vector<Vec3> v;
  for (int k = 0; k < 8; ++k)
    v.push_back(lo + size * Vec3(Real(k & 1), Real((k >> 1) & 1), Real((k >> 2) & 1)));
  std::vector<TriangleIndices> t = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                                    {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return Mesh(v, t, "cube");
}

// ---- 1. hand-made cases ---------------------------------------------------------------------------

TEST(ExactDistance, BoxesAtKnownGaps) {
  const Obb a = box(Vec3::Zero(), Vec3(1, 1, 1)), b = box(Vec3::Zero(), Vec3(1, 1, 1));
  struct Case {
    Vec3 offset;
    double distance;
    exact::Relation relation;
  };
  const Case cases[] = {
      {Vec3(3, 0, 0), 1, exact::Relation::Separated},          // face to face
      {Vec3(3, 3, 0), std::sqrt(2.0), exact::Relation::Separated},  // edge to edge
      {Vec3(3, 3, 3), std::sqrt(3.0), exact::Relation::Separated},  // corner to corner
      {Vec3(2, 0, 0), 0, exact::Relation::Touching},           // faces touch
      {Vec3(2, 2, 2), 0, exact::Relation::Touching},           // corners touch
      {Vec3(1.5, 0.5, 0), -0.5, exact::Relation::Penetrating}, // overlap 0.5 along x
  };
  for (const Case& c : cases) {
    SCOPED_TRACE("offset " + str(c.offset));
    const exact::ExactDistance d = exact::distance(a, Transform::identity(), b, pose(c.offset));
    EXPECT_EQ(d.distance, c.distance);
    EXPECT_EQ(d.relation, c.relation);
    EXPECT_NEAR((d.pointA - d.pointB).norm(), std::abs(c.distance), 1e-15);
    if (c.distance != 0) EXPECT_NEAR((d.pointA - d.pointB).dot(d.normal), c.distance, 1e-15);
  }
  // Corner to corner: unique points and normal (from B to A).
  const exact::ExactDistance d = exact::distance(a, Transform::identity(), b, pose(Vec3(3, 3, 3)));
  EXPECT_EQ(d.pointA, Vec3d(1, 1, 1));
  EXPECT_EQ(d.pointB, Vec3d(2, 2, 2));
  EXPECT_NEAR(d.normal.dot(-Vec3d(1, 1, 1).normalized()), 1.0, 1e-15);
  // Penetrating: A must move by depth along -x: normal from B to A is -x.
  const exact::ExactDistance p = exact::distance(a, Transform::identity(), b, pose(Vec3(1.5, 0.5, 0)));
  EXPECT_EQ(p.normal, Vec3d(-1, 0, 0));
  EXPECT_EQ(p.pointA.x(), 1.0);
  EXPECT_EQ(p.pointB.x(), 0.5);
  // A quarter turn given by its rounded quaternion is the exact permutation (Snapped rule).
  const Real h = Real(std::sqrt(0.5));
  const Obb longBox = box(Vec3::Zero(), Vec3(2, 1, 1));
  const exact::ExactDistance q = exact::distance(longBox, pose(Vec3::Zero(), Quat(h, 0, 0, h)), b, pose(Vec3(0, 4, 0)));
  EXPECT_EQ(q.distance, 1.0);  // the long axis now along y: 2 + 1 + gap 1 = 4
}

TEST(ExactDistance, SpheresApartOverlappingAndConcentric) {
  const Sphere a{Vec3(0, 0, 0), 1}, b{Vec3(3, 4, 0), Real(1.5)};
  const exact::ExactDistance d = exact::distance(a, Transform::identity(), b, Transform::identity());
  EXPECT_EQ(d.distance, 2.5);
  EXPECT_NEAR((d.pointA - Vec3d(0.6, 0.8, 0)).norm(), 0, 1e-15);
  EXPECT_NEAR((d.pointB - Vec3d(2.1, 2.8, 0)).norm(), 0, 1e-15);
  const exact::ExactDistance o = exact::distance(a, Transform::identity(), Sphere{Vec3(0, 0, 1), 1}, Transform::identity());
  EXPECT_EQ(o.distance, -1.0);
  EXPECT_EQ(o.normal, Vec3d(0, 0, -1));
  const exact::ExactDistance c = exact::distance(a, Transform::identity(), Sphere{Vec3::Zero(), 2}, Transform::identity());
  EXPECT_EQ(c.distance, -3.0);
  EXPECT_EQ(c.relation, exact::Relation::Flat);
  EXPECT_NEAR(c.normal.norm(), 1.0, 1e-15);
}

TEST(ExactDistance, CrossingCapsules) {
  const Capsule a{Vec3(-1, 0, 0), Vec3(1, 0, 0), Real(0.25)};
  const Capsule above{Vec3(0, -1, 1), Vec3(0, 1, 1), Real(0.25)};
  const exact::ExactDistance d = exact::distance(a, Transform::identity(), above, Transform::identity());
  EXPECT_EQ(d.distance, 0.5);
  EXPECT_EQ(d.pointA, Vec3d(0, 0, 0.25));
  EXPECT_EQ(d.pointB, Vec3d(0, 0, 0.75));
  EXPECT_EQ(d.normal, Vec3d(0, 0, -1));
  // Crossing segments: a flat (parallelogram) Minkowski difference holding the origin.
  const Capsule crossing{Vec3(0, -1, 0), Vec3(0, 1, 0), Real(0.25)};
  const exact::ExactDistance c = exact::distance(a, Transform::identity(), crossing, Transform::identity());
  EXPECT_EQ(c.distance, -0.5);
  EXPECT_EQ(c.relation, exact::Relation::Flat);
  EXPECT_EQ(std::abs(c.normal.z()), 1.0);
  EXPECT_EQ(c.pointA - c.pointB, c.distance * c.normal);
}

TEST(ExactDistance, DegenerateTriangles) {
  const Triangle segment{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 0, 0)};
  const exact::ExactDistance d = exact::distance(segment, Transform::identity(), Sphere{Vec3(1, 1, 0), 0}, Transform::identity());
  EXPECT_EQ(d.distance, 1.0);
  EXPECT_EQ(d.pointA, Vec3d(1, 0, 0));
  const Triangle point{Vec3(1, 1, 1), Vec3(1, 1, 1), Vec3(1, 1, 1)};
  const exact::ExactDistance p = exact::distance(point, Transform::identity(), Sphere{Vec3(1, 1, 3), 1}, Transform::identity());
  EXPECT_EQ(p.distance, 1.0);
  EXPECT_EQ(p.pointB, Vec3d(1, 1, 2));
  // A collinear triangle (a segment) piercing a proper triangle: a solid difference (a prism),
  // depth 1 along the segment (its lower end is 1 below the plane; the sides are farther).
  const Triangle flat{Vec3(-8, -8, 0), Vec3(8, -8, 0), Vec3(0, 8, 0)};
  const Triangle needle{Vec3(0, 0, -1), Vec3(0, 0, 3), Vec3(0, 0, 1)};
  const exact::ExactDistance n = exact::distance(flat, Transform::identity(), needle, Transform::identity());
  EXPECT_EQ(n.relation, exact::Relation::Penetrating);
  EXPECT_EQ(n.distance, -1.0);  // the needle leaves downwards by 1 (upwards it would take 3)
  EXPECT_EQ(n.normal, Vec3d(0, 0, -1));
}

TEST(ExactDistance, HullsOfCoplanarPoints) {
  const Shape square = hullOf({Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(2, 2, 0), Vec3(0, 2, 0), Vec3(1, 1, 0)});
  const exact::ExactDistance up = exact::distance(square.view(), Transform::identity(), Sphere{Vec3(1, 1, 5), 1}, Transform::identity());
  EXPECT_EQ(up.distance, 4.0);
  EXPECT_EQ(up.pointA, Vec3d(1, 1, 0));
  const exact::ExactDistance side = exact::distance(square.view(), Transform::identity(), Sphere{Vec3(3, 1, 0), 0.5}, Transform::identity());
  EXPECT_EQ(side.distance, 0.5);
  EXPECT_EQ(side.pointA, Vec3d(2, 1, 0));
  // Two coplanar overlapping squares: flat difference, depth 0, normal ±z.
  const Shape other = hullOf({Vec3(1, 1, 0), Vec3(3, 1, 0), Vec3(3, 3, 0), Vec3(1, 3, 0)});
  const exact::ExactDistance f = exact::distance(square.view(), Transform::identity(), other.view(), Transform::identity());
  EXPECT_EQ(f.distance, 0.0);
  EXPECT_EQ(f.relation, exact::Relation::Flat);
  EXPECT_EQ(std::abs(f.normal.z()), 1.0);
  EXPECT_EQ(f.pointA, f.pointB);
}

TEST(ExactDistance, BoxThroughATriangle) {
  // A big horizontal triangle at z = 0.75 through a box [-1,1]³: the box leaves it downwards.
  const Triangle t{Vec3(-5, -5, Real(0.75)), Vec3(5, -5, Real(0.75)), Vec3(0, 5, Real(0.75))};
  const exact::ExactDistance d = exact::distance(box(Vec3::Zero(), Vec3(1, 1, 1)), Transform::identity(), t, Transform::identity());
  EXPECT_EQ(d.distance, -0.25);
  EXPECT_EQ(d.normal, Vec3d(0, 0, -1));
  EXPECT_EQ(d.pointA.z(), 1.0);
  EXPECT_EQ(d.pointB.z(), 0.75);
}

TEST(ExactDistance, CubeMeshAgainstShapesAndCubes) {
  const Mesh cube = cubeMesh();
  const exact::ExactDistance s = exact::distance(cube, Transform::identity(), Sphere{Vec3(Real(0.5), Real(0.5), 2), Real(0.5)}, Transform::identity());
  EXPECT_EQ(s.distance, 0.5);
  EXPECT_TRUE(s.triangleA == 2 || s.triangleA == 3) << s.triangleA;  // the top face
  EXPECT_EQ(s.normal, Vec3d(0, 0, -1));                                // from the sphere into the mesh
  // The docs/batch.md example: a box sunk 0.125 into the top face: two contacts (the top
  // triangles) at margin 0, each 0.125 deep.
  const Obb b = box(Vec3(Real(0.5), Real(0.5), Real(1.375)), Vec3(Real(0.25), Real(0.25), Real(0.5)));
  const std::vector<exact::ExactContact> c = exact::contacts(cube, Transform::identity(), b, Transform::identity(), 0);
  ASSERT_EQ(c.size(), 2u);
  for (const exact::ExactContact& k : c) {
    EXPECT_TRUE(k.triangle == 2 || k.triangle == 3);
    EXPECT_EQ(k.depth, 0.125);
  }
  // The side faces are 0.25 from the box: within a margin of 0.25 some side triangles join.
  EXPECT_GT(exact::contacts(cube, Transform::identity(), b, Transform::identity(), 0.25).size(), 2u);
  // Two cubes: apart, touching, crossing.
  const Mesh other = cubeMesh();
  EXPECT_EQ(exact::meshDistance(cube, Transform::identity(), other, pose(Vec3(2, 0, 0)))->distance, 1.0);
  EXPECT_EQ(exact::meshDistance(cube, Transform::identity(), other, pose(Vec3(2, 2, 0)))->distance, std::sqrt(2.0));
  EXPECT_EQ(exact::meshDistance(cube, Transform::identity(), other, pose(Vec3(1, 0, 0)))->distance, 0.0);
  const auto crossing = exact::meshDistance(cube, Transform::identity(), other, pose(Vec3(Real(0.5), Real(0.25), Real(0.25))));
  EXPECT_EQ(crossing->distance, 0.0);
  EXPECT_EQ(crossing->pointA, crossing->pointB);
  EXPECT_FALSE(exact::meshDistance(cube, Transform::identity(), other, pose(Vec3(3, 0, 0)), 1.5).has_value());
  EXPECT_TRUE(exact::meshDistance(cube, Transform::identity(), other, pose(Vec3(3, 0, 0)), 2.0).has_value());
}

// ---- 2. native vs exact on seeded random cases ---------------------------------------------------

/// The diff fuzzer's families (docs/diff.md), for the narrow phase's operands.
enum class Family { General, Grid, Touching, Degenerate, Tiny, Huge };
const char* name(Family f) {
  static const char* names[] = {"general", "grid", "touching", "degenerate", "tiny", "huge"};
  return names[int(f)];
}
constexpr Family kFamilies[] = {Family::General, Family::Grid,  Family::Touching,
                                Family::Degenerate, Family::Tiny, Family::Huge};

/// SplitMix64-driven generator (portable: no standard distributions).
struct Gen {
  std::uint64_t state;
  Family family;
  std::uint64_t next() {
    std::uint64_t z = (state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  double unit() { return double(next() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * unit(); }
  int integer(int lo, int hi) { return lo + int(next() % std::uint64_t(hi - lo + 1)); }
  bool grid() const { return family == Family::Grid || family == Family::Touching || family == Family::Degenerate; }
  double scale() const { return family == Family::Tiny ? 1e-6 : family == Family::Huge ? 1e6 : 1.0; }
  /// A coordinate: an integer in [-r, r] on the grids, else uniform in [-r, r] × scale.
  Real coord(int r) { return grid() ? Real(integer(-r, r)) : Real(uniform(-r, r) * scale()); }
  Vec3 point(int r) { return Vec3(coord(r), coord(r), coord(r)); }
  Real length(double lo, double hi) { return grid() ? Real(integer(int(lo), int(hi))) : Real(uniform(lo, hi) * scale()); }
  Quat rotation() {
    if (grid()) {  // identity or a half turn: exact in every representation
      static const Quat turns[] = {Quat(1, 0, 0, 0), Quat(0, 1, 0, 0), Quat(0, 0, 1, 0), Quat(0, 0, 0, 1)};
      return turns[integer(0, 3)];
    }
    Quat q(Real(uniform(-1, 1)), Real(uniform(-1, 1)), Real(uniform(-1, 1)), Real(uniform(-1, 1)));
    if (q.norm() < Real(0.1)) q = Quat::Identity();
    return q.normalized();
  }
  Transform pose(int r) { return crux::pose(point(r), rotation()); }
};

Shape randomShape(Gen& g) {
  Shape s;
  const bool degenerate = g.family == Family::Degenerate;
  switch (g.integer(0, 4)) {
    case 0:
      s.s = Sphere{g.point(1), degenerate ? Real(0) : g.length(1, 2) * Real(g.grid() ? 1 : 0.5)};
      break;
    case 1: {
      Obb b;
      b.center = g.point(1);
      b.half = Vec3(g.length(1, 2), g.length(1, 2), g.length(1, 2)) * Real(g.grid() ? 1 : 0.5);
      if (degenerate) b.half[g.integer(0, 2)] = 0;
      b.axes = g.grid() ? Mat3(Mat3::Identity()) : Mat3(g.rotation().toRotationMatrix());
      s.s = b;
      break;
    }
    case 2: {
      const Vec3 a = g.point(2);
      s.s = Capsule{a, degenerate ? a : g.point(2), degenerate ? Real(0) : g.length(1, 2) * Real(g.grid() ? 1 : 0.3)};
      break;
    }
    case 3: {
      Triangle t{g.point(2), g.point(2), g.point(2)};
      if (degenerate) t.c = t.a + (t.b - t.a) * Real(g.integer(-1, 2));  // collinear (or a point)
      s.s = t;
      break;
    }
    default: {
      std::vector<Vec3> pts;
      const int n = g.integer(4, 10);
      for (int i = 0; i < n; ++i) {
        Vec3 p = g.point(2);
        if (degenerate) p.z() = 0;  // coplanar (sometimes collinear, by chance)
        pts.push_back(p);
      }
      return hullOf(pts);
    }
  }
  return s;
}

/// World extents of a shape along `axis`: the placed core's extremes ± the radius.
std::pair<double, double> extent(const Shape& s, const Transform& t, int axis) {
  const ConvexShape v = s.view();
  double lo = HUGE_VAL, hi = -HUGE_VAL;
  for (int i = 0; i < v.vertexCount(); ++i) {
    const double x = double(t.apply(v.vertex(i))[axis]);
    lo = std::min(lo, x);
    hi = std::max(hi, x);
  }
  return {lo - double(v.radius), hi + double(v.radius)};
}

struct Pair {
  Shape a, b;
  Transform ta, tb;
  std::string describe() const {
    return "A " + a.describe() + " at " + str(ta) + ", B " + b.describe() + " at " + str(tb);
  }
  double scale() const {
    return a.size() + b.size() + double(ta.translation.norm()) + double(tb.translation.norm());
  }
};

Pair randomPair(Gen& g) {
  Pair p{randomShape(g), randomShape(g), g.pose(2), g.pose(2)};
  if (g.family == Family::Touching) {
    // Shift B along an axis so that its lowest extent meets A's highest (integers: exact), with
    // a random integer side offset: the pair touches or is apart, never overlaps.
    const int axis = g.integer(0, 2);
    const double shift = extent(p.a, p.ta, axis).second - extent(p.b, p.tb, axis).first;
    p.tb.translation[axis] += Real(shift);
  }
  return p;
}

/// Unsigned distance from a point to a convex shape's surface (0 when on it), exactly.
double toSurface(const Vec3& x, const Shape& s, const Transform& t) {
  return std::abs(exact::distance(Sphere{x, 0}, Transform::identity(), s.view(), t).distance);
}

TEST(NativeVsExact, ConvexPairsInEveryFamily) {
  const int perFamily = test::scaledCases(250, 60);
  for (const Family family : kFamilies) {
    Gen g{0x5eed0000u + std::uint64_t(family), family};
    int separated = 0, overlapping = 0, zeroBoth = 0, zeroExact = 0;
    double worst = 0;
    for (int i = 0; i < perFamily; ++i) {
      const Pair p = randomPair(g);
      const DistanceResult n = distance(p.a.view(), p.ta, p.b.view(), p.tb);
      const exact::ExactDistance e = exact::distance(p.a.view(), p.ta, p.b.view(), p.tb);
      const double S = p.scale(), tol = tolerance(e.distance, S);
      const std::string what = std::string(name(family)) + " case " + std::to_string(i) + ": " + p.describe() +
                               "\n  native " + str(double(n.distance)) + " pA " + str(n.pointA) + " pB " +
                               str(n.pointB) + " n " + str(n.normal) + "\n  exact  " + str(e.distance) + " pA " +
                               str(e.pointA) + " pB " + str(e.pointB) + " n " + str(e.normal) + " tol " + str(tol);
      (e.distance > 0 ? separated : overlapping)++;
      zeroExact += e.distance == 0 ? 1 : 0;
      if (e.distance == 0 && n.distance == 0) ++zeroBoth;
      worst = std::max(worst, std::abs(double(n.distance) - e.distance) / S);
      ASSERT_LE(std::abs(double(n.distance) - e.distance), tol) << what;
      // The native points: on their shapes, realising the distance.
      EXPECT_LE(toSurface(n.pointA, p.a, p.ta), tol) << "pointA not on A: " << what;
      EXPECT_LE(toSurface(n.pointB, p.b, p.tb), tol) << "pointB not on B: " << what;
      EXPECT_LE(std::abs(double((n.pointA - n.pointB).norm()) - std::abs(e.distance)), 2 * tol) << what;
      // General position: unique witnesses, compared directly (and the normal).
      if (family == Family::General && (e.relation == exact::Relation::Separated || e.relation == exact::Relation::Penetrating)) {
        const double pointTol = 1e-4 * S;
        EXPECT_LE((n.pointA.cast<double>() - e.pointA).norm(), pointTol) << what;
        EXPECT_LE((n.pointB.cast<double>() - e.pointB).norm(), pointTol) << what;
        EXPECT_GE(n.normal.cast<double>().dot(e.normal), 1 - 1e-6) << what;
      }
    }
    std::printf("%-10s %d pairs: %d separated, %d touching/overlapping, exactly 0: %d exact, %d of them native too; "
                "worst |native - exact| / S = %.3g\n",
                name(family), perFamily, separated, overlapping, zeroExact, zeroBoth, worst);
    EXPECT_GE(separated, perFamily / 10) << name(family);
    if (family != Family::Touching) EXPECT_GE(overlapping, perFamily / 20) << name(family);
  }
}

/// A soup of small triangles around the origin (integer corners on the grids).
Mesh randomSoup(Gen& g, int count) {
  std::vector<Vec3> v;
  std::vector<TriangleIndices> t;
  for (int i = 0; i < count; ++i) {
    const Vec3 c = g.point(2);
    for (int k = 0; k < 3; ++k) v.push_back(c + g.point(1));
    if (g.family == Family::Degenerate && i % 3 == 0) v.back() = v[v.size() - 2];
    t.push_back({std::uint32_t(3 * i), std::uint32_t(3 * i + 1), std::uint32_t(3 * i + 2)});
  }
  return Mesh(v, t, "soup");
}

std::string describe(const Mesh& m) {
  std::string out = "mesh{";
  for (std::uint32_t t = 0; t < m.triangleCount(); ++t) {
    const Triangle x = m.triangle(t);
    out += "[" + str(x.a) + " " + str(x.b) + " " + str(x.c) + "] ";
  }
  return out + "}";
}

double meshSize(const Mesh& m) {
  double r = 0;
  for (const Vec3& v : m.vertices()) r = std::max(r, double(v.norm()));
  return r;
}

TEST(NativeVsExact, ConvexAgainstMeshDistanceAndContacts) {
  const int perFamily = test::scaledCases(40, 12);
  for (const Family family : kFamilies) {
    Gen g{0x3e5c0000u + std::uint64_t(family), family};
    int contactsSeen = 0, pointsChecked = 0;
    for (int i = 0; i < perFamily; ++i) {
      const Mesh mesh = randomSoup(g, 12);
      const Shape shape = randomShape(g);
      const Transform tm = g.pose(1), ts = g.pose(2);
      const double S = meshSize(mesh) + shape.size() + double(tm.translation.norm()) + double(ts.translation.norm());
      const std::string what = std::string(name(family)) + " case " + std::to_string(i) + ": shape " +
                               shape.describe() + " at " + str(ts) + ", mesh at " + str(tm) + " " + describe(mesh);
      // Distance: the minimum over triangles.
      const MeshDistanceResult n = distance(mesh, tm, shape.view(), ts);
      const exact::ExactDistance e = exact::distance(mesh, tm, shape.view(), ts);
      const double tol = tolerance(e.distance, S);
      ASSERT_TRUE(n.found) << what;
      ASSERT_LE(std::abs(double(n.distance) - e.distance), tol)
          << what << "\n  native " << str(double(n.distance)) << " triangle " << n.triangle << "\n  exact  "
          << str(e.distance) << " triangle " << e.triangleA;
      // Per-triangle exact signed distances.
      std::vector<double> per(mesh.triangleCount());
      for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t)
        per[t] = exact::distance(mesh.triangle(t), tm, shape.view(), ts).distance;
      EXPECT_LE(std::abs(double(n.distance) - per[n.triangle]), tol) << "native's triangle: " << what;
      // Contacts, adjacency off.
      const double margin = g.unit() * 0.5 * g.scale();
      MeshContactManifold m;
      contacts(mesh, tm, shape.view(), ts, Real(margin), m, nullptr);
      const double deepest = *std::min_element(per.begin(), per.end());
      const double ctol = tolerance(deepest, S) + tolerance(margin, S);
      const std::string cwhat = what + " margin " + str(margin) + " exact deepest " + str(deepest);
      double nativeDeepest = HUGE_VAL;
      for (int k = 0; k < m.count; ++k) {
        const MeshContactPoint& c = m.points[k];
        ++pointsChecked;
        EXPECT_LE(per[c.triangle], margin + ctol) << "triangle " << c.triangle << " not within margin: " << cwhat;
        EXPECT_GE(double(c.separation), per[c.triangle] - ctol)
            << "point deeper than its triangle " << c.triangle << " (" << str(double(c.separation)) << "): " << cwhat;
        nativeDeepest = std::min(nativeDeepest, double(c.separation));
      }
      if (deepest <= margin - ctol) {
        ++contactsSeen;
        ASSERT_GT(m.count, 0) << "no native contact: " << cwhat;
        EXPECT_LE(std::abs(nativeDeepest - deepest), ctol) << "deepest: native " << str(nativeDeepest) << ": " << cwhat;
      } else if (deepest > margin + ctol) {
        EXPECT_EQ(m.count, 0) << cwhat;
      }
      // The exact contacts: exactly the triangles within the margin (ascending). The mesh queries
      // place only the triangles their conservative boxes cannot rule out (LazyPlaced): the
      // per-triangle answers here place every one, so the minimum is the mesh distance bit for bit.
      const std::vector<exact::ExactContact> ec = exact::contacts(mesh, tm, shape.view(), ts, margin);
      std::vector<std::uint32_t> within, got;
      for (std::uint32_t t = 0; t < per.size(); ++t)
        if (per[t] <= margin) within.push_back(t);
      for (const exact::ExactContact& c : ec) got.push_back(c.triangle);
      EXPECT_EQ(got, within) << cwhat;
      EXPECT_EQ(e.distance, deepest) << what;
      EXPECT_EQ(e.distance, per[e.triangleA]) << what;
    }
    std::printf("%-10s %d shape-mesh cases, %d with contacts, %d native contact points checked\n", name(family),
                perFamily, contactsSeen, pointsChecked);
    EXPECT_GT(contactsSeen, perFamily / 10) << name(family);
  }
}

TEST(NativeVsExact, MeshMeshDistance) {
  const int perFamily = test::scaledCases(25, 8);
  for (const Family family : kFamilies) {
    Gen g{0x3e5b0000u + std::uint64_t(family), family};
    int zeros = 0;
    for (int i = 0; i < perFamily; ++i) {
      const Mesh a = randomSoup(g, 10), b = randomSoup(g, 10);
      Transform ta = g.pose(1), tb = g.pose(3);
      if (g.grid() && g.integer(0, 1)) {  // quarter turns: crux maps them as exact permutations
        const Real h = Real(std::sqrt(0.5)), q = Real(0.5);
        const Quat turns[] = {Quat(h, h, 0, 0), Quat(h, 0, h, 0), Quat(h, 0, 0, h), Quat(q, q, q, q)};
        tb.rotation = turns[g.integer(0, 3)];
      }
      const double S = meshSize(a) + meshSize(b) + double(ta.translation.norm()) + double(tb.translation.norm());
      const MeshMeshDistanceResult n = distance(a, ta, b, tb, MeshDistanceOptions{});
      const std::optional<exact::ExactDistance> e = exact::meshDistance(a, ta, b, tb);
      ASSERT_TRUE(e && n.found);
      const double tol = tolerance(e->distance, S);
      const std::string what = std::string(name(family)) + " case " + std::to_string(i) + ": a " + describe(a) +
                               " at " + str(ta) + "\n  b " + describe(b) + " at " + str(tb) + "\n  native " + str(double(n.distance)) + " triangles " +
                               std::to_string(n.triangleA) + "," + std::to_string(n.triangleB) + "\n  exact  " +
                               str(e->distance) + " triangles " + std::to_string(e->triangleA) + "," +
                               std::to_string(e->triangleB);
      ASSERT_LE(std::abs(double(n.distance) - e->distance), tol) << what;
      if (g.grid() && e->distance == 0) {
        ++zeros;
        EXPECT_EQ(n.distance, 0) << "touching grid meshes: " << what;
      }
      // Native points on both surfaces (the exact distance of each point to its mesh).
      EXPECT_LE(exact::distance(a, ta, Sphere{n.pointA, 0}, Transform::identity()).distance, tol) << what;
      EXPECT_LE(exact::distance(b, tb, Sphere{n.pointB, 0}, Transform::identity()).distance, tol) << what;
      EXPECT_LE(exact::distance(a, ta, Sphere{Vec3(e->pointA.cast<Real>()), 0}, Transform::identity()).distance, tol) << what;
    }
    std::printf("%-10s %d mesh pairs, %d touching or crossing on the grid\n", name(family), perFamily, zeros);
  }
}

/// A height field of n × n unit quads (two triangles each) over [0, n]², scaled by the family's
/// scale; heights are the family's coordinates in [-1, 1] (integers on the grids).
Mesh terrain(Gen& g, int n) {
  std::vector<Vec3> v;
  std::vector<TriangleIndices> t;
  const Real s = Real(g.scale());
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) v.push_back(Vec3(Real(x) * s, Real(y) * s, g.coord(1)));
  auto at = [&](int x, int y) { return std::uint32_t(y * (n + 1) + x); };
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      t.push_back({at(x, y), at(x + 1, y), at(x + 1, y + 1)});
      t.push_back({at(x, y), at(x + 1, y + 1), at(x, y + 1)});
    }
  return Mesh(v, t, "terrain");
}

// exact::meshDistance searches two trees of conservative triangle boxes (it tested all
// n·m pairs before). Its answer must be the minimum over every triangle pair's exact distance,
// bit for bit, including near ties: two terrains face to face (b turned over above a), apart,
// touching (the grids) or crossing, and a distance limit just below and just above the answer. An
// over-eager prune (a pair dropped that could beat or tie the best) fails here.
TEST(ExactMeshDistance, TreeSearchEqualsTheMinimumOverEveryTrianglePair) {
  const int perFamily = test::scaledCases(3, 1);
  int separated = 0, zero = 0;
  for (const Family family : kFamilies) {
    Gen g{0x3e5d0000u + std::uint64_t(family), family};
    for (int i = 0; i < perFamily; ++i) {
      const Mesh a = terrain(g, 3), b = terrain(g, 3);
      const Transform ta = g.pose(1);
      Transform tb = ta;  // b turned over (a half turn about x) and lifted along a's z
      tb.rotation = (ta.rotation * Quat(0, 1, 0, 0)).normalized();
      const Real lift = Real(g.grid() ? g.integer(0, 3) : g.uniform(-0.5, 3) * g.scale());
      tb.translation = ta.translation + ta.rotation * Vec3(0, Real(3 * g.scale()), lift);
      double best = HUGE_VAL;
      std::vector<double> per(std::size_t(a.triangleCount()) * b.triangleCount());
      for (std::uint32_t x = 0; x < a.triangleCount(); ++x)
        for (std::uint32_t y = 0; y < b.triangleCount(); ++y) {
          per[x * b.triangleCount() + y] = exact::distance(a.triangle(x), ta, b.triangle(y), tb).distance;
          best = std::min(best, per[x * b.triangleCount() + y]);
        }
      const std::string what = std::string(name(family)) + " case " + std::to_string(i) + ": lift " + str(double(lift)) +
                               " a at " + str(ta) + ", b at " + str(tb) + ", minimum over pairs " + str(best);
      const std::optional<exact::ExactDistance> e = exact::meshDistance(a, ta, b, tb);
      ASSERT_TRUE(e.has_value()) << what;
      const double pair = per[e->triangleA * b.triangleCount() + e->triangleB];
      if (best > 0) {
        ++separated;
        EXPECT_EQ(e->distance, best) << what;
        EXPECT_EQ(pair, best) << "triangles " << e->triangleA << "," << e->triangleB << ": " << what;
        // (the answer is rounded from the exact squared distance: a limit 1e-12 below or above it)
        EXPECT_FALSE(exact::meshDistance(a, ta, b, tb, best * (1 - 1e-12)).has_value()) << what;
        const std::optional<exact::ExactDistance> at = exact::meshDistance(a, ta, b, tb, best * (1 + 1e-12));
        ASSERT_TRUE(at.has_value()) << what;
        EXPECT_EQ(at->distance, best) << what;
      } else {
        ++zero;
        EXPECT_EQ(e->distance, 0.0) << what;
        EXPECT_LE(pair, 0.0) << "triangles " << e->triangleA << "," << e->triangleB << " apart: " << what;
      }
    }
  }
  std::printf("%d terrain pairs apart, %d touching or crossing\n", separated, zero);
  EXPECT_GT(separated, 0);
  EXPECT_GT(zero, 0);
}

// withinDistance (overlap.hpp) on two cores of 1-3 points against the exact backend's contacts
// verdict (within the margin, decided in rationals): points, segments and triangles (degenerate
// ones included) on a small integer grid, integer radii, the margin the exact distance rounded to
// an integer (so many pairs sit exactly at it). The predicate decides the convex pair and
// sphere/capsule-triangle contacts at the margin (docs/narrowphase.md).
TEST(WithinDistance, EqualsTheExactContactsVerdictOnTheGrid) {
  test::GridDraws draws(0x3e5e0000u);
  const int cases = test::scaledCases(600, 120);
  int atTheMargin = 0, within = 0;
  for (int i = 0; i < cases; ++i) {
    Vec3 pa[3], pb[3];
    const int na = draws.integer(1, 3), nb = draws.integer(1, 3);
    for (Vec3& v : pa) v = draws.point(3);
    for (Vec3& v : pb) v = draws.point(3) + Vec3(Real(draws.integer(0, 4)), 0, 0);
    if (draws.integer(0, 4) == 0) pa[2] = pa[1];  // degenerate cores now and then
    if (draws.integer(0, 4) == 0) pb[1] = pb[0];
    const Real ra = na == 3 ? Real(0) : Real(draws.integer(0, 1)), rb = nb == 3 ? Real(0) : Real(draws.integer(0, 1));
    auto shape = [](const Vec3* p, int n, Real r) {
      return n == 1 ? ConvexShape(Sphere{p[0], r}) : n == 2 ? ConvexShape(Capsule{p[0], p[1], r}) : ConvexShape(Triangle{p[0], p[1], p[2]});
    };
    const ConvexShape A = shape(pa, na, ra), B = shape(pb, nb, rb);
    const double d = exact::distance(A, Transform::identity(), B, Transform::identity()).distance;
    const Real margin = Real(std::max(0.0, std::round(d)));
    const bool exactWithin = !exact::contacts(A, Transform::identity(), B, Transform::identity(), double(margin)).empty();
    WVec3 wa[3], wb[3];
    for (int k = 0; k < 3; ++k) wa[k] = wide(pa[k]), wb[k] = wide(pb[k]);
    const bool got = withinDistance(wa, na, wb, nb, Wide(ra), Wide(rb), Wide(margin));
    atTheMargin += d == double(margin);
    within += exactWithin;
    EXPECT_EQ(got, exactWithin) << "case " << i << ": " << na << " and " << nb << " points, radii " << ra << ", " << rb
                                << ", margin " << margin << ", exact distance " << str(d);
    ContactManifold m;
    EXPECT_EQ(contacts(A, Transform::identity(), B, Transform::identity(), margin, m), exactWithin) << "contacts, case " << i;
  }
  std::printf("%d core pairs, %d within the margin, %d exactly at it\n", cases, within, atTheMargin);
  EXPECT_GT(atTheMargin, cases / 20);
  EXPECT_THROW(withinDistance(nullptr, 0, nullptr, 1, 0, 0, 0), InvalidInput);
}

/// contacts(P, Q) and contacts(Q, P) at the margin the exact distance rounds to (>= 0) against the
/// exact backend's verdict there; counts the pairs within the margin and exactly at it.
void expectContactsVerdictAtTheRoundedDistance(const ConvexShape& P, const ConvexShape& Q, const std::string& what,
                                               int& within, int& atTheMargin) {
  const Transform I = Transform::identity();
  const double d = exact::distance(P, I, Q, I).distance;
  const Real margin = Real(std::max(0.0, std::round(d)));
  const bool exactWithin = !exact::contacts(P, I, Q, I, double(margin)).empty();
  atTheMargin += d == double(margin);
  within += exactWithin;
  ContactManifold m;
  const std::string where = what + ", margin " + std::to_string(double(margin)) + ", exact distance " + str(d);
  EXPECT_EQ(contacts(P, I, Q, I, margin, m), exactWithin) << where;
  EXPECT_EQ(contacts(Q, I, P, I, margin, m), exactWithin) << "(swapped) " << where;
}

// contacts() of a box or a hull of 4-6 points against a core of 1-3 points (sphere, capsule,
// triangle) against the exact backend's verdict, on the grid with the margin the exact distance
// rounded to an integer (many pairs exactly at it): the polytope's exact margin decision
// (boundary triangles and containment, contact.cpp) where the GJK distance is within rounding.
TEST(ExactContacts, PolytopeAgainstACoreEqualsTheExactVerdictOnTheGrid) {
  test::GridDraws draws(0x9017e5u);
  const int cases = test::scaledCases(600, 120);
  int atTheMargin = 0, within = 0, hulls = 0;
  for (int i = 0; i < cases; ++i) {
    std::vector<Vec3> pts;
    for (int j = draws.integer(4, 6); j > 0; --j) pts.push_back(draws.point(3));
    const ConvexHull hull = ConvexHull::build(pts);
    const Obb box{draws.point(3), Vec3(Real(draws.integer(1, 3)), Real(draws.integer(0, 2)), Real(draws.integer(1, 2))), Mat3::Identity()};
    const bool useHull = i % 2 == 1 && hull.vertices().size() > 3;
    hulls += useHull;
    const ConvexShape P = useHull ? ConvexShape(hull) : ConvexShape(box);
    Vec3 q[3];
    for (Vec3& v : q) v = draws.point(3) + Vec3(Real(draws.integer(2, 6)), 0, 0);
    const int nq = draws.integer(1, 3);
    const Real r = nq == 3 ? Real(0) : Real(draws.integer(0, 1));
    const ConvexShape Q = nq == 1 ? ConvexShape(Sphere{q[0], r})
                          : nq == 2 ? ConvexShape(Capsule{q[0], q[1], r})
                                    : ConvexShape(Triangle{q[0], q[1], q[2]});
    expectContactsVerdictAtTheRoundedDistance(
        P, Q, "case " + std::to_string(i) + (useHull ? ": hull" : ": box") + " vs a core of " + std::to_string(nq) + " points",
        within, atTheMargin);
  }
  std::printf("%d polytope-core pairs (%d hulls), %d within the margin, %d exactly at it\n", cases, hulls, within,
              atTheMargin);
  EXPECT_GT(atTheMargin, cases / 20);
  EXPECT_GT(hulls, cases / 4);
}

// contacts() of two polytopes (boxes and hulls of 4-6 points, both kinds against each other)
// against the exact backend's verdict, on the grid with the margin the exact distance rounded to
// an integer (many pairs exactly at it): the two polytopes' exact margin decision (containment
// and boundary-triangle pairs, contact.cpp's polytopesWithin) where GJK's distance is within
// rounding, in both operand orders.
TEST(ExactContacts, TwoPolytopesEqualTheExactVerdictOnTheGrid) {
  test::GridDraws draws(0x9017e6u);
  const int cases = test::scaledCases(400, 80);
  int atTheMargin = 0, within = 0, hullPairs = 0;
  auto polytope = [&](std::unique_ptr<ConvexHull>& keep, const Vec3& shift, bool hull) {
    if (hull) {
      std::vector<Vec3> pts;
      for (int j = draws.integer(4, 6); j > 0; --j) pts.push_back(draws.point(3) + shift);
      keep = std::make_unique<ConvexHull>(ConvexHull::build(pts));
      if (keep->vertices().size() > 3) return ConvexShape(*keep);
    }
    return ConvexShape(Obb{draws.point(3) + shift,
                           Vec3(Real(draws.integer(1, 3)), Real(draws.integer(0, 2)), Real(draws.integer(1, 2))),
                           Mat3::Identity()});
  };
  for (int i = 0; i < cases; ++i) {
    std::unique_ptr<ConvexHull> ha, hb;
    const ConvexShape P = polytope(ha, Vec3::Zero(), i % 3 != 0);
    const ConvexShape Q = polytope(hb, Vec3(Real(draws.integer(2, 7)), 0, 0), i % 3 != 2);
    hullPairs += P.kind == ConvexKind::Hull && Q.kind == ConvexKind::Hull;
    expectContactsVerdictAtTheRoundedDistance(P, Q, "case " + std::to_string(i), within, atTheMargin);
  }
  std::printf("%d polytope pairs (%d hull-hull), %d within the margin, %d exactly at it\n", cases, hullPairs, within,
              atTheMargin);
  EXPECT_GT(atTheMargin, cases / 20);
  EXPECT_GT(hullPairs, cases / 5);
}

}  // namespace
}  // namespace crux
