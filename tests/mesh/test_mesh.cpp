// Tests of crux::Mesh (src/mesh/mesh.cpp): validation, MeshStats, setVertices + refit, memory.
#include <crux/mesh/mesh.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

#if __has_include(<CGAL/Exact_predicates_inexact_constructions_kernel.h>)
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include "support/invalid_input.hpp"
#define CRUX_TEST_HAVE_CGAL 1
#endif

namespace crux {
namespace {

using test_support::invalidInputMessage;

bool startsWith(const std::string& s, const std::string& prefix) { return s.rfind(prefix, 0) == 0; }
bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

/// Cube [-1,1]^3: vertex i has x = bit 0, y = bit 1, z = bit 2 (0 -> -1, 1 -> +1); faces wound
/// counter-clockwise seen from outside.
std::vector<Vec3> cubeVertices() {
  std::vector<Vec3> v;
  for (int i = 0; i < 8; ++i) v.emplace_back((i & 1) ? 1 : -1, (i & 2) ? 1 : -1, (i & 4) ? 1 : -1);
  return v;
}
std::vector<TriangleIndices> cubeTriangles() {
  return {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
          {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
}

/// An n x n grid of unit squares in the z = 0 plane, two triangles each.
Mesh gridMesh(int n) {
  std::vector<Vec3> v;
  std::vector<TriangleIndices> t;
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) v.emplace_back(Real(x), Real(y), 0);
  auto id = [n](int x, int y) { return std::uint32_t(y * (n + 1) + x); };
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      t.push_back({id(x, y), id(x + 1, y), id(x + 1, y + 1)});
      t.push_back({id(x, y), id(x + 1, y + 1), id(x, y + 1)});
    }
  return Mesh(std::move(v), std::move(t), "grid");
}

Aabb boundsOf(const std::vector<Vec3>& v) {
  Aabb b = Aabb::empty();
  for (const Vec3& p : v) b.grow(p);
  return b;
}

bool sameBox(const Aabb& a, const Aabb& b) { return a.min == b.min && a.max == b.max; }

/// Every lane's box is exactly the union of its node's lanes (inner) or its triangles' (leaf)
/// boxes, every triangle is referenced once, and the mesh's bounds are the root lanes' union.
void expectBvhFitsMesh(const Mesh& mesh) {
  const WideBvh& bvh = mesh.bvh();
  ASSERT_FALSE(bvh.empty());
  std::vector<int> referenced(mesh.triangleCount(), 0);
  for (std::size_t i = 0; i < bvh.nodes.size(); ++i) {
    const WideBvhNode& node = bvh.nodes[i];
    for (int lane = 0; lane < 4; ++lane) {
      if (!node.used(lane)) continue;
      Aabb expected = Aabb::empty();
      if (node.count[lane] > 0) {
        for (std::uint32_t k = node.child[lane]; k < node.child[lane] + node.count[lane]; ++k) {
          const std::uint32_t prim = bvh.primIndices[k];
          ++referenced[prim];
          expected.grow(bounds(mesh.triangle(prim)));
        }
      } else {
        const WideBvhNode& child = bvh.nodes[node.child[lane]];
        for (int c = 0; c < 4; ++c)
          if (child.used(c)) expected.grow(child.laneBounds(c));
      }
      EXPECT_TRUE(sameBox(node.laneBounds(lane), expected)) << "node " << i << " lane " << lane;
    }
  }
  for (std::size_t i = 0; i < referenced.size(); ++i) EXPECT_EQ(referenced[i], 1) << "triangle " << i;
  EXPECT_TRUE(sameBox(mesh.bounds(), wideSubtreeBounds(bvh, 0)));
  EXPECT_EQ(mesh.scale(), std::max(mesh.bounds().min.cwiseAbs().maxCoeff(), mesh.bounds().max.cwiseAbs().maxCoeff()));
}

// ---- validation ------------------------------------------------------------------------------

TEST(MeshValidation, MeshWithoutTrianglesIsRejected) {
  const std::string m1 = invalidInputMessage([] { Mesh({}, {}, "empty"); });
  EXPECT_TRUE(startsWith(m1, "empty: ")) << m1;
  EXPECT_TRUE(contains(m1, "no triangles")) << m1;
  const std::string m2 = invalidInputMessage([] { Mesh(cubeVertices(), {}, "verticesOnly"); });
  EXPECT_TRUE(startsWith(m2, "verticesOnly: ")) << m2;
  EXPECT_TRUE(contains(m2, "no triangles")) << m2;
}

TEST(MeshValidation, MeshWithoutVerticesIsRejected) {
  const std::string m = invalidInputMessage([] { Mesh({}, {{0, 1, 2}}, "trianglesOnly"); });
  EXPECT_TRUE(startsWith(m, "trianglesOnly: ")) << m;
  EXPECT_TRUE(contains(m, "no vertices")) << m;
}

TEST(MeshValidation, IndexOutOfRangeNamesTriangleAndIndex) {
  std::vector<TriangleIndices> t = cubeTriangles();
  t[7] = {2, 8, 3};  // 8 vertices: index 8 is one past the end
  const std::string m = invalidInputMessage([&] { Mesh(cubeVertices(), t, "cube"); });
  EXPECT_TRUE(startsWith(m, "cube: ")) << m;
  EXPECT_TRUE(contains(m, "triangle 7 ")) << m;
  EXPECT_TRUE(contains(m, "index 8")) << m;

  t[7] = {2, 7, std::numeric_limits<std::uint32_t>::max()};
  const std::string m2 = invalidInputMessage([&] { Mesh(cubeVertices(), t, "cube"); });
  EXPECT_TRUE(contains(m2, "triangle 7 ")) << m2;
  EXPECT_TRUE(contains(m2, std::to_string(std::numeric_limits<std::uint32_t>::max()))) << m2;
}

TEST(MeshValidation, NonFiniteVertexIsNamed) {
  const Real values[] = {std::numeric_limits<Real>::quiet_NaN(), std::numeric_limits<Real>::infinity(),
                         -std::numeric_limits<Real>::infinity()};
  for (const Real bad : values)
    for (int axis = 0; axis < 3; ++axis) {
      std::vector<Vec3> v = cubeVertices();
      v[5][axis] = bad;
      const std::string m = invalidInputMessage([&] { Mesh(v, cubeTriangles(), "cube"); });
      EXPECT_TRUE(startsWith(m, "cube: ")) << m;
      EXPECT_TRUE(contains(m, "vertex 5 ")) << m;
      EXPECT_TRUE(contains(m, "non-finite")) << m;
    }
}

TEST(MeshValidation, BadBvhOptionsAreReportedWithTheMeshName) {
  BvhBuildOptions options;
  options.maxLeafSize = 0;
  const std::string m = invalidInputMessage([&] { Mesh(cubeVertices(), cubeTriangles(), "cube", options); });
  EXPECT_TRUE(startsWith(m, "cube: ")) << m;
}

TEST(MeshValidation, UnreferencedVerticesAreAllowed) {
  std::vector<Vec3> v = cubeVertices();
  v.emplace_back(100, 100, 100);  // used by no triangle
  const Mesh mesh(v, cubeTriangles(), "cube");
  EXPECT_EQ(mesh.vertexCount(), 9u);
  // The BVH covers the triangles; the stray vertex is not part of the surface.
  EXPECT_TRUE(sameBox(mesh.bounds(), boundsOf(cubeVertices())));
}

// ---- stats -------------------------------------------------------------------------------------

TEST(MeshStats, ClosedCubeHasNoBoundaryEdges) {
  const Mesh mesh(cubeVertices(), cubeTriangles(), "cube");
  const MeshStats s = mesh.stats();
  EXPECT_EQ(s.triangles, 12u);
  EXPECT_EQ(s.vertices, 8u);
  EXPECT_EQ(s.edges.boundaryEdges, 0u);
  EXPECT_EQ(s.edges.nonManifoldEdges, 0u);
  EXPECT_EQ(s.degenerateTriangles, 0u);
  EXPECT_EQ(s.duplicateTriangles, 0u);
  EXPECT_TRUE(s.closed());
  EXPECT_TRUE(sameBox(s.bounds, Aabb{Vec3::Constant(-1), Vec3::Constant(1)}));
  EXPECT_TRUE(sameBox(mesh.bounds(), s.bounds));
}

TEST(MeshStats, CubeMissingOneFaceHasFourBoundaryEdges) {
  std::vector<TriangleIndices> t = cubeTriangles();
  t.erase(t.begin(), t.begin() + 2);  // the z = -1 face
  const MeshStats s = Mesh(cubeVertices(), t, "open cube").stats();
  EXPECT_EQ(s.edges.boundaryEdges, 4u);
  EXPECT_EQ(s.edges.nonManifoldEdges, 0u);
  EXPECT_FALSE(s.closed());
}

TEST(MeshStats, OpenQuadHasFourBoundaryEdges) {
  const std::vector<Vec3> v = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  const MeshStats s = Mesh(v, {{0, 1, 2}, {0, 2, 3}}, "quad").stats();
  EXPECT_EQ(s.triangles, 2u);
  EXPECT_EQ(s.edges.boundaryEdges, 4u);  // the diagonal 0-2 is shared
  EXPECT_EQ(s.edges.nonManifoldEdges, 0u);
  EXPECT_FALSE(s.closed());
}

TEST(MeshStats, NonManifoldFanOfThreeTrianglesOnOneEdge) {
  // Three fins on the edge (0,0,0)-(0,0,1).
  const std::vector<Vec3> v = {{0, 0, 0}, {0, 0, 1}, {1, 0, 0}, {0, 1, 0}, {-1, -1, 0}};
  const MeshStats s = Mesh(v, {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}}, "fan").stats();
  EXPECT_EQ(s.edges.nonManifoldEdges, 1u);
  EXPECT_EQ(s.edges.boundaryEdges, 6u);
  EXPECT_FALSE(s.closed());
}

TEST(MeshStats, ClosedCubeWithADuplicatedTriangleIsNotClosed) {
  std::vector<TriangleIndices> t = cubeTriangles();
  t.push_back({3, 0, 2});  // triangle 0 again, rotated
  const MeshStats s = Mesh(cubeVertices(), t, "cube").stats();
  EXPECT_EQ(s.duplicateTriangles, 1u);
  EXPECT_EQ(s.edges.nonManifoldEdges, 3u);  // its three edges now have three triangles each
  EXPECT_FALSE(s.closed());
}

TEST(MeshStats, DegenerateAndDuplicateTrianglesAreCounted) {
  const std::vector<Vec3> v = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0},  // collinear
                               {0, 1, 0}, {5, 5, 5}, {5, 5, 5}, {5, 5, 5}};
  const std::vector<TriangleIndices> t = {
      {0, 1, 3},  // proper
      {0, 1, 2},  // collinear corners: a segment
      {3, 3, 1},  // repeated index: a segment
      {4, 5, 6},  // three distinct indices at one position: a point
      {1, 3, 0},  // duplicate of triangle 0 (rotated)
      {3, 1, 0},  // duplicate of triangle 0 (reversed winding)
      {3, 1, 3},  // duplicate of triangle 2
  };
  const MeshStats s = Mesh(v, t, "degenerate").stats();
  EXPECT_EQ(s.degenerateTriangles, 4u);  // 1, 2, 3 and 6
  EXPECT_EQ(s.duplicateTriangles, 3u);   // 4, 5 and 6
}

