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
