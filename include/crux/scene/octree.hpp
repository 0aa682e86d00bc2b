#pragma once
/// @file octree.hpp  A loose octree broad phase that grows instead of dropping boxes.
///
/// The book's octree (fixed depth, fixed root cube) silently dropped models outside the root,
/// returned a model once per leaf it touched and was never updated on add/remove/move. This one
/// fixes all three: the root grows (doubles towards the new box) until it contains every box;
/// each box is stored in exactly one node, so queries return it once; insert/remove/update keep
/// the tree in sync and free empty nodes.
///
/// Loose octree (Ulrich, "Loose Octrees", Game Programming Gems 1, 2000): a node's loose bounds
/// are its cell grown by half the cell size on every side (twice the cell's extent). A box whose
/// largest half-extent is at most a quarter of the cell fits the loose bounds of the child cell
/// containing its centre, so a box's depth depends only on its size, and straddling a cell
/// boundary never forces it up to the root or into several nodes.

#include <crux/scene/broad_phase.hpp>

#include <cstdint>
#include <vector>

namespace crux {

/// Loose octree over boxes. Nodes live in one flat array with a free list; the boxes of a node
/// form an intrusive doubly-linked list through the per-id entries.
class Octree final : public BroadPhase {
 public:
  /// Deepest level of any node (root = 0). Boxes are placed at most 24 levels below the root
  /// (points stop there); growing the root pushes existing nodes deeper, and when that would
  /// exceed kMaxDepth the tree is rebuilt under the grown root. Bounds the traversal stacks.
  static constexpr int kMaxDepth = 32;

  Octree() = default;

  BroadPhaseKind kind() const override { return BroadPhaseKind::Octree; }
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
  /// Each box queried against the tree, pairs reported from the smaller id (O(n log n + k)).
  void pairs(PairCollector& collector) override;

  /// Live nodes (for tests and statistics).
  std::size_t nodeCount() const { return nodes_.size() - freeNodes_.size(); }
  /// Levels below the root of the deepest node ever made since the last rebuild (an upper bound).
  int depth() const { return depth_; }
  /// The root cell (not its loose bounds); the empty box when the tree is empty.
  Aabb rootCell() const;
  /// How many times growth forced a rebuild (for tests).
  std::size_t rebuilds() const { return rebuilds_; }
  /// The depth of the node that holds `id` (root = 0). Precondition: contains(id).
  int depthOf(ProxyId id) const;

 private:
  static constexpr std::uint32_t kNone = 0xffffffffu;

  struct Node {
    Vec3 center = Vec3::Zero();
    Real half = 0;                 // half the cell's edge; loose bounds are center ± 2·half
    std::uint32_t parent = kNone;
    std::uint32_t child[8] = {kNone, kNone, kNone, kNone, kNone, kNone, kNone, kNone};
    std::uint32_t first = kNone;   // first entry of this node's list
    std::uint32_t count = 0;       // boxes in this node's subtree
  };
  struct Entry {
    Aabb box;
    std::uint32_t node = kNone;    // kNone: id not present
    std::uint32_t prev = kNone, next = kNone;
  };

  template <class NodeTest, class LeafTest>
  bool traverse(const NodeTest& nodeTest, const LeafTest& leafTest, ProxyCollector& collector) const;

  Aabb looseBounds(const Node& n) const;
  bool fits(const Aabb& box, const Node& n) const;
  std::uint32_t allocNode(const Vec3& center, Real half, std::uint32_t parent);
  void freeNode(std::uint32_t index);
  void growToContain(const Aabb& box);
  void place(ProxyId id);        // inserts entries_[id].box below the root
  void unlink(ProxyId id);       // removes id from its node, frees emptied nodes
  void rebuild();

  std::vector<Node> nodes_;
  std::vector<std::uint32_t> freeNodes_;
  std::vector<Entry> entries_;   // by id
  std::uint32_t root_ = kNone;
  std::size_t size_ = 0;
  int depth_ = 0;
  std::size_t rebuilds_ = 0;
};

}  // namespace crux
