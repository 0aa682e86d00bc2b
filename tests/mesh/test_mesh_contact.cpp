// Tests of src/mesh/mesh_contact.cpp: mesh vs convex shape contacts and distance through the BVH
// against the brute-force path and against the convex routine applied to every triangle by the
// test itself; internal-edge (ghost contact) correction on flat grids; a box on the bunny with
// every point on both surfaces. Seeded randomness; failing cases printed with 17 digits.

#include <crux/geometry/box_triangle_contact.hpp>
#include <crux/geometry/closest_point.hpp>
#include <crux/geometry/triangle_contact.hpp>
#include <crux/mesh/mesh_contact.hpp>
#include <crux/mesh/mesh_query_data.hpp>

#include <crux/error.hpp>

#include <gtest/gtest.h>

#include <functional>
#include <iomanip>

#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>
#include <limits>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "support/allocation_counter.hpp"  // allocationCount(): queries that must not allocate
#include "support/test_scale.hpp"
#include <crux/precondition.hpp>
#include "support/bad_inputs.hpp"

namespace crux {
namespace {

constexpr Real kEps = std::numeric_limits<Real>::epsilon();
/// Mesh contacts (computed in the mesh's frame, closed form for spheres and capsules) against the
/// generic convex routine applied in the world frame, relative to the coordinates' scale: the
/// two differ by the rounding of the relative pose and of the outputs (64 ulps of Real in float
/// builds) and, in double builds, by GJK/EPA's convergence tolerance (kGjkScaleTolerance, 1000
/// ulps of double, and 1e-12 relative; 1e-11 leaves EPA a factor 40 on thin prisms).
constexpr Real kPerTriangleAgreement = sizeof(Real) == 4 ? Real(64) * kEps : Real(1e-11);

std::string str(const Vec3& v) {
  std::ostringstream s;
  s.precision(17);
  s << "(" << double(v.x()) << ", " << double(v.y()) << ", " << double(v.z()) << ")";
  return s.str();
}
std::string str(const Transform& t) {
  std::ostringstream s;
  s.precision(17);
  s << "{q=(" << double(t.rotation.w()) << ", " << double(t.rotation.x()) << ", " << double(t.rotation.y()) << ", "
    << double(t.rotation.z()) << "), t=" << str(t.translation) << "}";
  return s.str();
}

/// nx × ny cells of size `cell` on z = height(x, y), two triangles per cell (alternating diagonals).
template <class H>
Mesh gridMesh(int nx, int ny, Real cell, H height) {
  std::vector<Vec3> v;
  std::vector<TriangleIndices> t;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) v.emplace_back(i * cell, j * cell, height(i, j));
  auto id = [&](int i, int j) { return std::uint32_t(j * (nx + 1) + i); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const auto a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      if ((i + j) % 2 == 0) {
        t.push_back({a, b, c});
        t.push_back({a, c, d});
      } else {
        t.push_back({a, b, d});
        t.push_back({b, c, d});
      }
    }
  return Mesh(std::move(v), std::move(t), "grid");
}

Quat randomRotation(std::mt19937& rng) {
  std::normal_distribution<double> g;
  Eigen::Quaterniond q(g(rng), g(rng), g(rng), g(rng));
  q.normalize();
  return q.cast<Real>();
}

struct ShapeCase {
  std::string name;
  ConvexShape shape;
};

std::vector<ShapeCase> shapes(const ConvexHull& hull) {
  Obb box;
  box.half = Vec3(Real(0.5), Real(0.3), Real(0.2));
  return {{"sphere", Sphere{Vec3::Zero(), Real(0.4)}},
          {"capsule", Capsule{Vec3(Real(-0.3), 0, 0), Vec3(Real(0.3), 0, 0), Real(0.2)}},
          {"box", box},
          {"hull", hull}};
}

ConvexHull randomHull(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-0.4, 0.4);
  std::vector<Vec3> pts;
  for (int i = 0; i < 16; ++i) pts.emplace_back(Real(u(rng)), Real(u(rng)), Real(u(rng)));
  return ConvexHull::build(pts);
}

/// A uniformly random point q of triangle tri and its unit normal n (two draws of rng, made
/// only when the triangle has an area); false for a zero-area triangle.
bool randomPointOn(const Triangle& tri, std::mt19937& rng, Vec3& q, Vec3& n) {
  n = (tri.b - tri.a).cross(tri.c - tri.a);
  if (!(n.norm() > 0)) return false;
  n.normalize();
  std::uniform_real_distribution<double> u(0, 1);
  double s = u(rng), w = u(rng);
  if (s + w > 1) s = 1 - s, w = 1 - w;
  q = tri.a + Real(s) * (tri.b - tri.a) + Real(w) * (tri.c - tri.a);
  return true;
}

Real minSeparation(const MeshContactManifold& m) {
  Real s = kNoLimit;
  for (int i = 0; i < m.count; ++i) s = std::min(s, m.points[i].separation);
  return s;
}

// --- BVH vs brute force vs the convex routine per triangle -------------------------------------

TEST(MeshContact, BvhAgreesWithBruteForceAndPerTriangleRoutine) {
  std::mt19937 rng(20261122);
  std::uniform_real_distribution<double> noise(-0.3, 0.3);
  std::vector<Real> heights(11 * 11);
  for (auto& h : heights) h = Real(noise(rng));
  const Mesh bumpy = gridMesh(10, 10, Real(0.5), [&](int i, int j) { return heights[j * 11 + i]; });
  std::vector<Vec3> sv;
  std::vector<TriangleIndices> st;
  std::uniform_real_distribution<double> c(0, 5), d(-0.4, 0.4);
  for (int k = 0; k < 150; ++k) {
    const Vec3 o(Real(c(rng)), Real(c(rng)), Real(c(rng) * 0.2));
    for (int m = 0; m < 3; ++m) sv.push_back(o + Vec3(Real(d(rng)), Real(d(rng)), Real(d(rng))));
    st.push_back({std::uint32_t(3 * k), std::uint32_t(3 * k + 1), std::uint32_t(3 * k + 2)});
  }
  const Mesh soup(std::move(sv), std::move(st), "soup");
  const ConvexHull hull = randomHull(rng);
  const Real margin = Real(0.05);
  int withContacts = 0, checked = 0;
  for (const Mesh* mesh : {&bumpy, &soup}) {
    const MeshQueryData data(*mesh, MeshQueryParts::Contacts);
    for (const ShapeCase& sc : shapes(hull)) {
      for (int trial = 0; trial < 60; ++trial) {
        Transform meshPose;
        meshPose.rotation = randomRotation(rng);
        meshPose.translation = Vec3(Real(d(rng)), Real(d(rng)), Real(d(rng)));
        Transform shapePose;
        shapePose.rotation = randomRotation(rng);
        const Vec3 local(Real(c(rng)), Real(c(rng)), Real(noise(rng)));
        shapePose.translation = meshPose.apply(local);
        const std::string info = mesh->name() + " " + sc.name + " meshPose " + str(meshPose) + " shapePose " +
                                 str(shapePose);
        // reference: the convex routine on every triangle
        Real refSep = kNoLimit, refDist = kNoLimit;
        for (std::uint32_t t = 0; t < mesh->triangleCount(); ++t) {
          ContactManifold m;
          if (contacts(ConvexShape(mesh->triangle(t)), meshPose, sc.shape, shapePose, margin, m))
            for (int i = 0; i < m.count; ++i) refSep = std::min(refSep, m.points[i].separation);
          refDist = std::min(refDist, distance(ConvexShape(mesh->triangle(t)), meshPose, sc.shape, shapePose).distance);
        }
        MeshContactManifold bvh, brute, adj, adjBrute;
        const bool hit = contacts(*mesh, meshPose, sc.shape, shapePose, margin, bvh);
        contacts(*mesh, meshPose, sc.shape, shapePose, margin, brute, nullptr, QueryPath::BruteForce);
        contacts(*mesh, meshPose, sc.shape, shapePose, margin, adj, &data);
        contacts(*mesh, meshPose, sc.shape, shapePose, margin, adjBrute, &data, QueryPath::BruteForce);
        // The mesh routine works in the mesh's frame (and with closed-form sphere/capsule
        // routines), the reference in the world: equal up to kPerTriangleAgreement; BVH and
        // brute force run the same per-triangle code and agree exactly.
        const Real agree = kPerTriangleAgreement * (meshPose.translation.norm() + shapePose.translation.norm() +
                                                   sc.shape.size() + 5);
        if (hit != (refSep != kNoLimit)) {
          ASSERT_LE(std::abs((hit ? minSeparation(bvh) : refSep) - margin), agree) << "verdict away from the margin " << info;
          continue;
        }
        ASSERT_EQ(bvh.count > 0, brute.count > 0) << info;
        ASSERT_LE(bvh.count, 4) << info;
        if (hit) {
          ++withContacts;
          ASSERT_NEAR(minSeparation(bvh), refSep, agree) << info;
          ASSERT_EQ(minSeparation(brute), minSeparation(bvh)) << info;
          ASSERT_EQ(bvh.points[0].separation, minSeparation(bvh)) << "deepest first " << info;
          ASSERT_EQ(adj.count > 0, adjBrute.count > 0) << info;
          if (adj.count > 0) ASSERT_EQ(minSeparation(adj), minSeparation(adjBrute)) << info;
          for (const MeshContactManifold* m : {&bvh, &adj})
            for (int i = 0; i < m->count; ++i) {
              const MeshContactPoint& p = m->points[i];
              const Real scale = p.pointA.cwiseAbs().maxCoeff() + 5;
              ASSERT_LE(p.separation, margin) << info;
              ASSERT_NEAR(double(p.normal.norm()), 1.0, 100 * kEps) << info;
              ASSERT_LE((p.pointA - p.pointB - p.separation * p.normal).norm(), 1000 * kEps * scale)
                  << info << " point " << i;
            }
        }
        // distance: BVH vs brute force vs reference; early out
        const MeshDistanceResult db = distance(*mesh, meshPose, sc.shape, shapePose);
        const MeshDistanceResult df = distance(*mesh, meshPose, sc.shape, shapePose, kNoLimit, QueryPath::BruteForce);
        ASSERT_TRUE(db.found && df.found) << info;
        ASSERT_EQ(db.distance, refDist) << info;
        ASSERT_EQ(df.distance, refDist) << info;
        ASSERT_EQ(db.triangle, df.triangle) << info;
        ASSERT_LE((db.pointA - db.pointB - db.distance * db.normal).norm(),
                  1000 * kEps * (db.pointA.cwiseAbs().maxCoeff() + 5))
            << info;
        if (refDist > 0) {
          ASSERT_FALSE(distance(*mesh, meshPose, sc.shape, shapePose, refDist / 2).found) << info;
          const MeshDistanceResult up = distance(*mesh, meshPose, sc.shape, shapePose, refDist * 2);
          ASSERT_TRUE(up.found) << info;
          ASSERT_EQ(up.distance, refDist) << info;
        }
        ++checked;
      }
    }
  }
  std::printf("checked %d poses, %d with contacts\n", checked, withContacts);
  EXPECT_GT(withContacts, checked / 5);
}

