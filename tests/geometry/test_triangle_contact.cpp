// Tests of src/geometry/triangle_contact.cpp: the closed-form sphere–triangle and
// capsule–triangle manifolds against the generic GJK/EPA + clipping routine of contact.hpp
// (`contacts(ConvexShape(tri), I, shape, I, margin, m)`) on seeded random, degenerate, touching,
// crossing and lying-along-the-face families; invariants (points on both surfaces,
// pointA − pointB = separation·normal); the documented deterministic normal of the flat cases.
// Failing cases are printed with 17 digits.

#include <crux/geometry/triangle_contact.hpp>

#include <crux/geometry/closest_point.hpp>
#include <crux/geometry/overlap.hpp>
#include <crux/geometry/triangle_distance.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <utility>

#include "support/grid_touching.hpp"
#include "support/test_scale.hpp"
#include <crux/precondition.hpp>
#include "geometry/unchecked.hpp"
#include "support/bad_inputs.hpp"

namespace crux {
namespace {

constexpr double kEpsReal = std::numeric_limits<Real>::epsilon();
/// Agreement of two answers (separations, positions) computed by different algorithms, relative
/// to the pair's length scale: the generic routine converges to kGjkScaleTolerance (1000 ulps of
/// double) × scale plus 1e-12 relative, and both round their outputs to Real: 64 ulps of Real
/// covers both in float builds; in double builds the GJK tolerance (2.2e-13) dominates, and
/// 1e-11 leaves a factor 40 for the convergence of EPA on thin prisms.
constexpr double kAgreeRelative = sizeof(Real) == 4 ? 64 * kEpsReal : 1e-11;
/// Normals are compared when the pair is well conditioned: core distance or depth above this
/// × scale (below it the direction of a near-zero vector is noise).
constexpr double kWellConditionedRelative = 1e-3;
/// Angle (rad) within which two normals count as the same direction (float normals are rounded
/// to 6e-8; GJK's direction error is about tolerance / distance <= 1e-9 when well conditioned).
constexpr double kNormalAngle = 1e-5;

std::string str(const Vec3& v) {
  std::ostringstream s;
  s.precision(17);
  s << "(" << double(v.x()) << ", " << double(v.y()) << ", " << double(v.z()) << ")";
  return s.str();
}

std::string describe(const Triangle& t, const std::string& shape) {
  return "triangle " + str(t.a) + " " + str(t.b) + " " + str(t.c) + " vs " + shape;
}

std::string describe(const ContactManifold& m) {
  std::ostringstream s;
  s.precision(17);
  s << "normal " << str(m.normal) << " count " << m.count;
  for (int i = 0; i < m.count; ++i)
    s << " [A " << str(m.points[i].pointA) << " B " << str(m.points[i].pointB) << " sep "
      << double(m.points[i].separation) << " fA " << std::hex << m.points[i].featureA << " fB " << m.points[i].featureB
      << std::dec << "]";
  return s.str();
}

double minSeparation(const ContactManifold& m) {
  double s = std::numeric_limits<double>::infinity();
  for (int i = 0; i < m.count; ++i) s = std::min(s, double(m.points[i].separation));
  return s;
}

/// Distance from p to the triangle in double, independent of the code under test: the minimum
/// over the three edges and, when p projects inside (same-side tests on the exact normal), the
/// plane distance. Robust on nearly collinear triangles.
double triangleDistance(const Triangle& t, const Vec3& pIn) {
  const Eigen::Vector3d v[3] = {t.a.cast<double>(), t.b.cast<double>(), t.c.cast<double>()};
  const Eigen::Vector3d p = pIn.cast<double>();
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d a = v[i], e = v[(i + 1) % 3] - v[i];
    const double l2 = e.squaredNorm();
    const double s = l2 > 0 ? std::clamp(e.dot(p - a) / l2, 0.0, 1.0) : 0.0;
    best = std::min(best, (a + s * e - p).norm());
  }
  const Eigen::Vector3d n = (v[1] - v[0]).cross(v[2] - v[0]);
  if (n.squaredNorm() > 0) {
    bool inside = true;
    for (int i = 0; i < 3; ++i) inside = inside && n.dot((v[(i + 1) % 3] - v[i]).cross(p - v[i])) >= 0;
    if (inside) best = std::min(best, std::abs(n.normalized().dot(p - v[0])));
  }
  return best;
}

/// Distance between segments [p1,q1] and [p2,q2] in double (RTCD 5.1.9 with the parallel case
/// clamped), written here independently of the code under test.
double segmentDistance(const Eigen::Vector3d& p1, const Eigen::Vector3d& q1, const Eigen::Vector3d& p2,
                       const Eigen::Vector3d& q2) {
  const Eigen::Vector3d d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0, t = 0;
  if (a <= 0 && e <= 0) return r.norm();
  if (a <= 0) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= 0) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), den = a * e - b * b;
      s = den > 0 ? std::clamp((b * f - c * e) / den, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1) {
        t = 1;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  return (p1 + s * d1 - (p2 + t * d2)).norm();
}

/// Statistics of a family.
struct Stats {
  int cases = 0, hits = 0, normalsCompared = 0, manifoldsCompared = 0, twoPoints = 0;
  int regions[3] = {0, 0, 0};  // sphereTriangleContact's regions met: face, edge, corner
  double worstSep = 0, worstAngle = 0;
};

