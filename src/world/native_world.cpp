/// @file native_world.cpp  The "native" backend: every hook forwards to the crux function of the
/// same op, so the world answers exactly what the direct API answers. Models and the scene are
/// one crux::Scene (dynamic AABB tree broad phase) with model names kept beside it.

#include <crux/world/native_world.hpp>

#include <crux/geometry/closest_point.hpp>
#include <crux/geometry/contact.hpp>
#include <crux/mesh/mesh_cast.hpp>
#include <crux/scene/scene_cast.hpp>
#include <crux/mesh/mesh_contact.hpp>
#include <crux/mesh/mesh_distance.hpp>
#include <crux/mesh/mesh_query_data.hpp>
#include <crux/mesh/mesh_volume.hpp>
#include <crux/geometry/overlap.hpp>
#include <crux/geometry/raycast.hpp>
#include <crux/mesh/mesh_query.hpp>
#include <crux/model/model_query.hpp>
#include <crux/scene/scene.hpp>

#include "geometry/unchecked.hpp"
#include "model/rigid.hpp"

#include <algorithm>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace crux {
namespace {

WorldRayHit toWorld(const RayHit& h) {
  WorldRayHit w;
  w.t = double(h.t);
  w.point = h.point.cast<double>();
  w.normal = h.normal.cast<double>();
  return w;
}

WorldRayHit toWorld(const MeshRayHit& h, ModelHandle model = {}) {
  WorldRayHit w;
  w.t = double(h.t);
  w.point = h.point.cast<double>();
  w.normal = h.normal.cast<double>();
  w.triangle = h.triangle;
  w.model = model;
  return w;
}

WorldCast toWorld(const CastResult& r) {
  WorldCast w;
  w.hit = true;
  w.t = double(r.t);
  w.pointA = r.pointA.cast<double>();
  w.pointB = r.pointB.cast<double>();
  w.normal = r.normal.cast<double>();
  w.startsOverlapping = r.startsOverlapping;
  w.depth = double(r.depth);
  w.capped = r.capped;
  return w;
}

/// A cast against a mesh at `meshPose` (mesh_cast.hpp), linear or rigid by `motion`.
WorldCast meshCast(const Mesh& m, const Transform& meshPose, const ConvexShape& shape, const Transform& shapePose,
                   const WorldMotion& motion, CastFind find) {
  const RigidMotion rigid{shapePose, motion.end.value_or(shapePose)};
  if (find == CastFind::Any) {
    WorldCast w;
    w.hit = motion.end ? castAny(m, meshPose, shape, rigid) : castAny(m, meshPose, shape, shapePose, motion.translation);
    return w;
  }
  const std::optional<MeshCastHit> h =
      motion.end ? castClosest(m, meshPose, shape, rigid) : castClosest(m, meshPose, shape, shapePose, motion.translation);
  if (!h) return {};
  WorldCast w = toWorld(h->cast);
  w.triangleB = h->triangle;
  return w;
}

/// A JSON-style quoted name for error messages (quotes and backslashes escaped).
std::string quoted(const std::string& s) {
  std::string q = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') q += '\\';
    q += c;
  }
  return q + '"';
}

/// Offers the hits of one mesh (a crux::Mesh or a PlacedMesh) to a collector, by its mode.
template <class MeshLike>
void collectHits(const MeshLike& mesh, const Ray& r, RayHitCollector& hits, const RayQueryOptions& options,
                 ModelHandle model = {}) {
  switch (hits.mode()) {
    case RayCollect::Closest:
      if (const auto h = raycastClosest(mesh, r, options)) hits.add(toWorld(*h, model));
      break;
    case RayCollect::Any:
      if (raycastAny(mesh, r, options)) hits.addAnonymousHit();
      break;
    case RayCollect::All:
      for (const MeshRayHit& h : raycastAll(mesh, r, options)) hits.add(toWorld(h, model));
      break;
  }
}

/// The convex view of an operand's shape (not a mesh). Points into `o` (hulls are not copied).
ConvexShape convexOf(const WorldOperand& o) {
  return std::visit(
      [](const auto& s) -> ConvexShape {
        if constexpr (std::is_same_v<std::decay_t<decltype(s)>, MeshHandle>)
          return ConvexShape();  // not reached: callers pass convex operands only
        else
          return ConvexShape(s);
      },
      o.shape);
}

WorldDistance toWorld(const DistanceResult& d) {
  WorldDistance w;
  w.distance = double(d.distance);
  w.pointA = d.pointA.cast<double>();
  w.pointB = d.pointB.cast<double>();
  w.normal = d.normal.cast<double>();
  return w;
}

