// Tests of src/geometry/box_triangle_contact.cpp: named configurations (a box resting on a big
// triangle, a triangle edge lying on a box face, degenerate triangles, flat boxes), seeded
// properties against the generic GJK/EPA + clipping routine of contact.hpp over thousands of
// cases in seven families, penetration depth against libccd, integer-grid cases against the
// exact (CGAL) overlap and an exact integer SAT (touching gives separation 0 exactly), the
// routine's shortcuts against its full SAT bit for bit, no heap allocation, and a
// microbenchmark (printed, not asserted).

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <crux/geometry/box_triangle_contact.hpp>
#include <crux/geometry/closest_point.hpp>
#include <crux/geometry/gjk.hpp>
#include <cstdio>
#include <cstring>
#include <exact/exact_kernel.hpp>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <support/allocation_counter.hpp>
#include <support/printing.hpp>
#include <support/test_scale.hpp>
#include <vector>

#include <crux/precondition.hpp>
#include "geometry/unchecked.hpp"
#include "support/bad_inputs.hpp"

#if CRUX_HAVE_CCD_ORACLE
#include "ccd/ccd_oracle.hpp"
#endif

namespace crux {
namespace {

using test_support::str;
using V3d = Eigen::Vector3d;
constexpr double kEpsReal = std::numeric_limits<Real>::epsilon();

/// Tolerance of geometric checks (points on surfaces, pointA − pointB = sep·n): the rounding of
/// the returned Real values (the computation is double) × the pair's length scale.
constexpr double kCheckUlps = 64;
/// Depth along a normal vs the generic (EPA) distance: the face bias of the routine (relative to
/// the scale rounded up to a power of two, < 2·scale) plus the accuracy of EPA
/// (docs/narrowphase.md: 1e-6 relative, + float ulps, added where used).
constexpr double kDepthRelative = 2 * kBoxTriangleFaceBias + 1e-6;
/// Distances this close to the margin may get either verdict (the generic routine's accuracy).
constexpr double kVerdictBandRelative = 1e-6;

struct Case {
  Vec3 half = Vec3::Ones();
  Triangle tri;
  Real margin = 0;
};

std::string describe(const Case& c) {
  return "half " + str(c.half) + " tri " + str(c.tri.a) + " " + str(c.tri.b) + " " + str(c.tri.c) + " margin " +
         str(double(c.margin));
}

std::string describe(const ContactManifold& m) {
  std::ostringstream os;
  os << "normal " << str(m.normal) << ", " << m.count << " points:";
  for (int i = 0; i < m.count; ++i)
    os << "\n  A " << str(m.points[i].pointA) << " B " << str(m.points[i].pointB) << " sep "
       << str(double(m.points[i].separation)) << " fa " << std::hex << m.points[i].featureA << " fb "
       << m.points[i].featureB << std::dec;
  return os.str();
}

Obb boxOf(const Case& c) {
  Obb b;
  b.half = c.half;
  return b;
}

bool generic(const Case& c, ContactManifold& out) {
  return contacts(ConvexShape(c.tri), Transform{}, ConvexShape(boxOf(c)), Transform{}, c.margin, out);
}

double scaleOf(const Case& c) {
  return std::max({1e-30, double(c.half.cwiseAbs().maxCoeff()), double(c.tri.a.cwiseAbs().maxCoeff()),
                   double(c.tri.b.cwiseAbs().maxCoeff()), double(c.tri.c.cwiseAbs().maxCoeff())});
}

/// Separation of the triangle from the box along unit u (u from the box to the triangle):
/// min of the triangle along u minus the box's support along u. A lower bound of the distance.
double sepAlong(const Case& c, const V3d& u) {
  const double lo =
      std::min({u.dot(c.tri.a.cast<double>()), u.dot(c.tri.b.cast<double>()), u.dot(c.tri.c.cast<double>())});
  return lo - c.half.cast<double>().dot(u.cwiseAbs());
}

/// n is a box face normal or ± the triangle's normal (up to the rounding of a returned Real).
bool isFaceNormal(const Case& c, const V3d& n) {
  const V3d m =
      (c.tri.b.cast<double>() - c.tri.a.cast<double>()).cross(c.tri.c.cast<double>() - c.tri.a.cast<double>());
  return n.cwiseAbs().maxCoeff() == 1 || (m.norm() > 0 && std::abs(m.normalized().dot(n)) >= 1 - 8 * kEpsReal);
}

double minSeparation(const ContactManifold& m) {
  double s = std::numeric_limits<double>::infinity();
  for (int i = 0; i < m.count; ++i) s = std::min(s, double(m.points[i].separation));
  return s;
}

/// Invariants of a manifold, independent of how it was made: unit normal, <= 4 points, every
/// pointA on the triangle (closest-point distance), every pointB on the box's surface,
/// pointA − pointB = separation·normal, separation <= margin. Returns false (and reports) on
/// the first violation.
::testing::AssertionResult wellFormed(const Case& c, const ContactManifold& m) {
  const double S = scaleOf(c) + double(c.margin);
  const double tol = kCheckUlps * kEpsReal * S;
  auto fail = [&](const std::string& what) {
    return ::testing::AssertionFailure() << what << "\n" << describe(c) << "\n" << describe(m);
  };
  if (m.count < 1 || m.count > ContactManifold::kMaxContactPoints) return fail("point count");
  if (!(std::abs(double(m.normal.norm()) - 1) <= 8 * kEpsReal)) return fail("normal not unit");
  const V3d h = c.half.cast<double>();
  for (int i = 0; i < m.count; ++i) {
    const ContactPoint& p = m.points[i];
    const V3d a = p.pointA.cast<double>(), b = p.pointB.cast<double>();
    if (!std::isfinite(a.sum() + b.sum() + double(p.separation))) return fail("non-finite point");
    // On the triangle: its closest point, or (well conditioned on slivers and segments) its edges.
    double dA = double(squaredDistance(c.tri, p.pointA));
    for (int e = 0; e < 3; ++e)
      dA = std::min(dA, double(squaredDistance(Segment{c.tri[e], c.tri[(e + 1) % 3]}, p.pointA)));
    if (!(std::sqrt(dA) <= tol)) return fail("pointA not on the triangle");
    const V3d excess = b.cwiseAbs() - h;
    if (!(excess.maxCoeff() <= tol)) return fail("pointB outside the box");
    if (!(excess.maxCoeff() >= -tol)) return fail("pointB inside the box, not on its surface");
    if (!((a - b - double(p.separation) * m.normal.cast<double>()).norm() <= tol))
      return fail("pointA - pointB != separation * normal");
    if (!(double(p.separation) <= double(c.margin) + tol)) return fail("separation > margin");
  }
  return ::testing::AssertionSuccess();
}

/// Seeded case generator, families as in the brief.
struct Gen {
  std::mt19937_64 rng;
  explicit Gen(std::uint64_t seed) : rng(seed) {}
  double uni(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); }
  int pick(int n) { return int(std::uniform_int_distribution<int>(0, n - 1)(rng)); }
  V3d vec(double r) { return V3d(uni(-r, r), uni(-r, r), uni(-r, r)); }
  V3d unit() {
    V3d v;
    do v = vec(1);
    while (v.squaredNorm() > 1 || v.squaredNorm() < 1e-4);
    return v.normalized();
  }
  Vec3 half() { return Vec3(Real(uni(0.1, 2)), Real(uni(0.1, 2)), Real(uni(0.1, 2))); }
  Real margin() {
    const double ms[] = {0, 0, 0.02, 0.2};
    return Real(ms[pick(4)]);
  }
  static Triangle tri(const V3d& a, const V3d& b, const V3d& c) {
    return Triangle{a.cast<Real>(), b.cast<Real>(), c.cast<Real>()};
  }