// distance()'s separating-axis pruning (a triangle whose plane, or a box's face axes, bound its
// signed distance above the best so far is skipped) must give the brute-force answer bit for bit,
// above all on deep placements where it skips most of the overlapped triangles.
TEST(MeshContact, DistancePruningKeepsTheBruteForceAnswerOnDeepPlacements) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  std::vector<double> heights(21 * 21);
  for (double& h : heights) h = u(rng);
  const Mesh grid = gridMesh(20, 20, 1, [&](int i, int j) { return Real(heights[std::size_t(j * 21 + i)]); });
  const ConvexHull hull = randomHull(rng);
  std::uniform_real_distribution<double> xy(3, 17), lift(-0.8, 1.6);
  const int poses = test::scaledCases(60, 10);
  int penetrating = 0, checked = 0;
  for (const ShapeCase& sc : shapes(hull)) {
    ConvexShape shape = sc.shape;  // ~1.5 across: a few cells
    shape.radius *= 3;
    for (Vec3& p : shape.p) p *= 3;
    if (shape.kind == ConvexKind::Box) shape.p[0] = Vec3::Zero();
    if (shape.kind == ConvexKind::Hull) shape = Sphere{Vec3::Zero(), Real(1.2)};
    for (int k = 0; k < poses; ++k) {
      const Real x = Real(xy(rng)), y = Real(xy(rng));
      const Real z = Real(heights[std::size_t(std::lround(double(y)) * 21 + std::lround(double(x)))] + lift(rng));
      Transform meshPose;
      meshPose.rotation = randomRotation(rng);
      meshPose.translation = Vec3(Real(u(rng) * 10), Real(u(rng) * 10), Real(u(rng) * 10));
      const Transform shapePose{randomRotation(rng), meshPose.apply(Vec3(x, y, z))};
      const std::string info = sc.name + " meshPose " + str(meshPose) + " shapePose " + str(shapePose);
      const MeshDistanceResult a = distance(grid, meshPose, shape, shapePose);
      const MeshDistanceResult b = distance(grid, meshPose, shape, shapePose, kNoLimit, QueryPath::BruteForce);
      ASSERT_TRUE(a.found && b.found) << info;
      ASSERT_EQ(a.distance, b.distance) << info;
      ASSERT_EQ(a.triangle, b.triangle) << info;
      ASSERT_EQ(a.pointA, b.pointA) << info;
      ASSERT_EQ(a.pointB, b.pointB) << info;
      ASSERT_EQ(a.normal, b.normal) << info;
      // with an early-out bound just above the answer, as a TOI or proximity query would ask
      const Real limit = a.distance + Real(0.01);
      const MeshDistanceResult c = distance(grid, meshPose, shape, shapePose, limit);
      ASSERT_TRUE(c.found) << info;
      ASSERT_EQ(c.distance, a.distance) << info;
      ASSERT_EQ(c.triangle, a.triangle) << info;
      penetrating += a.distance < 0;
      ++checked;
    }
  }
  std::printf("checked %d placements, %d penetrating\n", checked, penetrating);
  EXPECT_GT(penetrating, checked / 3);
}

// --- ghost contacts on internal edges -----------------------------------------------------------

TEST(MeshContact, SphereOnFlatGridHasOneVerticalContactEvenAtInternalEdges) {
  const Mesh grid = gridMesh(8, 8, 1, [](int, int) { return Real(0); });
  const MeshQueryData data(grid, MeshQueryParts::Contacts);
  const Real r = Real(0.5);
  const Real tol = 100 * kEps * 8;
  int ghostsWithoutAdjacency = 0, cases = 0;
  for (const Real depth : {Real(0.01), Real(-0.005)})  // penetrating, and speculative (within margin)
  for (int i = 0; i <= 32; ++i)
    for (int j = 0; j <= 32; ++j) {
      const Vec3 c(2 + Real(i) / 8, 2 + Real(j) / 8, r - depth);
      const Transform pose{Quat::Identity(), c};
      const std::string info = "sphere centre " + str(c);
      MeshContactManifold m;
      ASSERT_TRUE(contacts(grid, Transform::identity(), Sphere{Vec3::Zero(), r}, pose, Real(0.02), m, &data))
          << info;
      ASSERT_EQ(m.count, 1) << info;
      ASSERT_LE((m.points[0].normal - Vec3(0, 0, -1)).norm(), tol) << info << " normal " << str(m.points[0].normal);
      ASSERT_NEAR(double(m.points[0].separation), -double(depth), double(tol)) << info;
      ASSERT_NEAR(double(m.points[0].pointA.z()), 0.0, double(tol)) << info;
      MeshContactManifold ghost;
      contacts(grid, Transform::identity(), Sphere{Vec3::Zero(), r}, pose, Real(0.02), ghost);
      for (int k = 0; k < ghost.count; ++k)
        if ((ghost.points[k].normal - Vec3(0, 0, -1)).norm() > tol) {
          ++ghostsWithoutAdjacency;
          break;
        }
      ++cases;
    }
  std::printf("%d of %d positions have ghost normals without adjacency\n", ghostsWithoutAdjacency, cases);
  EXPECT_GT(ghostsWithoutAdjacency, 0);  // the test would see ghosts
}

TEST(MeshContact, RotatedBoxAndCapsuleOnFlatGridHaveOnlyVerticalNormals) {
  const Mesh grid = gridMesh(8, 8, 1, [](int, int) { return Real(0); });
  const MeshQueryData data(grid, MeshQueryParts::Contacts);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(2, 6), a(0, 6.283185307179586);
  const Real tol = 100 * kEps * 8;
  const Real depth = Real(0.01);
  for (int trial = 0; trial < 200; ++trial) {
    const Real angle = Real(a(rng));
    Obb box;
    box.half = Vec3(Real(0.7), Real(0.4), Real(0.3));
    Capsule cap{Vec3(Real(-0.6), 0, 0), Vec3(Real(0.6), 0, 0), Real(0.25)};
    const Vec3 xy(Real(u(rng)), Real(u(rng)), 0);
    for (int s = 0; s < 2; ++s) {
      const ConvexShape shape = s == 0 ? ConvexShape(box) : ConvexShape(cap);
      const Real h = s == 0 ? box.half.z() : cap.radius;
      const Transform pose{Quat(Eigen::AngleAxis<Real>(angle, Vec3::UnitZ())), xy + Vec3(0, 0, h - depth)};
      const std::string info = std::string(s == 0 ? "box" : "capsule") + " pose " + str(pose);
      MeshContactManifold m;
      ASSERT_TRUE(contacts(grid, Transform::identity(), shape, pose, Real(0.02), m, &data)) << info;
      // box: the 4 corners of its bottom face; capsule: its two ends, plus possibly a rounded end
      // over a seam reported by its own triangle, slightly shallower (a real contact, not a ghost)
      if (s == 0) ASSERT_EQ(m.count, 4) << info;
      else ASSERT_GE(m.count, 2) << info;
      for (int k = 0; k < m.count; ++k) {
        ASSERT_LE((m.points[k].normal - Vec3(0, 0, -1)).norm(), tol) << info << " normal " << str(m.points[k].normal);
        ASSERT_NEAR(double(m.points[k].separation), -double(depth), double(tol)) << info;
      }
    }
  }
}

