/// @file bench_scene.cpp  The crux scene against Bullet and FCL, in one process, on the same scenes.
///
/// Scenes of N models (default 1k, 10k, 100k): instances of four real meshes (data/meshes:
/// bunny00, cow, knot1, rotor, each centred and scaled to radius 1) placed uniformly with random
/// rotations in a cube whose volume grows with N (constant density). 10% of the models move
/// every frame (a fixed set of movers with constant linear and angular velocities, bouncing off
/// the cube's walls). Every frame's moves and the models' world boxes (crux::sceneBounds) are
/// computed once and handed to every engine, so every engine answers exactly the same question.
///
/// Workloads, each timed as the median of --runs runs after a validation pass that checks the
/// answers agree:
///  1. update + pairs, per frame: apply the movers' new boxes, then count every pair of models
///     whose boxes overlap. crux: the three broad phases (BroadPhase::update + pairs) and the
///     whole Scene (setTransforms, which recomputes the bounds, + boundsPairs); Bullet:
///     btCollisionWorld on btDbvtBroadphase (setWorldTransform + broadphase setAabb, then
///     computeOverlappingPairs and a pass over the pair cache keeping the pairs whose exact
///     proxy boxes overlap, since Bullet's cache holds pairs of fattened boxes); FCL:
///     DynamicAABBTreeCollisionManager (setTransform + the box, update(movers), collide with a
///     callback keeping pairs whose boxes overlap).
///  2. scene rays: closest triangle hit over all models. crux: Scene::raycast per broad phase;
///     Bullet: btCollisionWorld::rayTest with ClosestRayResultCallback on btBvhTriangleMeshShape.
///     FCL 0.7's managers have no ray query.
///  3. region queries: (a) AABB, bounds only (broad phase): crux BroadPhase::query, Bullet
///     btDbvtBroadphase::aabbTest, FCL collide(query object); (b) sphere, exact (triangles):
///     crux Scene::query, FCL collide(sphere object) + fcl::collide narrow phase.
/// Boxes given to Bullet/FCL are the crux boxes, so they skip computing bounds; the crux Scene
/// row includes that work (model hierarchy + worldBounds) and the broad-phase rows do not.

#include "bench_output.hpp"
#include "peers/bench_types.hpp"
#include <crux/mesh/mesh.hpp>
#include <crux/model/model_query.hpp>
#include <crux/scene/dynamic_aabb_tree.hpp>
#include <crux/scene/scene.hpp>
#include <crux/scene/scene_batch.hpp>

#if CRUX_BENCH_HAVE_BULLET
#include <btBulletCollisionCommon.h>
#endif
#if CRUX_BENCH_HAVE_FCL
#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/config.h>
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/math/bv/OBBRSS.h>
#include <fcl/narrowphase/collision.h>
#endif

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#ifndef CRUX_BENCH_BUILD_TYPE
#define CRUX_BENCH_BUILD_TYPE "unknown"
#endif
#ifndef CRUX_BENCH_MESH_DIR
#define CRUX_BENCH_MESH_DIR "data/meshes"
#endif

