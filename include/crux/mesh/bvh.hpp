#pragma once
/// @file bvh.hpp  A bounding-volume hierarchy over boxes: flat, index-linked, built by binned SAH.
///
/// Generic over primitives (it sees only their bounds), so meshes use it over triangles and
/// other layers may use it over anything with a box. The builder is separate from traversal;
/// traversal is one function template parameterised by a node test and a leaf visitor.

#include <crux/geometry/shapes.hpp>

#include <cstdint>
#include <limits>
#include <type_traits>
#include <utility>
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
  std::uint32_t bins = 16;        ///< SAH bins per axis at most (a node of n: min(bins, n, 4 + n/20), >= 2)
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
/// within maxLeafSize. Node bounds are fitted to their contents. An axis whose centroids lie
/// farther apart than the largest Real is not binned, and a node with no split of finite cost
/// (or too deep for SAH, kBvhMaxDepth) is a leaf within maxLeafSize and else halved by count.
/// Throws InvalidInput for bad options, too many primitives, or a primitive whose bounds are
/// not finite or are empty (naming it).
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
///       the traversal;
///   or, instead of slot, `bool leaf(std::uint32_t first, std::uint32_t count)` — visits a
///       leaf's slots [first, first + count) together (e.g. tested in SIMD lanes).
/// Returns false when the visitor stopped it early.
template <class Visitor>
bool traverseBvhSlots(const Bvh& bvh, Visitor& visitor);

namespace bvh_detail {
template <class V, class = void>
struct HasLeaf : std::false_type {};
template <class V>
struct HasLeaf<V, std::void_t<decltype(std::declval<V&>().leaf(std::uint32_t(), std::uint32_t()))>> : std::true_type {};
}  // namespace bvh_detail

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
      if constexpr (bvh_detail::HasLeaf<Visitor>::value) {
        if (!visitor.leaf(node.first, node.count)) return false;
      } else {
        for (std::uint32_t k = node.first, e = node.first + node.count; k < e; ++k)
          if (!visitor.slot(k)) return false;
      }
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
/// "Getting Rid of Packets", RT 2008): a node's lanes are its binary node's children, then,
/// while fewer than four, the inner lane of largest surface area replaced in place by its two
/// children (2-4 lanes; the leaves keep the binary tree's left-to-right order). The lanes' boxes are stored by
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
  /// Lane i's box.
  Aabb laneBounds(int i) const { return {Vec3(minX[i], minY[i], minZ[i]), Vec3(maxX[i], maxY[i], maxZ[i])}; }
  /// Whether lane i is used.
  bool used(int i) const { return child[i] != kEmpty; }
};

/// A flat 4-wide BVH; node 0 is the root (absent for an empty BVH). A leaf lane covers slots
/// [child, child + count) of primIndices, the binary BVH's it was collapsed from, so each
/// primitive is referenced exactly once and slot-ordered data (Mesh::slotTriangle) serves both.
/// The tree of every Mesh (Mesh::bvh).
struct WideBvh {
  std::vector<WideBvhNode> nodes;
  std::vector<std::uint32_t> primIndices;
  bool empty() const { return nodes.empty(); }
  std::size_t memoryBytes() const {
    return nodes.capacity() * sizeof(WideBvhNode) + primIndices.capacity() * sizeof(std::uint32_t);
  }
};

