// Tests of src/mesh/mesh_volume.cpp: closedness census (closed, boundary, non-manifold,
// inconsistently oriented, index-degenerate triangles), exact point-in-mesh on integer-grid
// closed meshes (boxes, unions of unit cubes incl. a hollow one, tetrahedra, a box with a
// T-junction patched by a zero-area triangle) against independent exact references (voxel
// membership, integer barycentric signs) and CGAL::Side_of_triangle_mesh (exact kernel), with
// query points on vertices, edges, faces, inside and outside; volume-mode overlaps; refusal of
// non-closed meshes; no heap allocation in MeshVolume queries; real meshes (bunny00).

#include <crux/error.hpp>
#include <crux/mesh/mesh_query.hpp>
#include <crux/mesh/mesh_volume.hpp>

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <new>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "support/allocation_counter.hpp"  // allocationCount(): queries that must not allocate

namespace crux {
namespace {

using K = CGAL::Exact_predicates_exact_constructions_kernel;
using CgalMesh = CGAL::Surface_mesh<K::Point_3>;

std::string str17(const Vec3& v) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "(%.17g, %.17g, %.17g)", double(v.x()), double(v.y()), double(v.z()));
  return buf;
}

/// CGAL's exact point-in-closed-mesh classifier (ray shooting on an AABB tree, exact kernel).
class CgalSide {
 public:
  explicit CgalSide(const Mesh& m) {
    std::vector<CgalMesh::Vertex_index> v;
    for (const Vec3& p : m.vertices()) v.push_back(sm_.add_vertex(K::Point_3(double(p.x()), double(p.y()), double(p.z()))));
    for (const TriangleIndices& t : m.triangles()) {
      const auto f = sm_.add_face(v[t[0]], v[t[1]], v[t[2]]);
      EXPECT_NE(f, CgalMesh::null_face()) << "CGAL rejected a face of " << m.name();
    }
    side_ = std::make_unique<CGAL::Side_of_triangle_mesh<CgalMesh, K>>(sm_);
  }
  bool inside(const Vec3& p) const {
    return (*side_)(K::Point_3(double(p.x()), double(p.y()), double(p.z()))) != CGAL::ON_UNBOUNDED_SIDE;
  }

 private:
  CgalMesh sm_;
  std::unique_ptr<CGAL::Side_of_triangle_mesh<CgalMesh, K>> side_;
};

/// Integer grid point -> vertex index, building the vertex array as points appear.
struct VertexPool {
  std::map<std::array<int, 3>, std::uint32_t> ids;
  std::vector<Vec3> vertices;
  std::uint32_t operator()(int x, int y, int z) {
    const auto [it, added] = ids.emplace(std::array<int, 3>{x, y, z}, std::uint32_t(vertices.size()));
    if (added) vertices.push_back(Vec3(Real(x), Real(y), Real(z)));
    return it->second;
  }
};

/// Appends the two triangles of quad q (counter-clockwise seen from outside).
void addQuad(std::vector<TriangleIndices>& tris, const std::array<std::uint32_t, 4>& q) {
  tris.push_back({q[0], q[1], q[2]});
  tris.push_back({q[0], q[2], q[3]});
}

/// The square of grid face: axis `a`, at coordinate `at` on that axis, lower corner (u0, v0) in
/// the other two axes (cyclic order), outward along +a (positive) or -a.
std::array<std::uint32_t, 4> faceQuad(VertexPool& pool, int a, int at, int u0, int v0, int u1, int v1, bool positive) {
  auto id = [&](int u, int v) {
    int c[3];
    c[a] = at, c[(a + 1) % 3] = u, c[(a + 2) % 3] = v;
    return pool(c[0], c[1], c[2]);
  };
  std::array<std::uint32_t, 4> q{id(u0, v0), id(u1, v0), id(u1, v1), id(u0, v1)};
  if (!positive) std::swap(q[1], q[3]);
  return q;
}