  /// family 0 general, 1 near a box face (tilt up to ~3°, offset ±0.3), 2 a triangle edge near a
  /// box edge, 3 a triangle vertex near a box corner, 4 degenerate (segment / point), 5 flat box,
  /// 6 big triangle under a small box (mesh-like).
  Case make(int family) {
    Case c;
    c.half = half();
    c.margin = margin();
    const V3d h = c.half.cast<double>();
    switch (family) {
      case 0:
        c.tri = tri(vec(3), vec(3), vec(3));
        break;
      case 1: {
        const int k = pick(3);
        const double s = pick(2) ? 1 : -1;
        const double off = uni(-0.3, 0.3);
        V3d n = V3d::Unit(k) * s + unit() * uni(0, 0.05);
        n.normalize();
        const V3d u = n.unitOrthogonal(), v = n.cross(u);
        const V3d o = V3d::Unit(k) * s * (h[k] + off) + u * uni(-1, 1) + v * uni(-1, 1);
        const double r = uni(0.2, 3), a0 = uni(0, 6.3);
        V3d p[3];
        for (int i = 0; i < 3; ++i) {
          const double a = a0 + i * 2.1 + uni(-0.3, 0.3);
          p[i] = o + r * (std::cos(a) * u + std::sin(a) * v);
        }
        c.tri = tri(p[0], p[1], p[2]);
        break;
      }
      case 2: {
        const int i = pick(3);
        V3d corner(pick(2) ? h.x() : -h.x(), pick(2) ? h.y() : -h.y(), pick(2) ? h.z() : -h.z());
        corner[i] = uni(-h[i], h[i]);
        const V3d out = (corner - V3d::Unit(i) * corner[i]).normalized();
        const V3d mid = corner + out * uni(-0.2, 0.2);
        const V3d dir = unit();
        const double len = uni(0.5, 3);
        const V3d a = mid - dir * len * uni(0.2, 0.8), b = a + dir * len;
        const V3d third = mid + out * uni(0.3, 2) + vec(0.5);
        c.tri = tri(a, b, third);
        break;
      }
      case 3: {
        const V3d corner(pick(2) ? h.x() : -h.x(), pick(2) ? h.y() : -h.y(), pick(2) ? h.z() : -h.z());
        const V3d tip = corner + vec(0.2);
        const V3d away = (corner + unit() * 0.5).normalized();
        c.tri = tri(tip, tip + away * uni(0.5, 2) + vec(0.8), tip + away * uni(0.5, 2) + vec(0.8));
        break;
      }
      case 4: {
        const V3d a = vec(2.5), b = pick(3) == 0 ? a : V3d(vec(2.5));
        const double t = uni(-0.5, 1.5);
        c.tri = pick(2) ? tri(a, b, a + t * (b - a)) : tri(a, a + t * (b - a), b);
        break;
      }
      case 5: {
        c.half[pick(3)] = 0;
        if (pick(4) == 0) c.half[pick(3)] = 0;
        c.tri = tri(vec(2.5), vec(2.5), vec(2.5));
        break;
      }
      default: {
        c.half = c.half * Real(0.25);
        const V3d n = (V3d::UnitZ() + unit() * 0.3).normalized();
        const V3d u = n.unitOrthogonal(), v = n.cross(u);
        const V3d o = vec(0.3) - n * (c.half.cast<double>().dot(n.cwiseAbs()) + uni(-0.2, 0.1));
        const double a0 = uni(0, 6.3);
        V3d p[3];
        for (int i = 0; i < 3; ++i) p[i] = o + 5 * (std::cos(a0 + 2.1 * i) * u + std::sin(a0 + 2.1 * i) * v);
        c.tri = tri(p[0], p[1], p[2]);
        break;
      }
    }
    return c;
  }
};

// ---- named configurations -------------------------------------------------------------------

TEST(BoxTriangleContact, BoxRestingOnABigTriangleGivesItsFourCorners) {
  Case c;
  c.half = Vec3(Real(0.5), Real(0.25), 1);
  c.tri = Triangle{Vec3(-10, -10, Real(-0.9)), Vec3(10, -10, Real(-0.9)), Vec3(0, 10, Real(-0.9))};
  ContactManifold m;
  ASSERT_TRUE(boxTriangleContacts(c.half, c.tri, 0, m));
  ASSERT_TRUE(wellFormed(c, m));
  ASSERT_EQ(m.count, 4) << describe(m);
  EXPECT_EQ(m.normal, Vec3(0, 0, -1)) << describe(m);
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(double(m.points[i].separation), -0.1, 8 * kEpsReal) << describe(m);
    EXPECT_EQ(std::abs(m.points[i].pointB.x()), Real(0.5)) << describe(m);
    EXPECT_EQ(std::abs(m.points[i].pointB.y()), Real(0.25)) << describe(m);
    EXPECT_EQ(m.points[i].featureA, featureId(FeatureKind::Face, 0)) << describe(m);  // box on the front side
    EXPECT_EQ(m.points[i].featureB >> 24, std::uint32_t(FeatureKind::Vertex)) << describe(m);
  }
}