namespace {

using namespace crux;

// ---- options and timing ------------------------------------------------------------------------

struct Options {
  std::vector<std::size_t> sizes = {1000, 10000, 100000};
  int runs = 3;
  bool quick = false;
  bool cpuClock = false;
  std::uint64_t seed = 20240601;
  std::string only;  // run only engines whose name contains this (profiling)
  std::string workloads = "pairs,rays,boxes,spheres";
  std::string json;  // --json FILE: every row (crux report reads it)
  bool has(const char* w) const { return workloads.find(w) != std::string::npos; }
};

/// Wall and process CPU time (bench/peers/bench_types.hpp, shared with the other benches).
using crux::bench::Seconds;
using crux::bench::Stopwatch;

/// Median run (by the reported clock) of a set of runs.
struct Timing {
  std::vector<Seconds> runs;
  Seconds median(bool cpu) const {
    std::vector<Seconds> s = runs;
    std::sort(s.begin(), s.end(), [cpu](const Seconds& a, const Seconds& b) { return cpu ? a.cpu < b.cpu : a.wall < b.wall; });
    return s.empty() ? Seconds{} : s[s.size() / 2];
  }
};

std::string loadAverage() {
  std::ifstream f("/proc/loadavg");
  std::string a, b, c;
  f >> a >> b >> c;
  return a + " " + b + " " + c;
}

// ---- meshes and scenes ------------------------------------------------------------------------

/// A mesh centred and scaled to radius 1 (half its bounding-box diagonal), as float arrays
/// shared by every engine and as the crux Mesh built from exactly those floats.
struct BenchMesh {
  std::string name;
  std::vector<float> positions;          // xyz per vertex
  std::vector<std::uint32_t> indices;    // 3 per triangle
  std::shared_ptr<const Mesh> mesh;
};

BenchMesh loadBenchMesh(const std::string& name) {
  const Mesh loaded = loadMesh(std::string(CRUX_BENCH_MESH_DIR) + "/" + name + ".off");
  const Aabb b = loaded.bounds();
  const Vec3 c = b.center();
  const Real s = Real(1) / (b.half().norm());
  BenchMesh m;
  m.name = name;
  std::vector<Vec3> vertices;
  for (const Vec3& v : loaded.vertices()) {
    const Vec3 p = (v - c) * s;
    for (int i = 0; i < 3; ++i) m.positions.push_back(float(p[i]));
    vertices.emplace_back(Real(float(p.x())), Real(float(p.y())), Real(float(p.z())));
  }
  std::vector<TriangleIndices> triangles = loaded.triangles();
  for (const auto& t : triangles) m.indices.insert(m.indices.end(), t.begin(), t.end());
  m.mesh = std::make_shared<const Mesh>(std::move(vertices), std::move(triangles), name);
  return m;
}

struct Placement {
  std::uint32_t mesh = 0;
  Transform world;
  Aabb box;
};
struct Move {
  ProxyId id = 0;
  Transform world;
  Aabb box;
};
struct Frame {
  std::vector<Move> moves;
  std::vector<std::pair<ModelId, Transform>> sceneMoves;  // the same moves, for Scene::setTransforms
};
struct RayCase {
  Ray ray;     // unit direction
  Real length;  // reaches beyond the scene
};

/// Everything generated for one scene size.
struct Workload {
  std::size_t models = 0;
  Real side = 0;
  std::vector<Placement> initial, final;
  std::vector<Frame> frames;
  std::vector<RayCase> rays;
  std::vector<Aabb> boxes;
  std::vector<Sphere> spheres;
};

/// Volume of scene per model (radius-1 models): about two box neighbours per model.
constexpr Real kVolumePerModel = 60;

Quat randomRotation(std::mt19937_64& rng) {
  std::normal_distribution<Real> n(0, 1);
  return Quat(n(rng), n(rng), n(rng), n(rng)).normalized();
}

Workload makeWorkload(const std::vector<BenchMesh>& meshes, std::size_t n, int frameCount, std::size_t rayCount,
                      std::size_t boxCount, std::size_t sphereCount, std::uint64_t seed) {
  std::mt19937_64 rng(seed ^ (n * 0x9e3779b97f4a7c15ull));
  std::uniform_real_distribution<Real> unit(0, 1);
  Workload w;
  w.models = n;
  w.side = std::cbrt(Real(n) * kVolumePerModel);
  const Real side = w.side;
  auto placed = [&](std::uint32_t mesh, const Transform& t) {
    return Placement{mesh, t, sceneBounds(PlacedMesh{meshes[mesh].mesh.get(), t})};
  };
  for (std::size_t i = 0; i < n; ++i) {
    const Transform t{randomRotation(rng), Vec3(unit(rng), unit(rng), unit(rng)) * side};
    w.initial.push_back(placed(std::uint32_t(rng() % meshes.size()), t));
  }
  // Movers: the first 10% (positions are random, so this is a random subset in space).
  const std::size_t movers = n / 10;
  std::vector<Vec3> velocity(movers);
  std::vector<Quat> spin(movers);
  for (std::size_t i = 0; i < movers; ++i) {
    const Vec3 dir = Vec3(unit(rng) - Real(0.5), unit(rng) - Real(0.5), unit(rng) - Real(0.5)).normalized();
    velocity[i] = dir * (Real(0.02) + Real(0.06) * unit(rng));  // 2-8% of the radius per frame
    spin[i] = Quat(Eigen::AngleAxis<Real>(Real(0.02), randomRotation(rng) * Vec3::UnitX()));
  }
  std::vector<Transform> current(n);
  for (std::size_t i = 0; i < n; ++i) current[i] = w.initial[i].world;
  for (int f = 0; f < frameCount; ++f) {
    Frame frame;
    for (std::size_t i = 0; i < movers; ++i) {
      Transform& t = current[i];
      for (int k = 0; k < 3; ++k) {
        const Real next = t.translation[k] + velocity[i][k];
        if (next < 0 || next > side) velocity[i][k] = -velocity[i][k];
      }
      t.translation += velocity[i];
      t.rotation = (spin[i] * t.rotation).normalized();
      const Placement p = placed(w.initial[i].mesh, t);
      frame.moves.push_back({ProxyId(i), t, p.box});
      frame.sceneMoves.emplace_back(ModelId(i), t);
    }
    w.frames.push_back(std::move(frame));
  }
  for (std::size_t i = 0; i < n; ++i) w.final.push_back(placed(w.initial[i].mesh, current[i]));

  // Rays from the faces of a cube 10% larger than the scene towards points inside it.
  for (std::size_t i = 0; i < rayCount; ++i) {
    Vec3 o(unit(rng), unit(rng), unit(rng));
    const int axis = int(rng() % 3);
    o[axis] = (rng() % 2) ? Real(1.1) : Real(-0.1);
    o = o * side;
    const Vec3 target = Vec3(unit(rng), unit(rng), unit(rng)) * side;
    w.rays.push_back({Ray{o, (target - o).normalized()}, Real(2) * side * std::sqrt(Real(3))});
  }
  for (std::size_t i = 0; i < boxCount; ++i) {
    const Vec3 c = Vec3(unit(rng), unit(rng), unit(rng)) * side;
    const Vec3 h = Vec3(unit(rng), unit(rng), unit(rng)) * Real(3) + Vec3::Ones();
    w.boxes.push_back({c - h, c + h});
  }
  for (std::size_t i = 0; i < sphereCount; ++i)
    w.spheres.push_back({Vec3(unit(rng), unit(rng), unit(rng)) * side, Real(0.5) + Real(2.5) * unit(rng)});
  return w;
}

// ---- engines: update + pairs --------------------------------------------------------------------

/// An engine of the update+pairs workload.
class PairEngine {
 public:
  virtual ~PairEngine() = default;
  virtual std::string name() const = 0;
  /// Builds the engine's structure for the initial placement (not timed).
  virtual void build(const std::vector<Placement>& initial) = 0;
  /// Applies one frame's moves, then counts the overlapping box pairs.
  virtual std::size_t frame(const Frame& f) = 0;
};

class CountPairs final : public PairCollector {
 public:
  void add(ProxyId, ProxyId) override { ++count; }
  std::size_t count = 0;
};

class CruxBroadPhaseEngine final : public PairEngine {
 public:
  explicit CruxBroadPhaseEngine(BroadPhaseKind kind) : kind_(kind) {}
  std::string name() const override { return "crux " + std::string(broadPhaseName(kind_)); }
  void build(const std::vector<Placement>& initial) override {
    bp_ = makeBroadPhase(kind_);
    for (std::size_t i = 0; i < initial.size(); ++i) bp_->insert(ProxyId(i), initial[i].box);
    CountPairs c;
    bp_->pairs(c);  // a frame 0, as the peers' build also finds the initial pairs
  }
  std::size_t frame(const Frame& f) override {
    for (const Move& m : f.moves) bp_->update(m.id, m.box);
    CountPairs c;
    bp_->pairs(c);
    return c.count;
  }

 private:
  BroadPhaseKind kind_;
  std::unique_ptr<BroadPhase> bp_;
};

class CruxSceneEngine final : public PairEngine {
 public:
  explicit CruxSceneEngine(const std::vector<BenchMesh>& meshes) : meshes_(meshes) {}
  std::string name() const override { return "crux Scene (tree, +bounds)"; }
  void build(const std::vector<Placement>& initial) override {
    scene_ = std::make_unique<Scene>(BroadPhaseKind::DynamicAabbTree);
    for (std::size_t i = 0; i < initial.size(); ++i) {
      const ModelId id = scene_->add(meshes_[initial[i].mesh].mesh, initial[i].world);
      if (id != i) std::abort();  // a fresh scene numbers models in insertion order
    }
    CountPairs c;
    scene_->boundsPairs(c);
  }
  std::size_t frame(const Frame& f) override {
    scene_->setTransforms(f.sceneMoves);
    CountPairs c;
    scene_->boundsPairs(c);
    return c.count;
  }