/// Boundary of a union of unit voxels (closed when no two voxels share only an edge or vertex).
struct VoxelSet {
  int n;
  std::vector<char> filled;
  explicit VoxelSet(int n_) : n(n_), filled(std::size_t(n_ * n_ * n_), 0) {}
  bool at(int x, int y, int z) const {
    if (x < 0 || y < 0 || z < 0 || x >= n || y >= n || z >= n) return false;
    return filled[std::size_t(x + n * (y + n * z))] != 0;
  }
  void set(int x, int y, int z, bool v) { filled[std::size_t(x + n * (y + n * z))] = v; }
  /// Exact membership of the point q/2 (q integer) in the union of closed unit cubes.
  bool containsHalf(const std::array<int, 3>& q) const {
    int lo[3], hi[3];
    for (int i = 0; i < 3; ++i) {  // voxels i with 2i <= q <= 2i + 2
      hi[i] = q[i] >= 0 ? q[i] / 2 : -((-q[i] + 1) / 2);
      lo[i] = q[i] % 2 == 0 ? hi[i] - 1 : hi[i];
    }
    for (int x = lo[0]; x <= hi[0]; ++x)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int z = lo[2]; z <= hi[2]; ++z)
          if (at(x, y, z)) return true;
    return false;
  }
  Mesh mesh(const std::string& name) const {
    VertexPool pool;
    std::vector<TriangleIndices> tris;
    for (int x = 0; x < n; ++x)
      for (int y = 0; y < n; ++y)
        for (int z = 0; z < n; ++z) {
          if (!at(x, y, z)) continue;
          const int c[3] = {x, y, z};
          for (int a = 0; a < 3; ++a)
            for (int s = 0; s < 2; ++s) {
              int nb[3] = {x, y, z};
              nb[a] += s ? 1 : -1;
              if (at(nb[0], nb[1], nb[2])) continue;
              const int u = c[(a + 1) % 3], v = c[(a + 2) % 3];
              addQuad(tris, faceQuad(pool, a, c[a] + s, u, v, u + 1, v + 1, s == 1));
            }
        }
    return Mesh(pool.vertices, tris, name);
  }
};

/// A 12-triangle box with integer corners lo < hi, outward-oriented.
Mesh boxMesh(const std::array<int, 3>& lo, const std::array<int, 3>& hi, const std::string& name = "box") {
  VertexPool pool;
  std::vector<TriangleIndices> tris;
  for (int a = 0; a < 3; ++a) {
    const int u = (a + 1) % 3, v = (a + 2) % 3;
    addQuad(tris, faceQuad(pool, a, hi[a], lo[u], lo[v], hi[u], hi[v], true));
    addQuad(tris, faceQuad(pool, a, lo[a], lo[u], lo[v], hi[u], hi[v], false));
  }
  return Mesh(pool.vertices, tris, name);
}

using I3 = std::array<long long, 3>;
long long orient(const I3& a, const I3& b, const I3& c, const I3& d) {
  const long long bx = b[0] - a[0], by = b[1] - a[1], bz = b[2] - a[2];
  const long long cx = c[0] - a[0], cy = c[1] - a[1], cz = c[2] - a[2];
  const long long dx = d[0] - a[0], dy = d[1] - a[1], dz = d[2] - a[2];
  return bx * (cy * dz - cz * dy) - by * (cx * dz - cz * dx) + bz * (cx * dy - cy * dx);
}

Vec3 half(const std::array<int, 3>& q) { return Vec3(Real(q[0]) / 2, Real(q[1]) / 2, Real(q[2]) / 2); }

// ---- closedness -----------------------------------------------------------------------------

TEST(MeshVolumeClosedness, BoxIsClosed) {
  const Mesh m = boxMesh({0, 0, 0}, {2, 3, 4});
  const MeshClosedness c = closedness(m);
  EXPECT_TRUE(c.closed());
  EXPECT_EQ(c.boundaryEdges, 0u);
  EXPECT_EQ(c.effectiveTriangles, 12u);
  EXPECT_EQ(c.reason(m.name()), "");
  EXPECT_EQ(isClosed(m), m.stats().closed());
}

TEST(MeshVolumeClosedness, OpenBoxNamesTheBoundaryEdge) {
  const Mesh closed = boxMesh({0, 0, 0}, {1, 1, 1});
  std::vector<TriangleIndices> tris = closed.triangles();
  const TriangleIndices removed = tris.back();
  tris.pop_back();
  const Mesh open(closed.vertices(), tris, "lid");
  const MeshClosedness c = closedness(open);
  EXPECT_FALSE(c.closed());
  EXPECT_EQ(c.boundaryEdges, 3u);
  EXPECT_EQ(c.edgeUses, 1u);
  std::set<std::uint32_t> corners(removed.begin(), removed.end());
  EXPECT_TRUE(corners.count(c.edgeI) && corners.count(c.edgeJ));
  const std::string expected = "mesh \"lid\" is not closed: edge (" + std::to_string(c.edgeI) + "," +
                               std::to_string(c.edgeJ) + ") is used by 1 triangle";
  try {
    (void)pointInside(open, Vec3(Real(0.5), Real(0.5), Real(0.5)));
    ADD_FAILURE() << "pointInside accepted an open mesh";
  } catch (const InvalidInput& e) {
    EXPECT_EQ(std::string(e.what()).rfind(expected, 0), 0u) << e.what();
  }
  EXPECT_THROW(MeshVolume{open}, InvalidInput);
  EXPECT_THROW((void)overlapsVolume(open, Sphere{Vec3::Zero(), 1}), InvalidInput);
  EXPECT_THROW((void)overlapsVolume(open, Aabb{Vec3::Zero(), Vec3::Ones()}), InvalidInput);
}