TEST(BoxTriangleContact, TriangleBelowTheBoxFromTheBackIsTheBackFace) {
  Case c;
  c.tri = Triangle{Vec3(-10, -10, Real(-0.9)), Vec3(0, 10, Real(-0.9)), Vec3(10, -10, Real(-0.9))};  // normal −z
  ContactManifold m;
  ASSERT_TRUE(boxTriangleContacts(c.half, c.tri, 0, m));
  ASSERT_TRUE(wellFormed(c, m));
  ASSERT_EQ(m.count, 4) << describe(m);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(m.points[i].featureA, featureId(FeatureKind::Face, 1)) << describe(m);
}

TEST(BoxTriangleContact, TriangleEdgeLyingOnABoxFaceIsAFaceContact) {
  // The edge (−3,0,1)–(3,0,1) lies on the +z face: the z face axis ties the edge axes; the face
  // wins and the edge is clipped to the face (two points at x = ±1, separation 0 exactly).
  Case c;
  c.tri = Triangle{Vec3(-3, 0, 1), Vec3(3, 0, 1), Vec3(0, Real(0.5), 4)};
  ContactManifold m;
  ASSERT_TRUE(boxTriangleContacts(c.half, c.tri, 0, m));
  ASSERT_TRUE(wellFormed(c, m));
  ASSERT_EQ(m.count, 2) << describe(m);
  EXPECT_EQ(m.normal, Vec3(0, 0, 1)) << describe(m);
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(m.points[i].separation, 0) << describe(m);
    EXPECT_EQ(std::abs(m.points[i].pointA.x()), 1) << describe(m);
    EXPECT_EQ(m.points[i].featureB, featureId(FeatureKind::Face, 5)) << describe(m);
    EXPECT_EQ(m.points[i].featureA, featureId(FeatureKind::Edge, 0 * 64 + 1)) << describe(m);
  }
}

TEST(BoxTriangleContact, PointTriangleIsAVertexContact) {
  Case c;
  c.tri = Triangle{Vec3(Real(0.2), Real(0.3), Real(0.9)), Vec3(Real(0.2), Real(0.3), Real(0.9)),
                   Vec3(Real(0.2), Real(0.3), Real(0.9))};
  ContactManifold m;
  ASSERT_TRUE(boxTriangleContacts(c.half, c.tri, 0, m));
  ASSERT_TRUE(wellFormed(c, m));
  ASSERT_EQ(m.count, 1) << describe(m);
  EXPECT_EQ(m.normal, Vec3(0, 0, 1)) << describe(m);
  EXPECT_NEAR(double(m.points[0].separation), -0.1, 4 * kEpsReal);
  EXPECT_EQ(m.points[0].featureA, featureId(FeatureKind::Vertex, 0));
}

TEST(BoxTriangleContact, SegmentTriangleAcrossACornerIsAnEdgeEdgeContact) {
  // A segment (collinear corners) crossing over the edge x = y = 1 of the unit box, diagonally.
  Case c;
  c.tri = Triangle{Vec3(Real(1.9), 0, 0), Vec3(0, Real(1.9), 0), Vec3(Real(0.95), Real(0.95), 0)};
  ContactManifold m;
  ASSERT_TRUE(boxTriangleContacts(c.half, c.tri, 0, m));
  ASSERT_TRUE(wellFormed(c, m));
  ASSERT_EQ(m.count, 1) << describe(m);
  const double r = std::sqrt(0.5);
  EXPECT_NEAR((m.normal.cast<double>() - V3d(r, r, 0)).norm(), 0, 8 * kEpsReal) << describe(m);
  EXPECT_NEAR(double(m.points[0].separation), 0.95 * std::sqrt(2.0) - std::sqrt(2.0), 16 * kEpsReal);
}

