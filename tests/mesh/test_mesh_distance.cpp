// Mesh–mesh and model–model distance (src/mesh/mesh_distance.cpp, model_query.cpp) against
// brute force: the BVH path against the BruteForce path (same triangle routine: equal minima),
// and both against an independent reference — the exact CGAL distance over every triangle pair
// (triangles mapped into a's frame in double by the test) — on small seeded meshes; the
// maxDistance / stopDistance contract; exact zero for touching and crossing integer-grid meshes
// (agreeing with the exact mesh–mesh overlap test); a real mesh (blob.off) against brute force.

#include <crux/error.hpp>
#include <crux/geometry/closest_point.hpp>
#include <crux/mesh/mesh_distance.hpp>
#include <crux/mesh/mesh_query_data.hpp>
#include <crux/mesh/mesh_query.hpp>
#include <crux/model/model_query.hpp>

#include <exact/exact.hpp>
#include <exact/exact_kernel.hpp>

#include <gtest/gtest.h>

#include <support/scene_fixtures.hpp>
#include <support/test_scale.hpp>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <cstdio>
#include <iomanip>
#include <limits>
#include <memory>
#include <sstream>
#include <random>
#include <string>
#include <vector>
#include <crux/precondition.hpp>
#include "support/bad_inputs.hpp"