/// Checks `mine` against the generic routine for triangle `tri` vs `shape` (`core`: segment or
/// point of the shape for the membership checks).
void compare(const Triangle& tri, const ConvexShape& shape, Real margin, const ContactManifold& mine,
             const std::string& info, Stats& st) {
  ++st.cases;
  ContactManifold gen;
  contacts(ConvexShape(tri), Transform::identity(), shape, Transform::identity(), margin, gen);
  const double scale = double(ConvexShape(tri).size()) + double(shape.size());
  const double tol = kAgreeRelative * scale;
  const std::string full = info + "\n  mine    " + describe(mine) + "\n  generic " + describe(gen);
  double sGen = minSeparation(gen);
  const double sMine = minSeparation(mine);
  // A degenerate triangle is the segment it spans: its computed normal is rounding noise, which
  // the generic routine may take for a face and clip against (a separation measured along a
  // noise direction). The reference is then the exact distance to its edges minus the radius.
  bool degenerate = false;
  {
    const Eigen::Vector3d ab = (tri.b - tri.a).cast<double>(), ac = (tri.c - tri.a).cast<double>();
    const double longest = std::max({ab.squaredNorm(), ac.squaredNorm(), (ac - ab).squaredNorm()});
    degenerate = classifyTriangle(ab.cross(ac).norm(), longest).degenerate;
  }
  if (degenerate) {
    const Eigen::Vector3d v[3] = {tri.a.cast<double>(), tri.b.cast<double>(), tri.c.cast<double>()};
    const Eigen::Vector3d c0 = shape.p[0].cast<double>();
    const Eigen::Vector3d c1 = (shape.kind == ConvexKind::Capsule ? shape.p[1] : shape.p[0]).cast<double>();
    double d = std::numeric_limits<double>::infinity();
    for (int i = 0; i < 3; ++i) d = std::min(d, segmentDistance(v[i], v[(i + 1) % 3], c0, c1));
    const double ref = d - double(shape.radius);
    if ((ref <= double(margin)) != (mine.count > 0)) {
      ASSERT_LE(std::abs(ref - double(margin)), tol) << "degenerate: verdict vs exact edges " << full;
      return;
    }
    if (mine.count > 0) {
      ++st.hits;
      ASSERT_LE(std::abs(sMine - ref), tol) << "degenerate: separation vs exact edges " << full;
    }
    return;
  }
  // Verdicts: equal unless the generic separation is within the tolerance of the margin.
  if (gen.count > 0 != (mine.count > 0)) {
    const double s = gen.count > 0 ? sGen : sMine;
    ASSERT_LE(std::abs(s - double(margin)), tol) << "verdicts differ away from the margin " << full;
    return;
  }
  if (gen.count == 0) return;
  ++st.hits;
  ASSERT_LE(std::abs(sGen - sMine), tol) << "deepest separation " << full;
  st.worstSep = std::max(st.worstSep, std::abs(sGen - sMine) / scale);
  // Invariants of mine: unit normal, pointA − pointB = sep·n, points on both shapes.
  ASSERT_NEAR(double(mine.normal.norm()), 1.0, 16 * kEpsReal) << full;
  const Vec3 core0 = shape.kind == ConvexKind::Capsule ? shape.p[0] : shape.p[0];
  const Vec3 core1 = shape.kind == ConvexKind::Capsule ? shape.p[1] : shape.p[0];
  for (int i = 0; i < mine.count; ++i) {
    const ContactPoint& p = mine.points[i];
    ASSERT_LE(double(p.separation), double(margin) + tol) << full;
    ASSERT_LE(double((p.pointA - p.pointB - p.separation * mine.normal).norm()), tol) << "point " << i << " " << full;
    ASSERT_LE(triangleDistance(tri, p.pointA), tol) << "pointA off the triangle, point " << i << " " << full;
    // On the surface for a single pair; a clipped point is moved by the radius along the
    // reference normal, within the feature angle of the segment's normal plane.
    const double onB = double((closestPoint(Segment{core0, core1}, p.pointB) - p.pointB).norm());
    // (a clipped point's projection on the reference line may overhang the segment's end by up
    // to sin(feature angle) × its length)
    const double sinTol = std::sqrt(1 - double(kContactFaceAngleCos) * double(kContactFaceAngleCos));
    const double overhang = mine.count == 1 ? 0 : sinTol * (double((core1 - core0).norm()) + double(shape.radius));
    ASSERT_LE(onB, double(shape.radius) + overhang + tol) << "pointB outside the shape, point " << i << " " << full;
    // (the clip bound for every count: since contact.cpp merges coincident clipped points, a
    // clipped manifold can be left with one point; its separation and points are compared with
    // the generic routine's below)
    ASSERT_GE(onB, double(shape.radius) * double(kContactFaceAngleCos) - tol)
        << "pointB inside the shape, point " << i << " " << full;
  }
  // Normals, when well conditioned (|core distance| or depth not near zero).
  const double coreGen = sGen + double(shape.radius);
  if (std::abs(coreGen) <= kWellConditionedRelative * scale) return;
  ++st.normalsCompared;
  const Eigen::Vector3d ng = gen.normal.cast<double>(), nm = mine.normal.cast<double>();
  const double angle = std::atan2(ng.cross(nm).norm(), ng.dot(nm));
  if (angle > kNormalAngle) {
    // Allowed only for a tie of penetration axes: both normals must give the same depth.
    ASSERT_LT(coreGen, 0) << "normals differ on a separated pair (angle " << angle << ") " << full;
    return;
  }
  st.worstAngle = std::max(st.worstAngle, angle);
  // Same normal: the same manifold (count, separations, features; points within tol).
  ++st.manifoldsCompared;
  ASSERT_EQ(mine.count, gen.count) << full;
  st.twoPoints += mine.count == 2;
  // The supporting vertex of the triangle along −normal decides which edge is named when two
  // corners tie (an edge perpendicular to the normal): then the two routines may name different
  // (equally valid) features, which the ids are not compared for.
  double proj[3] = {-double(ng.dot(tri.a.cast<double>())), -double(ng.dot(tri.b.cast<double>())),
                    -double(ng.dot(tri.c.cast<double>()))};
  std::sort(proj, proj + 3);
  const bool tiedSupport = proj[2] - proj[1] <= tol;
  for (int i = 0; i < gen.count; ++i) {
    int match = -1;
    double bestDist = std::numeric_limits<double>::infinity();
    for (int j = 0; j < mine.count; ++j) {
      if (mine.points[j].featureB != gen.points[i].featureB && gen.count == 1) continue;
      const double dist = double((mine.points[j].pointA - gen.points[i].pointA).norm());
      if (dist < bestDist) {
        bestDist = dist;
        match = j;
      }
    }
    ASSERT_GE(match, 0) << "generic point " << i << " has no counterpart " << full;
    const ContactPoint& pm = mine.points[match];
    const ContactPoint& pg = gen.points[i];
    ASSERT_LE(std::abs(double(pm.separation - pg.separation)), tol) << "point " << i << " " << full;
    if (!tiedSupport) ASSERT_EQ(pm.featureA, pg.featureA) << "point " << i << " " << full;
    if (gen.count > 1) {  // clipped points are determined; a single GJK pair may slide on a flat contact
      ASSERT_LE(double((pm.pointA - pg.pointA).norm()), tol) << full;
      ASSERT_LE(double((pm.pointB - pg.pointB).norm()), tol) << full;
      ASSERT_TRUE(pm.featureB == pg.featureB || tiedSupport) << full;
    } else {
      ASSERT_EQ(pm.featureB, pg.featureB) << full;
    }
  }
}