TEST(BoxTriangleContact, RepeatedCornerSegmentReportsItsFirstEdge) {
  // A triangle with b == c is the segment ab, present twice among the SAT's edges: as edge
  // (0,1) and as edge (2,0). Both copies' axes must get the same separation (all three corners
  // projected on each), so the first, edge (0,1), wins the tie. Found while speeding up the
  // edge axes: projecting only an edge's first corner and the opposite one made the copies
  // differ by an ulp and the second win on these cases (random, 17 digits).
  struct Seg {
    double half[3], a[3], b[3];
    double margin;
  };
  const Seg cases[] = {
      {{0.15248043835163116, 0.20511634647846222, 0.12665635347366333},
       {0.68461126089096069, 0.32755276560783386, -1.9302594661712646},
       {-0.52184563875198364, 0.0015091508394107223, 1.5411454439163208},
       0.20000000298023224},
      {{1.0004466772079468, 0.80531412363052368, 0.60821843147277832},
       {1.7929775714874268, 0.24653197824954987, -0.40365183353424072},
       {-0.021730678156018257, 1.2534226179122925, -0.17776615917682648},
       0.0099999997764825821},
      {{0.56222420930862427, 0.73872083425521851, 1.039616584777832},
       {-0.63463866710662842, 1.7233678102493286, -0.65244203805923462},
       {0.38736176490783691, 0.00027703650994226336, 0.0076805893331766129},
       0},
  };
  for (const Seg& s : cases) {
    Case c;
    c.half = Vec3(Real(s.half[0]), Real(s.half[1]), Real(s.half[2]));
    const Vec3 a(Real(s.a[0]), Real(s.a[1]), Real(s.a[2])), b(Real(s.b[0]), Real(s.b[1]), Real(s.b[2]));
    c.tri = Triangle{a, b, b};
    c.margin = Real(s.margin);
    ContactManifold m;
    ASSERT_TRUE(boxTriangleContacts(c.half, c.tri, c.margin, m)) << describe(c);
    ASSERT_TRUE(wellFormed(c, m)) << describe(c);
    ASSERT_EQ(m.count, 1) << describe(c) << "\n" << describe(m);
    EXPECT_EQ(m.points[0].featureA, featureId(FeatureKind::Edge, 0 * 64 + 1)) << describe(c) << "\n" << describe(m);
    EXPECT_EQ(m.points[0].featureB >> 24, std::uint32_t(FeatureKind::Edge)) << describe(c) << "\n" << describe(m);
  }
}

TEST(BoxTriangleContact, FlatBoxIsAClosedRectangle) {
  // half z = 0: the box is the square |x|, |y| <= 1 in z = 0; a triangle crossing it.
  Case c;
  c.half = Vec3(1, 1, 0);
  c.tri = Triangle{Vec3(Real(0.5), 0, Real(-0.5)), Vec3(Real(0.5), Real(0.5), Real(0.5)), Vec3(3, 0, Real(0.5))};
  ContactManifold m;
  ASSERT_TRUE(boxTriangleContacts(c.half, c.tri, 0, m));
  ASSERT_TRUE(wellFormed(c, m));
  Case far = c;
  far.tri = Triangle{Vec3(Real(1.5), 0, Real(-0.5)), Vec3(Real(1.5), Real(0.5), Real(0.5)), Vec3(3, 0, Real(0.5))};
  EXPECT_FALSE(boxTriangleContacts(far.half, far.tri, 0, m)) << describe(m);
  EXPECT_TRUE(boxTriangleContacts(far.half, far.tri, Real(0.6), m));
  EXPECT_TRUE(wellFormed({far.half, far.tri, Real(0.6)}, m));
  EXPECT_NEAR(minSeparation(m), 0.5, 16 * kEpsReal) << describe(m);
}

TEST(BoxTriangleContact, NearlyParallelOffsetEdgesKeepPointsOnTheBox) {
  // Separated within the margin, a triangle edge nearly parallel to a box edge: contact.cpp's
  // edge-reference clipping reports a pointB outside the box here (|y| = 1.782 > 1.7356, double
  // build); the SAT routine answers with the GJK pair.
  Case c;
  c.half = Vec3(Real(0.82585418100247765), Real(1.7355784415104598), Real(0.49252121972387419));
  c.tri = Triangle{Vec3(Real(1.1181553810141036), Real(-1.7530383300405692), Real(-0.50425362319975031)),
                   Vec3(Real(-0.80504669195608036), Real(-1.8079226704036215), Real(-0.50776341272902537)),
                   Vec3(Real(0.4474789120501419), Real(-3.2561772844565269), Real(-1.1719251984506456))};
  c.margin = Real(0.2);
  ContactManifold m;
  ASSERT_TRUE(boxTriangleContacts(c.half, c.tri, c.margin, m));
  EXPECT_TRUE(wellFormed(c, m));
}

TEST(BoxTriangleContact, BadMarginAndHugeInputsGiveNoNaN) {
  ContactManifold m;
  const Triangle t{Vec3(0, 0, Real(0.5)), Vec3(1, 0, Real(0.5)), Vec3(0, 1, Real(0.5))};
  EXPECT_TRUE(boxTriangleContacts(Vec3::Ones(), t, std::numeric_limits<Real>::quiet_NaN(), m));
  EXPECT_TRUE(boxTriangleContacts(Vec3::Ones(), t, Real(-1), m));
  const Real big = std::numeric_limits<Real>::max() / 4;
  const Triangle tb{Vec3(0, 0, big / 2), Vec3(big, 0, big / 2), Vec3(0, big, big / 2)};
  ASSERT_TRUE(boxTriangleContacts(Vec3(big, big, big), tb, 0, m));
  for (int i = 0; i < m.count; ++i) {
    EXPECT_TRUE(std::isfinite(m.points[i].separation)) << describe(m);
    EXPECT_TRUE(m.points[i].pointA.allFinite() && m.points[i].pointB.allFinite()) << describe(m);
  }
  EXPECT_TRUE(m.normal.allFinite());
}

// ---- against the generic routine ---------------------------------------------------------------

