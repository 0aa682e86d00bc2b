#include <crux/scene/dynamic_aabb_tree.hpp>

#include "box_tests.hpp"

#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace crux {
namespace {

constexpr const char* kName = "DynamicAabbTree";

Aabb merged(const Aabb& a, const Aabb& b) { return {a.min.cwiseMin(b.min), a.max.cwiseMax(b.max)}; }

/// Surface area of a (non-empty) box, and of the union of two boxes without forming it: the
/// insertion cost and the rotations evaluate these on every level.
Real areaOf(const Aabb& a) {
  const Real x = a.max.x() - a.min.x(), y = a.max.y() - a.min.y(), z = a.max.z() - a.min.z();
  return 2 * (x * y + y * z + z * x);
}
Real unionArea(const Aabb& a, const Aabb& b) {
  const Real x = std::max(a.max.x(), b.max.x()) - std::min(a.min.x(), b.min.x());
  const Real y = std::max(a.max.y(), b.max.y()) - std::min(a.min.y(), b.min.y());
  const Real z = std::max(a.max.z(), b.max.z()) - std::min(a.min.z(), b.min.z());
  return 2 * (x * y + y * z + z * x);
}

std::uint64_t pairKey(ProxyId a, ProxyId b) {
  return a < b ? (std::uint64_t(a) << 32 | b) : (std::uint64_t(b) << 32 | a);
}

}  // namespace

DynamicAabbTree::DynamicAabbTree(const DynamicAabbTreeOptions& options) : options_(options) {
  if (!(options.marginFraction >= 0) || !std::isfinite(options.marginFraction))
    throw InvalidInput("DynamicAabbTreeOptions.marginFraction must be finite and >= 0");
  if (!(options.displacementMultiplier >= 0) || !std::isfinite(options.displacementMultiplier))
    throw InvalidInput("DynamicAabbTreeOptions.displacementMultiplier must be finite and >= 0");
  if (!(options.rayTreeRaysPerBox >= 0))
    throw InvalidInput("DynamicAabbTreeOptions.rayTreeRaysPerBox must be >= 0 (+inf: never)");
}

Aabb DynamicAabbTree::fatten(const Aabb& box) const {
  const Real margin = options_.marginFraction * (box.max - box.min).maxCoeff();
  const Vec3 m = Vec3::Constant(margin);
  return {box.min - m, box.max + m};
}

std::uint32_t DynamicAabbTree::allocNode() {
  std::uint32_t index;
  if (freeList_ != kNull) {
    index = freeList_;
    freeList_ = nodes_[index].parent;
    --freeCount_;
  } else {
    index = static_cast<std::uint32_t>(nodes_.size());
    nodes_.emplace_back();
  }
  nodes_[index] = Node{};
  return index;
}

void DynamicAabbTree::freeNode(std::uint32_t index) {
  Node& n = nodes_[index];
  n.parent = freeList_;
  n.child1 = n.child2 = kNull;
  n.height = -1;
  freeList_ = index;
  ++freeCount_;
}

void DynamicAabbTree::insertLeaf(std::uint32_t leaf) {
  if (root_ == kNull) {
    root_ = leaf;
    nodes_[leaf].parent = kNull;
    return;
  }
  // Greedy descent (Goldsmith & Salmon): stop where making a new parent costs no more than the
  // cheapest lower bound of going further down. `inherited` is the area the ancestors above the
  // current node gain by enclosing the leaf.
  const Aabb leafBox = nodes_[leaf].box;
  std::uint32_t index = root_;
  Real inherited = 0;
  while (!nodes_[index].isLeaf()) {
    const Node& n = nodes_[index];
    const Real joined = unionArea(n.box, leafBox);
    const Real here = joined + inherited;
    const Real down = inherited + (joined - areaOf(n.box));
    const auto descendCost = [&](std::uint32_t c) {
      const Node& cn = nodes_[c];
      const Real u = unionArea(cn.box, leafBox);
      return down + (cn.isLeaf() ? u : u - areaOf(cn.box));
    };
    const Real cost1 = descendCost(n.child1);
    const Real cost2 = descendCost(n.child2);
    if (here <= cost1 && here <= cost2) break;
    inherited = down;
    index = cost1 <= cost2 ? n.child1 : n.child2;
  }

  // A new parent joins the chosen sibling and the leaf.
  const std::uint32_t sibling = index;
  const std::uint32_t oldParent = nodes_[sibling].parent;
  const std::uint32_t parent = allocNode();  // may reallocate nodes_: no references held
  Node& p = nodes_[parent];
  p.parent = oldParent;
  p.box = merged(leafBox, nodes_[sibling].box);
  p.height = nodes_[sibling].height + 1;
  p.child1 = sibling;
  p.child2 = leaf;
  nodes_[sibling].parent = parent;
  nodes_[leaf].parent = parent;
  if (oldParent == kNull) {
    root_ = parent;
  } else {
    Node& op = nodes_[oldParent];
    (op.child1 == sibling ? op.child1 : op.child2) = parent;
  }
  refitUpwards(oldParent);
}