std::mt19937 rngFor(unsigned seed) { return std::mt19937(seed); }

Vec3 randomVec(std::mt19937& rng, double lo, double hi) {
  std::uniform_real_distribution<double> u(lo, hi);
  return Vec3(Real(u(rng)), Real(u(rng)), Real(u(rng)));
}

Vec3 randomUnit(std::mt19937& rng) {
  std::normal_distribution<double> g;
  Eigen::Vector3d v(g(rng), g(rng), g(rng));
  return v.normalized().cast<Real>();
}

/// A random triangle: general, or degenerate (collinear, two equal corners, a point).
Triangle randomTriangle(std::mt19937& rng, int family, double size) {
  Triangle t{randomVec(rng, -size, size), randomVec(rng, -size, size), randomVec(rng, -size, size)};
  std::uniform_real_distribution<double> u(0, 1);
  switch (family) {
    case 1: t.c = t.a + Real(u(rng)) * (t.b - t.a); break;  // collinear (up to rounding)
    case 2: t.c = t.a; break;                                // two equal corners
    case 3: t.b = t.c = t.a; break;                          // a point
    default: break;
  }
  return t;
}

Vec3 pointOn(const Triangle& t, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  double w1 = u(rng), w2 = u(rng);
  if (w1 + w2 > 1) w1 = 1 - w1, w2 = 1 - w2;
  return t.a + Real(w1) * (t.b - t.a) + Real(w2) * (t.c - t.a);
}

Vec3 faceNormal(const Triangle& t) { return (t.b - t.a).cross(t.c - t.a).normalized(); }

void report(const char* name, const Stats& st) {
  std::printf("%s: %d cases, %d with contacts, %d normals compared (worst angle %.3g), %d manifolds compared "
              "(%d with 2 points), worst |separation diff|/scale %.3g\n",
              name, st.cases, st.hits, st.normalsCompared, st.worstAngle, st.manifoldsCompared, st.twoPoints,
              st.worstSep);
}

// --- sphere -------------------------------------------------------------------------------------

TEST(TriangleContact, SphereAgreesWithGenericRoutine) {
  std::mt19937 rng = rngFor(20261122);
  const int n = test::scaledCases(6000);
  std::uniform_real_distribution<double> u(0, 1);
  Stats st;
  for (int k = 0; k < n; ++k) {
    const int family = k % 8 < 5 ? 0 : k % 8 - 4;  // 5/8 general, then collinear, 2 equal, point
    const Triangle tri = randomTriangle(rng, family, 1);
    const Real radius = Real(0.05 + 0.75 * u(rng));
    const Real margin = Real(0.1 * u(rng));
    Vec3 c;
    switch (k % 3) {
      case 0: c = randomVec(rng, -1.5, 1.5); break;  // anywhere
      case 1:  // near the surface: penetrating or within the margin
        c = pointOn(tri, rng) + Real(u(rng) * 1.1 * (radius + margin)) * randomUnit(rng);
        break;
      default: {  // touching: at distance radius from a point of the triangle along the normal
        const Vec3 nrm = family == 0 ? faceNormal(tri) : randomUnit(rng);
        c = pointOn(tri, rng) + radius * nrm;
        break;
      }
    }
    ContactManifold m;
    sphereTriangleContacts(tri, c, radius, margin, m);
    std::ostringstream info;
    info.precision(17);
    info << "case " << k << " " << describe(tri, "sphere centre " + str(c)) << " radius " << double(radius)
         << " margin " << double(margin);
    compare(tri, Sphere{c, radius}, margin, m, info.str(), st);
    if (HasFatalFailure()) return;
    // The mesh's form: the same point bit for bit, and the region the point lies in.
    SphereTriangleContact h;
    ASSERT_EQ(sphereTriangleContact(tri, c, radius, margin, h), m.count > 0) << info.str();
    if (m.count == 0) continue;
    ASSERT_EQ(h.pointA, m.points[0].pointA) << info.str();
    ASSERT_EQ(h.pointB, m.points[0].pointB) << info.str();
    ASSERT_EQ(h.normal, m.normal) << info.str();
    ASSERT_EQ(h.separation, m.points[0].separation) << info.str();
    const double tol =
        kAgreeRelative * (double(std::max({tri.a.norm(), tri.b.norm(), tri.c.norm()})) + double(c.norm()) + double(radius));
    if (h.region == SphereTriangleContact::kFace) {
      ASSERT_NEAR(std::abs(double(h.normal.dot(h.face))), 1.0, 16 * kEpsReal) << info.str();
      ++st.regions[0];
    } else if (h.region >= 3) {
      ASSERT_LE(double((h.pointA - tri[h.region - 3]).norm()), tol) << info.str();
      ++st.regions[2];
    } else if (h.region >= 0) {
      const Segment e{tri[h.region], tri[(h.region + 1) % 3]};
      ASSERT_LE(double((closestPoint(e, h.pointA) - h.pointA).norm()), tol) << info.str();
      ++st.regions[1];
    } else {
      ASSERT_EQ(h.region, SphereTriangleContact::kDegenerate) << info.str();
      ASSERT_NE(family, 0) << "a general triangle is not degenerate " << info.str();
    }
  }
  report("sphere", st);
  std::printf("sphere regions: %d face, %d edge, %d corner\n", st.regions[0], st.regions[1], st.regions[2]);
  for (const int r : st.regions) EXPECT_GT(r, n / 200);
  EXPECT_GT(st.hits, n / 3);
  EXPECT_GT(st.manifoldsCompared, n / 4);
}

