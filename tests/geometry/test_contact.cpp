// Tests of src/geometry/contact.cpp: manifolds with known answers (stacked boxes, a rotated box,
// capsule and sphere resting on a box, parallel capsules, a triangle on a box, hull on hull,
// speculative margin) and seeded properties over random pairs (every point on both shapes,
// pointA - pointB = separation·normal, separation <= margin, at most 4 points), plus the
// issue-6 regressions: sliver triangles and nearly parallel, offset edges (triangle vs box),
// quarter-turn grid boxes at the margin, and degenerate shapes (flat / segment / point boxes,
// zero-radius capsules, collinear and coplanar hulls) giving no coincident contact points.

#include <crux/error.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <crux/geometry/closest_point.hpp>
#include <crux/geometry/contact.hpp>
#include <limits>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "support/grid_touching.hpp"
#include "support/test_scale.hpp"
#include <crux/precondition.hpp>
#include "support/bad_inputs.hpp"

namespace crux {
namespace {

constexpr double kEps = std::numeric_limits<Real>::epsilon();
using V3d = Eigen::Vector3d;

std::string str(const Vec3& v) {
  std::ostringstream os;
  os.precision(17);
  os << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return os.str();
}

std::string str(const ContactManifold& m) {
  std::ostringstream os;
  os.precision(17);
  os << "normal " << str(m.normal) << ", " << m.count << " points:";
  for (int i = 0; i < m.count; ++i)
    os << "\n  A " << str(m.points[i].pointA) << " B " << str(m.points[i].pointB) << " sep " << m.points[i].separation
       << " fa " << std::hex << m.points[i].featureA << " fb " << m.points[i].featureB << std::dec;
  return os.str();
}

Transform at(Real x, Real y, Real z, Quat q = Quat::Identity()) {
  Transform t;
  t.translation = Vec3(x, y, z);
  t.rotation = q;
  return t;
}

const Obb kCube{Vec3::Zero(), Vec3::Ones(), Mat3::Identity()};

TEST(Contacts, StackedBoxesGiveFourCornerPoints) {
  ContactManifold m;
  ASSERT_TRUE(contacts(kCube, at(0, 0, Real(1.9)), kCube, Transform{}, 0, m));
  ASSERT_EQ(m.count, 4) << str(m);
  EXPECT_NEAR((m.normal - Vec3(0, 0, 1)).norm(), 0, 8 * kEps) << str(m);
  for (int i = 0; i < 4; ++i) {
    const ContactPoint& p = m.points[i];
    EXPECT_NEAR(p.separation, -0.1, 16 * kEps) << str(m);
    EXPECT_NEAR(p.pointA.z(), 0.9, 16 * kEps) << str(m);
    EXPECT_NEAR(p.pointB.z(), 1, 16 * kEps) << str(m);
    EXPECT_NEAR(std::abs(p.pointB.x()), 1, 16 * kEps) << str(m);
    EXPECT_NEAR(std::abs(p.pointB.y()), 1, 16 * kEps) << str(m);
  }
  EXPECT_NEAR(m.depth(), 0.1, 16 * kEps);
}

TEST(Contacts, ReversedOrderFlipsTheNormal) {
  ContactManifold m;
  ASSERT_TRUE(contacts(kCube, Transform{}, kCube, at(0, 0, Real(1.9)), 0, m));
  ASSERT_EQ(m.count, 4) << str(m);
  EXPECT_NEAR((m.normal - Vec3(0, 0, -1)).norm(), 0, 8 * kEps) << str(m);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(m.points[i].pointA.z(), 1, 16 * kEps) << str(m);
}

TEST(Contacts, RotatedBoxOnBoxIsReducedToFourPointsOfTheOctagon) {
  const Quat q(Eigen::AngleAxis<Real>(Real(M_PI / 4), Vec3::UnitZ()));
  ContactManifold m;
  ASSERT_TRUE(contacts(kCube, at(0, 0, Real(1.95), q), kCube, Transform{}, 0, m));
  ASSERT_EQ(m.count, 4) << str(m);
  for (int i = 0; i < 4; ++i) {
    const ContactPoint& p = m.points[i];
    EXPECT_NEAR(p.separation, -0.05, 64 * kEps) << str(m);
    // Inside both footprints: |x|,|y| <= 1 and |x|+|y| <= sqrt(2).
    EXPECT_LE(p.pointB.cwiseAbs().head<2>().maxCoeff(), 1 + 16 * kEps) << str(m);
    EXPECT_LE(std::abs(p.pointB.x()) + std::abs(p.pointB.y()), std::sqrt(2.0) + 16 * kEps) << str(m);
  }
  // Area-maximising choice: the four points are not all on one side (they span > half the octagon).
  double minX = 1e9, maxX = -1e9, minY = 1e9, maxY = -1e9;
  for (int i = 0; i < 4; ++i) {
    minX = std::min(minX, double(m.points[i].pointB.x()));
    maxX = std::max(maxX, double(m.points[i].pointB.x()));
    minY = std::min(minY, double(m.points[i].pointB.y()));
    maxY = std::max(maxY, double(m.points[i].pointB.y()));
  }
  EXPECT_GT((maxX - minX) * (maxY - minY), 1.0) << str(m);
}

TEST(Contacts, CapsuleLyingOnABoxTouchesAtBothEnds) {
  const Capsule cap{Vec3(Real(-0.5), 0, 0), Vec3(Real(0.5), 0, 0), Real(0.5)};
  ContactManifold m;
  ASSERT_TRUE(contacts(cap, at(0, 0, Real(1.4)), kCube, Transform{}, 0, m));
  ASSERT_EQ(m.count, 2) << str(m);
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(m.points[i].separation, -0.1, 16 * kEps) << str(m);
    EXPECT_NEAR(std::abs(m.points[i].pointA.x()), 0.5, 16 * kEps) << str(m);
    EXPECT_NEAR(m.points[i].pointA.z(), 0.9, 16 * kEps) << str(m);
    EXPECT_NEAR(m.points[i].pointB.z(), 1, 16 * kEps) << str(m);
  }
}

TEST(Contacts, SphereOnABoxIsOnePoint) {
  ContactManifold m;
  ASSERT_TRUE(contacts(Sphere{Vec3::Zero(), Real(0.5)}, at(Real(0.25), 0, Real(1.25)), kCube, Transform{}, 0, m));
  ASSERT_EQ(m.count, 1) << str(m);
  EXPECT_NEAR(m.points[0].separation, -0.25, 16 * kEps);
  EXPECT_NEAR((m.points[0].pointB - Vec3(Real(0.25), 0, 1)).norm(), 0, 16 * kEps) << str(m);
  EXPECT_NEAR((m.points[0].pointA - Vec3(Real(0.25), 0, Real(0.75))).norm(), 0, 16 * kEps) << str(m);
}

TEST(Contacts, ParallelCapsulesGiveTheOverlapOfTheirSegments) {
  const Capsule a{Vec3(0, 0, 0), Vec3(2, 0, 0), Real(0.5)}, b{Vec3(1, 0, 0), Vec3(4, 0, 0), Real(0.5)};
  ContactManifold m;
  ASSERT_TRUE(contacts(a, at(0, Real(0.9), 0), b, Transform{}, 0, m));
  ASSERT_EQ(m.count, 2) << str(m);
  std::vector<Real> xs{m.points[0].pointA.x(), m.points[1].pointA.x()};
  std::sort(xs.begin(), xs.end());
  EXPECT_NEAR(xs[0], 1, 16 * kEps);
  EXPECT_NEAR(xs[1], 2, 16 * kEps);
  for (int i = 0; i < 2; ++i) EXPECT_NEAR(m.points[i].separation, -0.1, 16 * kEps);
}

TEST(Contacts, TriangleOnABoxFace) {
  const Triangle t{Vec3(Real(-0.5), Real(-0.5), 0), Vec3(Real(0.5), Real(-0.5), 0), Vec3(0, Real(0.5), 0)};
  ContactManifold m;
  ASSERT_TRUE(contacts(kCube, at(0, 0, Real(0.95)), t, Transform{}, 0, m));  // box sinks 0.05 into the triangle
  ASSERT_EQ(m.count, 3) << str(m);
  EXPECT_NEAR(std::abs(m.normal.z()), 1, 8 * kEps) << str(m);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(m.points[i].separation, -0.05, 16 * kEps) << str(m);
}

TEST(Contacts, HullOnHull) {
  std::vector<Vec3> pts;
  for (int i = 0; i < 8; ++i) pts.emplace_back((i & 1) ? 1 : -1, (i & 2) ? 1 : -1, (i & 4) ? 1 : -1);
  const ConvexHull h = ConvexHull::build(pts);
  ContactManifold m;
  ASSERT_TRUE(contacts(h, at(Real(0.5), 0, Real(1.98)), h, Transform{}, 0, m));
  ASSERT_EQ(m.count, 4) << str(m);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(m.points[i].separation, -0.02, 64 * kEps) << str(m);
  EXPECT_EQ(m.points[0].featureA >> 24, std::uint32_t(FeatureKind::Face));
}

TEST(Contacts, SpeculativeMargin) {
  ContactManifold m;
  EXPECT_TRUE(contacts(kCube, at(0, 0, Real(2.05)), kCube, Transform{}, Real(0.1), m));
  ASSERT_EQ(m.count, 4) << str(m);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(m.points[i].separation, 0.05, 16 * kEps);
  EXPECT_FALSE(contacts(kCube, at(0, 0, Real(2.05)), kCube, Transform{}, Real(0.01), m));
  EXPECT_EQ(m.count, 0);
}

TEST(Contacts, EdgeOnFaceGivesTwoPoints) {
  const Quat q(Eigen::AngleAxis<Real>(Real(M_PI / 4), Vec3::UnitX()));  // edge down, along x
  ContactManifold e;
  ASSERT_TRUE(contacts(kCube, at(0, 0, Real(1 + std::sqrt(2.0) - 0.1), q), kCube, Transform{}, 0, e));
  ASSERT_EQ(e.count, 2) << str(e);
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(e.points[i].separation, -0.1, 64 * kEps) << str(e);
    EXPECT_NEAR(std::abs(e.points[i].pointA.x()), 1, 64 * kEps) << str(e);
  }
}

