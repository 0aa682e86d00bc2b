/// @file native_world.cpp  The "native" backend: every hook forwards to the crux function of the
/// same op, so the world answers exactly what the direct API answers. Models and the scene are
/// one crux::Scene (dynamic AABB tree broad phase) with model names kept beside it.

#include <crux/world/native_world.hpp>

#include <crux/geometry/closest_point.hpp>
#include <crux/geometry/overlap.hpp>
#include <crux/geometry/raycast.hpp>
#include <crux/mesh/mesh_query.hpp>
#include <crux/model/model_query.hpp>
#include <crux/scene/scene.hpp>

#include <algorithm>
#include <map>
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
  // The base class keeps the crux::Mesh, which carries its own BVH: nothing else to build.
  void onMeshAdded(MeshHandle, const Mesh&) override {}
  void onMeshRemoved(MeshHandle) override {}

  Vec3d doClosestPoint(const Triangle& t, const Vec3& p) override { return crux::closestPoint(t, p).cast<double>(); }
  bool doOverlaps(const Triangle& t, const Sphere& s) override { return crux::overlaps(t, s); }
  bool doOverlaps(const Triangle& t, const Aabb& b) override { return crux::overlaps(t, b); }
  bool doOverlaps(const Triangle& t, const Obb& b) override { return crux::overlaps(t, b); }
  bool doOverlaps(const Triangle& t, const Plane& p) override { return crux::overlaps(t, p); }
  bool doOverlaps(const Triangle& a, const Triangle& b) override { return crux::overlaps(a, b); }
  std::optional<WorldRayHit> doRaycast(const Ray& r, const Triangle& t) override {
    const std::optional<RayHit> h = crux::raycast(r, t);
    if (!h) return std::nullopt;
    return toWorld(*h);
  }
  bool doIntersects(const Segment& s, const Triangle& t) override { return crux::intersects(s, t); }

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

  // ---- models -----------------------------------------------------------------------------------

  ModelHandle doAddModel(const std::string& name, MeshHandle m, const Transform& local,
                         std::optional<ModelHandle> parent) override {
    if (byName_.count(name)) throw InvalidInput("name: a model named " + quoted(name) + " already exists");
    const ModelId parentId = parent ? require(*parent, "parent") : kNoModel;
    const ModelId id = scene_.add(sharedMesh(m), local, parentId);
    if (id >= names_.size()) names_.resize(std::size_t(id) + 1);
    names_[id] = name;
    byName_.emplace(name, id);
    return ModelHandle{id};
  }
  void doRemoveModel(ModelHandle model) override {
    const ModelId id = require(model, "model");
    scene_.remove(id);
    byName_.erase(names_[id]);
    names_[id].clear();
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
  PlacedMesh placed(ModelHandle model) const { return scene_.placed(require(model, "model")); }

  Scene scene_;                                          ///< dynamic AABB tree broad phase
  std::vector<std::string> names_;                       ///< by ModelId; empty for free ids
  std::map<std::string, ModelId, std::less<>> byName_;  ///< live model names
};

}  // namespace

std::unique_ptr<CollisionWorld> makeNativeWorld() { return std::make_unique<NativeWorld>(); }

}  // namespace crux
