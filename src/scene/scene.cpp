#include <crux/scene/scene.hpp>

#include "box_tests.hpp"

#include <algorithm>
#include <cmath>

namespace crux {
namespace {

/// Closest hit over the candidates the broad phase hands out front to back; lowers maxT to
/// the best hit (plus slack) so farther boxes are pruned.
class ClosestModelCollector final : public RayProxyCollector {
 public:
  ClosestModelCollector(const ModelHierarchy& models, const Ray& ray, const RayQueryOptions& options)
      : models_(models), ray_(ray), options_(options), originScale_(ray.origin.cwiseAbs().maxCoeff()) {
    maxT = withSlack(options.maxDistance);
    boxMargin = kSceneQuerySlack * originScale_;
  }
  bool add(ProxyId id, Real) override {
    RayQueryOptions o = options_;
    if (best) o.maxDistance = best->hit.t;
    const std::optional<MeshRayHit> h = raycastClosest(models_.placed(id), ray_, o);
    if (h && (!best || h->t < best->hit.t || (h->t == best->hit.t && id < best->model))) {
      best = SceneRayHit{id, *h};
      maxT = withSlack(h->t);
    }
    return true;
  }
  std::optional<SceneRayHit> best;

 private:
  Real withSlack(Real t) const { return t + kSceneQuerySlack * (t + originScale_); }
  const ModelHierarchy& models_;
  const Ray& ray_;
  const RayQueryOptions& options_;
  Real originScale_;
};

class IdListCollector final : public ProxyCollector {
 public:
  explicit IdListCollector(std::vector<ModelId>& ids) : ids_(ids) {}
  bool add(ProxyId id) override {
    ids_.push_back(id);
    return true;
  }

 private:
  std::vector<ModelId>& ids_;
};

class PairListCollector final : public PairCollector {
 public:
  explicit PairListCollector(std::vector<std::pair<ModelId, ModelId>>& pairs) : pairs_(pairs) {}
  void add(ProxyId a, ProxyId b) override { pairs_.emplace_back(a, b); }

