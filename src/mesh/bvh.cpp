/// @file bvh.cpp  Binned-SAH BVH construction (serial or parallel with oneTBB) and bottom-up refit.
///
/// Parallel build: when the calling task arena has more than one thread, the top of the tree
/// (nodes of at least kParallelSubtreeMin primitives) is split with the two children built as
/// parallel tasks (tbb::parallel_invoke) and the largest nodes are binned in parallel chunks;
/// the result is the serial build's array bit for bit (see Builder). A one-thread arena (e.g.
/// tbb::task_arena(1)) gives the plain serial build.
///
/// Layout: the builder appends both children of a node at the end of the node array when it
/// splits that node, so siblings are adjacent and every child has a larger index than its
/// parent. Refit therefore sweeps the array once in reverse (children before parents).
///
/// Depth bound: a node at depth d holding c primitives is split by SAH only while
/// d + ceil(log2 c) <= kBvhMaxDepth - 2; otherwise it is halved by count (median split). By
/// induction every node satisfies d + ceil(log2 c) <= kBvhMaxDepth - 1, so no leaf is deeper than
/// kBvhMaxDepth - 1 whatever the input (identical triangles, collinear points, exponentially
/// spaced clusters that make SAH peel off one primitive per level).

#include <crux/error.hpp>
#include <crux/mesh/bvh.hpp>

#include "build_array.hpp"
#include "bvh_build.hpp"
#include "lanes.hpp"
#include "tbb_policy.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <memory>
#include <string>