TEST(MeshContact, SphereWhoseSquaredReachOverflowsSkipsUnusedLanes) {
  // A finite sphere so large that its squared reach is +inf: every used lane passes the node
  // test, and the unused lanes of the tree (empty boxes, whose keys are +inf too) must still be
  // skipped (entering one reads past the node array: ASan, or a crash). 3 x 1 cells: 6
  // triangles, a root with unused lanes. The BVH answer equals the brute-force one.
  const Mesh grid = gridMesh(3, 1, 1, [](int, int) { return Real(0); });
  bool unused = false;
  for (const WideBvhNode& n : grid.bvh().nodes)
    for (int l = 0; l < 4; ++l) unused |= !n.used(l);
  ASSERT_TRUE(unused);
  const Real r = 2 * std::sqrt(std::numeric_limits<Real>::max());
  ASSERT_TRUE(std::isfinite(r));
  const Transform pose{Quat::Identity(), Vec3(1, Real(0.5), r / 2)};
  MeshContactManifold a, b;
  contacts(grid, Transform::identity(), Sphere{Vec3::Zero(), r}, pose, Real(0.01), a);
  contacts(grid, Transform::identity(), Sphere{Vec3::Zero(), r}, pose, Real(0.01), b, nullptr, QueryPath::BruteForce);
  ASSERT_EQ(a.count, b.count);
  EXPECT_GT(a.count, 0);
  if (a.count > 0) EXPECT_EQ(minSeparation(a), minSeparation(b));
}

TEST(MeshContact, ConvexEdgeKeepsItsNormal) {
  // A roof: two triangles meeting at a convex ridge along y at x = 0.
  std::vector<Vec3> v = {{-1, -1, -1}, {0, -1, 0}, {0, 1, 0}, {-1, 1, -1}, {1, -1, -1}, {1, 1, -1}};
  std::vector<TriangleIndices> t = {{0, 1, 2}, {0, 2, 3}, {1, 4, 5}, {1, 5, 2}};
  const Mesh roof(std::move(v), std::move(t), "roof");
  const MeshQueryData data(roof, MeshQueryParts::Contacts);
  const Real r = Real(0.3);
  const Transform pose{Quat::Identity(), Vec3(0, 0, r - Real(0.01))};
  MeshContactManifold m;
  ASSERT_TRUE(contacts(roof, Transform::identity(), Sphere{Vec3::Zero(), r}, pose, 0, m, &data));
  ASSERT_EQ(m.count, 1);
  EXPECT_LE((m.points[0].normal - Vec3(0, 0, -1)).norm(), 100 * kEps) << str(m.points[0].normal);
}

TEST(MeshContact, SphereInConcaveValleyGetsOnlyFaceNormals) {
  // floor z = 0 for x in [-2, 0], wall z = x for x in [0, 2]: a concave crease along y at x = 0
  std::vector<Vec3> v = {{-2, -2, 0}, {0, -2, 0}, {0, 2, 0}, {-2, 2, 0}, {2, -2, 2}, {2, 2, 2}};
  std::vector<TriangleIndices> t = {{0, 1, 2}, {0, 2, 3}, {1, 4, 5}, {1, 5, 2}};
  const Mesh valley(std::move(v), std::move(t), "valley");
  const MeshQueryData data(valley, MeshQueryParts::Contacts);
  const Real r = Real(0.5), h = Real(0.49), margin = Real(0.02);
  const Vec3 floorN(0, 0, -1);
  const Vec3 wallN = Vec3(1, 0, -1).normalized();
  const Real tol = 1000 * kEps * 4;
  for (int i = 0; i <= 130; ++i) {
    const Real x = Real(-1) + Real(i) / 100;
    const Vec3 c(x, Real(0.25), h);
    const std::string info = "sphere centre " + str(c);
    MeshContactManifold m;
    const bool hit = contacts(valley, Transform::identity(), Sphere{Vec3::Zero(), r}, Transform{Quat::Identity(), c},
                              margin, m, &data);
    // analytic: the floor is touched (sep h - r) while the centre is over it; the wall when the
    // centre's projection on its plane lies on it (x + h >= 0) at sep |h - x|/√2 - r
    Real expected = kNoLimit;
    if (x <= 0) expected = h - r;
    const Real wallSep = std::abs(h - x) / std::sqrt(Real(2)) - r;
    if (x + h >= 0 && wallSep <= margin) expected = std::min(expected, wallSep);
    if (expected == kNoLimit) continue;
    ASSERT_TRUE(hit) << info;
    ASSERT_NEAR(double(minSeparation(m)), double(expected), double(tol)) << info;
    for (int k = 0; k < m.count; ++k) {
      const Vec3& n = m.points[k].normal;
      ASSERT_TRUE((n - floorN).norm() <= tol || (n - wallN).norm() <= tol) << info << " normal " << str(n);
    }
  }
}

// --- box on the bunny ---------------------------------------------------------------------------

TEST(MeshContact, BoxOnBunnyPointsLieOnBothSurfaces) {
  const Mesh bunny = loadMesh(std::string(CRUX_SOURCE_DIR) + "/data/meshes/bunny00.off");
  const MeshQueryData data(bunny, MeshQueryParts::Contacts);
  const Real diag = (bunny.bounds().max - bunny.bounds().min).norm();
  const Real scale = diag + bunny.bounds().max.cwiseAbs().maxCoeff() + bunny.bounds().min.cwiseAbs().maxCoeff();
  const Real tol = 1000 * kEps * scale;
  std::mt19937 rng(99);
  std::uniform_int_distribution<std::uint32_t> pick(0, std::uint32_t(bunny.triangleCount() - 1));
  int points = 0;
  for (int trial = 0; trial < 100; ++trial) {
    const std::uint32_t ti = pick(rng);
    Vec3 q, n;
    if (!randomPointOn(bunny.triangle(ti), rng, q, n)) continue;
    Obb box;
    box.half = Vec3(Real(0.03), Real(0.02), Real(0.015)) * diag;
    const Quat rot = randomRotation(rng);
    const Mat3 axes = rot.toRotationMatrix();
    // the box corner deepest along -n goes to q - depth·n
    const Vec3 signs = (axes.transpose() * (-n)).cwiseSign();
    const Vec3 corner = axes * box.half.cwiseProduct(signs);
    const Transform pose{rot, q - Real(0.002) * diag * n - corner};
    const Real margin = Real(0.001) * diag;
    const std::string info = "triangle " + std::to_string(ti) + " box pose " + str(pose);
    MeshContactManifold m;
    ASSERT_TRUE(contacts(bunny, Transform::identity(), box, pose, margin, m, &data)) << info;
    for (int k = 0; k < m.count; ++k) {
      const MeshContactPoint& p = m.points[k];
      // on the mesh: some triangle within tol (mesh_query's exact sphere test, independent code)
      ASSERT_TRUE(overlaps(bunny, Sphere{p.pointA, tol})) << info << " pointA " << str(p.pointA);
      const Vec3 local = pose.rotation.conjugate() * (p.pointB - pose.translation);
      const Real outside = (local.cwiseAbs() - box.half).maxCoeff();
      ASSERT_LE(std::abs(outside), tol) << info << " pointB " << str(p.pointB) << " local " << str(local);
      ASSERT_LE(p.separation, margin) << info;
      ASSERT_LE((p.pointA - p.pointB - p.separation * p.normal).norm(), tol) << info;
      ++points;
    }
  }
  std::printf("%d contact points checked on the bunny\n", points);
  EXPECT_GT(points, 100);
}

// An OBB whose third axis is negated is the same box in a left-handed frame. A box's points are
// corrected, merged and reduced in the box's frame, where a left-handed frame turns every triangle
// over: the internal-edge correction must still read the edge activity of the side the box is
// on in the mesh's orientation. Both boxes give the same manifold (to rounding), on flat grid
// seams (where the correction acts) and on the bunny.
TEST(MeshContact, LeftHandedBoxFrameGivesTheSameManifold) {
  const Mesh bunny = loadMesh(std::string(CRUX_SOURCE_DIR) + "/data/meshes/bunny00.off");
  const MeshQueryData data(bunny, MeshQueryParts::Contacts);
  const Real diag = (bunny.bounds().max - bunny.bounds().min).norm();
  const Real tol = 1000 * kEps * diag;
  std::mt19937 rng(17);
  std::uniform_int_distribution<std::uint32_t> pick(0, std::uint32_t(bunny.triangleCount() - 1));
  int points = 0, corrected = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Triangle tri = bunny.triangle(pick(rng));
    Vec3 n = (tri.b - tri.a).cross(tri.c - tri.a);
    if (!(n.norm() > 0)) continue;
    n.normalize();
    Obb right;
    right.half = Vec3(Real(0.03), Real(0.02), Real(0.015)) * diag;
    right.axes = randomRotation(rng).toRotationMatrix();
    right.center = tri.a + (right.half.z() - Real(0.003) * diag) * n;
    Obb left = right;
    left.axes.col(2) = -right.axes.col(2);
    const Real margin = Real(0.001) * diag;
    MeshContactManifold a, b, raw;
    contacts(bunny, Transform::identity(), right, Transform::identity(), margin, a, &data);
    contacts(bunny, Transform::identity(), left, Transform::identity(), margin, b, &data);
    contacts(bunny, Transform::identity(), right, Transform::identity(), margin, raw);
    ASSERT_EQ(a.count, b.count) << "trial " << trial;
    for (int k = 0; k < a.count; ++k) {
      EXPECT_LE((a.points[k].pointA - b.points[k].pointA).norm(), tol) << "trial " << trial;
      EXPECT_LE((a.points[k].pointB - b.points[k].pointB).norm(), tol) << "trial " << trial;
      EXPECT_LE((a.points[k].normal - b.points[k].normal).norm(), Real(1e-4)) << "trial " << trial;
      EXPECT_EQ(a.points[k].triangle, b.points[k].triangle) << "trial " << trial;
      ++points;
    }
    bool differs = raw.count != a.count;
    for (int k = 0; !differs && k < a.count; ++k) differs = (raw.points[k].normal - a.points[k].normal).norm() > Real(1e-3);
    corrected += differs;
  }
  std::printf("%d points compared; the correction changed %d of the manifolds\n", points, corrected);
  EXPECT_GT(points, 200);
  EXPECT_GT(corrected, 10);  // the correction acted: the test reads the edge activity
}