 private:
  std::vector<std::pair<ModelId, ModelId>>& pairs_;
};

bool touches(const PlacedMesh& m, const Sphere& s) { return overlaps(m, s); }
bool touches(const PlacedMesh& m, const Aabb& b) { return overlaps(m, b); }
bool touches(const PlacedMesh& m, const Obb& b) { return overlaps(m, b); }

/// The shape grown by kSceneQuerySlack relative to its own magnitude (candidates for exact tests).
Sphere grown(const Sphere& s) {
  return {s.center, s.radius + kSceneQuerySlack * (s.center.cwiseAbs().maxCoeff() + s.radius)};
}
Aabb grown(const Aabb& b) {
  const Real m = kSceneQuerySlack * std::max(b.min.cwiseAbs().maxCoeff(), b.max.cwiseAbs().maxCoeff());
  return {b.min - Vec3::Constant(m), b.max + Vec3::Constant(m)};
}
Obb grown(const Obb& b) {
  Obb o = b;
  o.half += Vec3::Constant(kSceneQuerySlack * (b.center.cwiseAbs().maxCoeff() + b.half.maxCoeff()));
  return o;
}

detail::AabbRegion region(const Aabb& b) { return detail::AabbRegion{b}; }
detail::SphereRegion region(const Sphere& s) { return detail::SphereRegion{s}; }
detail::ObbRegion region(const Obb& b) { return detail::ObbRegion(b); }

}  // namespace

Aabb sceneBounds(const PlacedMesh& placed) {
  const Aabb b = worldBounds(placed);
  const Real magnitude = std::max(b.min.cwiseAbs().maxCoeff(), b.max.cwiseAbs().maxCoeff());
  const Real pad = kSceneBoundsPadding * (magnitude + (b.max - b.min).maxCoeff());
  const Vec3 p = Vec3::Constant(pad);
  return {b.min - p, b.max + p};
}

Scene::Scene(BroadPhaseKind kind) : broadPhase_(makeBroadPhase(kind)) {}

Scene::Scene(std::unique_ptr<BroadPhase> broadPhase) : broadPhase_(std::move(broadPhase)) {
  if (!broadPhase_) throw InvalidInput("Scene: the broad phase is null");
  if (broadPhase_->size() != 0) throw InvalidInput("Scene: the broad phase is not empty");
}

void Scene::upsert(ModelId id) {
  const Aabb box = sceneBounds(hierarchy_.placed(id));
  if (broadPhase_->contains(id)) broadPhase_->update(id, box);
  else broadPhase_->insert(id, box);
}

void Scene::sync() {
  for (const ModelId id : hierarchy_.takeMoved()) {
    if (hierarchy_.contains(id)) upsert(id);
    else if (broadPhase_->contains(id)) broadPhase_->remove(id);
  }
}

ModelId Scene::add(std::shared_ptr<const Mesh> mesh, const Transform& local, ModelId parent) {
  const ModelId id = hierarchy_.add(std::move(mesh), local, parent);
  upsert(id);
  sync();
  return id;
}

void Scene::remove(ModelId id) {
  hierarchy_.remove(id);
  if (broadPhase_->contains(id)) broadPhase_->remove(id);
  sync();
}

void Scene::setTransform(ModelId id, const Transform& local) {
  hierarchy_.setLocal(id, local);
  sync();
}

void Scene::setTransforms(const std::vector<std::pair<ModelId, Transform>>& moves) {
  for (const auto& move : moves)
    if (!hierarchy_.contains(move.first))
      throw InvalidInput("Scene::setTransforms: no model with id " + std::to_string(move.first));
  for (const auto& [id, local] : moves) hierarchy_.setLocal(id, local);
  sync();
}

void Scene::setParent(ModelId id, ModelId parent) {
  hierarchy_.setParent(id, parent);
  sync();
}

std::optional<SceneRayHit> Scene::raycast(const Ray& ray, const RayQueryOptions& options, ScenePath path) const {
  if (path == ScenePath::BroadPhase) {
    ClosestModelCollector collector(hierarchy_, ray, options);
    broadPhase_->raycast(ray, collector);
    return collector.best;
  }
  std::optional<SceneRayHit> best;
  for (const ModelId id : hierarchy_.ids()) {
    const std::optional<MeshRayHit> h = raycastClosest(hierarchy_.placed(id), ray, options);
    if (h && (!best || h->t < best->hit.t || (h->t == best->hit.t && id < best->model))) best = SceneRayHit{id, *h};
  }
  return best;
}

template <class Shape>
std::vector<ModelId> Scene::regionQuery(const Shape& shape, RegionTest test, ScenePath path) const {
  std::vector<ModelId> result;
  if (path == ScenePath::BroadPhase) {
    std::vector<ModelId> candidates;
    IdListCollector collector(candidates);
    if (test == RegionTest::Bounds) broadPhase_->query(shape, collector);
    else broadPhase_->query(grown(shape), collector);
    if (test == RegionTest::Bounds) {
      result = std::move(candidates);
    } else {
      for (const ModelId id : candidates)
        if (touches(hierarchy_.placed(id), shape)) result.push_back(id);
    }
    std::sort(result.begin(), result.end());
    return result;
  }
  const auto r = region(shape);
  for (const ModelId id : hierarchy_.ids()) {
    const PlacedMesh m = hierarchy_.placed(id);
    if (test == RegionTest::Bounds ? r.leaf(sceneBounds(m)) : touches(m, shape)) result.push_back(id);
  }
  return result;  // ids() is ascending
}

std::vector<ModelId> Scene::query(const Sphere& sphere, RegionTest test, ScenePath path) const {
  return regionQuery(sphere, test, path);
}
std::vector<ModelId> Scene::query(const Aabb& box, RegionTest test, ScenePath path) const {
  return regionQuery(box, test, path);
}
std::vector<ModelId> Scene::query(const Obb& box, RegionTest test, ScenePath path) const {
  return regionQuery(box, test, path);
}

std::vector<std::pair<ModelId, ModelId>> Scene::boundsPairs(ScenePath path) {
  std::vector<std::pair<ModelId, ModelId>> result;
  if (path == ScenePath::BroadPhase) {
    PairListCollector collector(result);
    broadPhase_->pairs(collector);
    std::sort(result.begin(), result.end());
    return result;
  }
  const std::vector<ModelId> ids = hierarchy_.ids();
  std::vector<Aabb> boxes;
  boxes.reserve(ids.size());
  for (const ModelId id : ids) boxes.push_back(sceneBounds(hierarchy_.placed(id)));
  for (std::size_t i = 0; i < ids.size(); ++i)
    for (std::size_t j = i + 1; j < ids.size(); ++j)
      if (overlaps(boxes[i], boxes[j])) result.emplace_back(ids[i], ids[j]);
  return result;
}

std::vector<std::pair<ModelId, ModelId>> Scene::overlappingPairs(ScenePath path) {
  std::vector<std::pair<ModelId, ModelId>> result;
  if (path == ScenePath::BroadPhase) {
    for (const auto& [a, b] : boundsPairs(ScenePath::BroadPhase))
      if (overlaps(hierarchy_.placed(a), hierarchy_.placed(b))) result.emplace_back(a, b);
    return result;
  }
  const std::vector<ModelId> ids = hierarchy_.ids();
  for (std::size_t i = 0; i < ids.size(); ++i)
    for (std::size_t j = i + 1; j < ids.size(); ++j)
      if (overlaps(hierarchy_.placed(ids[i]), hierarchy_.placed(ids[j]))) result.emplace_back(ids[i], ids[j]);
  return result;
}

}  // namespace crux
