// Tests of src/geometry/cast.cpp: linear and rigid casts against closed-form times of impact
// (sphere vs plane and triangle, axis-aligned boxes on an integer grid, a rotating segment), the
// semantics (starting in contact, zero motion, grazing, degenerate triangles, bad input), and
// seeded random property tests over every convex kind: at the reported t the shapes are within
// the contact tolerance, before it they are apart, a miss stays apart over the whole motion, and
// casting B by the reversed motion against A gives the same t.

#include <gtest/gtest.h>

#include <crux/geometry/cast.hpp>
#include <crux/precondition.hpp>

#include "support/bad_inputs.hpp"

#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace crux {
namespace {

/// The pair's length scale as cast.hpp defines it (sizes, origin offset, motion length).
double castScale(const ConvexShape& a, const Transform& ta, const ConvexShape& b, const Transform& tb,
                 double motionLength) {
  return double(a.size()) + double(b.size()) + (ta.translation - tb.translation).cast<double>().norm() +
         motionLength;
}

double contactTolerance(double scale) { return kCastRelativeTolerance * scale; }

/// A numerically zero distance: GJK's own tolerance, a few times over, plus Real's rounding of
/// the reported distance and of poses placed in Real.
double zeroSlack(double scale) {
  return 16 * kGjkScaleTolerance * scale + 16 * double(std::numeric_limits<Real>::epsilon()) * scale;
}

Transform translated(const Transform& t, const Vec3& d) {
  Transform r = t;
  r.translation += d;
  return r;
}

double gap(const ConvexShape& a, const Transform& ta, const ConvexShape& b, const Transform& tb) {
  return double(distance(a, ta, b, tb).distance);
}

// ---- closed forms ------------------------------------------------------------------------------

TEST(CastClosedForm, SphereAgainstALargeTriangleHitsAtThePlaneTime) {
  // Triangle in z = 0 covering the impact point; sphere radius r at height h moving down by m.
  const Triangle tri{Vec3(-10, -10, 0), Vec3(10, -10, 0), Vec3(0, 10, 0)};
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  for (int i = 0; i < 200; ++i) {
    const Real r = Real(0.1 + u(rng));
    const Real h = Real(r + 0.5 + 3 * u(rng));
    const Vec3 c(Real(2 * u(rng) - 1), Real(2 * u(rng) - 1), h);
    const Vec3 m(Real(u(rng) - 0.5), Real(u(rng) - 0.5), -Real(h + 2 * u(rng)));
    const double tRef = (double(h) - double(r)) / -double(m.z());
    const CastResult res = cast(Sphere{Vec3::Zero(), r}, Transform{Quat::Identity(), c}, m, tri, Transform{});
    const double scale = castScale(Sphere{Vec3::Zero(), r}, Transform{Quat::Identity(), c}, tri, Transform{}, m.norm());
    ASSERT_TRUE(res.hit) << i;
    EXPECT_LE(double(res.t), tRef + 4 * double(std::numeric_limits<Real>::epsilon()));
    EXPECT_GE(double(res.t), tRef - contactTolerance(scale) / -double(m.z()) - 2 * double(std::numeric_limits<Real>::epsilon())) << i;
    EXPECT_NEAR(double(res.normal.z()), 1, 1e-5);
    EXPECT_NEAR(double(res.pointB.z()), 0, 1e-5);
    EXPECT_FALSE(res.startsOverlapping);
  }
}

TEST(CastClosedForm, SphereAgainstAPlaneOfABoxFaceHitsAtThePlaneTime) {
  // A wide flat box's top face is the plane z = 0 where the sphere lands.
  const Obb floor{Vec3(0, 0, -1), Vec3(100, 100, 1), Mat3::Identity()};
  const Sphere s{Vec3::Zero(), Real(0.5)};
  const Transform start{Quat::Identity(), Vec3(1, 2, 3)};
  const Vec3 m(2, -1, -5);
  const CastResult res = cast(s, start, m, floor, Transform{});
  ASSERT_TRUE(res.hit);
  EXPECT_NEAR(double(res.t), 2.5 / 5, 1e-6);
  EXPECT_NEAR(double(res.pointA.z()), 0, 1e-5);
  EXPECT_NEAR(double(res.pointA.x()), 1 + 2 * 0.5, 1e-5);
}

TEST(CastClosedForm, AxisAlignedBoxesOnAnIntegerGridMatchTheSlabIntervals) {
  // Per axis the boxes overlap while |cA + t·m − cB| <= hA + hB: t_first = max of the entry
  // times, a hit when it is <= the min of the exit times and within [0, 1].
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> coord(-4, 4), half(0, 3), mot(-10, 10);
  int hits = 0;
  const int n = 3000;
  for (int i = 0; i < n; ++i) {
    Vec3 ca, cb, ha, hb, m;
    for (int k = 0; k < 3; ++k) {
      ca[k] = Real(coord(rng));
      cb[k] = Real(coord(rng));
      ha[k] = Real(half(rng));
      hb[k] = Real(half(rng));
      m[k] = Real(mot(rng));
    }
    double enter = 0, exit = 1;
    for (int k = 0; k < 3; ++k) {
      const double reach = double(ha[k]) + double(hb[k]), off = double(ca[k]) - double(cb[k]);
      if (m[k] == 0) {
        if (std::abs(off) > reach) enter = 2;  // never overlaps on this axis
        continue;
      }
      const double t0 = (-reach - off) / double(m[k]), t1 = (reach - off) / double(m[k]);
      enter = std::max(enter, std::min(t0, t1));
      exit = std::min(exit, std::max(t0, t1));
    }
    const bool hitRef = enter <= exit;
    const Obb a{Vec3::Zero(), ha, Mat3::Identity()}, b{cb, hb, Mat3::Identity()};
    const Transform ta{Quat::Identity(), ca};
    const CastResult res = cast(a, ta, m, b, Transform{});
    ASSERT_EQ(res.hit, hitRef) << "case " << i << " ca " << ca.transpose() << " m " << m.transpose() << " cb "
                               << cb.transpose() << " ha " << ha.transpose() << " hb " << hb.transpose();
    if (!hitRef) continue;
    ++hits;
    const double scale = castScale(a, ta, b, Transform{}, m.norm());
    // never late; early by at most δ over the approach speed (>= 1 on the grid: the contact
    // normal of an axis-aligned pair is an axis, |m_k| >= 1 on it)
    EXPECT_LE(double(res.t), enter + 1e-12) << i;
    EXPECT_GE(double(res.t), enter - contactTolerance(scale) - 4 * double(std::numeric_limits<Real>::epsilon()))
        << i;
    EXPECT_EQ(res.startsOverlapping, enter == 0) << i;
  }
  EXPECT_GT(hits, n / 5);
  EXPECT_LT(hits, 4 * n / 5);
}

TEST(CastClosedForm, RotatingSegmentSweepsIntoAPointAtTheSlerpAngle) {
  // A segment from the origin along x (length 2) turns by 90° about z; a ball of radius r at
  // (1, 1, 0) is first touched when the segment is within r of its centre: angle 45° − asin(r/√2).
  for (const double r : {0.0, 0.05, 0.3}) {
    const Capsule seg{Vec3::Zero(), Vec3(2, 0, 0), 0};
    const Sphere ball{Vec3(1, 1, 0), Real(r)};
    RigidMotion motion;
    motion.end.rotation = Quat(Eigen::AngleAxis<Real>(Real(M_PI / 2), Vec3::UnitZ()));
    const CastResult res = cast(seg, motion, ball, Transform{});
    ASSERT_TRUE(res.hit) << r;
    const double tRef = (M_PI / 4 - std::asin(r / std::sqrt(2.0))) / (M_PI / 2);
    EXPECT_LE(double(res.t), tRef + 1e-6) << r;
    EXPECT_GE(double(res.t), tRef - 1e-4) << r;
    EXPECT_LE(gap(seg, poseAt(motion, res.t), ball, Transform{}), 1e-4);
  }
}

TEST(CastClosedForm, ShapeTurningPastBWithoutApproachingItMissesInFewSteps) {
  // A unit ball 1000 from its origin turns 2 rad about z around a ball of radius 998: always 1
  // apart. The bound θ·|u × n|·r_max (2,002 per unit time against a gap of 1) would take ~2,000
  // steps, beyond the cap; the support bound sees the ball move across n.
  const Sphere orbiting{Vec3(1000, 0, 0), 1};
  const Sphere centre{Vec3::Zero(), 998};
  RigidMotion motion;
  motion.end.rotation = Quat(Eigen::AngleAxis<Real>(2, Vec3::UnitZ()));
  const CastResult res = cast(orbiting, motion, centre, Transform{});
  EXPECT_FALSE(res.hit) << "t " << res.t << ", iterations " << res.iterations << ", capped " << res.capped;
  EXPECT_LT(res.iterations, 200);
  // Against a ball of radius 999 it touches from the start.
  const CastResult touching = cast(orbiting, motion, Sphere{Vec3::Zero(), 999}, Transform{});
  EXPECT_TRUE(touching.hit);
  EXPECT_EQ(touching.t, 0);
  EXPECT_FALSE(touching.capped);
}

// ---- semantics ----------------------------------------------------------------------------------

TEST(CastSemantics, StartingInContactHitsAtZeroWithTheDepth) {
  const Obb box{Vec3::Zero(), Vec3(1, 1, 1), Mat3::Identity()};
  // touching face to face
  CastResult res = cast(box, Transform{Quat::Identity(), Vec3(2, 0, 0)}, Vec3(5, 0, 0), box, Transform{});
  EXPECT_TRUE(res.hit);
  EXPECT_EQ(res.t, 0);
  EXPECT_TRUE(res.startsOverlapping);
  EXPECT_EQ(res.depth, 0);
  // overlapping by 0.5 along x, moving away: still t = 0 with the depth
  res = cast(box, Transform{Quat::Identity(), Vec3(Real(1.5), 0, 0)}, Vec3(5, 0, 0), box, Transform{});
  EXPECT_TRUE(res.hit);
  EXPECT_EQ(res.t, 0);
  EXPECT_TRUE(res.startsOverlapping);
  EXPECT_NEAR(double(res.depth), 0.5, 1e-5);
  EXPECT_NEAR(double(res.normal.x()), 1, 1e-5);
}

TEST(CastSemantics, ZeroMotionIsTheOverlapTest) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-2, 2);
  for (int i = 0; i < 300; ++i) {
    const Capsule c{Vec3(u(rng), u(rng), u(rng)), Vec3(u(rng), u(rng), u(rng)), Real(0.3)};
    const Triangle t{Vec3(u(rng), u(rng), u(rng)), Vec3(u(rng), u(rng), u(rng)), Vec3(u(rng), u(rng), u(rng))};
    const CastResult res = cast(c, Transform{}, Vec3::Zero(), t, Transform{});
    const double d = gap(c, Transform{}, t, Transform{});
    if (std::abs(d) < 1e-4) continue;  // leave the boundary to the tolerance tests
    EXPECT_EQ(res.hit, d < 0) << i;
    if (res.hit) EXPECT_EQ(res.t, 0);
  }
}