TEST(MeshStats, TrianglesRepeatingAnIndexSpanNoSurfaceAndCloseNothing) {
  // Only repeated-index triangles (a segment and a point): no edge is left open, but there is no
  // surface either. Not closed, as MeshVolume refuses it.
  const std::vector<Vec3> v = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const Mesh mesh(v, {{0, 0, 1}, {2, 2, 2}}, "collapsed");
  const MeshStats s = mesh.stats();
  EXPECT_EQ(s.edges.effectiveTriangles, 0u);
  EXPECT_EQ(s.edges.skippedTriangles, 2u);
  EXPECT_EQ(s.edges.boundaryEdges, 0u);
  EXPECT_FALSE(s.closed());
  EXPECT_FALSE(isClosed(mesh));
  // Added to a closed cube, (0, 0, 1) on the cube's edge 0-1 is skipped: the cube stays closed.
  std::vector<TriangleIndices> t = cubeTriangles();
  t.push_back({t[0][0], t[0][0], t[0][1]});
  const MeshStats cube = Mesh(cubeVertices(), t, "cube").stats();
  EXPECT_EQ(cube.edges.nonManifoldEdges, 0u);
  EXPECT_TRUE(cube.closed());
}

TEST(MeshStats, InconsistentlyOrientedCubeIsNotClosed) {
  std::vector<TriangleIndices> t = cubeTriangles();
  std::swap(t[0][1], t[0][2]);  // one triangle flipped: its three edges are used twice in one direction
  const MeshStats s = Mesh(cubeVertices(), t, "flipped").stats();
  EXPECT_EQ(s.edges.boundaryEdges, 0u);
  EXPECT_EQ(s.edges.nonManifoldEdges, 0u);
  EXPECT_EQ(s.edges.inconsistentEdges, 3u);
  EXPECT_FALSE(s.closed());
}