namespace crux {
namespace {

using Rng = std::mt19937_64;
using crux::test::randomPose;

constexpr double kRelative = 1e-6;
constexpr double kAbsolute = 1e-12;
/// Mapping b into a's frame rounds in Real: a few ulps of Real × the coordinate scale.
constexpr double kMapUlps = 16 * double(std::numeric_limits<Real>::epsilon());

std::string show(const Transform& t) {
  std::ostringstream s;
  s << std::setprecision(17) << "q=(" << t.rotation.w() << "," << t.rotation.x() << "," << t.rotation.y() << ","
    << t.rotation.z() << ") t=(" << t.translation.transpose() << ")";
  return s.str();
}

/// A random triangle soup of n triangles of size ~0.6 in [-1, 1]^3.
std::shared_ptr<const Mesh> soup(Rng& rng, int n) {
  std::uniform_real_distribution<double> u(-1, 1), e(-0.3, 0.3);
  std::vector<Vec3> v;
  std::vector<TriangleIndices> t;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d c(u(rng), u(rng), u(rng));
    for (int k = 0; k < 3; ++k) v.push_back((c + Eigen::Vector3d(e(rng), e(rng), e(rng))).cast<Real>());
    t.push_back({std::uint32_t(3 * i), std::uint32_t(3 * i + 1), std::uint32_t(3 * i + 2)});
  }
  return std::make_shared<const Mesh>(std::move(v), std::move(t), "soup");
}

/// Exact reference: min over all pairs of the exact distance between a's triangles and b's
/// triangles mapped into a's frame in double (then rounded to double coordinates).
double exactReference(const Mesh& a, const Transform& ta, const Mesh& b, const Transform& tb) {
  using namespace crux::exact::detail;
  const Eigen::Quaterniond qa = ta.rotation.cast<double>().normalized(), qb = tb.rotation.cast<double>().normalized();
  const Eigen::Matrix3d R = (qa.conjugate() * qb).toRotationMatrix();
  const Eigen::Vector3d t = qa.conjugate() * (tb.translation.cast<double>() - ta.translation.cast<double>());
  auto map = [&](const Vec3& p) { const Eigen::Vector3d x = R * p.cast<double>() + t; return Point(x.x(), x.y(), x.z()); };
  std::vector<Simplex> sb;
  for (std::uint32_t j = 0; j < b.triangleCount(); ++j) {
    const Triangle tr = b.triangle(j);
    sb.push_back(simplexOf(map(tr.a), map(tr.b), map(tr.c)));
  }
  FT best = -1;
  for (std::uint32_t i = 0; i < a.triangleCount(); ++i) {
    const Simplex sa = toSimplex(a.triangle(i));
    const Triangle3* ta3 = std::get_if<Triangle3>(&sa);
    for (const Simplex& s : sb) {
      const Triangle3* tb3 = std::get_if<Triangle3>(&s);
      if (!ta3 || !tb3) continue;  // the soups and spheres here have no degenerate triangles
      const FT d = CGAL::do_intersect(*ta3, *tb3) ? FT(0) : CGAL::squared_distance(*ta3, *tb3);
      if (best < 0 || d < best) best = d;
    }
  }
  return std::sqrt(CGAL::to_double(best));
}

double scaleOf(const Mesh& a, const Mesh& b, const Transform& ta, const Transform& tb) {
  auto mx = [](const Aabb& box) { return std::max(box.min.cwiseAbs().maxCoeff(), box.max.cwiseAbs().maxCoeff()); };
  return double(std::max(mx(a.bounds()), mx(b.bounds())) + (tb.translation - ta.translation).cwiseAbs().maxCoeff());
}

/// The answer's own consistency: points on the reported triangles (world), gap = distance.
void checkPoints(const Mesh& a, const Transform& ta, const Mesh& b, const Transform& tb, const MeshMeshDistanceResult& r,
                 double tol, const std::string& what) {
  const Vec3 pa = ta.inverse().apply(r.pointA), pb = tb.inverse().apply(r.pointB);
  EXPECT_LE(std::sqrt(double(squaredDistance(a.triangle(r.triangleA), pa))), tol) << what;
  EXPECT_LE(std::sqrt(double(squaredDistance(b.triangle(r.triangleB), pb))), tol) << what;
  EXPECT_NEAR(double((r.pointA - r.pointB).norm()), double(r.distance), tol) << what;
}

TEST(MeshDistance, BvhEqualsBruteForceAndExactOnSoups) {
  Rng rng(11);
  const int cases = crux::test::scaledCases(60, 20);
  int separated = 0, touching = 0;
  double worst = 0;
  for (int c = 0; c < cases; ++c) {
    const auto a = soup(rng, 24), b = soup(rng, 30);
    const Transform ta = randomPose(rng, 0.5), tb = randomPose(rng, 1.6);
    const MeshMeshDistanceResult bvh = distance(*a, ta, *b, tb);
    MeshDistanceOptions brute;
    brute.path = QueryPath::BruteForce;
    const MeshMeshDistanceResult ref = distance(*a, ta, *b, tb, brute);
    const double exact = exactReference(*a, ta, *b, tb);
    const double scale = scaleOf(*a, *b, ta, tb);
    const std::string what = "case " + std::to_string(c) + " ta " + show(ta) + " tb " + show(tb);
    ASSERT_TRUE(bvh.found && ref.found) << what;
    EXPECT_EQ(bvh.distance, ref.distance) << what;
    // The oriented-box accelerators only prune: same minimum, on either or both sides.
    const MeshQueryData accA(*a, MeshQueryParts::Distance), accB(*b, MeshQueryParts::Distance);
    MeshDistanceOptions withAccel;
    withAccel.dataA = &accA;
    EXPECT_EQ(distance(*a, ta, *b, tb, withAccel).distance, ref.distance) << what;
    withAccel.dataB = &accB;
    EXPECT_EQ(distance(*a, ta, *b, tb, withAccel).distance, ref.distance) << what;
    EXPECT_NEAR(double(bvh.distance), exact, kRelative * exact + kAbsolute * scale + kMapUlps * scale) << what;
    checkPoints(*a, ta, *b, tb, bvh, kMapUlps * scale + kRelative * exact, what);
    EXPECT_EQ(bvh.distance == 0, overlaps(*a, ta, *b, tb)) << what;
    if (exact > 0) worst = std::max(worst, std::fabs(double(bvh.distance) - exact) / exact);
    (bvh.distance > 0 ? separated : touching)++;
  }
  std::printf("soups: %d separated, %d intersecting, worst relative error vs exact %.3g\n", separated, touching, worst);
  EXPECT_GT(separated, cases / 5);
  EXPECT_GT(touching, cases / 10);
}

TEST(MeshDistance, MaxDistanceAndStopDistanceContract) {
  Rng rng(12);
  const auto a = test::bumpySphere(8, 12), b = test::bumpySphere(6, 10);
  const int cases = crux::test::scaledCases(40, 20);
  for (int c = 0; c < cases; ++c) {
    const Transform ta = randomPose(rng, 1), tb = randomPose(rng, 4);
    MeshDistanceOptions brute;
    brute.path = QueryPath::BruteForce;
    const MeshMeshDistanceResult ref = distance(*a, ta, *b, tb, brute);
    const std::string what = "case " + std::to_string(c) + " ta " + show(ta) + " tb " + show(tb);
    ASSERT_TRUE(ref.found);
    std::uniform_real_distribution<double> f(0.2, 1.8);
    for (const QueryPath path : {QueryPath::Bvh, QueryPath::BruteForce}) {
      MeshDistanceOptions o;
      o.path = path;
      o.maxDistance = Real(double(ref.distance) * f(rng));
      const MeshMeshDistanceResult r = distance(*a, ta, *b, tb, o);
      EXPECT_EQ(r.found, ref.distance <= o.maxDistance) << what;
      if (r.found) EXPECT_EQ(r.distance, ref.distance) << what;
      MeshDistanceOptions s;
      s.path = path;
      s.stopDistance = Real(double(ref.distance) * f(rng));
      const MeshMeshDistanceResult e = distance(*a, ta, *b, tb, s);
      ASSERT_TRUE(e.found) << what;
      EXPECT_GE(e.distance, ref.distance) << what;
      if (ref.distance <= s.stopDistance) EXPECT_LE(e.distance, s.stopDistance) << what;
      else EXPECT_EQ(e.distance, ref.distance) << what;
      EXPECT_EQ(e.stoppedEarly, e.distance > 0 && e.distance <= s.stopDistance) << what;
    }
  }
}

/// A soup of n triangles with integer corners in [-3, 3]^3 (degenerate ones included).
Mesh gridSoup(Rng& rng, int n) {
  std::uniform_int_distribution<int> g(-3, 3);
  std::vector<Vec3> v;
  std::vector<TriangleIndices> t;
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) v.emplace_back(Real(g(rng)), Real(g(rng)), Real(g(rng)));
    t.push_back({std::uint32_t(3 * i), std::uint32_t(3 * i + 1), std::uint32_t(3 * i + 2)});
  }
  return Mesh(std::move(v), std::move(t), "grid");
}