namespace crux {
namespace {

using detail::BuildArray;

/// Upper limit of BvhBuildOptions::bins.
constexpr std::uint32_t kMaxBins = 256;

/// Four-lane coordinates (x, y, z, 0) so box growth is two SIMD min/max operations (the mesh
/// layer's lane type, lanes.hpp).
using mesh_detail::Lanes;
using mesh_detail::lanesMax;
using mesh_detail::lanesMin;
using mesh_detail::lanesOf;
using mesh_detail::lanesSplat;
/// Four bin indices (x, y, z, unused).
using LaneIndex = std::int32_t __attribute__((vector_size(16)));

constexpr Real kInf = std::numeric_limits<Real>::infinity();

Vec3 vec(const Lanes& l) { return Vec3(l[0], l[1], l[2]); }

/// A box over lanes; the empty box has min = +inf, max = -inf.
struct LaneBox {
  Lanes min = lanesSplat(kInf);
  Lanes max = lanesSplat(-kInf);
  void grow(const Lanes& lo, const Lanes& hi) {
    min = lanesMin(min, lo);
    max = lanesMax(max, hi);
  }
  void grow(const LaneBox& b) { grow(b.min, b.max); }
  /// As an Aabb, with -0 coordinates made +0 (x + 0): min/max of +0 and -0 depend on operand
  /// order, and the parallel build merges bins in a different order than the serial one.
  Aabb aabb() const { return {vec(min + Real(0)), vec(max + Real(0))}; }
};

/// A primitive as the builder moves it around: its bounds in lanes, partitioned in place
/// together with its original index (a parallel array).
struct BuildPrim {
  Lanes min, max;
  /// The centroid, computed the same way everywhere (halves first: no overflow near the float
  /// limit).
  Lanes centroid() const { return min * Real(0.5) + max * Real(0.5); }
};

/// A SAH bin: the primitives' bounds and their count.
struct Bin {
  LaneBox bounds;
  std::uint32_t count = 0;
};

int ceilLog2(std::uint32_t c) { return c <= 1 ? 0 : 32 - __builtin_clz(c - 1); }

/// SAH cost measure of a non-empty box: its surface area, or for boxes of zero area (segments
/// and points, e.g. nodes over collinear degenerate triangles) the sum of its extents, so that
/// such nodes are still split where it shortens them instead of arbitrarily. Products are taken
/// in Wide so that areas times counts do not overflow.
Wide costMeasure(const LaneBox& b, bool useLength) {
  const Lanes e = b.max - b.min;
  const Wide x = e[0], y = e[1], z = e[2];
  if (useLength) return x + y + z;
  return 2 * (x * y + y * z + z * x);
}

/// Primitive counts from which the builder works in parallel (when the current task arena has
/// more than one thread): nodes with at least kParallelSubtreeMin primitives are split on the
/// calling task and their two children built as parallel tasks (smaller nodes are built whole,
/// serially, by one task); nodes with at least kParallelBinMin primitives are also binned in
/// parallel chunks of kParallelBinGrain.
constexpr std::uint32_t kParallelSubtreeMin = 4096;
constexpr std::uint32_t kParallelBinMin = 32768;
constexpr std::uint32_t kParallelBinGrain = 8192;

/// Per-task scratch of the builder, reused by every node the task splits.
struct Scratch {
  explicit Scratch(std::uint32_t bins) : bins(3 * std::size_t(bins)), rightCost(bins) {}
  std::vector<Bin> bins;        // 3 × options.bins
  std::vector<Wide> rightCost;  // options.bins
  std::vector<std::uint32_t> order, ids;  // median splits only
  std::vector<BuildPrim> prims;           // median splits only
};

/// The builder. Serial order (what `nodes` looks like): a node's two children are appended as a
/// pair when it is split, and the left child's whole subtree is split before the right child's
/// (a depth-first work stack). The parallel build reproduces that array exactly: it builds
/// subtrees independently (each into its own array, laid out by the same rule), then places
/// every subtree's pairs at the offset the serial build would have given them. Every split
/// decision depends only on the node's primitive range (binning is order-independent: min/max
/// and integer counts are exact in any order), and the in-place partitions of disjoint ranges
/// are the serial ones, so nodes and primIndices are identical bit for bit.
/// The builder's result: the binary tree's nodes in the builder's own array (build_array.hpp),
/// which buildBvh copies and buildWideBvh widens and drops.
struct BinaryTree {
  BuildArray<BvhNode> nodes;
  std::vector<std::uint32_t> primIndices;
};

class Builder {
 public:
  /// n primitives (n >= 1), primitive i's box boxOf(i).
  template <class BoxOf>
  Builder(std::uint32_t n, const BoxOf& boxOf, const BvhBuildOptions& options)
      : options_(options), parallel_(kTbbParallelAllowed && tbb::this_task_arena::max_concurrency() > 1), prims_(n) {
    tree_.nodes = BuildArray<BvhNode>(2 * std::size_t(n) - 1);
    tree_.primIndices.resize(n);
    for (std::uint32_t i = 0; i < n; ++i) {
      const Aabb box = boxOf(i);
      prims_.push_back(BuildPrim{lanesOf(box.min), lanesOf(box.max)});
      tree_.primIndices[i] = i;
    }
  }

  BinaryTree run() && {
    const auto n = static_cast<std::uint32_t>(prims_.size());
    LaneBox bounds, centroids;
    for (const BuildPrim& p : prims_) {
      bounds.grow(p.min, p.max);
      const Lanes c = p.centroid();
      centroids.grow(c, c);
    }
    BvhNode root;
    root.bounds = bounds.aabb();
    root.first = 0;
    root.count = n;
    if (!parallel_ || n < kParallelSubtreeMin) {
      Scratch scratch(options_.bins);
      buildSerial(root, 0, centroids, tree_.nodes, scratch);
      return std::move(tree_);
    }
    Subtree top;
    top.root = root;
    expand(top, 0, centroids);
    tree_.nodes.resizeForOverwrite(1 + 2 * top.pairs);  // place constructs every node
    place(top, 0, 1);
    return std::move(tree_);
  }

 private:
  /// A node whose bounds are set, waiting to be split or made a leaf.
  struct Work {
    std::uint32_t node;
    int depth;
    LaneBox centroids;
  };

  /// A chosen split: the left part's size and both parts' bounds and centroid bounds.
  struct Split {
    std::uint32_t leftCount = 0;  // 0: no split
    LaneBox left, right, leftCentroids, rightCentroids;
  };