TEST(CastSemantics, GrazingASphereAlongABoxFaceHitsAtTheEdge) {
  // The ball slides along the box's top face y = 1 (tangent); first contact at the edge x = -1.
  const Obb box{Vec3::Zero(), Vec3(1, 1, 1), Mat3::Identity()};
  const Sphere ball{Vec3::Zero(), 1};
  const CastResult res = cast(ball, Transform{Quat::Identity(), Vec3(-5, 2, 0)}, Vec3(10, 0, 0), box, Transform{});
  ASSERT_TRUE(res.hit);
  EXPECT_FALSE(res.capped);
  EXPECT_LE(double(res.t), 0.4 + 1e-6);
  EXPECT_GE(double(res.t), 0.4 - 1e-3);
  // passing 1e-3 above the face misses
  EXPECT_FALSE(castAny(ball, Transform{Quat::Identity(), Vec3(-5, Real(2.001), 0)}, Vec3(10, 0, 0), box, Transform{}));
}

TEST(CastSemantics, SlidingAlongAFaceInContactStartsAtZero) {
  const Obb box{Vec3::Zero(), Vec3(1, 1, 1), Mat3::Identity()};
  const Obb slider{Vec3::Zero(), Vec3(Real(0.5), Real(0.5), Real(0.5)), Mat3::Identity()};
  const CastResult res =
      cast(slider, Transform{Quat::Identity(), Vec3(0, Real(1.5), 0)}, Vec3(4, 0, 0), box, Transform{});
  EXPECT_TRUE(res.hit);
  EXPECT_EQ(res.t, 0);
  EXPECT_TRUE(res.startsOverlapping);
}