// Found by `crux diff` (docs/diff.md): a flat hull poking through blob-closed near a vertex whose
// edges are flat or concave. The correction dropped the only raw contact (its face-normal
// projection leaves the triangle, and no neighbour reports it), so `contacts` was empty while
// `distance` said the pair penetrates by 0.031. The manifold must never be shallower than the
// deepest triangle (the signed distance), with or without adjacency.
TEST(MeshContact, CorrectionNeverLosesTheDeepestPenetration) {
  const Mesh blob = loadMesh(std::string(CRUX_SOURCE_DIR) + "/data/meshes/blob-closed.off");
  const MeshQueryData data(blob, MeshQueryParts::Contacts);
  const std::vector<std::vector<Vec3>> hulls = {
      {{0, 0, 0}, {Real(0.05859375), 0, Real(-0.1171875)}, {Real(-0.0625), 0, 0}},  // the shrunk case
      {{0, 0, 0}, {Real(0.05859375), 0, Real(-0.1171875)}, {Real(-0.0625), 0, 0}, {0, Real(0.001), 0}},
  };
  std::mt19937_64 rng(61);
  std::uniform_real_distribution<double> u(-1, 1);
  int checked = 0;
  for (const std::vector<Vec3>& points : hulls) {
    const ConvexHull hull = ConvexHull::build(points);
    const ConvexShape shape(hull);
    for (int k = 0; k < 400; ++k) {
      Transform pose;
      pose.translation = k == 0 ? Vec3(Real(0.875), 0, 0)
                                : Vec3(Real(0.875 + 0.2 * u(rng)), Real(0.2 * u(rng)), Real(0.2 * u(rng)));
      if (k > 0) pose.rotation = Quat(Real(u(rng)), Real(u(rng)), Real(u(rng)), Real(u(rng))).normalized();
      const MeshDistanceResult d = distance(blob, Transform::identity(), shape, pose);
      if (!(d.distance < 0)) continue;  // penetrating placements only
      SCOPED_TRACE("hull " + std::to_string(points.size()) + " points, pose " + str(pose));
      ++checked;
      for (const MeshQueryData* adj : {static_cast<const MeshQueryData*>(nullptr), &data}) {
        MeshContactManifold m;
        contacts(blob, Transform::identity(), shape, pose, 0, m, adj);
        ASSERT_GT(m.count, 0) << std::setprecision(17) << "placement " << k << " adjacency " << (adj != nullptr) << ": distance "
                              << double(d.distance) << " but no contact";
        EXPECT_LE(-m.depth(), d.distance + kMeshFeatureRelativeTolerance * 4)
            << std::setprecision(17) << "placement " << k << " adjacency " << (adj != nullptr) << ": manifold depth " << double(m.depth())
            << " shallower than the deepest triangle " << double(-d.distance);
      }
    }
  }
  EXPECT_GT(checked, 50);
}

TEST(MeshContact, BunnyBvhAgreesWithBruteForce) {
  const Mesh bunny = loadMesh(std::string(CRUX_SOURCE_DIR) + "/data/meshes/bunny00.off");
  const MeshQueryData data(bunny, MeshQueryParts::Contacts);
  const Real diag = (bunny.bounds().max - bunny.bounds().min).norm();
  std::mt19937 rng(11);
  const ConvexHull hull = randomHull(rng);
  std::uniform_int_distribution<std::uint32_t> pick(0, std::uint32_t(bunny.triangleCount() - 1));
  std::uniform_real_distribution<double> lift(-0.01, 0.05);
  const Real shapeScale = Real(0.05) * diag;
  int hits = 0;
  // (each trial runs both paths over all 75k triangles: one per shape under CRUX_TEST_SCALE 0.1)
  const int trials = test::scaledCases(3, 1);
  for (const ShapeCase& sc : shapes(hull)) {
    for (int trial = 0; trial < trials; ++trial) {
      const Triangle t = bunny.triangle(pick(rng));
      const Vec3 n = (t.b - t.a).cross(t.c - t.a).normalized();
      // rotated mesh; the shape near a triangle, from 1% inside to 5% of the diagonal outside
      Transform meshPose;
      meshPose.rotation = randomRotation(rng);
      const Vec3 q = ((t.a + t.b + t.c) / 3 + Real(lift(rng)) * diag * n);
      const Transform shapePose{randomRotation(rng), meshPose.apply(q)};
      const Real margin = Real(0.002) * diag;
      const std::string info = sc.name + " meshPose " + str(meshPose) + " shapePose " + str(shapePose);
      // shapes() are ~0.5 in size: scale them to 5% of the bunny (the hull becomes a sphere)
      ConvexShape shape = sc.shape;
      if (shape.kind == ConvexKind::Hull) shape = Sphere{Vec3::Zero(), shapeScale};
      else {
        shape.radius *= shapeScale / Real(0.5);
        for (Vec3& p : shape.p) p *= shapeScale / Real(0.5);
        if (shape.kind == ConvexKind::Box) shape.p[0] = Vec3::Zero();
      }
      MeshContactManifold a, b;
      contacts(bunny, meshPose, shape, shapePose, margin, a, &data);
      contacts(bunny, meshPose, shape, shapePose, margin, b, &data, QueryPath::BruteForce);
      ASSERT_EQ(a.count > 0, b.count > 0) << info;
      if (a.count > 0) {
        ++hits;
        ASSERT_EQ(minSeparation(a), minSeparation(b)) << info;
      }
      const MeshDistanceResult da = distance(bunny, meshPose, shape, shapePose);
      const MeshDistanceResult db = distance(bunny, meshPose, shape, shapePose, kNoLimit, QueryPath::BruteForce);
      ASSERT_EQ(da.distance, db.distance) << info;
      ASSERT_EQ(da.triangle, db.triangle) << info;
    }
  }
  EXPECT_GT(hits, 0);
}

// MeshAdjacency::memoryBytes (the figure docs/bench.md quotes per triangle) counts every array
// it holds: at least the per-triangle neighbours, opposite vertices, activity and per-slot data;
// and no array twice (capacity slack only).
TEST(MeshAdjacency, MemoryBytesCountsEveryArrayItHolds) {
  const Mesh bunny = loadMesh(std::string(CRUX_SOURCE_DIR) + "/data/meshes/bunny00.off");
  const MeshAdjacency adjacency(bunny);
  const std::size_t n = bunny.triangleCount();
  // neighbours and opposite vertices (3 × 4 bytes each per triangle), activity (1), per slot a
  // tolerance and an activity byte (at least sizeof(Real) + 1)
  const std::size_t perTriangle = 3 * 4 + 3 * 4 + 1 + sizeof(Real) + 1;
  EXPECT_GE(adjacency.memoryBytes(), perTriangle * n);
  EXPECT_LE(adjacency.memoryBytes(), 2 * (perTriangle + 8) * n);
}

// Query data records the mesh's geometry id: after setVertices (same counts, new positions)
// its activity bits and tolerances describe the old surface, so contacts() refuses it for every
// shape, naming it and the mesh. A copy of the mesh shares the id; refresh() rebuilds the data
// for the moved mesh, which is then accepted and finds the contact at the new position (and then
// refused for the unmoved copy).
TEST(MeshContact, QueryDataBuiltBeforeSetVerticesIsRefusedForEveryShapeUntilRefreshed) {
  Mesh grid = gridMesh(6, 6, 1, [](int, int) { return Real(0); });
  const Mesh copy = grid;
  const MeshQueryData before(grid, MeshQueryParts::Contacts);
  std::vector<Vec3> moved = grid.vertices();
  for (Vec3& p : moved) p += Vec3(0, 0, 10);
  grid.setVertices(moved);
  MeshQueryData after = before;
  EXPECT_FALSE(after.isCurrentFor(grid));
  EXPECT_TRUE(after.refresh(grid));
  EXPECT_TRUE(after.isCurrentFor(grid));
  EXPECT_FALSE(after.refresh(grid));
  const ConvexShape shapes[] = {Sphere{Vec3::Zero(), Real(0.5)},
                                Capsule{Vec3(Real(-0.5), 0, 0), Vec3(Real(0.5), 0, 0), Real(0.5)},
                                Obb{Vec3::Zero(), Vec3(Real(0.5), Real(0.5), Real(0.5)), Mat3::Identity()}};
  for (const ConvexShape& shape : shapes) {
    const Transform atOld{Quat::Identity(), Vec3(3, 3, Real(0.4))}, atNew{Quat::Identity(), Vec3(3, 3, Real(10.4))};
    MeshContactManifold m;
    try {
      contacts(grid, Transform::identity(), shape, atNew, Real(0.01), m, &before);
      FAIL() << "stale query data was accepted, shape kind " << int(shape.kind);
    } catch (const InvalidInput& e) {
      const std::string msg = e.what();
      EXPECT_EQ(msg.rfind("data", 0), 0u) << msg;
      EXPECT_NE(msg.find("stale"), std::string::npos) << msg;
    }
    EXPECT_THROW(contacts(copy, Transform::identity(), shape, atOld, Real(0.01), m, &after), InvalidInput);
    // the old data serves the unmoved copy, the refreshed one the moved mesh
    EXPECT_TRUE(contacts(copy, Transform::identity(), shape, atOld, Real(0.01), m, &before));
    EXPECT_NEAR(m.points[0].pointA.z(), 0, 1e-5);
    EXPECT_TRUE(contacts(grid, Transform::identity(), shape, atNew, Real(0.01), m, &after));
    EXPECT_NEAR(m.points[0].pointA.z(), 10, 1e-5);
    EXPECT_FALSE(contacts(grid, Transform::identity(), shape, atOld, Real(0.01), m, &after));
  }
}