 private:
  const std::vector<BenchMesh>& meshes_;
  std::unique_ptr<Scene> scene_;
};

#if CRUX_BENCH_HAVE_BULLET
static_assert(sizeof(btScalar) == sizeof(float), "Debian's Bullet is the float build");

btVector3 bt(const Vec3& v) { return btVector3(btScalar(v.x()), btScalar(v.y()), btScalar(v.z())); }
btTransform bt(const Transform& t) {
  return btTransform(btQuaternion(btScalar(t.rotation.x()), btScalar(t.rotation.y()), btScalar(t.rotation.z()),
                                  btScalar(t.rotation.w())),
                     bt(t.translation));
}

/// One btBvhTriangleMeshShape per mesh over the shared float arrays (margin 0).
struct BulletShapes {
  explicit BulletShapes(const std::vector<BenchMesh>& meshes) {
    for (const BenchMesh& m : meshes) {
      arrays.push_back(std::make_unique<btTriangleIndexVertexArray>(
          int(m.indices.size() / 3), reinterpret_cast<int*>(const_cast<std::uint32_t*>(m.indices.data())),
          int(3 * sizeof(std::uint32_t)), int(m.positions.size() / 3), const_cast<float*>(m.positions.data()),
          int(3 * sizeof(float))));
      shapes.push_back(std::make_unique<btBvhTriangleMeshShape>(arrays.back().get(), true, true));
      shapes.back()->setMargin(0);
    }
  }
  std::vector<std::unique_ptr<btTriangleIndexVertexArray>> arrays;
  std::vector<std::unique_ptr<btBvhTriangleMeshShape>> shapes;
};

/// A btCollisionWorld on btDbvtBroadphase holding every model, with the crux boxes.
struct BulletWorld {
  BulletWorld(BulletShapes& shapes, const std::vector<Placement>& placements) {
    objects.reserve(placements.size());
    for (std::size_t i = 0; i < placements.size(); ++i) {
      objects.push_back(std::make_unique<btCollisionObject>());
      btCollisionObject& o = *objects.back();
      o.setCollisionShape(shapes.shapes[placements[i].mesh].get());
      o.setWorldTransform(bt(placements[i].world));
      o.setUserIndex(int(i));
      world.addCollisionObject(&o);
      setBox(o, placements[i].box);
    }
  }
  void setBox(btCollisionObject& o, const Aabb& box) {
    broadphase.setAabb(o.getBroadphaseHandle(), bt(box.min), bt(box.max), &dispatcher);
  }
  // Objects outlive the world (its destructor reads them).
  std::vector<std::unique_ptr<btCollisionObject>> objects;
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher{&configuration};
  btDbvtBroadphase broadphase;
  btCollisionWorld world{&dispatcher, &broadphase, &configuration};
};

class BulletPairEngine final : public PairEngine {
 public:
  explicit BulletPairEngine(BulletShapes& shapes) : shapes_(shapes) {}
  std::string name() const override { return "Bullet btDbvtBroadphase"; }
  void build(const std::vector<Placement>& initial) override {
    w_.reset();
    w_ = std::make_unique<BulletWorld>(shapes_, initial);
    w_->world.computeOverlappingPairs();
  }
  std::size_t frame(const Frame& f) override {
    for (const Move& m : f.moves) {
      btCollisionObject& o = *w_->objects[m.id];
      o.setWorldTransform(bt(m.world));
      w_->setBox(o, m.box);
    }
    w_->world.computeOverlappingPairs();
    // The cache holds pairs of fattened boxes (and stale ones until its incremental cleanup):
    // keep the pairs whose exact proxy boxes overlap.
    const btBroadphasePairArray& pairs = w_->world.getPairCache()->getOverlappingPairArray();
    std::size_t count = 0;
    for (int i = 0; i < pairs.size(); ++i) {
      const btBroadphaseProxy* a = pairs[i].m_pProxy0;
      const btBroadphaseProxy* b = pairs[i].m_pProxy1;
      count += TestAabbAgainstAabb2(a->m_aabbMin, a->m_aabbMax, b->m_aabbMin, b->m_aabbMax) ? 1 : 0;
    }
    return count;
  }

