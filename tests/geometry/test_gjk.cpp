// Tests of src/geometry/gjk.cpp and epa.cpp: analytic answers (spheres, capsules, boxes at integer
// offsets), a certificate check of every separated answer (the two points lie on the shapes and
// the planes through them perpendicular to the normal support the shapes: lower bound = upper
// bound), penetration depths against libccd (ccdGJKPenetration, ccdMPRPenetration) and the
// separating-translation check, over seeded random rigid transforms in the families general,
// touching, face-to-face, degenerate hulls, huge (1e6) and tiny (1e-6).

#include <gtest/gtest.h>

#include <cmath>
#include <crux/geometry/closest_point.hpp>
#include <crux/geometry/gjk.hpp>
#include <functional>
#include <limits>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#if CRUX_HAVE_CCD_ORACLE
#include "ccd/ccd_oracle.hpp"
#include <crux/precondition.hpp>
#include "support/bad_inputs.hpp"
#endif

namespace crux {
namespace {

using V3d = Eigen::Vector3d;
constexpr double kEpsReal = std::numeric_limits<Real>::epsilon();

std::string str(const Vec3& v) {
  std::ostringstream os;
  os.precision(17);
  os << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return os.str();
}

std::string str(const Transform& t) {
  std::ostringstream os;
  os.precision(17);
  os << "{q=(" << t.rotation.w() << ", " << t.rotation.x() << ", " << t.rotation.y() << ", " << t.rotation.z()
     << "), t=" << str(t.translation) << "}";
  return os.str();
}

std::string str(const ConvexShape& s) {
  std::ostringstream os;
  os.precision(17);
  const char* names[] = {"sphere", "capsule", "box", "triangle", "hull"};
  os << names[int(s.kind)] << " r=" << s.radius;
  if (s.kind == ConvexKind::Box) {
    os << " c=" << str(s.p[0]) << " half=" << str(s.p[1]) << " axes=[" << s.axes.row(0) << "; " << s.axes.row(1)
       << "; " << s.axes.row(2) << "]";
  } else if (s.kind == ConvexKind::Hull) {
    os << " vertices=[";
    for (const Vec3& v : s.hull->vertices()) os << str(v) << " ";
    os << "]";
  } else {
    for (int i = 0; i < s.vertexCount(); ++i) os << " " << str(s.p[i]);
  }
  return os.str();
}

std::string describe(const ConvexShape& a, const Transform& ta, const ConvexShape& b, const Transform& tb) {
  return "A: " + str(a) + " at " + str(ta) + "\nB: " + str(b) + " at " + str(tb);
}

/// Independent (brute-force) support value: max over world core vertices of dot(x, d) + radius|d|.
double supportValue(const ConvexShape& s, const Transform& t, const V3d& d) {
  const Eigen::Matrix3d R = t.rotation.cast<double>().toRotationMatrix();
  double best = -INFINITY;
  for (int i = 0; i < s.vertexCount(); ++i)
    best = std::max(best, (R * s.vertex(i).cast<double>() + t.translation.cast<double>()).dot(d));
  return best + double(s.radius) * d.norm();
}

/// Distance from the world point p to the shape (0 inside), computed without GJK.
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
    case ConvexKind::Triangle: {
      const Triangle tri{s.p[0], s.p[1], s.p[2]};
      return (closestPoint(tri, l.cast<Real>()).cast<double>() - l).norm();
    }
    case ConvexKind::Hull: {
      const ConvexHull& h = *s.hull;
      if (h.dimension() < 3) {  // lower-dimensional: check against the vertices' span loosely
        double best = INFINITY;
        for (const Vec3& v : h.vertices()) best = std::min(best, (v.cast<double>() - l).norm());
        if (h.dimension() == 0) return best;
        return 0;  // not checked (segment/polygon membership is covered by test_convex)
      }
      double worst = 0;
      for (const HullFace& f : h.faces()) worst = std::max(worst, f.normal.cast<double>().dot(l) - f.offset);
      return worst;
    }
  }
  return 0;
}

// ---- random shapes and poses --------------------------------------------------------------

struct Gen {
  std::mt19937_64 rng;
  explicit Gen(std::uint64_t seed) : rng(seed) {}
  double uni(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }
  Vec3 vec(double lo, double hi) { return Vec3(Real(uni(lo, hi)), Real(uni(lo, hi)), Real(uni(lo, hi))); }
  Quat rot() {
    std::normal_distribution<double> g;
    Eigen::Quaterniond q(g(rng), g(rng), g(rng), g(rng));
    return q.normalized().cast<Real>();
  }
  Transform pose(double spread, double scale) {
    Transform t;
    t.rotation = rot();
    t.translation = (vec(-spread, spread).cast<double>() * scale).cast<Real>();
    return t;
  }
};