void DynamicAabbTree::removeLeaf(std::uint32_t leaf) {
  if (leaf == root_) {
    root_ = kNull;
    return;
  }
  const std::uint32_t parent = nodes_[leaf].parent;
  const std::uint32_t grand = nodes_[parent].parent;
  const std::uint32_t sibling = nodes_[parent].child1 == leaf ? nodes_[parent].child2 : nodes_[parent].child1;
  nodes_[sibling].parent = grand;
  if (grand == kNull) {
    root_ = sibling;
  } else {
    Node& g = nodes_[grand];
    (g.child1 == parent ? g.child1 : g.child2) = sibling;
  }
  freeNode(parent);
  nodes_[leaf].parent = kNull;
  refitUpwards(grand);
}

void DynamicAabbTree::refitUpwards(std::uint32_t index) {
  while (index != kNull) {
    Node& n = nodes_[index];
    n.height = 1 + std::max(nodes_[n.child1].height, nodes_[n.child2].height);
    n.box = merged(nodes_[n.child1].box, nodes_[n.child2].box);
    rotate(index);
    index = nodes_[index].parent;
  }
}

// Tree rotation (Kopta et al. 2012): at node A = (B, C), swapping B with a child of C (or C
// with a child of B) leaves A's box unchanged and replaces the box of the inner child. Of the
// (up to) four swaps, apply the one that shrinks that child's surface area the most.
void DynamicAabbTree::rotate(std::uint32_t a) {
  const std::uint32_t b = nodes_[a].child1, c = nodes_[a].child2;
  std::uint32_t bestStay = kNull, bestSwap = kNull, bestInner = kNull;
  Real bestGain = 0;
  // Swap `out` (a child of a) with `in` (a child of `inner`, the other child of a); `keep` is
  // inner's other child. The inner node becomes (out, keep).
  const auto consider = [&](std::uint32_t out, std::uint32_t inner) {
    const Node& in = nodes_[inner];
    if (in.isLeaf()) return;
    const Real before = areaOf(in.box);
    for (const auto& [swap, keep] : {std::pair{in.child1, in.child2}, std::pair{in.child2, in.child1}}) {
      const Real gain = before - unionArea(nodes_[out].box, nodes_[keep].box);
      if (gain > bestGain) {
        bestGain = gain;
        bestStay = out;
        bestSwap = swap;
        bestInner = inner;
      }
    }
  };
  consider(b, c);
  consider(c, b);
  if (bestInner == kNull) return;

  // a's child bestStay and inner's child bestSwap trade places.
  Node& na = nodes_[a];
  Node& ni = nodes_[bestInner];
  (na.child1 == bestStay ? na.child1 : na.child2) = bestSwap;
  (ni.child1 == bestSwap ? ni.child1 : ni.child2) = bestStay;
  nodes_[bestSwap].parent = a;
  nodes_[bestStay].parent = bestInner;
  ni.box = merged(nodes_[ni.child1].box, nodes_[ni.child2].box);
  ni.height = 1 + std::max(nodes_[ni.child1].height, nodes_[ni.child2].height);
  na.height = 1 + std::max(nodes_[na.child1].height, nodes_[na.child2].height);
}