TEST(MeshStats, NearlyCollinearTriangleIsNotDegenerate) {
  // One ulp off the line: the cross product is tiny but not zero.
  const Real two = 2;
  const Vec3 c(2, 2, std::nextafter(two, Real(3)));
  const MeshStats s = Mesh({{0, 0, 0}, {1, 1, 1}, c}, {{0, 1, 2}}, "sliver").stats();
  EXPECT_EQ(s.degenerateTriangles, 0u);
  const MeshStats exact = Mesh({{0, 0, 0}, {1, 1, 1}, {2, 2, 2}}, {{0, 1, 2}}, "segment").stats();
  EXPECT_EQ(exact.degenerateTriangles, 1u);
}

TEST(MeshStats, CancellationInTheCrossProductIsResolvedExactly) {
  // z of (b-a)×(c-a) = bx·cy - by·cx = (1+e)(1+e) - 1·(1+2e) = e² with e = 2^-(p-1) one ulp
  // of 1: naive double evaluation rounds (1+e)² to 1+2e in double builds and gets 0.
  const Real e = std::numeric_limits<Real>::epsilon();
  const Vec3 b(1 + e, 1, 0), c(1 + 2 * e, 1 + e, 0);
  const MeshStats s = Mesh({{0, 0, 0}, b, c}, {{0, 1, 2}}, "sliver").stats();
  EXPECT_EQ(s.degenerateTriangles, 0u);
}