TEST(MeshVolumeClosedness, FlippedTriangleIsInconsistent) {
  const Mesh closed = boxMesh({0, 0, 0}, {1, 1, 1});
  std::vector<TriangleIndices> tris = closed.triangles();
  std::swap(tris[0][1], tris[0][2]);
  const MeshClosedness c = closedness(Mesh(closed.vertices(), tris, "flipped"));
  EXPECT_FALSE(c.closed());
  EXPECT_EQ(c.inconsistentEdges, 3u);
  EXPECT_TRUE(c.edgeSameDirection);
  EXPECT_NE(c.reason("flipped").find("same direction"), std::string::npos) << c.reason("flipped");
}

TEST(MeshVolumeClosedness, EdgeSharedByFourTrianglesIsNonManifold) {
  VoxelSet v(2);  // two cubes touching along one edge only
  v.set(0, 0, 0, true);
  v.set(1, 1, 0, true);
  const Mesh m = v.mesh("diagonal");
  const MeshClosedness c = closedness(m);
  EXPECT_FALSE(c.closed());
  EXPECT_EQ(c.nonManifoldEdges, 1u);
  EXPECT_EQ(c.edgeUses, 4u);
  EXPECT_THROW(MeshVolume{m}, InvalidInput);
}

TEST(MeshVolumeClosedness, TrianglesRepeatingAnIndexAreSkipped) {
  const Mesh closed = boxMesh({0, 0, 0}, {1, 1, 1});
  std::vector<TriangleIndices> tris = closed.triangles();
  tris.push_back({0, 0, 1});
  tris.push_back({2, 2, 2});
  const MeshClosedness c = closedness(Mesh(closed.vertices(), tris, "repeats"));
  EXPECT_TRUE(c.closed());
  EXPECT_EQ(c.skippedTriangles, 2u);
  const MeshClosedness none = closedness(Mesh(closed.vertices(), {{0, 0, 1}}, "nothing"));
  EXPECT_FALSE(none.closed());
  EXPECT_NE(none.reason("nothing").find("no triangle with three distinct"), std::string::npos);
}

// ---- point inside ---------------------------------------------------------------------------

/// Every half-integer point of the mesh's bounds grown by 1/2 against the voxel reference and
/// CGAL.
void checkVoxels(const VoxelSet& v, const std::string& name, int& hits, int& total) {
  const Mesh m = v.mesh(name);
  ASSERT_TRUE(isClosed(m)) << closedness(m).reason(name);
  const MeshVolume vol(m);
  const CgalSide cgal(m);
  const Aabb b = m.bounds();
  for (int x = int(2 * b.min.x()) - 1; x <= int(2 * b.max.x()) + 1; ++x)
    for (int y = int(2 * b.min.y()) - 1; y <= int(2 * b.max.y()) + 1; ++y)
      for (int z = int(2 * b.min.z()) - 1; z <= int(2 * b.max.z()) + 1; ++z) {
        const std::array<int, 3> q{x, y, z};
        const Vec3 p = half(q);
        const bool expected = v.containsHalf(q);
        const bool got = vol.contains(p);
        ASSERT_EQ(got, expected) << name << " p = " << str17(p);
        ASSERT_EQ(cgal.inside(p), expected) << "reference disagrees with CGAL: " << name << " p = " << str17(p);
        hits += got, ++total;
      }
}