// ---- properties ------------------------------------------------------------------------------

double distanceToShape(const ConvexShape& s, const Transform& t, const Vec3& p) {
  const Eigen::Matrix3d R = t.rotation.cast<double>().toRotationMatrix();
  const V3d l = R.transpose() * (p.cast<double>() - t.translation.cast<double>());
  switch (s.kind) {
    case ConvexKind::Sphere: return std::max(0.0, (l - s.p[0].cast<double>()).norm() - s.radius);
    case ConvexKind::Capsule: {
      const V3d a = s.p[0].cast<double>(), e = s.p[1].cast<double>() - a;
      const double u = e.squaredNorm() > 0 ? std::clamp((l - a).dot(e) / e.squaredNorm(), 0.0, 1.0) : 0.0;
      return std::max(0.0, (l - a - u * e).norm() - s.radius);
    }
    case ConvexKind::Box: {
      const V3d q = s.axes.cast<double>().transpose() * (l - s.p[0].cast<double>());
      return (q.cwiseAbs() - s.p[1].cast<double>()).cwiseMax(0.0).norm();
    }
    case ConvexKind::Hull: {
      double worst = 0;
      for (const HullFace& f : s.hull->faces()) worst = std::max(worst, f.normal.cast<double>().dot(l) - f.offset);
      return worst;
    }
    default: return 0;
  }
}

TEST(ContactsProperty, RandomPairs) {
  std::mt19937_64 rng(555);
  std::uniform_real_distribution<double> u(-1, 1);
  std::normal_distribution<double> g;
  auto v = [&](double s) { return Vec3(Real(u(rng) * s), Real(u(rng) * s), Real(u(rng) * s)); };
  auto rot = [&] { return Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().cast<Real>(); };
  std::vector<std::unique_ptr<ConvexHull>> hulls;
  int withPoints = 0, multi = 0;
  for (int i = 0; i < 4000; ++i) {
    auto make = [&](int kind) -> ConvexShape {
      switch (kind) {
        case 0: return Sphere{v(0.2), Real(0.3 + 0.5 * std::abs(u(rng)))};
        case 1: return Capsule{v(1), v(1), Real(0.1 + 0.4 * std::abs(u(rng)))};
        case 2: return Obb{v(0.2), v(1).cwiseAbs() + Vec3::Constant(Real(0.1)), rot().toRotationMatrix()};
        default: {
          std::vector<Vec3> pts;
          for (int k = 0; k < 12; ++k) pts.push_back(v(1));
          hulls.push_back(std::make_unique<ConvexHull>(ConvexHull::build(pts)));
          return *hulls.back();
        }
      }
    };
    const bool faceToFace = i % 3 == 0;  // axis-aligned boxes under one rotation: face contacts
    ConvexShape a = make(faceToFace ? 2 : int(std::abs(u(rng)) * 4)), b = make(faceToFace ? 2 : int(std::abs(u(rng)) * 4));
    if (faceToFace) a.axes = b.axes = Mat3::Identity();
    Transform ta, tb;
    ta.rotation = rot();
    tb.rotation = rot();
    ta.translation = v(1.5);
    tb.translation = v(1.5);
    // Every few pairs: snap to face-to-face (same rotation) to exercise clipping.
    if (faceToFace) tb.rotation = ta.rotation;
    const Real margin = Real(0.05);
    ContactManifold m;
    const bool any = contacts(a, ta, b, tb, margin, m);
    const DistanceResult d = distance(a, ta, b, tb);
    const double S = double(a.size() + b.size()) + (ta.translation - tb.translation).cast<double>().norm();
    const double tol = 64 * kEps * S + 1e-9 * S;
    ASSERT_EQ(any, d.distance <= margin) << i;
    ASSERT_EQ(any, m.count > 0);
    if (!any) continue;
    ++withPoints;
    if (m.count > 1) ++multi;
    ASSERT_LE(m.count, 4);
    EXPECT_NEAR(m.normal.norm(), 1, 16 * kEps);
    double minSep = INFINITY;
    for (int k = 0; k < m.count; ++k) {
      const ContactPoint& p = m.points[k];
      ASSERT_TRUE(p.pointA.allFinite() && p.pointB.allFinite() && std::isfinite(p.separation));
      EXPECT_LE(p.separation, margin + tol);
      EXPECT_LE(((p.pointA - p.pointB).cast<double>() - double(p.separation) * m.normal.cast<double>()).norm(), tol)
          << "pair " << i << " kinds " << int(a.kind) << " " << int(b.kind) << " status " << int(d.status) << "\n" << str(m);
      EXPECT_LE(distanceToShape(a, ta, p.pointA), tol) << "pair " << i << "\n" << str(m);
      EXPECT_LE(distanceToShape(b, tb, p.pointB), tol) << "pair " << i << " kinds " << int(a.kind) << " " << int(b.kind) << "\n" << str(m);
      minSep = std::min(minSep, double(p.separation));
    }
    // The deepest point agrees with GJK/EPA up to the 2° feature angle.
    EXPECT_NEAR(minSep, d.distance, 0.035 * S) << "pair " << i << "\n" << str(m);
  }
  EXPECT_GT(withPoints, 800);
  EXPECT_GT(multi, 200);
}

}  // namespace
}  // namespace crux

namespace crux {
namespace {

TEST(Contacts, BadMarginIsInvalidInputNamingIt) {
  ContactManifold m;
  for (const Real bad : {Real(-0.1), std::numeric_limits<Real>::quiet_NaN(), std::numeric_limits<Real>::infinity()}) {
    try {
      contacts(Sphere{Vec3::Zero(), Real(0.5)}, at(Real(0.25), 0, Real(1.25)), kCube, Transform{}, bad, m);
      ADD_FAILURE() << "margin " << bad << " accepted";
    } catch (const InvalidInput& e) {
      EXPECT_EQ(std::string(e.what()).rfind("margin: ", 0), 0u) << e.what();
    }
  }
}

}  // namespace
}  // namespace crux

// ---- regressions: sliver triangles, nearly parallel offset edges (triangle A, box B) ----