TEST(MeshDistance, IntegerGridTouchingAndCrossingGiveExactZero) {
  // Grid meshes under integer translations and axis-aligned quarter turns: distance 0 exactly
  // when (and only when) the exact overlap test says the surfaces touch.
  Rng rng(13);
  std::uniform_int_distribution<int> g(-3, 3), turn(0, 3);
  int zero = 0, positive = 0;
  const int cases = crux::test::scaledCases(1500, 300);
  for (int c = 0; c < cases; ++c) {
    const Mesh a = gridSoup(rng, 4), b = gridSoup(rng, 4);
    Transform tb;
    tb.rotation = quatFromEulerDegrees(0, 0, Real(90 * turn(rng)));
    tb.translation = Vec3(Real(g(rng) * 2), Real(g(rng) * 2), Real(g(rng) * 2));
    const bool exactOverlap = overlaps(a, Transform::identity(), b, tb);
    const MeshMeshDistanceResult r = distance(a, Transform::identity(), b, tb);
    MeshDistanceOptions brute;
    brute.path = QueryPath::BruteForce;
    const MeshMeshDistanceResult ref = distance(a, Transform::identity(), b, tb, brute);
    EXPECT_EQ(r.distance == 0, exactOverlap) << "case " << c << " tb " << show(tb) << " d=" << r.distance;
    EXPECT_EQ(r.distance, ref.distance) << "case " << c;
    (r.distance == 0 ? zero : positive)++;
  }
  std::printf("grid: %d touching/crossing, %d apart\n", zero, positive);
  EXPECT_GT(zero, cases / 10);
  EXPECT_GT(positive, cases / 10);
}

TEST(MeshDistance, RealMeshAgainstBruteForce) {
  const Mesh blob = loadMesh(std::string(CRUX_SOURCE_DIR) + "/data/meshes/blob.off");
  Rng rng(14);
  const Aabb box = blob.bounds();
  const double size = double((box.max - box.min).norm());
  for (int c = 0; c < 6; ++c) {
    Transform tb = randomPose(rng, 0);
    std::uniform_real_distribution<double> sep(0.2, 1.5);
    const Eigen::Vector3d dir = Eigen::Vector3d::Random().normalized();
    tb.translation = (dir * sep(rng) * size).cast<Real>();
    const MeshQueryData acc(blob, MeshQueryParts::Distance);
    MeshDistanceOptions withAccel;
    withAccel.dataA = withAccel.dataB = &acc;
    const MeshMeshDistanceResult r = distance(blob, Transform::identity(), blob, tb, withAccel);
    EXPECT_EQ(distance(blob, Transform::identity(), blob, tb).distance, r.distance) << "case " << c;
    MeshDistanceOptions brute;
    brute.path = QueryPath::BruteForce;
    const MeshMeshDistanceResult ref = distance(blob, Transform::identity(), blob, tb, brute);
    EXPECT_EQ(r.distance, ref.distance) << "case " << c << " " << show(tb);
    checkPoints(blob, Transform::identity(), blob, tb, r, kMapUlps * 4 * size + 1e-6 * double(r.distance), "blob");
  }
}

TEST(MeshDistance, ParallelGridsWithManyTiedPairsEqualBruteForce) {
  // Two flat grids facing each other: thousands of node and triangle pairs have (nearly) the same
  // bound or distance, so the order of the search decides which pair is found first, never the
  // distance. (Heap overflow: ConcentricSpheresOverflowTheBestFirstHeapAndStayExact.) The brute
  // force reference is O(n⁴): under CRUX_TEST_SCALE < 1 (the sanitizer stage) a 12×12 grid
  // (288 triangles) and fewer poses, the full 24×24 grid (1,152) and 3 poses otherwise.
  auto grid = [](int n) {
    std::vector<Vec3> v;
    std::vector<TriangleIndices> t;
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j <= n; ++j) v.emplace_back(Real(i) / Real(n), Real(j) / Real(n), 0);
    auto at = [n](int i, int j) { return std::uint32_t(i * (n + 1) + j); };
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        t.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
        t.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
      }
    return Mesh(std::move(v), std::move(t), "grid");
  };
  const Mesh a = grid(crux::test::testScale() < 1 ? 12 : 24);
  const MeshQueryData acc(a, MeshQueryParts::Distance);
  const int poses = crux::test::scaledCases(3, 1);
  for (int c = 0; c < poses; ++c) {
    Transform tb;
    if (c > 0) tb.rotation = Quat(Eigen::AngleAxis<Real>(Real(0.002 * c), Vec3(Real(0.3), 1, 0).normalized()));
    tb.translation = Vec3(Real(0.013 * c), Real(0.007), Real(0.05));
    MeshDistanceOptions brute;
    brute.path = QueryPath::BruteForce;
    const MeshMeshDistanceResult ref = distance(a, Transform::identity(), a, tb, brute);
    MeshDistanceOptions withAccel;
    withAccel.dataA = withAccel.dataB = &acc;
    EXPECT_EQ(distance(a, Transform::identity(), a, tb).distance, ref.distance) << "case " << c;
    EXPECT_EQ(distance(a, Transform::identity(), a, tb, withAccel).distance, ref.distance) << "case " << c;
  }
}

