#include <crux/scene/scene.hpp>
#include <crux/precondition.hpp>

#include <sstream>

#include "geometry/unchecked.hpp"
#include "box_tests.hpp"
#include "../model/rigid.hpp"

#include <algorithm>
#include <cmath>

namespace crux {
namespace {

/// Closest hit over the candidates the broad phase hands out front to back; lowers maxT to
/// the best hit (plus slack) so farther boxes are pruned.
class ClosestModelCollector final : public RayProxyCollector {
 public:
  ClosestModelCollector(const std::vector<model_detail::PreparedModel>& models, const Ray& ray, const RayQueryOptions& options)
      : models_(models), ray_(ray), options_(options), originScale_(ray.origin.cwiseAbs().maxCoeff()) {
    maxT = withSlack(options.maxDistance);
    boxMargin = kSceneQuerySlack * originScale_;
  }
  bool add(ProxyId id, Real) override {
    RayQueryOptions o = options_;
    if (best) o.maxDistance = best->hit.t;
    // raycastClosest(placed(id), ray_, o) with the model's stored mesh and frame
    const model_detail::PreparedModel& m = models_[id];
    const std::optional<MeshRayHit> h = model_detail::raycastClosest(*m.mesh, m.frame, ray_, o);
    if (h && (!best || h->t < best->hit.t || (h->t == best->hit.t && id < best->model))) {
      best = SceneRayHit{id, *h};
      maxT = withSlack(h->t);
    }
    return true;
  }
  std::optional<SceneRayHit> best;

 private:
  Real withSlack(Real t) const { return t + kSceneQuerySlack * (t + originScale_); }
  const std::vector<model_detail::PreparedModel>& models_;
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

namespace {

/// The broad-phase box of model `id`; throws InvalidInput when the placement carries the mesh
/// beyond the largest Real (docs/limits.md), before anything is stored.
Aabb checkedSceneBounds(const ModelHierarchy& hierarchy, ModelId id) {
  const Aabb box = sceneBounds(hierarchy.placed(id));
  if (!box.min.allFinite() || !box.max.allFinite()) {
    std::ostringstream os;
    os.precision(17);
    const Vec3& t = hierarchy.world(id).translation;
    os << "Scene: model " << id << " placed beyond the representable range: its world bounds overflow (world "
       << "translation [" << t.x() << ", " << t.y() << ", " << t.z() << "]); the change was not applied";
    throw InvalidInput(os.str());
  }
  return box;
}

}  // namespace

void Scene::upsert(ModelId id) {
  const Aabb box = checkedSceneBounds(hierarchy_, id);
  store(id, box);
}

void Scene::store(ModelId id, const Aabb& box) {
  if (broadPhase_->contains(id)) broadPhase_->update(id, box);
  else broadPhase_->insert(id, box);
  if (id >= rayModels_.size()) rayModels_.resize(std::size_t(id) + 1);
  rayModels_[id] = {hierarchy_.mesh(id).get(), model_detail::RigidFrame(hierarchy_.world(id))};
}

void Scene::sync() {
  // Every box first, so that an overflowing placement throws before the broad phase changes
  // (the callers then restore the hierarchy).
  const std::vector<ModelId> moved = hierarchy_.takeMoved();
  std::vector<Aabb> boxes;
  boxes.reserve(moved.size());
  for (const ModelId id : moved)
    if (hierarchy_.contains(id)) boxes.push_back(checkedSceneBounds(hierarchy_, id));
  std::size_t next = 0;
  for (const ModelId id : moved) {
    if (hierarchy_.contains(id)) {
      store(id, boxes[next++]);
    } else if (broadPhase_->contains(id)) {
      broadPhase_->remove(id);
    }
  }
}

ModelId Scene::add(std::shared_ptr<const Mesh> mesh, const Transform& local, ModelId parent) {
  const ModelId id = hierarchy_.add(std::move(mesh), local, parent);
  try {
    upsert(id);
  } catch (const InvalidInput&) {  // not added: hierarchy and broad phase stay in step
    hierarchy_.remove(id);
    (void)hierarchy_.takeMoved();
    throw;
  }
  sync();
  return id;
}

void Scene::remove(ModelId id) {
  hierarchy_.remove(id);
  if (broadPhase_->contains(id)) broadPhase_->remove(id);
  sync();
}

void Scene::setTransform(ModelId id, const Transform& local) {
  const Transform old = hierarchy_.local(id);
  hierarchy_.setLocal(id, local);
  try {
    sync();
  } catch (const InvalidInput&) {  // a descendant overflowed: undo (same inputs, same world transforms)
    hierarchy_.setLocal(id, old);
    sync();
    throw;
  }
}

void Scene::setTransforms(const std::vector<std::pair<ModelId, Transform>>& moves) {
  for (const auto& move : moves)
    if (!hierarchy_.contains(move.first))
      throw InvalidInput("Scene::setTransforms: no model with id " + std::to_string(move.first));
  std::vector<Transform> old;
  old.reserve(moves.size());
  std::size_t applied = 0;
  try {
    for (const auto& [id, local] : moves) {
      old.push_back(hierarchy_.local(id));
      hierarchy_.setLocal(id, local);
      ++applied;
    }
    sync();
  } catch (const InvalidInput&) {  // an invalid transform or an overflow: undo in reverse order
    for (std::size_t k = applied; k-- > 0;) hierarchy_.setLocal(moves[k].first, old[k]);
    sync();
    throw;
  }
}

void Scene::setParent(ModelId id, ModelId parent) {
  hierarchy_.setParent(id, parent);
  sync();
}

std::optional<SceneRayHit> Scene::raycast(const Ray& ray, const RayQueryOptions& options, ScenePath path) const {
  if (!detail::entryPreconditions("Scene::raycast", detail::rule::kRay, ray))
    return std::nullopt;
  if (path == ScenePath::BroadPhase) {
    ClosestModelCollector collector(rayModels_, ray, options);
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
  if (!detail::entryPreconditions("Scene::query", detail::rule::kRegion, shape))
    return result;
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
      if (unchecked::overlaps(boxes[i], boxes[j])) result.emplace_back(ids[i], ids[j]);
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