namespace crux {
namespace {

/// Tolerance of "on the shape" / pointA - pointB = separation·normal: the rounding of the
/// returned Real values × the pair's coordinate scale (as in test_box_triangle_contact.cpp).
constexpr double kOnShapeUlps = 64;

std::string describeTriBox(const Triangle& t, const Vec3& half, Real margin) {
  std::ostringstream os;
  os.precision(17);
  os << "tri " << str(t.a) << " " << str(t.b) << " " << str(t.c) << " half " << str(half) << " margin "
     << double(margin);
  return os.str();
}

/// Every point of the manifold of (triangle, identity) vs (box of half extents `half`, identity)
/// lies on both shapes, pointA - pointB = separation·normal, separation <= margin.
::testing::AssertionResult triBoxWellFormed(const Triangle& t, const Vec3& half, Real margin,
                                            const ContactManifold& m) {
  const double S = std::max({double(half.cwiseAbs().maxCoeff()), double(t.a.cwiseAbs().maxCoeff()),
                             double(t.b.cwiseAbs().maxCoeff()), double(t.c.cwiseAbs().maxCoeff())}) +
                   double(margin);
  const double tol = kOnShapeUlps * kEps * S;
  auto num = [](double x) {
    std::ostringstream os;
    os.precision(17);
    os << x;
    return os.str();
  };
  auto fail = [&](const std::string& what) {
    return ::testing::AssertionFailure() << what << "\n" << describeTriBox(t, half, margin) << "\n" << str(m);
  };
  if (m.count < 1 || m.count > ContactManifold::kMaxContactPoints) return fail("point count");
  if (!(std::abs(double(m.normal.norm()) - 1) <= 8 * kEps)) return fail("normal not unit");
  const V3d h = half.cast<double>();
  for (int i = 0; i < m.count; ++i) {
    const ContactPoint& p = m.points[i];
    const V3d a = p.pointA.cast<double>(), b = p.pointB.cast<double>();
    if (!std::isfinite(a.sum() + b.sum() + double(p.separation))) return fail("non-finite point");
    // On the triangle: its closest point, or (well conditioned on slivers) its edges.
    double dA = double(squaredDistance(t, p.pointA));
    for (int e = 0; e < 3; ++e) dA = std::min(dA, double(squaredDistance(Segment{t[e], t[(e + 1) % 3]}, p.pointA)));
    if (!(std::sqrt(dA) <= tol)) return fail("pointA not on the triangle, off by " + num(std::sqrt(dA)));
    const V3d excess = b.cwiseAbs() - h;
    if (!(excess.maxCoeff() <= tol)) return fail("pointB outside the box by " + num(excess.maxCoeff()));
    if (!(excess.maxCoeff() >= -tol)) return fail("pointB inside the box, not on its surface");
    if (!((a - b - double(p.separation) * m.normal.cast<double>()).norm() <= tol))
      return fail("pointA - pointB != separation * normal");
    if (!(double(p.separation) <= double(margin) + tol)) return fail("separation > margin");
  }
  return ::testing::AssertionSuccess();
}

bool triBox(const Triangle& t, const Vec3& half, Real margin, ContactManifold& m) {
  Obb box;
  box.half = half;
  return contacts(ConvexShape(t), Transform{}, ConvexShape(box), Transform{}, margin, m);
}

TEST(ContactsOnTheBoundary, NearlyParallelOffsetEdgesKeepPointsOnTheBox) {
  // From H2's NearlyParallelOffsetEdgesKeepPointsOnTheBox (test_box_triangle_contact.cpp): the
  // edge-reference clipping put pointB at |y| = 1.782 > 1.7356 (double build).
  const Vec3 half(Real(0.82585418100247765), Real(1.7355784415104598), Real(0.49252121972387419));
  const Triangle t{Vec3(Real(1.1181553810141036), Real(-1.7530383300405692), Real(-0.50425362319975031)),
                   Vec3(Real(-0.80504669195608036), Real(-1.8079226704036215), Real(-0.50776341272902537)),
                   Vec3(Real(0.4474789120501419), Real(-3.2561772844565269), Real(-1.1719251984506456))};
  ContactManifold m;
  ASSERT_TRUE(triBox(t, half, Real(0.2), m));
  EXPECT_TRUE(triBoxWellFormed(t, half, Real(0.2), m));
}

TEST(ContactsOnTheBoundary, ExactlyParallelEdgesStillGiveTwoPoints) {
  // A triangle edge parallel to the box edge (y = z = 1) and 0.05 above it along the bisector:
  // the overlap of the two edges, both ends.
  const Real d = Real(0.05 / std::sqrt(2.0));
  const Triangle t{Vec3(Real(-0.5), 1 + d, 1 + d), Vec3(Real(1.5), 1 + d, 1 + d), Vec3(Real(0.5), 2, 2)};
  ContactManifold m;
  ASSERT_TRUE(triBox(t, Vec3::Ones(), Real(0.1), m));
  EXPECT_TRUE(triBoxWellFormed(t, Vec3::Ones(), Real(0.1), m));
  ASSERT_EQ(m.count, 2) << str(m);
  const Real xs[2] = {std::min(m.points[0].pointB.x(), m.points[1].pointB.x()),
                      std::max(m.points[0].pointB.x(), m.points[1].pointB.x())};
  EXPECT_NEAR(xs[0], -0.5, 64 * kEps) << str(m);
  EXPECT_NEAR(xs[1], 1, 64 * kEps) << str(m);
  for (int i = 0; i < 2; ++i) EXPECT_NEAR(m.points[i].separation, 0.05, 64 * kEps) << str(m);
}

/// Unit vector perpendicular to v (any).
V3d perpendicular(const V3d& v) {
  const V3d o = std::abs(v.x()) < 0.9 ? V3d::UnitX() : V3d::UnitY();
  return v.cross(o).normalized();
}

TEST(ContactsOnTheBoundary, RandomNearlyParallelOffsetEdgesStayOnBothShapes) {
  // A triangle edge within 0.01°..2° of a box edge, offset along the edge's outward bisector
  // (gap) and across it (lateral), the third vertex away from the box.
  std::mt19937_64 rng(20261122);
  std::uniform_real_distribution<double> U(0, 1);
  int found = 0, multi = 0;
  const int n = 6000;
  for (int i = 0; i < n; ++i) {
    const V3d h(0.3 + 1.7 * U(rng), 0.3 + 1.7 * U(rng), 0.3 + 1.7 * U(rng));
    const int ax = int(U(rng) * 3) % 3, ay = (ax + 1) % 3, az = (ax + 2) % 3;
    const double sy = U(rng) < 0.5 ? -1 : 1, sz = U(rng) < 0.5 ? -1 : 1;
    V3d corner = V3d::Zero();
    corner[ay] = sy * h[ay];
    corner[az] = sz * h[az];
    V3d bis = V3d::Zero();
    bis[ay] = sy;
    bis[az] = sz;
    bis.normalize();
    V3d dir = V3d::Unit(ax);
    const double angle = (0.01 + 1.99 * U(rng)) * M_PI / 180;
    dir = Eigen::AngleAxisd(angle, (bis * std::cos(6.3 * U(rng)) + dir.cross(bis) * std::sin(6.3 * U(rng))).normalized()) * dir;
    const double scale = h.maxCoeff();
    const double gap = scale * (-0.02 + 0.1 * U(rng)), lateral = scale * 0.05 * (2 * U(rng) - 1);
    const V3d mid = corner + V3d::Unit(ax) * h[ax] * (2 * U(rng) - 1) + bis * gap + dir.cross(bis).normalized() * lateral;
    const double len = scale * (0.5 + 2 * U(rng));
    const V3d a = mid - dir * len * U(rng), b = mid + dir * len * U(rng);
    const V3d away = (bis + perpendicular(bis) * (U(rng) - 0.5)).normalized();
    const V3d c = (a + b) / 2 + away * scale * (0.3 + U(rng));
    const Triangle t{a.cast<Real>(), b.cast<Real>(), c.cast<Real>()};
    const Real margin = Real(scale * 0.1 * U(rng));
    ContactManifold m;
    if (!triBox(t, h.cast<Real>(), margin, m)) continue;
    ++found;
    if (m.count > 1) ++multi;
    ASSERT_TRUE(triBoxWellFormed(t, h.cast<Real>(), margin, m)) << "case " << i;
  }
  EXPECT_GT(found, n / 3);
  std::printf("near-parallel edges: %d contacts of %d, %d with > 1 point\n", found, n, multi);
}

TEST(ContactsOnTheBoundary, RandomSliverTrianglesStayOnBothShapes) {
  // Slivers (height / length 1e-1 .. 1e-7, not exactly degenerate) near a box face, tilted by up
  // to 3°, some long enough to overhang an edge.
  std::mt19937_64 rng(6006);
  std::uniform_real_distribution<double> U(0, 1);
  int found = 0, multi = 0;
  const int n = 6000;
  for (int i = 0; i < n; ++i) {
    const V3d h(0.3 + 1.7 * U(rng), 0.3 + 1.7 * U(rng), 0.3 + 1.7 * U(rng));
    const int ax = int(U(rng) * 3) % 3;
    const double side = U(rng) < 0.5 ? -1 : 1;
    const V3d nrm = V3d::Unit(ax) * side;
    V3d onFace = V3d(h.x() * (2 * U(rng) - 1), h.y() * (2 * U(rng) - 1), h.z() * (2 * U(rng) - 1)) * 1.2;
    onFace[ax] = side * h[ax];
    const double scale = h.maxCoeff();
    const V3d tiltAxis = perpendicular(nrm);
    const Eigen::Matrix3d tilt =
        Eigen::AngleAxisd(3 * M_PI / 180 * U(rng), Eigen::AngleAxisd(6.3 * U(rng), nrm) * tiltAxis).toRotationMatrix();
    const V3d u = tilt * (Eigen::AngleAxisd(6.3 * U(rng), nrm) * perpendicular(nrm));
    const V3d w = (tilt * nrm).cross(u).normalized();
    const double len = scale * (0.2 + 2 * U(rng)), thin = std::pow(10.0, -1 - 6 * U(rng));
    const V3d a = onFace + nrm * scale * (-0.02 + 0.1 * U(rng)) - u * len * U(rng);
    const V3d b = a + u * len;
    const V3d c = a + u * len * (-0.2 + 1.4 * U(rng)) + (U(rng) < 0.5 ? w : V3d(tilt * nrm)) * len * thin;
    const Triangle t{a.cast<Real>(), b.cast<Real>(), c.cast<Real>()};
    const Real margin = Real(scale * 0.1 * U(rng));
    ContactManifold m;
    if (!triBox(t, h.cast<Real>(), margin, m)) continue;
    ++found;
    if (m.count > 1) ++multi;
    ASSERT_TRUE(triBoxWellFormed(t, h.cast<Real>(), margin, m)) << "case " << i << " thinness " << thin;
  }
  EXPECT_GT(found, n / 3);
  std::printf("slivers: %d contacts of %d, %d with > 1 point\n", found, n, multi);
}

// ---- quarter turns on the integer grid (found by `crux diff`) ---------------------------

/// The 24 rotations mapping coordinate axes to signed coordinate axes: the exact integer matrix
/// (a permutation with signs, determinant +1, built here by hand) and the unit quaternion a user
/// types for it, whose ½ and √½ components are rounded to Real.
struct GridTurn {
  Eigen::Matrix3i m;
  Quat q;
};

std::vector<GridTurn> gridTurns() {
  std::vector<GridTurn> out;
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (const auto& p : perms)
    for (int s = 0; s < 8; ++s) {
      Eigen::Matrix3i m = Eigen::Matrix3i::Zero();
      for (int i = 0; i < 3; ++i) m(i, p[i]) = ((s >> i) & 1) ? -1 : 1;
      if (m.cast<double>().determinant() != 1) continue;
      const Eigen::Matrix3d md = m.cast<double>();
      out.push_back({m, Quat(Eigen::Quaterniond(md).cast<Real>())});
    }
  return out;
}

Vec3 toVec3(const Eigen::Vector3i& v) { return v.cast<Real>(); }

TEST(ContactsOnTheBoundary, QuarterTurnFlatBoxesTouchingAtTheMarginHaveAContact) {
  // The `crux diff` case of docs/diff.md: two flat boxes (segments along z once placed), b under
  // a quarter turn about x typed as (√½, √½, 0, 0); a spans z in [-1, 1], b z in [2, 6]: the
  // separation is exactly 1 = margin, so the speculative contact is reported (exact backend: one
  // contact at separation 1). The quaternion's rounded √½ used to place b a few ulps farther.
  Mat3 axesA, axesB;
  axesA << 0, 1, 0, 1, 0, 0, 0, 0, 1;  // columns u, v, w
  axesB << 0, 0, -1, 0, 1, 0, 1, 0, 0;
  const Obb a{Vec3(0, 0, 0), Vec3(0, 0, 1), axesA};
  const Obb b{Vec3(0, 3, 0), Vec3(0, 2, 0), axesB};
  const Real h = std::sqrt(Real(0.5));
  const Transform tb = at(0, 0, 1, Quat(h, h, 0, 0));
  ContactManifold m;
  ASSERT_TRUE(contacts(a, Transform{}, b, tb, 1, m)) << str(m);
  ASSERT_GE(m.count, 1);
  for (int i = 0; i < m.count; ++i) {
    EXPECT_EQ(m.points[i].separation, 1) << str(m);
    EXPECT_EQ(m.points[i].pointA, Vec3(0, 0, 1)) << str(m);
    EXPECT_EQ(m.points[i].pointB, Vec3(0, 0, 2)) << str(m);
  }
  EXPECT_EQ(distance(a, Transform{}, b, tb).distance, 1);
  EXPECT_FALSE(contacts(a, Transform{}, b, tb, Real(0.5), m)) << str(m);
}

TEST(ContactsOnTheBoundary, GridBoxesUnderQuarterTurnsAtSeparationEqualToTheMargin) {
  // Integer boxes (half extents 0..2, flat ones included, signed-permutation frames) placed by
  // quarter-turn quaternions and integer translations, b put at an integer gap vector g from a
  // (per axis: apart by g_i, or the intervals overlapping / touching when g_i = 0) with |g| an
  // integer (0..3, or 5 = |(3, 4, 0)|). The hand-derived separation is |g|: contacts with
  // margin |g| must report a contact (no tolerance on the verdict: grid inputs), margin |g| − 1
  // none; the contact's separation and distance() are |g| within a few ulps. Both poses are
  // quarter turns, so the world boxes are axis-aligned.
  const std::vector<GridTurn> turns = gridTurns();
  ASSERT_EQ(turns.size(), 24u);
  std::mt19937_64 rng(20261122);
  auto pick = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
  const Eigen::Vector3i gaps[] = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}, {3, 4, 0}, {4, 0, 3}};
  const int n = 3000;
  // coordinates stay below 16: a few ulps of that scale
  const Real kRounding = 16 * std::numeric_limits<Real>::epsilon() * 16;
  int failures = 0, withContacts = 0;
  for (int k = 0; k < n && failures < 5; ++k) {
    const GridTurn& frameA = turns[std::size_t(pick(0, 23))];
    const GridTurn& frameB = turns[std::size_t(pick(0, 23))];
    const GridTurn& poseA = turns[std::size_t(pick(0, 23))];
    const GridTurn& poseB = turns[std::size_t(pick(0, 23))];
    const Eigen::Vector3i cA(pick(-2, 2), pick(-2, 2), pick(-2, 2)), cB(pick(-2, 2), pick(-2, 2), pick(-2, 2));
    const Eigen::Vector3i hA(pick(0, 2), pick(0, 2), pick(0, 2)), hB(pick(0, 2), pick(0, 2), pick(0, 2));
    const Eigen::Vector3i tA(pick(-3, 3), pick(-3, 3), pick(-3, 3));
    // world boxes: centre M·c + t, half |M·F|·h
    const Eigen::Matrix3i worldA = poseA.m * frameA.m, worldB = poseB.m * frameB.m;
    const Eigen::Vector3i centerA = poseA.m * cA + tA;
    const Eigen::Vector3i halfA = worldA.cwiseAbs() * hA, halfB = worldB.cwiseAbs() * hB;
    Eigen::Vector3i g = gaps[pick(0, 5)];
    std::shuffle(g.data(), g.data() + 3, rng);
    Eigen::Vector3i centerB;
    for (int i = 0; i < 3; ++i) {
      const int loA = centerA[i] - halfA[i], hiA = centerA[i] + halfA[i];
      int loB;
      if (g[i] > 0) loB = pick(0, 1) ? hiA + g[i] : loA - g[i] - 2 * halfB[i];
      else loB = pick(loA - 2 * halfB[i], hiA);  // touching or overlapping intervals
      centerB[i] = loB + halfB[i];
    }
    const Eigen::Vector3i tB = centerB - poseB.m * cB;
    const Obb a{toVec3(cA), toVec3(hA), frameA.m.cast<Real>()}, b{toVec3(cB), toVec3(hB), frameB.m.cast<Real>()};
    Transform ta, tb;
    ta.rotation = poseA.q;
    ta.translation = toVec3(tA);
    tb.rotation = poseB.q;
    tb.translation = toVec3(tB);
    const int dist = int(std::lround(std::sqrt(double(g.squaredNorm()))));
    ContactManifold m;
    const bool found = contacts(a, ta, b, tb, Real(dist), m);
    // the verdict is exact: a contact at margin |g|, none at |g| − 1
    ContactManifold none;
    const bool verdictOk = found && m.count >= 1 && !(dist > 0 && contacts(a, ta, b, tb, Real(dist - 1), none));
    // the numbers within rounding (GJK's barycentric combinations round in double builds)
    Real deepest = std::numeric_limits<Real>::infinity();
    for (int i = 0; i < m.count; ++i) deepest = std::min(deepest, m.points[i].separation);
    const Real d = distance(a, ta, b, tb).distance;
    // (gap 0: the boxes touch or overlap, so separation and distance are <= 0)
    const bool numbersOk = dist == 0 ? (!found || deepest <= kRounding) && d <= kRounding
                                     : (!found || std::abs(deepest - Real(dist)) <= kRounding) &&
                                           std::abs(d - Real(dist)) <= kRounding;
    withContacts += found ? 1 : 0;
    if (!verdictOk || !numbersOk) {
      ++failures;
      ADD_FAILURE() << (verdictOk ? "numbers" : "VERDICT") << " case " << k << ": a centre " << str(toVec3(cA))
                    << " half " << str(toVec3(hA)) << " axes\n"
                    << frameA.m << "\n pose rotation " << str(poseA.q.vec()) << " w " << poseA.q.w()
                    << " translation " << str(toVec3(tA)) << "\n b centre " << str(toVec3(cB)) << " half "
                    << str(toVec3(hB)) << " axes\n"
                    << frameB.m << "\n pose rotation " << str(poseB.q.vec()) << " w " << poseB.q.w()
                    << " translation " << str(toVec3(tB)) << "\n gap " << g.transpose() << " margin " << dist
                    << ": found " << found << ", " << str(m) << "\n distance " << std::setprecision(17) << double(d);
    }
  }
  EXPECT_EQ(failures, 0);
  EXPECT_EQ(withContacts, n);
}


