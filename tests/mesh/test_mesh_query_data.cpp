// Tests of src/mesh/mesh_query_data.cpp: the caller-held per-mesh data of contact and distance
// queries: the parts it builds and its key to the mesh's geometry (stale data refused by both
// kinds of query, refresh() rebuilding it). Threads sharing one: tests/scene/test_concurrent_queries.cpp.

#include <crux/mesh/mesh_query_data.hpp>

#include <crux/error.hpp>

#include <gtest/gtest.h>

#include "support/invalid_input.hpp"

#include <string>
#include <thread>
#include <vector>

namespace crux {
namespace {

/// n × n unit cells on z = 0.1·((i·j) mod 3), two triangles per cell: ridges and valleys.
Mesh wavyGrid(int n, const char* name) {
  std::vector<Vec3> v;
  std::vector<TriangleIndices> t;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) v.emplace_back(Real(i), Real(j), Real(0.1) * Real((i * j) % 3));
  auto id = [&](int i, int j) { return std::uint32_t(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      t.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      t.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return Mesh(std::move(v), std::move(t), name);
}

using test_support::invalidInputMessage;

TEST(MeshQueryData, BuildsOnlyThePartsAskedForAndCountsTheirBytes) {
  const Mesh grid = wavyGrid(8, "grid");
  const MeshQueryData all(grid), contactsOnly(grid, MeshQueryParts::Contacts),
      distanceOnly(grid, MeshQueryParts::Distance);
  EXPECT_EQ(all.parts(), MeshQueryParts::All);
  EXPECT_EQ(all.geometryId(), grid.geometryId());
  EXPECT_TRUE(all.isCurrentFor(grid));
  EXPECT_EQ(all.memoryBytes(), MeshAdjacency(grid).memoryBytes() + MeshDistanceAccel(grid).memoryBytes());
  EXPECT_EQ(contactsOnly.memoryBytes(), MeshAdjacency(grid).memoryBytes());
  EXPECT_EQ(distanceOnly.memoryBytes(), MeshDistanceAccel(grid).memoryBytes());
  EXPECT_EQ(all.adjacencyFor(grid).triangleCount(), grid.triangleCount());
  EXPECT_EQ(all.distanceAccelFor(grid).corners().size(), 3 * grid.triangleCount());
  EXPECT_EQ(invalidInputMessage([&] { contactsOnly.distanceAccelFor(grid, "field"); }).rfind("field: ", 0), 0u);
  EXPECT_NE(invalidInputMessage([&] { distanceOnly.adjacencyFor(grid); }).find("contacts part"), std::string::npos);
  // Empty data holds nothing, matches no mesh and cannot be refreshed into anything.
  MeshQueryData empty;
  EXPECT_FALSE(empty.isCurrentFor(grid));
  EXPECT_FALSE(empty.refresh(grid));
  EXPECT_EQ(empty.memoryBytes(), 0u);
  EXPECT_THROW(empty.adjacencyFor(grid), InvalidInput);
}

// MeshQueryDataOnDemand (the native world's and Python's per-mesh data) builds each part once,
// on its first use, holding only that part; threads that ask for a part at once get the one
// object; a part set other than Contacts or Distance is refused.
TEST(MeshQueryData, OnDemandBuildsEachPartOnceOnFirstUse) {
  const Mesh grid = wavyGrid(8, "grid");
  const MeshQueryDataOnDemand onDemand(grid);
  const MeshQueryData* seen[4] = {};
  std::vector<std::thread> threads;
  for (int i = 0; i < 4; ++i)
    threads.emplace_back([&, i] { seen[i] = &onDemand.get(i % 2 ? MeshQueryParts::Distance : MeshQueryParts::Contacts); });
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(seen[0], seen[2]);
  EXPECT_EQ(seen[1], seen[3]);
  EXPECT_EQ(seen[0]->parts(), MeshQueryParts::Contacts);
  EXPECT_EQ(seen[1]->parts(), MeshQueryParts::Distance);
  EXPECT_TRUE(seen[0]->isCurrentFor(grid));
  EXPECT_EQ(&onDemand.get(MeshQueryParts::Distance), seen[1]);
  EXPECT_EQ(seen[1]->memoryBytes(), MeshDistanceAccel(grid).memoryBytes());
  EXPECT_NE(invalidInputMessage([&] { onDemand.get(MeshQueryParts::All); }).find("Contacts or Distance"), std::string::npos);
  EXPECT_THROW(onDemand.get(MeshQueryParts::None), InvalidInput);
}

// The query data of a mesh whose vertices moved (Mesh::setVertices) describes the old surface:
// a contact query and a mesh–mesh distance query given it both throw InvalidInput saying it is
// stale, never answering from the old edge flags or corners. refresh() rebuilds it, after which
// both queries answer exactly as with data built from scratch (and as the brute-force paths).
TEST(MeshQueryData, StaleDataIsRefusedByContactsAndDistanceUntilRefreshed) {
  Mesh grid = wavyGrid(8, "moving grid");
  const Mesh other = wavyGrid(4, "other grid");
  MeshQueryData data(grid);
  const MeshQueryData otherData(other);
  const Sphere sphere{Vec3::Zero(), Real(0.4)};
  const Transform above{Quat::Identity(), Vec3(Real(3.3), Real(4.6), Real(0.45))};
  Transform otherPose;
  otherPose.translation = Vec3(Real(1.5), Real(1.5), Real(0.5));
  MeshDistanceOptions withData;
  withData.dataA = &data;
  withData.dataB = &otherData;
  MeshContactManifold m;
  ASSERT_TRUE(contacts(grid, Transform::identity(), sphere, above, Real(0.05), m, &data));

  std::vector<Vec3> moved = grid.vertices();
  for (Vec3& p : moved) p = Vec3(p.x(), p.y(), Real(0.2) * p.z() + Real(0.1));
  grid.setVertices(moved);
  EXPECT_FALSE(data.isCurrentFor(grid));
  const std::string contactError =
      invalidInputMessage([&] { contacts(grid, Transform::identity(), sphere, above, Real(0.05), m, &data); });
  EXPECT_NE(contactError.find("stale"), std::string::npos) << contactError;
  EXPECT_NE(contactError.find("moving grid"), std::string::npos) << contactError;
  const std::string distanceError =
      invalidInputMessage([&] { distance(grid, Transform::identity(), other, otherPose, withData); });
  EXPECT_NE(distanceError.find("options.dataA"), std::string::npos) << distanceError;
  EXPECT_NE(distanceError.find("stale"), std::string::npos) << distanceError;

  ASSERT_TRUE(data.refresh(grid));
  EXPECT_TRUE(data.isCurrentFor(grid));
  EXPECT_EQ(data.parts(), MeshQueryParts::All);
  const MeshQueryData fresh(grid);
  MeshContactManifold a, b, brute;
  const bool hit = contacts(grid, Transform::identity(), sphere, above, Real(0.05), a, &data);
  contacts(grid, Transform::identity(), sphere, above, Real(0.05), b, &fresh);
  contacts(grid, Transform::identity(), sphere, above, Real(0.05), brute, &fresh, QueryPath::BruteForce);
  ASSERT_TRUE(hit);
  ASSERT_EQ(a.count, b.count);
  for (int i = 0; i < a.count; ++i) {
    EXPECT_EQ(a.points[i].pointA, b.points[i].pointA);
    EXPECT_EQ(a.points[i].normal, b.points[i].normal);
    EXPECT_EQ(a.points[i].separation, b.points[i].separation);
    EXPECT_EQ(a.points[i].triangle, b.points[i].triangle);
  }
  EXPECT_EQ(a.points[0].separation, brute.points[0].separation);
  const MeshMeshDistanceResult d = distance(grid, Transform::identity(), other, otherPose, withData);
  MeshDistanceOptions bruteOptions;
  bruteOptions.path = QueryPath::BruteForce;
  const MeshMeshDistanceResult ref = distance(grid, Transform::identity(), other, otherPose, bruteOptions);
  ASSERT_TRUE(d.found);
  EXPECT_EQ(d.distance, ref.distance);
}

}  // namespace
}  // namespace crux