/// Owns the hulls the ConvexShape views point to.
struct ShapeStore {
  std::vector<std::unique_ptr<ConvexHull>> hulls;
  ConvexShape random(Gen& g, double scale, int kind, bool degenerateHull = false) {
    const auto S = [&](double x) { return Real(x * scale); };
    switch (kind) {
      case 0: return Sphere{(g.vec(-0.2, 0.2).cast<double>() * scale).cast<Real>(), S(g.uni(0.1, 1))};
      case 1:
        return Capsule{(g.vec(-1, 1).cast<double>() * scale).cast<Real>(),
                       (g.vec(-1, 1).cast<double>() * scale).cast<Real>(), S(g.uni(0.05, 0.6))};
      case 2: {
        Obb b;
        b.center = (g.vec(-0.2, 0.2).cast<double>() * scale).cast<Real>();
        b.half = (g.vec(0.1, 1).cast<double>() * scale).cast<Real>();
        b.axes = g.rot().toRotationMatrix();
        return b;
      }
      case 3:
        return Triangle{(g.vec(-1, 1).cast<double>() * scale).cast<Real>(),
                        (g.vec(-1, 1).cast<double>() * scale).cast<Real>(),
                        (g.vec(-1, 1).cast<double>() * scale).cast<Real>()};
      default: {
        std::vector<Vec3> pts;
        const int n = 4 + int(g.uni(0, 24));
        const int mode = degenerateHull ? int(g.uni(0, 3)) : 3;  // 0 point, 1 collinear, 2 coplanar
        const V3d e1 = g.vec(-1, 1).cast<double>().normalized(), e2 = e1.cross(V3d(0.3, 0.7, -0.2)).normalized();
        for (int i = 0; i < n; ++i) {
          V3d p;
          if (mode == 0) p = V3d(0.1, -0.2, 0.3);
          else if (mode == 1) p = e1 * g.uni(-1, 1);
          else if (mode == 2) p = e1 * g.uni(-1, 1) + e2 * g.uni(-1, 1);
          else p = g.vec(-1, 1).cast<double>();
          pts.push_back((p * scale).cast<Real>());
        }
        hulls.push_back(std::make_unique<ConvexHull>(ConvexHull::build(pts)));
        return *hulls.back();
      }
    }
  }
};

/// Absolute accuracy budget of a distance on a problem of length scale S: rounding the answer to
/// Real (a few ulps of S) plus the double-precision iteration (kGjkScaleTolerance·S, 1000 ulps of
/// double), and the 1e-6 relative allowance of the spec.
double budget(double S, double d) { return 16 * kEpsReal * S + 4 * kGjkScaleTolerance * S + 1e-6 * std::abs(d); }

double pairScale(const ConvexShape& a, const Transform& ta, const ConvexShape& b, const Transform& tb) {
  return double(a.size()) + double(b.size()) + (ta.translation - tb.translation).cast<double>().norm();
}

/// The certificate of a separated answer: points on the shapes, pA - pB = d·n, and the planes
/// through them normal to n support the shapes, so d is the distance within `tol`.
::testing::AssertionResult certified(const ConvexShape& a, const Transform& ta, const ConvexShape& b,
                                     const Transform& tb, const DistanceResult& r) {
  const double S = pairScale(a, ta, b, tb);
  const double tol = budget(S, r.distance);
  const V3d n = r.normal.cast<double>();
  std::ostringstream why;
  why.precision(17);
  if (!std::isfinite(r.distance) || !r.pointA.allFinite() || !r.pointB.allFinite() || !r.normal.allFinite())
    why << "non-finite result; ";
  if (std::abs(n.norm() - 1) > 16 * kEpsReal) why << "|normal| = " << n.norm() << "; ";
  const double onA = distanceToShape(a, ta, r.pointA), onB = distanceToShape(b, tb, r.pointB);
  if (onA > tol) why << "pointA is " << onA << " off A; ";
  if (onB > tol) why << "pointB is " << onB << " off B; ";
  const V3d gap = (r.pointA - r.pointB).cast<double>() - double(r.distance) * n;
  if (gap.norm() > tol) why << "pointA - pointB - d*n = " << gap.norm() << "; ";
  // Lower bound: the slab between the supporting planes of A (along -n) and B (along n).
  const double lower = -supportValue(a, ta, -n) - supportValue(b, tb, n);
  if (double(r.distance) - lower > tol) why << "distance " << r.distance << " exceeds the lower bound " << lower << "; ";
  if (why.str().empty()) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << why.str() << "(tolerance " << tol << ")\n"
                                       << describe(a, ta, b, tb) << "\ndistance " << r.distance << " normal "
                                       << str(r.normal) << " pA " << str(r.pointA) << " pB " << str(r.pointB);
}