TEST(MeshDistance, ConcentricSpheresOverflowTheBestFirstHeapAndStayExact) {
  // A sphere inside a sphere: every part of one is about equally far from the other, so the
  // pending node pairs outgrow the fixed best-first heap and its depth-first fallback runs.
  auto sphere = [](int rings, double radius) {
    const int segments = 2 * rings;
    std::vector<Vec3> v;
    std::vector<TriangleIndices> t;
    for (int i = 0; i <= rings; ++i)
      for (int j = 0; j < segments; ++j) {
        const double th = M_PI * i / rings, ph = 2 * M_PI * j / segments;
        v.emplace_back(Real(radius * std::sin(th) * std::cos(ph)), Real(radius * std::sin(th) * std::sin(ph)),
                       Real(radius * std::cos(th)));
      }
    auto at = [&](int i, int j) { return std::uint32_t(i * segments + (j % segments)); };
    for (int i = 0; i < rings; ++i)
      for (int j = 0; j < segments; ++j) {
        t.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
        t.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
      }
    return Mesh(std::move(v), std::move(t), "sphere");
  };
  const Mesh outer = sphere(20, 1.0), inner = sphere(10, 0.5);
  const MeshQueryData accOuter(outer, MeshQueryParts::Distance), accInner(inner, MeshQueryParts::Distance);
  MeshDistanceOptions brute;
  brute.path = QueryPath::BruteForce;
  Rng rng(17);
  for (int c = 0; c < 2; ++c) {
    const Transform tb = randomPose(rng, 0.05);
    const MeshMeshDistanceResult ref = distance(outer, Transform::identity(), inner, tb, brute);
    MeshDistanceOptions withAccel;
    withAccel.dataA = &accOuter;
    withAccel.dataB = &accInner;
    EXPECT_EQ(distance(outer, Transform::identity(), inner, tb).distance, ref.distance) << "case " << c;
    EXPECT_EQ(distance(outer, Transform::identity(), inner, tb, withAccel).distance, ref.distance) << "case " << c;
  }
}

/// A soup with degenerate members: proper triangles, collinear (needle) triangles, triangles
/// with a repeated corner and point triangles, plus a flat sheet (zero-thickness oriented boxes),
/// of overall size ~`size` around `centre`.
Mesh degenerateSoup(Rng& rng, int n, double size, const Eigen::Vector3d& centre) {
  std::uniform_real_distribution<double> u(-1, 1), e(-0.2, 0.2);
  std::uniform_int_distribution<int> kind(0, 4);
  std::vector<Vec3> v;
  std::vector<TriangleIndices> t;
  auto add = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& r) {
    const std::uint32_t k = std::uint32_t(v.size());
    for (const Eigen::Vector3d& x : {p, q, r}) v.push_back((centre + size * x).cast<Real>());
    t.push_back({k, k + 1, k + 2});
  };
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d c(u(rng), u(rng), u(rng)), d1(e(rng), e(rng), e(rng)), d2(e(rng), e(rng), e(rng));
    switch (kind(rng)) {
      case 0: add(c, c + d1, c + d2); break;                 // proper
      case 1: add(c, c + d1, c + 0.5 * d1); break;           // collinear
      case 2: add(c, c + d1, c + d1); break;                 // repeated corner
      case 3: add(c, c, c); break;                           // a point
      default: add(Eigen::Vector3d(c.x(), c.y(), 0.25), Eigen::Vector3d(c.x() + d1.x(), c.y() + d1.y(), 0.25),
                   Eigen::Vector3d(c.x() + d2.x(), c.y() + d2.y(), 0.25));  // flat sheet z = 0.25
    }
  }
  return Mesh(std::move(v), std::move(t), "degenerate soup");
}

TEST(MeshDistance, AcceleratedBoundsNeverPruneTheAnswerOnDegenerateMeshes) {
  // The oriented-box pair bounds (line of centres, then box gaps in either box's frame) and the
  // four-way split of similar-size node pairs must only prune: with accelerators on both sides,
  // on one side, or none, the BVH answer equals brute force exactly. Degenerate soups (needles,
  // points, flat sheets: zero-thickness boxes), meshes of very different sizes (one side split
  // alone), random, quarter-turn and near-touching poses, at scales 1e-3 and 1e3.
  Rng rng(18);
  std::uniform_real_distribution<double> u(-1, 1);
  std::uniform_int_distribution<int> turn(0, 3), poseKind(0, 2);
  const int cases = crux::test::scaledCases(240, 60);
  int zero = 0;
  for (int c = 0; c < cases; ++c) {
    const double scale = c % 3 == 0 ? 1e-3 : (c % 3 == 1 ? 1.0 : 1e3);
    const double sizeB = scale * (c % 4 == 0 ? 0.02 : 1.0);  // a tiny mesh against a big one
    const Mesh a = degenerateSoup(rng, 40, scale, Eigen::Vector3d::Zero());
    const Mesh b = degenerateSoup(rng, 30, sizeB, Eigen::Vector3d::Zero());
    Transform tb;
    switch (poseKind(rng)) {
      case 0: tb = randomPose(rng, 1.5); break;
      case 1:
        tb.rotation = quatFromEulerDegrees(Real(90 * turn(rng)), 0, Real(90 * turn(rng)));
        tb.translation = Vec3(Real(u(rng)), Real(u(rng)), Real(u(rng)));
        break;
      default: tb = randomPose(rng, 0.3);
    }
    tb.translation *= Real(scale);
    const std::string what = "case " + std::to_string(c) + " scale " + std::to_string(scale) + " tb " + show(tb);
    MeshDistanceOptions brute;
    brute.path = QueryPath::BruteForce;
    const MeshMeshDistanceResult ref = distance(a, Transform::identity(), b, tb, brute);
    ASSERT_TRUE(ref.found) << what;
    const MeshQueryData accA(a, MeshQueryParts::Distance), accB(b, MeshQueryParts::Distance);
    for (int k = 0; k < 4; ++k) {
      MeshDistanceOptions o;
      o.dataA = (k & 1) ? &accA : nullptr;
      o.dataB = (k & 2) ? &accB : nullptr;
      const MeshMeshDistanceResult r = distance(a, Transform::identity(), b, tb, o);
      ASSERT_TRUE(r.found) << what << " accelerators " << k;
      EXPECT_EQ(r.distance, ref.distance) << std::setprecision(17) << what << " accelerators " << k << " bvh "
                                          << r.distance << " brute " << ref.distance;
      // maxDistance exactly at the answer still finds it (the bounds are inclusive).
      o.maxDistance = ref.distance;
      EXPECT_TRUE(distance(a, Transform::identity(), b, tb, o).found) << what << " accelerators " << k;
    }
    if (ref.distance == 0) ++zero;
  }
  std::printf("degenerate soups: %d of %d touching\n", zero, cases);
}

