#pragma once
/// @file scene.hpp  A scene: models in a transform hierarchy, kept in a broad phase, with ray,
/// region and pair queries over all of them.
///
/// Every mutation (add, remove, setTransform, setParent) brings the broad phase up to date
/// before it returns, using ModelHierarchy::takeMoved() to find every model whose world
/// transform changed (descendants of a moved model included). Queries then go through the
/// broad phase (ScenePath::BroadPhase, the default) or over every model (ScenePath::BruteForce,
/// the reference the tests compare with, which also recomputes each model's bounds from
/// scratch); both give identical answers.
///
/// Threads (docs/threads.md): const members (raycast, query, placed, bounds, models, ...) only
/// read — the hierarchy keeps world transforms current on every mutation and the broad phases'
/// const queries use stack storage — so any number of threads may run them at once, with no
/// preparation call (scene_batch.hpp runs batches of them on all cores). Mutations (add, remove,
/// setTransform(s), setParent) and the non-const pair queries (overlappingPairs, boundsPairs:
/// the broad phase updates its pair cache) are exclusive: nothing else may use the scene
/// meanwhile.
///
/// Errata fixed: the book's scene raycast took t = -1 ("no hit") as the closest hit; its region
/// queries tested bounding boxes only without saying so. Here rays report the closest real hit
/// and region queries test triangles unless RegionTest::Bounds is asked for.

#include <crux/model/hierarchy.hpp>
#include <crux/model/rigid_frame.hpp>
#include <crux/scene/broad_phase.hpp>

#include <limits>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

namespace crux {

/// Which path a scene query takes.
enum class ScenePath { BroadPhase, BruteForce };

/// What a region query tests: the models' triangles (exact) or only their bounding boxes.
enum class RegionTest { Triangles, Bounds };

/// The closest ray hit in a scene: the model and the hit in world space.
struct SceneRayHit {
  ModelId model = kNoModel;
  MeshRayHit hit;
};

/// Relative padding of the boxes the scene keeps in its broad phase: a model's world bounds
/// (worldBounds) grown on every side by kSceneBoundsPadding·(largest |coordinate| of the box +
/// its largest extent). It absorbs the rounding of worldBounds and of the model queries'
/// world-to-model mappings (a few ulps of the coordinates), so the broad phase never hides a
/// model that a query or another model touches. 8 ulps of Real.
inline constexpr Real kSceneBoundsPadding = Real(8) * std::numeric_limits<Real>::epsilon();

/// Relative slack of the broad-phase stage of scene queries, for shapes and rays whose
/// coordinates are much larger than the models they reach (the padding above scales with the
/// models only). 64 ulps of Real:
///  - rays test boxes grown by kSceneQuerySlack·(largest |origin coordinate|), and a box entered
///    beyond best_t + kSceneQuerySlack·(best_t + largest |origin coordinate|) is pruned (entry
///    distances come from the slab test, hits from the model ray casts in model space);
///  - exact region queries collect candidates with the shape grown by kSceneQuerySlack·(its
///    largest |coordinate| + its size) before testing triangles (bounds-only queries use the
///    shape as given).
/// Only which boxes are visited depends on it, never an answer.
inline constexpr Real kSceneQuerySlack = Real(64) * std::numeric_limits<Real>::epsilon();

/// The box the scene stores for a placed mesh: worldBounds padded by kSceneBoundsPadding.
Aabb sceneBounds(const PlacedMesh& placed);

/// A scene of models over shared meshes.
class Scene {
 public:
  /// An empty scene with a broad phase of the given kind (the dynamic AABB tree by default).
  explicit Scene(BroadPhaseKind kind = BroadPhaseKind::DynamicAabbTree);
  /// An empty scene using the given (empty) broad phase. Throws InvalidInput for a null or
  /// non-empty broad phase.
  explicit Scene(std::unique_ptr<BroadPhase> broadPhase);