// ---- analytic -----------------------------------------------------------------------------

TEST(GjkAnalytic, SphereSphere) {
  const Sphere a{Vec3(0, 0, 0), 1}, b{Vec3(0, 0, 0), Real(0.5)};
  Transform tb;
  tb.translation = Vec3(3, 4, 0);
  const DistanceResult r = distance(a, Transform{}, b, tb);
  EXPECT_NEAR(r.distance, 3.5, 8 * kEpsReal);
  EXPECT_NEAR((r.normal - Vec3(Real(-0.6), Real(-0.8), 0)).norm(), 0, 8 * kEpsReal);
  EXPECT_NEAR((r.pointA - Vec3(Real(0.6), Real(0.8), 0)).norm(), 0, 8 * kEpsReal);
  EXPECT_NEAR((r.pointB - Vec3(Real(2.7), Real(3.6), 0)).norm(), 0, 16 * kEpsReal);
  tb.translation = Vec3(0, Real(1.25), 0);  // overlapping by 0.25
  const DistanceResult p = distance(a, Transform{}, b, tb);
  EXPECT_NEAR(p.distance, -0.25, 8 * kEpsReal);
  EXPECT_NEAR((p.normal - Vec3(0, -1, 0)).norm(), 0, 8 * kEpsReal);
  EXPECT_TRUE(overlaps(a, Transform{}, b, tb));
}

TEST(GjkAnalytic, ConcentricSpheresGetAFiniteNormal) {
  const Sphere a{Vec3(0, 0, 0), 1}, b{Vec3(0, 0, 0), 2};
  const DistanceResult r = distance(a, Transform{}, b, Transform{});
  EXPECT_NEAR(r.distance, -3, 8 * kEpsReal);
  EXPECT_TRUE(r.normal.allFinite());
  EXPECT_NEAR(r.normal.norm(), 1, 8 * kEpsReal);
}

TEST(GjkAnalytic, ParallelCapsules) {
  const Capsule a{Vec3(0, 0, 0), Vec3(1, 0, 0), Real(0.5)}, b{Vec3(Real(0.5), 2, 0), Vec3(2, 2, 0), Real(0.25)};
  const DistanceResult r = distance(a, Transform{}, b, Transform{});
  EXPECT_NEAR(r.distance, 1.25, 8 * kEpsReal);
  EXPECT_NEAR((r.normal - Vec3(0, -1, 0)).norm(), 0, 8 * kEpsReal);
  EXPECT_NEAR(r.pointA.y(), 0.5, 8 * kEpsReal);
  EXPECT_NEAR(r.pointB.y(), 1.75, 8 * kEpsReal);
  EXPECT_GE(r.pointA.x(), 0.5 - 8 * kEpsReal);  // on the overlap of the two x-ranges
  EXPECT_LE(r.pointA.x(), 1 + 8 * kEpsReal);
}

TEST(GjkAnalytic, CrossingCapsulesPenetrateAlongTheCommonNormal) {
  const Capsule a{Vec3(-1, 0, 0), Vec3(1, 0, 0), Real(0.5)}, b{Vec3(0, -1, Real(0.25)), Vec3(0, 1, Real(0.25)), Real(0.5)};
  const DistanceResult r = distance(a, Transform{}, b, Transform{});
  EXPECT_NEAR(r.distance, -0.75, 8 * kEpsReal);
  EXPECT_NEAR((r.normal - Vec3(0, 0, -1)).norm(), 0, 8 * kEpsReal);
  const Capsule c{Vec3(0, -1, 0), Vec3(0, 1, 0), Real(0.5)};  // exactly crossing: core distance 0
  const DistanceResult x = distance(a, Transform{}, c, Transform{});
  EXPECT_NEAR(x.distance, -1, 8 * kEpsReal);
  EXPECT_NEAR(std::abs(x.normal.z()), 1, 8 * kEpsReal);
}