// ---- degenerate shapes: no duplicate contact points ----------------------------------

/// Index pair (i, j) of two points of `m` that coincide on both bodies within `tol`, or (-1, -1).
std::pair<int, int> coincidentPoints(const ContactManifold& m, double tol) {
  for (int i = 0; i < m.count; ++i)
    for (int j = i + 1; j < m.count; ++j)
      if ((m.points[i].pointA - m.points[j].pointA).cast<double>().norm() <= tol &&
          (m.points[i].pointB - m.points[j].pointB).cast<double>().norm() <= tol)
        return {i, j};
  return {-1, -1};
}

TEST(ContactsDegenerate, FlatBoxesUnderQuarterTurnsGiveDistinctPointsAndTheExactDepth) {
  // Integer boxes with one, two or three zero half extents (a rectangle, a segment, a point) and
  // full boxes, in signed-permutation frames, placed by quarter-turn quaternions at integer
  // translations near each other: the world boxes are axis-aligned, so the hand-derived signed
  // distance is that of two intervals per axis (separated: the norm of the per-axis gaps;
  // overlapping: minus the smallest per-axis overlap). A flat box's face has coincident corners;
  // the manifold must still never hold two points at the same place on both bodies, and its
  // deepest point must have that signed distance (within rounding).
  const std::vector<GridTurn> turns = gridTurns();
  std::mt19937_64 rng(61122);
  auto pick = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
  const int n = 4000;
  const Real kRounding = 16 * std::numeric_limits<Real>::epsilon() * 16;  // coordinates below 16
  int failures = 0, withContacts = 0, multi = 0;
  for (int k = 0; k < n && failures < 5; ++k) {
    Eigen::Vector3i h[2], c[2], t[2];
    const GridTurn* frame[2];
    const GridTurn* pose[2];
    Eigen::Vector3i lo[2], hi[2];
    for (int s = 0; s < 2; ++s) {
      h[s] = Eigen::Vector3i(pick(0, 2), pick(0, 2), pick(0, 2));
      const int zeros = pick(0, 3);  // force that many zero half extents
      for (int z = 0; z < zeros; ++z) h[s][pick(0, 2)] = 0;
      c[s] = Eigen::Vector3i(pick(-1, 1), pick(-1, 1), pick(-1, 1));
      t[s] = Eigen::Vector3i(pick(-1, 1), pick(-1, 1), pick(-1, 1));  // near each other
      frame[s] = &turns[std::size_t(pick(0, 23))];
      pose[s] = &turns[std::size_t(pick(0, 23))];
      const Eigen::Vector3i centre = pose[s]->m * c[s] + t[s];
      const Eigen::Vector3i half = (pose[s]->m * frame[s]->m).cwiseAbs() * h[s];
      lo[s] = centre - half;
      hi[s] = centre + half;
    }
    double gap2 = 0, overlap = std::numeric_limits<double>::infinity();
    for (int i = 0; i < 3; ++i) {
      const int g = std::max({0, lo[1][i] - hi[0][i], lo[0][i] - hi[1][i]});
      gap2 += double(g) * g;
      overlap = std::min(overlap, double(std::min(hi[0][i] - lo[1][i], hi[1][i] - lo[0][i])));
    }
    const double expected = gap2 > 0 ? std::sqrt(gap2) : -overlap;
    const Obb a{toVec3(c[0]), toVec3(h[0]), frame[0]->m.cast<Real>()};
    const Obb b{toVec3(c[1]), toVec3(h[1]), frame[1]->m.cast<Real>()};
    Transform ta, tb;
    ta.rotation = pose[0]->q;
    ta.translation = toVec3(t[0]);
    tb.rotation = pose[1]->q;
    tb.translation = toVec3(t[1]);
    const Real margin = 1;
    ContactManifold m;
    const bool found = contacts(a, ta, b, tb, margin, m);
    Real deepest = std::numeric_limits<Real>::infinity();
    for (int i = 0; i < m.count; ++i) deepest = std::min(deepest, m.points[i].separation);
    const std::pair<int, int> dup = coincidentPoints(m, 4 * double(kRounding));
    const bool ok = found == (expected <= double(margin)) && dup.first < 0 &&
                    (!found || std::abs(double(deepest) - expected) <= double(kRounding));
    withContacts += found ? 1 : 0;
    multi += m.count > 1 ? 1 : 0;
    if (!ok) {
      ++failures;
      ADD_FAILURE() << "case " << k << ": a centre " << str(toVec3(c[0])) << " half " << str(toVec3(h[0]))
                    << " axes\n" << frame[0]->m << "\n pose rotation " << str(pose[0]->q.vec()) << " w "
                    << pose[0]->q.w() << " translation " << str(toVec3(t[0])) << "\n b centre "
                    << str(toVec3(c[1])) << " half " << str(toVec3(h[1])) << " axes\n" << frame[1]->m
                    << "\n pose rotation " << str(pose[1]->q.vec()) << " w " << pose[1]->q.w() << " translation "
                    << str(toVec3(t[1])) << "\n margin " << margin << ", expected signed distance "
                    << std::setprecision(17) << expected << ", coincident points " << dup.first << " "
                    << dup.second << ", found " << found << ", " << str(m);
    }
  }
  EXPECT_EQ(failures, 0);
  EXPECT_GT(withContacts, n / 4);
  EXPECT_GT(multi, n / 20);
  std::printf("flat boxes: %d contacts of %d, %d with > 1 point\n", withContacts, n, multi);
}