// The sphere's internal-edge correction takes the features a point lies on from the sphere
// routine's Voronoi region (correctSphere); every other shape runs the generic per-edge tests.
// A capsule whose segment is a point is that same sphere through the generic path: both
// manifolds must agree point for point (separations, normals, positions).
TEST(MeshContact, SphereCorrectionAgreesWithTheGenericOneOnAPointCapsule) {
  const Mesh bunny = loadMesh(std::string(CRUX_SOURCE_DIR) + "/data/meshes/bunny00.off");
  const MeshQueryData data(bunny, MeshQueryParts::Contacts);
  const Real diag = (bunny.bounds().max - bunny.bounds().min).norm();
  std::mt19937 rng(20261122);
  std::uniform_int_distribution<std::uint32_t> pick(0, std::uint32_t(bunny.triangleCount() - 1));
  std::uniform_real_distribution<double> u(0, 1);
  const int cases = test::scaledCases(1500, 300);
  int compared = 0, corrected = 0;
  for (int k = 0; k < cases; ++k) {
    const Triangle t = bunny.triangle(pick(rng));
    const Vec3 n = (t.b - t.a).cross(t.c - t.a).normalized();
    const Real r = Real((0.01 + 0.05 * u(rng)) * double(diag));
    const Real margin = Real(0.01) * r;
    Transform meshPose;
    meshPose.rotation = randomRotation(rng);
    meshPose.translation = Vec3(Real(u(rng)), Real(u(rng)), Real(u(rng)));
    // the centre above a point of the triangle, from 0.3 r inside to the margin outside
    const Real w1 = Real(u(rng)), w2 = Real(u(rng)) * (1 - w1);
    const Vec3 q = t.a + w1 * (t.b - t.a) + w2 * (t.c - t.a) + (r * Real(0.7 + 0.3 * u(rng)) + margin * Real(u(rng))) * n;
    const Vec3 centre = meshPose.apply(q);
    MeshContactManifold sphere, capsule;
    contacts(bunny, meshPose, Sphere{centre, r}, Transform::identity(), margin, sphere, &data);
    contacts(bunny, meshPose, Capsule{centre, centre, r}, Transform::identity(), margin, capsule, &data);
    std::ostringstream info;
    info.precision(17);
    info << "case " << k << " centre " << str(centre) << " radius " << double(r) << " margin " << double(margin)
         << " meshPose " << str(meshPose);
    ASSERT_EQ(sphere.count, capsule.count) << info.str();
    const Real agree = kPerTriangleAgreement * (centre.norm() + meshPose.translation.norm() + r + 5);
    for (int i = 0; i < sphere.count; ++i) {
      const MeshContactPoint &a = sphere.points[i], &b = capsule.points[i];
      // (the triangle may differ: equal separations at a shared edge or corner are ordered by
      // triangle index, and the two routines round differently)
      ASSERT_NEAR(a.separation, b.separation, agree) << info.str() << " point " << i;
      ASSERT_LE((a.pointA - b.pointA).norm(), agree) << info.str() << " point " << i;
      ASSERT_GE(a.normal.dot(b.normal), 1 - 100 * kEps) << info.str() << " point " << i;
    }
    MeshContactManifold raw;
    contacts(bunny, meshPose, Sphere{centre, r}, Transform::identity(), margin, raw);
    bool changed = raw.count != sphere.count;
    for (int i = 0; !changed && i < raw.count; ++i)
      changed = raw.points[i].triangle != sphere.points[i].triangle ||
                raw.points[i].normal.dot(sphere.points[i].normal) < 1 - 100 * kEps;
    corrected += changed;
    compared += sphere.count > 0;
  }
  std::printf("%d of %d placements compared, %d changed by the correction\n", compared, cases, corrected);
  EXPECT_GT(compared, cases * 9 / 10);
  EXPECT_GT(corrected, cases / 4);
}

// --- The internal-edge correction against a reference written from the header's rule ----------

/// A raw per-triangle point in the frame the reference corrects it in (the mesh frame; a box's
/// own frame for a box, as mesh_contact.cpp computes its points there).
struct RefPoint {
  Vec3 a, b, normal;
  Real separation;
  std::uint32_t triangle;
};

/// The shape as the reference sees it in its correction frame: projection interval on a unit
/// direction and support point.
struct RefShape {
  ConvexKind kind;
  Vec3 p0 = Vec3::Zero(), p1 = Vec3::Zero(), half = Vec3::Zero();
  Real radius = 0;
  void project(const Vec3& u, Real& lo, Real& hi) const {
    if (kind == ConvexKind::Box) {
      hi = half.x() * std::abs(u.x()) + half.y() * std::abs(u.y()) + half.z() * std::abs(u.z());
      lo = -hi;
      return;
    }
    lo = std::min(u.dot(p0), u.dot(p1)) - radius;
    hi = std::max(u.dot(p0), u.dot(p1)) + radius;
  }
  Vec3 support(const Vec3& d) const {
    if (kind == ConvexKind::Box)
      return {d.x() > 0 ? half.x() : -half.x(), d.y() > 0 ? half.y() : -half.y(), d.z() > 0 ? half.z() : -half.z()};
    return (p1.dot(d) > p0.dot(d) ? p1 : p0) + radius * d.normalized();
  }
};

/// The header's internal-edge rule for one point of triangle t, written directly from its text:
/// no correction for a degenerate triangle or a normal within the face cone; the shape's side
/// of the plane by its projection; every edge within the feature tolerance by its closest point;
/// the activity of that side from MeshAdjacency::edgeActivity(t) (by triangle, not by slot); an
/// inactive feature takes the face normal, the shape's deepest point along it and its
/// projection, dropped beyond the margin or off the triangle. False: drop.
bool referenceCorrect(const MeshAdjacency& adjacency, const Triangle& meshTriangle, const Triangle& ft,
                      const RefShape& shape, Real margin, RefPoint& p) {
  Vec3 face = (ft.b - ft.a).cross(ft.c - ft.a);
  const Real len = face.norm();
  if (!(len > 0)) return true;
  face /= len;
  if (std::abs(face.dot(p.normal)) >= kMeshFaceConeCos) return true;
  Real lo = 0, hi = 0;
  shape.project(face, lo, hi);
  const Real base = face.dot(ft.a);
  const bool back = base - lo > hi - base;
  const Vec3 side = back ? Vec3(-face) : face;
  const Real tol = meshFeatureTolerance(meshTriangle);
  bool onSomeEdge = false;
  for (int i = 0; i < 3; ++i) {
    const Segment edge{ft[i], ft[(i + 1) % 3]};
    if ((closestPoint(edge, p.a) - p.a).squaredNorm() > tol * tol) continue;
    onSomeEdge = true;
    if ((adjacency.edgeActivity(p.triangle) >> (2 * i + (back ? 1 : 0))) & 1u) return true;
  }
  if (!onSomeEdge) return true;
  RefPoint q = p;
  q.normal = -side;
  q.b = shape.support(q.normal);
  q.separation = side.dot(q.b - ft.a);
  if (q.separation > margin) return false;
  q.a = q.b - q.separation * side;
  if ((closestPoint(ft, q.a) - q.a).squaredNorm() > tol * tol) return false;
  p = q;
  return true;
}

