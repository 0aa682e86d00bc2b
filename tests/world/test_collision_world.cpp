// The narrow-phase and volume ops of crux::CollisionWorld (src/world/collision_world.cpp, the
// native hooks in src/world/native_world.cpp, the peers' in oracle/): validation at the edge,
// the conventions (normals B→A, signed distance, operand order), and cross-backend agreement:
//  - point_inside and volume-mode booleans: native == exact (CGAL Side_of_triangle_mesh) on
//    integer / half-integer grids, where every answer must be exact in float and double builds;
//  - distance and mesh_distance: native vs fcl::distance on separated pairs, within the stated
//    tolerance kDistanceTolerance below.

#include <crux/geometry/contact.hpp>
#include <crux/mesh/mesh_volume.hpp>
#include <crux/world/collision_world.hpp>
#include <crux/world/native_world.hpp>
#include <world_factory.hpp>

#include <support/test_scale.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>
#include "support/printing.hpp"

namespace crux {
namespace {

using test_support::str;

bool built(std::string_view backend) {
  const auto& b = builtBackends();
  return std::find(b.begin(), b.end(), backend) != b.end();
}

/// A closed voxel solid: the boundary faces between filled and empty unit cells, two
/// counter-clockwise (seen from outside) triangles each, vertices shared by index. The voxel
/// set must have no two cells touching only along an edge (which would make that edge
/// non-manifold).
std::shared_ptr<const Mesh> voxelMesh(const std::vector<std::array<int, 3>>& cells, const std::string& name) {
  std::map<std::array<int, 3>, bool> filled;
  for (const auto& c : cells) filled[c] = true;
  std::map<std::array<int, 3>, std::uint32_t> index;
  std::vector<Vec3> vertices;
  const auto vertex = [&](std::array<int, 3> p) {
    const auto it = index.find(p);
    if (it != index.end()) return it->second;
    vertices.emplace_back(Real(p[0]), Real(p[1]), Real(p[2]));
    return index[p] = std::uint32_t(vertices.size() - 1);
  };
  std::vector<TriangleIndices> triangles;
  for (const auto& c : cells) {
    for (int axis = 0; axis < 3; ++axis) {
      for (int side = 0; side < 2; ++side) {
        std::array<int, 3> n = c;
        n[axis] += side ? 1 : -1;
        if (filled.count(n)) continue;
        // The face's four corners in counter-clockwise order seen from the outside (+axis for
        // side 1): u, v are the other two axes in cyclic order.
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        std::array<int, 3> q[4];
        for (auto& p : q) p = c;
        for (auto& p : q) p[axis] += side;
        q[1][u] += 1;
        q[2][u] += 1;
        q[2][v] += 1;
        q[3][v] += 1;
        std::uint32_t k[4];
        for (int i = 0; i < 4; ++i) k[i] = vertex(q[i]);
        if (side) {
          triangles.push_back({k[0], k[1], k[2]});
          triangles.push_back({k[0], k[2], k[3]});
        } else {
          triangles.push_back({k[0], k[2], k[1]});
          triangles.push_back({k[0], k[3], k[2]});
        }
      }
    }
  }
  return std::make_shared<const Mesh>(std::move(vertices), std::move(triangles), name);
}

/// A 3-D cross: the cell at the origin and its six face neighbours (non-convex, closed).
std::shared_ptr<const Mesh> crossMesh() {
  return voxelMesh({{0, 0, 0}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}}, "cross");
}

/// An open square (two triangles): not closed.
std::shared_ptr<const Mesh> quadMesh() {
  return std::make_shared<const Mesh>(std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}},
                                      std::vector<TriangleIndices>{{0, 1, 2}, {0, 2, 3}}, "quad");
}

