#pragma once
/// @file bvh.hpp  A bounding-volume hierarchy over boxes: flat, index-linked, built by binned SAH.
///
/// Generic over primitives (it sees only their bounds), so meshes use it over triangles and
/// other layers may use it over anything with a box. The builder is separate from traversal;
/// traversal is one function template parameterised by a node test and a leaf visitor.

#include <crux/geometry/shapes.hpp>

#include <cstdint>
#include <vector>

namespace crux {

/// A BVH node (32 bytes in float builds). A leaf has count > 0 and covers
/// primIndices[first, first + count); an inner node has count == 0 and children `first` and
/// `first + 1` (siblings are adjacent, so one index links both).
struct BvhNode {
  Aabb bounds;
  std::uint32_t first = 0;
  std::uint32_t count = 0;
  bool isLeaf() const { return count != 0; }
};

/// Build parameters.
struct BvhBuildOptions {
  std::uint32_t maxLeafSize = 4;  ///< leaf size cap (a leaf never holds more)
  std::uint32_t bins = 16;        ///< SAH bins per axis
  Real traversalCost = 2;         ///< SAH cost of visiting a node, relative to one primitive test
};

/// A flat BVH: node 0 is the root (absent for zero primitives); each primitive is referenced
/// exactly once in primIndices. buildBvh places children after their parent (larger index), so
/// a reverse sweep of `nodes` visits every child before its parent (refitBvh relies on it).
struct Bvh {
  std::vector<BvhNode> nodes;
  std::vector<std::uint32_t> primIndices;