TEST(TriangleContact, SphereCentreOnTheTriangleGetsMinusTheFrontNormal) {
  std::mt19937 rng = rngFor(7);
  for (int k = 0; k < 200; ++k) {
    // integer corners, so that a vertex, an edge midpoint and (a + b + 2c)/4 are exact
    std::uniform_int_distribution<int> coord(-8, 8);
    auto corner = [&] { return Vec3(Real(coord(rng)), Real(coord(rng)), Real(coord(rng))); };
    const Triangle tri{corner(), corner(), corner()};
    // (a sliver — area below 0.1 × longest edge² — is named by an edge, contact.hpp's rule)
    const Real longest = std::max({(tri.b - tri.a).norm(), (tri.c - tri.b).norm(), (tri.a - tri.c).norm()});
    if (!((tri.b - tri.a).cross(tri.c - tri.a).norm() > Real(0.1) * longest * longest)) continue;
    const Vec3 points[3] = {tri.a, Real(0.5) * (tri.a + tri.b), (tri.a + tri.b + Real(2) * tri.c) / Real(4)};
    for (const Vec3& c : points) {
      ContactManifold m;
      ASSERT_TRUE(sphereTriangleContacts(tri, c, Real(0.25), 0, m));
      const std::string info = describe(tri, "centre " + str(c)) + " " + describe(m);
      ASSERT_EQ(m.count, 1) << info;
      // the centre lies on the triangle exactly: the flat case, depth = radius, −front normal
      ASSERT_EQ(m.points[0].separation, Real(-0.25)) << info;
      ASSERT_GE(double(m.normal.dot(-faceNormal(tri))), 1 - 16 * kEpsReal) << info;
      ASSERT_EQ(m.points[0].featureA, featureId(FeatureKind::Face, 0)) << info;
      ASSERT_EQ(m.points[0].featureB, featureId(FeatureKind::Vertex, 0)) << info;
    }
  }
  // A point triangle with the centre on it: a finite deterministic normal (−z).
  ContactManifold m;
  const Vec3 p(Real(0.5), Real(-2), Real(3));
  ASSERT_TRUE(sphereTriangleContacts(Triangle{p, p, p}, p, Real(1), 0, m));
  EXPECT_EQ(m.normal, Vec3(0, 0, -1));
  EXPECT_EQ(m.points[0].separation, Real(-1));
}

// Slivers (height below 1e-3 of the longest edge, above the degenerate threshold) with a tiny edge
// near the origin: RTCD's region tests cancel there. Found by a scratch search in double builds:
// the face region was taken and the distance measured from the plane of (b − a) × (c − a), whose
// direction the rounding tilts by ~1 %, so a sphere 0.00085 from the triangle was reported at
// 0.00080 (deeper than it is). The separation must be the triangle's distance minus the radius,
// that distance lying within half the sliver's height of the boundary's (computed here per edge).
TEST(TriangleContact, SphereAgainstASliverWithATinyEdgeMeasuresTheTriangle) {
  auto f = [](double x, double y, double z) { return Vec3(Real(float(x)), Real(float(y)), Real(float(z))); };
  const Triangle t{f(-0.0922143372, 0.11088197, 0.117350176), f(9.92430456e-16, -4.73706923e-16, 5.76330799e-16),
                   f(-1.57302142e-15, -1.69576038e-15, 2.22014493e-15)};
  const Vec3 p = f(-0.0171521575, 0.020356842, 0.0205872674);
  double boundary = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i)
    boundary = std::min(boundary, (closestPoint(Segment{t[i], t[(i + 1) % 3]}, p) - p).cast<double>().norm());
  const Eigen::Vector3d a = t.a.cast<double>(), b = t.b.cast<double>(), c = t.c.cast<double>();
  const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
  const double halfHeight = 0.5 * (b - a).cross(c - a).norm() / longest;
  const Real radius = Real(0.5 * boundary), margin = Real(0.6 * boundary);
  SphereTriangleContact h;
  ASSERT_TRUE(sphereTriangleContact(t, p, radius, margin, h));
  const double tol = 1e-6 * boundary + halfHeight;  // float builds: the Real rounding of the inputs and output
  EXPECT_NEAR(double(h.separation), boundary - double(radius), tol) << "region " << h.region;
  ContactManifold m;
  ASSERT_TRUE(sphereTriangleContacts(t, p, radius, margin, m));
  EXPECT_NEAR(double(m.points[0].separation), boundary - double(radius), tol);
}