TEST(MeshDistance, AcceleratedIntegerGridsTouchExactlyWhenTheyOverlap) {
  // The integer-grid quarter-turn family with accelerators on both sides: distance 0 exactly when
  // the exact overlap test says so, and equal to brute force.
  Rng rng(19);
  std::uniform_int_distribution<int> g(-3, 3), turn(0, 3);
  int zero = 0;
  const int cases = crux::test::scaledCases(600, 150);
  for (int c = 0; c < cases; ++c) {
    const Mesh a = gridSoup(rng, 12), b = gridSoup(rng, 12);
    const MeshQueryData accA(a, MeshQueryParts::Distance), accB(b, MeshQueryParts::Distance);
    Transform tb;
    tb.rotation = quatFromEulerDegrees(Real(90 * turn(rng)), 0, Real(90 * turn(rng)));
    tb.translation = Vec3(Real(g(rng) * 2), Real(g(rng) * 2), Real(g(rng) * 2));
    MeshDistanceOptions o, brute;
    o.dataA = &accA;
    o.dataB = &accB;
    brute.path = QueryPath::BruteForce;
    const MeshMeshDistanceResult r = distance(a, Transform::identity(), b, tb, o);
    EXPECT_EQ(r.distance == 0, overlaps(a, Transform::identity(), b, tb)) << "case " << c << " tb " << show(tb);
    EXPECT_EQ(r.distance, distance(a, Transform::identity(), b, tb, brute).distance) << "case " << c << " tb " << show(tb);
    zero += r.distance == 0;
  }
  EXPECT_GT(zero, cases / 10);
  EXPECT_LT(zero, cases - cases / 10);
}

TEST(MeshDistance, ModelDistanceUsesWorldTransforms) {
  Rng rng(15);
  const auto a = test::bumpySphere(6, 8), b = test::bumpySphere(5, 7);
  for (int c = 0; c < 20; ++c) {
    const Transform ta = randomPose(rng, 3), tb = randomPose(rng, 3);
    const MeshMeshDistanceResult m = distance(PlacedMesh{a.get(), ta}, PlacedMesh{b.get(), tb});
    MeshDistanceOptions brute;
    brute.path = QueryPath::BruteForce;
    const MeshMeshDistanceResult ref = distance(*a, ta, *b, tb, brute);
    const double scale = scaleOf(*a, *b, ta, tb);
    EXPECT_NEAR(double(m.distance), double(ref.distance), kMapUlps * scale + kRelative * double(ref.distance));
    checkPoints(*a, ta, *b, tb, m, 4 * kMapUlps * scale, "model case " + std::to_string(c));
  }
}

TEST(MeshDistance, InvalidOptionsThrowNamingTheField) {
  const auto a = test::bumpySphere(3, 4);
  MeshDistanceOptions o;
  o.maxDistance = std::numeric_limits<Real>::quiet_NaN();
  try {
    distance(*a, Transform::identity(), *a, Transform::identity(), o);
    FAIL() << "no throw";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("maxDistance"), std::string::npos) << e.what();
  }
  o = {};
  o.stopDistance = -1;
  try {
    distance(*a, Transform::identity(), *a, Transform::identity(), o);
    FAIL() << "no throw";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("stopDistance"), std::string::npos) << e.what();
  }
  const auto other = test::bumpySphere(5, 6);
  const MeshQueryData foreign(*other, MeshQueryParts::Distance);
  o = {};
  o.dataB = &foreign;
  try {
    distance(*a, Transform::identity(), *a, Transform::identity(), o);
    FAIL() << "no throw";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("dataB"), std::string::npos) << e.what();
  }
}