TEST(BoxTriangleContact, AgreesWithTheGenericRoutineOnRandomCases) {
  Gen g(20261122);
  const int n = test::scaledCases(14000, 2000);
  int normalDiffer = 0, faceRule = 0, verdicts = 0, contactsFound = 0, penetrating = 0, bandSkipped = 0,
      depthCompared = 0, deepestDiffer = 0;
  double worstDepth = 0, worstDeepest = 0, worstNormal = 0;
  int perFamily[7] = {0, 0, 0, 0, 0, 0, 0};
  for (int i = 0; i < n; ++i) {
    const int family = i % 7;
    const Case c = g.make(family);
    ContactManifold mine, ref;
    const bool got = boxTriangleContacts(c.half, c.tri, c.margin, mine);
    const bool want = generic(c, ref);
    EXPECT_EQ(got, mine.count > 0);
    const DistanceResult d = distance(ConvexShape(c.tri), Transform{}, ConvexShape(boxOf(c)), Transform{});
    const double S = scaleOf(c);
    if (std::abs(double(d.distance) - double(c.margin)) <= kVerdictBandRelative * S + 64 * kEpsReal * S) {
      ++bandSkipped;
    } else {
      ++verdicts;
      EXPECT_EQ(got, want) << "verdict, family " << family << ", distance " << str(double(d.distance)) << "\n"
                           << describe(c) << "\nmine: " << describe(mine) << "\ngeneric: " << describe(ref);
    }
    if (!got) continue;
    ++contactsFound;
    ++perFamily[family];
    EXPECT_TRUE(wellFormed(c, mine)) << "family " << family;
    // Points are pairs of surface points: none is deeper than the overlap along the normal.
    const double tolD = kDepthRelative * S + 64 * kEpsReal * S;
    EXPECT_GE(minSeparation(mine), sepAlong(c, mine.normal.cast<double>()) - tolD) << describe(c) << "\n"
                                                                                   << describe(mine);
    if (double(d.distance) < 0) {
      ++penetrating;
      // The normal is a minimum-penetration direction: the separation along it equals the
      // signed distance (it can never exceed it: any direction's separation is a lower bound).
      // Or, as contact.cpp does, a face normal within 2° of the minimum-penetration direction.
      const V3d n = mine.normal.cast<double>();
      const double along = sepAlong(c, n);
      ++depthCompared;
      if (std::abs(along - double(d.distance)) <= tolD) {
        worstDepth = std::max(worstDepth, std::abs(along - double(d.distance)) / S);
      } else {
        ++faceRule;
        EXPECT_TRUE(isFaceNormal(c, n) && n.dot(d.normal.cast<double>()) >= double(kContactFaceAngleCos) - 8 * kEpsReal)
            << "not a minimum-penetration normal, nor a face within 2° of one: along " << str(along) << " distance "
            << str(double(d.distance)) << " EPA normal " << str(d.normal) << "\n"
            << describe(c) << "\nmine: " << describe(mine) << "\ngeneric: " << describe(ref);
      }
      if (want) {
        // The generic routine's normal is as deep: the same minimum-penetration direction, or
        // the same face rule.
        const double alongRef = sepAlong(c, ref.normal.cast<double>());
        if (std::abs(along - alongRef) > tolD) ++normalDiffer;
        worstNormal = std::max(worstNormal, std::abs(along - alongRef) / S);
        const double diff = std::abs(minSeparation(mine) - minSeparation(ref)) / S;
        worstDeepest = std::max(worstDeepest, diff);
        if (diff > kDepthRelative) ++deepestDiffer;
      }
    }
  }
  std::printf(
      "box-triangle vs generic: %d cases, %d verdicts compared (%d within the margin band), %d contacts "
      "(per family %d %d %d %d %d %d %d), %d penetrating (%d with a face normal within 2° of the EPA one, deeper along "
      "it); worst |sepAlong(normal) - distance|/S otherwise %.3g; deepest point "
      "differs from the generic manifold's by > %.1g·S in %d (worst %.3g·S)\n",
      n, verdicts, bandSkipped, contactsFound, perFamily[0], perFamily[1], perFamily[2], perFamily[3], perFamily[4],
      perFamily[5], perFamily[6], penetrating, faceRule, worstDepth, kDepthRelative, deepestDiffer, worstDeepest);
  std::printf("separation along crux's normal vs along the generic normal: differs by > tol in %d (worst %.3g·S)\n",
              normalDiffer, worstNormal);
  for (int f = 0; f < 7; ++f) EXPECT_GT(perFamily[f], n / 7 / 8) << "family " << f << " rarely in contact";
  EXPECT_GT(penetrating, n / 5);
}

// ---- the shortcuts against the full SAT, bit for bit ---------------------------------------

/// Both answers identical bit for bit: verdict, count, normal and every point's fields.
::testing::AssertionResult sameBits(bool ra, const ContactManifold& a, bool rb, const ContactManifold& b) {
  auto bits = [](const Vec3& v) {
    std::array<std::uint32_t, 3 * sizeof(Real) / 4> w{};
    std::memcpy(w.data(), v.data(), 3 * sizeof(Real));
    return w;
  };
  auto same = [&](Real x, Real y) { return std::memcmp(&x, &y, sizeof(Real)) == 0; };
  bool ok = ra == rb && a.count == b.count && (!ra || bits(a.normal) == bits(b.normal));
  for (int i = 0; ok && i < a.count; ++i) {
    const ContactPoint &p = a.points[i], &q = b.points[i];
    ok = bits(p.pointA) == bits(q.pointA) && bits(p.pointB) == bits(q.pointB) && same(p.separation, q.separation) &&
         p.featureA == q.featureA && p.featureB == q.featureB;
  }
  if (ok) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "shortcuts (" << ra << "): " << describe(a) << "\nfull SAT (" << rb
                                       << "): " << describe(b);
}