// contacts() with an adjacency corrects each point by a restructured, branch-reduced form of the
// rule (a per-triangle FaceRule, a corner mask, a cheap edge-line drop, the activity and
// tolerance read by BVH slot: docs/narrowphase.md, "Design choices (measured)"). Here every triangle of the mesh
// is run through the per-triangle routine by the test itself and corrected by referenceCorrect
// (plus the rule that the deepest dropped point is kept when nothing kept is as deep); every
// point contacts() reports must then be one of the reference's points (same triangle, position,
// normal and separation to rounding), and the deepest separations must agree. Sphere, capsule
// and box on the bunny and on a bumpy grid (flat, ridge and valley seams), penetrating and
// within the margin.
TEST(MeshContact, CorrectionAgreesWithAReferenceWrittenFromTheRule) {
  const Mesh bunny = loadMesh(std::string(CRUX_SOURCE_DIR) + "/data/meshes/bunny00.off");
  std::mt19937 heights(5);
  std::uniform_int_distribution<int> bump(-1, 1);
  std::vector<Real> h(6 * 6);  // plateaus of 4 x 4 cells (flat seams) with ridges and valleys between
  for (Real& z : h) z = Real(0.02) * Real(bump(heights));
  const Mesh grid = gridMesh(20, 20, Real(0.05), [&](int i, int j) { return h[std::size_t((j / 4) * 6 + i / 4)]; });
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> u(0, 1);
  int points = 0, corrected = 0, dropped = 0, placements = 0;
  for (const Mesh* mesh : {&bunny, &grid}) {
    const MeshQueryData data(*mesh, MeshQueryParts::Contacts);
    const Real diag = (mesh->bounds().max - mesh->bounds().min).norm();
    const Real s = Real(0.025) * diag;
    const Real margin = Real(0.01) * s;
    const Real tol = 64 * kEps * (diag + mesh->bounds().max.cwiseAbs().maxCoeff() + mesh->bounds().min.cwiseAbs().maxCoeff());
    const std::vector<ConvexShape> shapesHere = {
        Sphere{Vec3::Zero(), s}, Capsule{Vec3(0, 0, Real(-0.8) * s), Vec3(0, 0, Real(0.8) * s), Real(0.6) * s},
        Obb{Vec3::Zero(), Vec3(s, Real(0.7) * s, Real(0.5) * s), Mat3::Identity()}};
    std::uniform_int_distribution<std::uint32_t> pick(0, std::uint32_t(mesh->triangleCount() - 1));
    for (const ConvexShape& shape : shapesHere) {
      for (int trial = 0; trial < test::scaledCases(150, 50); ++trial) {
        // a random point of a random triangle; the shape's deepest point along -n at a depth
        // in [-0.8 margin, 0.2 s]
        Vec3 q, n;
        if (!randomPointOn(mesh->triangle(pick(rng)), rng, q, n)) continue;
        Transform pose;
        pose.rotation = randomRotation(rng);
        const Vec3 deepest = pose.rotation * support(shape, pose.rotation.conjugate() * Vec3(-n));
        const Real depth = Real(-0.8 * u(rng)) * margin + (trial % 2 == 0 ? Real(0.2 * u(rng)) * s : Real(0));
        pose.translation = q - depth * n - deepest;
        // The shape in the mesh frame (mesh at the identity) as LocalShape takes it: the rotation
        // in double from the quaternion, the shape's points rounded once.
        const Eigen::Matrix3d R = pose.rotation.cast<double>().normalized().toRotationMatrix();
        const Eigen::Vector3d t = pose.translation.cast<double>();
        RefShape ref{shape.kind};
        const bool isBox = shape.kind == ConvexKind::Box;
        Eigen::Matrix3d toBox = Eigen::Matrix3d::Identity();
        if (isBox) {
          ref.half = shape.p[1];
          toBox = (R * shape.axes.cast<double>()).transpose();
          ASSERT_GT(toBox.determinant(), 0);
        } else {
          ref.radius = shape.radius;
          ref.p0 = (R * shape.p[0].cast<double>() + t).cast<Real>();
          ref.p1 = (R * shape.p[shape.kind == ConvexKind::Capsule ? 1 : 0].cast<double>() + t).cast<Real>();
        }
        const Eigen::Vector3d boxCentre = R * shape.p[0].cast<double>() + t;
        auto toMesh = [&](const Vec3& v) {
          return isBox ? Vec3((toBox.transpose() * v.cast<double>() + boxCentre).cast<Real>()) : v;
        };
        std::vector<RefPoint> kept;
        RefPoint deepestDropped{};
        bool hasDropped = false;
        for (std::uint32_t ti = 0; ti < mesh->triangleCount(); ++ti) {
          const Triangle tri = mesh->triangle(ti);
          const Vec3 c = (tri.a + tri.b + tri.c) / 3;
          if ((c - pose.translation).norm() > 4 * s + (tri.a - c).norm() + (tri.b - c).norm() + (tri.c - c).norm())
            continue;  // far beyond the shape (size <= 1.3 s) and the margin
          Triangle ft = tri;
          ContactManifold m;
          bool any = false;
          if (isBox) {
            ft = {(toBox * (tri.a.cast<double>() - boxCentre)).cast<Real>(),
                  (toBox * (tri.b.cast<double>() - boxCentre)).cast<Real>(),
                  (toBox * (tri.c.cast<double>() - boxCentre)).cast<Real>()};
            any = boxTriangleContacts(ref.half, ft, margin, m);
          } else if (shape.kind == ConvexKind::Capsule) {
            any = capsuleTriangleContacts(tri, ref.p0, ref.p1, ref.radius, margin, m);
          } else {
            SphereTriangleContact one;
            any = sphereTriangleContact(tri, ref.p0, ref.radius, margin, one);
            m.count = any ? 1 : 0;
            m.normal = one.normal;
            m.points[0].pointA = one.pointA;
            m.points[0].pointB = one.pointB;
            m.points[0].separation = one.separation;
          }
          for (int k = 0; any && k < m.count; ++k) {
            RefPoint p{m.points[k].pointA, m.points[k].pointB, m.normal, m.points[k].separation, ti};
            const RefPoint raw = p;
            if (!referenceCorrect(data.adjacencyFor(*mesh), tri, ft, ref, margin, p)) {
              ++dropped;
              if (!hasDropped || raw.separation < deepestDropped.separation ||
                  (raw.separation == deepestDropped.separation && raw.triangle < deepestDropped.triangle))
                deepestDropped = raw, hasDropped = true;
              continue;
            }
            corrected += (p.normal - raw.normal).norm() > 0;
            kept.push_back(p);
          }
        }
        Real keptMin = kNoLimit;
        for (const RefPoint& p : kept) keptMin = std::min(keptMin, p.separation);
        if (hasDropped && !(keptMin <= deepestDropped.separation)) kept.push_back(deepestDropped);
        Real refMin = kNoLimit;
        for (const RefPoint& p : kept) refMin = std::min(refMin, p.separation);

        MeshContactManifold out;
        contacts(*mesh, Transform::identity(), shape, pose, margin, out, &data);
        const std::string info = std::string(mesh == &bunny ? "bunny" : "grid") + " kind " +
                                 std::to_string(int(shape.kind)) + " trial " + std::to_string(trial) + " pose " +
                                 str(pose);
        ASSERT_EQ(out.count > 0, !kept.empty()) << info;
        if (kept.empty()) continue;
        ++placements;
        EXPECT_NEAR(minSeparation(out), refMin, tol) << info;
        for (int k = 0; k < out.count; ++k) {
          const MeshContactPoint& o = out.points[k];
          bool found = false;
          for (const RefPoint& p : kept)
            found = found || (p.triangle == o.triangle && std::abs(p.separation - o.separation) <= tol &&
                              (toMesh(p.a) - o.pointA).norm() <= tol && (toMesh(p.b) - o.pointB).norm() <= tol &&
                              (isBox ? Vec3((toBox.transpose() * p.normal.cast<double>()).cast<Real>()) : p.normal)
                                          .dot(o.normal) >= 1 - 64 * kEps);
          EXPECT_TRUE(found) << info << " point " << k << " on triangle " << o.triangle << " at " << str(o.pointA)
                             << " normal " << str(o.normal) << " separation " << double(o.separation)
                             << " is none of the reference's " << kept.size() << " points";
          ++points;
        }
      }
    }
  }
  std::printf("%d placements, %d reported points found among the reference's; the reference corrected %d and "
              "dropped %d raw points\n", placements, points, corrected, dropped);
  EXPECT_GT(placements, 3 * test::scaledCases(150, 50));  // most placements touch on both meshes
  EXPECT_GT(corrected, 0);  // the rule acted (grid seams)
  EXPECT_GT(dropped, 0);
}

TEST(MeshContact, TimingOnBunny) {  // figures only (no assertion on time: shared machine)
  const Mesh bunny = loadMesh(std::string(CRUX_SOURCE_DIR) + "/data/meshes/bunny00.off");
  const MeshQueryData data(bunny, MeshQueryParts::Contacts);
  const Real diag = (bunny.bounds().max - bunny.bounds().min).norm();
  Obb box;
  box.half = Vec3(Real(0.03), Real(0.02), Real(0.015)) * diag;
  const ConvexShape shapesOnBunny[3] = {Sphere{Vec3::Zero(), Real(0.02) * diag},
                                        Capsule{Vec3(-Real(0.02) * diag, 0, 0), Vec3(Real(0.02) * diag, 0, 0),
                                                Real(0.01) * diag},
                                        box};
  const char* names[3] = {"sphere", "capsule", "box"};
  std::mt19937 rng(5);
  std::uniform_int_distribution<std::uint32_t> pick(0, std::uint32_t(bunny.triangleCount() - 1));
  for (int s = 0; s < 3; ++s) {
    // resting poses: the shape's deepest point 0.001·diag below a triangle's centroid
    std::vector<Transform> poses;
    const std::size_t count = std::size_t(test::scaledCases(500, 50));  // (figures only)
    while (poses.size() < count) {
      const Triangle t = bunny.triangle(pick(rng));
      Vec3 n = (t.b - t.a).cross(t.c - t.a);
      if (!(n.norm() > 0)) continue;
      n.normalize();
      const Quat rot = randomRotation(rng);
      const Vec3 deepest = rot * support(shapesOnBunny[s], rot.conjugate() * (-n));
      poses.push_back({rot, (t.a + t.b + t.c) / 3 - Real(0.001) * diag * n - deepest});
    }
    MeshContactManifold m;
    int hits = 0;
    const auto t0 = std::chrono::steady_clock::now();
    for (const Transform& pose : poses) hits += contacts(bunny, Transform::identity(), shapesOnBunny[s], pose,
                                                         Real(0.001) * diag, m, &data);
    const auto t1 = std::chrono::steady_clock::now();
    Real sink = 0;
    for (const Transform& pose : poses) sink += distance(bunny, Transform::identity(), shapesOnBunny[s], pose).distance;
    const auto t2 = std::chrono::steady_clock::now();
    std::printf("%s vs bunny00 (%zu triangles): contacts %.2f us/query (%d/%zu hit), distance %.2f us/query (%g)\n",
                names[s], bunny.triangleCount(), std::chrono::duration<double, std::micro>(t1 - t0).count() / poses.size(),
                hits, poses.size(), std::chrono::duration<double, std::micro>(t2 - t1).count() / poses.size(),
                double(sink));
  }
}