  /// A subtree of the parallel build: either split by the parallel stage (left/right set) or
  /// built serially into `local` (local[0] is `root`, children indices local).
  struct Subtree {
    BvhNode root;
    std::unique_ptr<Subtree> left, right;
    std::vector<BvhNode> local;
    std::size_t pairs = 0;  // child pairs in the subtree
  };

  /// The serial build of the subtree under `root` into `nodes` (cleared; nodes[0] = root): the
  /// tree's own array, or a parallel subtree's `local` one.
  template <class Nodes>
  void buildSerial(const BvhNode& root, int depth, const LaneBox& centroids, Nodes& nodes, Scratch& scratch) {
    nodes.clear();
    nodes.push_back(root);
    std::vector<Work> work;
    work.reserve(2 * kBvhMaxDepth + 2);
    work.push_back({0, depth, centroids});
    while (!work.empty()) {
      const Work w = work.back();
      work.pop_back();
      process(w, nodes, work, scratch);
    }
  }

  /// The split of a node as the serial build decides it (leftCount 0: the node is a leaf).
  /// Partitions the node's primitive range in place.
  Split chooseSplit(const BvhNode& node, int depth, const LaneBox& centroids, Scratch& scratch, bool parallelBins) {
    const std::uint32_t first = node.first, count = node.count;
    if (count <= 1) return {};
    // A node the SAH can only make a leaf is not binned: with count <= traversalCost its leaf
    // cost count·A is at most traversalCost·A + any split's cost (>= 0), also when rounded.
    if (count <= options_.maxLeafSize && Wide(count) <= Wide(options_.traversalCost)) return {};
    Split split;
    const bool forceBalanced = depth + ceilLog2(count) > kBvhMaxDepth - 2;
    if (!forceBalanced) split = sahSplit(first, count, node.bounds, centroids, scratch, parallelBins);
    if (split.leftCount == 0) {
      if (count <= options_.maxLeafSize) return {};
      split = medianSplit(first, count, centroids, scratch);
    }
    return split;
  }

  static void children(const BvhNode& parent, const Split& split, BvhNode& left, BvhNode& right) {
    left.bounds = split.left.aabb();
    left.first = parent.first;
    left.count = split.leftCount;
    right.bounds = split.right.aabb();
    right.first = parent.first + split.leftCount;
    right.count = parent.count - split.leftCount;
  }

  /// Splits nodes[w.node] if worthwhile, appending both children as a pair (left at index k,
  /// right at k + 1, both after the parent) and queueing them.
  template <class Nodes>
  void process(const Work& w, Nodes& nodes, std::vector<Work>& work, Scratch& scratch) {
    const Split split = chooseSplit(nodes[w.node], w.depth, w.centroids, scratch, false);
    if (split.leftCount == 0) return;
    const auto child = static_cast<std::uint32_t>(nodes.size());
    BvhNode left, right;
    children(nodes[w.node], split, left, right);
    nodes.push_back(left);
    nodes.push_back(right);
    BvhNode& parent = nodes[w.node];
    parent.first = child;
    parent.count = 0;
    work.push_back({child + 1, w.depth + 1, split.rightCentroids});
    work.push_back({child, w.depth + 1, split.leftCentroids});
  }

  /// The parallel stage: splits large nodes here and builds both children as parallel tasks;
  /// hands nodes below kParallelSubtreeMin to buildSerial.
  void expand(Subtree& t, int depth, const LaneBox& centroids) {
    Scratch scratch(options_.bins);
    if (t.root.count < kParallelSubtreeMin) {
      buildSerial(t.root, depth, centroids, t.local, scratch);
      t.pairs = (t.local.size() - 1) / 2;
      return;
    }
    const Split split = chooseSplit(t.root, depth, centroids, scratch, t.root.count >= kParallelBinMin);
    if (split.leftCount == 0) {
      t.local.assign(1, t.root);
      return;
    }
    t.left = std::make_unique<Subtree>();
    t.right = std::make_unique<Subtree>();
    children(t.root, split, t.left->root, t.right->root);
    tbb::parallel_invoke([&] { expand(*t.left, depth + 1, split.leftCentroids); },
                         [&] { expand(*t.right, depth + 1, split.rightCentroids); });
    t.pairs = 1 + t.left->pairs + t.right->pairs;
  }