 private:
  BulletShapes& shapes_;
  std::unique_ptr<BulletWorld> w_;
};
#endif

#if CRUX_BENCH_HAVE_FCL
using FclModel = fcl::BVHModel<fcl::OBBRSSd>;

/// A collision object whose world box is set from outside (the crux box), so FCL uses exactly
/// the boxes every other engine uses (FCL's own computeAABB bounds a rotated mesh by its
/// bounding sphere). Constructed over a small placeholder geometry and then given the mesh, so
/// that FCL does not recompute the mesh's local AABB (a pass over all vertices) per instance.
class FclObject : public fcl::CollisionObjectd {
 public:
  FclObject(const std::shared_ptr<fcl::CollisionGeometryd>& placeholder, const std::shared_ptr<fcl::CollisionGeometryd>& geometry)
      : fcl::CollisionObjectd(placeholder) {
    cgeom = geometry;
    cgeom_const = geometry;
  }
  void setBox(const Aabb& b) {
    aabb.min_ = fcl::Vector3d(double(b.min.x()), double(b.min.y()), double(b.min.z()));
    aabb.max_ = fcl::Vector3d(double(b.max.x()), double(b.max.y()), double(b.max.z()));
  }
  void place(const Transform& t, const Aabb& b) {
    setTransform(fcl::Quaterniond(double(t.rotation.w()), double(t.rotation.x()), double(t.rotation.y()),
                                  double(t.rotation.z())),
                 fcl::Vector3d(double(t.translation.x()), double(t.translation.y()), double(t.translation.z())));
    setBox(b);
  }
};

struct FclShapes {
  explicit FclShapes(const std::vector<BenchMesh>& meshes) {
    for (const BenchMesh& m : meshes) {
      std::vector<fcl::Vector3d> points;
      for (std::size_t i = 0; i < m.positions.size(); i += 3)
        points.emplace_back(m.positions[i], m.positions[i + 1], m.positions[i + 2]);
      std::vector<fcl::Triangle> tris;
      for (std::size_t i = 0; i < m.indices.size(); i += 3) tris.emplace_back(m.indices[i], m.indices[i + 1], m.indices[i + 2]);
      auto model = std::make_shared<FclModel>();
      model->beginModel(int(tris.size()), int(points.size()));
      model->addSubModel(points, tris);
      model->endModel();
      model->computeLocalAABB();
      models.push_back(model);
    }
    placeholder = std::make_shared<fcl::Boxd>(1, 1, 1);
  }
  std::vector<std::shared_ptr<fcl::CollisionGeometryd>> models;
  std::shared_ptr<fcl::CollisionGeometryd> placeholder;
};

struct FclWorld {
  FclWorld(FclShapes& shapes, const std::vector<Placement>& placements) {
    objects.reserve(placements.size());
    std::vector<fcl::CollisionObjectd*> all;
    for (std::size_t i = 0; i < placements.size(); ++i) {
      objects.push_back(std::make_unique<FclObject>(shapes.placeholder, shapes.models[placements[i].mesh]));
      objects.back()->place(placements[i].world, placements[i].box);
      objects.back()->setUserData(reinterpret_cast<void*>(std::uintptr_t(i)));
      all.push_back(objects.back().get());
    }
    manager.registerObjects(all);
    manager.setup();
  }
  std::vector<std::unique_ptr<FclObject>> objects;
  fcl::DynamicAABBTreeCollisionManagerd manager;
};

bool countOverlappingBoxes(fcl::CollisionObjectd* a, fcl::CollisionObjectd* b, void* data) {
  if (a->getAABB().overlap(b->getAABB())) ++*static_cast<std::size_t*>(data);
  return false;  // go on
}

class FclPairEngine final : public PairEngine {
 public:
  explicit FclPairEngine(FclShapes& shapes) : shapes_(shapes) {}
  std::string name() const override { return "FCL DynamicAABBTree"; }
  void build(const std::vector<Placement>& initial) override {
    w_.reset();
    w_ = std::make_unique<FclWorld>(shapes_, initial);
  }
  std::size_t frame(const Frame& f) override {
    updated_.clear();
    for (const Move& m : f.moves) {
      FclObject& o = *w_->objects[m.id];
      o.place(m.world, m.box);
      updated_.push_back(&o);
    }
    w_->manager.update(updated_);
    std::size_t count = 0;
    w_->manager.collide(&count, countOverlappingBoxes);
    return count;
  }

 private:
  FclShapes& shapes_;
  std::unique_ptr<FclWorld> w_;
  std::vector<fcl::CollisionObjectd*> updated_;
};
#endif

// ---- engines: static queries ------------------------------------------------------------------

struct RayAnswer {
  bool hit = false;
  std::uint32_t model = 0;
  double t = 0;
};

/// An engine of the static-query workloads (built once at the final placement).
class QueryEngine {
 public:
  virtual ~QueryEngine() = default;
  virtual std::string name() const = 0;
  virtual bool hasRays() const { return true; }
  /// Called once before the ray rows (a static scene's preparation; untimed there).
  virtual void prepareRays() {}
  virtual bool hasSpheres() const { return true; }
  virtual RayAnswer ray(const RayCase& r) = 0;
  virtual std::size_t boxCount(const Aabb& box) = 0;
  virtual std::vector<std::uint32_t> sphereModels(const Sphere& s) = 0;
};

class CountIds final : public ProxyCollector {
 public:
  bool add(ProxyId) override {
    ++count;
    return true;
  }
  std::size_t count = 0;
};

class CruxQueryEngine final : public QueryEngine {
 public:
  CruxQueryEngine(BroadPhaseKind kind, const std::vector<BenchMesh>& meshes, const std::vector<Placement>& placements)
      : kind_(kind), scene_(kind) {
    for (const Placement& p : placements) scene_.add(meshes[p.mesh].mesh, p.world);
  }
  std::string name() const override { return "crux " + std::string(broadPhaseName(kind_)); }
  RayAnswer ray(const RayCase& r) override {
    RayQueryOptions o;
    o.maxDistance = r.length;
    const auto h = scene_.raycast(r.ray, o);
    return h ? RayAnswer{true, h->model, double(h->hit.t)} : RayAnswer{};
  }
  std::size_t boxCount(const Aabb& box) override {
    CountIds c;
    scene_.broadPhase().query(box, c);
    return c.count;
  }
  std::vector<std::uint32_t> sphereModels(const Sphere& s) override { return scene_.query(s); }
  const Scene& scene() const { return scene_; }
  /// The dynamic tree's wide ray tree is built here, as a static scene would (prepareRays),
  /// not after its threshold of rays; the build time is printed beside the rows.
  void prepareRays() override {
    const auto* tree = dynamic_cast<const DynamicAabbTree*>(&scene_.broadPhase());
    if (!tree || tree->hasRayTree()) return;
    const Stopwatch sw;
    tree->prepareRays();
    const double seconds = sw.elapsed().wall;
    std::printf("  %s: wide ray tree built in %.3f ms (%.0f ns per model); the ray rows walk it\n", name().c_str(),
                seconds * 1e3, seconds * 1e9 / double(std::max<std::size_t>(1, scene_.size())));
  }

 private:
  BroadPhaseKind kind_;
  Scene scene_;
};

#if CRUX_BENCH_HAVE_BULLET
class BulletQueryEngine final : public QueryEngine {
 public:
  BulletQueryEngine(BulletShapes& shapes, const std::vector<Placement>& placements) : w_(shapes, placements) {
    w_.world.computeOverlappingPairs();
  }
  std::string name() const override { return "Bullet btCollisionWorld"; }
  bool hasSpheres() const override { return false; }
  RayAnswer ray(const RayCase& r) override {
    const btVector3 from = bt(r.ray.origin), to = bt(r.ray.origin + r.ray.dir * r.length);
    btCollisionWorld::ClosestRayResultCallback cb(from, to);
    w_.world.rayTest(from, to, cb);
    if (!cb.hasHit()) return {};
    return {true, std::uint32_t(cb.m_collisionObject->getUserIndex()), double(cb.m_closestHitFraction) * double(r.length)};
  }
  std::size_t boxCount(const Aabb& box) override {
    struct Count : btBroadphaseAabbCallback {
      btVector3 min, max;
      std::size_t count = 0;
      bool process(const btBroadphaseProxy* p) override {
        count += TestAabbAgainstAabb2(p->m_aabbMin, p->m_aabbMax, min, max) ? 1 : 0;
        return true;
      }
    } cb;
    cb.min = bt(box.min);
    cb.max = bt(box.max);
    w_.broadphase.aabbTest(cb.min, cb.max, cb);
    return cb.count;
  }
  std::vector<std::uint32_t> sphereModels(const Sphere&) override { return {}; }