// Caller-held query data records the mesh's geometry id: after setVertices (same counts, new
// positions) the query refuses it, naming the field and the mesh, instead of reading the old
// corners (it answered 2, the distance of the old positions, where the truth is sqrt(85)). A copy
// of the mesh shares the id, and data refreshed after the move gives the brute-force answer.
TEST(MeshDistance, QueryDataBuiltBeforeSetVerticesIsRefusedNamingTheFieldAndMeshUntilRefreshed) {
  const std::vector<Vec3> v{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  const std::vector<TriangleIndices> t{{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  Mesh a(v, t, "a");
  const Mesh b(v, t, "b");
  const MeshQueryData accA(a, MeshQueryParts::Distance), accB(b, MeshQueryParts::Distance);
  Transform ta, tb;
  tb.translation = Vec3(3, 0, 0);
  MeshDistanceOptions o;
  o.dataA = &accA, o.dataB = &accB;
  EXPECT_EQ(distance(a, ta, b, tb, o).distance, 2);
  const Mesh copy = a;  // shares the geometry id: the accelerator serves it
  EXPECT_EQ(distance(copy, ta, b, tb, o).distance, 2);
  std::vector<Vec3> moved = v;
  for (Vec3& p : moved) p += Vec3(0, 0, 10);
  a.setVertices(moved);
  MeshDistanceOptions brute;
  brute.path = QueryPath::BruteForce;
  const Real truth = distance(a, ta, b, tb, brute).distance;
  EXPECT_NEAR(truth, std::sqrt(Real(85)), 1e-4);  // a's corner (1,0,10) to b's (3,0,1)
  try {
    distance(a, ta, b, tb, o);
    FAIL() << "stale query data was accepted";
  } catch (const InvalidInput& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("dataA"), std::string::npos) << m;
    EXPECT_NE(m.find("stale"), std::string::npos) << m;
    EXPECT_NE(m.find("\"a\""), std::string::npos) << m;
  }
  // as mesh b of the query (the other field)
  MeshDistanceOptions swapped;
  swapped.dataB = &accA;
  EXPECT_THROW(distance(b, tb, a, ta, swapped), InvalidInput);
  // the old data still serves the unmoved copy; refreshed, it serves the moved mesh
  EXPECT_EQ(distance(copy, ta, b, tb, o).distance, 2);
  MeshQueryData refreshed = accA;
  EXPECT_TRUE(refreshed.refresh(a));
  o.dataA = &refreshed;
  EXPECT_EQ(distance(a, ta, b, tb, o).distance, truth);
  EXPECT_THROW(distance(copy, ta, b, tb, o), InvalidInput);
  EXPECT_EQ(distance(a, ta, b, tb).distance, truth);
}

TEST(MeshDistance, IdenticalPosesGiveZeroAndFarMeshesNotFound) {
  const auto a = test::bumpySphere(6, 8);
  EXPECT_EQ(distance(*a, Transform::identity(), *a, Transform::identity()).distance, 0);
  Transform far;
  far.translation = Vec3(100, 0, 0);
  MeshDistanceOptions o;
  o.maxDistance = 10;
  EXPECT_FALSE(distance(*a, Transform::identity(), *a, far, o).found);
}

TEST(MeshDistance, ForeignQueryDataWithTheSameNodeCountButOtherTrianglesIsRefused) {
  // The node counts agree (one leaf each), only the triangle counts differ: the data's corner
  // copy would be read past its end. Refused (another geometry) naming the data's field.
  const Mesh one({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)}, {{0, 1, 2}}, "one");
  const Mesh quad({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)}, {{0, 1, 2}, {0, 2, 3}}, "quad");
  ASSERT_EQ(one.bvh().nodes.size(), quad.bvh().nodes.size()) << "the case needs equal node counts";
  ASSERT_NE(one.triangleCount(), quad.triangleCount());
  const MeshQueryData accelQuad(quad, MeshQueryParts::Distance), accelOne(one, MeshQueryParts::Distance);
  Transform apart;
  apart.translation = Vec3(0, 0, 2);
  for (const bool sideA : {true, false}) {
    MeshDistanceOptions o;
    (sideA ? o.dataA : o.dataB) = &accelQuad;
    try {
      distance(one, Transform::identity(), one, apart, o);
      FAIL() << "no throw, side " << (sideA ? "a" : "b");
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(sideA ? "dataA" : "dataB"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("stale"), std::string::npos) << e.what();
    }
  }
  // Data without the distance part is refused too, naming the missing part.
  const MeshQueryData contactsOnly(one, MeshQueryParts::Contacts);
  MeshDistanceOptions partless;
  partless.dataA = &contactsOnly;
  try {
    distance(one, Transform::identity(), one, apart, partless);
    FAIL() << "no throw for data without the distance part";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("distance part"), std::string::npos) << e.what();
  }
  // The matching data are accepted and give the brute-force answer.
  MeshDistanceOptions own;
  own.dataA = &accelOne, own.dataB = &accelQuad;
  MeshDistanceOptions brute;
  brute.path = QueryPath::BruteForce;
  EXPECT_EQ(distance(one, Transform::identity(), quad, apart, own).distance,
            distance(one, Transform::identity(), quad, apart, brute).distance);
}