// Rebuilds the whole tree top-down by median splits of the leaves' fat-box centres along the
// axis of largest spread (a balanced tree of height ceil(log2 n), whatever the boxes: nested
// boxes with one common centre defeat SAH binning), keeping every leaf node (and so the
// id -> leaf map) as it is.
void DynamicAabbTree::rebuild() {
  ++rebuilds_;
  std::vector<std::uint32_t> leaves;
  for (const Entry& e : entries_)
    if (e.leaf != kNull) leaves.push_back(e.leaf);
  for (std::uint32_t i = 0; i < nodes_.size(); ++i)  // free every inner node; leaves stay
    if (nodes_[i].height > 0) freeNode(i);
  root_ = kNull;
  if (leaves.empty()) return;
  const auto centre = [this](std::uint32_t leaf) { return nodes_[leaf].box.min * Real(0.5) + nodes_[leaf].box.max * Real(0.5); };
  struct Range {
    std::size_t begin, end;
    std::uint32_t parent;
    bool second;  // becomes child2 of parent (else child1, or the root)
  };
  std::vector<Range> stack = {{0, leaves.size(), kNull, false}};
  while (!stack.empty()) {
    const Range r = stack.back();
    stack.pop_back();
    std::uint32_t index;
    if (r.end - r.begin == 1) {
      index = leaves[r.begin];
    } else {
      Aabb spread = Aabb::empty();
      for (std::size_t i = r.begin; i < r.end; ++i) spread.grow(centre(leaves[i]));
      int axis = 0;
      (spread.max - spread.min).maxCoeff(&axis);
      const std::size_t mid = (r.begin + r.end) / 2;
      std::nth_element(leaves.begin() + std::ptrdiff_t(r.begin), leaves.begin() + std::ptrdiff_t(mid),
                       leaves.begin() + std::ptrdiff_t(r.end),
                       [&](std::uint32_t a, std::uint32_t b) { return centre(a)[axis] < centre(b)[axis]; });
      index = allocNode();
      stack.push_back({r.begin, mid, index, false});
      stack.push_back({mid, r.end, index, true});
    }
    nodes_[index].parent = r.parent;
    if (r.parent == kNull) root_ = index;
    else (r.second ? nodes_[r.parent].child2 : nodes_[r.parent].child1) = index;
  }
  // Heights and boxes bottom-up, by an explicit post-order walk.
  std::vector<std::pair<std::uint32_t, bool>> post = {{root_, false}};
  while (!post.empty()) {
    const auto [index, expanded] = post.back();
    post.pop_back();
    Node& n = nodes_[index];
    if (n.isLeaf()) continue;
    if (expanded) {
      n.height = 1 + std::max(nodes_[n.child1].height, nodes_[n.child2].height);
      n.box = merged(nodes_[n.child1].box, nodes_[n.child2].box);
    } else {
      post.push_back({index, true});
      post.push_back({n.child1, false});
      post.push_back({n.child2, false});
    }
  }
}

double DynamicAabbTree::innerArea() const {
  double sum = 0;
  for (const Node& n : nodes_)
    if (n.height > 0) sum += double(n.box.area());
  return sum;
}

void DynamicAabbTree::markChanged(ProxyId id, std::uint8_t flag) {
  if (flags_[id] == 0) changed_.push_back(id);
  flags_[id] |= flag;
  dropRayTree();
}

void DynamicAabbTree::dropRayTree() {
  rayTreeReady_.store(false, std::memory_order_relaxed);
  raysSinceChange_.store(0, std::memory_order_relaxed);
}

void DynamicAabbTree::insert(ProxyId id, const Aabb& box) {
  validate(box, "box");
  if (contains(id)) detail::badProxy(kName, id, "is already present");
  if (id >= entries_.size()) {
    entries_.resize(std::size_t(id) + 1);
    flags_.resize(std::size_t(id) + 1, 0);
  }
  const std::uint32_t leaf = allocNode();
  nodes_[leaf].box = fatten(box);
  nodes_[leaf].id = id;
  entries_[id] = {box, leaf};
  insertLeaf(leaf);
  markChanged(id, kFatChanged);
  ++size_;
  if (height() > kRebuildHeight) rebuild();
}

void DynamicAabbTree::remove(ProxyId id) {
  if (!contains(id)) detail::badProxy(kName, id, "is not present");
  const std::uint32_t leaf = entries_[id].leaf;
  removeLeaf(leaf);
  freeNode(leaf);
  entries_[id].leaf = kNull;
  markChanged(id, kFatChanged);
  --size_;
  if (height() > kRebuildHeight) rebuild();
}

void DynamicAabbTree::update(ProxyId id, const Aabb& box) {
  validate(box, "box");
  if (!contains(id)) detail::badProxy(kName, id, "is not present");
  Entry& e = entries_[id];
  const Aabb previous = e.box;
  e.box = box;
  if (detail::containsBox(nodes_[e.leaf].box, box)) {
    markChanged(id, kBoxChanged);
    return;
  }
  removeLeaf(e.leaf);
  Aabb fat = fatten(box);
  // Stretch towards where the box is heading (the centre's displacement, halves avoid overflow).
  const Vec3 move = (box.min * Real(0.5) + box.max * Real(0.5)) - (previous.min * Real(0.5) + previous.max * Real(0.5));
  for (int i = 0; i < 3; ++i) {
    const Real stretch = options_.displacementMultiplier * move[i];
    if (!std::isfinite(stretch)) continue;
    if (stretch < 0) fat.min[i] += stretch;
    else fat.max[i] += stretch;
  }
  nodes_[e.leaf].box = fat;
  insertLeaf(e.leaf);
  ++reinsertions_;
  markChanged(id, kFatChanged | kBoxChanged);
  if (height() > kRebuildHeight) rebuild();
}