  /// Writes subtree t with its root at tree_.nodes[at] and its child pairs from `base` on, where
  /// the serial build puts them: the root's pair first, then the left subtree's pairs, then
  /// the right's.
  void place(const Subtree& t, std::size_t at, std::size_t base) {
    BvhNode* out = tree_.nodes.data();
    if (t.left) {
      BvhNode n = t.root;
      n.first = static_cast<std::uint32_t>(base);
      n.count = 0;
      new (out + at) BvhNode(n);
      tbb::parallel_invoke([&] { place(*t.left, base, base + 2); },
                           [&] { place(*t.right, base + 1, base + 2 + 2 * t.left->pairs); });
      return;
    }
    // Local index c >= 1 goes to base + c - 1.
    auto relocate = [&](BvhNode n) {
      if (!n.isLeaf()) n.first = static_cast<std::uint32_t>(base + n.first - 1);
      return n;
    };
    new (out + at) BvhNode(relocate(t.local[0]));
    for (std::size_t c = 1; c < t.local.size(); ++c) new (out + base + c - 1) BvhNode(relocate(t.local[c]));
  }

  /// Binned SAH over all three axes (Wald 2007) with min(bins, count, 4 + count / 20) bins per
  /// axis, at least 2: small nodes, which are most nodes, get fewer bins, whose sweeps cost less
  /// and whose splits are nearly as good (Embree's binner sizes its bins the same way; figures in
  /// docs/bvh.md). Partitions the range in place;
  /// leftCount 0 when no split beats a leaf (only allowed within the leaf cap) or the centroids
  /// cannot be binned (all equal). With parallelBins the binning pass runs
  /// in parallel chunks whose bins are merged (exact: min, max and integer sums).
  Split sahSplit(std::uint32_t first, std::uint32_t count, const Aabb& nodeBounds, const LaneBox& centroidBounds,
                 Scratch& scratch, bool parallelBins) {
    const std::uint32_t bins = std::min(options_.bins, std::max(std::min(count, 4 + count / 20), 2u));
    Bin* bin[3] = {scratch.bins.data(), scratch.bins.data() + bins, scratch.bins.data() + 2 * bins};
    Lanes scale = lanesSplat(0);
    bool any = false;
    for (int a = 0; a < 3; ++a) {
      const Real extent = centroidBounds.max[a] - centroidBounds.min[a];
      const Real s = extent > 0 ? Real(bins) / extent : Real(0);
      // Unusable axes get scale 0: every centroid lands in bin 0 and no split is a candidate.
      if (extent > 0 && s > 0 && std::isfinite(s)) scale[a] = s, any = true;
      for (std::uint32_t b = 0; b < bins; ++b) bin[a][b] = Bin{};
    }
    if (!any) return {};

    const Lanes cmin = centroidBounds.min;
    const Real lastBin = Real(bins - 1);
    const Lanes zero = lanesSplat(0), last = lanesSplat(lastBin);
    // The one binning formula, used by the binning pass and the partition below (so a primitive
    // goes to the side of the bin it was counted in): bin = min(floor((centroid - cmin) * scale),
    // bins - 1) per axis. On an unusable axis (scale 0) whose centroid extent overflowed,
    // (centroid - cmin) * scale is inf · 0 = NaN: max(·, 0) makes it bin 0 (lanesMax gives its
    // second operand for a NaN).
    auto binOf = [&](const BuildPrim& p) -> LaneIndex {
      return __builtin_convertvector(lanesMin(lanesMax((p.centroid() - cmin) * scale, zero), last), LaneIndex);
    };
    BuildPrim* prims = prims_.data() + first;
    auto binRange = [&](std::uint32_t begin, std::uint32_t end, Bin* const* into) {
      for (std::uint32_t i = begin; i < end; ++i) {
        const BuildPrim& p = prims[i];
        const LaneIndex b = binOf(p);
        for (int a = 0; a < 3; ++a) {
          Bin& target = into[a][b[a]];
          target.bounds.grow(p.min, p.max);
          ++target.count;
        }
      }
    };
    if (parallelBins) {
      // One set of 3 × bins per chunk, merged in chunk order.
      const std::uint32_t chunks = (count + kParallelBinGrain - 1) / kParallelBinGrain;
      std::vector<Bin> partial(std::size_t(chunks) * 3 * bins);
      tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, chunks, 1), [&](const tbb::blocked_range<std::uint32_t>& r) {
        for (std::uint32_t c = r.begin(); c < r.end(); ++c) {
          Bin* base = partial.data() + std::size_t(c) * 3 * bins;
          Bin* into[3] = {base, base + bins, base + 2 * bins};
          binRange(c * kParallelBinGrain, std::min(count, (c + 1) * kParallelBinGrain), into);
        }
      });
      for (std::uint32_t c = 0; c < chunks; ++c) {
        const Bin* base = partial.data() + std::size_t(c) * 3 * bins;
        for (int a = 0; a < 3; ++a)
          for (std::uint32_t b = 0; b < bins; ++b) {
            const Bin& from = base[a * bins + b];
            bin[a][b].bounds.grow(from.bounds);
            bin[a][b].count += from.count;
          }
      }
    } else {
      binRange(0, count, bin);
    }