TEST(GjkAnalytic, BoxesAtIntegerOffsets) {
  // Cubes of half extent 1 at every integer offset in [-3,3]^3: the distance is the norm of
  // max(0, |d_i| - 2), the overlap boolean is exact (touching faces, edges, corners included),
  // and the depth of an overlap is min_i (2 - |d_i|).
  const Obb cube{Vec3::Zero(), Vec3::Ones(), Mat3::Identity()};
  int checked = 0;
  for (int x = -3; x <= 3; ++x)
    for (int y = -3; y <= 3; ++y)
      for (int z = -3; z <= 3; ++z) {
        Transform tb;
        tb.translation = Vec3(Real(x), Real(y), Real(z));
        const Eigen::Vector3d d(std::abs(x), std::abs(y), std::abs(z));
        const double want = (d.array() - 2).cwiseMax(0).matrix().norm();
        const bool touch = (d.array() <= 2).all();
        const DistanceResult r = distance(cube, Transform{}, cube, tb);
        SCOPED_TRACE("offset " + str(tb.translation));
        EXPECT_EQ(overlaps(cube, Transform{}, cube, tb), touch);
        if (want > 0) {
          EXPECT_NEAR(r.distance, want, 16 * kEpsReal * 4);
        } else {
          const double depth = (2 - d.array()).minCoeff();
          EXPECT_NEAR(r.distance, -depth, 16 * kEpsReal * 4);
        }
        EXPECT_TRUE(r.normal.allFinite());
        ++checked;
      }
  EXPECT_EQ(checked, 343);
}

TEST(GjkAnalytic, FaceToFaceBoxesTouchingExactly) {
  const Obb box{Vec3::Zero(), Vec3(1, 2, 3), Mat3::Identity()};
  Transform tb;
  tb.translation = Vec3(Real(0.5), Real(0.25), 6);  // stacked on z, faces coplanar
  const DistanceResult r = distance(box, Transform{}, box, tb);
  EXPECT_NEAR(r.distance, 0, 64 * kEpsReal);
  EXPECT_NEAR(std::abs(r.normal.z()), 1, 1e-6);
  EXPECT_TRUE(overlaps(box, Transform{}, box, tb));
  tb.translation.z() = Real(6.001);
  EXPECT_FALSE(overlaps(box, Transform{}, box, tb));
}

TEST(GjkAnalytic, CoplanarTrianglesOverlappingHaveZeroDepthAndTheirPlaneNormal) {
  const Triangle a{Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0)}, b{Vec3(1, 1, 0), Vec3(-1, 1, 0), Vec3(1, -1, 0)};
  const DistanceResult r = distance(a, Transform{}, b, Transform{});
  EXPECT_EQ(r.status, GjkStatus::Flat);
  EXPECT_NEAR(r.distance, 0, 16 * kEpsReal);
  EXPECT_NEAR(std::abs(r.normal.z()), 1, 1e-6);
}

TEST(GjkAnalytic, DegenerateHullsActAsPointSegmentPolygon) {
  const ConvexHull point = ConvexHull::build({Vec3(1, 1, 1), Vec3(1, 1, 1)});
  const ConvexHull seg = ConvexHull::build({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 0, 0)});
  const Sphere unit{Vec3::Zero(), 1};
  Transform t;
  t.translation = Vec3(0, 3, 0);
  EXPECT_NEAR(distance(point, Transform{}, unit, t).distance, std::sqrt(1.0 + 4 + 1) - 1, 16 * kEpsReal);
  EXPECT_NEAR(distance(seg, Transform{}, unit, t).distance, 2, 16 * kEpsReal);
}

// ---- properties over seeded random pairs ----------------------------------------------------------

struct Family {
  const char* name;
  double scale;
  bool degenerateHulls;
};