void DynamicAabbTree::clear() {
  nodes_.clear();
  root_ = freeList_ = kNull;
  freeCount_ = 0;
  entries_.clear();
  flags_.clear();
  size_ = 0;
  changed_.clear();
  pairKeys_.clear();
  pairOverlap_.clear();
  dropRayTree();
}

bool DynamicAabbTree::contains(ProxyId id) const { return id < entries_.size() && entries_[id].leaf != kNull; }

const Aabb& DynamicAabbTree::bounds(ProxyId id) const { return entries_[id].box; }

const Aabb& DynamicAabbTree::fatBounds(ProxyId id) const { return nodes_[entries_[id].leaf].box; }

int DynamicAabbTree::height() const { return root_ == kNull ? -1 : nodes_[root_].height; }

template <class NodeTest, class Visit>
bool DynamicAabbTree::traverse(const NodeTest& nodeTest, const Visit& visit) const {
  if (root_ == kNull) return true;
  std::uint32_t stack[kStackSize];  // each pop pushes at most 2: depth <= height + 1
  int top = 0;
  stack[top++] = root_;
  while (top > 0) {
    const Node& n = nodes_[stack[--top]];
    if (!nodeTest(n.box)) continue;
    if (n.isLeaf()) {
      if (!visit(n)) return false;
      continue;
    }
    stack[top++] = n.child1;
    stack[top++] = n.child2;
  }
  return true;
}

template <class Region>
bool DynamicAabbTree::queryRegion(const Region& region, ProxyCollector& collector) const {
  return traverse([&region](const Aabb& b) { return region.node(b); },
                  [&](const Node& leaf) {
                    return !region.leaf(entries_[leaf.id].box) || collector.add(leaf.id);
                  });
}

bool DynamicAabbTree::query(const Aabb& box, ProxyCollector& collector) const {
  return queryRegion(detail::AabbRegion{box}, collector);
}
bool DynamicAabbTree::query(const Sphere& sphere, ProxyCollector& collector) const {
  return queryRegion(detail::SphereRegion{sphere}, collector);
}
bool DynamicAabbTree::query(const Obb& box, ProxyCollector& collector) const {
  return queryRegion(detail::ObbRegion(box), collector);
}

// Builds the wide ray tree over the exact boxes, once per change (the first caller past the
// threshold; the others wait on the mutex and find it built). One box per leaf lane, so a leaf
// is decided by its lane's test; the leaf lanes are set to the boxes themselves (the builder
// fits them exactly already; writing them makes the lane test rayBoxEntry's on the box by
// construction). The build runs isolated: a TBB worker holding the mutex must not pick up
// another ray of an enclosing batch, which would wait on the same mutex.
void DynamicAabbTree::buildRayTree() const {
  const std::lock_guard<std::mutex> lock(rayTreeMutex_);
  if (rayTreeReady_.load(std::memory_order_relaxed)) return;
  std::vector<Aabb> boxes;
  std::vector<ProxyId> ids;
  boxes.reserve(size_);
  ids.reserve(size_);
  for (std::size_t id = 0; id < entries_.size(); ++id)
    if (entries_[id].leaf != kNull) {
      boxes.push_back(entries_[id].box);
      ids.push_back(ProxyId(id));
    }
  BvhBuildOptions options;
  options.maxLeafSize = 1;
  tbb::this_task_arena::isolate([&] { rayTree_ = buildWideBvh(boxes, options); });
  for (WideBvhNode& node : rayTree_.nodes)
    for (int i = 0; i < 4; ++i) {
      if (node.count[i] == 0) continue;
      const Aabb& b = boxes[rayTree_.primIndices[node.child[i]]];
      node.minX[i] = b.min.x(), node.minY[i] = b.min.y(), node.minZ[i] = b.min.z();
      node.maxX[i] = b.max.x(), node.maxY[i] = b.max.y(), node.maxZ[i] = b.max.z();
    }
  raySlotIds_.resize(boxes.size());
  for (std::size_t k = 0; k < boxes.size(); ++k) raySlotIds_[k] = ids[rayTree_.primIndices[k]];
  rayTreeBuilds_.fetch_add(1, std::memory_order_relaxed);
  rayTreeReady_.store(true, std::memory_order_release);
}