  bool empty() const { return nodes.empty(); }
  std::size_t memoryBytes() const {
    return nodes.capacity() * sizeof(BvhNode) + primIndices.capacity() * sizeof(std::uint32_t);
  }
};

/// Builds a BVH over primitives with the given bounds, top-down with the binned surface-area
/// heuristic (Wald, "On fast Construction of SAH-based Bounding Volume Hierarchies", 2007),
/// splitting on centroids; leaves are made when SAH finds no cheaper split and the count is
/// within maxLeafSize. Node bounds are fitted to their contents.
Bvh buildBvh(const std::vector<Aabb>& primBounds, const BvhBuildOptions& options = {});

/// Refits every node's bounds bottom-up to new primitive bounds (same primitive count and
/// topology), e.g. after a deforming mesh moved its vertices. O(nodes), no rebuild.
void refitBvh(Bvh& bvh, const std::vector<Aabb>& primBounds);

/// Deepest tree buildBvh makes (it falls back to balanced median splits below this depth),
/// so traversal stacks of kBvhMaxDepth + 1 entries never overflow.
inline constexpr int kBvhMaxDepth = 96;

/// The one BVH traversal: depth-first with an explicit fixed stack, visiting the nearer child
/// first. Parameterised by a visitor with
///   `bool enter(const BvhNode& node, Real& key)` — false prunes the subtree; `key` orders
///       siblings (smaller first) and is re-checked when a deferred sibling is popped;
///   `bool keep(Real key)` — whether a deferred subtree with this key still matters (e.g.
///       key <= best hit so far); return true for plain overlap queries;
///   `bool slot(std::uint32_t k)` — visits the primitive in slot k of a leaf (the primitive
///       bvh.primIndices[k]; slots let callers read data stored in leaf order); false stops
///       the traversal.
/// Returns false when the visitor stopped it early.
template <class Visitor>
bool traverseBvhSlots(const Bvh& bvh, Visitor& visitor) {
  if (bvh.nodes.empty()) return true;
  Real rootKey = 0;
  if (!visitor.enter(bvh.nodes[0], rootKey)) return true;
  struct Entry {
    std::uint32_t node;
    Real key;
  };
  Entry stack[kBvhMaxDepth + 1];
  int top = 0;
  std::uint32_t current = 0;
  for (;;) {
    const BvhNode& node = bvh.nodes[current];
    if (node.isLeaf()) {
      for (std::uint32_t k = node.first, e = node.first + node.count; k < e; ++k)
        if (!visitor.slot(k)) return false;
    } else {
      const std::uint32_t l = node.first, r = node.first + 1;
      Real kl = 0, kr = 0;
      const bool el = visitor.enter(bvh.nodes[l], kl);
      const bool er = visitor.enter(bvh.nodes[r], kr);
      if (el && er) {
        const bool leftFirst = kl <= kr;
        current = leftFirst ? l : r;
        stack[top++] = leftFirst ? Entry{r, kr} : Entry{l, kl};
        continue;
      }
      if (el || er) {
        current = el ? l : r;
        continue;
      }
    }
    for (;;) {
      if (top == 0) return true;
      const Entry e = stack[--top];
      if (visitor.keep(e.key)) {
        current = e.node;
        break;
      }
    }
  }
}

/// A 4-wide BVH collapsed from a binary one (Dammertz, Hanika & Keller, "Shallow Bounding Volume
/// Hierarchies for Fast SIMD Ray Tracing of Incoherent Rays", EGSR 2008; Wald, Benthin & Boulos,
/// "Getting Rid of Packets", RT 2008): a node's lanes are its binary node's children, each inner
/// child replaced by its own two children, in order (2-4 lanes). The lanes' boxes are stored by
/// coordinate, so one SIMD test checks all four. Leaves are the binary BVH's (slots [first,
/// first + count) of its primIndices).
struct alignas(64) WideBvhNode {
  static constexpr std::uint32_t kEmpty = 0xffffffffu;
  /// Lane boxes by coordinate: minX[i] .. maxZ[i] is lane i's box; an unused lane holds the empty
  /// box (min +inf, max -inf), which every overlap test rejects.
  Real minX[4], minY[4], minZ[4], maxX[4], maxY[4], maxZ[4];
  /// Lane i: a wide node's index (count[i] == 0), a leaf's first slot (count[i] > 0), or kEmpty.
  std::uint32_t child[4];
  std::uint32_t count[4];
};

/// A flat 4-wide BVH; node 0 is the root (absent for an empty BVH). Leaf slots are the binary
/// BVH's, so slot-ordered data (Mesh::slotTriangle) serves both.
struct WideBvh {
  std::vector<WideBvhNode> nodes;
  bool empty() const { return nodes.empty(); }
  std::size_t memoryBytes() const { return nodes.capacity() * sizeof(WideBvhNode); }
};

/// Collapses a binary BVH into a WideBvh (O(nodes)); rebuild it after refitBvh.
WideBvh widenBvh(const Bvh& bvh);

/// Depth-first traversal of a WideBvh, visiting the leaves in the order traverseBvhSlots visits
/// the binary BVH's with equal keys (lanes in order, each lane's subtree before the next lane).
/// Visitor:
///   `unsigned enter(const WideBvhNode& node)` — bit i set: enter lane i (unused lanes must be
///       left out; their empty boxes make an overlap test reject them);
///   `bool slot(std::uint32_t k)` — as traverseBvhSlots'; false stops the traversal.
/// A lane is tested without its binary parent's box (the parent is skipped), so the test must be
/// monotone (a box inside a rejected box is rejected), as separating-axis and distance tests are.
/// Returns false when the visitor stopped it early.
template <class Visitor>
bool traverseWideBvhSlots(const WideBvh& bvh, Visitor& visitor) {
  if (bvh.nodes.empty()) return true;
  struct Entry {
    std::uint32_t child, count;
  };
  // each node pushes at most 4 entries and pops 1; the wide tree is at most
  // (kBvhMaxDepth + 1) / 2 + 1 deep
  Entry stack[4 * (kBvhMaxDepth / 2 + 2) + 1];  // (+1: a lane not entered is written past the top)
  int top = 0;
  stack[top++] = {0, 0};
  while (top > 0) {
    const Entry e = stack[--top];
    if (e.count > 0) {
      for (std::uint32_t k = e.child, end = e.child + e.count; k < end; ++k)
        if (!visitor.slot(k)) return false;
      continue;
    }
    const WideBvhNode& node = bvh.nodes[e.child];
    const unsigned hits = visitor.enter(node) & 15u;
    // pushed last lane first, so lane 0 is popped first; without branches (every lane is
    // written, the stack top moves past the entered ones: the branches were mispredicted)
    for (int i = 3; i >= 0; --i) {
      stack[top] = {node.child[i], node.count[i]};
      top += int(hits >> i & 1u);
    }
  }
  return true;
}

/// traverseBvhSlots with a visitor that sees primitive indices instead of slots:
/// `bool leaf(std::uint32_t prim)` in place of `slot`.
template <class Visitor>
bool traverseBvh(const Bvh& bvh, Visitor& visitor) {
  struct Slots {
    const Bvh& bvh;
    Visitor& v;
    bool enter(const BvhNode& node, Real& key) { return v.enter(node, key); }
    bool keep(Real key) { return v.keep(key); }
    bool slot(std::uint32_t k) { return v.leaf(bvh.primIndices[k]); }
  } slots{bvh, visitor};
  return traverseBvhSlots(bvh, slots);
}

}  // namespace crux