// A capsule against a sliver (a needle near the origin, 1.7e-14 of its longest edge high): its
// plane reject measured both ends beyond radius + margin from the plane of (b − a) × (c − a),
// which the rounding tilts, and dropped a capsule 0.0659 from the triangle at margin 0.079 (found
// by a scratch search, 55 of 200,000 such pairs in float builds). A sliver now skips that reject,
// takes its ends' closest points from closestOnSliver and decides crossing by the exact
// segment-triangle test. Reference: closestPoints with the segment as a degenerate triangle.
TEST(TriangleContact, CapsuleAgainstASliverWithATinyEdgeIsNotRejectedByItsPlane) {
  auto f = [](double x, double y, double z) { return Vec3(Real(float(x)), Real(float(y)), Real(float(z))); };
  const Triangle t{f(-3.64807177, 23.2632256, -8.1571331), f(-5.55402458e-13, -1.72173406e-13, -5.90908724e-13),
                   f(-5.60229163e-13, -4.31398379e-13, -7.11957281e-14)};
  const Vec3 p0 = f(0.0621858537, 0.498824, -0.135457903), p1 = f(0.0520624667, 0.507180214, -0.147355333);
  const double ref = double(closestPoints(t, Triangle{p0, p1, p1}).distance);
  ASSERT_NEAR(ref, 0.131878532, 1e-6);
  const Real radius = Real(0.5 * ref), margin = Real(0.6 * ref);
  ContactManifold m;
  ASSERT_TRUE(capsuleTriangleContacts(t, p0, p1, radius, margin, m));
  double least = std::numeric_limits<double>::infinity();
  for (int i = 0; i < m.count; ++i) least = std::min(least, double(m.points[i].separation));
  EXPECT_NEAR(least, ref - double(radius), 1e-5 * ref);
}

TEST(TriangleContact, SphereFarFromThePlaneIsRejected) {
  const Triangle tri{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  ContactManifold m;
  EXPECT_FALSE(sphereTriangleContacts(tri, Vec3(Real(0.2), Real(0.2), Real(1.5)), 1, Real(0.4), m));
  EXPECT_EQ(m.count, 0);
  // within the margin: a speculative point at separation 0.5 - ... exactly along -z
  ASSERT_TRUE(sphereTriangleContacts(tri, Vec3(Real(0.25), Real(0.25), Real(1.5)), 1, Real(0.5), m));
  EXPECT_EQ(m.normal, Vec3(0, 0, -1));
  EXPECT_EQ(m.points[0].separation, Real(0.5));
  EXPECT_EQ(m.points[0].pointA, Vec3(Real(0.25), Real(0.25), 0));
  EXPECT_EQ(m.points[0].pointB, Vec3(Real(0.25), Real(0.25), Real(0.5)));
}

// --- capsule ------------------------------------------------------------------------------------

TEST(TriangleContact, CapsuleAgreesWithGenericRoutine) {
  std::mt19937 rng = rngFor(20261123);
  const int n = test::scaledCases(8000);
  std::uniform_real_distribution<double> u(0, 1);
  Stats st;
  for (int k = 0; k < n; ++k) {
    const int family = k % 10 < 7 ? 0 : k % 10 - 6;
    const Triangle tri = randomTriangle(rng, family, 1);
    const Real radius = Real(0.05 + 0.5 * u(rng));
    const Real margin = Real(0.1 * u(rng));
    Vec3 a, b;
    const int placement = (k / 10) % 5;
    const Vec3 nrm = family == 0 ? faceNormal(tri) : randomUnit(rng);
    switch (placement) {
      case 0:  // anywhere
        a = randomVec(rng, -1.5, 1.5);
        b = randomVec(rng, -1.5, 1.5);
        break;
      case 1: {  // crossing the triangle (the segment through a point of it)
        const Vec3 p = pointOn(tri, rng), d = randomUnit(rng);
        a = p - Real(0.1 + u(rng)) * d;
        b = p + Real(0.1 + u(rng)) * d;
        break;
      }
      case 2: {  // lying along the face: parallel to the plane at height h (in or out of contact)
        Vec3 d = randomUnit(rng);
        d = (d - d.dot(nrm) * nrm).normalized();
        const Vec3 p = pointOn(tri, rng) + Real((u(rng) * 2 - 1) * (radius + margin)) * nrm;
        a = p - Real(0.1 + u(rng)) * d;
        b = p + Real(0.1 + u(rng)) * d;
        break;
      }
      case 3: {  // near the surface, random direction
        const Vec3 p = pointOn(tri, rng) + Real(u(rng) * 1.2 * (radius + margin)) * randomUnit(rng);
        const Vec3 d = randomUnit(rng);
        a = p;
        b = p + Real(0.05 + u(rng)) * d;
        break;
      }
      default: {  // degenerate capsule (a sphere) or very short, touching the face
        const Vec3 p = pointOn(tri, rng) + radius * nrm;
        a = p;
        b = (k % 2) ? p : Vec3(p + Real(1e-4) * randomUnit(rng));
        break;
      }
    }
    ContactManifold m;
    capsuleTriangleContacts(tri, a, b, radius, margin, m);
    std::ostringstream info;
    info.precision(17);
    info << "case " << k << " (placement " << placement << ") " << describe(tri, "capsule " + str(a) + " " + str(b))
         << " radius " << double(radius) << " margin " << double(margin);
    compare(tri, Capsule{a, b, radius}, margin, m, info.str(), st);
    if (HasFatalFailure()) return;
  }
  report("capsule", st);
  EXPECT_GT(st.hits, n / 3);
  EXPECT_GT(st.manifoldsCompared, n / 4);
  EXPECT_GT(st.twoPoints, n / 50);
}

TEST(TriangleContact, CapsuleLyingOnTheFaceGivesTwoPointsWithTheFaceNormal) {
  const Triangle tri{Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(0, 4, 0)};
  const Real r = Real(0.5);
  ContactManifold m;
  // lying at height 0.25 (penetrating by 0.25), both ends over the face
  ASSERT_TRUE(capsuleTriangleContacts(tri, Vec3(Real(0.5), Real(0.5), Real(0.25)), Vec3(Real(2.5), Real(0.5), Real(0.25)),
                                      r, 0, m));
  ASSERT_EQ(m.count, 2) << describe(m);
  EXPECT_EQ(m.normal, Vec3(0, 0, -1));
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(m.points[i].separation, Real(-0.25)) << describe(m);
    EXPECT_EQ(m.points[i].featureA, featureId(FeatureKind::Face, 0));
    EXPECT_EQ(m.points[i].pointA.z(), 0);
    EXPECT_EQ(m.points[i].pointB.z(), Real(-0.25));
  }
  // one end beyond the hypotenuse: the clip cuts the segment at x + y = 4
  ASSERT_TRUE(capsuleTriangleContacts(tri, Vec3(Real(0.5), Real(0.5), Real(0.25)), Vec3(Real(5.5), Real(0.5), Real(0.25)),
                                      r, 0, m));
  ASSERT_EQ(m.count, 2) << describe(m);
  EXPECT_NEAR(double(m.points[1].pointA.x()), 3.5, 1e-6) << describe(m);
  EXPECT_EQ(m.points[1].featureB, featureId(FeatureKind::Edge, 1)) << describe(m);
  // below the face (back side): normal +z, back face
  ASSERT_TRUE(capsuleTriangleContacts(tri, Vec3(Real(0.5), Real(0.5), Real(-0.25)),
                                      Vec3(Real(2.5), Real(0.5), Real(-0.25)), r, 0, m));
  ASSERT_EQ(m.count, 2);
  EXPECT_EQ(m.normal, Vec3(0, 0, 1));
  EXPECT_EQ(m.points[0].featureA, featureId(FeatureKind::Face, 1));
}