TEST(CastSemantics, EdgeGrazingBoxesTouchAtTheClosedFormTime) {
  // Box edge meets box edge exactly (distance 0 at one instant only): closed sets, a hit.
  const Obb box{Vec3::Zero(), Vec3(1, 1, 1), Mat3::Identity()};
  // A at (-1 + 8t, y0 - 8t) against B at (5, 5): x-overlap for t in [0.5, 1]; y-overlap for
  // t in [(y0 - 7)/8, (y0 - 3)/8]. y0 = 5: [-0.25, 0.25], a miss; y0 = 7: [0, 0.5], so the boxes
  // share only the edge through (4, 4) at t = 0.5.
  const CastResult res = cast(box, Transform{Quat::Identity(), Vec3(-1, 5, 0)}, Vec3(8, -8, 0), box,
                              Transform{Quat::Identity(), Vec3(5, 5, 0)});
  EXPECT_FALSE(res.hit);
  const CastResult touch = cast(box, Transform{Quat::Identity(), Vec3(-1, 7, 0)}, Vec3(8, -8, 0), box,
                                Transform{Quat::Identity(), Vec3(5, 5, 0)});
  ASSERT_TRUE(touch.hit);
  EXPECT_NEAR(double(touch.t), 0.5, 1e-6);
  EXPECT_LE(double(touch.t), 0.5);
}