/// A straightforward scalar evaluation of mesh_detail::obbPairOffsets for pair l, in the order
/// its documentation states.
void referenceOffsets(const MeshDistanceAccel::Node& A, const MeshDistanceAccel::Node& B, const Mat3& R, const Vec3& t,
                      Real keep, Real pad, Real (&d)[3], Real (&e)[3], Real (&dA)[3], Real (&dB)[3], Real& len2,
                      Real& extent, Real& bound) {
  Real u[3];
  for (int r = 0; r < 3; ++r) {
    const Real w = R(r, 0) * B.center[0] + R(r, 1) * B.center[1] + R(r, 2) * B.center[2];
    d[r] = (w + t[r]) - A.center[r];
    u[r] = t[r] - A.center[r];
  }
  for (int c = 0; c < 3; ++c) e[c] = B.center[c] + (R(0, c) * u[0] + R(1, c) * u[1] + R(2, c) * u[2]);
  for (int c = 0; c < 3; ++c) {
    dA[c] = A.axes(0, c) * d[0] + A.axes(1, c) * d[1] + A.axes(2, c) * d[2];
    dB[c] = B.axes(0, c) * e[0] + B.axes(1, c) * e[1] + B.axes(2, c) * e[2];
  }
  len2 = dA[0] * dA[0] + dA[1] * dA[1] + dA[2] * dA[2];
  const Real radiusA = A.half[0] * std::abs(dA[0]) + A.half[1] * std::abs(dA[1]) + A.half[2] * std::abs(dA[2]);
  const Real radiusB = B.half[0] * std::abs(dB[0]) + B.half[1] * std::abs(dB[1]) + B.half[2] * std::abs(dB[2]);
  extent = radiusA + radiusB;
  const Real len = std::sqrt(len2);
  if (len2 - extent > keep * len) bound = std::numeric_limits<Real>::infinity();
  else if (!(len2 > 0)) bound = -std::numeric_limits<Real>::infinity();
  else bound = (len - extent / len) - pad;
}