TEST(MeshVolumePointInside, UnionsOfCubesMatchVoxelsAndCgal) {
  std::mt19937 rng(20261122);
  int hits = 0, total = 0, meshes = 0;
  for (int trial = 0; meshes < 12 && trial < 400; ++trial) {
    const int n = 4;
    VoxelSet v(n);
    std::uniform_int_distribution<int> coord(0, n - 1);
    const int boxes = 1 + trial % 3;
    for (int b = 0; b < boxes; ++b) {
      int lo[3], hi[3];
      for (int i = 0; i < 3; ++i) {
        lo[i] = coord(rng), hi[i] = coord(rng);
        if (lo[i] > hi[i]) std::swap(lo[i], hi[i]);
      }
      for (int x = lo[0]; x <= hi[0]; ++x)
        for (int y = lo[1]; y <= hi[1]; ++y)
          for (int z = lo[2]; z <= hi[2]; ++z) v.set(x, y, z, true);
    }
    if (!isClosed(v.mesh("probe"))) continue;  // edge/vertex-only contacts are not manifold
    checkVoxels(v, "voxels" + std::to_string(trial), hits, total);
    if (HasFatalFailure()) return;
    ++meshes;
  }
  EXPECT_EQ(meshes, 12);
  const double rate = double(hits) / total;
  std::printf("unions of cubes: %d meshes, %d points, inside rate %.3f\n", meshes, total, rate);
  EXPECT_GE(rate, 0.2);
  EXPECT_LE(rate, 0.8);
}

TEST(MeshVolumePointInside, HollowCubeHasAnEmptyCavity) {
  VoxelSet v(3);
  for (int x = 0; x < 3; ++x)
    for (int y = 0; y < 3; ++y)
      for (int z = 0; z < 3; ++z) v.set(x, y, z, !(x == 1 && y == 1 && z == 1));
  int hits = 0, total = 0;
  checkVoxels(v, "hollow", hits, total);
  const Mesh hollow = v.mesh("hollow");
  const MeshVolume vol(hollow);
  EXPECT_FALSE(vol.contains(Vec3(Real(1.5), Real(1.5), Real(1.5))));   // cavity centre
  EXPECT_TRUE(vol.contains(Vec3(Real(1), Real(1.5), Real(1.5))));      // cavity wall
  EXPECT_TRUE(vol.contains(Vec3(Real(0.5), Real(1.5), Real(1.5))));    // in the shell
}

TEST(MeshVolumePointInside, TetrahedraMatchBarycentricSigns) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> coord(-6, 6);
  int hits = 0, total = 0;
  for (int t = 0; t < 40; ++t) {
    I3 c[4];
    for (auto& v : c)
      for (auto& x : v) x = coord(rng);
    long long vol6 = orient(c[0], c[1], c[2], c[3]);
    if (vol6 == 0) continue;
    if (vol6 > 0) std::swap(c[1], c[2]);  // make (0,1,2) face outward: orient(...,3) < 0
    std::vector<Vec3> verts;
    for (auto& v : c) verts.push_back(Vec3(Real(v[0]), Real(v[1]), Real(v[2])));
    const std::vector<TriangleIndices> tris{{0, 1, 2}, {0, 3, 1}, {1, 3, 2}, {2, 3, 0}};
    const Mesh m(verts, tris, "tetra" + std::to_string(t));
    ASSERT_TRUE(isClosed(m));
    const MeshVolume volume(m);
    const CgalSide cgal(m);
    std::uniform_int_distribution<int> q(-12, 12);  // half-integer points in the tetra's range
    for (int k = 0; k < 300; ++k) {
      I3 p2;
      std::array<int, 3> qi;
      // half the points uniform, half at corners / edge midpoints / face centroid-like grid points
      for (int i = 0; i < 3; ++i) {
        long long lo = c[0][i], hi = c[0][i];
        for (auto& v : c) lo = std::min(lo, v[i]), hi = std::max(hi, v[i]);
        std::uniform_int_distribution<int> r(int(2 * lo) - 1, int(2 * hi) + 1);
        qi[i] = r(rng);
      }
      if (k % 5 == 0) {  // a corner or an edge midpoint
        const I3& a = c[k % 4];
        const I3& b = c[(k / 5) % 4];
        for (int i = 0; i < 3; ++i) qi[i] = int(a[i] + b[i]);
      }
      for (int i = 0; i < 3; ++i) p2[i] = qi[i];
      I3 c2[4];
      for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 3; ++i) c2[j][i] = 2 * c[j][i];
      const bool expected = orient(c2[0], c2[1], c2[2], p2) <= 0 && orient(c2[0], c2[3], c2[1], p2) <= 0 &&
                            orient(c2[1], c2[3], c2[2], p2) <= 0 && orient(c2[2], c2[3], c2[0], p2) <= 0;
      const Vec3 p = half(qi);
      ASSERT_EQ(volume.contains(p), expected) << m.name() << " p = " << str17(p);
      ASSERT_EQ(cgal.inside(p), expected) << m.name() << " p = " << str17(p);
      hits += expected, ++total;
    }
  }
  const double rate = double(hits) / total;
  std::printf("tetrahedra: %d points, inside rate %.3f\n", total, rate);
  EXPECT_GE(rate, 0.2);
  EXPECT_LE(rate, 0.8);
}