    LaneBox parent;
    parent.grow(lanesOf(nodeBounds.min), lanesOf(nodeBounds.max));
    const bool useLength = !(costMeasure(parent, false) > 0);
    Wide bestCost = std::numeric_limits<Wide>::infinity();
    int bestAxis = -1;
    std::uint32_t bestSplit = 0;
    Wide* rightCost = scratch.rightCost.data();
    for (int a = 0; a < 3; ++a) {
      if (scale[a] == 0) continue;
      // rightCost[s] = measure(bins s..end) * count(bins s..end), 0 while those are empty. The
      // sweeps have no data-dependent branches (an empty bin's box is the empty box, which
      // growing ignores), so sweeping costs no mispredictions.
      LaneBox acc;
      std::uint32_t n = 0;
      for (std::uint32_t s = bins - 1; s >= 1; --s) {
        acc.grow(bin[a][s].bounds);
        n += bin[a][s].count;
        const Wide cost = costMeasure(acc, useLength) * Wide(n);
        rightCost[s] = n > 0 ? cost : Wide(0);
      }
      // Candidates: the splits with primitives on both sides; the first of equal costs wins.
      acc = LaneBox{};
      n = 0;
      for (std::uint32_t s = 1; s < bins; ++s) {
        acc.grow(bin[a][s - 1].bounds);
        n += bin[a][s - 1].count;
        const Wide cost = costMeasure(acc, useLength) * Wide(n) + rightCost[s];
        const bool better = n > 0 && n < count && cost < bestCost;
        bestCost = better ? cost : bestCost;
        bestSplit = better ? s : bestSplit;
        bestAxis = better ? a : bestAxis;
      }
    }
    if (bestAxis < 0) return {};
    const Wide parentMeasure = costMeasure(parent, useLength);
    const Wide splitCost = Wide(options_.traversalCost) * parentMeasure + bestCost;
    const Wide leafCost = Wide(count) * parentMeasure;
    if (count <= options_.maxLeafSize && leafCost <= splitCost) return {};

