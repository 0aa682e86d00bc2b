// Tests of src/scene/scene.cpp: the scene with each broad phase against its own brute-force
// path (every model tested, bounds recomputed from scratch) under long seeded random sequences
// of add/remove/move/reparent, compared after every step (rays, sphere/AABB/OBB region queries
// exact and bounds-only, model pairs exact and bounds-only, broad phase in sync); families near
// the origin and at 1e6; models teleported far outside any initial bounds; zero-size meshes
// (a single degenerate triangle); deep hierarchies (depth 50). Then exactness on the integer
// grid (axis-aligned rotations, integer translations and shapes) against the CGAL oracle
// applied to every world-space triangle.

#include <crux/scene/scene.hpp>
#include <crux/precondition.hpp>

#include <crux/geometry/overlap.hpp>
#include <crux/mesh/mesh.hpp>
#include <exact/exact.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <optional>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "support/test_scale.hpp"  // CRUX_TEST_SCALE: fewer rounds in the sanitizer stage

namespace crux {
namespace {

std::string str(const Vec3& v) {
  std::ostringstream s;
  s << std::setprecision(17) << "[" << v.x() << ", " << v.y() << ", " << v.z() << "]";
  return s.str();
}
std::string str(const Quat& q) {
  std::ostringstream s;
  s << std::setprecision(17) << "[" << q.w() << ", " << q.x() << ", " << q.y() << ", " << q.z() << "]";
  return s.str();
}
std::string str(const Transform& t) { return "{t " + str(t.translation) + ", q " + str(t.rotation) + "}"; }
std::string str(const std::vector<ModelId>& v) {
  std::ostringstream s;
  s << "[";
  for (const auto x : v) s << " " << x;
  return s.str() + " ]";
}
std::string str(const std::vector<std::pair<ModelId, ModelId>>& v) {
  std::ostringstream s;
  s << "[";
  for (const auto& [a, b] : v) s << " (" << a << "," << b << ")";
  return s.str() + " ]";
}
std::string str(const std::optional<SceneRayHit>& h) {
  if (!h) return "miss";
  std::ostringstream s;
  s << std::setprecision(17) << "model " << h->model << " t " << h->hit.t << " triangle " << h->hit.triangle
    << " point " << str(h->hit.point);
  return s.str();
}

std::string str(const std::optional<MeshRayHit>& h) {
  if (!h) return "miss";
  std::ostringstream s;
  s << std::setprecision(17) << "t " << h->t << " triangle " << h->triangle << " point " << str(h->point);
  return s.str();
}

std::shared_ptr<const Mesh> makeMesh(std::vector<Vec3> v, std::vector<TriangleIndices> t, const char* name) {
  return std::make_shared<const Mesh>(std::move(v), std::move(t), name);
}
/// The cube [0, s]^3 as 12 triangles.
std::shared_ptr<const Mesh> cube(Real s) {
  return makeMesh({{0, 0, 0}, {s, 0, 0}, {s, s, 0}, {0, s, 0}, {0, 0, s}, {s, 0, s}, {s, s, s}, {0, s, s}},
                  {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                   {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}},
                  "cube");
}
std::shared_ptr<const Mesh> tetra(Real s) {
  return makeMesh({{0, 0, 0}, {s, 0, 0}, {0, s, 0}, {0, 0, s}}, {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}, "tetra");
}
/// Zero-size mesh: one triangle whose corners coincide (the point p).
std::shared_ptr<const Mesh> pointMesh(const Vec3& p) { return makeMesh({p, p, p}, {{0, 1, 2}}, "point"); }
/// One degenerate (collinear) triangle: the segment from a to b.
std::shared_ptr<const Mesh> segmentMesh(const Vec3& a, const Vec3& b) {
  return makeMesh({a, b, (a + b) / 2}, {{0, 1, 2}}, "segment");
}
/// A flat square [0, s]^2 in z = 0.
std::shared_ptr<const Mesh> square(Real s) {
  return makeMesh({{0, 0, 0}, {s, 0, 0}, {s, s, 0}, {0, s, 0}}, {{0, 1, 2}, {0, 2, 3}}, "square");
}

struct HitRate {
  std::size_t n = 0, hits = 0;
  void count(bool hit) {
    ++n;
    hits += hit;
  }
  double rate() const { return n ? double(hits) / double(n) : 0; }
};

// ---------------------------------------------------------------------------------------------
// Random edit sequences: broad-phase path == brute-force path after every step.

class Editor {
 public:
  Editor(std::uint64_t seed, Vec3 center, Real spread) : rng_(seed), center_(center), spread_(spread) {
    meshes_ = {cube(2), tetra(2), pointMesh(Vec3(0.5f, 0.5f, 0.5f)), segmentMesh(Vec3(0, 0, 0), Vec3(2, 1, 0)),
               square(2), std::make_shared<const Mesh>(loadMesh(CRUX_SOURCE_DIR "/data/meshes/icosahedron.off"))};
  }