void DynamicAabbTree::prepareRays() const {
  if (!rayTreeReady_.load(std::memory_order_acquire)) buildRayTree();
}

// The wide ray tree, nearest lane first (traverseWideBvhOrdered). A leaf lane holds one box and
// its lane's entry is rayBoxEntry's for that box: the walk hands it to the collector as it pops
// (after keep() has checked it against the collector's current maxT).
bool DynamicAabbTree::raycastWide(const Ray& ray, RayProxyCollector& collector) const {
  struct Visitor {
    const DynamicAabbTree& tree;
    const detail::RayLaneTest lanes;
    RayProxyCollector& collector;
    unsigned enter(const WideBvhNode& node, Real (&keys)[4]) const { return lanes.enter(node, collector.maxT, keys); }
    bool keep(Real key) const { return key <= collector.maxT; }
    bool leaf(std::uint32_t first, std::uint32_t /*count: 1*/, Real key) {
      return collector.add(tree.raySlotIds_[first], key);
    }
  };
  const RaySlabs slabs(ray, collector.boxMargin);
  Visitor visitor{*this, detail::RayLaneTest(slabs), collector};
  return traverseWideBvhOrdered(rayTree_, visitor);
}

bool DynamicAabbTree::raycast(const Ray& ray, RayProxyCollector& collector) const {
  if (root_ == kNull) return true;
  if (!rayTreeReady_.load(std::memory_order_acquire)) {
    const std::size_t rays = raysSinceChange_.fetch_add(1, std::memory_order_relaxed) + 1;
    if (Real(rays) > options_.rayTreeRaysPerBox * Real(size_)) buildRayTree();
  }
  if (rayTreeReady_.load(std::memory_order_acquire)) return raycastWide(ray, collector);
  const RaySlabs slabs(ray, collector.boxMargin);
  struct Item {
    std::uint32_t node;
    Real t;
  };
  Item stack[kStackSize];
  int top = 0;
  Real t0;
  if (!rayBoxEntry(slabs, nodes_[root_].box, collector.maxT, t0)) return true;
  stack[top++] = {root_, t0};
  while (top > 0) {
    const Item item = stack[--top];
    if (item.t > collector.maxT) continue;  // a nearer hit was found meanwhile
    const Node& n = nodes_[item.node];
    if (n.isLeaf()) {
      Real t;
      if (rayBoxEntry(slabs, entries_[n.id].box, collector.maxT, t) && !collector.add(n.id, t)) return false;
      continue;
    }
    Real t1 = 0, t2 = 0;  // (set whenever read: rayBoxEntry writes them on a hit; initialised for -Wmaybe-uninitialized)
    const bool hit1 = rayBoxEntry(slabs, nodes_[n.child1].box, collector.maxT, t1);
    const bool hit2 = rayBoxEntry(slabs, nodes_[n.child2].box, collector.maxT, t2);
    if (hit1 && hit2) {  // nearer on top
      if (t1 <= t2) {
        stack[top++] = {n.child2, t2};
        stack[top++] = {n.child1, t1};
      } else {
        stack[top++] = {n.child1, t1};
        stack[top++] = {n.child2, t2};
      }
    } else if (hit1) {
      stack[top++] = {n.child1, t1};
    } else if (hit2) {
      stack[top++] = {n.child2, t2};
    }
  }
  return true;
}