TEST(CastSemantics, DegenerateTrianglesAreTheirSegmentsAndPoints) {
  const Sphere ball{Vec3::Zero(), Real(0.5)};
  const Transform start{Quat::Identity(), Vec3(0, 0, 3)};
  const Vec3 m(0, 0, -6);
  // collinear corners: the segment from (-1,0,0) to (2,0,0); the ball lands on it at t = 2.5/6
  const Triangle seg{Vec3(-1, 0, 0), Vec3(2, 0, 0), Vec3(1, 0, 0)};
  CastResult res = cast(ball, start, m, seg, Transform{});
  ASSERT_TRUE(res.hit);
  EXPECT_NEAR(double(res.t), 2.5 / 6, 1e-6);
  // the same segment, displaced sideways by 0.6 > r: a miss (a proper triangle would be hit)
  const Triangle segAside{Vec3(-1, Real(0.6), 0), Vec3(2, Real(0.6), 0), Vec3(1, Real(0.6), 0)};
  EXPECT_FALSE(castAny(ball, start, m, segAside, Transform{}));
  // coincident corners: a point
  const Triangle point{Vec3(0, Real(0.3), 0), Vec3(0, Real(0.3), 0), Vec3(0, Real(0.3), 0)};
  res = cast(ball, start, m, point, Transform{});
  ASSERT_TRUE(res.hit);
  const double tRef = (3 - std::sqrt(0.25 - 0.09)) / 6;
  EXPECT_LE(double(res.t), tRef + 1e-6);
  EXPECT_GE(double(res.t), tRef - 1e-4);
}