/// A mesh–mesh result; nothing when no pair is within the bound.
std::optional<WorldDistance> toWorld(const MeshMeshDistanceResult& d) {
  if (!d.found) return std::nullopt;
  WorldDistance w;
  w.distance = double(d.distance);
  w.pointA = d.pointA.cast<double>();
  w.pointB = d.pointB.cast<double>();
  const Vec3d gap = w.pointA - w.pointB;
  const double n = gap.norm();
  if (n > 0) w.normal = gap / n;
  w.triangleA = d.triangleA;
  w.triangleB = d.triangleB;
  return w;
}

/// A distance bound in Real: beyond the largest finite Real it is no limit (a plain conversion
/// would be undefined behaviour there).
Real toRealBound(double bound) {
  return bound >= double(std::numeric_limits<Real>::max()) ? kNoLimit : Real(bound);
}

/// Per-mesh structures of the narrow phase and volume mode, built on first use (std::call_once,
/// so concurrent queries may race to it safely): the query data (MeshQueryDataOnDemand, one
/// object per part — contacts: the edge adjacency that removes ghost contacts on internal edges;
/// distance: the oriented boxes of mesh–mesh distance — so a world that asks only one kind
/// builds only its part), and the closed-solid view (mesh_volume.hpp). A world's meshes never
/// move their vertices, so the data stays current.
struct NativeMeshExtras {
  explicit NativeMeshExtras(const Mesh& mesh) : queryData(mesh) {}
  MeshQueryDataOnDemand queryData;
  std::once_flag volumeOnce;
  std::unique_ptr<MeshVolume> volume;
};

class NativeWorld final : public CollisionWorld {
 public:
  std::string_view backend() const override { return "native"; }
  std::string description() const override {
    return std::string("crux (geometry, mesh, model and scene layers), ") +
           (sizeof(Real) == sizeof(double) ? "double" : "float");
  }
  bool supports(WorldOp) const override { return true; }
  WorldTolerance tolerance() const override { return kNativeTolerance; }

  bool concurrentQueries() const override { return true; }
  // ModelHierarchy keeps world transforms current on every change and its const accessors never
  // write (docs/threads.md): nothing to prepare, so the base's no-op prepareConcurrentQueries()
  // stands.

 protected:
  // The base class keeps the crux::Mesh, which carries its own BVH; the adjacency and volume
  // view are built lazily (NativeMeshExtras).
  void onMeshAdded(MeshHandle h, const Mesh& m) override { extras_[h.index] = std::make_unique<NativeMeshExtras>(m); }
  void onMeshRemoved(MeshHandle h) override { extras_.erase(h.index); }

  Vec3d doClosestPoint(const Triangle& t, const Vec3& p) override { return unchecked::closestPoint(t, p).cast<double>(); }
  bool doOverlaps(const Triangle& t, const Sphere& s) override { return unchecked::overlaps(t, s); }
  bool doOverlaps(const Triangle& t, const Aabb& b) override { return unchecked::overlaps(t, b); }
  bool doOverlaps(const Triangle& t, const Obb& b) override { return unchecked::overlaps(t, b); }
  bool doOverlaps(const Triangle& t, const Plane& p) override { return unchecked::overlaps(t, p); }
  bool doOverlaps(const Triangle& a, const Triangle& b) override { return unchecked::overlaps(a, b); }
  std::optional<WorldRayHit> doRaycast(const Ray& r, const Triangle& t) override {
    const std::optional<RayHit> h = unchecked::raycast(r, t);
    if (!h) return std::nullopt;
    return toWorld(*h);
  }
  bool doIntersects(const Segment& s, const Triangle& t) override { return unchecked::intersects(s, t); }