 private:
  BulletWorld w_;
};
#endif

#if CRUX_BENCH_HAVE_FCL
struct FclQueryData {
  fcl::CollisionObjectd* query = nullptr;
  std::size_t count = 0;
  std::vector<std::uint32_t> models;
};

bool countQueryBox(fcl::CollisionObjectd* a, fcl::CollisionObjectd* b, void* data) {
  auto& d = *static_cast<FclQueryData*>(data);
  fcl::CollisionObjectd* other = a == d.query ? b : a;
  if (other->getAABB().overlap(d.query->getAABB())) ++d.count;
  return false;
}

bool collectSphereHits(fcl::CollisionObjectd* a, fcl::CollisionObjectd* b, void* data) {
  auto& d = *static_cast<FclQueryData*>(data);
  fcl::CollisionObjectd* other = a == d.query ? b : a;
  const fcl::CollisionRequestd request(1, false);
  fcl::CollisionResultd result;
  fcl::collide(other, d.query, request, result);
  if (result.isCollision()) d.models.push_back(std::uint32_t(reinterpret_cast<std::uintptr_t>(other->getUserData())));
  return false;
}

class FclQueryEngine final : public QueryEngine {
 public:
  FclQueryEngine(FclShapes& shapes, const std::vector<Placement>& placements) : w_(shapes, placements) {}
  std::string name() const override { return "FCL DynamicAABBTree"; }
  bool hasRays() const override { return false; }
  RayAnswer ray(const RayCase&) override { return {}; }
  std::size_t boxCount(const Aabb& box) override {
    const Vec3 c = box.center(), e = box.max - box.min;
    fcl::CollisionObjectd q(std::make_shared<fcl::Boxd>(double(e.x()), double(e.y()), double(e.z())));
    q.setTranslation(fcl::Vector3d(double(c.x()), double(c.y()), double(c.z())));
    q.computeAABB();
    FclQueryData d;
    d.query = &q;
    w_.manager.collide(&q, &d, countQueryBox);
    return d.count;
  }
  std::vector<std::uint32_t> sphereModels(const Sphere& s) override {
    fcl::CollisionObjectd q(std::make_shared<fcl::Sphered>(double(s.radius)));
    q.setTranslation(fcl::Vector3d(double(s.center.x()), double(s.center.y()), double(s.center.z())));
    q.computeAABB();
    FclQueryData d;
    d.query = &q;
    w_.manager.collide(&q, &d, collectSphereHits);
    std::sort(d.models.begin(), d.models.end());
    return d.models;
  }