TEST(CastSemantics, GridPairsFarFromTheOriginDecideAsAtTheOrigin) {
  // Integer-grid pairs translated by 2^22 (exact in float: the ulp there is 1/2). The contact
  // tolerance follows the pair's extent, floored at twice GJK's tolerance (6.5e-6 here, below
  // the grid's clearances), so segments 4e-4 apart do not touch there, as at the origin.
  const Real far = Real(1 << 22);
  const auto at = [](const Vec3& offset, const std::array<std::array<int, 3>, 3>& corners) {
    Triangle t;
    Vec3* v[3] = {&t.a, &t.b, &t.c};
    for (int i = 0; i < 3; ++i) *v[i] = offset + Vec3(Real(corners[i][0]), Real(corners[i][1]), Real(corners[i][2]));
    return ConvexShape(t);
  };
  const Transform id = Transform::identity();
  for (const Vec3& offset : {Vec3(0, 0, 0), Vec3(far, far, far)}) {
    // two segments 4.0e-4 apart, zero motion
    const ConvexShape a = at(offset, {{{0, 0, 0}, {-36, -31, -30}, {-36, -31, -30}}});
    const ConvexShape b = at(offset, {{{-5, -19, -2}, {-43, -2, -41}, {-43, -2, -41}}});
    EXPECT_FALSE(cast(a, id, Vec3::Zero(), b, id).hit) << offset.transpose();
    // a point passing that segment 4.0e-4 away
    const ConvexShape point = at(offset, {{{0, 0, 0}, {0, 0, 0}, {0, 0, 0}}});
    EXPECT_FALSE(cast(point, id, Vec3(-36, -31, -30), b, id).hit) << offset.transpose();
  }
  std::mt19937_64 rng(0x5eed0c57);
  std::uniform_int_distribution<int> coordinate(-32, 32), pick(0, 3);
  const auto corners = [&] {
    std::array<std::array<int, 3>, 3> c{};
    for (auto& v : c)
      for (int& x : v) x = coordinate(rng);
    if (pick(rng) == 0) c[2] = c[1];  // a segment
    return c;
  };
  int hits = 0;
  const int cases = 3000;
  for (int i = 0; i < cases; ++i) {
    const auto ca = corners(), cb = corners();
    const Vec3 motion(Real(coordinate(rng)), Real(coordinate(rng)), Real(coordinate(rng)));
    const CastResult near = cast(at(Vec3::Zero(), ca), id, motion, at(Vec3::Zero(), cb), id);
    const CastResult farAway = cast(at(Vec3(far, far, far), ca), id, motion, at(Vec3(far, far, far), cb), id);
    ASSERT_EQ(near.hit, farAway.hit) << "case " << i;
    hits += near.hit;
  }
  EXPECT_GT(hits, cases / 10);
  EXPECT_LT(hits, cases * 9 / 10);
}

TEST(CastValidation, BadInputNamesTheField) {
  const auto message = [](auto&& f) {
    try {
      f();
    } catch (const InvalidInput& e) {
      return std::string(e.what());
    }
    return std::string("no throw");
  };
  const Real nan = std::numeric_limits<Real>::quiet_NaN(), inf = std::numeric_limits<Real>::infinity();
  EXPECT_NE(message([&] { validate(ConvexShape(Sphere{Vec3::Zero(), -1}), "a"); }).find("a.radius"), std::string::npos);
  EXPECT_NE(message([&] { validate(ConvexShape(Capsule{Vec3(nan, 0, 0), Vec3::Zero(), 1}), "b"); }).find("b.a"),
            std::string::npos);
  Mat3 skew = Mat3::Identity();
  skew(0, 1) = Real(0.1);
  EXPECT_NE(message([&] { validate(ConvexShape(Obb{Vec3::Zero(), Vec3::Ones(), skew}), "a"); }).find("a.axes"),
            std::string::npos);
  EXPECT_NE(message([&] { validate(ConvexShape(Triangle{Vec3::Zero(), Vec3(0, inf, 0), Vec3::Zero()}), "b"); })
                .find("b[1]"),
            std::string::npos);
  EXPECT_NE(message([&] { validateMotion(Vec3(0, 0, inf), "motion"); }).find("motion"), std::string::npos);
  EXPECT_EQ(message([&] { validateMotion(Vec3(1, 2, 3), "motion"); }), "no throw");
  EXPECT_EQ(message([&] { validate(ConvexShape(Sphere{Vec3::Zero(), 0}), "a"); }), "no throw");
}

// ---- seeded random properties ---------------------------------------------------------------------

struct RandomPair {
  std::vector<std::unique_ptr<ConvexHull>> hulls;
  std::mt19937 rng;
  explicit RandomPair(unsigned seed) : rng(seed) {}
  double uni(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }
  Vec3 vec(double lo, double hi) { return Vec3(Real(uni(lo, hi)), Real(uni(lo, hi)), Real(uni(lo, hi))); }
  Quat rotation() {
    Quat q(Real(uni(-1, 1)), Real(uni(-1, 1)), Real(uni(-1, 1)), Real(uni(-1, 1)));
    return q.normalized();
  }
  ConvexShape shape(int kind) {
    switch (kind) {
      case 0: return Sphere{vec(-0.2, 0.2), Real(uni(0.1, 1))};
      case 1: return Capsule{vec(-1, 1), vec(-1, 1), Real(uni(0.05, 0.5))};
      case 2: return Obb{vec(-0.2, 0.2), vec(0.1, 1), rotation().toRotationMatrix()};
      case 3: return Triangle{vec(-1.5, 1.5), vec(-1.5, 1.5), vec(-1.5, 1.5)};
      default: {
        std::vector<Vec3> pts;
        for (int i = 0; i < 10; ++i) pts.push_back(vec(-1, 1));
        hulls.push_back(std::make_unique<ConvexHull>(ConvexHull::build(pts)));
        return *hulls.back();
      }
    }
  }
};