/// Subtrees of a WideBvh by number, for traversals that hold subtrees rather than nodes (the
/// simultaneous descent of two trees, per-subtree side data such as MeshDistanceAccel's boxes):
/// 0 is the whole tree, 4n + i + 1 is lane i of node n. A subtree is a leaf (slots [first,
/// first + count) of primIndices, count > 0) or inner (its lanes are node `first`'s).
struct WideSubtree {
  std::uint32_t first = 0, count = 0;
  bool isLeaf() const { return count != 0; }
};
/// Number of subtree ids of a WideBvh with `nodes` nodes (0 .. 4·nodes).
inline std::size_t wideSubtreeCount(std::size_t nodes) { return 4 * nodes + 1; }
/// The id of lane i of node n.
inline std::uint32_t wideLaneId(std::uint32_t node, int lane) { return 4 * node + std::uint32_t(lane) + 1; }
/// Subtree `id` of a non-empty WideBvh (its lane must be used).
inline WideSubtree wideSubtree(const WideBvh& bvh, std::uint32_t id) {
  if (id == 0) return {0, 0};
  const WideBvhNode& n = bvh.nodes[(id - 1) >> 2];
  return {n.child[(id - 1) & 3], n.count[(id - 1) & 3]};
}
/// The root's box: the union of node 0's lanes (out of line: wideSubtreeBounds's rare case).
Aabb wideRootBounds(const WideBvh& bvh);
/// The box of subtree `id` (the root's: the union of node 0's lanes). Inline: the mesh pair
/// descents ask it for every pair they bound.
inline Aabb wideSubtreeBounds(const WideBvh& bvh, std::uint32_t id) {
  if (id == 0) return wideRootBounds(bvh);
  return bvh.nodes[(id - 1) >> 2].laneBounds(int((id - 1) & 3));
}

/// Entries of a wide traversal's fixed stack: the wide tree is at most kBvhMaxDepth + 1 deep
/// (each level descends at least one binary level), each node pops one entry and pushes at most
/// four, and a branch-free push writes all four lanes past the top.
inline constexpr int kWideBvhStackSize = 3 * (kBvhMaxDepth + 2) + 4;

/// Collapses a binary BVH into a WideBvh (O(nodes)); primIndices are copied.
WideBvh widenBvh(const Bvh& bvh);

/// Builds a WideBvh: buildBvh, then widenBvh (the binary tree is a build step only).
WideBvh buildWideBvh(const std::vector<Aabb>& primBounds, const BvhBuildOptions& options = {});

/// Refits a WideBvh in place, same topology, to new primitive bounds: slotBox(k) is the box of
/// the primitive in leaf slot k (so a mesh reads its slot-ordered triangles, no index gather).
/// One reverse sweep (children follow their parents in widenBvh's order): a leaf lane is the
/// union of its slots' boxes, an inner lane the union of its node's lanes. No allocation.
template <class SlotBox>
void refitWideBvhSlots(WideBvh& bvh, const SlotBox& slotBox) {
  for (std::size_t n = bvh.nodes.size(); n-- > 0;) {
    WideBvhNode& node = bvh.nodes[n];
    for (int i = 0; i < 4; ++i) {
      if (node.child[i] == WideBvhNode::kEmpty) continue;
      Aabb box = Aabb::empty();
      if (node.count[i] > 0) {
        for (std::uint32_t k = node.child[i], e = node.child[i] + node.count[i]; k < e; ++k) box.grow(slotBox(k));
      } else {
        const WideBvhNode& c = bvh.nodes[node.child[i]];
        for (int j = 0; j < 4; ++j)
          if (c.used(j)) box.grow(c.laneBounds(j));
      }
      node.minX[i] = box.min.x(), node.minY[i] = box.min.y(), node.minZ[i] = box.min.z();
      node.maxX[i] = box.max.x(), node.maxY[i] = box.max.y(), node.maxZ[i] = box.max.z();
    }
  }
}


namespace detail {
template <class V, class = void>
struct HasLeafSlots : std::false_type {};
template <class V>
struct HasLeafSlots<V, std::void_t<decltype(std::declval<V&>().leaf(std::uint32_t(), std::uint32_t()))>>
    : std::true_type {};
}  // namespace detail

