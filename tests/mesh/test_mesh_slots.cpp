/// Tests of the mesh's BVH-leaf-ordered triangle copy (Mesh::slotTriangle), which the mesh
/// queries read instead of triangle(primIndices[k]).
#include <crux/mesh/mesh.hpp>

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace crux {
namespace {

/// A random soup: n triangles over a shared pool of vertices (so indices repeat, as in real meshes).
Mesh randomMesh(std::mt19937_64& rng, std::uint32_t n, const BvhBuildOptions& options = {}) {
  std::uniform_real_distribution<Real> coord(-10, 10);
  std::vector<Vec3> vertices(n + 2);
  for (Vec3& v : vertices) v = Vec3(coord(rng), coord(rng), coord(rng));
  std::uniform_int_distribution<std::uint32_t> index(0, n + 1);
  std::vector<TriangleIndices> triangles(n);
  for (TriangleIndices& t : triangles) t = {index(rng), index(rng), index(rng)};
  return Mesh(std::move(vertices), std::move(triangles), "soup", options);
}

void expectSlotsMatch(const Mesh& mesh) {
  const std::vector<std::uint32_t>& prims = mesh.bvh().primIndices;
  ASSERT_EQ(prims.size(), mesh.triangleCount());
  for (std::uint32_t k = 0; k < prims.size(); ++k) {
    const Triangle s = mesh.slotTriangle(k), t = mesh.triangle(prims[k]);
    EXPECT_TRUE(s.a == t.a && s.b == t.b && s.c == t.c) << "slot " << k << " triangle " << prims[k];
  }
}

TEST(MeshSlots, SlotTriangleIsTriangleOfPrimIndex) {
  std::mt19937_64 rng(1201);
  for (std::uint32_t n : {1u, 2u, 5u, 64u, 1000u}) {
    SCOPED_TRACE(n);
    expectSlotsMatch(randomMesh(rng, n));
    BvhBuildOptions options;
    options.maxLeafSize = 1;
    options.traversalCost = 1;
    expectSlotsMatch(randomMesh(rng, n, options));
  }
}

TEST(MeshSlots, SlotTrianglesFollowSetVertices) {
  std::mt19937_64 rng(1202);
  Mesh mesh = randomMesh(rng, 300);
  std::vector<Vec3> moved = mesh.vertices();
  for (Vec3& v : moved) v = 2 * v + Vec3(1, -3, 0.5f);
  mesh.setVertices(std::move(moved));
  expectSlotsMatch(mesh);
}

TEST(MeshSlots, MemoryCountsTheSlotCopy) {
  std::mt19937_64 rng(1203);
  const Mesh mesh = randomMesh(rng, 500);
  const std::size_t arrays = mesh.vertices().capacity() * sizeof(Vec3) +
                             2 * mesh.triangles().capacity() * sizeof(TriangleIndices) + mesh.bvh().memoryBytes();
  EXPECT_EQ(mesh.memoryBytes(), arrays);
}

}  // namespace
}  // namespace crux