  Real uniform(Real lo, Real hi) { return std::uniform_real_distribution<Real>(lo, hi)(rng_); }
  int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }
  bool chance(double p) { return std::bernoulli_distribution(p)(rng_); }
  Vec3 offset(Real r) { return Vec3(uniform(-r, r), uniform(-r, r), uniform(-r, r)); }
  Vec3 point(Real r) { return center_ + offset(r); }
  Quat rotation() { return Quat(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1), uniform(-1, 1)).normalized(); }
  const std::shared_ptr<const Mesh>& mesh() { return meshes_[std::size_t(integer(0, int(meshes_.size()) - 1))]; }

  /// A world-space placement near the centre (converted to local by the caller's parent).
  Transform placement() { return {rotation(), point(spread_)}; }
  Transform farPlacement() {
    const Vec3 dir = offset(1).normalized();
    return {rotation(), center_ + dir * spread_ * std::pow(Real(10), uniform(1, 3))};
  }

  Sphere sphere() { return {point(spread_), uniform(0, spread_ / 3)}; }
  Aabb box() {
    const Vec3 c = point(spread_);
    const Vec3 h(uniform(0, spread_ / 4), uniform(0, spread_ / 4), uniform(0, spread_ / 4));
    return {c - h, c + h};
  }
  Obb obb() {
    Obb o;
    o.center = point(spread_);
    o.half = Vec3(uniform(0, spread_ / 4), uniform(0, spread_ / 4), uniform(0, spread_ / 4));
    o.axes = rotation().toRotationMatrix();
    return o;
  }
  Ray ray(const Vec3* target) {
    Ray r;
    r.origin = point(spread_ * 2);
    r.dir = (target ? *target : point(spread_)) - r.origin;
    if (r.dir.isZero()) r.dir = Vec3::UnitZ();
    return r;
  }
  Real spread() const { return spread_; }

 private:
  std::mt19937_64 rng_;
  Vec3 center_;
  Real spread_;
  std::vector<std::shared_ptr<const Mesh>> meshes_;
};

/// Local transform that places a model at `world` under `parent` (or the world).
Transform localFor(const Scene& scene, ModelId parent, const Transform& world) {
  return parent == kNoModel ? world : scene.models().world(parent).inverse() * world;
}

struct Rates {
  HitRate region, bounds, rays, pairs;
};

/// Compares every query through the broad phase with the brute-force path; "" when all agree.
std::string compareScene(Scene& scene, Editor& ed, Rates& rates) {
  const std::vector<ModelId> ids = scene.models().ids();
  if (scene.broadPhase().size() != ids.size()) return "broad phase holds " + std::to_string(scene.broadPhase().size()) +
                                                       " boxes for " + std::to_string(ids.size()) + " models";
  for (const ModelId id : ids) {
    const Aabb fresh = sceneBounds(scene.placed(id));
    if (!scene.broadPhase().contains(id) || scene.bounds(id).min != fresh.min || scene.bounds(id).max != fresh.max)
      return "broad phase out of sync for model " + std::to_string(id);
  }
  for (int k = 0; k < 2; ++k) {
    Vec3 target;
    const bool aim = k == 0 && !ids.empty();
    if (aim) target = scene.bounds(ids[std::size_t(ed.integer(0, int(ids.size()) - 1))]).center();
    const Ray ray = ed.ray(aim ? &target : nullptr);
    RayQueryOptions options;
    if (ed.chance(0.3)) options.maxDistance = ed.uniform(0, 2) * ray.dir.norm();
    const auto got = scene.raycast(ray, options);
    const auto want = scene.raycast(ray, options, ScenePath::BruteForce);
    rates.rays.count(want.has_value());
    const bool same = got.has_value() == want.has_value() &&
                      (!got || (got->model == want->model && got->hit.t == want->hit.t &&
                                got->hit.triangle == want->hit.triangle && got->hit.point == want->hit.point &&
                                got->hit.normal == want->hit.normal));
    if (!same)
      return "ray " + str(ray.origin) + " dir " + str(ray.dir) + ": got " + str(got) + ", want " + str(want);
  }
  const auto region = [&](const auto& shape, const std::string& what) -> std::string {
    for (const RegionTest test : {RegionTest::Triangles, RegionTest::Bounds}) {
      const auto got = scene.query(shape, test);
      const auto want = scene.query(shape, test, ScenePath::BruteForce);
      (test == RegionTest::Triangles ? rates.region : rates.bounds).count(!want.empty());
      if (got != want)
        return what + (test == RegionTest::Bounds ? " (bounds)" : "") + ": got " + str(got) + ", want " + str(want);
    }
    return "";
  };
  const Sphere s = ed.sphere();
  if (auto e = region(s, "sphere " + str(s.center) + " r " + std::to_string(s.radius)); !e.empty()) return e;
  const Aabb b = ed.box();
  if (auto e = region(b, "aabb " + str(b.min) + " " + str(b.max)); !e.empty()) return e;
  const Obb o = ed.obb();
  if (auto e = region(o, "obb at " + str(o.center)); !e.empty()) return e;
  const auto pg = scene.overlappingPairs();
  const auto pw = scene.overlappingPairs(ScenePath::BruteForce);
  rates.pairs.count(!pw.empty());
  if (pg != pw) return "pairs: got " + str(pg) + ", want " + str(pw);
  const auto bg = scene.boundsPairs();
  const auto bw = scene.boundsPairs(ScenePath::BruteForce);
  if (bg != bw) return "bounds pairs: got " + str(bg) + ", want " + str(bw);
  return "";
}