 private:
  FclWorld w_;
};
#endif

// ---- reporting ----------------------------------------------------------------------------------

struct Row {
  std::size_t models;
  std::string workload, engine, agree;
  double perItem = 0;  // seconds per frame / per query
  double cpuShare = 0;
  double items = 0;    // e.g. pairs per frame, hits
};
std::vector<Row> gRows;

const char* unitOf(const std::string& workload) { return workload == "update+pairs" ? "ms/frame" : "us/query"; }
double scaleOf(const std::string& workload) { return workload == "update+pairs" ? 1e3 : 1e6; }

void printRow(const Row& r, double reference) {
  std::printf("%8zu  %-30s %12.4f %10s  %8.2fx  %4.0f%%  %12.1f  %s\n", r.models, r.engine.c_str(),
              r.perItem * scaleOf(r.workload), unitOf(r.workload), reference > 0 ? r.perItem / reference : 0.0,
              100 * r.cpuShare, r.items, r.agree.c_str());
}

// ---- the workloads --------------------------------------------------------------------------------

void runPairs(const Workload& w, std::vector<std::unique_ptr<PairEngine>>& engines, const Options& opt) {
  std::printf("\n== update + pairs: %zu models, %zu movers, %zu frames ==\n", w.models, w.frames.empty() ? 0 : w.frames[0].moves.size(),
              w.frames.size());
  std::printf("%8s  %-30s %12s %10s  %9s  %5s  %12s  %s\n", "models", "engine", "time", "", "vs tree", "cpu", "pairs/frame",
              "agreement");
  std::vector<std::vector<std::size_t>> counts(engines.size());
  std::vector<Timing> timing(engines.size());
  for (int run = 0; run < opt.runs; ++run) {
    for (std::size_t e = 0; e < engines.size(); ++e) {
      const std::size_t k = run % 2 ? engines.size() - 1 - e : e;  // alternate the order
      engines[k]->build(w.initial);
      std::vector<std::size_t> perFrame;
      perFrame.reserve(w.frames.size());
      const Stopwatch sw;
      for (const Frame& f : w.frames) perFrame.push_back(engines[k]->frame(f));
      timing[k].runs.push_back(sw.elapsed());
      if (run == 0) counts[k] = std::move(perFrame);
    }
  }
  double reference = 0;
  for (std::size_t e = 0; e < engines.size(); ++e) {
    std::size_t mismatched = 0;
    for (std::size_t f = 0; f < w.frames.size(); ++f) mismatched += counts[e][f] != counts[0][f];
    double mean = 0;
    for (const std::size_t c : counts[e]) mean += double(c);
    const Seconds m = timing[e].median(opt.cpuClock);
    Row r{w.models, "update+pairs", engines[e]->name(),
          e == 0 ? "reference" : (mismatched ? std::to_string(mismatched) + " frames differ" : "all frames equal"),
          (opt.cpuClock ? m.cpu : m.wall) / double(w.frames.size()), m.wall > 0 ? m.cpu / m.wall : 0,
          mean / double(std::max<std::size_t>(1, w.frames.size()))};
    if (e == 0) reference = r.perItem;
    printRow(r, reference);
    gRows.push_back(r);
    if (mismatched) {
      std::fprintf(stderr, "bench_scene: %s disagrees on pair counts in %zu frames\n", engines[e]->name().c_str(), mismatched);
    }
  }
}

template <class Query, class Answer>
void timeQueries(const std::string& workload, const Workload& w, std::vector<QueryEngine*>& engines,
                 const std::vector<Query>& queries, const std::function<Answer(QueryEngine&, const Query&)>& ask,
                 const std::function<std::string(const std::vector<Answer>&, const std::vector<Answer>&)>& compare,
                 const std::function<double(const std::vector<Answer>&)>& items, const Options& opt) {
  std::printf("\n== %s: %zu models, %zu queries ==\n", workload.c_str(), w.models, queries.size());
  std::printf("%8s  %-30s %12s %10s  %9s  %5s  %12s  %s\n", "models", "engine", "time", "", "vs tree", "cpu", "answers",
              "agreement");
  std::vector<std::vector<Answer>> answers(engines.size());
  std::vector<Timing> timing(engines.size());
  for (int run = 0; run < opt.runs; ++run) {
    for (std::size_t e = 0; e < engines.size(); ++e) {
      const std::size_t k = run % 2 ? engines.size() - 1 - e : e;
      std::vector<Answer> out;
      out.reserve(queries.size());
      const Stopwatch sw;
      for (const Query& q : queries) out.push_back(ask(*engines[k], q));
      timing[k].runs.push_back(sw.elapsed());
      if (run == 0) answers[k] = std::move(out);
    }
  }
  double reference = 0;
  for (std::size_t e = 0; e < engines.size(); ++e) {
    const Seconds m = timing[e].median(opt.cpuClock);
    Row r{w.models, workload, engines[e]->name(), e == 0 ? "reference" : compare(answers[0], answers[e]),
          (opt.cpuClock ? m.cpu : m.wall) / double(std::max<std::size_t>(1, queries.size())), m.wall > 0 ? m.cpu / m.wall : 0,
          items(answers[e])};
    if (e == 0) reference = r.perItem;
    printRow(r, reference);
    gRows.push_back(r);
  }
}

void runQueries(const Workload& w, std::vector<QueryEngine*>& all, const Options& opt) {
  std::vector<QueryEngine*> rayEngines, sphereEngines;
  for (QueryEngine* e : all) {
    if (e->hasRays()) rayEngines.push_back(e);
    if (e->hasSpheres()) sphereEngines.push_back(e);
  }
  const double tolerance = 1e-4 * double(w.side);
  if (opt.has("rays"))
    for (QueryEngine* e : rayEngines) e->prepareRays();
  if (opt.has("rays") && !rayEngines.empty())
  timeQueries<RayCase, RayAnswer>(
      "scene rays", w, rayEngines, w.rays, [](QueryEngine& e, const RayCase& r) { return e.ray(r); },
      [tolerance](const std::vector<RayAnswer>& ref, const std::vector<RayAnswer>& got) {
        std::size_t hitDiffers = 0, modelDiffers = 0;
        double worst = 0;
        for (std::size_t i = 0; i < ref.size(); ++i) {
          if (ref[i].hit != got[i].hit) {
            ++hitDiffers;
            continue;
          }
          if (!ref[i].hit) continue;
          const double d = std::abs(ref[i].t - got[i].t);
          worst = std::max(worst, d);
          if (ref[i].model != got[i].model && d > tolerance) ++modelDiffers;
        }
        std::ostringstream s;
        s.precision(2);
        if (!hitDiffers && !modelDiffers) s << "all equal, max |dt| " << worst;
        else s << hitDiffers << " hit/miss + " << modelDiffers << " model differ, max |dt| " << worst;
        return s.str();
      },
      [](const std::vector<RayAnswer>& a) {
        return double(std::count_if(a.begin(), a.end(), [](const RayAnswer& x) { return x.hit; }));
      },
      opt);
  if (opt.has("boxes"))
  timeQueries<Aabb, std::size_t>(
      "AABB region queries (bounds only)", w, all, w.boxes, [](QueryEngine& e, const Aabb& b) { return e.boxCount(b); },
      [](const std::vector<std::size_t>& ref, const std::vector<std::size_t>& got) {
        std::size_t differ = 0;
        for (std::size_t i = 0; i < ref.size(); ++i) differ += ref[i] != got[i];
        return differ ? std::to_string(differ) + " counts differ" : std::string("all counts equal");
      },
      [](const std::vector<std::size_t>& a) {
        double s = 0;
        for (const std::size_t x : a) s += double(x);
        return s / double(std::max<std::size_t>(1, a.size()));
      },
      opt);
  if (opt.has("spheres") && !sphereEngines.empty())
  timeQueries<Sphere, std::vector<std::uint32_t>>(
      "sphere region queries (exact, triangles)", w, sphereEngines, w.spheres,
      [](QueryEngine& e, const Sphere& s) { return e.sphereModels(s); },
      [](const std::vector<std::vector<std::uint32_t>>& ref, const std::vector<std::vector<std::uint32_t>>& got) {
        std::size_t differ = 0;
        for (std::size_t i = 0; i < ref.size(); ++i) differ += ref[i] != got[i];
        return differ ? std::to_string(differ) + " model sets differ" : std::string("all model sets equal");
      },
      [](const std::vector<std::vector<std::uint32_t>>& a) {
        double s = 0;
        for (const auto& x : a) s += double(x.size());
        return s / double(std::max<std::size_t>(1, a.size()));
      },
      opt);
}

/// Scene rays as one batch (crux::raycast(scene, rays, out, options, ParallelOptions), scene_batch.hpp)
/// on 1 thread and on every hardware thread: the cost of the same rays with more cores. Every
/// ray gets the longest ray length of the set as its maxDistance (a batch takes one options);
/// the N-thread answers must equal the 1-thread answers bitwise (the batch's contract).
void runThreadedRays(const Workload& w, const CruxQueryEngine& engine, const Options& opt) {
  const std::uint32_t n = std::max(2u, std::thread::hardware_concurrency());
  std::vector<Ray> rays;
  RayQueryOptions options;
  options.maxDistance = 0;
  for (const RayCase& r : w.rays) {
    rays.push_back(r.ray);
    options.maxDistance = std::max(options.maxDistance, r.length);
  }
  const std::string workload = "scene rays, 1 and N threads";
  std::printf("\n== %s: %zu models, %zu rays (batch, maxDistance %.3g) ==\n", workload.c_str(), w.models, rays.size(),
              double(options.maxDistance));
  std::vector<std::optional<SceneRayHit>> reference(rays.size()), out(rays.size());
  double reference1 = 0;
  for (const std::uint32_t threads : {1u, n}) {
    ParallelOptions parallel;
    parallel.threads = threads;
    crux::raycast(engine.scene(), Span<const Ray>(rays), Span<std::optional<SceneRayHit>>(threads == 1 ? reference : out),
                  options, parallel);
    std::size_t differ = 0, hits = 0;
    if (threads != 1) {
      for (std::size_t i = 0; i < rays.size(); ++i) {
        const auto& a = reference[i];
        const auto& b = out[i];
        differ += a.has_value() != b.has_value() || (a && (a->model != b->model || a->hit.t != b->hit.t));
      }
    }
    for (const auto& h : reference) hits += h.has_value();
    // Repetitions so a run lasts ~0.05 s; median of opt.runs runs.
    const Stopwatch probe;
    crux::raycast(engine.scene(), Span<const Ray>(rays), Span<std::optional<SceneRayHit>>(out), options, parallel);
    const Seconds once = probe.elapsed();
    const int reps = std::max(1, int(0.05 / std::max(1e-6, opt.cpuClock ? once.cpu : once.wall)));
    Timing timing;
    for (int run = 0; run < opt.runs; ++run) {
      const Stopwatch sw;
      for (int k = 0; k < reps; ++k)
        crux::raycast(engine.scene(), Span<const Ray>(rays), Span<std::optional<SceneRayHit>>(out), options, parallel);
      Seconds t = sw.elapsed();
      t.wall /= reps;
      t.cpu /= reps;
      timing.runs.push_back(t);
    }
    const Seconds m = timing.median(opt.cpuClock);
    Row r{w.models, workload, engine.name() + ", " + std::to_string(threads) + (threads == 1 ? " thread" : " threads"),
          threads == 1 ? "reference" : (differ ? std::to_string(differ) + " rays differ" : "all equal (bitwise)"),
          (opt.cpuClock ? m.cpu : m.wall) / double(std::max<std::size_t>(1, rays.size())),
          m.wall > 0 ? m.cpu / m.wall / threads : 0, double(hits)};
    if (threads == 1) reference1 = r.perItem;
    printRow(r, reference1);
    gRows.push_back(r);
  }
}

double findTime(std::size_t models, const std::string& workload, const std::string& engine) {
  for (const Row& r : gRows)
    if (r.models == models && r.workload == workload && r.engine == engine) return r.perItem;
  return 0;
}

void printTargets(const Options& opt) {
  std::printf("\n== targets ==\n");
  const auto target = [](const char* what, double crux, double peer, double factor) {
    if (crux <= 0 || peer <= 0) {
      std::printf("  %-62s n/a (not run)\n", what);
      return;
    }
    const double ratio = peer / crux;
    std::printf("  %-62s %6.2fx  %s (target >= %.0fx)\n", what, ratio, ratio >= factor ? "PASS" : "MISS", factor);
  };
  for (const std::size_t n : opt.sizes) {
    if (n < 10000) continue;
    const double tree = findTime(n, "update+pairs", "crux dynamic_aabb_tree");
    std::string label = "update+pairs, " + std::to_string(n) + " models: tree vs Bullet";
    target(label.c_str(), tree, findTime(n, "update+pairs", "Bullet btDbvtBroadphase"), 3);
    label = "update+pairs, " + std::to_string(n) + " models: tree vs FCL";
    target(label.c_str(), tree, findTime(n, "update+pairs", "FCL DynamicAABBTree"), 3);
  }
  for (const std::size_t n : opt.sizes) {
    const std::string label = "scene rays, " + std::to_string(n) + " models: tree vs Bullet";
    target(label.c_str(), findTime(n, "scene rays", "crux dynamic_aabb_tree"),
           findTime(n, "scene rays", "Bullet btCollisionWorld"), 10);
  }
}

void printScaling(const Options& opt) {
  if (opt.sizes.size() < 2) return;
  std::printf("\n== scaling: time per frame / per query relative to the smallest scene (%zu models) ==\n", opt.sizes[0]);
  std::map<std::pair<std::string, std::string>, std::vector<double>> series;
  std::vector<std::pair<std::string, std::string>> order;
  for (const Row& r : gRows) {
    const auto key = std::make_pair(r.workload, r.engine);
    if (!series.count(key)) order.push_back(key);
    series[key].push_back(r.perItem);
  }
  std::printf("  %-42s %-28s", "workload", "engine");
  for (const std::size_t n : opt.sizes) std::printf(" %9zu", n);
  std::printf("\n");
  for (const auto& key : order) {
    const auto& v = series[key];
    std::printf("  %-42s %-28s", key.first.c_str(), key.second.c_str());
    for (const double x : v) std::printf(" %8.2fx", v[0] > 0 ? x / v[0] : 0.0);
    std::printf("\n");
  }
}

/// --json FILE: the settings and every printed row (seconds per frame or per query).
void writeJson(const Options& opt) {
  std::ofstream out(opt.json);
  if (!out) {
    std::fprintf(stderr, "bench_scene: cannot write %s\n", opt.json.c_str());
    return;
  }
  out << "{\n  \"bench\": \"bench_scene\",\n  \"build_type\": " << crux::bench::jsonString(CRUX_BENCH_BUILD_TYPE)
      << ",\n  \"crux_real\": " << crux::bench::jsonString(sizeof(Real) == sizeof(float) ? "float" : "double")
      << ",\n  \"quick\": " << (opt.quick ? "true" : "false") << ",\n  \"runs\": " << opt.runs
      << ",\n  \"clock\": " << crux::bench::jsonString(opt.cpuClock ? "cpu" : "wall") << ",\n  \"seed\": " << opt.seed
      << ",\n  \"rows\": [";
  char number[32];
  for (std::size_t i = 0; i < gRows.size(); ++i) {
    const Row& r = gRows[i];
    out << (i ? "," : "") << "\n    {\"models\": " << r.models << ", \"workload\": " << crux::bench::jsonString(r.workload)
        << ", \"engine\": " << crux::bench::jsonString(r.engine) << ", \"agreement\": " << crux::bench::jsonString(r.agree);
    std::snprintf(number, sizeof number, "%.9g", r.perItem);
    out << ", \"seconds_per_item\": " << number;
    std::snprintf(number, sizeof number, "%.4g", r.cpuShare);
    out << ", \"cpu_share\": " << number;
    std::snprintf(number, sizeof number, "%.9g", r.items);
    out << ", \"items\": " << number << "}";
  }
  out << "\n  ]\n}\n";
}

void usage() {
  std::printf(
      "bench_scene [--quick] [--sizes N,N,...] [--runs R] [--clock wall|cpu] [--seed S] [--only ENGINE]\n"
      "            [--workloads pairs,rays,boxes,spheres] [--json FILE]\n"
      "  crux scenes (3 broad phases) vs Bullet btCollisionWorld+btDbvtBroadphase and FCL\n"
      "  DynamicAABBTreeCollisionManager: update+pairs, scene rays, region queries.\n");
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        usage();
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--quick") {
      opt.quick = true;
      opt.sizes = {1000, 5000};
      opt.runs = 1;
    } else if (a == "--sizes") {
      opt.sizes.clear();
      std::stringstream s(next());
      for (std::string x; std::getline(s, x, ',');) opt.sizes.push_back(std::stoul(x));
    } else if (a == "--runs") {
      opt.runs = std::max(1, std::stoi(next()));
    } else if (a == "--clock") {
      opt.cpuClock = next() == "cpu";
    } else if (a == "--seed") {
      opt.seed = std::stoull(next());
    } else if (a == "--only") {
      opt.only = next();
    } else if (a == "--workloads") {
      opt.workloads = next();
    } else if (a == "--json") {
      opt.json = next();
    } else {
      usage();
      return a == "--help" || a == "-h" ? 0 : 2;
    }
  }

  std::printf("bench_scene: crux::Real = %s, build %s, clock %s, runs %d (median)\n",
              sizeof(Real) == sizeof(float) ? "float" : "double", CRUX_BENCH_BUILD_TYPE, opt.cpuClock ? "cpu" : "wall",
              opt.runs);
  std::printf("load average at start: %s\n", loadAverage().c_str());
