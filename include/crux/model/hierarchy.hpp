#pragma once
/// @file hierarchy.hpp  A forest of models: shared meshes, local transforms, parents.
///
/// Flat arrays indexed by ModelId with a free list; children as intrusive doubly linked sibling
/// lists (first child / next / previous sibling). World transforms are kept up to date eagerly:
/// setLocal recomputes the world transforms of the model and its descendants (world =
/// parent_world ∘ local, pre-order) before it returns, so reading never writes. Setting a
/// parent that would make a cycle throws InvalidInput; removing a model re-parents its children
/// to its parent keeping their world pose. Nothing recurses (every walk is an explicit loop), so
/// chains 10,000 deep are fine.
///
/// Composition keeps axis-aligned rotations exact (see model_query.hpp): a parent rotated by a
/// quarter turn maps its children's integer translations to integers, and chains of such
/// rotations do not drift.
///
/// Threads (docs/threads.md): every const member only reads (no `mutable` state), so any number
/// of threads may call const members at once. Mutation (add, remove, setLocal, setParent,
/// takeMoved, refreshWorld) is exclusive: no other thread may use the hierarchy meanwhile.

#include <crux/model/model_query.hpp>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace crux {

/// Index of a model in a ModelHierarchy (stable until removed; ids are reused after removal).
using ModelId = std::uint32_t;
inline constexpr ModelId kNoModel = 0xffffffffu;

/// The models of a scene and their transform hierarchy.
class ModelHierarchy {
 public:
  /// Adds a model with a shared mesh, a transform relative to `parent` (kNoModel: the world).
  /// Throws InvalidInput for a null mesh, an unknown parent or an invalid transform
  /// (validate(Transform)); the rotation is stored normalised. A new model is not reported by
  /// takeMoved (its caller knows it exists). Reuses the most recently freed id, if any.
  ModelId add(std::shared_ptr<const Mesh> mesh, const Transform& local = {}, ModelId parent = kNoModel);
  /// Removes a model; its children move to its parent keeping their world transforms (their
  /// cached world transforms are kept as they are; their local transforms are recomputed).
  /// Throws InvalidInput for an unknown id.
  void remove(ModelId id);
  /// Sets the local transform (relative to the parent) and recomputes the world transforms of
  /// the model and all its descendants (O(subtree)); they are reported by the next takeMoved.
  /// Throws InvalidInput for an unknown id or an invalid transform.
  void setLocal(ModelId id, const Transform& local);
  /// Re-parents a model keeping its world pose (its local transform is recomputed; its cached
  /// world transform and those of its descendants stay as they were, so nothing is reported
  /// by takeMoved); kNoModel detaches it. Throws InvalidInput when `parent` is the model itself
  /// or one of its descendants (a cycle), or for an unknown id.
  void setParent(ModelId id, ModelId parent);

  /// Whether `id` names a live model.
  bool contains(ModelId id) const;
  /// The local transform (relative to the parent). Throws InvalidInput for an unknown id (as
  /// do all accessors below).
  const Transform& local(ModelId id) const;
  /// The parent, or kNoModel for a root.
  ModelId parent(ModelId id) const;
  const std::shared_ptr<const Mesh>& mesh(ModelId id) const;
  /// How many times `id` has been freed: (id, generation) names one model for its lifetime,
  /// so holders of ids can detect reuse.
  std::uint32_t generation(ModelId id) const;
  /// World transform (kept up to date by every mutation; reading it never writes). The
  /// reference stays valid until the next add().
  const Transform& world(ModelId id) const;
  /// The model's mesh placed in the world.
  PlacedMesh placed(ModelId id) const;
  /// Every descendant (all levels), ascending ids.
  std::vector<ModelId> descendants(ModelId id) const;
  /// Direct children, ascending ids.
  std::vector<ModelId> children(ModelId id) const;
  /// Ids of all live models, ascending.
  std::vector<ModelId> ids() const;
  /// Number of live models.
  std::size_t size() const { return size_; }
  /// Models whose world transform changed since the last call (setLocal on themselves or on an
  /// ancestor), deduplicated, ascending; clears the set. Removed models are not reported. The
  /// scene uses it to update its broad phase.
  std::vector<ModelId> takeMoved();
  /// Kept for callers that prepared a hierarchy for concurrent reads: world transforms are now
  /// always current, so there is nothing to do (O(1)); const members are thread-safe without it.
  void refreshWorld() {}

 private:
  void require(ModelId id, const char* what) const;
  void link(ModelId id, ModelId parent);
  void unlink(ModelId id);
  void markMovedAndUpdateWorld(ModelId root);
  bool isAncestorOrSelf(ModelId ancestor, ModelId id) const;

  // One slot per id; slots of removed models are on free_ (alive_ == 0).
  std::vector<std::shared_ptr<const Mesh>> mesh_;
  std::vector<Transform> local_;
  std::vector<Transform> world_;  ///< current world transform of every live model
  std::vector<ModelId> parent_;
  std::vector<ModelId> firstChild_;
  std::vector<ModelId> nextSibling_;
  std::vector<ModelId> prevSibling_;
  /// Reported by the next takeMoved.
  std::vector<std::uint8_t> moved_;
  std::vector<std::uint8_t> alive_;
  std::vector<std::uint32_t> generation_;
  std::vector<ModelId> free_;       ///< freed ids, most recent last
  std::vector<ModelId> movedList_;  ///< ids whose moved_ flag was set (may repeat or be stale)
  std::size_t size_ = 0;
};

}  // namespace crux