TEST(BoxTriangleContact, ShortcutsGiveTheFullSatAnswerBitForBit) {
  // The routine's shortcuts (edge axes skipped under the clearance bound, the supporting feature
  // along a box face on single components, a single-corner contact written out directly) against
  // detail::boxTriangleContactsFullSat, which takes none of them: the seven families above, a
  // corner inside the box at any depth (the bound's case, up to a clearance of 0), a corner just
  // off a box face within the margin (corner contacts after the edge axes), integer grids (exact
  // ties: touching corners, edges on faces).
  Gen g(31337);
  const int n = test::scaledCases(20000, 3000);
  int deep = 0, cornerContacts = 0, contactsFound = 0;
  for (int i = 0; i < n; ++i) {
    const int family = i % 10;
    Case c;
    if (family < 7) {
      c = g.make(family);
    } else if (family == 7) {
      c.half = g.half();
      c.margin = g.margin();
      const V3d h = c.half.cast<double>();
      const double depth = g.pick(4) == 0 ? 1e-7 * g.uni(0, 1) : g.uni(0, 1);  // shallow ones near the bound
      V3d in(g.uni(-1, 1) * h.x(), g.uni(-1, 1) * h.y(), g.uni(-1, 1) * h.z());
      const int k = g.pick(3);
      in[k] = (g.pick(2) ? 1 : -1) * h[k] * (1 - depth);
      c.tri = Gen::tri(in, in + g.vec(2.5), in + g.vec(2.5));
    } else if (family == 8) {
      c.half = g.half();
      c.margin = Real(g.uni(0.01, 0.3));
      const V3d h = c.half.cast<double>();
      const int k = g.pick(3);
      const double s = g.pick(2) ? 1 : -1;
      V3d p(g.uni(-1, 1) * h.x(), g.uni(-1, 1) * h.y(), g.uni(-1, 1) * h.z());
      p[k] = s * (h[k] + g.uni(-0.02, 1) * double(c.margin));
      V3d q1 = p + g.vec(2), q2 = p + g.vec(2);
      q1[k] = p[k] + s * g.uni(0, 1.5);
      q2[k] = p[k] + s * g.uni(0, 1.5);
      c.tri = Gen::tri(p, q1, q2);
    } else {
      for (int k = 0; k < 3; ++k) {
        c.half[k] = Real(0.5 * g.pick(5));
        c.tri.a[k] = Real(g.pick(9) - 4);
        c.tri.b[k] = Real(g.pick(9) - 4);
        c.tri.c[k] = Real(g.pick(9) - 4);
      }
      c.margin = Real(g.pick(3) == 0 ? 0.5 * g.pick(3) : 0);
    }
    for (const Vec3& v : {c.tri.a, c.tri.b, c.tri.c})
      if ((c.half.cast<double>() - v.cast<double>().cwiseAbs()).minCoeff() >= 0) {
        ++deep;
        break;
      }
    ContactManifold a, b;
    std::memset(static_cast<void*>(&a), 0, sizeof a);
    std::memset(static_cast<void*>(&b), 0, sizeof b);
    const bool ra = boxTriangleContacts(c.half, c.tri, c.margin, a);
    const bool rb = detail::boxTriangleContactsFullSat(c.half, c.tri, c.margin, b);
    EXPECT_TRUE(sameBits(ra, a, rb, b)) << "case " << i << ", family " << family << "\n" << describe(c);
    if (!ra) continue;
    ++contactsFound;
    if (a.count == 1 && (a.points[0].featureA >> 24) == std::uint32_t(FeatureKind::Vertex) &&
        (a.points[0].featureB >> 24) == std::uint32_t(FeatureKind::Face))
      ++cornerContacts;
  }
  std::printf("shortcuts vs full SAT: %d cases, %d with a corner inside the box, %d contacts, %d single-corner "
              "contacts on a box face\n",
              n, deep, contactsFound, cornerContacts);
  EXPECT_GT(deep, n / 8);  // the clearance bound's cases are exercised
  EXPECT_GT(cornerContacts, n / 8);
}

// ---- integer grid: exact verdicts, touching at separation 0 exactly ----------------------------

/// Exact SAT in integers (coordinates doubled so half extents may be half-integers): the maximum
/// over the 13 candidate axes (zero axes skipped) of the separation numerator sign, as the
/// sign of max_k (lo_k − r_k, −r_k − hi_k)/|a_k|; returns −1 overlap with depth > 0, 0 touching,
/// +1 separated. Depth 0 iff the maximum is 0.
int exactSatSign(const Eigen::Vector3i& h2, const Eigen::Vector3i* t2) {
  std::vector<Eigen::Matrix<long long, 3, 1>> axes;
  for (int k = 0; k < 3; ++k) axes.push_back(Eigen::Matrix<long long, 3, 1>::Unit(k));
  const Eigen::Matrix<long long, 3, 1> a = t2[0].cast<long long>(), b = t2[1].cast<long long>(),
                                       c = t2[2].cast<long long>();
  const Eigen::Matrix<long long, 3, 1> e[3] = {b - a, c - b, a - c};
  axes.push_back(e[0].cross(c - a));
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 3; ++j) axes.push_back(Eigen::Matrix<long long, 3, 1>::Unit(k).cross(e[j]));
  int best = -1;
  for (const auto& ax : axes) {
    if (ax.isZero()) continue;
    const long long p[3] = {ax.dot(a), ax.dot(b), ax.dot(c)};
    const long long lo = std::min({p[0], p[1], p[2]}), hi = std::max({p[0], p[1], p[2]});
    const long long r = std::abs(ax.x()) * h2.x() + std::abs(ax.y()) * h2.y() + std::abs(ax.z()) * h2.z();
    const long long s = std::max(lo - r, -r - hi);
    best = std::max(best, s > 0 ? 1 : (s == 0 ? 0 : -1));
  }
  return best;
}