/// `boundsRateBounded`: whether the bounds-only hit rate must stay below 80% (see the 1e6 test).
void randomEdits(BroadPhaseKind kind, std::uint64_t seed, Vec3 center, Real spread, int steps,
                 bool boundsRateBounded = true) {
  Editor ed(seed, center, spread);
  Scene scene(kind);
  Rates rates;
  std::vector<std::string> log;
  std::size_t cycles = 0, far = 0, maxDepth = 0;
  for (int step = 0; step < steps; ++step) {
    const std::vector<ModelId> ids = scene.models().ids();
    const auto pick = [&]() { return ids[std::size_t(ed.integer(0, int(ids.size()) - 1))]; };
    const int op = ed.integer(0, 99);
    std::string line;
    if ((op < 25 || ids.size() < 8) && ids.size() < 30) {
      const ModelId parent = (!ids.empty() && ed.chance(0.4)) ? pick() : kNoModel;
      const Transform local = localFor(scene, parent, ed.placement());
      const ModelId id = scene.add(ed.mesh(), local, parent);
      line = "add " + std::to_string(id) + " parent " + std::to_string(parent) + " local " + str(local);
    } else if (op < 35) {
      const ModelId id = pick();
      scene.remove(id);
      line = "remove " + std::to_string(id);
    } else if (op < 75) {
      const ModelId id = pick();
      Transform local = scene.models().local(id);
      const int how = ed.integer(0, 99);
      if (how < 60) {
        local.translation += ed.offset(ed.spread() / 20);
      } else if (how < 95) {
        local = localFor(scene, scene.models().parent(id), ed.placement());
      } else {
        local = localFor(scene, scene.models().parent(id), ed.farPlacement());
        ++far;
      }
      scene.setTransform(id, local);
      line = "set_transform " + std::to_string(id) + " " + str(local);
    } else {
      const ModelId id = pick();
      const ModelId parent = ed.chance(0.25) ? kNoModel : pick();
      const auto desc = scene.models().descendants(id);
      const bool cycle = parent == id || std::find(desc.begin(), desc.end(), parent) != desc.end();
      if (cycle) {
        const Transform before = scene.models().world(id);
        EXPECT_THROW(scene.setParent(id, parent), InvalidInput);
        EXPECT_EQ(scene.models().world(id).translation, before.translation);
        ++cycles;
        line = "set_parent " + std::to_string(id) + " " + std::to_string(parent) + " (cycle, rejected)";
      } else {
        scene.setParent(id, parent);
        line = "set_parent " + std::to_string(id) + " " + std::to_string(parent);
      }
    }
    log.push_back(line);
    if (log.size() > 10) log.erase(log.begin());
    for (const ModelId id : scene.models().ids()) {
      std::size_t depth = 0;
      for (ModelId p = scene.models().parent(id); p != kNoModel; p = scene.models().parent(p)) ++depth;
      maxDepth = std::max(maxDepth, depth);
    }
    const std::string problem = compareScene(scene, ed, rates);
    if (!problem.empty()) {
      std::string history;
      for (const auto& l : log) history += "  " + l + "\n";
      FAIL() << broadPhaseName(kind) << ", seed " << seed << ", step " << step << ": " << problem
             << "\nlast edits:\n"
             << history;
    }
  }
  EXPECT_GT(cycles, 0u);
  EXPECT_GT(far, 0u);
  EXPECT_GE(maxDepth, 3u);
  for (const auto* r : {&rates.region, &rates.bounds, &rates.rays}) {
    EXPECT_GE(r->rate(), 0.2);
    if (r != &rates.bounds || boundsRateBounded) EXPECT_LE(r->rate(), 0.8);
  }
  std::printf("%s at %s: %d steps; non-empty: region %.0f%% of %zu, bounds %.0f%%, rays %.0f%% of %zu, pairs %.0f%%;"
              " %zu cycles rejected, %zu far moves, depth up to %zu\n",
              std::string(broadPhaseName(kind)).c_str(), str(center).c_str(), steps, 100 * rates.region.rate(),
              rates.region.n, 100 * rates.bounds.rate(), 100 * rates.rays.rate(), rates.rays.n,
              100 * rates.pairs.rate(), cycles, far, maxDepth);
}