TEST(CastSemantics, EarlyOutAbandonsOnlyLaterImpacts) {
  RandomPair g(5);
  for (int i = 0; i < 300; ++i) {
    const ConvexShape a = g.shape(i % 5), b = g.shape((i / 5) % 5);
    const Transform ta{g.rotation(), g.vec(-4, 4)}, tb{g.rotation(), g.vec(-1, 1)};
    const Vec3 m = (tb.translation - ta.translation + g.vec(-1, 1)) * Real(1.5);
    const CastResult full = cast(a, ta, m, b, tb);
    CastOptions o;
    o.earlyOut = Real(g.uni(0, 1));
    const CastResult early = cast(a, ta, m, b, tb, o);
    if (full.hit && full.t <= o.earlyOut) {
      ASSERT_TRUE(early.hit) << i;
      EXPECT_EQ(early.t, full.t) << i;
      EXPECT_EQ(early.pointA, full.pointA) << i;
    } else {
      EXPECT_FALSE(early.hit) << i;
    }
  }
}

TEST(CastProperty, ImpactIsWithinToleranceAndNothingTouchesBefore) {
  RandomPair g(2024);
  int hits = 0, misses = 0;
  const int n = 1500;
  for (int i = 0; i < n; ++i) {
    const ConvexShape a = g.shape(i % 5), b = g.shape((i / 5) % 5);
    const Transform ta{g.rotation(), g.vec(-4, 4)};
    const Transform tb{g.rotation(), g.vec(-1, 1)};
    // aim near B with an offset, so that about half the casts hit
    const Vec3 aim = tb.translation + g.vec(-1.5, 1.5);
    const Vec3 m = (aim - ta.translation) * Real(g.uni(0.5, 2.0));
    const CastResult res = cast(a, ta, m, b, tb);
    const double scale = castScale(a, ta, b, tb, m.norm());
    const double tol = contactTolerance(scale), zero = zeroSlack(scale);
    ASSERT_FALSE(res.capped) << i;
    if (res.hit) {
      ++hits;
      EXPECT_LE(gap(a, translated(ta, res.t * m), b, tb), tol + zero) << i;
      EXPECT_EQ(res.startsOverlapping, res.t == 0) << i;
      // before t: apart (sampled); the last sample just before t
      for (int k = 0; k < 8 && res.t > 0; ++k) {
        const Real s = res.t * Real(k) / 8;
        EXPECT_GT(gap(a, translated(ta, s * m), b, tb), -zero) << i << " at " << s << " of " << res.t;
      }
      EXPECT_NEAR(double(res.normal.norm()), 1, 1e-5);
      // reversed roles: B cast by -m against A hits at the same time (within the tolerance,
      // over the approach speed: compared loosely)
      const CastResult rev = cast(b, tb, -m, a, ta);
      EXPECT_TRUE(rev.hit) << i;
      EXPECT_NEAR(double(rev.t), double(res.t), 1e-3) << i;
    } else {
      ++misses;
      for (int k = 0; k <= 32; ++k) {
        const Real s = Real(k) / 32;
        EXPECT_GT(gap(a, translated(ta, s * m), b, tb), -zero) << i << " at " << s;
      }
      EXPECT_FALSE(cast(b, tb, -m, a, ta).hit) << i;
    }
  }
  EXPECT_GT(hits, n / 4);
  EXPECT_GT(misses, n / 4);
}