#if CRUX_BENCH_HAVE_BULLET
  std::printf("peer: Bullet %d (btScalar = float)\n", btGetVersion());
#else
  std::printf("peer absent: Bullet (libbullet-dev)\n");
#endif
#if CRUX_BENCH_HAVE_FCL
  std::printf("peer: FCL %s\n", FCL_VERSION);
#else
  std::printf("peer absent: FCL (libfcl-dev)\n");
#endif

  std::vector<BenchMesh> meshes;
  for (const char* name : {"bunny00", "cow", "knot1", "rotor"}) meshes.push_back(loadBenchMesh(name));
  std::printf("meshes (scaled to radius 1, shared by all instances):");
  for (const BenchMesh& m : meshes) std::printf(" %s %zu tris;", m.name.c_str(), m.mesh->triangleCount());
  std::printf("\n");
#if CRUX_BENCH_HAVE_BULLET
  BulletShapes bulletShapes(meshes);
#endif
#if CRUX_BENCH_HAVE_FCL
  FclShapes fclShapes(meshes);
#endif

  for (const std::size_t n : opt.sizes) {
    const int frames = opt.quick ? 5 : (n <= 1000 ? 100 : n <= 10000 ? 40 : 20);
    const std::size_t rays = opt.quick ? 200 : (n <= 10000 ? 2000 : 1000);
    const std::size_t boxes = opt.quick ? 200 : 2000;
    const std::size_t spheres = opt.quick ? 50 : (n <= 10000 ? 500 : 200);
    const Workload w = makeWorkload(meshes, n, frames, rays, boxes, spheres, opt.seed);
    std::printf("\n######## %zu models in a cube of side %.1f (radius-1 models), %d frames ########\n", n, double(w.side),
                frames);

    std::vector<std::unique_ptr<PairEngine>> pairEngines;
    pairEngines.push_back(std::make_unique<CruxBroadPhaseEngine>(BroadPhaseKind::DynamicAabbTree));
    pairEngines.push_back(std::make_unique<CruxBroadPhaseEngine>(BroadPhaseKind::Octree));
    if (n <= 10000) pairEngines.push_back(std::make_unique<CruxBroadPhaseEngine>(BroadPhaseKind::BruteForce));
    else std::printf("(crux brute_force update+pairs skipped at %zu models: n(n-1)/2 = %.1e box tests per frame)\n", n,
                     double(n) * double(n - 1) / 2);
    pairEngines.push_back(std::make_unique<CruxSceneEngine>(meshes));
#if CRUX_BENCH_HAVE_BULLET
    if (sizeof(Real) == sizeof(float)) pairEngines.push_back(std::make_unique<BulletPairEngine>(bulletShapes));
#endif
#if CRUX_BENCH_HAVE_FCL
    pairEngines.push_back(std::make_unique<FclPairEngine>(fclShapes));
#endif
    if (!opt.only.empty())
      pairEngines.erase(std::remove_if(pairEngines.begin(), pairEngines.end(),
                                       [&](const auto& e) { return e->name().find(opt.only) == std::string::npos; }),
                        pairEngines.end());
    if (!pairEngines.empty() && opt.has("pairs")) runPairs(w, pairEngines, opt);
    pairEngines.clear();

    const auto wanted = [&opt](const std::string& name) { return opt.only.empty() || name.find(opt.only) != std::string::npos; };
    std::vector<std::unique_ptr<QueryEngine>> queryEngines;
    for (const BroadPhaseKind kind : {BroadPhaseKind::DynamicAabbTree, BroadPhaseKind::Octree, BroadPhaseKind::BruteForce})
      if (wanted("crux " + std::string(broadPhaseName(kind))))
        queryEngines.push_back(std::make_unique<CruxQueryEngine>(kind, meshes, w.final));
#if CRUX_BENCH_HAVE_BULLET
    if (sizeof(Real) == sizeof(float) && wanted("Bullet btCollisionWorld"))
      queryEngines.push_back(std::make_unique<BulletQueryEngine>(bulletShapes, w.final));
#endif
#if CRUX_BENCH_HAVE_FCL
    if (wanted("FCL DynamicAABBTree")) queryEngines.push_back(std::make_unique<FclQueryEngine>(fclShapes, w.final));
#endif
    std::vector<QueryEngine*> raw;
    for (auto& e : queryEngines)
      if (opt.only.empty() || e->name().find(opt.only) != std::string::npos) raw.push_back(e.get());
    if (!raw.empty()) runQueries(w, raw, opt);
    if (opt.has("rays") && !queryEngines.empty())
      if (const auto* engine = dynamic_cast<const CruxQueryEngine*>(queryEngines.front().get())) runThreadedRays(w, *engine, opt);
  }
  printTargets(opt);
  printScaling(opt);
  if (!opt.json.empty()) writeJson(opt);
  std::printf("\nload average at end: %s\n", loadAverage().c_str());
  return 0;
}