class EveryBroadPhase : public ::testing::TestWithParam<BroadPhaseKind> {};

TEST_P(EveryBroadPhase, MatchesBruteForceUnderRandomEdits) {
  randomEdits(GetParam(), 0x5ce0001, Vec3::Zero(), 6, 3000);
}

TEST_P(EveryBroadPhase, MatchesBruteForceAtMillionCoordinates) {
  // In float builds worldBounds pads rotated models by 64 ulps of their translation (~7.6 at
  // 1e6), so nearly every bounds-only query near the models touches some box: only its lower
  // hit rate is checked there.
  randomEdits(GetParam(), 0x5ce0002, Vec3(1e6f, -1e6f, 1e6f), 6, 1500, sizeof(Real) == sizeof(double));
}

TEST_P(EveryBroadPhase, DeepHierarchyOfFiftyStaysInSync) {
  Scene scene(GetParam());
  const auto mesh = cube(1);
  std::vector<ModelId> chain;
  const Transform step{Quat(Eigen::AngleAxis<Real>(Real(0.05), Vec3::UnitZ())), Vec3(1.5f, 0, 0)};
  for (int i = 0; i < 50; ++i) chain.push_back(scene.add(mesh, step, chain.empty() ? kNoModel : chain.back()));
  EXPECT_EQ(scene.models().descendants(chain[0]).size(), 49u);
  Editor ed(0x5ce0003, Vec3(20, 20, 0), 25);
  Rates rates;
  const auto check = [&](const char* when) {
    for (int k = 0; k < 20; ++k) {
      const std::string problem = compareScene(scene, ed, rates);
      ASSERT_TRUE(problem.empty()) << when << ": " << problem;
    }
  };
  check("built");
  // Moving the root moves all 50 boxes.
  scene.setTransform(chain[0], {Quat(Eigen::AngleAxis<Real>(Real(0.7), Vec3::UnitY())), Vec3(3, -2, 5)});
  check("root moved");
  const Vec3 tipBefore = scene.models().world(chain[49]).translation;
  scene.setParent(chain[25], kNoModel);  // detach the lower half, keeping its pose
  EXPECT_LT((scene.models().world(chain[49]).translation - tipBefore).norm(), 1e-3f * (1 + tipBefore.norm()));
  scene.setTransform(chain[0], Transform{});
  check("upper half moved alone");
  scene.remove(chain[30]);  // its child 31 moves up to 29, keeping its pose
  EXPECT_EQ(scene.models().parent(chain[31]), chain[29]);
  check("middle removed");
  EXPECT_THROW(scene.setParent(chain[25], chain[40]), InvalidInput);  // 40 descends from 25
  check("cycle rejected");
}