TEST(MeshContact, QueriesDoNotAllocate) {
  const Mesh grid = gridMesh(8, 8, 1, [](int, int) { return Real(0.1); });
  const MeshQueryData data(grid, MeshQueryParts::Contacts);
  std::mt19937 rng(3);
  const ConvexHull hull = randomHull(rng);
  const std::vector<ShapeCase> cases = shapes(hull);
  MeshContactManifold m;
  Real sink = 0;
  const long before = test::allocationCount();
  for (const ShapeCase& sc : cases)
    for (int i = 0; i < 20; ++i) {
      const Transform pose{Quat(Eigen::AngleAxis<Real>(Real(0.3) * i, Vec3::UnitX())),
                           Vec3(1 + Real(0.3) * i, 2, Real(0.3))};
      contacts(grid, Transform::identity(), sc.shape, pose, Real(0.05), m, &data);
      sink += m.depth() + distance(grid, Transform::identity(), sc.shape, pose, Real(1)).distance;
    }
  EXPECT_EQ(test::allocationCount(), before) << sink;
}

TEST(MeshContact, AdjacencyOfAGrid) {
  const Mesh grid = gridMesh(3, 2, 1, [](int, int) { return Real(0); });
  const MeshAdjacency adjacency(grid);
  ASSERT_EQ(adjacency.triangleCount(), grid.triangleCount());
  int interior = 0, boundary = 0;
  for (std::uint32_t t = 0; t < grid.triangleCount(); ++t)
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t nb = adjacency.neighbor(t, e);
      if (nb == MeshAdjacency::kNone) {
        ++boundary;
        continue;
      }
      ++interior;
      bool back = false;
      for (int f = 0; f < 3; ++f) back = back || adjacency.neighbor(nb, f) == t;
      EXPECT_TRUE(back) << t << " " << e;
    }
  // 3x2 cells: boundary edges 2*(3+2) = 10; interior edges counted twice
  EXPECT_EQ(boundary, 10);
  const int edges = 3 * 3 + 4 * 2 + 6;  // horizontal + vertical + diagonals
  EXPECT_EQ(interior, 2 * (edges - boundary));
}

TEST(MeshContact, EdgeActivityOfRidgeValleyFlatAndBoundaryEdges) {
  // Hand-derived: a ridge (convex seen from above, concave from below), a valley (the reverse),
  // a flat seam (inactive on both sides) and boundary edges (active on both sides). Every
  // triangle's corner order makes its normal point up (+z: the front side).
  auto bitsOfSharedEdge = [](const Mesh& mesh, const MeshAdjacency& adjacency, std::uint32_t t) {
    for (int e = 0; e < 3; ++e)
      if (adjacency.neighbor(t, e) != MeshAdjacency::kNone) return (adjacency.edgeActivity(t) >> (2 * e)) & 3u;
    ADD_FAILURE() << mesh.name() << ": triangle " << t << " has no neighbour";
    return 0u;
  };
  for (const Real apex : {Real(1), Real(-1), Real(0)}) {  // ridge, valley, flat
    std::vector<Vec3> v = {{-1, -1, 0}, {0, -1, apex}, {0, 1, apex}, {1, -1, 0}};
    std::vector<TriangleIndices> t = {{0, 1, 2}, {1, 3, 2}};
    const Mesh m(std::move(v), std::move(t), "fold");
    const MeshAdjacency adjacency(m);
    const unsigned expected = apex > 0 ? 1u : apex < 0 ? 2u : 0u;  // bit 0 front (above), bit 1 back
    for (std::uint32_t tri = 0; tri < 2; ++tri) {
      EXPECT_EQ(bitsOfSharedEdge(m, adjacency, tri), expected) << "apex " << double(apex) << " triangle " << tri;
      for (int e = 0; e < 3; ++e)
        if (adjacency.neighbor(tri, e) == MeshAdjacency::kNone)
          EXPECT_EQ((adjacency.edgeActivity(tri) >> (2 * e)) & 3u, 3u) << "boundary edge " << e;
    }
  }
  // A zero-area triangle has no face cone: every bit set.
  const Mesh sliver({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 1, 3}}, "sliver");
  EXPECT_EQ(MeshAdjacency(sliver).edgeActivity(0), 0x3fu);
}

TEST(MeshContact, EdgeActivityMatchesTheDihedralSignOnABumpyGridAndBySlotWithTheFeatureTolerance) {
  // A random height field (a few exactly flat patches): each interior edge is convex on exactly
  // one side unless flat; the sign of the neighbour's opposite vertex against the plane,
  // computed here in double from the mesh arrays, decides it wherever it is far from the
  // tolerance.
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  std::vector<double> heights(31 * 31);
  for (double& h : heights) h = u(rng);
  for (int j = 0; j < 8; ++j)
    for (int i = 0; i < 8; ++i) heights[std::size_t(j * 31 + i)] = 0.25;  // a flat patch
  const Mesh grid = gridMesh(30, 30, 1, [&](int i, int j) { return Real(heights[std::size_t(j * 31 + i)]); });
  const MeshAdjacency adjacency(grid);
  int checked = 0, flat = 0;
  for (std::uint32_t t = 0; t < grid.triangleCount(); ++t) {
    const Triangle tri = grid.triangle(t);
    const Eigen::Vector3d a = tri.a.cast<double>(), b = tri.b.cast<double>(), c = tri.c.cast<double>();
    const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
    for (int e = 0; e < 3; ++e) {
      const unsigned bits = (adjacency.edgeActivity(t) >> (2 * e)) & 3u;
      const std::uint32_t nb = adjacency.neighbor(t, e);
      if (nb == MeshAdjacency::kNone) {
        EXPECT_EQ(bits, 3u) << "triangle " << t << " boundary edge " << e;
        continue;
      }
      double d = 0;  // the neighbour's third corner against this plane
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t w = grid.triangles()[nb][k];
        if (w != grid.triangles()[t][e] && w != grid.triangles()[t][(e + 1) % 3])
          d = n.dot(grid.vertices()[w].cast<double>() - tri[e].cast<double>());
      }
      // Beyond twice the feature tolerance the sign decides; within half of it the edge is flat
      // (inactive on both sides); between, the Real rounding of the plane may go either way.
      const double tol = double(meshFeatureTolerance(tri));
      if (std::abs(d) > 2 * tol) {
        EXPECT_EQ(bits, d < 0 ? 1u : 2u) << "triangle " << t << " edge " << e << " d " << d << " tol " << tol;
        ++checked;
      } else if (std::abs(d) < tol / 2) {
        EXPECT_EQ(bits, 0u) << "triangle " << t << " edge " << e << " d " << d << " tol " << tol;
        ++flat;
      }
    }
  }
  EXPECT_GT(checked, 3000);
  EXPECT_GT(flat, 100);
  const auto& prims = grid.bvh().primIndices;
  for (std::size_t k = 0; k < prims.size(); ++k)
    ASSERT_EQ(adjacency.edgeActivityBySlot(std::uint32_t(k)), adjacency.edgeActivity(prims[k])) << "slot " << k;
  // the feature tolerance table: the value a query would compute from the slot's triangle
  for (std::size_t k = 0; k < prims.size(); ++k)
    ASSERT_EQ(adjacency.featureToleranceBySlot(std::uint32_t(k)), meshFeatureTolerance(grid.triangle(prims[k])))
        << "slot " << k;
}

}  // namespace
}  // namespace crux

namespace crux {
namespace {

TEST(MeshContact, BadMarginForeignOrPartlessDataAndNanBoundAreInvalidInput) {
  const Mesh grid = gridMesh(4, 4, 1, [](int, int) { return Real(0); });
  const Mesh other = gridMesh(2, 2, 1, [](int, int) { return Real(0); });
  const MeshQueryData foreign(other, MeshQueryParts::Contacts);
  const MeshQueryData distanceOnly(grid, MeshQueryParts::Distance);
  const Sphere s{Vec3::Zero(), Real(0.5)};
  const Transform pose{Quat::Identity(), Vec3(2, 2, Real(0.4))};
  MeshContactManifold m;
  auto message = [](const std::function<void()>& f) -> std::string {
    try {
      f();
    } catch (const InvalidInput& e) {
      return e.what();
    }
    return "no error";
  };
  EXPECT_EQ(message([&] { contacts(grid, Transform::identity(), s, pose, Real(-1), m); }).rfind("margin: ", 0), 0u);
  EXPECT_EQ(message([&] { contacts(grid, Transform::identity(), s, pose, Real(0.01), m, &foreign); }).rfind("data is stale", 0),
            0u);
  EXPECT_EQ(message([&] { contacts(grid, Transform::identity(), s, pose, Real(0.01), m, &distanceOnly); })
                .rfind("data: this MeshQueryData was built without its contacts part", 0),
            0u);
  EXPECT_EQ(message([&] { distance(grid, Transform::identity(), s, pose, std::numeric_limits<Real>::quiet_NaN()); })
                .rfind("maxDistance: ", 0),
            0u);
  // The mesh's own data is accepted.
  const MeshQueryData own(grid, MeshQueryParts::Contacts);
  EXPECT_TRUE(contacts(grid, Transform::identity(), s, pose, Real(0.01), m, &own));
}


// --- Seeded manifolds against a pinned hash ----------------------------------------------------

/// SplitMix64 (Steele, Lea, Flood 2014): a portable seeded integer stream. Reals come from its
/// top 53 bits by an explicit mapping, never from <random>'s distributions, whose results differ
/// between standard libraries: the hash below must see the same inputs everywhere.
class PortableRandom {
 public:
  explicit PortableRandom(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  /// Uniform in [lo, hi) (a dyadic double in [0, 1) scaled, then rounded once to Real).
  Real uniform(double lo, double hi) { return Real(lo + (hi - lo) * (double(next() >> 11) * 0x1p-53)); }
  /// Uniform integer in [0, n) (n small: the modulo bias is irrelevant to a regression hash).
  std::uint32_t below(std::uint32_t n) { return std::uint32_t(next() % n); }
  /// A point with coordinates uniform in [lo, hi), drawn x, y, z in turn (one statement per draw:
  /// the order of a call's arguments is unspecified, GCC and Clang differ).
  Vec3 point(double lo, double hi) {
    const Real x = uniform(lo, hi);
    const Real y = uniform(lo, hi);
    const Real z = uniform(lo, hi);
    return Vec3(x, y, z);
  }
  /// A unit quaternion from four uniform coordinates (not uniform on SO(3); any rotation will do).
  Quat rotation() {
    const Vec3 v = point(-1, 1);
    const Real w = uniform(-1, 1);
    Quat q(w, v.x(), v.y(), v.z());
    if (!(q.norm() > Real(0.1))) q = Quat::Identity();
    return q.normalized();
  }

 private:
  std::uint64_t state_;
};

/// FNV-1a over the bytes of every value fed to it.
class OutputHash {
 public:
  template <class T>
  void add(const T& value) {
    unsigned char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    for (unsigned char b : bytes) value_ = (value_ ^ b) * 0x100000001B3ull;
  }
  void add(const Vec3& v) {
    for (int i = 0; i < 3; ++i) add(v[i]);
  }
  std::uint64_t value() const { return value_; }