TEST(TriangleContact, CapsuleThroughTheFaceTakesTheMinimumTranslation) {
  const Triangle tri{Vec3(-4, -4, 0), Vec3(4, -4, 0), Vec3(0, 4, 0)};
  ContactManifold m;
  // vertical segment from z = -0.3 to z = 1: pushing it up (0.3) beats pushing it down (1)
  ASSERT_TRUE(capsuleTriangleContacts(tri, Vec3(0, 0, Real(-0.3)), Vec3(0, 0, 1), Real(0.1), 0, m));
  ASSERT_EQ(m.count, 1) << describe(m);
  EXPECT_NEAR(double(m.normal.z()), -1, 1e-12);
  EXPECT_NEAR(double(m.points[0].separation), -0.4, 1e-6);
  EXPECT_EQ(m.points[0].featureB, featureId(FeatureKind::Vertex, 0));
  // a long segment through a thin sliver near an edge: the edge axis wins
  const Triangle sliver{Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(0, Real(0.1), 0)};
  ASSERT_TRUE(capsuleTriangleContacts(sliver, Vec3(1, Real(0.02), -2), Vec3(1, Real(0.02), 2), 0, 0, m));
  ContactManifold g;
  contacts(ConvexShape(sliver), Transform::identity(), Capsule{Vec3(1, Real(0.02), -2), Vec3(1, Real(0.02), 2), 0},
           Transform::identity(), 0, g);
  EXPECT_NEAR(double(minSeparation(m)), double(minSeparation(g)), 1e-6) << describe(m) << " vs " << describe(g);
  EXPECT_LT(double(minSeparation(m)), -0.01);
  EXPECT_GT(double(minSeparation(m)), -0.03);
}

/// Radius and margin reaching one less than radius + margin (integers, radius + margin >= 1), both
/// >= 0 as the primitive layer requires: the radius one less, or the margin when the radius is 0.
std::pair<Real, Real> oneReachShort(Real radius, Real margin) {
  return radius >= 1 ? std::pair<Real, Real>(radius - 1, margin) : std::pair<Real, Real>(radius, margin - 1);
}