// The pair cache holds every pair whose fat boxes overlap, sorted, with a bit saying whether
// the exact boxes overlap. A pair's fat-box status can only change when a member's fat box
// changed (kFatChanged), and its exact status only when a member's box changed (kBoxChanged):
//  1. each fat-changed live id queries the tree with its fat box; new keys are collected once
//     per pair (when both members changed, by the smaller id);
//  2. one merge pass keeps cached pairs without a fat-changed member (re-testing the exact
//     boxes when a member's box changed) and adds the new keys (testing their exact boxes);
//  3. pairs whose exact boxes overlap are reported in key order.
void DynamicAabbTree::pairs(PairCollector& collector) {
  newKeys_.clear();
  for (const ProxyId id : changed_) {
    if (!(flags_[id] & kFatChanged) || entries_[id].leaf == kNull) continue;
    const Aabb fat = nodes_[entries_[id].leaf].box;
    traverse([&fat](const Aabb& b) { return detail::boxesTouch(b, fat); },
             [&](const Node& leaf) {
               const ProxyId other = leaf.id;
               if (other != id && !((flags_[other] & kFatChanged) && other < id)) newKeys_.push_back(pairKey(id, other));
               return true;
             });
  }
  std::sort(newKeys_.begin(), newKeys_.end());

  mergedKeys_.clear();
  mergedOverlap_.clear();
  const std::size_t nOld = pairKeys_.size(), nNew = newKeys_.size();
  std::size_t i = 0, j = 0;
  const auto emit = [&](std::uint64_t key, bool exact) {
    mergedKeys_.push_back(key);
    mergedOverlap_.push_back(exact ? 1 : 0);
    if (exact) collector.add(ProxyId(key >> 32), ProxyId(key & 0xffffffffu));
  };
  while (i < nOld || j < nNew) {
    if (i < nOld && (j == nNew || pairKeys_[i] < newKeys_[j])) {
      const std::uint64_t key = pairKeys_[i];
      const ProxyId a = ProxyId(key >> 32), b = ProxyId(key & 0xffffffffu);
      const std::uint8_t f = flags_[a] | flags_[b];
      if (!(f & kFatChanged)) emit(key, (f & kBoxChanged) ? detail::boxesTouch(entries_[a].box, entries_[b].box) : pairOverlap_[i] != 0);
      ++i;
    } else {
      if (i < nOld && pairKeys_[i] == newKeys_[j]) ++i;  // re-found: the new entry replaces it
      const std::uint64_t key = newKeys_[j++];
      const ProxyId a = ProxyId(key >> 32), b = ProxyId(key & 0xffffffffu);
      emit(key, detail::boxesTouch(entries_[a].box, entries_[b].box));
    }
  }
  pairKeys_.swap(mergedKeys_);
  pairOverlap_.swap(mergedOverlap_);
  for (const ProxyId id : changed_) flags_[id] = 0;
  changed_.clear();
}

std::string DynamicAabbTree::checkInvariants() const {
  std::ostringstream err;
  std::size_t reachable = 0, leaves = 0;
  if (root_ != kNull) {
    if (nodes_[root_].parent != kNull) return "root has a parent";
    std::vector<std::uint32_t> stack = {root_};
    while (!stack.empty()) {
      const std::uint32_t index = stack.back();
      stack.pop_back();
      ++reachable;
      const Node& n = nodes_[index];
      if (n.height < 0) return "node " + std::to_string(index) + " is reachable but free";
      if (n.isLeaf()) {
        ++leaves;
        if (n.child2 != kNull || n.height != 0) return "leaf " + std::to_string(index) + " malformed";
        if (n.id >= entries_.size() || entries_[n.id].leaf != index)
          return "leaf " + std::to_string(index) + " not mapped from id " + std::to_string(n.id);
        if (!detail::containsBox(n.box, entries_[n.id].box))
          return "fat box of id " + std::to_string(n.id) + " does not contain its box";
        continue;
      }
      for (const std::uint32_t c : {n.child1, n.child2}) {
        if (c >= nodes_.size()) return "child index out of range";
        if (nodes_[c].parent != index) return "child " + std::to_string(c) + " has a wrong parent";
        if (!detail::containsBox(n.box, nodes_[c].box)) return "node " + std::to_string(index) + " misses a child box";
        stack.push_back(c);
      }
      const int h1 = nodes_[n.child1].height, h2 = nodes_[n.child2].height;
      if (n.height != 1 + std::max(h1, h2)) return "node " + std::to_string(index) + " has a wrong height";
    }
  }
  if (height() > kRebuildHeight) return "height " + std::to_string(height()) + " above kRebuildHeight";
  if (leaves != size_) return "leaf count " + std::to_string(leaves) + " != size " + std::to_string(size_);
  std::size_t freeNodes = 0;
  for (std::uint32_t f = freeList_; f != kNull; f = nodes_[f].parent) {
    if (nodes_[f].height != -1) return "free node " + std::to_string(f) + " is not marked free";
    if (++freeNodes > nodes_.size()) return "free list cycles";
  }
  if (freeNodes != freeCount_) return "free count mismatch";
  if (reachable + freeNodes != nodes_.size()) return "nodes leaked";
  std::size_t live = 0;
  for (const Entry& e : entries_) live += e.leaf != kNull;
  if (live != size_) return "live entries != size";
  return err.str();
}

}  // namespace crux