 private:
  std::uint64_t value_ = 0xCBF29CE484222325ull;
};

/// A closed, bumpy sphere of radius ~2: a cube's surface split into n × n cells per face, each
/// lattice point pushed to the radius 2 + bump (square roots and divisions only, so the same
/// positions everywhere), corners shared across the cube's edges so the adjacency sees one surface.
Mesh bumpySphere(int n, PortableRandom& rng) {
  std::vector<Vec3> v;
  std::vector<TriangleIndices> t;
  std::map<std::array<int, 3>, std::uint32_t> index;
  auto vertex = [&](int x, int y, int z) {
    const std::array<int, 3> key{x, y, z};
    const auto it = index.find(key);
    if (it != index.end()) return it->second;
    const Vec3 p(Real(2 * x - n), Real(2 * y - n), Real(2 * z - n));
    v.push_back(p / p.norm() * (Real(2) + rng.uniform(-0.15, 0.15)));
    return index[key] = std::uint32_t(v.size() - 1);
  };
  // Each face: an axis, a side and two in-plane axes ordered so that the normal points outwards.
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, w = (axis + 2) % 3;
      auto at = [&](int i, int j) {
        int c[3];
        c[axis] = side * n;
        c[u] = side ? i : j;
        c[w] = side ? j : i;
        return vertex(c[0], c[1], c[2]);
      };
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          const auto a = at(i, j), b = at(i + 1, j), c = at(i + 1, j + 1), d = at(i, j + 1);
          t.push_back({a, b, c});
          t.push_back({a, c, d});
        }
    }
  return Mesh(std::move(v), std::move(t), "bumpy sphere");
}

// Bit-for-bit regression of the mesh contact rules: 6,400 seeded queries (sphere, capsule, box
// and convex hull near random points of an open bumpy grid and of a closed bumpy sphere, both
// rotated and moved, each query with and without the adjacency data) hash every output bit —
// the verdict, the count, and per point both positions, the normal, the separation, the
// triangle and the shape's feature — and compare with a hash pinned per precision. A
// refactoring must leave it unchanged. When a contact rule changes on purpose, re-pin: run
// `test_mesh_contact --gtest_filter=MeshContact.SeededManifoldsMatchPinnedHash` in a float and
// in a double (CRUX_DOUBLE_PRECISION=ON) build, check the change against the exact backend,
// copy the printed hashes into kPinned below, and name the change in the commit. The inputs
// come from PortableRandom (one draw per statement) and the meshes from + - × ÷ and √ only, so
// they are the same on every standard library and compiler; the outputs assume IEEE arithmetic
// without contraction (no -ffast-math, no FMA unless the build asks for it): GCC -O3 and Clang
// -O1 (the sanitizer stage) give the same hash.
TEST(MeshContact, SeededManifoldsMatchPinnedHash) {
#if CRUX_DOUBLE_PRECISION_ENABLED
  constexpr std::uint64_t kPinned = 0x39bdb82ff4aabaa4ull;
#else
  constexpr std::uint64_t kPinned = 0x93138f51432dd6d6ull;
#endif
  PortableRandom rng(20261129);
  std::vector<Real> heights(17 * 17);
  for (Real& h : heights) h = rng.uniform(-0.3, 0.3);
  const Mesh grid = gridMesh(16, 16, Real(0.5), [&](int i, int j) { return heights[j * 17 + i]; });
  const Mesh sphere = bumpySphere(8, rng);
  std::vector<Vec3> hullPoints;
  for (int i = 0; i < 16; ++i) hullPoints.push_back(rng.point(-0.4, 0.4));
  const ConvexHull hull = ConvexHull::build(hullPoints);
  const Real margin = Real(0.05);
  OutputHash hash;
  int queries = 0, withContacts = 0, changedByAdjacency = 0;
  for (const Mesh* mesh : {&grid, &sphere}) {
    const MeshQueryData data(*mesh, MeshQueryParts::Contacts);
    for (const ShapeCase& sc : shapes(hull)) {
      for (int trial = 0; trial < 400; ++trial) {
        // The shape's centre near a random point of a random triangle: from 0.3 below to 1.0
        // above it along the face normal, both the mesh and the shape rotated.
        const Triangle tri = mesh->triangle(rng.below(std::uint32_t(mesh->triangleCount())));
        Real s = rng.uniform(0, 1), w = rng.uniform(0, 1);
        if (s + w > 1) s = 1 - s, w = 1 - w;
        const Vec3 normal = (tri.b - tri.a).cross(tri.c - tri.a).normalized();
        const Vec3 local = tri.a + s * (tri.b - tri.a) + w * (tri.c - tri.a) + rng.uniform(-0.3, 1.0) * normal;
        Transform meshPose;
        meshPose.rotation = rng.rotation();
        meshPose.translation = rng.point(-3, 3);
        const Transform shapePose{rng.rotation(), meshPose.apply(local)};
        MeshContactManifold plain, corrected;
        const bool hit = contacts(*mesh, meshPose, sc.shape, shapePose, margin, plain);
        contacts(*mesh, meshPose, sc.shape, shapePose, margin, corrected, &data);
        queries += 2;
        withContacts += hit;
        for (const MeshContactManifold* m : {&plain, &corrected}) {
          hash.add(m->count > 0);
          hash.add(m->count);
          for (int i = 0; i < m->count; ++i) {
            const MeshContactPoint& p = m->points[i];
            hash.add(p.pointA);
            hash.add(p.pointB);
            hash.add(p.normal);
            hash.add(p.separation);
            hash.add(p.triangle);
            hash.add(p.featureB);
          }
        }
        changedByAdjacency += plain.count != corrected.count || (hit && plain.points[0].normal != corrected.points[0].normal);
      }
    }
  }
  std::printf("%d queries, %d poses with contacts, %d changed by the adjacency, hash 0x%016llxull\n", queries,
              withContacts, changedByAdjacency, static_cast<unsigned long long>(hash.value()));
  // The hash covers real manifolds (most poses touch) and the internal-edge correction.
  EXPECT_GT(withContacts, queries / 4);
  EXPECT_GT(changedByAdjacency, queries / 100);
  EXPECT_EQ(hash.value(), kPinned) << std::hex << "hash 0x" << hash.value() << ": a contact output changed; if on "
                                   << "purpose, re-pin (see the comment above this test)";
}

// Non-queryable shapes or poses (precondition.hpp): no contact and no distance; a non-finite pose
// used to crash the BVH walk.
TEST(MeshContactPreconditions, NonQueryableInputsGetNoAnswer) {
  if (CRUX_CHECK_PRECONDITIONS) GTEST_SKIP() << "this build aborts instead (precondition.hpp)";
  const Mesh mesh({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)}, {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
  const ConvexShape box = Obb{Vec3::Constant(Real(0.2)), Vec3::Constant(Real(0.5)), Mat3::Identity()};
  MeshContactManifold m;
  for (const Transform& pose : test_support::badPoses()) {
    EXPECT_FALSE(contacts(mesh, Transform{}, box, pose, Real(0.01), m));
    EXPECT_FALSE(contacts(mesh, pose, box, Transform{}, Real(0.01), m));
    EXPECT_FALSE(distance(mesh, pose, box, Transform{}).found);
    EXPECT_FALSE(distance(mesh, Transform{}, box, pose).found);
  }
  for (const ConvexShape& shape : test_support::badShapes()) {
    EXPECT_FALSE(contacts(mesh, Transform{}, shape, Transform{}, Real(0.01), m));
    EXPECT_FALSE(distance(mesh, Transform{}, shape, Transform{}).found);
  }
  EXPECT_TRUE(contacts(mesh, Transform{}, box, Transform{}, Real(0.01), m));
}

}  // namespace
}  // namespace crux