// Touching on the integer grid must be reported (every boolean answer on integer-grid
// inputs equals the exact answer; crux diff found a capsule touching a segment triangle at
// distance exactly 1, which the double distance put at 1 + 2e-16, and dropped). Two constructions,
// each touching at radius + margin = k exactly and apart by 1 at one less:
// - corner: the capsule's segment s0 + t·d (integers) has its foot on the line at a rational
//   t = (X - s0)·d / |d|² inside the segment, at an integer distance k from the integer point X
//   (searched: |w|²|d|² - (w·d)² = k²|d|²); X is a corner of the triangle, whose other corners
//   lie in the half-space beyond X away from the segment. The foot is not representable, so the
//   computed distance is off by an ulp either way.
// - face: the triangle lies in the plane through X normal to an integer u of integer length L
//   (a Pythagorean quadruple), X inside it; the sphere's centre is X + k·u, the capsule's segment
//   parallel to the plane through X + k·u: the distance is k·L in the face region.
// Also the withinDistance predicates directly. The first fails without the exact margin decision.
TEST(TriangleContact, TouchingOnTheIntegerGridIsReported) {
  test::GridDraws draws(0x70c4u);
  const int cases = test::scaledCases(3000, 300);
  int missed = 0, falseHits = 0, corner = 0, degenerate = 0;
  std::string first;
  auto check = [&](const char* kind, const Triangle& tri, const Vec3* centre, const Vec3& p0, const Vec3& p1,
                   Real reach) {
    const Real margin = Real(draws.integer(0, 1)), radius = reach - margin;
    const auto [lessRadius, lessMargin] = oneReachShort(radius, margin);
    std::ostringstream what;
    what << kind << ": triangle " << tri.a.transpose() << " | " << tri.b.transpose() << " | " << tri.c.transpose()
         << ", radius " << radius << " margin " << margin << ", ";
    ContactManifold m;
    if (centre) {
      what << "sphere centre " << centre->transpose();
      EXPECT_TRUE(withinDistance(tri, *centre, radius, margin)) << what.str();
      EXPECT_FALSE(withinDistance(tri, *centre, lessRadius, lessMargin)) << what.str();
      if (sphereTriangleContacts(tri, *centre, radius, margin, m)) {
        EXPECT_LE(m.points[0].separation, margin) << what.str();
      } else if (++missed == 1) {
        first = what.str();
      }
      falseHits += sphereTriangleContacts(tri, *centre, lessRadius, lessMargin, m);
      return;
    }
    what << "capsule " << p0.transpose() << " -> " << p1.transpose();
    EXPECT_TRUE(withinDistance(tri, p0, p1, radius, margin)) << what.str();
    EXPECT_FALSE(withinDistance(tri, p0, p1, lessRadius, lessMargin)) << what.str();
    if (capsuleTriangleContacts(tri, p0, p1, radius, margin, m)) {
      for (int j = 0; j < m.count; ++j) EXPECT_LE(m.points[j].separation, margin) << what.str();
    } else if (++missed == 1) {
      first = what.str();
    }
    falseHits += capsuleTriangleContacts(tri, p0, p1, lessRadius, lessMargin, m);
  };
  for (int i = 0; i < cases; ++i) {
    const Vec3 X = draws.point(5);
    if (i % 2 == 0) {
      // corner: search a segment at an integer distance from X, its foot strictly inside
      Vec3 s0, d;
      long k = 0;
      if (!test::segmentAtIntegerDistance(draws, X, s0, d, k)) continue;
      // the far half-space: (y - X)·(foot - X) <= 0, with foot - X = (s0 - X) + t·d scaled by |d|²
      const Vec3 n = test::towardsFoot(X, s0, d);
      Vec3 v[2] = {test::pointBehind(draws, X, n), test::pointBehind(draws, X, n)};
      if (i % 6 == 0) v[1] = v[0];  // a segment triangle (a point when v[0] == X)
      const Triangle tri{X, v[0], v[1]};
      degenerate += (v[1] - X).cross(v[0] - X).squaredNorm() == 0;
      ++corner;
      check("corner", tri, nullptr, s0, s0 + d, Real(k));
    } else {
      // face: a triangle around X in the plane normal to u, the shapes at height k·L
      struct Quad {
        int x, y, z, length;
      };
      static const Quad quads[] = {{0, 3, 4, 5}, {1, 2, 2, 3}, {2, 3, 6, 7}, {1, 4, 8, 9}, {4, 4, 7, 9}, {2, 6, 9, 11}};
      const Quad& q = quads[std::size_t(draws.integer(0, 5))];
      const Vec3 u(Real(q.x * (draws.integer(0, 1) ? 1 : -1)), Real(q.y * (draws.integer(0, 1) ? 1 : -1)),
                   Real(q.z * (draws.integer(0, 1) ? 1 : -1)));
      Vec3 e1 = u.cross(draws.point(2));
      if (e1.squaredNorm() == 0) e1 = u.cross(Vec3(1, 0, 0)).squaredNorm() > 0 ? u.cross(Vec3(1, 0, 0)) : u.cross(Vec3(0, 1, 0));
      const Vec3 e2 = u.cross(e1);  // e1, e2: integer, normal to u and to each other
      const Vec3 a = X + Real(2) * e1, b = X - e1 + e2, c = X - e1 - e2;  // centroid X
      const Triangle tri{a, b, c};
      const int k = draws.integer(1, 2);
      const Vec3 centre = X + Real(k) * u;
      check("face", tri, &centre, centre, centre, Real(k * q.length));
      const Vec3 p0 = centre - Real(draws.integer(0, 2)) * e1, p1 = centre + Real(draws.integer(1, 2)) * e1;
      check("face", tri, nullptr, p0, p1, Real(k * q.length));
    }
  }
  std::printf("%d grid touching cases (%d corner, %d of them on degenerate triangles)\n", cases, corner, degenerate);
  EXPECT_EQ(missed, 0) << first;
  EXPECT_EQ(falseHits, 0);
  EXPECT_GT(corner, cases / 4);
  EXPECT_GT(degenerate, 0);
}

