#pragma once
/// @file dynamic_aabb_tree.hpp  The default broad phase: a dynamic bounding-volume tree over
/// fattened boxes with incremental insert/remove/move and height-balancing rotations.
///
/// Ideas from Erin Catto's b2DynamicTree (Box2D) and Bullet's btDbvt, written afresh:
///  - Each box is stored in a leaf with a fat box (the box grown by a margin). Moving a box
///    inside its fat box costs nothing in the tree; leaving it re-inserts the leaf.
///  - Insertion descends towards the sibling that increases the surface area least (the
///    greedy SAH cost of Goldsmith & Salmon 1987), then walks up refitting and applying at each
///    ancestor the tree rotation (a child swapped with a grandchild) that most reduces the
///    surface area, if any (Kopta et al., "Fast, Effective BVH Updates for Animated Scenes",
///    I3D 2012). Removal refits and rotates the same way.
///  - Should the height ever exceed kRebuildHeight (adversarial inputs such as many nested
///    boxes), the tree is rebuilt top-down by median splits (height ceil(log2 n)); so the height
///    never exceeds kRebuildHeight and traversals use a fixed stack of that depth.
///  - Nodes live in one flat array with a free list; children are indices.
///  - pairs() keeps a persistent, sorted cache of fat-box pairs: only boxes whose fat box
///    changed since the previous call are queried against the tree, the cache is merged in one
///    linear pass, and only pairs with a moved member re-test their exact boxes.
/// Queries test fat boxes on the way down and the exact boxes at the leaves, so every answer
/// is the same as BruteForceBroadPhase's.
///
/// Rays have a second, read-only tree. An incrementally built binary tree suits moving boxes and
/// pairs, but a ray walks it one scalar slab test per node. So once enough rays have been cast
/// since the last change (DynamicAabbTreeOptions::rayTreeRaysPerBox), raycast builds a 4-wide
/// SAH tree over the exact boxes (buildWideBvh, the meshes' builder) and walks it nearest first
/// with rayBoxEntry evaluated on four lanes at once (the same operations per lane, so a lane is
/// entered exactly when rayBoxEntry enters its box, and the answers are unchanged). Any insert,
/// remove, update or clear drops it. The build is amortised: it costs about as much as the rays
/// already cast through the binary tree since the change, so a scene that moves every frame and
/// casts few rays pays at most twice what it paid before. The first raycast to reach the threshold builds it under a
/// mutex (other threads wait), so const queries stay safe from many threads.

#include <crux/mesh/bvh.hpp>
#include <crux/scene/broad_phase.hpp>

#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

namespace crux {

/// Parameters of the dynamic tree.
struct DynamicAabbTreeOptions {
  /// Fat boxes are the exact box grown on every side by this fraction of its largest extent
  /// (relative, so the tree behaves the same at every scale; a zero-size box gets no margin).
  Real marginFraction = Real(0.1);
  /// When a moved box leaves its fat box, the new fat box is also stretched in the direction
  /// of the move by this multiple of the displacement of the box's centre (predictive
  /// fattening, as Box2D's aabbMultiplier): steadily moving boxes re-insert less often.
  Real displacementMultiplier = Real(2);
  /// raycast builds its wide ray tree (see the file comment) once this many rays per box have
  /// been cast since the last change: 0 builds it at the first ray, +inf never. The default,
  /// 1/8, spends on rays through the binary tree about what the build costs (measured on
  /// bench_scene's 10k models: ~3,300 instructions per box to build, ~20,000 per ray).
  Real rayTreeRaysPerBox = Real(1) / 8;
};

/// Dynamic AABB tree (see the file comment).
class DynamicAabbTree final : public BroadPhase {
 public:
  explicit DynamicAabbTree(const DynamicAabbTreeOptions& options = {});

  BroadPhaseKind kind() const override { return BroadPhaseKind::DynamicAabbTree; }
  void insert(ProxyId id, const Aabb& box) override;
  void remove(ProxyId id) override;
  void update(ProxyId id, const Aabb& box) override;
  void clear() override;
  bool contains(ProxyId id) const override;
  const Aabb& bounds(ProxyId id) const override;
  std::size_t size() const override { return size_; }

  bool query(const Aabb& box, ProxyCollector& collector) const override;
  bool query(const Sphere& sphere, ProxyCollector& collector) const override;
  bool query(const Obb& box, ProxyCollector& collector) const override;
  bool raycast(const Ray& ray, RayProxyCollector& collector) const override;
  /// Reports pairs in ascending (a, b) order.
  void pairs(PairCollector& collector) override;