TEST_P(EveryBroadPhase, ZeroSizeMeshesAreHitTouchedAndPaired) {
  Scene scene(GetParam());
  const auto point = pointMesh(Vec3(0, 0, 0));
  const ModelId a = scene.add(point, {Quat::Identity(), Vec3(1, 2, 3)});
  const ModelId b = scene.add(point, {Quat::Identity(), Vec3(1, 2, 3)});   // coincident point
  const ModelId c = scene.add(cube(1), {Quat::Identity(), Vec3(1, 2, 3)});  // a corner at the point
  const ModelId d = scene.add(point, {Quat::Identity(), Vec3(1, 2, 5)});
  const auto hit = scene.raycast({Vec3(1, 2, 10), Vec3(0, 0, -2)});
  ASSERT_TRUE(hit.has_value());
  EXPECT_EQ(hit->model, d);
  EXPECT_EQ(hit->hit.t, 5);
  EXPECT_EQ(scene.query(Sphere{Vec3(1, 2, 4), 1}), (std::vector<ModelId>{a, b, c, d}));
  EXPECT_EQ(scene.query(Sphere{Vec3(1, 2, 2), 1}), (std::vector<ModelId>{a, b, c}));
  EXPECT_EQ(scene.query(Aabb{Vec3(0, 0, 0), Vec3(1, 2, 3)}), (std::vector<ModelId>{a, b, c}));
  EXPECT_EQ(scene.overlappingPairs(), (std::vector<std::pair<ModelId, ModelId>>{{a, b}, {a, c}, {b, c}}));
  EXPECT_EQ(scene.overlappingPairs(), scene.overlappingPairs(ScenePath::BruteForce));
  scene.setTransform(d, {Quat::Identity(), Vec3(1, 2, 4)});  // now on the cube's top face
  EXPECT_EQ(scene.overlappingPairs(),
            (std::vector<std::pair<ModelId, ModelId>>{{a, b}, {a, c}, {b, c}, {c, d}}));
}

TEST_P(EveryBroadPhase, ParentAndChildPairsAreIncluded) {
  Scene scene(GetParam());
  const ModelId parent = scene.add(cube(2));
  const ModelId child = scene.add(cube(2), {Quat::Identity(), Vec3(1, 1, 1)}, parent);
  const ModelId grandchild = scene.add(cube(2), {Quat::Identity(), Vec3(2, 0, 0)}, child);
  EXPECT_EQ(scene.overlappingPairs(), (std::vector<std::pair<ModelId, ModelId>>{{parent, child}, {child, grandchild}}));
  scene.setTransform(parent, {Quat::Identity(), Vec3(100, 0, 0)});  // all move together
  EXPECT_EQ(scene.overlappingPairs(), (std::vector<std::pair<ModelId, ModelId>>{{parent, child}, {child, grandchild}}));
  EXPECT_EQ(scene.query(Sphere{Vec3(104.5f, 1, 1), 0.5f}), (std::vector<ModelId>{grandchild}));
  EXPECT_TRUE(scene.query(Sphere{Vec3(4.5f, 1, 1), 0.5f}).empty());
}

TEST_P(EveryBroadPhase, ClosestRayHitNotFirstFound) {
  Scene scene(GetParam());
  // Three stacked slabs along +z; the ray from above must report the top one whatever order the
  // broad phase visits them in (the book's scene returned t = -1 or the first model found).
  const auto sq = square(4);
  const ModelId low = scene.add(sq, {Quat::Identity(), Vec3(0, 0, 0)});
  const ModelId high = scene.add(sq, {Quat::Identity(), Vec3(0, 0, 10)});
  const ModelId mid = scene.add(sq, {Quat::Identity(), Vec3(0, 0, 5)});
  const auto hit = scene.raycast({Vec3(1, 1, 20), Vec3(0, 0, -1)});
  ASSERT_TRUE(hit.has_value());
  EXPECT_EQ(hit->model, high);
  EXPECT_EQ(hit->hit.t, 10);
  RayQueryOptions limited;
  limited.maxDistance = 9.5f;
  EXPECT_FALSE(scene.raycast({Vec3(1, 1, 20), Vec3(0, 0, -1)}, limited).has_value());
  const auto up = scene.raycast({Vec3(1, 1, -1), Vec3(0, 0, 1)});
  ASSERT_TRUE(up.has_value());
  EXPECT_EQ(up->model, low);
  scene.remove(low);
  EXPECT_EQ(scene.raycast({Vec3(1, 1, -1), Vec3(0, 0, 1)})->model, mid);
  EXPECT_FALSE(scene.raycast({Vec3(1, 1, -1), Vec3(0, 0, -1)}).has_value());  // pointing away
}

INSTANTIATE_TEST_SUITE_P(Scene, EveryBroadPhase,
                         ::testing::Values(BroadPhaseKind::BruteForce, BroadPhaseKind::Octree,
                                           BroadPhaseKind::DynamicAabbTree),
                         [](const auto& info) { return std::string(broadPhaseName(info.param)); });

TEST(Scene, RejectsABadBroadPhaseAndUnknownModels) {
  EXPECT_THROW(Scene(std::unique_ptr<BroadPhase>()), InvalidInput);
  auto used = makeBroadPhase(BroadPhaseKind::Octree);
  used->insert(0, Aabb{Vec3::Zero(), Vec3::Zero()});
  EXPECT_THROW(Scene(std::move(used)), InvalidInput);
  Scene scene;
  const ModelId a = scene.add(cube(1));
  EXPECT_THROW(scene.setTransforms({{a, Transform{}}, {a + 7, Transform{}}}), InvalidInput);
  EXPECT_THROW(scene.add(nullptr), InvalidInput);
  EXPECT_EQ(scene.size(), 1u);
  EXPECT_EQ(scene.broadPhase().size(), 1u);
}