// A sphere touching a triangle's edge far from the origin (integer coordinates up to ~4e6, still
// exact in float): the computed distance to the edge's foot rounds by ~|coordinates| × ulp, far
// more than a tolerance relative to the radius alone, so an early reject on the radius scale
// would drop a touching pair the exact decision reports.
TEST(TriangleContact, TouchingFarFromTheOriginIsReported) {
  test::GridDraws draws(0xfa70u);
  const int cases = test::scaledCases(2000, 300);
  int built = 0, missed = 0, falseHits = 0;
  std::string first;
  for (int i = 0; i < cases; ++i) {
    test::PointAndSegment g;
    if (!test::drawPointAndSegment(draws, g)) continue;
    const Vec3 &X = g.X, &s0 = g.s0, &d = g.d, &n = g.n;
    const long k = g.k;
    // beyond the plane through the foot normal to X → foot: n·(c − X) >= |d|²k² (n = |d|²(foot − X))
    Vec3 c;
    int tries = 0;
    do c = s0 + draws.point(4);
    while (double(n.dot(c - X)) < double(d.squaredNorm()) * double(k * k) && ++tries < 1000);
    if (tries == 1000) continue;
    const int scale = 1 << draws.integer(12, 22);
    const Vec3 offset(Real(scale * (draws.integer(0, 1) ? 1 : -1)), Real(draws.integer(-scale, scale)),
                      Real(draws.integer(-scale, scale)));
    const Triangle tri{s0 + offset, s0 + d + offset, c + offset};
    const Vec3 centre = X + offset;
    const Real margin = Real(draws.integer(0, 1)), radius = Real(k) - margin;
    const auto [lessRadius, lessMargin] = oneReachShort(radius, margin);
    ++built;
    ContactManifold m;
    if (!sphereTriangleContacts(tri, centre, radius, margin, m) && ++missed == 1) {
      std::ostringstream what;
      what << "triangle " << tri.a.transpose() << " | " << tri.b.transpose() << " | " << tri.c.transpose()
           << ", sphere " << centre.transpose() << " radius " << radius << " margin " << margin;
      first = what.str();
    }
    EXPECT_TRUE(withinDistance(tri, centre, radius, margin));
    falseHits += sphereTriangleContacts(tri, centre, lessRadius, lessMargin, m);
    // the same pair as a capsule (the segment) against a triangle cornered at the sphere's centre
    const Vec3 v[2] = {test::pointBehind(draws, X, n), test::pointBehind(draws, X, n)};
    const Triangle corner{centre, v[0] + offset, v[1] + offset};
    const Vec3 p0 = s0 + offset, p1 = s0 + d + offset;
    if (!capsuleTriangleContacts(corner, p0, p1, radius, margin, m) && ++missed == 1) {
      std::ostringstream what;
      what << "triangle " << corner.a.transpose() << " | " << corner.b.transpose() << " | " << corner.c.transpose()
           << ", capsule " << p0.transpose() << " -> " << p1.transpose() << " radius " << radius << " margin " << margin;
      first = what.str();
    }
    falseHits += capsuleTriangleContacts(corner, p0, p1, lessRadius, lessMargin, m);
    // and through the generic convex pair routine (GJK with the exact margin decision)
    if (!contacts(ConvexShape(tri), Transform::identity(), ConvexShape(Sphere{centre, radius}), Transform::identity(),
                  margin, m) &&
        ++missed == 1)
      first = "contacts(): sphere of the first case kind";
    if (!contacts(ConvexShape(corner), Transform::identity(), ConvexShape(Capsule{p0, p1, radius}),
                  Transform::identity(), margin, m) &&
        ++missed == 1)
      first = "contacts(): capsule of the second case kind";
  }
  std::printf("%d far touching cases built\n", built);
  EXPECT_GT(built, cases / 2);
  EXPECT_EQ(missed, 0) << first;
  EXPECT_EQ(falseHits, 0);
}

// Non-queryable inputs (precondition.hpp, rule::kPrimitive): the routines behind the public entries
// (geometry/unchecked.hpp, what those entries run in release builds and the mesh, scene and contact
// layers call) give an unspecified answer, but return without undefined behaviour, which the
// sanitizer stage checks here.
TEST(TriangleContactPreconditions, NonQueryableInputsReturnWithoutUndefinedBehaviour) {
  const test_support::BadPrimitives bad = test_support::badPrimitives();
  const Triangle tri{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  const Vec3 c(Real(0.2), Real(0.2), Real(0.4)), c1(Real(0.4), Real(0.2), Real(0.4));
  int calls = 0;
  ContactManifold m;
  SphereTriangleContact one;
  const auto all = [&](const Triangle& t, const Vec3& p, const Vec3& q, Real r) {
    calls += 3;
    (void)unchecked::sphereTriangleContacts(t, p, r, 0, m);
    (void)unchecked::sphereTriangleContact(t, p, r, 0, one);
    (void)unchecked::capsuleTriangleContacts(t, p, q, r, 0, m);
  };
  for (const Triangle& t : bad.triangles) all(t, c, c1, Real(0.5));
  for (const Vec3& p : bad.points) all(tri, p, c1, Real(0.5)), all(tri, c, p, Real(0.5));
  for (const Real r : test_support::nonFiniteValues()) all(tri, c, c1, r);
  all(tri, c, c1, -1);
  EXPECT_GT(calls, 80);
  EXPECT_TRUE(unchecked::sphereTriangleContacts(tri, c, Real(0.5), 0, m));
}

// In debug builds (CRUX_CHECK_PRIMITIVE_PRECONDITIONS, on without NDEBUG) a non-queryable input
// aborts with a message naming the query.
TEST(TriangleContactPreconditions, DebugBuildsAbortNamingTheQuery) {
  if (!CRUX_CHECK_PRIMITIVE_PRECONDITIONS)
    GTEST_SKIP() << "the primitive check is off in this build (NDEBUG)";
  const Triangle tri{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  ContactManifold m;
  const Vec3 c(Real(0.2), Real(0.2), Real(0.4));
  EXPECT_DEATH((void)sphereTriangleContacts(tri, c, -1, 0, m),
               "precondition violated in sphereTriangleContacts");
  const Real nan = std::numeric_limits<Real>::quiet_NaN();
  EXPECT_DEATH((void)capsuleTriangleContacts(tri, c, Vec3(nan, 0, 0), Real(0.5), 0, m),
               "precondition violated in capsuleTriangleContacts");
}

}  // namespace
}  // namespace crux