TEST(BoxTriangleContact, IntegerGridVerdictsAreExactAndTouchingIsSeparationZero) {
  Gen g(77);
  const int n = test::scaledCases(6000, 1500);
  int touching = 0, overlapping = 0, separated = 0;
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3i h2(g.pick(5), g.pick(5), g.pick(5));  // doubled half extents 0..4
    Eigen::Vector3i t2[3];
    for (auto& v : t2) v = Eigen::Vector3i(g.pick(13) - 6, g.pick(13) - 6, g.pick(13) - 6);
    if (g.pick(6) == 0) t2[2] = t2[g.pick(2)];   // segment
    if (g.pick(10) == 0) t2[1] = t2[2] = t2[0];  // point
    if (g.pick(3) == 0)
      t2[g.pick(3)] =
          h2.cwiseProduct(Eigen::Vector3i(g.pick(3) - 1, g.pick(3) - 1, g.pick(3) - 1));  // a vertex on a box feature
    Case c;
    c.half = h2.cast<Real>() * Real(0.5);
    c.tri = Triangle{t2[0].cast<Real>() * Real(0.5), t2[1].cast<Real>() * Real(0.5), t2[2].cast<Real>() * Real(0.5)};
    const Aabb box{-c.half, c.half};
    const bool exact = exact::detail::overlapsSimplex(exact::detail::toSimplex(c.tri), box);
    const int sat = exactSatSign(h2, t2);
    ASSERT_EQ(exact, sat <= 0) << "the test's integer SAT disagrees with CGAL\n" << describe(c);
    ContactManifold m;
    const bool got = boxTriangleContacts(c.half, c.tri, 0, m);
    ASSERT_EQ(got, exact) << describe(c) << "\n" << describe(m);
    if (!got) {
      ++separated;
      continue;
    }
    EXPECT_TRUE(wellFormed(c, m));
    if (sat == 0) {
      ++touching;
      EXPECT_EQ(minSeparation(m), 0.0) << "touching\n" << describe(c) << "\n" << describe(m);
    } else {
      ++overlapping;
      EXPECT_LT(minSeparation(m), 0.0) << describe(c) << "\n" << describe(m);
    }
  }
  std::printf("integer grid: %d cases, %d touching, %d overlapping, %d separated\n", n, touching, overlapping,
              separated);
  EXPECT_GT(touching, n / 20);
  EXPECT_GT(overlapping, n / 20);
  EXPECT_GT(separated, n / 20);
}

// ---- libccd ------------------------------------------------------------------------------------

#if CRUX_HAVE_CCD_ORACLE
TEST(BoxTriangleContactVsLibccd, PenetrationDepth) {
  // libccd's GJK+EPA depth vs the depth along crux's normal. Every direction's overlap bounds the
  // true depth from above, so crux must never be deeper than the overlap along libccd's own
  // direction; where libccd claims a shallower depth than its direction shows, libccd is wrong.
  Gen g(4242);
  const int n = test::scaledCases(3000, 1000);
  int compared = 0, agree = 0, ccdInconsistent = 0, ccdFailures = 0, faceRule = 0;
  for (int i = 0; i < n; ++i) {
    const Case c = g.make(i % 7 == 4 ? 0 : i % 7);  // libccd needs full-dimensional shapes: no degenerate family
    ContactManifold m;
    if (!boxTriangleContacts(c.half, c.tri, 0, m)) continue;
    const double depth = -sepAlong(c, m.normal.cast<double>());
    if (!(depth > 1e-6 * scaleOf(c))) continue;
    // Face normals deeper than the minimum-penetration direction (contact.hpp's 2° face rule, or
    // the face bias) are deeper than the minimum by design: checked against crux's own EPA in
    // AgreesWithTheGenericRoutineOnRandomCases, not here.
    const DistanceResult d = distance(ConvexShape(c.tri), Transform{}, ConvexShape(boxOf(c)), Transform{});
    if (isFaceNormal(c, m.normal.cast<double>()) && depth > -double(d.distance) + 64 * kEpsReal * scaleOf(c)) {
      ++faceRule;
      continue;
    }
    const oracle_ccd::Penetration p =
        oracle_ccd::gjkPenetration(ConvexShape(c.tri), Transform{}, ConvexShape(boxOf(c)), Transform{});
    if (p.status != 0 || !std::isfinite(p.depth) || !(p.dir.norm() > 0)) {
      ++ccdFailures;
      continue;
    }
    ++compared;
    const double S = scaleOf(c);
    // libccd's EPA tolerance (1e-6·S) + crux's (kDepthRelative·S) + the rounding budget of the
    // returned Real values (as in wellFormed), both sides.
    const double tol = 1e-6 * S + 2 * kDepthRelative * S + 2 * kCheckUlps * kEpsReal * S;
    // libccd moves obj2 (the box) along dir: the triangle separates along −dir.
    const double ccdOverlap = -sepAlong(c, -p.dir.normalized());
    EXPECT_LE(depth, ccdOverlap + tol) << "crux deeper than libccd's direction allows\n"
                                       << describe(c) << "\n"
                                       << describe(m) << "\nccd depth " << str(p.depth) << " dir " << str(p.dir);
    if (std::abs(depth - p.depth) <= tol) ++agree;
    if (p.depth < ccdOverlap - tol) ++ccdInconsistent;
  }
  std::printf(
      "box-triangle vs libccd: %d penetrating pairs, depth agrees in %d, libccd's depth below the overlap along "
      "its own direction in %d, libccd failures %d (%d face-rule pairs skipped)\n",
      compared, agree, ccdInconsistent, ccdFailures, faceRule);
  EXPECT_GT(compared, n / 10);
  EXPECT_GT(agree, compared * 9 / 10);
}
#endif