#ifdef CRUX_TEST_HAVE_CGAL
/// The exact oracle: CGAL's exact collinearity predicate on the exactly converted corners.
bool cgalCollinear(const Vec3& a, const Vec3& b, const Vec3& c) {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  auto p = [](const Vec3& v) { return K::Point_3(double(v.x()), double(v.y()), double(v.z())); };
  return CGAL::collinear(p(a), p(b), p(c));
}

std::string describe(const Vec3& a, const Vec3& b, const Vec3& c) {
  char buf[512];
  std::snprintf(buf, sizeof buf, "a=(%.17g, %.17g, %.17g) b=(%.17g, %.17g, %.17g) c=(%.17g, %.17g, %.17g)",
                double(a.x()), double(a.y()), double(a.z()), double(b.x()), double(b.y()), double(b.z()), double(c.x()),
                double(c.y()), double(c.z()));
  return buf;
}

/// Triangles a, a + i·d, a + j·d (collinear, often with repeated corners), then with
/// probability 1/2 one coordinate of the third corner moved by `nudge`. Asserts that the
/// construction is exact in Real, then compares stats().degenerateTriangles, one triangle at a
/// time, with CGAL.
template <class Coordinate, class Direction, class Nudge>
void compareDegenerateCountWithCgal(std::uint64_t seed, int cases, Coordinate coordinate, Direction direction,
                                    Nudge nudge) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> step(-3, 3), axis(0, 2), coin(0, 1);
  int degenerate = 0;
  for (int n = 0; n < cases; ++n) {
    WVec3 a, d;
    for (int k = 0; k < 3; ++k) a[k] = coordinate(rng), d[k] = direction(rng);
    const Wide i = step(rng), j = step(rng);
    const WVec3 wb = a + i * d, wc = a + j * d;
    const Vec3 pa = a.cast<Real>(), pb = wb.cast<Real>();
    Vec3 pc = wc.cast<Real>();
    ASSERT_TRUE(pa.cast<Wide>() == a && pb.cast<Wide>() == wb && pc.cast<Wide>() == wc)
        << "generator not exact in Real: " << describe(pa, pb, pc);
    if (coin(rng)) {
      const int k = axis(rng);
      pc[k] = nudge(pc[k], rng);
    }
    const bool expected = cgalCollinear(pa, pb, pc);
    degenerate += expected;
    const MeshStats s = Mesh({pa, pb, pc}, {{0, 1, 2}}, "case").stats();
    ASSERT_EQ(s.degenerateTriangles, expected ? 1u : 0u) << "case " << n << ": " << describe(pa, pb, pc);
  }
  const double rate = double(degenerate) / cases;
  std::printf("seed %llu: %d cases, %.2f%% degenerate\n", static_cast<unsigned long long>(seed), cases, 100 * rate);
  EXPECT_GE(rate, 0.2);
  EXPECT_LE(rate, 0.8);
}