void runFamily(const Family& fam, std::uint64_t seed, int pairs, int* separatedCount, int* overlapCount) {
  Gen g(seed);
  ShapeStore store;
  for (int i = 0; i < pairs; ++i) {
    const int ka = int(g.uni(0, 5)), kb = int(g.uni(0, 5));
    const ConvexShape a = store.random(g, fam.scale, ka, fam.degenerateHulls);
    const ConvexShape b = store.random(g, fam.scale, kb, fam.degenerateHulls);
    const Transform ta = g.pose(1.2, fam.scale), tb = g.pose(1.2, fam.scale);
    const DistanceResult r = distance(a, ta, b, tb);
    SCOPED_TRACE(std::string(fam.name) + " pair " + std::to_string(i));
    ASSERT_TRUE(std::isfinite(r.distance) && r.normal.allFinite() && r.pointA.allFinite() && r.pointB.allFinite())
        << describe(a, ta, b, tb);
    EXPECT_NE(r.status, GjkStatus::IterationCap) << describe(a, ta, b, tb);
    const double S = pairScale(a, ta, b, tb);
    if (r.distance > 0) {
      ++*separatedCount;
      EXPECT_TRUE(certified(a, ta, b, tb, r));
    } else {
      ++*overlapCount;
    }
    // The boolean agrees with the distance away from touching.
    if (std::abs(r.distance) > 1e-5 * S) EXPECT_EQ(overlaps(a, ta, b, tb), r.distance < 0) << describe(a, ta, b, tb);
    if (r.distance < 0) {
      const V3d gap = (r.pointA - r.pointB).cast<double>() - double(r.distance) * r.normal.cast<double>();
      EXPECT_LE(gap.norm(), budget(S, r.distance)) << "pointA - pointB != distance * normal\n" << describe(a, ta, b, tb);
      // Separating translation: moving A by depth along the normal leaves the pair touching.
      Transform moved = ta;
      const double depth = -double(r.distance);
      moved.translation = (ta.translation.cast<double>() + depth * r.normal.cast<double>()).cast<Real>();
      const DistanceResult after = distance(a, moved, b, tb);
      EXPECT_LE(std::abs(double(after.distance)), budget(S, depth) + 4 * kEpsReal * S)
          << "depth " << depth << " after separation " << after.distance << "\n"
          << describe(a, ta, b, tb);
    }
  }
}

TEST(GjkProperty, Families) {
  const Family families[] = {{"general", 1, false}, {"huge", 1e6, false}, {"tiny", 1e-6, false},
                             {"degenerate-hulls", 1, true}};
  std::uint64_t seed = 20261122;
  for (const Family& f : families) {
    int sep = 0, ov = 0;
    runFamily(f, seed++, 3000, &sep, &ov);
    // Both outcomes are exercised in every family (the hit rate is part of the test).
    EXPECT_GT(sep, 300) << f.name;
    EXPECT_GT(ov, 300) << f.name;
  }
}

TEST(GjkProperty, TouchingPairsHaveDistanceZero) {
  // Build a touching pair from a separated one: translate B along the normal by the distance.
  Gen g(77);
  ShapeStore store;
  int done = 0;
  for (int i = 0; i < 2000; ++i) {
    const ConvexShape a = store.random(g, 1, int(g.uni(0, 5))), b = store.random(g, 1, int(g.uni(0, 5)));
    const Transform ta = g.pose(3, 1);
    Transform tb = g.pose(3, 1);
    const DistanceResult r = distance(a, ta, b, tb);
    if (!(r.distance > 0)) continue;
    tb.translation = (tb.translation.cast<double>() + double(r.distance) * r.normal.cast<double>()).cast<Real>();
    const DistanceResult t = distance(a, ta, b, tb);
    const double S = pairScale(a, ta, b, tb);
    EXPECT_LE(std::abs(double(t.distance)), budget(S, 0) + 8 * kEpsReal * S) << describe(a, ta, b, tb);
    ++done;
  }
  EXPECT_GT(done, 500);
}

// ---- libccd ------------------------------------------------------------------------------------

/// Face normals and edge directions of a core in world space (polytope cores and segments).
void features(const ConvexShape& s, const Transform& t, std::vector<V3d>& normals, std::vector<V3d>& edges) {
  const Eigen::Matrix3d R = t.rotation.cast<double>().toRotationMatrix();
  auto w = [&](int i) { return V3d(R * s.vertex(i).cast<double>()); };
  switch (s.kind) {
    case ConvexKind::Capsule: edges.push_back(w(1) - w(0)); break;
    case ConvexKind::Box:
      for (int k = 0; k < 3; ++k) {
        normals.push_back(R * s.axes.col(k).cast<double>());
        edges.push_back(normals.back());
      }
      break;
    case ConvexKind::Triangle:
      normals.push_back((w(1) - w(0)).cross(w(2) - w(0)));
      for (int k = 0; k < 3; ++k) edges.push_back(w((k + 1) % 3) - w(k));
      break;
    case ConvexKind::Hull:
      for (const HullFace& f : s.hull->faces()) {
        normals.push_back(R * f.normal.cast<double>());
        for (std::uint32_t k = 0; k < f.count; ++k) {
          const std::uint32_t i = s.hull->faceVertices()[f.first + k], j = s.hull->faceVertices()[f.first + (k + 1) % f.count];
          if (i < j) edges.push_back(w(int(j)) - w(int(i)));
        }
      }
      if (s.hull->dimension() == 1) edges.push_back(w(1) - w(0));
      break;
    default: break;
  }
}