  void doRaycast(MeshHandle m, const Ray& r, RayHitCollector& hits, const RayQueryOptions& options) override {
    collectHits(mesh(m), r, hits, options);
  }
  bool doIntersects(MeshHandle m, const Segment& s) override { return crux::intersects(mesh(m), s); }
  bool doOverlaps(MeshHandle m, const Sphere& s) override { return crux::overlaps(mesh(m), s); }
  bool doOverlaps(MeshHandle m, const Aabb& b) override { return crux::overlaps(mesh(m), b); }
  bool doOverlaps(MeshHandle m, const Obb& b) override { return crux::overlaps(mesh(m), b); }
  bool doOverlaps(MeshHandle m, const Plane& p) override { return crux::overlaps(mesh(m), p); }
  bool doOverlaps(MeshHandle m, const Triangle& t) override { return crux::overlaps(mesh(m), t); }
  bool doOverlaps(MeshHandle a, const Transform& ta, MeshHandle b, const Transform& tb) override {
    return crux::overlaps(mesh(a), ta, mesh(b), tb);
  }
  std::optional<std::vector<std::uint32_t>> doTouchingTriangles(MeshHandle m, const MeshQueryShape& shape) override {
    return std::visit([&](const auto& s) { return crux::touchingTriangles(mesh(m), s); }, shape);
  }
  std::optional<std::vector<std::pair<std::uint32_t, std::uint32_t>>> doTouchingTrianglePairs(
      MeshHandle a, const Transform& ta, MeshHandle b, const Transform& tb) override {
    return crux::touchingTrianglePairs(mesh(a), ta, mesh(b), tb);
  }

  // ---- narrow phase and volumes --------------------------------------------------------------------

  std::vector<WorldContact> doContacts(const WorldOperand& a, const WorldOperand& b, double margin) override {
    const Real m = Real(margin);
    std::vector<WorldContact> out;
    if (!a.isMesh() && !b.isMesh()) {
      ContactManifold manifold;
      crux::contacts(convexOf(a), a.pose, convexOf(b), b.pose, m, manifold);
      for (int i = 0; i < manifold.count; ++i) {
        const ContactPoint& p = manifold.points[i];
        out.push_back({p.pointA.cast<double>(), p.pointB.cast<double>(), manifold.normal.cast<double>(),
                       -double(p.separation), p.featureA, p.featureB});
      }
      return out;
    }
    // a mesh operand is a (CollisionWorld::contacts swaps a shape-first pair)
    const MeshHandle h = std::get<MeshHandle>(a.shape);
    MeshContactManifold manifold;
    crux::contacts(mesh(h), a.pose, convexOf(b), b.pose, m, manifold, &queryData(h, MeshQueryParts::Contacts));
    for (int i = 0; i < manifold.count; ++i) {
      const MeshContactPoint& p = manifold.points[i];
      out.push_back({p.pointA.cast<double>(), p.pointB.cast<double>(), p.normal.cast<double>(),
                     -double(p.separation), p.triangle, p.featureB});
    }
    return out;
  }

  WorldDistance doDistance(const WorldOperand& a, const WorldOperand& b) override {
    if (!a.isMesh()) return toWorld(crux::distance(convexOf(a), a.pose, convexOf(b), b.pose));
    // a mesh operand is a (CollisionWorld::distance swaps a shape-first pair)
    const MeshDistanceResult d = crux::distance(mesh(std::get<MeshHandle>(a.shape)), a.pose, convexOf(b), b.pose);
    WorldDistance w;
    w.distance = double(d.distance);
    w.pointA = d.pointA.cast<double>();
    w.pointB = d.pointB.cast<double>();
    w.normal = d.normal.cast<double>();
    w.triangleA = d.triangle;
    return w;
  }

  WorldCast doCast(const WorldOperand& a, const WorldMotion& motion, const WorldOperand& b, CastFind find) override {
    const ConvexShape shape = convexOf(a);
    if (b.isMesh()) return meshCast(mesh(std::get<MeshHandle>(b.shape)), b.pose, shape, a.pose, motion, find);
    const ConvexShape other = convexOf(b);
    const RigidMotion rigid{a.pose, motion.end.value_or(a.pose)};
    if (find == CastFind::Any) {
      WorldCast w;
      w.hit = motion.end ? crux::castAny(shape, rigid, other, b.pose)
                         : crux::castAny(shape, a.pose, motion.translation, other, b.pose);
      return w;
    }
    const CastResult r = motion.end ? crux::cast(shape, rigid, other, b.pose)
                                    : crux::cast(shape, a.pose, motion.translation, other, b.pose);
    return r.hit ? toWorld(r) : WorldCast{};
  }
  /// The mesh cast at the model's world pose (as castClosest / castAny of a PlacedMesh,
  /// model_cast.hpp).
  WorldCast doModelCast(const WorldOperand& a, const WorldMotion& motion, ModelHandle model, CastFind find) override {
    const PlacedMesh m = placed(model);
    return meshCast(*m.mesh, m.world, convexOf(a), a.pose, motion, find);
  }
  /// Scene::castClosest / castAny (scene_cast.hpp: ties go to the lowest model id).
  WorldCast doSceneCast(const WorldOperand& a, const WorldMotion& motion, CastFind find) override {
    const ConvexShape shape = convexOf(a);
    if (find == CastFind::Any) {
      WorldCast w;
      w.hit = motion.end ? crux::castAny(scene_, shape, RigidMotion{a.pose, *motion.end})
                         : crux::castAny(scene_, shape, a.pose, motion.translation);
      return w;
    }
    const std::optional<SceneCastHit> h = motion.end ? crux::castClosest(scene_, shape, RigidMotion{a.pose, *motion.end})
                                                     : crux::castClosest(scene_, shape, a.pose, motion.translation);
    if (!h) return {};
    WorldCast w = toWorld(h->hit.cast);
    w.triangleB = h->hit.triangle;
    w.model = ModelHandle{h->model};
    return w;
  }