std::shared_ptr<const Mesh> boxMesh(const Vec3& lo, const Vec3& hi, const std::string& name) {
  std::vector<Vec3> v;
  for (int k = 0; k < 8; ++k) v.emplace_back((k & 1) ? hi.x() : lo.x(), (k & 2) ? hi.y() : lo.y(), (k & 4) ? hi.z() : lo.z());
  // Outward counter-clockwise faces of the corner numbering k = x + 2y + 4z.
  const std::vector<TriangleIndices> t = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                                          {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  return std::make_shared<const Mesh>(std::move(v), t, name);
}

Obb axisBox(const Vec3& center, const Vec3& half) {
  Obb b;
  b.center = center;
  b.half = half;
  b.axes = Mat3::Identity();
  return b;
}

// ---------------------------------------------------------------------------------------------
// Validation at the edge.

TEST(CollisionWorldNarrowPhase, BadInputNamesTheField) {
  const auto w = makeNativeWorld();
  const MeshHandle cube = w->addMesh("cube", boxMesh(Vec3(0, 0, 0), Vec3(1, 1, 1), "cube"));
  const auto message = [](auto&& f) -> std::string {
    try {
      f();
    } catch (const InvalidInput& e) {
      return e.what();
    }
    return "";
  };
  const Real nan = std::numeric_limits<Real>::quiet_NaN();
  const WorldOperand sphere{Sphere{Vec3(0, 0, 3), 1}, Transform{}};
  EXPECT_EQ(message([&] { w->contacts(sphere, {cube, Transform{}}, -1); }).rfind("margin:", 0), 0u);
  EXPECT_EQ(message([&] { w->contacts(sphere, {cube, Transform{}}, std::nan("")); }).rfind("margin:", 0), 0u);
  EXPECT_EQ(message([&] { w->contacts({Sphere{Vec3(0, 0, 0), -1}, Transform{}}, {cube, Transform{}}); })
                .rfind("a.sphere.radius", 0),
            0u);
  EXPECT_EQ(message([&] { w->distance(sphere, {Capsule{Vec3(0, 0, 0), Vec3(nan, 0, 0), 1}, Transform{}}); })
                .rfind("b.capsule", 0),
            0u);
  EXPECT_EQ(message([&] { w->distance(sphere, {Capsule{Vec3(0, 0, 0), Vec3(1, 0, 0), -1}, Transform{}}); })
                .rfind("b.capsule", 0),
            0u);
  Transform bad;
  bad.rotation = Quat(2, 0, 0, 0);
  EXPECT_EQ(message([&] { w->distance(sphere, {cube, bad}); }).rfind("b.transform.rotation", 0), 0u);
  EXPECT_EQ(message([&] { w->distance({cube, Transform{}}, {cube, Transform{}}); }).rfind("b:", 0), 0u);
  EXPECT_EQ(message([&] { w->contacts({cube, Transform{}}, {cube, Transform{}}); }).rfind("b:", 0), 0u);
  EXPECT_EQ(message([&] { w->distance(sphere, {MeshHandle{77}, Transform{}}); }).rfind("b.mesh", 0), 0u);
  EXPECT_EQ(message([&] { w->meshDistance(cube, Transform{}, cube, Transform{}, -1); }).rfind("max:", 0), 0u);
  EXPECT_EQ(message([&] { w->meshDistance(cube, Transform{}, cube, Transform{}, std::nan("")); }).rfind("max:", 0),
            0u);
  EXPECT_EQ(message([&] { w->modelDistance(ModelHandle{5}, ModelHandle{6}); }).rfind("a:", 0), 0u);
  EXPECT_EQ(message([&] { w->pointInside(cube, Vec3(nan, 0, 0)); }).rfind("point", 0), 0u);
  EXPECT_EQ(message([&] { w->overlapsVolume(cube, Sphere{Vec3(0, 0, 0), -2}); }).rfind("sphere", 0), 0u);
  EXPECT_THROW(ConvexHull::build({}, "b.hull.points"), InvalidInput);
}

TEST(CollisionWorldNarrowPhase, OpenMeshesRefuseVolumeModeOnEveryBackendAlike) {
  for (const std::string_view name : builtBackends()) {
    const auto w = makeWorld(name);
    const MeshHandle quad = w->addMesh("quad", quadMesh());
    if (!w->supports(WorldOp::PointInside)) {
      EXPECT_THROW(w->pointInside(quad, Vec3(0, 0, 0)), Unsupported) << name;
      continue;
    }
    for (int k = 0; k < 2; ++k) {  // the verdict is cached: the second call says the same
      try {
        w->pointInside(quad, Vec3(0.5, 0.5, 1));
        ADD_FAILURE() << name << ": an open mesh answered point_inside";
      } catch (const InvalidInput& e) {
        EXPECT_EQ(std::string(e.what()),
                  "mesh: mesh \"quad\" is not closed: edge (0,1) is used by 1 triangle (4 boundary, 0 non-manifold, 0 "
                  "inconsistently oriented edges)")
            << name;
      }
    }
    EXPECT_THROW(w->overlapsVolume(quad, Sphere{Vec3(0.5, 0.5, 0), 1}), InvalidInput) << name;
    EXPECT_THROW(w->overlapsVolume(quad, axisBox(Vec3(0, 0, 0), Vec3(1, 1, 1))), InvalidInput) << name;
  }
}

// ---------------------------------------------------------------------------------------------
// Volume mode: native == exact (CGAL Side_of_triangle_mesh with Epeck).

TEST(CollisionWorldVolume, PointInsideEqualsExactOnAHalfIntegerGrid) {
  const auto native = makeNativeWorld();
  const auto exact = makeWorld("exact");
  const MeshHandle mn = native->addMesh("cross", crossMesh());
  const MeshHandle me = exact->addMesh("cross", crossMesh());
  int inside = 0, total = 0;
  // Every point of the half-integer grid over [-2.5, 3.5]^3: corners, edges and faces of the
  // cells (surface points count as inside), cell centres, and points outside.
  for (int i = -5; i <= 7; ++i)
    for (int j = -5; j <= 7; ++j)
      for (int k = -5; k <= 7; ++k) {
        const Vec3 p(Real(i) / 2, Real(j) / 2, Real(k) / 2);
        const bool n = native->pointInside(mn, p), e = exact->pointInside(me, p);
        ASSERT_EQ(n, e) << "point " << str(p);
        inside += n;
        ++total;
      }
  std::printf("cross: %d of %d grid points inside (surface included)\n", inside, total);
  EXPECT_GT(inside, 100);
  EXPECT_LT(inside, total - 100);
}

TEST(CollisionWorldVolume, PointInsideEqualsExactOnRealMeshes) {
  const auto native = makeNativeWorld();
  const auto exact = makeWorld("exact");
  std::mt19937_64 rng(20261122);
  for (const char* file : {"3torus.off", "P.off", "anchor.off"}) {
    const auto mesh = std::make_shared<const Mesh>(loadMesh(std::string(CRUX_SOURCE_DIR) + "/data/meshes/" + file));
    const MeshHandle mn = native->addMesh(file, mesh);
    const MeshHandle me = exact->addMesh(file, mesh);
    const Aabb box = mesh->bounds();
    const Vec3 lo = box.min - 0.1f * (box.max - box.min), hi = box.max + 0.1f * (box.max - box.min);
    int inside = 0;
    const int n = test::scaledCases(2000, 200);
    for (int i = 0; i < n; ++i) {
      Vec3 p;
      for (int a = 0; a < 3; ++a) p[a] = std::uniform_real_distribution<Real>(lo[a], hi[a])(rng);
      if (i % 10 == 0) p = mesh->vertices()[std::size_t(i) % mesh->vertexCount()];  // on the surface
      const bool got = native->pointInside(mn, p), want = exact->pointInside(me, p);
      ASSERT_EQ(got, want) << file << " point " << str(p);
      inside += got;
    }
    std::printf("%s: %d of %d points inside\n", file, inside, n);
    EXPECT_GT(inside, n / 10) << file;
  }
}

TEST(CollisionWorldVolume, VolumeModeEqualsExactOnTheGrid) {
  const auto native = makeNativeWorld();
  const auto exact = makeWorld("exact");
  const MeshHandle mn = native->addMesh("cross", crossMesh());
  const MeshHandle me = exact->addMesh("cross", crossMesh());
  std::mt19937_64 rng(6);
  const auto half = [&](int lo, int hi) { return Real(std::uniform_int_distribution<int>(2 * lo, 2 * hi)(rng)) / 2; };
  int hits = 0, insideOnly = 0;
  const int n = test::scaledCases(2000, 300);
  for (int i = 0; i < n; ++i) {
    // Half the centres in the cross's bounding box [-1, 2]^3, so that some shapes lie wholly inside.
    const int lo = (i % 2) ? -3 : -1, hi = (i % 2) ? 4 : 2;
    const Vec3 c(half(lo, hi), half(lo, hi), half(lo, hi));
    const Vec3 h(half(0, 1), half(0, 1), half(0, 1));
    const Sphere s{c, half(0, 1)};
    const Aabb b{c - h, c + h};
    const Obb o = axisBox(c, h);
    const Triangle t{c, c + Vec3(h.x(), 0, 0), c + Vec3(0, h.y(), h.z())};
    const bool got[4] = {native->overlapsVolume(mn, s), native->overlapsVolume(mn, b), native->overlapsVolume(mn, o),
                         native->overlapsVolume(mn, t)};
    const bool want[4] = {exact->overlapsVolume(me, s), exact->overlapsVolume(me, b), exact->overlapsVolume(me, o),
                          exact->overlapsVolume(me, t)};
    for (int k = 0; k < 4; ++k)
      ASSERT_EQ(got[k], want[k]) << "shape " << k << " centre " << str(c) << " half " << str(h) << " radius "
                                 << str(double(s.radius));
    hits += got[0];
    insideOnly += got[0] && !native->overlaps(mn, s);
  }
  std::printf("volume mode: %d of %d spheres touch the cross, %d of them wholly inside\n", hits, n, insideOnly);
  EXPECT_GT(insideOnly, 0);  // the cases the surface test misses are exercised
}

/// mesh_mesh volume: native == exact on half-integer boxes against the (non-convex) cross under
/// quarter/half turns about z and half-integer translations, each mesh placed by its own
/// transform; some boxes lie wholly inside the cross (volume hit, surface miss).
TEST(CollisionWorldVolume, MeshMeshVolumeEqualsExactOnTheGrid) {
  const auto native = makeNativeWorld();
  const auto exact = makeWorld("exact");
  const MeshHandle cn = native->addMesh("cross", crossMesh()), ce = exact->addMesh("cross", crossMesh());
  const MeshHandle qn = native->addMesh("quad", quadMesh()), qe = exact->addMesh("quad", quadMesh());
  std::mt19937_64 rng(66);
  const auto half = [&](int lo, int hi) { return Real(std::uniform_int_distribution<int>(2 * lo, 2 * hi)(rng)) / 2; };
  const Real h = std::sqrt(Real(0.5));
  const Quat turns[4] = {Quat::Identity(), Quat(h, 0, 0, h), Quat(0, 0, 0, 1), Quat(h, 0, 0, -h)};
  int hits = 0, insideOnly = 0, quadHits = 0;
  const int n = test::scaledCases(300, 60);
  for (int i = 0; i < n; ++i) {
    const Vec3 c = i % 3 ? Vec3(half(-1, 2), half(-1, 2), half(-1, 2))
                         : Vec3(Real(0.5), Real(0.5), Real(0.5)) + Vec3::Unit(i % 2 ? 0 : 2) * half(-1, 1);
    const Vec3 e = i % 3 ? Vec3(half(0, 1) + Real(0.25), Real(0.25) + Real(0.5) * (i % 2), half(0, 1) + Real(0.25))
                         : Vec3(Real(0.25), Real(0.25), Real(0.25));
    const std::string name = "box" + std::to_string(i);
    const MeshHandle bn = native->addMesh(name, boxMesh(c - e, c + e, name));
    const MeshHandle be = exact->addMesh(name, boxMesh(c - e, c + e, name));
    Transform ta, tb;
    ta.rotation = turns[std::uniform_int_distribution<int>(0, 3)(rng)];
    tb.rotation = turns[std::uniform_int_distribution<int>(0, 3)(rng)];
    ta.translation = Vec3(half(-1, 1), half(-1, 1), 0);
    tb.translation = Vec3(half(-1, 1), half(-1, 1), half(-1, 1));
    if (i % 3 == 0) tb = ta;  // the box at c relative to the cross: often in one of its cells
    const bool got = native->overlapsVolume(cn, ta, bn, tb), want = exact->overlapsVolume(ce, ta, be, tb);
    ASSERT_EQ(got, want) << "case " << i << ": box " << str(c - e) << " - " << str(c + e) << " placed by q "
                         << str(Vec3(tb.rotation.vec())) << " w " << str(double(tb.rotation.w())) << " t "
                         << str(tb.translation) << "; cross by q " << str(Vec3(ta.rotation.vec())) << " w "
                         << str(double(ta.rotation.w())) << " t " << str(ta.translation);
    // Operand order does not matter; one closed operand (the quad is open) suffices.
    ASSERT_EQ(native->overlapsVolume(bn, tb, cn, ta), got) << "case " << i << " swapped";
    const bool gotQuad = native->overlapsVolume(qn, tb, cn, ta);
    ASSERT_EQ(gotQuad, exact->overlapsVolume(qe, tb, ce, ta)) << "case " << i << ": quad placed by t "
                                                              << str(tb.translation);
    hits += got;
    quadHits += gotQuad;
    insideOnly += got && !native->overlaps(cn, ta, bn, tb);
  }
  std::printf("mesh_mesh volume: %d of %d boxes touch the cross, %d wholly inside; quad: %d\n", hits, n, insideOnly,
              quadHits);
  EXPECT_GT(insideOnly, n / 20);
  EXPECT_LT(hits, n);
}

/// A small closed mesh wholly inside a bigger one: a hit in volume mode (native and exact), no
/// hit in surface mode on every backend (FCL and Bullet answer surfaces only: their "free" is
/// recorded as what it is, and their volume mode is unsupported). Neither operand closed: an
/// error naming both.
TEST(CollisionWorldVolume, NestedMeshesOnEveryBackend) {
  for (const std::string_view name : builtBackends()) {
    const auto w = makeWorld(name);
    const MeshHandle big = w->addMesh("big", boxMesh(Vec3(-4, -4, -4), Vec3(4, 4, 4), "big"));
    const MeshHandle small = w->addMesh("small", boxMesh(Vec3(-1, -1, -1), Vec3(1, 2, 1), "small"));
    const MeshHandle quad = w->addMesh("quad", quadMesh());
    Transform t;
    t.translation = Vec3(1, 0, 0);
    if (w->supports(WorldOp::MeshMesh)) {
      EXPECT_FALSE(w->overlaps(big, Transform{}, small, t)) << name << ": surfaces do not touch";
      std::printf("%-7s mesh_mesh (surface) on nested boxes: free\n", std::string(name).c_str());
    }
    if (!w->supports(WorldOp::MeshMeshVolume)) {
      EXPECT_THROW(w->overlapsVolume(big, Transform{}, small, t), Unsupported) << name;
      continue;
    }
    EXPECT_TRUE(w->overlapsVolume(big, Transform{}, small, t)) << name;
    EXPECT_TRUE(w->overlapsVolume(small, t, big, Transform{})) << name;
    t.translation = Vec3(8, 0, 0);
    EXPECT_FALSE(w->overlapsVolume(big, Transform{}, small, t)) << name;
    try {
      w->overlapsVolume(quad, Transform{}, quad, t);
      ADD_FAILURE() << name << ": two open meshes answered mesh_mesh volume";
    } catch (const InvalidInput& e) {
      EXPECT_EQ(std::string(e.what()),
                "a: mesh_mesh volume needs a closed operand: a: mesh \"quad\" is not closed: edge (0,1) is used by 1 "
                "triangle (4 boundary, 0 non-manifold, 0 inconsistently oriented edges); b: mesh \"quad\" is not "
                "closed: edge (0,1) is used by 1 triangle (4 boundary, 0 non-manifold, 0 inconsistently oriented "
                "edges)")
          << name;
    }
  }
}

/// model_<shape> volume: native == exact for the cross as a child model under a parent, both
/// with quarter turns (about z, or x) and half-integer translations, against half-integer
/// spheres, AABBs, OBBs and triangles in world space; some shapes lie wholly inside (volume hit,
/// surface miss). Also a shape inside the model's local cross but outside its world placement.
TEST(CollisionWorldVolume, ModelVolumeEqualsExactWithAHierarchy) {
  const auto native = makeNativeWorld();
  const auto exact = makeWorld("exact");
  const MeshHandle cn = native->addMesh("cross", crossMesh()), ce = exact->addMesh("cross", crossMesh());
  const MeshHandle qn = native->addMesh("quad", quadMesh()), qe = exact->addMesh("quad", quadMesh());
  std::mt19937_64 rng(67);
  const auto half = [&](int lo, int hi) { return Real(std::uniform_int_distribution<int>(2 * lo, 2 * hi)(rng)) / 2; };
  const Real h = std::sqrt(Real(0.5));
  const Quat turns[6] = {Quat::Identity(), Quat(h, 0, 0, h), Quat(0, 0, 0, 1),
                         Quat(h, 0, 0, -h), Quat(h, h, 0, 0), Quat(0, 1, 0, 0)};
  const auto turn = [&] { return turns[std::uniform_int_distribution<int>(0, 5)(rng)]; };
  int hits = 0, insideOnly = 0;
  const int placements = test::scaledCases(12, 4), shapes = test::scaledCases(150, 60);
  for (int i = 0; i < placements; ++i) {
    Transform tp, tc;
    tp.rotation = turn();
    tp.translation = Vec3(half(-3, 3), half(-3, 3), half(-3, 3));
    tc.rotation = turn();
    tc.translation = Vec3(half(-1, 1), half(-1, 1), half(-1, 1));
    const std::string p = "p" + std::to_string(i), c = "c" + std::to_string(i);
    native->addModel(p, qn, tp);
    exact->addModel(p, qe, tp);
    const ModelHandle mn = native->addModel(c, cn, tc, native->findModel(p));
    const ModelHandle me = exact->addModel(c, ce, tc, exact->findModel(p));
    // The child's world pose is tp ∘ tc; shapes around its image of the cross's box [-1, 2]^3.
    const Vec3 centre = tp.rotation * (tc.rotation * Vec3(Real(0.5), Real(0.5), Real(0.5)) + tc.translation) +
                        tp.translation;
    const Vec3 origin(std::round(centre.x() * 2) / 2, std::round(centre.y() * 2) / 2, std::round(centre.z() * 2) / 2);
    for (int k = 0; k < shapes; ++k) {
      const Vec3 c0 = origin + Vec3(half(-2, 2), half(-2, 2), half(-2, 2));
      const Vec3 e(half(0, 1), half(0, 1), half(0, 1));
      const Sphere s{c0, half(0, 1)};
      const Aabb b{c0 - e, c0 + e};
      const Obb o = axisBox(c0, e);
      const Triangle t{c0, c0 + Vec3(e.x(), 0, 0), c0 + Vec3(0, e.y(), e.z())};
      const bool got[4] = {native->overlapsVolume(mn, s), native->overlapsVolume(mn, b),
                           native->overlapsVolume(mn, o), native->overlapsVolume(mn, t)};
      const bool want[4] = {exact->overlapsVolume(me, s), exact->overlapsVolume(me, b),
                            exact->overlapsVolume(me, o), exact->overlapsVolume(me, t)};
      for (int j = 0; j < 4; ++j)
        ASSERT_EQ(got[j], want[j]) << "placement " << i << " shape " << j << " centre " << str(c0) << " half "
                                   << str(e) << " radius " << str(double(s.radius)) << "; parent q "
                                   << str(Vec3(tp.rotation.vec())) << " w " << str(double(tp.rotation.w())) << " t "
                                   << str(tp.translation) << "; child q " << str(Vec3(tc.rotation.vec())) << " w "
                                   << str(double(tc.rotation.w())) << " t " << str(tc.translation);
      hits += got[0] + got[1] + got[2] + got[3];
      insideOnly += got[0] && !native->overlaps(mn, s);
    }
  }
  std::printf("model volume: %d of %d shape queries hit, %d spheres wholly inside\n", hits, 4 * placements * shapes,
              insideOnly);
  EXPECT_GT(insideOnly, 0);
  EXPECT_LT(hits, 4 * placements * shapes);
}

/// A sphere wholly inside a closed model overlaps in volume mode on native and exact (and only
/// there: FCL and Bullet say unsupported); an open model is refused naming model and mesh.
TEST(CollisionWorldVolume, ModelVolumeOnEveryBackend) {
  for (const std::string_view name : builtBackends()) {
    const auto w = makeWorld(name);
    const MeshHandle big = w->addMesh("big", boxMesh(Vec3(-4, -4, -4), Vec3(4, 4, 4), "big"));
    const MeshHandle quad = w->addMesh("quad", quadMesh());
    Transform t;
    t.translation = Vec3(10, 0, 0);
    const ModelHandle m = w->addModel("m", big, t);
    const ModelHandle q = w->addModel("q", quad);
    const Sphere inside{Vec3(11, 1, -1), 1}, outside{Vec3(1, 1, -1), 1};
    EXPECT_FALSE(w->overlaps(m, inside)) << name << ": the surface test misses a sphere inside";
    if (!w->supports(WorldOp::ModelSphereVolume)) {
      try {
        w->overlapsVolume(m, inside);
        ADD_FAILURE() << name << ": answered model_sphere volume";
      } catch (const Unsupported& e) {
        EXPECT_EQ(std::string(e.what()), "unsupported: model_sphere volume on " + std::string(name));
      }
      continue;
    }
    EXPECT_TRUE(w->overlapsVolume(m, inside)) << name;
    EXPECT_FALSE(w->overlapsVolume(m, outside)) << name;
    EXPECT_TRUE(w->overlapsVolume(m, Aabb{Vec3(9, 0, 0), Vec3(10, 1, 1)})) << name;
    EXPECT_TRUE(w->overlapsVolume(m, axisBox(Vec3(10, 0, 0), Vec3(1, 1, 1)))) << name;
    EXPECT_TRUE(w->overlapsVolume(m, Triangle{Vec3(9, 0, 0), Vec3(10, 0, 0), Vec3(9, 1, 0)})) << name;
    try {
      w->overlapsVolume(q, inside);
      ADD_FAILURE() << name << ": an open model answered volume mode";
    } catch (const InvalidInput& e) {
      EXPECT_EQ(std::string(e.what()),
                "model: model \"q\": mesh \"quad\" is not closed: edge (0,1) is used by 1 triangle (4 boundary, 0 "
                "non-manifold, 0 inconsistently oriented edges)")
          << name;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Conventions of the native world.

TEST(CollisionWorldNarrowPhase, SwappingOperandsSwapsPointsAndFlipsNormals) {
  const auto w = makeNativeWorld();
  const MeshHandle cube = w->addMesh("cube", boxMesh(Vec3(0, 0, 0), Vec3(1, 1, 1), "cube"));
  const WorldOperand box{axisBox(Vec3(0.5f, 0.5f, 1.375f), Vec3(0.25f, 0.25f, 0.5f)), Transform{}};
  const WorldOperand mesh{cube, Transform{}};
  const std::vector<WorldContact> ab = w->contacts(mesh, box), ba = w->contacts(box, mesh);
  ASSERT_EQ(ab.size(), 4u);  // the box's bottom face on the cube's top face
  ASSERT_EQ(ab.size(), ba.size());
  for (std::size_t i = 0; i < ab.size(); ++i) {
    EXPECT_EQ(ab[i].pointA, ba[i].pointB);
    EXPECT_EQ(ab[i].pointB, ba[i].pointA);
    EXPECT_EQ(ab[i].normal, -ba[i].normal);
    EXPECT_EQ(ab[i].depth, ba[i].depth);
    EXPECT_EQ(ab[i].featureA, ba[i].featureB);
    EXPECT_NEAR(ab[i].depth, 0.125, 1e-6);
    // B (the box) above A (the cube): the normal from B to A points down.
    EXPECT_NEAR(ab[i].normal.z(), -1, 1e-6);
    EXPECT_NEAR((ab[i].pointA - ab[i].pointB).dot(ab[i].normal), -ab[i].depth, 1e-6);
    ASSERT_TRUE(ab[i].featureA.has_value());
    EXPECT_TRUE(*ab[i].featureA == 2 || *ab[i].featureA == 3) << *ab[i].featureA;  // top face triangles
  }
  const WorldDistance d = w->distance(mesh, box), e = w->distance(box, mesh);
  EXPECT_NEAR(d.distance, -0.125, 1e-6);
  EXPECT_EQ(d.distance, e.distance);
  EXPECT_EQ(d.normal, -e.normal);
  EXPECT_EQ(d.triangleA, e.triangleB);
  EXPECT_FALSE(d.triangleB.has_value());
  // Margin: a box 0.1 above the cube has no contact at margin 0 and four speculative ones
  // (depth -0.1) at margin 0.2.
  const WorldOperand above{axisBox(Vec3(0.5f, 0.5f, 1.625f), Vec3(0.25f, 0.25f, 0.5f)), Transform{}};
  EXPECT_TRUE(w->contacts(mesh, above, 0).empty());
  const std::vector<WorldContact> speculative = w->contacts(mesh, above, 0.25);
  ASSERT_EQ(speculative.size(), 4u);
  for (const WorldContact& c : speculative) EXPECT_NEAR(c.depth, -0.125, 1e-6);
}

TEST(CollisionWorldNarrowPhase, ConvexPairsAndPosesAgreeWithTheGeometryLayer) {
  const auto w = makeNativeWorld();
  std::mt19937_64 rng(11);
  const auto u = [&](double lo, double hi) { return Real(std::uniform_real_distribution<double>(lo, hi)(rng)); };
  for (int i = 0; i < 200; ++i) {
    Transform ta, tb;
    ta.translation = Vec3(u(-2, 2), u(-2, 2), u(-2, 2));
    tb.translation = Vec3(u(-2, 2), u(-2, 2), u(-2, 2));
    ta.rotation = Quat(u(-1, 1), u(-1, 1), u(-1, 1), u(-1, 1)).normalized();
    tb.rotation = Quat(u(-1, 1), u(-1, 1), u(-1, 1), u(-1, 1)).normalized();
    const Capsule cap{Vec3(u(-1, 0), 0, 0), Vec3(u(0, 1), 0, 0), u(0.1, 0.5)};
    const Obb box = axisBox(Vec3(0, 0, 0), Vec3(u(0.2, 1), u(0.2, 1), u(0.2, 1)));
    const WorldDistance d = w->distance({cap, ta}, {box, tb});
    const DistanceResult g = crux::distance(cap, ta, box, tb);
    EXPECT_EQ(d.distance, double(g.distance)) << i;
    EXPECT_EQ(d.pointA, g.pointA.cast<double>()) << i;
    ContactManifold m;
    crux::contacts(cap, ta, box, tb, 0, m);
    EXPECT_EQ(int(w->contacts({cap, ta}, {box, tb}).size()), m.count) << i;
  }
}

// ---------------------------------------------------------------------------------------------
// Distances: native vs FCL (fcl::distance, enable_nearest_points, GJK tolerance 1e-12) on
// separated pairs. Stated tolerance: 4 × (native + fcl declared error) at the operands'
// magnitude, plus 32 ulps of Real × magnitude for the float rounding of crux's inputs/outputs.

double distanceTolerance(const CollisionWorld& a, const CollisionWorld& b, double magnitude) {
  return 4 * (a.tolerance().at(magnitude) + b.tolerance().at(magnitude)) +
         32 * std::numeric_limits<Real>::epsilon() * magnitude;
}

TEST(CollisionWorldDistance, NativeMatchesFclOnSeparatedConvexPairs) {
  if (!built("fcl")) GTEST_SKIP() << "fcl backend not built";
  const auto native = makeNativeWorld();
  const auto fcl = makeWorld("fcl");
  std::mt19937_64 rng(7);
  const auto u = [&](double lo, double hi) { return Real(std::uniform_real_distribution<double>(lo, hi)(rng)); };
  const auto shape = [&](int kind) -> OperandShape {
    switch (kind) {
      case 0: return Sphere{Vec3(u(-0.2, 0.2), u(-0.2, 0.2), u(-0.2, 0.2)), u(0.2, 1)};
      case 1: {
        Obb b = axisBox(Vec3(u(-0.2, 0.2), 0, 0), Vec3(u(0.2, 1), u(0.2, 1), u(0.2, 1)));
        b.axes = Quat(u(-1, 1), u(-1, 1), u(-1, 1), u(-1, 1)).normalized().toRotationMatrix();
        return b;
      }
      case 2: return Capsule{Vec3(u(-1, 0), u(-0.2, 0.2), 0), Vec3(u(0, 1), u(-0.2, 0.2), 0), u(0.1, 0.6)};
      default: {
        std::vector<Vec3> p;
        for (int k = 0; k < 12; ++k) p.emplace_back(u(-1, 1), u(-1, 1), u(-1, 1));
        return ConvexHull::build(p);
      }
    }
  };
  int compared = 0;
  double worst = 0;
  for (int i = 0; i < 400; ++i) {
    WorldOperand a{shape(i % 4), Transform{}}, b{shape((i / 4) % 4), Transform{}};
    a.pose.rotation = Quat(u(-1, 1), u(-1, 1), u(-1, 1), u(-1, 1)).normalized();
    b.pose.rotation = Quat(u(-1, 1), u(-1, 1), u(-1, 1), u(-1, 1)).normalized();
    a.pose.translation = Vec3(u(-1, 1), u(-1, 1), u(-1, 1));
    b.pose.translation = a.pose.translation + Vec3(u(2.5, 5), u(-1, 1), u(-1, 1));
    const WorldDistance n = native->distance(a, b);
    if (n.distance < 0.05) continue;  // separated pairs only (penetration: see docs/batch.md)
    const WorldDistance f = fcl->distance(a, b);
    const double tol = distanceTolerance(*native, *fcl, 8);
    worst = std::max(worst, std::abs(n.distance - f.distance));
    EXPECT_NEAR(n.distance, f.distance, tol) << "pair " << i << " kinds " << i % 4 << ", " << (i / 4) % 4
                                             << " native " << str(n.distance) << " fcl " << str(f.distance);
    ++compared;
  }
  std::printf("convex pairs: %d compared, worst |native - fcl| = %.3g\n", compared, worst);
  EXPECT_GT(compared, 300);
}

TEST(CollisionWorldDistance, NativeMatchesFclOnSeparatedShapeMeshAndMeshMeshPairs) {
  if (!built("fcl")) GTEST_SKIP() << "fcl backend not built";
  const auto native = makeNativeWorld();
  const auto fcl = makeWorld("fcl");
  const auto anchor = std::make_shared<const Mesh>(loadMesh(std::string(CRUX_SOURCE_DIR) + "/data/meshes/anchor.off"));
  const auto cross = crossMesh();
  const MeshHandle an = native->addMesh("anchor", anchor), af = fcl->addMesh("anchor", anchor);
  const MeshHandle cn = native->addMesh("cross", cross), cf = fcl->addMesh("cross", cross);
  const Aabb box = anchor->bounds();
  const double size = double((box.max - box.min).norm());
  std::mt19937_64 rng(8);
  const auto u = [&](double lo, double hi) { return Real(std::uniform_real_distribution<double>(lo, hi)(rng)); };
  const auto turn = [&] { return Quat(u(-1, 1), u(-1, 1), u(-1, 1), u(-1, 1)).normalized(); };
  int compared = 0;
  double worst = 0;
  for (int i = 0; i < 60; ++i) {
    // A capsule or box (B) beside the anchor (A), a few sizes away.
    Transform tm;
    tm.rotation = turn();
    const Vec3 centre = box.center();
    Transform ts;
    ts.rotation = turn();
    ts.translation = tm.apply(centre) + Vec3(u(0.7, 1.2), u(-0.3, 0.3), u(-0.3, 0.3)) * Real(size);
    const OperandShape s = (i % 2) ? OperandShape(Capsule{Vec3(Real(-0.1 * size), 0, 0), Vec3(Real(0.1 * size), 0, 0),
                                                          Real(0.05 * size)})
                                   : OperandShape(axisBox(Vec3(0, 0, 0), Vec3(1, 1, 1) * Real(0.1 * size)));
    const WorldDistance n = native->distance({an, tm}, {s, ts});
    const WorldDistance f = fcl->distance({af, tm}, {s, ts});
    if (n.distance < 0.01 * size) continue;
    const double tol = distanceTolerance(*native, *fcl, 2 * size + double(ts.translation.cwiseAbs().maxCoeff()));
    worst = std::max(worst, std::abs(n.distance - f.distance) / size);
    EXPECT_NEAR(n.distance, f.distance, tol) << "shape " << i << " native " << str(n.distance) << " fcl "
                                             << str(f.distance);
    ++compared;
    // The mesh point lies on the triangle both name (closest points on a mesh need not be unique,
    // so the triangles may differ; the distance may not).
    ASSERT_TRUE(n.triangleA.has_value());
    // Mesh–mesh: the cross beside itself, turned.
    Transform tb;
    tb.rotation = turn();
    tb.translation = Vec3(u(3.5, 6), u(-2, 2), u(-2, 2));
    const std::optional<WorldDistance> mn = native->meshDistance(cn, tm, cn, tb);
    const std::optional<WorldDistance> mf = fcl->meshDistance(cf, tm, cf, tb);
    ASSERT_TRUE(mn && mf);
    EXPECT_NEAR(mn->distance, mf->distance, distanceTolerance(*native, *fcl, 8))
        << "mesh pair " << i << " native " << str(mn->distance) << " fcl " << str(mf->distance);
    worst = std::max(worst, std::abs(mn->distance - mf->distance) / 8);
    // The bound: nothing within half the distance. (Touching placements, distance 0, occur too:
    // the draws depend on the compiler's argument evaluation order. Then the pair is found
    // within a bound of 0.)
    if (mn->distance > 0) {
      EXPECT_FALSE(native->meshDistance(cn, tm, cn, tb, mn->distance / 2)) << i;
      EXPECT_FALSE(fcl->meshDistance(cf, tm, cf, tb, mn->distance / 2)) << i;
    } else {
      EXPECT_TRUE(native->meshDistance(cn, tm, cn, tb, 0)) << i;
    }
  }
  std::printf("shape-mesh and mesh-mesh pairs: %d compared, worst |native - fcl| / size = %.3g\n", compared, worst);
  EXPECT_GT(compared, 40);
}

// ---------------------------------------------------------------------------------------------
// Contacts: native vs Bullet (btCollisionWorld::contactPairTest, margins 0) on clear cases — a
// sphere, capsule or box sunk 0.05-0.15 into the interior of one triangle of a face of the cube
// [0,4]^3, at least 0.2 away from the triangle's edges (the face diagonal included), so only that
// triangle is touched (each shape is more than twice as thick as it is sunk: a triangle is
// two-sided, so a thinner one would be pushed through). Both must report contacts whose deepest point has the designed depth and
// the normal −(face normal) (from the shape, B, into the mesh, A). Bullet does not reduce
// manifolds (a point per triangle), so point counts are compared for spheres only (one each).

TEST(CollisionWorldContacts, NativeMatchesBulletOnClearCases) {
  if (!built("bullet")) GTEST_SKIP() << "bullet backend not built";
  const auto native = makeNativeWorld();
  const auto bullet = makeWorld("bullet");
  const auto cube = boxMesh(Vec3(0, 0, 0), Vec3(4, 4, 4), "cube4");
  const MeshHandle mn = native->addMesh("cube4", cube), mb = bullet->addMesh("cube4", cube);
  std::mt19937_64 rng(12);
  const auto u = [&](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); };
  const double tol = 4 * (native->tolerance().at(5) + bullet->tolerance().at(5));
  int compared = 0;
  for (int i = 0; i < 120; ++i) {
    // A point inside the triangle (0,0)-(4,0)-(4,4) of the top face's parametrisation (x > y),
    // its inscribed margin >= 0.2 + the shape's reach; mirrored to the other triangle half the time.
    const int kind = i % 3;
    const double reach = kind == 0 ? 0.3 : 0.25;  // sphere radius / capsule half length + radius / box half
    double x, y;
    do {
      x = u(0.2, 3.8);
      y = u(0.2, 3.8);
    } while (!(x - y > (reach + 0.2) * std::sqrt(2.0) && y > reach + 0.2 && x < 4 - reach - 0.2));
    if (i % 2) std::swap(x, y);
    const double depth = u(0.05, 0.15);
    OperandShape shape;
    if (kind == 0) {
      shape = Sphere{Vec3(Real(x), Real(y), Real(4 + 0.3 - depth)), Real(0.3)};
    } else if (kind == 1) {
      shape = Capsule{Vec3(Real(x - 0.05), Real(y), Real(4 + 0.2 - depth)), Vec3(Real(x + 0.05), Real(y), Real(4 + 0.2 - depth)),
                      Real(0.2)};
    } else {
      // Taller than twice the depth: pushing it through the (two-sided) triangle would be longer.
      shape = axisBox(Vec3(Real(x), Real(y), Real(4 + 0.25 - depth)), Vec3(0.1f, 0.1f, 0.25f));
    }
    const WorldOperand a{mn, Transform{}}, ab{mb, Transform{}}, b{shape, Transform{}};
    const std::vector<WorldContact> n = native->contacts(a, b), bt = bullet->contacts(ab, b);
    const std::string where = "case " + std::to_string(i) + " kind " + std::to_string(kind) + " at (" + str(x) +
                              ", " + str(y) + ") depth " + str(depth);
    ASSERT_FALSE(n.empty()) << where;
    ASSERT_FALSE(bt.empty()) << where;
    const auto deepest = [](const std::vector<WorldContact>& c) {
      return *std::max_element(c.begin(), c.end(),
                               [](const WorldContact& p, const WorldContact& q) { return p.depth < q.depth; });
    };
    const WorldContact dn = deepest(n), db = deepest(bt);
    EXPECT_NEAR(dn.depth, depth, tol) << where;
    EXPECT_NEAR(db.depth, depth, tol) << where;
    EXPECT_NEAR(dn.normal.z(), -1, 1e-6) << where;
    EXPECT_NEAR(db.normal.z(), -1, 1e-3) << where;
    ASSERT_TRUE(dn.featureA && db.featureA) << where;
    EXPECT_EQ(*dn.featureA, *db.featureA) << where;  // the same top-face triangle
    if (kind == 0) {
      EXPECT_EQ(n.size(), 1u) << where;
      EXPECT_EQ(bt.size(), 1u) << where;
    }
    // Lifted 0.5 clear of the face: no contact on either at margin 0, and with margin 1 the
    // speculative contact at separation 0.5 - depth on both.
    const WorldOperand lifted{a.shape, [] {
                                Transform t;
                                t.translation = Vec3(0, 0, -0.5f);
                                return t;
                              }()};
    const WorldOperand liftedB{ab.shape, lifted.pose};
    EXPECT_TRUE(native->contacts(lifted, b).empty()) << where;
    EXPECT_TRUE(bullet->contacts(liftedB, b).empty()) << where;
    const std::vector<WorldContact> sn = native->contacts(lifted, b, 1), sb = bullet->contacts(liftedB, b, 1);
    ASSERT_FALSE(sn.empty() || sb.empty()) << where;
    EXPECT_NEAR(deepest(sn).depth, depth - 0.5, tol) << where;
    EXPECT_NEAR(deepest(sb).depth, depth - 0.5, tol) << where;
    ++compared;
  }
  std::printf("contacts: %d clear cases compared with bullet\n", compared);
}

}  // namespace
}  // namespace crux