    Split split;
    for (std::uint32_t s = 0; s < bins; ++s) {
      const Bin& b = bin[bestAxis][s];
      if (s < bestSplit) {
        split.left.grow(b.bounds);
        split.leftCount += b.count;
      } else {
        split.right.grow(b.bounds);
      }
    }
    // Partition of the primitives and their indices together without data-dependent branches
    // (Lomuto's scheme, every element swapped with the first right one, the boundary advanced
    // by the predicate: a Hoare partition mispredicts about every other element here), then
    // the children's centroid bounds over the two ranges.
    std::uint32_t* ids = tree_.primIndices.data() + first;
    std::uint32_t i = 0;
    for (std::uint32_t k = 0; k < count; ++k) {
      const BuildPrim p = prims[k];
      const std::uint32_t id = ids[k];
      const bool left = std::uint32_t(binOf(p)[bestAxis]) < bestSplit;
      prims[k] = prims[i];
      ids[k] = ids[i];
      prims[i] = p;
      ids[i] = id;
      i += left ? 1u : 0u;
    }
    for (std::uint32_t k = 0; k < i; ++k) {
      const Lanes c = prims[k].centroid();
      split.leftCentroids.grow(c, c);
    }
    for (std::uint32_t k = i; k < count; ++k) {
      const Lanes c = prims[k].centroid();
      split.rightCentroids.grow(c, c);
    }
    return split;
  }

  /// Balanced split by count: the median centroid along the widest centroid axis (or simply the
  /// halves when every centroid is equal).
  Split medianSplit(std::uint32_t first, std::uint32_t count, const LaneBox& centroidBounds, Scratch& scratch) {
    Split split;
    split.leftCount = count / 2;
    const Lanes extent = centroidBounds.max - centroidBounds.min;
    int axis = 0;
    if (extent[1] > extent[axis]) axis = 1;
    if (extent[2] > extent[axis]) axis = 2;
    BuildPrim* prims = prims_.data() + first;
    std::uint32_t* ids = tree_.primIndices.data() + first;
    if (extent[axis] > 0) {
      // Sort a permutation so the primitives and their indices move together.
      std::vector<std::uint32_t>& order = scratch.order;
      order.resize(count);
      for (std::uint32_t k = 0; k < count; ++k) order[k] = k;
      std::nth_element(order.begin(), order.begin() + split.leftCount, order.end(),
                       [&](std::uint32_t p, std::uint32_t q) { return prims[p].centroid()[axis] < prims[q].centroid()[axis]; });
      scratch.prims.resize(count);
      scratch.ids.resize(count);
      for (std::uint32_t k = 0; k < count; ++k) {
        scratch.prims[k] = prims[order[k]];
        scratch.ids[k] = ids[order[k]];
      }
      std::copy(scratch.prims.begin(), scratch.prims.end(), prims);
      std::copy(scratch.ids.begin(), scratch.ids.end(), ids);
    }
    for (std::uint32_t k = 0; k < count; ++k) {
      const BuildPrim& p = prims[k];
      LaneBox& b = k < split.leftCount ? split.left : split.right;
      LaneBox& c = k < split.leftCount ? split.leftCentroids : split.rightCentroids;
      b.grow(p.min, p.max);
      c.grow(p.centroid(), p.centroid());
    }
    return split;
  }

  const BvhBuildOptions& options_;
  const bool parallel_;  // the current task arena has more than one thread
  BuildArray<BuildPrim> prims_;
  BinaryTree tree_;
};

bool validBounds(const Aabb& b) {
  return b.min.allFinite() && b.max.allFinite() && (b.min.array() <= b.max.array()).all();
}

/// The build's entry rule: valid options and a primitive count the 32-bit indices can hold.
void checkBuild(std::size_t count, const BvhBuildOptions& options) {
  if (options.maxLeafSize == 0) throw InvalidInput("buildBvh: maxLeafSize must be at least 1");
  if (options.bins < 2 || options.bins > kMaxBins)
    throw InvalidInput("buildBvh: bins must be in [2, " + std::to_string(kMaxBins) + "], got " +
                       std::to_string(options.bins));
  if (!(options.traversalCost >= 0) || !std::isfinite(options.traversalCost))
    throw InvalidInput("buildBvh: traversalCost must be finite and >= 0");
  if (count >= std::size_t(std::numeric_limits<std::uint32_t>::max()) / 2)
    throw InvalidInput("buildBvh: too many primitives (" + std::to_string(count) + ")");
}