/// Depth-first traversal of a WideBvh, visiting the leaves in the order traverseBvhSlots visits
/// the binary BVH's with equal keys (lanes in order, each lane's subtree before the next lane).
/// Visitor:
///   `unsigned enter(const WideBvhNode& node)` — bit i set: enter lane i (unused lanes must be
///       left out; their empty boxes make an overlap test reject them);
///   `bool slot(std::uint32_t k)` — as traverseBvhSlots'; false stops the traversal; or
///   `bool leaf(std::uint32_t first, std::uint32_t count)` — the slots of one leaf together (so
///       their triangles can be tested in SIMD lanes), in place of slot(); false stops it.
/// A lane is tested without its binary parent's box (the parent is skipped), so the test must be
/// monotone (a box inside a rejected box is rejected), as separating-axis and distance tests are.
/// Returns false when the visitor stopped it early.
template <class Visitor>
bool traverseWideBvhSlots(const WideBvh& bvh, Visitor& visitor) {
  if (bvh.nodes.empty()) return true;
  struct Entry {
    std::uint32_t child, count;
  };
  Entry stack[kWideBvhStackSize];
  int top = 0;
  stack[top++] = {0, 0};
  while (top > 0) {
    const Entry e = stack[--top];
    if (e.count > 0) {
      if constexpr (detail::HasLeafSlots<Visitor>::value) {
        if (!visitor.leaf(e.child, e.count)) return false;
      } else {
        for (std::uint32_t k = e.child, end = e.child + e.count; k < end; ++k)
          if (!visitor.slot(k)) return false;
      }
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

/// Nearest-first traversal of a WideBvh for queries with a distance order (rays, segments): the
/// lanes a node's test enters are visited in increasing key, deferred lanes are dropped when
/// popped with a key the visitor no longer keeps (the best hit so far moved closer). Visitor:
///   `unsigned enter(const WideBvhNode& node, Real (&keys)[4])` — bit i set: enter lane i,
///       whose key (e.g. the ray's entry parameter) is keys[i] (unused lanes must be left out);
///   `bool keep(Real key)` — whether a deferred lane with this key still matters;
///   `bool leaf(std::uint32_t first, std::uint32_t count, Real key)` — visits the slots [first,
///       first + count) of a leaf together (so their triangles can be tested in SIMD lanes),
///       entered with the lane's key; false stops the traversal.
/// The root node is always entered (its key is −∞, so even a visitor whose limit is negative,
/// as signed distances may be, keeps it). Lanes with equal keys are visited in lane order. The
/// same monotonicity rule as
/// traverseWideBvhSlots holds. Returns false when the visitor stopped it early.
template <class Visitor>
bool traverseWideBvhOrdered(const WideBvh& bvh, Visitor& visitor) {
  if (bvh.nodes.empty()) return true;
  struct Entry {
    std::uint32_t child, count;
    Real key;
  };
  Entry stack[kWideBvhStackSize];
  int top = 0;
  Entry e = {0, 0, -std::numeric_limits<Real>::infinity()};  // the root: kept by every visitor
  for (;;) {
    // `e` is the next subtree in visiting order: the nearest lane of the node just tested goes
    // straight here (the same order as pushing it last and popping it next, with one stack
    // round trip fewer), the others wait on the stack.
    if (visitor.keep(e.key)) {
      if (e.count > 0) {
        if (!visitor.leaf(e.child, e.count, e.key)) return false;
      } else {
        const WideBvhNode& node = bvh.nodes[e.child];
        Real keys[4];
        unsigned hits = visitor.enter(node, keys) & 15u;
        if (hits != 0) {
          int i = __builtin_ctz(hits);
          hits &= hits - 1;
          if (hits == 0) {  // one lane entered (the common case)
            e = {node.child[i], node.count[i], keys[i]};
            continue;
          }
          const int i1 = __builtin_ctz(hits);
          if ((hits & (hits - 1)) == 0) {  // two lanes (the next most common): the nearer goes on
            const bool secondFirst = keys[i1] < keys[i];  // (equal keys: lane order)
            const int nearLane = secondFirst ? i1 : i, farLane = secondFirst ? i : i1;
            stack[top++] = {node.child[farLane], node.count[farLane], keys[farLane]};
            e = {node.child[nearLane], node.count[nearLane], keys[nearLane]};
            continue;
          }
          // Entered lanes sorted by key (insertion sort of at most four, stable: equal keys keep
          // lane order); all but the nearest pushed farthest first.
          int order[4] = {i, 0, 0, 0}, n = 1;
          while (hits) {
            i = __builtin_ctz(hits);
            hits &= hits - 1;
            int j = n++;
            for (; j > 0 && keys[order[j - 1]] > keys[i]; --j) order[j] = order[j - 1];
            order[j] = i;
          }
          for (int j = n - 1; j > 0; --j) stack[top++] = {node.child[order[j]], node.count[order[j]], keys[order[j]]};
          e = {node.child[order[0]], node.count[order[0]], keys[order[0]]};
          continue;
        }
      }
    }
    if (top == 0) break;
    e = stack[--top];
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