TEST(CastProperty, RigidMotionImpactIsWithinToleranceAndNothingTouchesBefore) {
  RandomPair g(77);
  int hits = 0, misses = 0, maxIterations = 0;
  const int n = 800;
  for (int i = 0; i < n; ++i) {
    const ConvexShape a = g.shape(i % 5), b = g.shape((i / 5) % 5);
    RigidMotion motion;
    motion.start = Transform{g.rotation(), g.vec(-4, 4)};
    const Transform tb{g.rotation(), g.vec(-1, 1)};
    motion.end = Transform{g.rotation(), Vec3(tb.translation + g.vec(-2, 2))};
    const CastResult res = cast(a, motion, b, tb);
    const double scale = castScale(a, motion.start, b, tb,
                                   (motion.end.translation - motion.start.translation).cast<double>().norm() +
                                       2 * M_PI * double(a.size()));
    const double zero = zeroSlack(scale);
    ASSERT_FALSE(res.capped) << i;
    maxIterations = std::max(maxIterations, res.iterations);
    if (res.hit) {
      ++hits;
      EXPECT_LE(gap(a, poseAt(motion, res.t), b, tb), contactTolerance(scale) + zero) << i;
      for (int k = 0; k < 8 && res.t > 0; ++k) {
        const Real s = res.t * Real(k) / 8;
        EXPECT_GT(gap(a, poseAt(motion, s), b, tb), -zero) << i << " at " << s;
      }
    } else {
      ++misses;
      for (int k = 0; k <= 64; ++k) {
        const Real s = Real(k) / 64;
        EXPECT_GT(gap(a, poseAt(motion, s), b, tb), -zero) << i << " at " << s;
      }
    }
  }
  EXPECT_GT(hits, n / 5);
  EXPECT_GT(misses, n / 5);
  RecordProperty("max_iterations", maxIterations);
  std::printf("rigid casts: at most %d iterations\n", maxIterations);
}

TEST(CastProperty, PoseAtKeepsTheEndsExactAndTurnsAtConstantRate) {
  RigidMotion m;
  m.start = Transform{Quat(Eigen::AngleAxis<Real>(Real(0.3), Vec3::UnitX())), Vec3(1, 2, 3)};
  m.end = Transform{Quat(Eigen::AngleAxis<Real>(Real(1.5), Vec3::UnitX())), Vec3(-3, 2, 7)};
  EXPECT_EQ(poseAt(m, 0).rotation.coeffs(), m.start.rotation.coeffs());
  EXPECT_EQ(poseAt(m, 1).translation, m.end.translation);
  const Transform half = poseAt(m, Real(0.5));
  EXPECT_NEAR(double(half.rotation.angularDistance(m.start.rotation)), 0.6, 1e-5);
  EXPECT_NEAR(double((half.translation - Vec3(-1, 2, 5)).norm()), 0, 1e-5);
}

// Non-queryable shapes, poses or motions (precondition.hpp): no hit. An infinite motion or pose
// used to report a hit at t = 0.
TEST(CastPreconditions, NonQueryableInputsGetNoHit) {
  if (CRUX_CHECK_PRECONDITIONS) GTEST_SKIP() << "this build aborts instead (precondition.hpp)";
  const ConvexShape box = Obb{Vec3::Zero(), Vec3::Constant(Real(0.5)), Mat3::Identity()};
  const Transform target{Quat::Identity(), Vec3(3, 0, 0)};
  const Vec3 motion(5, 0, 0);
  int cases = 0;
  for (const Transform& pose : test_support::badPoses()) {
    EXPECT_FALSE(cast(box, pose, motion, box, target).hit);
    EXPECT_FALSE(cast(box, Transform{}, motion, box, pose).hit);
    EXPECT_FALSE(castAny(box, pose, motion, box, target));
    EXPECT_FALSE(cast(box, RigidMotion{Transform{}, pose}, box, target).hit);
    EXPECT_FALSE(castAny(box, RigidMotion{pose, Transform{}}, box, target));
    ++cases;
  }
  for (const ConvexShape& shape : test_support::badShapes()) {
    EXPECT_FALSE(cast(shape, Transform{}, motion, box, target).hit);
    EXPECT_FALSE(castAny(box, Transform{}, motion, shape, target));
    ++cases;
  }
  for (const Real bad : test_support::nonFiniteValues()) {
    EXPECT_FALSE(cast(box, Transform{}, Vec3(bad, 0, 0), box, target).hit);
    EXPECT_FALSE(castAny(box, Transform{}, Vec3(0, 0, bad), box, target));
    ++cases;
  }
  EXPECT_GT(cases, 30);
  EXPECT_TRUE(cast(box, Transform{}, motion, box, target).hit);  // the good cast hits
}

}  // namespace
}  // namespace crux