TEST(ContactsDegenerate, RandomDegenerateShapesGiveDistinctPoints) {
  // Random poses of degenerate convex shapes — boxes with zero half extents (1 or 2 axes), zero-
  // radius capsules (segments), triangles, hulls of coplanar and of collinear points, a point
  // hull — against each other and against full boxes, half of the pairs under one rotation
  // (parallel features: clipping). No manifold may hold two points that coincide on both
  // bodies; every point lies on both shapes, and the deepest agrees with GJK/EPA up to the
  // feature angle (as in ContactsProperty.RandomPairs).
  std::mt19937_64 rng(6061);
  std::uniform_real_distribution<double> u(-1, 1);
  std::normal_distribution<double> g;
  auto v = [&](double s) { return Vec3(Real(u(rng) * s), Real(u(rng) * s), Real(u(rng) * s)); };
  auto rot = [&] { return Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().cast<Real>(); };
  std::vector<std::unique_ptr<ConvexHull>> hulls;
  auto hullOf = [&](std::vector<Vec3> pts) -> ConvexShape {
    hulls.push_back(std::make_unique<ConvexHull>(ConvexHull::build(pts)));
    return *hulls.back();
  };
  auto make = [&](int kind) -> ConvexShape {
    switch (kind) {
      case 0: {  // flat box: one zero half extent
        Vec3 h = v(1).cwiseAbs() + Vec3::Constant(Real(0.1));
        h[std::uniform_int_distribution<int>(0, 2)(rng)] = 0;
        return Obb{v(0.2), h, Mat3::Identity()};
      }
      case 1: {  // segment box: two zero half extents
        Vec3 h = Vec3::Zero();
        h[std::uniform_int_distribution<int>(0, 2)(rng)] = Real(0.2 + std::abs(u(rng)));
        return Obb{v(0.2), h, Mat3::Identity()};
      }
      case 2: return Capsule{v(1), v(1), 0};
      case 3: return Triangle{v(1), v(1), v(1)};
      case 4: {  // coplanar points (z = 0 before the pose): a polygon hull
        std::vector<Vec3> pts;
        for (int q = 0; q < 8; ++q) pts.emplace_back(Real(u(rng)), Real(u(rng)), 0);
        return hullOf(pts);
      }
      case 5: {  // collinear points: a segment hull
        const Vec3 d = v(1);
        std::vector<Vec3> pts;
        for (int q = 0; q < 5; ++q) pts.push_back(d * Real(u(rng)));
        return hullOf(pts);
      }
      case 6: return hullOf({v(0.5)});  // a point
      default: return Obb{v(0.2), v(1).cwiseAbs() + Vec3::Constant(Real(0.1)), Mat3::Identity()};
    }
  };
  const int n = 6000;
  int withPoints = 0, multi = 0, failures = 0;
  for (int i = 0; i < n && failures < 5; ++i) {
    const int ka = int(std::abs(u(rng)) * 7), kb = int(std::abs(u(rng)) * 8);
    const ConvexShape a = make(ka), b = make(kb);
    Transform ta, tb;
    ta.rotation = rot();
    tb.rotation = i % 2 == 0 ? ta.rotation : rot();
    ta.translation = v(0.5);
    tb.translation = v(0.5);
    const Real margin = Real(0.05);
    ContactManifold m;
    if (!contacts(a, ta, b, tb, margin, m)) continue;
    ++withPoints;
    multi += m.count > 1 ? 1 : 0;
    const DistanceResult d = distance(a, ta, b, tb);
    const double S = double(a.size() + b.size()) + (ta.translation - tb.translation).cast<double>().norm();
    const double tol = 64 * kEps * S + 1e-9 * S;
    const std::pair<int, int> dup = coincidentPoints(m, tol);
    double minSep = INFINITY, off = 0;
    for (int k = 0; k < m.count; ++k) {
      minSep = std::min(minSep, double(m.points[k].separation));
      if (a.kind != ConvexKind::Triangle) off = std::max(off, distanceToShape(a, ta, m.points[k].pointA));
      off = std::max(off, distanceToShape(b, tb, m.points[k].pointB));
    }
    if (dup.first >= 0 || off > tol || !(std::abs(minSep - double(d.distance)) <= 0.035 * S)) {
      ++failures;
      ADD_FAILURE() << "pair " << i << " kinds " << ka << " " << kb << " (shape kinds " << int(a.kind) << " "
                    << int(b.kind) << "): coincident points " << dup.first << " " << dup.second
                    << ", off the shapes by " << std::setprecision(17) << off << ", distance " << double(d.distance)
                    << "\n a translation " << str(ta.translation) << " rotation " << str(ta.rotation.vec()) << " w "
                    << ta.rotation.w() << "\n b translation " << str(tb.translation) << " rotation "
                    << str(tb.rotation.vec()) << " w " << tb.rotation.w() << "\n" << str(m);
    }
  }
  EXPECT_EQ(failures, 0);
  EXPECT_GT(withPoints, n / 10);
  EXPECT_GT(multi, n / 50);
  std::printf("degenerate shapes: %d contacts of %d, %d with > 1 point\n", withPoints, n, multi);
}