  std::optional<WorldDistance> doMeshDistance(MeshHandle a, const Transform& ta, MeshHandle b, const Transform& tb,
                                              double maxDistance) override {
    MeshDistanceOptions options;
    options.maxDistance = toRealBound(maxDistance);
    options.dataA = &queryData(a, MeshQueryParts::Distance);
    options.dataB = &queryData(b, MeshQueryParts::Distance);
    return toWorld(crux::distance(mesh(a), ta, mesh(b), tb, options));
  }

  std::optional<WorldDistance> doModelDistance(ModelHandle a, ModelHandle b, double maxDistance) override {
    const PlacedMesh pa = placed(a, "a"), pb = placed(b, "b");
    MeshDistanceOptions options;
    options.maxDistance = toRealBound(maxDistance);
    options.dataA = modelDistanceData(a.index, pa.mesh);
    options.dataB = modelDistanceData(b.index, pb.mesh);
    return toWorld(crux::distance(*pa.mesh, pa.world, *pb.mesh, pb.world, options));
  }

  bool doPointInside(MeshHandle m, const Vec3& p) override { return volume(m).contains(p); }
  bool doOverlapsVolume(MeshHandle m, const Sphere& s) override { return volume(m).overlaps(s); }
  bool doOverlapsVolume(MeshHandle m, const Aabb& b) override { return volume(m).overlaps(b); }
  bool doOverlapsVolume(MeshHandle m, const Obb& b) override { return volume(m).overlaps(b); }
  bool doOverlapsVolume(MeshHandle m, const Triangle& t) override { return volume(m).overlaps(t); }
  bool doOverlapsVolume(MeshHandle a, const Transform& ta, MeshHandle b, const Transform& tb, bool aClosed,
                        bool bClosed) override {
    if (aClosed && bClosed) return crux::overlapsVolume(volume(a), ta, volume(b), tb);
    if (aClosed) return crux::overlapsVolume(volume(a), ta, mesh(b), tb);
    return crux::overlapsVolume(volume(b), tb, mesh(a), ta);
  }

  // Model volume mode: the world-space shape mapped into the model's mesh frame exactly as the
  // surface queries of model_query.cpp map it (RigidFrame: the identity skipped, axis-aligned
  // rotations as exact signed permutations, so integer-grid answers stay exact), then the mesh's
  // cached MeshVolume. A sphere stays a sphere, an AABB becomes an OBB (an AABB again under an
  // axis-aligned rotation), an OBB stays an OBB, a triangle a triangle.
  ModelMeshRef doModelMesh(ModelHandle model, WorldOp) override {
    const ModelId id = require(model, "model");
    const ModelMesh& m = modelMeshes_[id];
    return {names_[id], m.handle, m.name, m.mesh.get()};
  }
  bool doOverlapsVolume(ModelHandle model, const Sphere& s) override {
    const auto [v, f] = modelVolume(model);
    return v.overlaps(f.identity() ? s : Sphere{f.toMesh(s.center), s.radius});
  }
  bool doOverlapsVolume(ModelHandle model, const Aabb& b) override {
    const auto [v, f] = modelVolume(model);
    if (f.identity()) return v.overlaps(b);
    if (f.axisAligned()) {
      const Vec3 p = f.toMesh(b.min), q = f.toMesh(b.max);
      return v.overlaps(Aabb{p.cwiseMin(q), p.cwiseMax(q)});
    }
    return v.overlaps(Obb{f.toMesh(b.center()), b.half(), f.rotation().transpose()});
  }
  bool doOverlapsVolume(ModelHandle model, const Obb& b) override {
    const auto [v, f] = modelVolume(model);
    return v.overlaps(f.identity() ? b : Obb{f.toMesh(b.center), b.half, f.rotation().transpose() * b.axes});
  }
  bool doOverlapsVolume(ModelHandle model, const Triangle& t) override {
    const auto [v, f] = modelVolume(model);
    return v.overlaps(f.identity() ? t : Triangle{f.toMesh(t.a), f.toMesh(t.b), f.toMesh(t.c)});
  }