TEST(MeshDistance, BatchedNodePairOffsetsAreBitIdenticalToAScalarEvaluation) {
  // The SIMD routine behind the accelerated query's first node-pair bound, against the
  // documented formula evaluated one pair at a time: random node quadruples of a real mesh's
  // accelerator (inner nodes and leaves, repeated lanes, one side's node in all four lanes, a node
  // against itself at the identity: d = 0), random rotations (and quarter turns), translations and limits, including limits
  // that prune some lanes and none.
  const Mesh blob = loadMesh(std::string(CRUX_SOURCE_DIR) + "/data/meshes/blob.off");
  const MeshDistanceAccel acc(blob);
  const auto& nodes = acc.nodes();
  Rng rng(2026);
  std::uniform_int_distribution<std::size_t> pick(0, nodes.size() - 1);
  std::uniform_real_distribution<double> u(-1, 1), lim(0, 0.6);
  std::normal_distribution<double> g;
  const int cases = crux::test::scaledCases(20000, 2000);
  int pruned = 0, kept = 0, zero = 0;
  auto bits = [](Real x) {
    std::uint64_t v = 0;
    std::memcpy(&v, &x, sizeof x);
    return v;
  };
  for (int c = 0; c < cases; ++c) {
    const MeshDistanceAccel::Node* a[4];
    const MeshDistanceAccel::Node* b[4];
    for (int l = 0; l < 4; ++l) a[l] = &nodes[pick(rng)], b[l] = &nodes[pick(rng)];
    if (c % 7 == 0) a[2] = a[0], b[3] = b[1];  // repeated lanes, as a 2-pair expansion has
    // one side a single node in every lane (the unsplit side of an expansion: broadcast)
    if (c % 3 == 1) b[1] = b[2] = b[3] = b[0];
    if (c % 3 == 2) a[1] = a[2] = a[3] = a[0];
    Transform tr;
    if (c % 11 == 0) {
      tr.rotation = Quat(Eigen::AngleAxis<Real>(Real(M_PI / 2), Vec3::UnitZ()));
    } else {
      tr.rotation = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().cast<Real>();
    }
    tr.translation = Vec3(Real(u(rng)), Real(u(rng)), Real(u(rng)));
    Mat3 R = tr.rotation.toRotationMatrix();
    Vec3 t = tr.translation;
    if (c % 13 == 0) R = Mat3::Identity(), t = Vec3::Zero(), b[1] = a[1];  // lane 1: d = 0
    const Real keep = c % 5 == 0 ? std::numeric_limits<Real>::infinity() : Real(lim(rng));
    const Real pad = Real(1e-6);
    mesh_detail::ObbPairOffsets o;
    mesh_detail::obbPairOffsets(a, b, R, t, keep, pad, o);
    for (int l = 0; l < 4; ++l) {
      Real d[3], e[3], dA[3], dB[3], len2, extent, bound;
      referenceOffsets(*a[l], *b[l], R, t, keep, pad, d, e, dA, dB, len2, extent, bound);
      std::ostringstream what;
      what << std::setprecision(17) << "case " << c << " lane " << l << " nodes " << (a[l] - nodes.data()) << ", "
           << (b[l] - nodes.data()) << " R " << R.reshaped().transpose() << " t " << t.transpose() << " keep " << keep;
      for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(bits(o.d[k][l]), bits(d[k])) << what.str() << " d" << k << " " << o.d[k][l] << " vs " << d[k];
        EXPECT_EQ(bits(o.e[k][l]), bits(e[k])) << what.str() << " e" << k << " " << o.e[k][l] << " vs " << e[k];
        EXPECT_EQ(bits(o.dA[k][l]), bits(dA[k])) << what.str() << " dA" << k << " " << o.dA[k][l] << " vs " << dA[k];
        EXPECT_EQ(bits(o.dB[k][l]), bits(dB[k])) << what.str() << " dB" << k << " " << o.dB[k][l] << " vs " << dB[k];
      }
      EXPECT_EQ(bits(o.len2[l]), bits(len2)) << what.str() << " len2 " << o.len2[l] << " vs " << len2;
      EXPECT_EQ(bits(o.extent[l]), bits(extent)) << what.str() << " extent " << o.extent[l] << " vs " << extent;
      ASSERT_EQ(bits(o.bound[l]), bits(bound)) << what.str() << " bound " << o.bound[l] << " vs " << bound;
      if (bound == std::numeric_limits<Real>::infinity()) ++pruned;
      else if (bound == -std::numeric_limits<Real>::infinity()) ++zero;
      else ++kept;
    }
  }
  std::printf("batched offsets: %d lanes pruned, %d bounded, %d at zero offset\n", pruned, kept, zero);
  EXPECT_GT(pruned, cases / 2);
  EXPECT_GT(kept, cases / 2);
  EXPECT_GT(zero, 0);
}

}  // namespace
TEST(MeshDistance, AcceleratorLayoutMirrorsTheBvhAndTheMesh) {
  // The query with accelerators on both sides reads only the accelerator: its child links, leaf
  // ranges and corner copy must be the BVH's and the mesh's exactly, and every subtree's box
  // must hold the corners under it (else pairs would be pruned or triangles misread).
  const Mesh blob = loadMesh(std::string(CRUX_SOURCE_DIR) + "/data/meshes/blob.off");
  const MeshDistanceAccel acc(blob);
  const WideBvh& bvh = blob.bvh();
  const std::size_t ids = wideSubtreeCount(bvh.nodes.size());
  ASSERT_EQ(acc.nodes().size(), ids);
  ASSERT_EQ(acc.leafRanges().size(), ids);
  ASSERT_EQ(acc.corners().size(), 3 * blob.triangleCount());
  if (sizeof(Real) == 4) EXPECT_EQ(sizeof(MeshDistanceAccel::Node), 64u);
  for (std::uint32_t k = 0; k < blob.triangleCount(); ++k) {
    const Triangle t = blob.slotTriangle(k);
    EXPECT_EQ(acc.corners()[3 * k], t.a) << "slot " << k;
    EXPECT_EQ(acc.corners()[3 * k + 1], t.b) << "slot " << k;
    EXPECT_EQ(acc.corners()[3 * k + 2], t.c) << "slot " << k;
  }
  const double scale = double(blob.scale());
  // The slots under subtree id (its leaves' ranges, collected by walking the tree).
  auto slotsUnder = [&](std::uint32_t id) {
    std::vector<std::uint32_t> slots, stack{id};
    while (!stack.empty()) {
      const WideSubtree sub = wideSubtree(bvh, stack.back());
      stack.pop_back();
      if (sub.isLeaf()) {
        for (std::uint32_t k = sub.first; k < sub.first + sub.count; ++k) slots.push_back(k);
      } else {
        for (int l = 0; l < 4; ++l)
          if (bvh.nodes[sub.first].used(l)) stack.push_back(wideLaneId(sub.first, l));
      }
    }
    return slots;
  };
  std::size_t unused = 0;
  for (std::uint32_t id = 0; id < ids; ++id) {
    const MeshDistanceAccel::Node& box = acc.nodes()[id];
    if (id != 0 && !bvh.nodes[(id - 1) / 4].used(int((id - 1) % 4))) {
      EXPECT_EQ(box.child, MeshDistanceAccel::kUnused) << "subtree " << id;
      ++unused;
      continue;
    }
    const WideSubtree sub = wideSubtree(bvh, id);
    if (sub.isLeaf()) {
      EXPECT_EQ(box.child, MeshDistanceAccel::kLeaf) << "subtree " << id;
      EXPECT_EQ(acc.leafRanges()[id].first, sub.first) << "subtree " << id;
      EXPECT_EQ(acc.leafRanges()[id].count, sub.count) << "subtree " << id;
    } else {
      EXPECT_EQ(box.child, sub.first) << "subtree " << id;
    }
    for (const std::uint32_t k : slotsUnder(id))
      for (const Vec3& p : {acc.corners()[3 * k], acc.corners()[3 * k + 1], acc.corners()[3 * k + 2]}) {
        const Eigen::Vector3d q = box.axes.cast<double>().transpose() * (p - box.center).cast<double>();
        // The query pads every bound by 64 ulps × scale: the box may miss a corner by less.
        const Eigen::Vector3d slack =
            box.half.cast<double>().array() + 64 * double(std::numeric_limits<Real>::epsilon()) * scale;
        EXPECT_TRUE((q.cwiseAbs().array() <= slack.array()).all())
            << "subtree " << id << " slot " << k << " local " << q.transpose() << " half " << box.half.transpose();
      }
  }
  EXPECT_LT(unused, ids / 2) << "most lanes are used";
}

namespace {


// Non-queryable poses (precondition.hpp): nothing found, never UB.
TEST(MeshDistancePreconditions, NonQueryablePosesFindNothing) {
  if (CRUX_CHECK_PRECONDITIONS) GTEST_SKIP() << "this build aborts instead (precondition.hpp)";
  const Mesh mesh({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)}, {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
  for (const Transform& pose : test_support::badPoses()) {
    EXPECT_FALSE(distance(mesh, Transform{}, mesh, pose, MeshDistanceOptions{}).found);
    EXPECT_FALSE(distance(mesh, pose, mesh, Transform{}, MeshDistanceOptions{}).found);
  }
  EXPECT_TRUE(distance(mesh, Transform{}, mesh, Transform{}, MeshDistanceOptions{}).found);
}

}  // namespace
}  // namespace crux