TEST(Scene, SetTransformsMovesManyThenSyncsOnce) {
  Scene scene;
  std::vector<ModelId> ids;
  for (int i = 0; i < 20; ++i) ids.push_back(scene.add(cube(1), {Quat::Identity(), Vec3(Real(3 * i), 0, 0)}));
  std::vector<std::pair<ModelId, Transform>> moves;
  for (int i = 0; i < 20; i += 2) moves.emplace_back(ids[std::size_t(i)], Transform{Quat::Identity(), Vec3(Real(3 * i) + 1, 0, 0)});
  scene.setTransforms(moves);
  for (const ModelId id : ids) {
    const Aabb fresh = sceneBounds(scene.placed(id));
    EXPECT_EQ(scene.bounds(id).min, fresh.min);
  }
  // Model i (even) now spans x in [3i+1, 3i+2]: apart from models i-1 ([3i-3, 3i-2]) and i+1
  // ([3i+3, 3i+4]). Shifted by 2 instead, it touches model i+1 at x = 3i+3.
  EXPECT_TRUE(scene.overlappingPairs().empty());
  moves.clear();
  for (int i = 0; i < 20; i += 2) moves.emplace_back(ids[std::size_t(i)], Transform{Quat::Identity(), Vec3(Real(3 * i) + 2, 0, 0)});
  scene.setTransforms(moves);
  EXPECT_EQ(scene.overlappingPairs().size(), 10u);
}

// ---------------------------------------------------------------------------------------------
// Exactness on the integer grid, against CGAL on every world-space triangle.

/// The 24 rotations mapping axes to signed axes, as quaternions (rounded; the model layer
/// snaps them to exact signed permutations).
std::vector<Quat> axisRotations() {
  std::vector<Quat> out;
  const double h = std::acos(0.0);  // 90°
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b)
      for (int c = 0; c < 4; ++c) {
        const Eigen::Quaterniond q = Eigen::AngleAxisd(a * h, Eigen::Vector3d::UnitX()) *
                                     Eigen::AngleAxisd(b * h, Eigen::Vector3d::UnitY()) *
                                     Eigen::AngleAxisd(c * h, Eigen::Vector3d::UnitZ());
        const Eigen::Matrix3d m = q.toRotationMatrix().array().round().matrix();
        bool seen = false;
        for (const Quat& o : out) seen = seen || (o.cast<double>().toRotationMatrix().array().round().matrix() == m);
        if (!seen) out.push_back(q.cast<Real>());
      }
  return out;
}

/// World triangles of a model placed by an axis-aligned rotation and an integer translation,
/// computed exactly (the rotation rounded to its signed permutation).
std::vector<Triangle> worldTriangles(const Mesh& mesh, const Transform& t) {
  const Eigen::Matrix3d r = t.rotation.cast<double>().toRotationMatrix().array().round().matrix();
  const auto map = [&](const Vec3& p) { return Vec3((r * p.cast<double>() + t.translation.cast<double>()).cast<Real>()); };
  std::vector<Triangle> out;
  for (std::uint32_t i = 0; i < mesh.triangleCount(); ++i) {
    const Triangle tri = mesh.triangle(i);
    out.push_back({map(tri.a), map(tri.b), map(tri.c)});
  }
  return out;
}