/// The grid touching tests' tally: contacts() must report a pair touching at margin m (every
/// point within it) and nothing at m − 0.5.
struct TouchingTally {
  int built = 0, missed = 0, falseHits = 0;
  std::string first;
  void check(const ConvexShape& A, const ConvexShape& B, Real m, const std::string& what) {
    ContactManifold out;
    if (contacts(A, Transform::identity(), B, Transform::identity(), m, out)) {
      for (int j = 0; j < out.count; ++j) EXPECT_LE(out.points[j].separation, m) << what;
    } else if (++missed == 1) {
      first = what;
    }
    if (m >= 1) falseHits += contacts(A, Transform::identity(), B, Transform::identity(), m - Real(0.5), out);
  }
  void expectEveryPairReported(int cases) const {
    std::printf("%d touching pairs built\n", built);
    EXPECT_GT(built, cases / 2);
    EXPECT_EQ(missed, 0) << first;
    EXPECT_EQ(falseHits, 0);
  }
};

// Touching on the integer grid is reported by the convex pair contacts too (the exactness
// on grids): an integer point X at an integer distance k from a segment s0 + t·d whose foot on
// the line is at a rational, unrepresentable t inside it (searched: |w|²|d|² - (w·d)² = k²|d|²);
// shapes built on X (a triangle or a capsule's segment reaching into the half-space away from the
// segment, or a sphere centred at X) against a capsule on the segment (or the segment as a
// degenerate triangle), radii and margin summing to k. The GJK distance is an ulp or so off
// either way; before the exact margin decision in contacts() some of these were missed
// (distance 4.4e-16 or 1 + 2e-16 with margin 0 or 1).
TEST(ContactsOnTheBoundary, TouchingSimplexCoresOnTheIntegerGridHaveAContact) {
  test::GridDraws draws(0x5eed9u);
  const int cases = 2000;
  TouchingTally tally;
  for (int i = 0; i < cases; ++i) {
    test::PointAndSegment g;
    if (!test::drawPointAndSegment(draws, g)) continue;
    const Vec3 &X = g.X, &s0 = g.s0, &d = g.d, &n = g.n;
    const long k = g.k;
    ++tally.built;
    const Vec3 v[2] = {test::pointBehind(draws, X, n), test::pointBehind(draws, X, n)};
    const Real margin = Real(draws.integer(0, 1)), rest = Real(k) - margin;  // radii sum to rest
    const Real rA = Real(draws.integer(0, int(rest))), rB = rest - rA;
    ConvexShape A, B;
    switch (i % 4) {
      case 0: A = ConvexShape(Triangle{X, v[0], v[1]}); B = ConvexShape(Capsule{s0, Vec3(s0 + d), rest}); break;
      case 1: A = ConvexShape(Capsule{X, v[0], rA}); B = ConvexShape(Capsule{s0, Vec3(s0 + d), rB}); break;
      case 2: A = ConvexShape(Sphere{X, rA}); B = ConvexShape(Capsule{s0, Vec3(s0 + d), rB}); break;
      default: A = ConvexShape(Triangle{X, v[0], v[1]}); B = ConvexShape(Triangle{s0, Vec3(s0 + d), Vec3(s0 + d)}); break;
    }
    const Real m = i % 4 == 3 ? Real(k) : margin;  // two triangles: the whole distance is margin
    std::ostringstream what;
    what << "case " << i % 4 << ": X " << X.transpose() << " segment " << s0.transpose() << " + t·" << d.transpose()
         << " k " << k << " rA " << rA << " rB " << rB << " margin " << m;
    tally.check(A, B, m, what.str());
  }
  tally.expectEveryPairReported(cases);
}