TEST(MeshStatsProperty, DegenerateCountMatchesCgalOnIntegerGrid) {
  // |coordinates| <= 32 + 3·8 + 1 <= 64; the nudge is one unit.
  std::uniform_int_distribution<int> grid(-32, 32), step(-8, 8);
  compareDegenerateCountWithCgal(
      0x5eed0001, 100000, [&](std::mt19937_64& rng) { return Wide(grid(rng)); },
      [&](std::mt19937_64& rng) { return Wide(step(rng)); },
      [](Real x, std::mt19937_64& rng) { return x + Real(std::uniform_int_distribution<int>(0, 1)(rng) ? 1 : -1); });
}

TEST(MeshStatsProperty, DegenerateCountMatchesCgalInGeneralPosition) {
  // Dyadic coordinates m·2^e (|m| < 2^8, e in [-8, 4]) keep a + i·d exact in float; the nudge
  // is one ulp of Real, the smallest possible departure from the line.
  std::uniform_int_distribution<int> mantissa(-255, 255), exponent(-8, 4);
  compareDegenerateCountWithCgal(
      0x5eed0002, 100000, [&](std::mt19937_64& rng) { return std::ldexp(Wide(mantissa(rng)), exponent(rng)); },
      [&](std::mt19937_64& rng) { return std::ldexp(Wide(mantissa(rng)), exponent(rng)); },
      [](Real x, std::mt19937_64& rng) {
        const Real inf = std::numeric_limits<Real>::infinity();
        return std::nextafter(x, std::uniform_int_distribution<int>(0, 1)(rng) ? inf : -inf);
      });
}
#endif

/// Reference for the topological counts: quadratic duplicate search and a std::map of edges
/// (uses, and uses from the lower index to the higher) over the triangles with three distinct
/// indices.
MeshStats referenceTopology(const std::vector<TriangleIndices>& t) {
  MeshStats s;
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::pair<int, int>> uses;
  for (std::size_t i = 0; i < t.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j)
      if (std::is_permutation(t[i].begin(), t[i].end(), t[j].begin())) {
        ++s.duplicateTriangles;
        break;
      }
    if (t[i][0] == t[i][1] || t[i][1] == t[i][2] || t[i][2] == t[i][0]) continue;
    ++s.edges.effectiveTriangles;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t p = t[i][k], q = t[i][(k + 1) % 3];
      auto& [count, forward] = uses[{std::min(p, q), std::max(p, q)}];
      ++count;
      forward += p < q;
    }
  }
  for (const auto& [edge, use] : uses) {
    s.edges.boundaryEdges += use.first == 1;
    s.edges.nonManifoldEdges += use.first > 2;
    s.edges.inconsistentEdges += use.first == 2 && use.second != 1;
  }
  return s;
}

TEST(MeshStatsProperty, TopologyCountsMatchReferenceOnRandomIndexSoups) {
  std::mt19937_64 rng(0x5eed0003);
  const int cases = 3000;
  int withDuplicates = 0, withNonManifold = 0, closed = 0;
  for (int n = 0; n < cases; ++n) {
    const int vertexCount = std::uniform_int_distribution<int>(3, 7)(rng);
    const int triangleCount = std::uniform_int_distribution<int>(1, 10)(rng);
    std::uniform_int_distribution<std::uint32_t> index(0, std::uint32_t(vertexCount - 1));
    std::uniform_real_distribution<Real> coordinate(-1, 1);
    std::vector<Vec3> v(static_cast<std::size_t>(vertexCount), Vec3::Zero());
    for (Vec3& p : v) p = Vec3(coordinate(rng), coordinate(rng), coordinate(rng));
    std::vector<TriangleIndices> t(static_cast<std::size_t>(triangleCount));
    for (TriangleIndices& tri : t) tri = {index(rng), index(rng), index(rng)};
    const MeshStats expected = referenceTopology(t);
    const MeshStats s = Mesh(v, t, "soup").stats();
    std::string dump;
    for (const TriangleIndices& tri : t)
      dump += " (" + std::to_string(tri[0]) + "," + std::to_string(tri[1]) + "," + std::to_string(tri[2]) + ")";
    ASSERT_EQ(s.duplicateTriangles, expected.duplicateTriangles) << "case " << n << ":" << dump;
    ASSERT_EQ(s.edges.boundaryEdges, expected.edges.boundaryEdges) << "case " << n << ":" << dump;
    ASSERT_EQ(s.edges.nonManifoldEdges, expected.edges.nonManifoldEdges) << "case " << n << ":" << dump;
    ASSERT_EQ(s.edges.inconsistentEdges, expected.edges.inconsistentEdges) << "case " << n << ":" << dump;
    ASSERT_EQ(s.closed(), expected.closed()) << "case " << n << ":" << dump;
    withDuplicates += s.duplicateTriangles > 0;
    withNonManifold += s.edges.nonManifoldEdges > 0;
    closed += s.closed();
  }
  std::printf("%d cases: %.1f%% with duplicates, %.1f%% with non-manifold edges, %d closed\n", cases,
              100.0 * withDuplicates / cases, 100.0 * withNonManifold / cases, closed);
  EXPECT_GE(withDuplicates, cases / 5);
  EXPECT_LE(withDuplicates, cases * 4 / 5);
  EXPECT_GE(withNonManifold, cases / 5);
  EXPECT_LE(withNonManifold, cases * 4 / 5);
}