/// A box whose top face has a T-junction at the midpoint m of edge ab, closed by the zero-area
/// triangle (a, b, m): rays through it, and points on it, must still be exact.
TEST(MeshVolumePointInside, ZeroAreaTriangleClosingATJunction) {
  const Mesh base = boxMesh({0, 0, 0}, {4, 4, 4});
  std::vector<Vec3> verts = base.vertices();
  std::vector<TriangleIndices> tris;
  auto find = [&](int x, int y, int z) {
    for (std::uint32_t i = 0; i < verts.size(); ++i)
      if (verts[i] == Vec3(Real(x), Real(y), Real(z))) return i;
    ADD_FAILURE() << "no vertex";
    return 0u;
  };
  const std::uint32_t a = find(0, 0, 4), b = find(4, 0, 4), c = find(4, 4, 4), d = find(0, 4, 4);
  for (const TriangleIndices& t : base.triangles()) {
    bool top = true;
    for (std::uint32_t i : t) top &= verts[i].z() == 4;
    if (!top) tris.push_back(t);
  }
  const std::uint32_t m = std::uint32_t(verts.size());
  verts.push_back(Vec3(2, 0, 4));
  tris.push_back({a, m, d});
  tris.push_back({m, b, c});
  tris.push_back({m, c, d});
  tris.push_back({a, b, m});  // zero area
  const Mesh mesh(verts, tris, "tjunction");
  ASSERT_TRUE(isClosed(mesh)) << closedness(mesh).reason("tjunction");
  EXPECT_EQ(mesh.stats().degenerateTriangles, 1u);
  const MeshVolume vol(mesh);
  int total = 0;
  for (int x = -1; x <= 9; ++x)
    for (int y = -1; y <= 9; ++y)
      for (int z = -1; z <= 9; ++z) {
        const Vec3 p = half({x, y, z});
        const bool expected = x >= 0 && x <= 8 && y >= 0 && y <= 8 && z >= 0 && z <= 8;
        ASSERT_EQ(vol.contains(p), expected) << "p = " << str17(p);
        ++total;
      }
  // Points on the zero-area triangle's segment, and rays from below it along its plane.
  EXPECT_TRUE(vol.contains(Vec3(1, 0, 4)));
  EXPECT_TRUE(vol.contains(Vec3(3, 0, 4)));
  EXPECT_FALSE(vol.contains(Vec3(5, 0, 4)));
  EXPECT_FALSE(vol.contains(Vec3(-1, 0, 4)));
  EXPECT_EQ(total, 11 * 11 * 11);
}

/// The first ray direction d(0) = (1009, 1361, 1777) aimed exactly at a box corner or along a
/// box edge: the crossing count of that ray is ambiguous, so another direction must be used.
TEST(MeshVolumePointInside, RayThroughAVertexOrEdgeRetriesAnotherDirection) {
  const Mesh corner = boxMesh({-1, -1, -1}, {1009, 1361, 1777}, "corner");
  const Mesh edge = boxMesh({-1, -1, -1}, {1009, 1361, 2000}, "edge");
  const Mesh far = boxMesh({0, 0, 0}, {10, 10, 10}, "far");
  EXPECT_TRUE(MeshVolume(corner).contains(Vec3(0, 0, 0)));
  EXPECT_TRUE(MeshVolume(edge).contains(Vec3(0, 0, 0)));
  EXPECT_FALSE(MeshVolume(far).contains(Vec3(-1009, -1361, -1777)));  // through corner (0,0,0)
  EXPECT_FALSE(MeshVolume(far).contains(Vec3(-1009, -1361, -1772)));  // through edge x=y=0
  EXPECT_TRUE(MeshVolume(far).contains(Vec3(0, 0, 5)));               // on a face
  EXPECT_TRUE(MeshVolume(far).contains(Vec3(0, 0, 0)));               // on a vertex
}