/// Exact penetration depth of two overlapping convex shapes whose Minkowski difference is
/// full-dimensional: min over unit u of h_A(u) + h_B(-u), attained at a face normal of A - B,
/// i.e. a face normal of A or B or a cross product of an edge of each (the SAT candidates).
double satDepth(const ConvexShape& a, const Transform& ta, const ConvexShape& b, const Transform& tb) {
  std::vector<V3d> axes, ea, eb;
  features(a, ta, axes, ea);
  features(b, tb, axes, eb);
  for (const V3d& x : ea)
    for (const V3d& y : eb) axes.push_back(x.cross(y));
  double best = INFINITY;
  for (V3d u : axes) {
    if (!(u.norm() > 1e-9 * std::max(1.0, u.cwiseAbs().maxCoeff()))) continue;
    u.normalize();
    best = std::min({best, supportValue(a, ta, u) + supportValue(b, tb, -u), supportValue(a, ta, -u) + supportValue(b, tb, u)});
  }
  return best;
}

TEST(GjkExact, PenetrationDepthIsTheSatMinimum) {
  // Polytope and capsule cores (never two lower-dimensional cores, whose Minkowski difference
  // may be flat): crux's EPA depth equals the exact minimum over the SAT candidate axes.
  Gen g(4243);
  ShapeStore store;
  int compared = 0;
  double worst = 0;
  for (int i = 0; i < 3000; ++i) {
    const int kinds[] = {1, 2, 3, 4};
    const int ka = kinds[int(g.uni(0, 4))], kb = kinds[int(g.uni(1, 4))];
    const ConvexShape a = store.random(g, 1, ka), b = store.random(g, 1, kb);
    const Transform ta = g.pose(0.8, 1), tb = g.pose(0.8, 1);
    const DistanceResult r = distance(a, ta, b, tb);
    // Rounded shapes: the SAT candidates hold only while the cores overlap (else the minimum is
    // on the rounded part, and equals radii - core distance, checked by the certificate tests).
    if (!(double(r.distance) < -double(a.radius + b.radius))) continue;
    const double S = pairScale(a, ta, b, tb);
    const double want = satDepth(a, ta, b, tb);
    ++compared;
    worst = std::max(worst, std::abs(-double(r.distance) - want) / S);
    EXPECT_NEAR(-double(r.distance), want, budget(S, want)) << describe(a, ta, b, tb);
  }
  std::printf("EPA vs exact SAT depth: %d pairs, worst |diff|/S %.3g\n", compared, worst);
  EXPECT_GT(compared, 800);
}

/// A pair of convex shapes that cross (at the identity pose), named for the failure message.
struct CrossingPair {
  const char* name;
  ConvexShape a, b;
};

/// distance() of every pair, in both orders, against the exact SAT minimum depth (which must
/// exceed minDepth: the pairs do cross), within the depth budget.
void expectCrossingDepthsMatchSat(const std::vector<CrossingPair>& cases, double minDepth) {
  for (const CrossingPair& c : cases) {
    for (int order = 0; order < 2; ++order) {
      const ConvexShape& a = order == 0 ? c.a : c.b;
      const ConvexShape& b = order == 0 ? c.b : c.a;
      const Transform id;
      const DistanceResult r = distance(a, id, b, id);
      const double S = pairScale(a, id, b, id);
      const double want = satDepth(a, id, b, id);
      EXPECT_GT(want, minDepth) << c.name;  // they do cross
      EXPECT_NEAR(-double(r.distance), want, budget(S, want)) << c.name << ", order " << order << "\n"
                                                               << describe(a, id, b, id);
    }
  }
}