/// checkBuild, and every box finite and non-empty.
void checkBuild(const std::vector<Aabb>& primBounds, const BvhBuildOptions& options) {
  checkBuild(primBounds.size(), options);
  for (std::size_t i = 0; i < primBounds.size(); ++i)
    if (!validBounds(primBounds[i]))
      throw InvalidInput("buildBvh: primitive " + std::to_string(i) + " has non-finite or empty bounds");
}

/// The binary tree over n >= 1 primitives, primitive i's box boxOf(i) (checked by the caller).
template <class BoxOf>
BinaryTree buildBinary(std::size_t n, const BoxOf& boxOf, const BvhBuildOptions& options) {
  return Builder(static_cast<std::uint32_t>(n), boxOf, options).run();
}

/// buildBinary over an array of boxes.
BinaryTree buildBinary(const std::vector<Aabb>& primBounds, const BvhBuildOptions& options) {
  return buildBinary(primBounds.size(), [&](std::uint32_t i) { return primBounds[i]; }, options);
}

}  // namespace

Bvh buildBvh(const std::vector<Aabb>& primBounds, const BvhBuildOptions& options) {
  checkBuild(primBounds, options);
  Bvh bvh;
  if (primBounds.empty()) return bvh;
  BinaryTree tree = buildBinary(primBounds, options);
  bvh.nodes.assign(tree.nodes.begin(), tree.nodes.end());
  bvh.primIndices = std::move(tree.primIndices);
  return bvh;
}

namespace {

/// The one bottom-up refit of a binary BVH: slotBox(k) is the box of the primitive in slot k.
template <class SlotBox>
void refitBinary(Bvh& bvh, const SlotBox& slotBox) {
  // Children always follow their parent in the array, so a reverse sweep sees them first.
  for (std::size_t i = bvh.nodes.size(); i-- > 0;) {
    BvhNode& node = bvh.nodes[i];
    Aabb b = Aabb::empty();
    if (node.isLeaf()) {
      for (std::uint32_t k = node.first, e = node.first + node.count; k < e; ++k) b.grow(slotBox(k));
    } else {
      b = bvh.nodes[node.first].bounds;
      b.grow(bvh.nodes[node.first + 1].bounds);
    }
    node.bounds = b;
  }
}

void checkRefitCount(const Bvh& bvh, std::size_t count) {
  if (count != bvh.primIndices.size())
    throw InvalidInput("refitBvh: expected " + std::to_string(bvh.primIndices.size()) + " primitive bounds, got " +
                       std::to_string(count));
}

}  // namespace

void refitBvh(Bvh& bvh, const std::vector<Aabb>& primBounds) {
  checkRefitCount(bvh, primBounds.size());
  refitBinary(bvh, [&](std::uint32_t k) -> const Aabb& { return primBounds[bvh.primIndices[k]]; });
}


