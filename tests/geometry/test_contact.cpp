// Tests of src/geometry/contact.cpp: manifolds with known answers (stacked boxes, a rotated box,
// capsule and sphere resting on a box, parallel capsules, a triangle on a box, hull on hull,
// speculative margin) and seeded properties over random pairs (every point on both shapes,
// pointA - pointB = separation·normal, separation <= margin, at most 4 points).

#include <crux/error.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <crux/geometry/contact.hpp>
#include <limits>
#include <memory>
#include <random>
#include <sstream>

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