// ---- no allocation, microbenchmark ---------------------------------------------------------------

TEST(BoxTriangleContact, NeverAllocates) {
  Gen g(5);
  std::vector<Case> cases;
  for (int i = 0; i < 700; ++i) cases.push_back(g.make(i % 7));
  ContactManifold m;
  const long before = test::allocationCount();
  int hits = 0;
  for (const Case& c : cases) hits += boxTriangleContacts(c.half, c.tri, c.margin, m) ? 1 : 0;
  EXPECT_EQ(test::allocationCount(), before);
  EXPECT_GT(hits, 100);
}

TEST(BoxTriangleContact, MicrobenchmarkAgainstTheGenericRoutine) {
  // Printed, not asserted: ns per call, interleaved runs (best of 3), on near-face cases (the
  // resting-box case), contact-heavy cases (families 1, 2, 3, 6: corners separated within the
  // margin take the generic fallback) and a BVH-candidate mix (all families).
  Gen g(11);
  std::vector<Case> faces, contactHeavy, mix;
  for (int i = 0; i < 2000; ++i) {
    const int fams[] = {1, 2, 3, 6};
    faces.push_back(g.make(i % 2 ? 1 : 6));
    contactHeavy.push_back(g.make(fams[i % 4]));
    mix.push_back(g.make(i % 7));
  }
  auto time = [](const std::vector<Case>& cs, bool fast, int& sink) {
    const auto t0 = std::chrono::steady_clock::now();
    ContactManifold m;
    for (const Case& c : cs) sink += fast ? boxTriangleContacts(c.half, c.tri, c.margin, m) : generic(c, m);
    return std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count() / double(cs.size());
  };
  int sink = 0;
  for (const auto* set : {&faces, &contactHeavy, &mix}) {
    double bestMine = 1e30, bestGeneric = 1e30;
    for (int rep = 0; rep < 3; ++rep) {
      bestMine = std::min(bestMine, time(*set, true, sink));
      bestGeneric = std::min(bestGeneric, time(*set, false, sink));
    }
    std::printf("box-triangle microbenchmark (%s): SAT %.0f ns/call, generic GJK/EPA %.0f ns/call, ratio %.1fx\n",
                set == &mix ? "all families"
                            : (set == &faces ? "near-face, families 1 and 6" : "contact-heavy, families 1 2 3 6"),
                bestMine, bestGeneric, bestGeneric / bestMine);
  }
  EXPECT_GT(sink, 0);
}

// Non-queryable inputs (precondition.hpp, rule::kPrimitive): the routines behind the public entries
// (geometry/unchecked.hpp, what those entries run in release builds and the mesh, scene and contact
// layers call) give an unspecified answer, but return without undefined behaviour, which the
// sanitizer stage checks here. (The routine's fallback, distance(ConvexShape, ...), would abort on
// them in debug builds: the routine answers them with no contact before it; the full-SAT reference
// is checked at entry, so it joins in where the primitive check is off.)
TEST(BoxTriangleContactPreconditions, NonQueryableInputsReturnWithoutUndefinedBehaviour) {
  const test_support::BadPrimitives bad = test_support::badPrimitives();
  const Triangle tri{Vec3(-2, -2, Real(0.9)), Vec3(2, -2, Real(0.9)), Vec3(0, 2, Real(0.9))};
  int calls = 0;
  ContactManifold m;
  const auto both = [&](const Vec3& half, const Triangle& t) {
    (void)unchecked::boxTriangleContacts(half, t, 0, m), ++calls;
    if (!CRUX_CHECK_PRIMITIVE_PRECONDITIONS) (void)detail::boxTriangleContactsFullSat(half, t, 0, m), ++calls;
  };
  for (const Triangle& t : bad.triangles) both(Vec3::Ones(), t);
  std::vector<Vec3> halves = bad.points;
  halves.push_back(Vec3(1, -1, 1));  // a negative half extent
  for (const Vec3& half : halves) both(half, tri);
  EXPECT_GT(calls, 15);
  EXPECT_TRUE(unchecked::boxTriangleContacts(Vec3::Ones(), tri, 0, m));
}

// In debug builds (CRUX_CHECK_PRIMITIVE_PRECONDITIONS, on without NDEBUG) a non-queryable input
// aborts with a message naming the query.
TEST(BoxTriangleContactPreconditions, DebugBuildsAbortNamingTheQuery) {
  if (!CRUX_CHECK_PRIMITIVE_PRECONDITIONS)
    GTEST_SKIP() << "the primitive check is off in this build (NDEBUG)";
  const Triangle tri{Vec3(-2, -2, Real(0.9)), Vec3(2, -2, Real(0.9)), Vec3(0, 2, Real(0.9))};
  ContactManifold m;
  const Real nan = std::numeric_limits<Real>::quiet_NaN();
  EXPECT_DEATH((void)boxTriangleContacts(Vec3(1, nan, 1), tri, 0, m),
               "precondition violated in boxTriangleContacts\\(half extents, Triangle\\)");
  EXPECT_DEATH((void)boxTriangleContacts(Vec3(1, -1, 1), tri, 0, m),
               "precondition violated in boxTriangleContacts\\(half extents, Triangle\\)");
}

}  // namespace
}  // namespace crux