  // ---- models -----------------------------------------------------------------------------------

  ModelHandle doAddModel(const std::string& name, MeshHandle m, const Transform& local,
                         std::optional<ModelHandle> parent) override {
    if (byName_.count(name)) throw InvalidInput("name: a model named " + quoted(name) + " already exists");
    const ModelId parentId = parent ? require(*parent, "parent") : kNoModel;
    const ModelId id = scene_.add(sharedMesh(m), local, parentId);
    if (id >= names_.size()) names_.resize(std::size_t(id) + 1);
    names_[id] = name;
    if (id >= modelMeshes_.size()) modelMeshes_.resize(std::size_t(id) + 1);
    modelMeshes_[id] = ModelMesh{m, meshName(m), sharedMesh(m)};
    byName_.emplace(name, id);
    return ModelHandle{id};
  }
  void doRemoveModel(ModelHandle model) override {
    const ModelId id = require(model, "model");
    scene_.remove(id);
    byName_.erase(names_[id]);
    names_[id].clear();
    modelMeshes_[id] = ModelMesh{};
  }
  void doSetTransform(ModelHandle model, const Transform& local) override {
    scene_.setTransform(require(model, "model"), local);
  }
  void doSetParent(ModelHandle model, std::optional<ModelHandle> parent) override {
    const ModelId id = require(model, "model");
    ModelId parentId = kNoModel;
    if (parent) {
      parentId = require(*parent, "parent");
      if (parentId == id) throw InvalidInput("parent: " + quoted(names_[id]) + " is the model itself (a cycle)");
      const std::vector<ModelId> below = scene_.models().descendants(id);
      if (std::binary_search(below.begin(), below.end(), parentId))
        throw InvalidInput("parent: " + quoted(names_[parentId]) + " descends from " + quoted(names_[id]) +
                           " (a cycle)");
    }
    scene_.setParent(id, parentId);
  }
  std::optional<ModelHandle> doFindModel(std::string_view name) override {
    const auto it = byName_.find(name);
    if (it == byName_.end()) return std::nullopt;
    return ModelHandle{it->second};
  }
  std::vector<std::string> doDescendants(ModelHandle model) override {
    std::vector<std::string> out;
    for (const ModelId d : scene_.models().descendants(require(model, "model"))) out.push_back(names_[d]);
    std::sort(out.begin(), out.end());
    return out;
  }
  void doRaycast(ModelHandle model, const Ray& r, RayHitCollector& hits, const RayQueryOptions& options) override {
    collectHits(placed(model), r, hits, options, model);
  }
  bool doIntersects(ModelHandle model, const Segment& s) override { return crux::intersects(placed(model), s); }
  bool doOverlaps(ModelHandle model, const Sphere& s) override { return crux::overlaps(placed(model), s); }
  bool doOverlaps(ModelHandle model, const Aabb& b) override { return crux::overlaps(placed(model), b); }
  bool doOverlaps(ModelHandle model, const Obb& b) override { return crux::overlaps(placed(model), b); }
  bool doOverlaps(ModelHandle model, const Plane& p) override { return crux::overlaps(placed(model), p); }
  bool doOverlaps(ModelHandle model, const Triangle& t) override { return crux::overlaps(placed(model), t); }

  // ---- the scene --------------------------------------------------------------------------------

  void doSceneRaycast(const Ray& r, RayHitCollector& hits, const RayQueryOptions& options) override {
    if (hits.mode() == RayCollect::All) {  // every model's hits (the collector sorts them)
      for (const ModelId id : scene_.models().ids()) collectHits(scene_.placed(id), r, hits, options, ModelHandle{id});
      return;
    }
    // Closest (and Any, which any hit satisfies): the scene's front-to-back broad-phase walk.
    if (const std::optional<SceneRayHit> h = scene_.raycast(r, options))
      hits.add(toWorld(h->hit, ModelHandle{h->model}));
  }
  std::vector<std::string> doSceneQuery(const SceneQueryShape& shape, bool boundsOnly) override {
    const RegionTest test = boundsOnly ? RegionTest::Bounds : RegionTest::Triangles;
    const std::vector<ModelId> ids = std::visit([&](const auto& s) { return scene_.query(s, test); }, shape);
    std::vector<std::string> out;
    out.reserve(ids.size());
    for (const ModelId id : ids) out.push_back(names_[id]);
    std::sort(out.begin(), out.end());
    return out;
  }
  std::vector<std::pair<std::string, std::string>> doScenePairs() override {
    std::vector<std::pair<std::string, std::string>> out;
    for (const auto& [a, b] : scene_.overlappingPairs()) {
      const std::string& na = names_[a];
      const std::string& nb = names_[b];
      out.emplace_back(std::min(na, nb), std::max(na, nb));
    }
    std::sort(out.begin(), out.end());
    return out;
  }