// Found by `crux diff` (tests/regressions/*.14201-*, *.14202-*): integer-grid pairs
// whose Minkowski difference holds the origin on the plane of GJK's final triangle. EPA grew it
// to a tetrahedron with the origin on a face, and the support point of its first expansion lay on
// the line of a horizon edge (the face beyond that edge has it in its plane and was kept), so the
// new face over that edge had no area and EPA stopped ("degenerate step") with the origin's face:
// depth 0, touching, for pairs crossing by 0.316 and 1/3; a hull and a triangle read 3.6 %
// shallow. EPA now counts a face with the new point in its plane as seen. Depths against the
// exact SAT minimum, in both precisions.
TEST(GjkExact, EpaExpandsPastAFaceHoldingTheNewPointInItsPlane) {
  Obb flat;  // a rectangle: x in [0, 2], y = 1, z in [0, 2]
  flat.center = Vec3(1, 1, 1);
  flat.half = Vec3(1, 0, 1);
  flat.axes.col(0) = Vec3(0, 0, -1);
  flat.axes.col(1) = Vec3(0, -1, 0);
  flat.axes.col(2) = Vec3(1, 0, 0);
  Obb box;
  box.center = Vec3(0, -1, -1);
  box.half = Vec3(1, 2, 1);
  box.axes.col(0) = Vec3(-1, 0, 0);
  box.axes.col(1) = Vec3(0, 0, -1);
  box.axes.col(2) = Vec3(0, 1, 0);
  const ConvexHull hull = ConvexHull::build({Vec3(-2, 1, 3), Vec3(0, 0, 3), Vec3(0, 0, 3), Vec3(-1, -2, 2), Vec3(0, 0, 4),
                                             Vec3(-2, 1, 4), Vec3(-1, -2, 4), Vec3(0, 0, 5)});
  const std::vector<CrossingPair> cases = {
      {"triangle through a flat box", Triangle{Vec3(0, -1, 0), Vec3(1, -1, 0), Vec3(0, 2, 2)}, flat},
      {"box and triangle crossing by 1/3", box, Triangle{Vec3(-2, -1, -2), Vec3(-1, 0, -2), Vec3(0, 0, -4)}},
      {"hull with a repeated point through a triangle", hull,
       Triangle{Vec3(1, 3, 4), Vec3(1, 3, -3), Vec3(-4, -3, 4)}},
  };
  expectCrossingDepthsMatchSat(cases, 0.3);
}

/// Sliver triangles (two corners ~1e-12 apart) against a flat box and a hull (`crux diff`,
/// double build, family `sliver`): EPA's last expansion took a support point a few
/// 1e-12 from a polytope vertex (the sliver's twin corner), the faces it made had meaningless
/// normals and the nearest one lay *nearer* than the face before (0.102 -> -0.152: depth 0,
/// "touching"; 0.359 -> 0.350: 2.5 % shallow). EPA's nearest-face distance never decreases in
/// exact arithmetic, so a drop now stops it with the face before. Both builds showed it.
TEST(GjkExact, EpaKeepsTheLastSoundFaceWhenAnExpansionBreaksThePolytope) {
  Obb flat;  // a rectangle (half extent 0 along its second axis)
  flat.center = Vec3(-0.25, -1, 0.109375);
  flat.half = Vec3(Real(1.04931640625), 0, 1);
  Mat3 rows;
  rows << Real(-0.2222191077851876), Real(0.9749735261985345), Real(-0.006729884631318045),
      Real(-0.9402330316983497), Real(-0.21246400009333977), Real(0.266121954689326), Real(0.2580320023533622),
      Real(0.06546504316299644), Real(0.9639158749004922);
  flat.axes = rows.transpose();
  const ConvexHull hull = ConvexHull::build({Vec3(0, 0, 0), Vec3(0, 0, 0), Vec3(0, 1, Real(-1.25)), Vec3(0, 2, 0),
                                             Vec3(1, Real(-0.75), Real(0.171875)), Vec3(0, 0, 0),
                                             Vec3(-1, -1, Real(0.03515625)), Vec3(0, 2, 1)});
  const std::vector<CrossingPair> cases = {
      {"sliver triangle through a flat box",
       Triangle{Vec3(0, Real(4.263256414560601e-13), Real(6.821210263296962e-13)),
                Vec3(Real(6.394884621840902e-14), Real(-6.252776074688882e-13), Real(-9.094947017729282e-13)),
                Vec3(-1, Real(-0.203125), -1)},
       flat},
      {"sliver triangle through a hull",
       Triangle{Vec3(Real(2.5011104298755527e-12), Real(1.3642420526593924e-12), Real(-2.5011104298755527e-12)),
                Vec3(0, Real(-1.8189894035458565e-12), 0), Vec3(0, -1, 0)},
       hull},
  };
  expectCrossingDepthsMatchSat(cases, 0.1);
}