TEST(Scene, IntegerGridQueriesAndPairsAreExact) {
  std::mt19937_64 rng(0x5ce0004);
  const auto integer = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
  const auto ivec = [&](int lo, int hi) { return Vec3(Real(integer(lo, hi)), Real(integer(lo, hi)), Real(integer(lo, hi))); };
  const std::vector<Quat> rotations = axisRotations();
  ASSERT_EQ(rotations.size(), 24u);
  // The identity and the half turns about the axes: quaternions with exact components. Mesh–mesh
  // (the mesh layer's overlaps(Mesh, Transform, Mesh, Transform)) is exact only when the
  // relative rotation is exactly representable, so pairs are checked on rounds using these.
  const std::vector<Quat> exactRotations = {Quat(1, 0, 0, 0), Quat(0, 1, 0, 0), Quat(0, 0, 1, 0), Quat(0, 0, 0, 1)};
  const std::vector<std::shared_ptr<const Mesh>> meshes = {
      cube(2), tetra(3), pointMesh(Vec3(1, 1, 1)), segmentMesh(Vec3(0, 0, 0), Vec3(2, 2, 0)), square(2)};
  HitRate sphereRate, boxRate, obbRate, pairRate, rayRate;
  std::size_t queries = 0, pairChecks = 0;
  const int rounds = test::scaledCases(100, 30);  // every broad phase with and without pairs 5 times
  for (int round = 0; round < rounds; ++round) {
    Scene scene(static_cast<BroadPhaseKind>(round % 3));
    std::vector<ModelId> ids;
    std::vector<std::vector<Triangle>> world;
    std::string layout;
    const bool checkPairs = round % 2 == 0;
    for (int m = 0; m < 10; ++m) {
      const auto& mesh = meshes[std::size_t(integer(0, int(meshes.size()) - 1))];
      const Quat q = checkPairs ? exactRotations[std::size_t(integer(0, 3))] : rotations[std::size_t(integer(0, 23))];
      const Transform t{q, ivec(-1, 2)};
      ids.push_back(scene.add(mesh, t));
      world.push_back(worldTriangles(*mesh, t));
      layout += "  model " + std::to_string(ids.back()) + ": " + mesh->name() + " " + str(t) + "\n";
    }
    const auto exactModels = [&](const auto& shape) {
      std::vector<ModelId> out;
      for (std::size_t i = 0; i < ids.size(); ++i)
        for (const Triangle& tri : world[i])
          if (exact::overlaps(tri, shape)) {
            out.push_back(ids[i]);
            break;
          }
      std::sort(out.begin(), out.end());
      return out;
    };
    for (int q = 0; q < 40; ++q, queries += 3) {
      const Sphere s{ivec(-3, 5), Real(integer(0, 3))};
      const auto ws = exactModels(s);
      sphereRate.count(!ws.empty());
      ASSERT_EQ(scene.query(s), ws) << "sphere " << str(s.center) << " r " << s.radius << "\n" << layout;
      const Vec3 lo = ivec(-5, 5);
      const Aabb b{lo, lo + ivec(0, 4)};
      const auto wb = exactModels(b);
      boxRate.count(!wb.empty());
      ASSERT_EQ(scene.query(b), wb) << "aabb " << str(b.min) << " " << str(b.max) << "\n" << layout;
      Obb o;
      o.center = ivec(-3, 5);
      o.half = ivec(0, 2);
      o.axes = rotations[std::size_t(integer(0, 23))].toRotationMatrix().array().round().matrix();
      const auto wo = exactModels(o);
      obbRate.count(!wo.empty());
      ASSERT_EQ(scene.query(o), wo) << "obb " << str(o.center) << " half " << str(o.half) << "\n" << layout;
      // Rays from integer origins towards integer points near the models: hit/miss exact,
      // nearest model exact, t within rounding.
      Ray ray{ivec(-8, 8), Vec3::Zero()};
      ray.dir = ivec(-1, 3) - ray.origin;
      if (ray.dir.isZero()) ray.dir = Vec3::UnitX();
      std::optional<double> best;
      std::vector<ModelId> nearest;
      std::vector<std::pair<ModelId, double>> modelTs;
      for (std::size_t i = 0; i < ids.size(); ++i) {
        std::optional<double> tm;
        for (const Triangle& tri : world[i])
          if (const auto t = exact::raycast(ray, tri); t && (!tm || *t < *tm)) tm = t;
        if (tm) modelTs.emplace_back(ids[i], *tm);
        if (tm && (!best || *tm < *best)) best = tm;
      }
      // Models hit at the nearest distance (the oracle rounds each exact distance to double on
      // its own, so equal distances may differ in the last bit): any of them may be reported.
      for (const auto& [id, t] : modelTs)
        if (t <= *best * (1 + 1e-12)) nearest.push_back(id);
      const auto got = scene.raycast(ray);
      rayRate.count(best.has_value());
      // Every model's exact and crux distance, for the failure message only (built on failure).
      const auto exactTs = [&] {
        std::ostringstream lines;
        lines << std::setprecision(17);
        for (const auto& [id, t] : modelTs)
          lines << "  exact t of model " << id << ": " << t << ", crux " << str(raycastClosest(scene.placed(id), ray))
                << "\n";
        return lines.str();
      };
      ASSERT_EQ(got.has_value(), best.has_value()) << "ray " << str(ray.origin) << " dir " << str(ray.dir) << "\n"
                                                   << layout;
      if (got) {
        EXPECT_NEAR(double(got->hit.t), *best, 1e-5 * (1 + *best)) << "ray " << str(ray.origin) << " " << str(ray.dir);
        EXPECT_NE(std::find(nearest.begin(), nearest.end(), got->model), nearest.end()) << "ray " << str(ray.origin) << " " << str(ray.dir) << "\n"
                                               << exactTs() << layout;
      }
    }
    if (!checkPairs) continue;
    std::vector<std::pair<ModelId, ModelId>> want;
    for (std::size_t i = 0; i < ids.size(); ++i)
      for (std::size_t j = i + 1; j < ids.size(); ++j, ++pairChecks) {
        bool touch = false;
        for (const Triangle& ta : world[i]) {
          for (const Triangle& tb : world[j])
            if ((touch = exact::overlaps(ta, tb))) break;
          if (touch) break;
        }
        pairRate.count(touch);
        if (touch) want.emplace_back(ids[i], ids[j]);
      }
    ASSERT_EQ(scene.overlappingPairs(), want) << layout;
  }
  for (const auto* r : {&sphereRate, &boxRate, &obbRate, &pairRate, &rayRate}) {
    EXPECT_GE(r->rate(), 0.2);
    EXPECT_LE(r->rate(), 0.8);
  }
  std::printf("integer grid: %zu region queries (non-empty: sphere %.0f%%, aabb %.0f%%, obb %.0f%%), %zu rays (%.0f%% hit),"
              " %zu model pairs (%.0f%% touching)\n",
              queries, 100 * sphereRate.rate(), 100 * boxRate.rate(), 100 * obbRate.rate(), rayRate.n,
              100 * rayRate.rate(), pairChecks, 100 * pairRate.rate());
}