 private:
  /// The id behind a handle; InvalidInput naming `field` when it is not a live model.
  ModelId require(ModelHandle model, const char* field) const {
    if (!scene_.models().contains(model.index))
      throw InvalidInput(std::string(field) + ": no model with handle " + std::to_string(model.index) +
                         " in this world");
    return model.index;
  }
  PlacedMesh placed(ModelHandle model, const char* field = "model") const {
    return scene_.placed(require(model, field));
  }
  NativeMeshExtras& extras(MeshHandle m) const { return *extras_.at(m.index); }
  /// Query data holding the one part `part` (Contacts or Distance) of the mesh, built on first use.
  const MeshQueryData& queryData(MeshHandle m, MeshQueryParts part) const { return extras(m).queryData.get(part); }
  /// The distance query data of a model's mesh while it is still the mesh defined under the
  /// handle the model was made with; null for a mesh whose name was redefined since (its
  /// distance then runs without the data: the same answers, slower near contact).
  const MeshQueryData* modelDistanceData(ModelId id, const Mesh* placedMesh) const {
    const MeshHandle h = modelMeshes_[id].handle;
    if (!extras_.count(h.index) || &mesh(h) != placedMesh) return nullptr;
    return &queryData(h, MeshQueryParts::Distance);
  }
  /// The closed-solid view (the base checked closedness before any volume hook runs).
  const MeshVolume& volume(MeshHandle m) const {
    NativeMeshExtras& e = extras(m);
    std::call_once(e.volumeOnce, [&] { e.volume = std::make_unique<MeshVolume>(mesh(m)); });
    return *e.volume;
  }
  /// The closed-solid view of a model's mesh and the model's world frame. The mesh's extras
  /// while it is still defined under the handle the model was made with; a model whose mesh
  /// name was redefined since keeps the old mesh, whose view lives in `retiredVolumes_`.
  std::pair<const MeshVolume&, model_detail::RigidFrame> modelVolume(ModelHandle model) {
    const ModelId id = require(model, "model");
    const PlacedMesh p = scene_.placed(id);
    const MeshHandle h = modelMeshes_[id].handle;
    const model_detail::RigidFrame frame(p.world);
    if (extras_.count(h.index) && &mesh(h) == p.mesh) return {volume(h), frame};
    std::lock_guard<std::mutex> lock(retiredMutex_);
    auto& [kept, v] = retiredVolumes_[p.mesh];
    if (!v) {
      kept = modelMeshes_[id].mesh;  // keeps the address from being reused while the view lives
      v = std::make_unique<MeshVolume>(*kept);
    }
    return {*v, frame};
  }

  std::map<std::uint32_t, std::unique_ptr<NativeMeshExtras>> extras_;  ///< by mesh handle
  /// The mesh each model was added with: its handle and name then (model volume mode).
  struct ModelMesh {
    MeshHandle handle;
    std::string name;
    std::shared_ptr<const Mesh> mesh;
  };
  std::vector<ModelMesh> modelMeshes_;  ///< by ModelId
  /// Volume views of meshes whose name was redefined while models still use them (rare; kept
  /// until the world goes, keyed by the mesh, which the models keep alive).
  std::map<const Mesh*, std::pair<std::shared_ptr<const Mesh>, std::unique_ptr<MeshVolume>>> retiredVolumes_;
  std::mutex retiredMutex_;
  Scene scene_;                                          ///< dynamic AABB tree broad phase
  std::vector<std::string> names_;                       ///< by ModelId; empty for free ids
  std::map<std::string, ModelId, std::less<>> byName_;  ///< live model names
};

}  // namespace

std::unique_ptr<CollisionWorld> makeNativeWorld() { return std::make_unique<NativeWorld>(); }

}  // namespace crux