#if CRUX_HAVE_CCD_ORACLE
TEST(GjkVsLibccd, PenetrationDepth) {
  // libccd's GJK+EPA (ccdGJKPenetration) is compared on polytope pairs; where it disagrees with
  // crux beyond its tolerance, the exact SAT depth arbitrates (and crux must equal it). libccd's
  // MPR is not a minimum-depth method: crux must never be deeper than it.
  Gen g(4242);
  ShapeStore store;
  int compared = 0, ccdFailures = 0, ccdWrong = 0, worseThanMpr = 0;
  for (int i = 0; i < 3000; ++i) {
    const int kinds[] = {2, 3, 4};
    const ConvexShape a = store.random(g, 1, kinds[int(g.uni(0, 3))]), b = store.random(g, 1, kinds[int(g.uni(0, 3))]);
    const Transform ta = g.pose(1, 1), tb = g.pose(1, 1);
    const DistanceResult r = distance(a, ta, b, tb);
    if (!(r.distance < -1e-6)) continue;
    const oracle_ccd::Penetration p = oracle_ccd::gjkPenetration(a, ta, b, tb);
    if (p.status != 0 || !std::isfinite(p.depth)) {
      ++ccdFailures;
      continue;
    }
    ++compared;
    const double depth = -double(r.distance);
    const double S = pairScale(a, ta, b, tb);
    const double tol = 1e-6 * S + budget(S, depth);
    if (std::abs(depth - p.depth) > tol) {
      const double exact = satDepth(a, ta, b, tb);
      EXPECT_NEAR(depth, exact, budget(S, exact)) << "crux and libccd disagree\n" << describe(a, ta, b, tb);
      if (std::abs(p.depth - exact) > tol) ++ccdWrong;
    }
    const oracle_ccd::Penetration m = oracle_ccd::mprPenetration(a, ta, b, tb);
    if (m.status == 0 && depth > m.depth + tol) ++worseThanMpr;
  }
  std::printf("libccd ccdGJKPenetration: %d pairs, wrong depth (vs exact SAT) in %d, failures %d\n", compared, ccdWrong,
              ccdFailures);
  EXPECT_GT(compared, 500);
  EXPECT_EQ(worseThanMpr, 0);
}

TEST(GjkVsLibccd, IntersectBooleanAwayFromTouching) {
  Gen g(99);
  ShapeStore store;
  int disagreeGjk = 0, disagreeMpr = 0, n = 0;
  for (int i = 0; i < 3000; ++i) {
    const ConvexShape a = store.random(g, 1, int(g.uni(0, 5))), b = store.random(g, 1, int(g.uni(0, 5)));
    const Transform ta = g.pose(2, 1), tb = g.pose(2, 1);
    const DistanceResult r = distance(a, ta, b, tb);
    if (std::abs(r.distance) < 1e-4) continue;
    ++n;
    const bool mine = overlaps(a, ta, b, tb);
    EXPECT_EQ(mine, r.distance < 0);
    if (oracle_ccd::gjkIntersect(a, ta, b, tb) != mine) ++disagreeGjk;
    if (oracle_ccd::mprIntersect(a, ta, b, tb) != mine) ++disagreeMpr;
  }
  std::printf("libccd intersect: %d pairs, GJK disagreements %d, MPR disagreements %d\n", n, disagreeGjk, disagreeMpr);
  EXPECT_EQ(disagreeGjk, 0);
  EXPECT_EQ(disagreeMpr, 0);
}
#endif


// Non-queryable shapes or poses (precondition.hpp): distance NaN, overlaps false, never UB.
TEST(GjkPreconditions, NonQueryableInputsGetNoAnswer) {
  if (CRUX_CHECK_PRECONDITIONS) GTEST_SKIP() << "this build aborts instead (precondition.hpp)";
  const ConvexShape box = Obb{Vec3::Zero(), Vec3::Constant(Real(0.5)), Mat3::Identity()};
  int cases = 0;
  for (const Transform& pose : test_support::badPoses()) {
    EXPECT_TRUE(std::isnan(distance(box, Transform{}, box, pose).distance));
    EXPECT_FALSE(overlaps(box, pose, box, Transform{}));
    ++cases;
  }
  for (const ConvexShape& shape : test_support::badShapes()) {
    EXPECT_TRUE(std::isnan(distance(shape, Transform{}, box, Transform{}).distance));
    EXPECT_FALSE(overlaps(box, Transform{}, shape, Transform{}));
    ++cases;
  }
  EXPECT_GT(cases, 30);
  EXPECT_TRUE(overlaps(box, Transform{}, box, Transform{}));  // the good pair overlaps
}

}  // namespace
}  // namespace crux