// ---- BVH, setVertices, memory ---------------------------------------------------------------

TEST(Mesh, BvhCoversEveryTriangleOnce) {
  const Mesh mesh = gridMesh(20);
  EXPECT_EQ(mesh.triangleCount(), 800u);
  expectBvhFitsMesh(mesh);
  EXPECT_TRUE(sameBox(mesh.bounds(), boundsOf(mesh.vertices())));
  EXPECT_GE(mesh.buildSeconds(), 0.0);
  EXPECT_TRUE(std::isfinite(mesh.buildSeconds()));
}

TEST(Mesh, SetVerticesRefitsTheBvh) {
  Mesh mesh = gridMesh(20);
  const std::vector<std::uint32_t> primOrder = mesh.bvh().primIndices;
  const std::size_t nodeCount = mesh.bvh().nodes.size();
  // A deformation: lift the grid into a bump and move it away.
  std::vector<Vec3> moved = mesh.vertices();
  for (Vec3& p : moved) p = Vec3(p.x() * 2 + 100, p.y() - 50, std::sin(p.x() * Real(0.3)) * p.y());
  mesh.setVertices(moved);
  EXPECT_EQ(mesh.vertices(), moved);
  EXPECT_TRUE(sameBox(mesh.bounds(), boundsOf(moved)));
  expectBvhFitsMesh(mesh);
  // Refit, not rebuild: the topology of the tree is unchanged.
  EXPECT_EQ(mesh.bvh().primIndices, primOrder);
  EXPECT_EQ(mesh.bvh().nodes.size(), nodeCount);
}

TEST(Mesh, SetVerticesRejectsBadInputAndKeepsTheMesh) {
  Mesh mesh(cubeVertices(), cubeTriangles(), "cube");
  std::vector<Vec3> tooFew = cubeVertices();
  tooFew.pop_back();
  const std::string m1 = invalidInputMessage([&] { mesh.setVertices(tooFew); });
  EXPECT_TRUE(startsWith(m1, "cube: ")) << m1;
  EXPECT_TRUE(contains(m1, "7")) << m1;
  std::vector<Vec3> nan = cubeVertices();
  for (Vec3& p : nan) p *= 3;
  nan[6].y() = std::numeric_limits<Real>::quiet_NaN();
  const std::string m2 = invalidInputMessage([&] { mesh.setVertices(nan); });
  EXPECT_TRUE(contains(m2, "vertex 6 ")) << m2;
  EXPECT_EQ(mesh.vertices(), cubeVertices());
  EXPECT_TRUE(sameBox(mesh.bounds(), boundsOf(cubeVertices())));
}

TEST(Mesh, MemoryBytesCountsVertexIndexAndBvhArrays) {
  const Mesh mesh = gridMesh(50);
  const std::size_t arrays = mesh.vertexCount() * sizeof(Vec3) + mesh.triangleCount() * sizeof(TriangleIndices) +
                             mesh.bvh().nodes.size() * sizeof(WideBvhNode) +
                             mesh.bvh().primIndices.size() * sizeof(std::uint32_t);
  EXPECT_GE(mesh.memoryBytes(), arrays);
  EXPECT_LE(mesh.memoryBytes(), 2 * arrays);  // capacity slack, not a second copy
}

}  // namespace
}  // namespace crux