// A MeshVolume keeps no copy of the positions (closedness depends on the indices only, which
// setVertices cannot change): after the mesh's vertices move, the same volume answers for the new
// positions, never the old ones.
TEST(MeshVolumePointInside, AnswersForTheCurrentVerticesAfterSetVertices) {
  Mesh box = boxMesh({0, 0, 0}, {2, 2, 2});
  const MeshVolume vol(box);
  const Vec3 oldCentre(1, 1, 1), newCentre(1, 1, 11);
  EXPECT_TRUE(vol.contains(oldCentre));
  EXPECT_FALSE(vol.contains(newCentre));
  EXPECT_TRUE(vol.overlaps(Sphere{oldCentre, Real(0.25)}));
  std::vector<Vec3> moved = box.vertices();
  for (Vec3& p : moved) p += Vec3(0, 0, 10);
  box.setVertices(moved);
  EXPECT_FALSE(vol.contains(oldCentre));
  EXPECT_TRUE(vol.contains(newCentre));
  EXPECT_TRUE(vol.onSurface(Vec3(1, 1, 10)));
  EXPECT_FALSE(vol.onSurface(Vec3(1, 1, 0)));
  EXPECT_FALSE(vol.overlaps(Sphere{oldCentre, Real(0.25)}));
  EXPECT_TRUE(vol.overlaps(Sphere{newCentre, Real(0.25)}));
}

TEST(MeshVolumePointInside, NoHeapAllocation) {
  VoxelSet v(4);
  for (int x = 0; x < 3; ++x)
    for (int y = 0; y < 3; ++y) v.set(x, y, 1, true);
  const Mesh m = v.mesh("slab");
  const MeshVolume vol(m);
  const long before = test::allocationCount();
  int inside = 0;
  for (int k = 0; k < 200; ++k) inside += vol.contains(Vec3(Real(k % 9) / 2, Real(k % 7) / 2, Real(k % 5) / 2));
  inside += vol.overlaps(Sphere{Vec3(1, 1, 1), Real(0.25)});
  inside += vol.overlaps(Aabb{Vec3(1, 1, 1), Vec3(2, 2, 2)});
  EXPECT_EQ(test::allocationCount(), before);
  EXPECT_GT(inside, 0);
}

// ---- volume overlaps ------------------------------------------------------------------------