// Hulls of 1-3 points (degenerate ConvexHulls: a point, a segment, a triangle) are cores of 1-3
// points too: contacts() decides their margin exactly like the spheres', capsules' and
// triangles' (earlier they kept GJK's decision and a triangle hull 5 from a capsule of
// radius 5 at margin 0 was missed).
TEST(ContactsOnTheBoundary, TouchingDegenerateHullsOnTheIntegerGridHaveAContact) {
  test::GridDraws draws(0x4a11u);
  const int cases = test::scaledCases(3000, 600);
  TouchingTally tally;
  for (int i = 0; i < cases; ++i) {
    test::PointAndSegment g;
    if (!test::drawPointAndSegment(draws, g)) continue;
    const Vec3 &X = g.X, &s0 = g.s0, &d = g.d, &n = g.n;
    const long k = g.k;
    const Vec3 v[2] = {test::pointBehind(draws, X, n), test::pointBehind(draws, X, n)};
    const Vec3 s1 = s0 + d;
    // (a ConvexShape views its hull: the hulls live here)
    const ConvexHull corner = ConvexHull::build({X}), segment = ConvexHull::build({s0, s1}),
                     triangle = ConvexHull::build({X, v[0], v[1]});
    ConvexShape A, B;
    Real m = Real(k);  // hulls have no radius: the whole distance is margin
    switch (i % 3) {
      case 0: A = ConvexShape(Triangle{X, v[0], v[1]}); B = ConvexShape(segment); break;
      case 1: A = ConvexShape(corner); B = ConvexShape(segment); break;
      default: {
        const Real margin = Real(draws.integer(0, 1));
        m = margin;
        A = ConvexShape(triangle);
        B = ConvexShape(Capsule{s0, s1, Real(k) - margin});
        break;
      }
    }
    ++tally.built;
    std::ostringstream what;
    what << "case " << i % 3 << ": X " << X.transpose() << " | " << v[0].transpose() << " | " << v[1].transpose()
         << ", segment " << s0.transpose() << " -> " << s1.transpose() << " k " << k << " margin " << m;
    tally.check(A, B, m, what.str());
  }
  tally.expectEveryPairReported(cases);
}

// Boxes and hulls of more than 3 vertices with a corner X at an integer distance k from a segment
// (its foot at an unrepresentable parameter), everything else beyond the plane through X normal
// to X → foot, against a capsule on that segment (radius k − margin) and a segment triangle:
// contacts() decides their margin exactly too (the polytope's boundary triangles and whether it
// holds the core; 172 box and 105 tetrahedron pairs of 40,000 were missed by GJK's decision).
TEST(ContactsOnTheBoundary, TouchingBoxesAndHullsOnTheIntegerGridHaveAContact) {
  test::GridDraws draws(0xb0c5u);
  const int cases = test::scaledCases(4000, 600);
  int built = 0, missed = 0, falseHits = 0;
  std::string first;
  const Transform I = Transform::identity();
  for (int i = 0; i < cases; ++i) {
    test::PointAndSegment g;
    if (!test::drawPointAndSegment(draws, g)) continue;
    const Vec3 &X = g.X, &s0 = g.s0, &d = g.d, &n = g.n;
    const long k = g.k;
    const Vec3 s1 = s0 + d;
    const Vec3 half(Real(draws.integer(1, 3)), Real(draws.integer(1, 3)), Real(draws.integer(1, 3)));
    Vec3 sign;
    for (int a = 0; a < 3; ++a) sign[a] = n[a] > 0 ? -1 : n[a] < 0 ? 1 : (draws.integer(0, 1) ? 1 : -1);
    const Obb box{X + sign.cwiseProduct(half), half, Mat3::Identity()};
    std::vector<Vec3> pts{X};
    for (int j = 0; j < 3 + i % 3; ++j) pts.push_back(test::pointBehind(draws, X, n));
    const ConvexHull hull = ConvexHull::build(pts);
    if (hull.vertices().size() <= 3) continue;
    ++built;
    const Real margin = Real(draws.integer(0, 1)), radius = Real(k) - margin;
    for (int which = 0; which < 4; ++which) {
      const ConvexShape P = which % 2 == 0 ? ConvexShape(box) : ConvexShape(hull);
      const bool capsule = which < 2;
      const ConvexShape Q = capsule ? ConvexShape(Capsule{s0, s1, radius}) : ConvexShape(Triangle{s0, s1, s1});
      const Real m = capsule ? margin : Real(k);
      ContactManifold out;
      // both orders: the polytope as A and as B
      const bool ab = contacts(P, I, Q, I, m, out), ba = contacts(Q, I, P, I, m, out);
      if ((!ab || !ba) && ++missed == 1) {
        std::ostringstream what;
        what << (which % 2 == 0 ? "box" : "hull") << " with corner " << X.transpose() << " vs "
             << (capsule ? "capsule " : "segment triangle ") << s0.transpose() << " -> " << s1.transpose() << " k " << k
             << " margin " << m << (ab ? "" : " (missed as A)") << (ba ? "" : " (missed as B)");
        first = what.str();
      }
      if (m >= 1) falseHits += contacts(P, I, Q, I, m - Real(0.5), out);
    }
  }
  std::printf("%d touching corners built (4 pairs each)\n", built);
  EXPECT_GT(built, cases / 2);
  EXPECT_EQ(missed, 0) << first;
  EXPECT_EQ(falseHits, 0);
}

// Two polytopes on the integer grid where the closest features are not corners. Two hulls
// (or an axis-aligned box and a hull) separated by a slab of integer-normed normal w (|w| = 3, 7,
// 9, 11 or 5: Pythagorean quadruples and triples), touching its two planes at skew edges (edge–
// edge: their projections along w cross at a rational, unrepresentable point), at a vertex and the
// middle of a face, or at a face and a vertex; the distance is m·|w| exactly, at offsets up to
// 2^21 from the origin (integer coordinates, exact in float). Every pair is reported at margin
// m·|w|, in both operand orders; none at m·|w| − 0.5.
TEST(ContactsOnTheBoundary, TouchingPolytopesOnTheIntegerGridHaveAContact) {
  test::GridDraws draws(0x9017u);
  using L3 = Eigen::Matrix<long, 3, 1>;
  const L3 normals[] = {L3(1, 2, 2), L3(2, 3, 6), L3(1, 4, 8), L3(2, 6, 9), L3(4, 4, 7),
                        L3(2, 10, 11), L3(6, 6, 7), L3(3, 4, 12), L3(0, 3, 4), L3(0, 0, 1)};
  const long norms[] = {3, 7, 9, 11, 9, 15, 11, 13, 5, 1};
  auto point = [](const L3& v) { return Vec3(Real(v.x()), Real(v.y()), Real(v.z())); };
  auto draw = [&](int r) { return L3(draws.integer(-r, r), draws.integer(-r, r), draws.integer(-r, r)); };
  const int cases = test::scaledCases(6000, 900);
  TouchingTally tally;
  for (int i = 0; i < cases; ++i) {
    const int which = draws.integer(0, 9), kind = i % 4;  // edge-edge, vertex-face, face-vertex, box edge-edge
    L3 w = normals[which];
    const long wn = norms[which];
    ASSERT_EQ(w.squaredNorm(), wn * wn);
    for (int a = 0; a < 3; ++a)
      if (draws.integer(0, 1)) w[a] = -w[a];
    if (kind != 3) std::swap(w[draws.integer(0, 2)], w[draws.integer(0, 2)]);
    else if (w.x() != 0) continue;  // the box's touching edge runs along x: w ⟂ x
    // u, v: integer directions perpendicular to w (a box's edge: x), not parallel to each other
    const L3 u = kind == 3 ? L3(draws.integer(1, 3), 0, 0) : L3(w.cross(draw(3))), v = w.cross(draw(3));
    if (u.squaredNorm() == 0 || v.squaredNorm() == 0 || u.cross(v).squaredNorm() == 0) continue;
    const int big = 1 << draws.integer(0, 21);
    const L3 X(draws.integer(-big, big), draws.integer(-big, big), draws.integer(-big, big));
    const long m = draws.integer(0, 2);
    const L3 Y = X + m * w;  // A touches the plane (p - X)·w = 0 from below, B the one through Y from above
    std::vector<Vec3> a, b;
    switch (kind) {
      case 1: a = {point(X)}; b = {point(Y - u), point(Y + u), point(Y - v), point(Y + v)}; break;
      case 2: a = {point(X - u), point(X + u), point(X - v), point(X + v)}; b = {point(Y)}; break;
      default: a = {point(X - u), point(X + u)}; b = {point(Y - v), point(Y + v)}; break;
    }
    auto beyond = [&] {  // r − k·w, strictly below the plane through 0 normal to w
      L3 r;
      do r = draw(4) - draws.integer(1, 3) * w;
      while (r.dot(w) >= 0);
      return r;
    };
    for (int j = 0; j < 3 + i % 3; ++j) {  // the rest strictly beyond the planes
      a.push_back(point(X + beyond()));
      b.push_back(point(Y - beyond()));
    }
    // the box: its edge X ± u (along x) on top, the box below it in y and z, away from w
    const Vec3 half(Real(u.x()), Real(draws.integer(1, 3)), Real(draws.integer(1, 3)));
    const Vec3 centre = point(X) - Vec3(0, w.y() > 0 ? half.y() : -half.y(), w.z() > 0 ? half.z() : -half.z());
    const ConvexHull ha = ConvexHull::build(a), hb = ConvexHull::build(b);
    if (ha.vertices().size() < 4 || hb.vertices().size() < 4) continue;
    const ConvexShape A = kind == 3 ? ConvexShape(Obb{centre, half, Mat3::Identity()}) : ConvexShape(ha), B(hb);
    ++tally.built;
    std::ostringstream what;
    what << "kind " << kind << ": w " << w.transpose() << " u " << u.transpose() << " v " << v.transpose() << " X "
         << X.transpose() << " m " << m;
    tally.check(A, B, Real(m * wn), what.str());
    tally.check(B, A, Real(m * wn), what.str() + " (swapped)");
  }
  tally.expectEveryPairReported(cases);
}