  /// The fat box of `id`'s leaf. Precondition: contains(id).
  const Aabb& fatBounds(ProxyId id) const;
  /// Height of the tree (a single leaf: 0; empty: -1).
  int height() const;
  /// Live nodes (leaves and inner nodes).
  std::size_t nodeCount() const { return nodes_.size() - freeCount_; }
  /// Pairs in the persistent fat-box pair cache after the last pairs() call.
  std::size_t cachedPairs() const { return pairKeys_.size(); }
  /// Leaves re-inserted because their box left the fat box, since construction.
  std::size_t reinsertions() const { return reinsertions_; }
  /// Top-down rebuilds forced by the height guard, since construction.
  std::size_t rebuilds() const { return rebuilds_; }
  /// Builds the wide ray tree now unless it is current (e.g. once a static scene is loaded,
  /// rather than after rayTreeRaysPerBox × size() rays). Const and safe beside other const
  /// queries, as the lazy build is.
  void prepareRays() const;
  /// Builds of the wide ray tree, since construction.
  std::size_t rayTreeBuilds() const { return rayTreeBuilds_.load(std::memory_order_relaxed); }
  /// Whether the wide ray tree is current (the next raycast walks it).
  bool hasRayTree() const { return rayTreeReady_.load(std::memory_order_acquire); }
  /// Sum of the surface areas of the inner nodes (the SAH cost up to constant factors).
  double innerArea() const;
  /// Checks every structural invariant (parent/child links, heights within kRebuildHeight,
  /// node boxes containing their children, fat boxes containing exact boxes, the id -> leaf
  /// map, the free list); returns "" when all hold, else the first violation. For tests.
  std::string checkInvariants() const;

  /// A tree higher than this after an insertion or removal is rebuilt top-down.
  static constexpr int kRebuildHeight = 100;

 private:
  static constexpr std::uint32_t kNull = 0xffffffffu;
  /// Traversal stack size: a depth-first traversal needs height + 1 entries, and the height
  /// never exceeds kRebuildHeight.
  static constexpr int kStackSize = kRebuildHeight + 2;

  struct Node {
    Aabb box;                      // fat box (leaf) or union of the children's boxes
    std::uint32_t parent = kNull;  // next free node while on the free list
    std::uint32_t child1 = kNull;  // kNull for a leaf
    std::uint32_t child2 = kNull;
    std::int32_t height = 0;       // leaf 0; -1 while free
    ProxyId id = 0;                // leaf only
    bool isLeaf() const { return child1 == kNull; }
  };
  /// Per id: its leaf and its exact box.
  struct Entry {
    Aabb box;
    std::uint32_t leaf = kNull;    // kNull: id not present
  };
  // Change flags per id for the pair cache (a separate byte array: the merge reads it per pair).
  static constexpr std::uint8_t kFatChanged = 1;    // inserted, re-inserted or removed since pairs()
  static constexpr std::uint8_t kBoxChanged = 2;    // exact box changed since pairs()

  /// Depth-first over the nodes whose box passes nodeTest; visit(leafNode) returns false to stop.
  template <class NodeTest, class Visit>
  bool traverse(const NodeTest& nodeTest, const Visit& visit) const;
  template <class Region>
  bool queryRegion(const Region& region, ProxyCollector& collector) const;

  Aabb fatten(const Aabb& box) const;
  std::uint32_t allocNode();
  void freeNode(std::uint32_t index);
  void insertLeaf(std::uint32_t leaf);
  void removeLeaf(std::uint32_t leaf);
  void rotate(std::uint32_t index);
  void refitUpwards(std::uint32_t index);
  void rebuild();
  void markChanged(ProxyId id, std::uint8_t flag);
  void dropRayTree();
  void buildRayTree() const;
  bool raycastWide(const Ray& ray, RayProxyCollector& collector) const;

  DynamicAabbTreeOptions options_;
  std::vector<Node> nodes_;
  std::uint32_t root_ = kNull;
  std::uint32_t freeList_ = kNull;
  std::size_t freeCount_ = 0;
  std::vector<Entry> entries_;     // by id
  std::vector<std::uint8_t> flags_;  // by id
  std::size_t size_ = 0;
  std::size_t reinsertions_ = 0;
  std::size_t rebuilds_ = 0;

  // Persistent pair cache (see pairs()).
  std::vector<ProxyId> changed_;               // ids with flags set since the last pairs()
  std::vector<std::uint64_t> pairKeys_;        // sorted (a << 32 | b), a < b: fat boxes overlap
  std::vector<std::uint8_t> pairOverlap_;      // per key: exact boxes overlap
  std::vector<std::uint64_t> newKeys_, mergedKeys_;  // scratch, kept to avoid reallocation
  std::vector<std::uint8_t> mergedOverlap_;

  // The wide ray tree (see the file comment): built by the first const raycast past the
  // threshold, under rayTreeMutex_; rayTreeReady_ publishes it. One box per leaf lane (the lane
  // is the box); slot-ordered ids, so a leaf reads its id without an index gather.
  mutable std::mutex rayTreeMutex_;
  mutable std::atomic<bool> rayTreeReady_{false};
  mutable std::atomic<std::size_t> raysSinceChange_{0};
  mutable WideBvh rayTree_;
  mutable std::vector<ProxyId> raySlotIds_;
  mutable std::atomic<std::size_t> rayTreeBuilds_{0};  // read by rayTreeBuilds() beside const queries
};

}  // namespace crux