// ---- preconditions ------------------------------------------------------------------------------

/// Scene rays and region queries with non-finite inputs, a zero direction or a negative radius get
/// no answer on every broad phase and on the brute-force path (an infinite ray origin crashed every
/// one of them before the entry check).
TEST(ScenePreconditions, InputsThatAreNotQueryableGetNoAnswer) {
  if (CRUX_CHECK_PRECONDITIONS) GTEST_SKIP() << "this build aborts instead";
  const Real nan = std::numeric_limits<Real>::quiet_NaN(), inf = std::numeric_limits<Real>::infinity();
  const auto mesh = std::make_shared<const Mesh>(
      std::vector<Vec3>{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)},
      std::vector<TriangleIndices>{{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
  for (const BroadPhaseKind kind : {BroadPhaseKind::DynamicAabbTree, BroadPhaseKind::Octree, BroadPhaseKind::BruteForce}) {
    Scene scene(kind);
    scene.add(mesh);
    scene.add(mesh, Transform{Quat::Identity(), Vec3(3, 0, 0)});
    for (const ScenePath path : {ScenePath::BroadPhase, ScenePath::BruteForce}) {
      for (const Real bad : {nan, inf, -inf}) {
        for (int i = 0; i < 3; ++i) {
          Vec3 v(Real(0.2), Real(0.2), -1);
          v[i] = bad;
          EXPECT_FALSE(scene.raycast(Ray{v, Vec3(0, 0, 1)}, {}, path).has_value());
          Vec3 d(0, 0, 1);
          d[i] = bad;
          EXPECT_FALSE(scene.raycast(Ray{Vec3(Real(0.2), Real(0.2), -1), d}, {}, path).has_value());
          Vec3 c = Vec3::Constant(Real(0.2));
          c[i] = bad;
          for (const RegionTest test : {RegionTest::Triangles, RegionTest::Bounds}) {
            EXPECT_TRUE(scene.query(Sphere{c, 1}, test, path).empty());
            EXPECT_TRUE(scene.query(Aabb{c, Vec3::Constant(4)}, test, path).empty());
            EXPECT_TRUE(scene.query(Obb{c, Vec3::Ones(), Mat3::Identity()}, test, path).empty());
          }
        }
        EXPECT_TRUE(scene.query(Sphere{Vec3::Constant(Real(0.2)), bad}, RegionTest::Triangles, path).empty());
      }
      EXPECT_FALSE(scene.raycast(Ray{Vec3(Real(0.2), Real(0.2), -1), Vec3::Zero()}, {}, path).has_value());
      EXPECT_TRUE(scene.query(Sphere{Vec3::Constant(Real(0.2)), -1}, RegionTest::Triangles, path).empty());
      EXPECT_TRUE(scene.raycast(Ray{Vec3(Real(0.2), Real(0.2), -1), Vec3(0, 0, 1)}, {}, path).has_value());
    }
  }
}

}  // namespace
}  // namespace crux