// Two polytopes (a hull of more than 3 vertices and a box) decide the margin exactly too, on
// their boundary triangles (contacts(), polytopesWithin): the two `crux diff` cases
// (seed 15042, double build, tests/regressions/native.crux-wrong.contacts.15042-*): integer-grid
// pairs exactly 1 apart along (0, −0.8, −0.6) and (6, 3, 2)/7, where GJK's double distance came out
// a hair above 1 and the margin-1 contact was missed. Reported at margin 1 with separation 1 (the
// margin, when the computed distance lies beyond it), in both operand orders; none at a margin
// just below 1.
TEST(ContactsOnTheBoundary, HullAndBoxExactlyAtTheMarginOnTheGridHaveAContact) {
  struct Case {
    std::vector<Vec3> hull;
    Obb box;
  };
  Mat3 axes1, axes2;  // columns: the box's axes
  axes1 << -1, 0, 0, 0, 0, 1, 0, -1, 0;
  axes2 << 1, 0, 0, 0, 0, -1, 0, -1, 0;
  const Case cases[] = {
      {{Vec3(-1, -1, 2), Vec3(0, 0, 0), Vec3(0, -1, 1), Vec3(1, 2, -2)}, Obb{Vec3(-2, 2, 3), Vec3(2, 2, 1), axes1}},
      {{Vec3(-2, -2, 1), Vec3(-2, 0, -2), Vec3(-4, 0, 0), Vec3(0, -4, -2), Vec3(-3, 0, 0)},
       Obb{Vec3(1, 0, 1), Vec3(2, 1, 1), axes2}},
  };
  const Transform I = Transform::identity();
  for (const Case& c : cases) {
    const ConvexHull h = ConvexHull::build(c.hull);
    ASSERT_GT(h.vertices().size(), 3u);
    const ConvexShape A(h), B(c.box);
    for (int order = 0; order < 2; ++order) {
      const ConvexShape& P = order ? B : A;
      const ConvexShape& Q = order ? A : B;
      ContactManifold m;
      ASSERT_TRUE(contacts(P, I, Q, I, 1, m)) << "order " << order << " hull " << c.hull[0].transpose();
      ASSERT_GE(m.count, 1);
      for (int i = 0; i < m.count; ++i) EXPECT_NEAR(m.points[i].separation, 1, 8 * kEps) << str(m);
      EXPECT_FALSE(contacts(P, I, Q, I, 1 - Real(1) / 1024, m)) << str(m);
      EXPECT_NEAR(distance(P, I, Q, I).distance, 1, 8 * kEps);
    }
  }
}

// A manifold is never shallower than the closest (deepest) pair beyond the face snapping's
// allowance: the overlap along any direction is at least the minimum, so a reference face within
// 2° of the contact normal measures its deepest support point at least as deep, unless the clip
// cuts that point away (it lies beyond the face's side planes); contacts() then reports the
// single closest pair (contact_detail::keepsClosest; crux diff found a hull and a capsule 6.6e-4
// relative shallow, tests/regressions/native.crux-wrong.contacts.9301-8420). Random triangles
// and hulls against capsules and boxes under random rotations: 210 of ~68,000 manifolds broke
// this before.
TEST(ContactsOnTheBoundary, ManifoldIsNeverShallowerThanTheClosestPairBeyondTheSnappingAllowance) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> U(-1, 1);
  auto v = [&] { return Vec3(Real(U(rng)), Real(U(rng)), Real(U(rng))); };
  const int cases = test::scaledCases(60000, 6000);
  int manifolds = 0, shallow = 0;
  std::string first;
  for (int i = 0; i < cases; ++i) {
    std::vector<Vec3> pts;
    for (int k = 0; k < 4 + i % 5; ++k) pts.push_back(v());
    const ConvexHull hull = ConvexHull::build(pts);
    const ConvexShape A = i % 3 == 0 ? ConvexShape(Triangle{pts[0], pts[1], pts[2]}) : ConvexShape(hull);
    const ConvexShape B = i % 2 ? ConvexShape(Capsule{v() * Real(1.5), v() * Real(1.5), Real(0.1 + 0.4 * (U(rng) + 1))})
                                : ConvexShape(Obb{v(), Vec3(Real(0.3), Real(0.5), Real(0.2)), Mat3::Identity()});
    Transform t;
    t.rotation = Quat(Real(U(rng)), Real(U(rng)), Real(U(rng)), Real(U(rng))).normalized();
    t.translation = v();
    ContactManifold m;
    if (!contacts(A, Transform::identity(), B, t, Real(0.05), m)) continue;
    ++manifolds;
    const double sep = distance(A, Transform::identity(), B, t).distance;
    double least = HUGE_VAL;
    for (int k = 0; k < m.count; ++k) least = std::min(least, double(m.points[k].separation));
    // (the rounding: float inputs and outputs, 1e-5 of the unit-sized shapes)
    if (least > sep + (1 - double(kContactFaceAngleCos)) * std::abs(sep) + 1e-5 * (1 + std::abs(sep)) && ++shallow == 1) {
      std::ostringstream what;
      what << "case " << i << ": deepest separation " << least << " vs the closest pair's " << sep << ", " << m.count
           << " points";
      first = what.str();
    }
  }
  std::printf("%d manifolds\n", manifolds);
  EXPECT_GT(manifolds, cases / 5);
  EXPECT_EQ(shallow, 0) << first;
}


// Non-queryable shapes or poses (precondition.hpp): no contact, never UB (an infinite
// translation used to report one).
TEST(ContactPreconditions, NonQueryableInputsGetNoContact) {
  if (CRUX_CHECK_PRECONDITIONS) GTEST_SKIP() << "this build aborts instead (precondition.hpp)";
  const ConvexShape box = Obb{Vec3::Zero(), Vec3::Constant(Real(0.5)), Mat3::Identity()};
  ContactManifold m;
  for (const Transform& pose : test_support::badPoses()) {
    EXPECT_FALSE(contacts(box, Transform{}, box, pose, Real(0.01), m));
    EXPECT_EQ(m.count, 0);
  }
  for (const ConvexShape& shape : test_support::badShapes()) EXPECT_FALSE(contacts(shape, Transform{}, box, Transform{}, Real(0.01), m));
  EXPECT_TRUE(contacts(box, Transform{}, box, Transform{}, Real(0.01), m));
}

}  // namespace
}  // namespace crux