  /// Adds a model (see ModelHierarchy::add; throws InvalidInput as it does, and when the
  /// model's world bounds overflow Real — the scene is then unchanged).
  ModelId add(std::shared_ptr<const Mesh> mesh, const Transform& local = {}, ModelId parent = kNoModel);
  /// Removes a model; its children move to its parent keeping their world pose.
  void remove(ModelId id);
  /// Sets a model's transform relative to its parent; its descendants move with it. Throws
  /// InvalidInput, leaving the scene unchanged, for an invalid transform or one that would put
  /// a moved model's world bounds beyond Real's range (docs/limits.md).
  void setTransform(ModelId id, const Transform& local);
  /// Sets the local transforms of many models, then updates the broad phase once (a frame's
  /// worth of moves). Throws InvalidInput with the scene unchanged when an id is unknown, a
  /// transform is invalid, or a moved model's world bounds would overflow (all moves undone).
  void setTransforms(const std::vector<std::pair<ModelId, Transform>>& moves);
  /// Re-parents a model keeping its world pose (kNoModel detaches it); a cycle throws.
  void setParent(ModelId id, ModelId parent);

  /// The models and their hierarchy (read-only: change them through the scene).
  const ModelHierarchy& models() const { return hierarchy_; }
  /// The broad phase (read-only: the scene keeps it in sync).
  const BroadPhase& broadPhase() const { return *broadPhase_; }
  /// The box stored in the broad phase for a model (sceneBounds of its placed mesh).
  const Aabb& bounds(ModelId id) const { return broadPhase_->bounds(id); }
  /// A model's mesh placed in the world.
  PlacedMesh placed(ModelId id) const { return hierarchy_.placed(id); }
  std::size_t size() const { return hierarchy_.size(); }

  /// Preconditions of raycast and query as of the mesh queries (mesh_query.hpp, precondition.hpp):
/// a ray, sphere, AABB or OBB that is not queryable(...) gets no hit or an empty list (an abort
/// naming the query with CRUX_CHECK_PRECONDITIONS).
/// Closest hit over all models (ties: lowest model id, then the model's own rule). The broad
  /// phase visits boxes front to back and prunes every box entered beyond the best hit.
  std::optional<SceneRayHit> raycast(const Ray& ray, const RayQueryOptions& options = {},
                                     ScenePath path = ScenePath::BroadPhase) const;
  /// Ids (ascending) of the models whose triangles (RegionTest::Triangles) or boxes
  /// (RegionTest::Bounds) touch the shape.
  std::vector<ModelId> query(const Sphere& sphere, RegionTest test = RegionTest::Triangles,
                             ScenePath path = ScenePath::BroadPhase) const;
  std::vector<ModelId> query(const Aabb& box, RegionTest test = RegionTest::Triangles,
                             ScenePath path = ScenePath::BroadPhase) const;
  std::vector<ModelId> query(const Obb& box, RegionTest test = RegionTest::Triangles,
                             ScenePath path = ScenePath::BroadPhase) const;
  /// Every pair (a < b, sorted) of models whose surfaces touch (broad phase, then mesh–mesh);
  /// parent/child pairs included. Not const: the broad phase may update its pair cache.
  std::vector<std::pair<ModelId, ModelId>> overlappingPairs(ScenePath path = ScenePath::BroadPhase);
  /// Every pair (a < b, sorted) of models whose boxes overlap (broad phase only).
  std::vector<std::pair<ModelId, ModelId>> boundsPairs(ScenePath path = ScenePath::BroadPhase);
  /// The broad phase's box pairs through a collector (no sorting, no allocation by the scene).
  void boundsPairs(PairCollector& collector) { broadPhase_->pairs(collector); }

 private:
  void upsert(ModelId id);
  /// Puts a model's box into the broad phase and its mesh and frame into rayModels_.
  void store(ModelId id, const Aabb& box);
  void sync();
  template <class Shape>
  std::vector<ModelId> regionQuery(const Shape& shape, RegionTest test, ScenePath path) const;

  ModelHierarchy hierarchy_;
  std::unique_ptr<BroadPhase> broadPhase_;
  /// Each model's mesh and world frame (by id, one cache line each), made when the broad phase
  /// takes its box: a ray maps into a model through it without re-deriving the rotation matrix
  /// per ray and model, and without the hierarchy's checked look-ups.
  std::vector<model_detail::PreparedModel> rayModels_;
};

}  // namespace crux