namespace {

/// The lanes of the wide node made from binary node `binary` (its children, then, while fewer
/// than four, the inner lane of largest surface area replaced in place by its two children: the
/// SAH's measure of how often a ray enters it; in place keeps the leaves in the binary tree's
/// left-to-right order; a leaf root is its own single lane). Returns the number of lanes.
int wideLanes(const BvhNode* nodes, std::uint32_t binary, std::uint32_t (&lanes)[4]) {
  int n = 0;
  const BvhNode& b = nodes[binary];
  if (b.isLeaf()) {
    lanes[n++] = binary;
    return n;
  }
  lanes[n++] = b.first;
  lanes[n++] = b.first + 1;
  while (n < 4) {
    int open = -1;
    Real openArea = -1;
    for (int i = 0; i < n; ++i) {
      const BvhNode& lane = nodes[lanes[i]];
      if (!lane.isLeaf() && lane.bounds.area() > openArea) open = i, openArea = lane.bounds.area();
    }
    if (open < 0) break;
    const std::uint32_t first = nodes[lanes[open]].first;
    for (int i = n; i > open + 1; --i) lanes[i] = lanes[i - 1];
    lanes[open] = first;
    lanes[open + 1] = first + 1;
    ++n;
  }
  return n;
}

/// The wide tree of a binary tree (nodes[0] its root). Two passes over the wide nodes in
/// creation order (children after parents): the first counts them, so the node array is
/// allocated once at its size (no spare capacity, no copy); the second fills them.
WideBvh widen(const BvhNode* nodes, std::vector<std::uint32_t> primIndices) {
  WideBvh wide;
  std::vector<std::uint32_t> todo{0u};  // binary node of each wide node, in creation order
  for (std::size_t next = 0; next < todo.size(); ++next) {
    std::uint32_t lanes[4];
    const int n = wideLanes(nodes, todo[next], lanes);
    for (int i = 0; i < n; ++i)
      if (!nodes[lanes[i]].isLeaf()) todo.push_back(lanes[i]);
  }
  constexpr Real inf = std::numeric_limits<Real>::infinity();
  wide.nodes.resize(todo.size());
  std::uint32_t created = 1;
  for (std::size_t index = 0; index < todo.size(); ++index) {
    std::uint32_t lanes[4];
    const int n = wideLanes(nodes, todo[index], lanes);
    WideBvhNode& node = wide.nodes[index];
    for (int i = 0; i < 4; ++i) {
      node.minX[i] = node.minY[i] = node.minZ[i] = inf;
      node.maxX[i] = node.maxY[i] = node.maxZ[i] = -inf;
      node.child[i] = WideBvhNode::kEmpty;
      node.count[i] = 0;
    }
    for (int i = 0; i < n; ++i) {
      const BvhNode& lane = nodes[lanes[i]];
      node.minX[i] = lane.bounds.min.x();
      node.minY[i] = lane.bounds.min.y();
      node.minZ[i] = lane.bounds.min.z();
      node.maxX[i] = lane.bounds.max.x();
      node.maxY[i] = lane.bounds.max.y();
      node.maxZ[i] = lane.bounds.max.z();
      // a leaf lane keeps its slots; an inner lane is the next wide node created (the first
      // pass pushed them in this order)
      node.child[i] = lane.isLeaf() ? lane.first : created++;
      node.count[i] = lane.isLeaf() ? lane.count : 0;
    }
  }
  wide.primIndices = std::move(primIndices);
  return wide;
}

}  // namespace

WideBvh widenBvh(const Bvh& bvh) {
  if (bvh.nodes.empty()) return {};
  return widen(bvh.nodes.data(), bvh.primIndices);
}

WideBvh buildWideBvh(const std::vector<Aabb>& primBounds, const BvhBuildOptions& options) {
  checkBuild(primBounds, options);
  if (primBounds.empty()) return {};
  BinaryTree tree = buildBinary(primBounds, options);
  return widen(tree.nodes.data(), std::move(tree.primIndices));
}

namespace detail {

WideBvh buildTriangleWideBvh(const std::vector<Vec3>& vertices, const std::vector<std::array<std::uint32_t, 3>>& triangles,
                             const BvhBuildOptions& options) {
  checkBuild(triangles.size(), options);
  if (triangles.empty()) return {};
  const auto triangleBox = [&](std::uint32_t i) {
    const std::array<std::uint32_t, 3>& t = triangles[i];
    return bounds(Triangle{vertices[t[0]], vertices[t[1]], vertices[t[2]]});
  };
  BinaryTree tree = buildBinary(triangles.size(), triangleBox, options);
  return widen(tree.nodes.data(), std::move(tree.primIndices));
}

}  // namespace detail

Aabb wideRootBounds(const WideBvh& bvh) {
  Aabb box = Aabb::empty();
  for (int i = 0; i < 4; ++i)
    if (bvh.nodes[0].used(i)) box.grow(bvh.nodes[0].laneBounds(i));
  return box;
}

}  // namespace crux