TEST(MeshVolumeOverlaps, ShapeWhollyInsideOverlapsOnlyInVolumeMode) {
  const Mesh m = boxMesh({-4, -4, -4}, {4, 4, 4});
  const MeshVolume vol(m);
  const Sphere s{Vec3(1, 1, 1), 1};
  const Aabb b{Vec3(-1, -1, -1), Vec3(1, 2, 3)};
  Obb o;
  o.center = Vec3(0, 1, 0), o.half = Vec3(1, 1, 1);
  const Triangle t{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  EXPECT_FALSE(overlaps(m, s));  // surface mode (FCL/Bullet semantics): free
  EXPECT_FALSE(overlaps(m, b));
  EXPECT_FALSE(overlaps(m, o));
  EXPECT_FALSE(overlaps(m, t));
  EXPECT_TRUE(vol.overlaps(s));
  EXPECT_TRUE(vol.overlaps(b));
  EXPECT_TRUE(vol.overlaps(o));
  EXPECT_TRUE(vol.overlaps(t));
  EXPECT_TRUE(overlapsVolume(m, s));
  EXPECT_TRUE(overlapsVolume(m, b));
  EXPECT_TRUE(overlapsVolume(m, o));
  EXPECT_TRUE(overlapsVolume(m, t));
  // Outside and apart: free in both modes; touching the surface from outside: overlapping.
  EXPECT_FALSE(vol.overlaps(Sphere{Vec3(7, 0, 0), 2}));
  EXPECT_TRUE(vol.overlaps(Sphere{Vec3(6, 0, 0), 2}));
  EXPECT_FALSE(vol.overlaps(Aabb{Vec3(5, 5, 5), Vec3(6, 6, 6)}));
  EXPECT_TRUE(vol.overlaps(Aabb{Vec3(4, 4, 4), Vec3(6, 6, 6)}));
  EXPECT_FALSE(vol.overlaps(Triangle{Vec3(5, 0, 0), Vec3(6, 0, 0), Vec3(5, 1, 0)}));
}

/// Mesh–mesh volume mode: a small closed box wholly inside a big one overlaps only in volume
/// mode (the surface test, FCL's and Bullet's semantics, says free), from either side; one
/// closed operand suffices (the other is a surface: an open box around the small solid is a
/// sheet outside it).
TEST(MeshVolumeOverlaps, NestedMeshesOverlapOnlyInVolumeMode) {
  const Mesh big = boxMesh({-4, -4, -4}, {4, 4, 4}, "big");
  const Mesh small = boxMesh({-1, -1, -1}, {1, 2, 1}, "small");
  const MeshVolume vBig(big), vSmall(small);
  const Transform id;
  EXPECT_FALSE(overlaps(big, id, small, id));
  EXPECT_TRUE(overlapsVolume(vBig, id, small, id));
  EXPECT_FALSE(overlapsVolume(vSmall, id, big, id));  // big's surface is outside small's solid
  EXPECT_TRUE(overlapsVolume(vSmall, id, vBig, id));
  EXPECT_TRUE(overlapsVolume(vBig, id, vSmall, id));
  // Moved out (touching, then apart) by integer translations.
  Transform out;
  out.translation = Vec3(5, 0, 0);  // small spans x in [4, 6]: touches big's face x = 4
  EXPECT_TRUE(overlapsVolume(vBig, id, vSmall, out));
  out.translation = Vec3(6, 0, 0);
  EXPECT_FALSE(overlapsVolume(vBig, id, vSmall, out));
  EXPECT_FALSE(overlapsVolume(vSmall, out, vBig, id));
  // An open box (one face removed) around the small solid: surface only, outside it.
  std::vector<TriangleIndices> tris = big.triangles();
  tris.resize(tris.size() - 2);
  const Mesh open(big.vertices(), tris, "open");
  EXPECT_FALSE(isClosed(open));
  EXPECT_FALSE(overlapsVolume(vSmall, id, open, id));
  EXPECT_TRUE(overlapsVolume(vBig, id, open, id));  // the surfaces coincide
}

/// Integer-grid boxes under axis-aligned rotations (quarter and half turns) and integer
/// translations stay axis-aligned integer boxes, so the solids overlap iff their world
/// intervals overlap on every axis: an independent exact reference for volume mode.
TEST(MeshVolumeOverlaps, RandomGridBoxPairsMatchIntervalOverlap) {
  std::mt19937 rng(20261122);
  std::uniform_int_distribution<int> coord(-3, 3), size(1, 6), turn(0, 3), shift(-1, 1);
  const Real h = std::sqrt(Real(0.5));
  // Rotation about z by k quarter turns, as a quaternion and as its integer action on (x, y).
  const Quat turns[4] = {Quat::Identity(), Quat(h, 0, 0, h), Quat(0, 0, 0, 1), Quat(h, 0, 0, -h)};
  const auto rotate = [](int k, long long x, long long y) -> std::array<long long, 2> {
    switch (k) {
      case 1: return {-y, x};
      case 2: return {-x, -y};
      case 3: return {y, -x};
      default: return {x, y};
    }
  };
  int hits = 0, nested = 0;
  for (int it = 0; it < 300; ++it) {
    std::array<int, 3> lo[2], hi[2];
    Transform tf[2];
    std::array<long long, 3> wlo[2], whi[2];
    int k[2];
    for (int m = 0; m < 2; ++m) {
      // Even cases: a big, b small (often nested); odd cases: both of any size.
      for (int i = 0; i < 3; ++i)
        lo[m][i] = coord(rng), hi[m][i] = lo[m][i] + (it % 2 ? size(rng) : m == 0 ? 5 + size(rng) : 1);
      k[m] = turn(rng);
      tf[m].rotation = turns[k[m]];
      tf[m].translation = Vec3(Real(shift(rng)), Real(shift(rng)), Real(shift(rng)));
      const auto p = rotate(k[m], lo[m][0], lo[m][1]), q = rotate(k[m], hi[m][0], hi[m][1]);
      wlo[m] = {std::min(p[0], q[0]), std::min(p[1], q[1]), lo[m][2]};
      whi[m] = {std::max(p[0], q[0]), std::max(p[1], q[1]), hi[m][2]};
      for (int i = 0; i < 3; ++i) wlo[m][i] += (long long)tf[m].translation[i], whi[m][i] += (long long)tf[m].translation[i];
    }
    bool want = true, inside = true;
    for (int i = 0; i < 3; ++i) {
      want = want && wlo[0][i] <= whi[1][i] && wlo[1][i] <= whi[0][i];
      inside = inside && wlo[0][i] < wlo[1][i] && whi[1][i] < whi[0][i];
    }
    const Mesh a = boxMesh(lo[0], hi[0], "a"), b = boxMesh(lo[1], hi[1], "b");
    const MeshVolume va(a), vb(b);
    const bool got = overlapsVolume(va, tf[0], vb, tf[1]);
    const bool gotOne = overlapsVolume(va, tf[0], b, tf[1]);  // b as a surface: same unless a is inside b
    hits += want;
    nested += inside;
    ASSERT_EQ(got, want) << "case " << it << ": a [" << wlo[0][0] << "," << wlo[0][1] << "," << wlo[0][2] << "]-["
                         << whi[0][0] << "," << whi[0][1] << "," << whi[0][2] << "] turn " << k[0] << " t "
                         << str17(tf[0].translation) << ", b [" << wlo[1][0] << "," << wlo[1][1] << "," << wlo[1][2]
                         << "]-[" << whi[1][0] << "," << whi[1][1] << "," << whi[1][2] << "] turn " << k[1] << " t "
                         << str17(tf[1].translation);
    if (inside) {
      EXPECT_TRUE(gotOne) << "case " << it;
      EXPECT_FALSE(overlaps(a, tf[0], b, tf[1])) << "case " << it << ": nested surfaces do not touch";
    }
  }
  std::printf("grid box pairs: %d of 300 overlap, %d with b strictly inside a\n", hits, nested);
  EXPECT_GT(hits, 30);
  EXPECT_LT(hits, 270);
  EXPECT_GT(nested, 5);
}

TEST(MeshVolumeOverlaps, RandomSpheresMatchSurfaceOrCentreInside) {
  VoxelSet v(4);
  for (int x = 0; x < 4; ++x)
    for (int y = 0; y < 4; ++y)
      for (int z = 0; z < 4; ++z) v.set(x, y, z, x == 0 || z == 0 || (y == 3 && x < 3));
  const Mesh m = v.mesh("bracket");
  ASSERT_TRUE(isClosed(m));
  const MeshVolume vol(m);
  std::mt19937 rng(99);
  std::uniform_int_distribution<int> q(-2, 10);
  std::uniform_int_distribution<int> r(0, 2);
  int hits = 0, total = 0;
  for (int k = 0; k < 2000; ++k) {
    const std::array<int, 3> c{q(rng), q(rng), q(rng)};
    const Sphere s{half(c), Real(r(rng)) / 4};
    // Reference: surface contact, or centre in the union of closed voxels (exact).
    const bool expected = overlaps(m, s) || v.containsHalf(c);
    ASSERT_EQ(vol.overlaps(s), expected) << "centre " << str17(s.center) << " radius " << s.radius;
    hits += expected, ++total;
  }
  const double rate = double(hits) / total;
  std::printf("volume sphere overlaps: %d, rate %.3f\n", total, rate);
  EXPECT_GE(rate, 0.2);
  EXPECT_LE(rate, 0.8);
}

// ---- real meshes ----------------------------------------------------------------------------

TEST(MeshVolumeRealMeshes, Bunny00) {
  const std::string path = std::string(CRUX_SOURCE_DIR) + "/data/meshes/bunny00.off";
  if (!std::ifstream(path)) GTEST_SKIP() << path << " missing (run scripts/setup)";
  const Mesh m = loadMesh(path);
  const MeshClosedness c = closedness(m);
  std::printf("bunny00: %zu triangles, closed %d (%zu boundary, %zu non-manifold, %zu inconsistent)\n",
              m.triangleCount(), int(c.closed()), c.boundaryEdges, c.nonManifoldEdges, c.inconsistentEdges);
  if (!c.closed()) {
    EXPECT_THROW(MeshVolume{m}, InvalidInput);
    GTEST_SKIP() << c.reason(m.name());
  }
  const MeshVolume vol(m);
  const CgalSide cgal(m);
  std::mt19937 rng(5);
  const Aabb box = m.bounds();
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Vec3> pts;
  for (int k = 0; k < 2000; ++k) {
    Vec3 p;
    for (int i = 0; i < 3; ++i) p[i] = Real(box.min[i] + (box.max[i] - box.min[i]) * u(rng));
    if (k % 10 == 0) p = m.vertices()[std::size_t(k) % m.vertexCount()];
    pts.push_back(p);
  }
  int hits = 0;
  const auto start = std::chrono::steady_clock::now();
  std::vector<char> got;
  for (const Vec3& p : pts) got.push_back(vol.contains(p));
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (std::size_t k = 0; k < pts.size(); ++k) {
    ASSERT_EQ(bool(got[k]), cgal.inside(pts[k])) << "p = " << str17(pts[k]);
    hits += got[k];
  }
  std::printf("bunny00: %zu points, inside rate %.3f, %.2f us/query\n", pts.size(), double(hits) / pts.size(),
              1e6 * secs / pts.size());
}

}  // namespace
}  // namespace crux
