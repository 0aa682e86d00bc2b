#include <crux/scene/octree.hpp>

#include "box_tests.hpp"
#include "geometry/small_sort.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace crux {
namespace {

constexpr const char* kName = "Octree";
/// Boxes are placed at most this many levels below the root; growth may push them deeper,
/// up to Octree::kMaxDepth, before a rebuild re-places everything under the grown root.
constexpr int kMaxPlaceDepth = 24;
/// Size of the first root cell, relative to the magnitude of the first box's centre, when that
/// box is a point (a zero extent gives no size to start from). Only affects performance.
constexpr Real kPointRootFraction = Real(1) / Real(1024);

/// Centre of a box without overflow (min + max may overflow for boxes near the limits of Real).
Vec3 centerOf(const Aabb& b) { return b.min * Real(0.5) + b.max * Real(0.5); }

/// Pairs by querying each box against the tree: a pair is reported by its smaller id.
class PairFromQuery final : public ProxyCollector {
 public:
  PairFromQuery(ProxyId self, PairCollector& out) : self_(self), out_(out) {}
  bool add(ProxyId other) override {
    if (other > self_) out_.add(self_, other);
    return true;
  }

 private:
  ProxyId self_;
  PairCollector& out_;
};

}  // namespace

Aabb Octree::looseBounds(const Node& n) const {
  const Vec3 r = Vec3::Constant(2 * n.half);
  return {n.center - r, n.center + r};
}

bool Octree::fits(const Aabb& box, const Node& n) const { return detail::containsBox(looseBounds(n), box); }

std::uint32_t Octree::allocNode(const Vec3& center, Real half, std::uint32_t parent) {
  std::uint32_t index;
  if (!freeNodes_.empty()) {
    index = freeNodes_.back();
    freeNodes_.pop_back();
    nodes_[index] = Node{};
  } else {
    index = static_cast<std::uint32_t>(nodes_.size());
    nodes_.emplace_back();
  }
  Node& n = nodes_[index];
  n.center = center;
  n.half = half;
  n.parent = parent;
  return index;
}

void Octree::freeNode(std::uint32_t index) {
  nodes_[index].count = 0;
  nodes_[index].parent = kNone;
  freeNodes_.push_back(index);
}

Aabb Octree::rootCell() const {
  if (root_ == kNone) return Aabb::empty();
  const Node& n = nodes_[root_];
  const Vec3 r = Vec3::Constant(n.half);
  return {n.center - r, n.center + r};
}

void Octree::growToContain(const Aabb& box) {
  const Vec3 c = centerOf(box);
  if (root_ == kNone) {
    const Real extent = (box.max * Real(0.5) - box.min * Real(0.5)).maxCoeff();
    Real half = extent;
    if (!(half > 0)) half = kPointRootFraction * std::max(Real(1), c.cwiseAbs().maxCoeff());
    root_ = allocNode(c, half, kNone);
    depth_ = 0;
    if (!fits(box, nodes_[root_])) nodes_[root_].half = std::numeric_limits<Real>::infinity();
    return;
  }
  // Grow until the box fits the root's loose bounds and its centre lies in the root's cell:
  // a box outside the cell (though inside the loose bounds) could not descend to the child
  // its size calls for and would stay at the root.
  const auto inCell = [&c](const Node& n) { return ((c - n.center).cwiseAbs().array() <= n.half).all(); };
  bool grew = false;
  while (!fits(box, nodes_[root_]) || !inCell(nodes_[root_])) {
    const Node old = nodes_[root_];
    // Double the root towards the box: the old root becomes one octant of the new one.
    Vec3 sign;
    for (int i = 0; i < 3; ++i) sign[i] = c[i] >= old.center[i] ? Real(1) : Real(-1);
    Real newHalf = 2 * old.half;
    Vec3 newCenter = old.center + sign * old.half;
    if (!std::isfinite(newHalf) || !newCenter.allFinite() || !looseBounds(Node{newCenter, newHalf}).min.allFinite() ||
        !looseBounds(Node{newCenter, newHalf}).max.allFinite()) {
      // The root would overflow Real: make it the whole space (boxes stay there, never lost).
      newHalf = std::numeric_limits<Real>::infinity();
      newCenter = old.center;
    }
    const std::uint32_t oldRoot = root_;
    const std::uint32_t newRoot = allocNode(newCenter, newHalf, kNone);
    int octant = 0;
    for (int i = 0; i < 3; ++i)
      if (old.center[i] >= newCenter[i]) octant |= 1 << i;
    nodes_[newRoot].child[octant] = oldRoot;
    nodes_[newRoot].count = old.count;
    nodes_[oldRoot].parent = newRoot;
    root_ = newRoot;
    ++depth_;
    grew = true;
  }
  if (grew && depth_ > kMaxDepth) rebuild();
}

void Octree::rebuild() {
  ++rebuilds_;
  const Node oldRoot = nodes_[root_];
  nodes_.clear();
  freeNodes_.clear();
  root_ = allocNode(oldRoot.center, oldRoot.half, kNone);
  depth_ = 0;
  for (ProxyId id = 0; id < entries_.size(); ++id) {
    if (entries_[id].node == kNone) continue;
    entries_[id].node = kNone;
    place(id);
  }
}

void Octree::place(ProxyId id) {
  Entry& e = entries_[id];
  const Vec3 c = centerOf(e.box);
  std::uint32_t index = root_;
  int d = 0;
  for (;;) {
    ++nodes_[index].count;
    const Node& n = nodes_[index];
    if (d >= kMaxPlaceDepth || !std::isfinite(n.half)) break;
    const Real childHalf = n.half / 2;
    if (!(childHalf > 0)) break;
    int octant = 0;
    Vec3 childCenter;
    for (int i = 0; i < 3; ++i) {
      const bool upper = c[i] >= n.center[i];
      if (upper) octant |= 1 << i;
      childCenter[i] = upper ? n.center[i] + childHalf : n.center[i] - childHalf;
    }
    const std::uint32_t existing = n.child[octant];
    if (existing != kNone) {
      if (!fits(e.box, nodes_[existing])) break;
      index = existing;
    } else {
      if (!fits(e.box, Node{childCenter, childHalf})) break;
      const std::uint32_t child = allocNode(childCenter, childHalf, index);  // may reallocate nodes_
      nodes_[index].child[octant] = child;
      index = child;
    }
    ++d;
  }
  Node& n = nodes_[index];
  e.node = index;
  e.prev = kNone;
  e.next = n.first;
  if (n.first != kNone) entries_[n.first].prev = id;
  n.first = id;
  depth_ = std::max(depth_, d);
}

void Octree::unlink(ProxyId id) {
  Entry& e = entries_[id];
  const std::uint32_t home = e.node;
  if (e.prev != kNone) entries_[e.prev].next = e.next;
  else nodes_[home].first = e.next;
  if (e.next != kNone) entries_[e.next].prev = e.prev;
  e.node = e.prev = e.next = kNone;
  for (std::uint32_t i = home; i != kNone; i = nodes_[i].parent) --nodes_[i].count;
  if (nodes_[root_].count == 0) {  // empty: start afresh at the next insertion
    nodes_.clear();
    freeNodes_.clear();
    root_ = kNone;
    depth_ = 0;
    return;
  }
  // Free the emptied nodes on the way up (every non-root node holds at least one box).
  std::uint32_t i = home;
  while (i != root_ && nodes_[i].count == 0) {
    const std::uint32_t parent = nodes_[i].parent;
    for (std::uint32_t& slot : nodes_[parent].child)
      if (slot == i) slot = kNone;
    freeNode(i);
    i = parent;
  }
}

void Octree::insert(ProxyId id, const Aabb& box) {
  validate(box, "box");
  if (contains(id)) detail::badProxy(kName, id, "is already present");
  if (id >= entries_.size()) entries_.resize(std::size_t(id) + 1);
  entries_[id].box = box;
  growToContain(box);
  place(id);
  ++size_;
}

void Octree::remove(ProxyId id) {
  if (!contains(id)) detail::badProxy(kName, id, "is not present");
  unlink(id);
  --size_;
}

void Octree::update(ProxyId id, const Aabb& box) {
  validate(box, "box");
  if (!contains(id)) detail::badProxy(kName, id, "is not present");
  // Stay when the box still fits the loose bounds of its node and of every ancestor.
  bool stays = true;
  for (std::uint32_t i = entries_[id].node; i != kNone && stays; i = nodes_[i].parent) stays = fits(box, nodes_[i]);
  if (stays) {
    entries_[id].box = box;
    return;
  }
  unlink(id);
  entries_[id].box = box;
  growToContain(box);
  place(id);
}

void Octree::clear() {
  nodes_.clear();
  freeNodes_.clear();
  entries_.clear();
  root_ = kNone;
  size_ = 0;
  depth_ = 0;
}

bool Octree::contains(ProxyId id) const { return id < entries_.size() && entries_[id].node != kNone; }

const Aabb& Octree::bounds(ProxyId id) const { return entries_[id].box; }

int Octree::depthOf(ProxyId id) const {
  int d = 0;
  for (std::uint32_t i = nodes_[entries_[id].node].parent; i != kNone; i = nodes_[i].parent) ++d;
  return d;
}

template <class NodeTest, class LeafTest>
bool Octree::traverse(const NodeTest& nodeTest, const LeafTest& leafTest, ProxyCollector& collector) const {
  if (root_ == kNone || !nodeTest(looseBounds(nodes_[root_]))) return true;
  // Each popped node pushes at most 8 children and the depth is at most kMaxDepth.
  std::uint32_t stack[8 * (kMaxDepth + 1)];
  int top = 0;
  stack[top++] = root_;
  while (top > 0) {
    const Node& n = nodes_[stack[--top]];
    for (std::uint32_t id = n.first; id != kNone; id = entries_[id].next)
      if (leafTest(entries_[id].box) && !collector.add(id)) return false;
    for (const std::uint32_t child : n.child)
      if (child != kNone && nodeTest(looseBounds(nodes_[child]))) stack[top++] = child;
  }
  return true;
}

bool Octree::query(const Aabb& box, ProxyCollector& collector) const {
  const detail::AabbRegion r{box};
  return traverse([&r](const Aabb& b) { return r.node(b); }, [&r](const Aabb& b) { return r.leaf(b); }, collector);
}

bool Octree::query(const Sphere& sphere, ProxyCollector& collector) const {
  const detail::SphereRegion r{sphere};
  return traverse([&r](const Aabb& b) { return r.node(b); }, [&r](const Aabb& b) { return r.leaf(b); }, collector);
}

bool Octree::query(const Obb& box, ProxyCollector& collector) const {
  const detail::ObbRegion r(box);
  return traverse([&r](const Aabb& b) { return r.node(b); }, [&r](const Aabb& b) { return r.leaf(b); }, collector);
}

bool Octree::raycast(const Ray& ray, RayProxyCollector& collector) const {
  if (root_ == kNone) return true;
  const RaySlabs slabs(ray, collector.boxMargin);
  struct Item {
    std::uint32_t node;
    Real t;
  };
  Item stack[8 * (kMaxDepth + 1)];
  int top = 0;
  Real t0;
  if (!rayBoxEntry(slabs, looseBounds(nodes_[root_]), collector.maxT, t0)) return true;
  stack[top++] = {root_, t0};
  while (top > 0) {
    const Item item = stack[--top];
    if (item.t > collector.maxT) continue;  // a nearer hit was found meanwhile
    const Node& n = nodes_[item.node];
    for (std::uint32_t id = n.first; id != kNone; id = entries_[id].next) {
      Real t;
      if (rayBoxEntry(slabs, entries_[id].box, collector.maxT, t) && !collector.add(id, t)) return false;
    }
    // Children entered within maxT, pushed farthest first so the nearest is visited next.
    Item children[8];
    int count = 0;
    for (const std::uint32_t child : n.child) {
      Real t;
      if (child != kNone && rayBoxEntry(slabs, looseBounds(nodes_[child]), collector.maxT, t))
        children[count++] = {child, t};
    }
    detail::insertionSort(children, count, [](const Item& a, const Item& b) { return a.t > b.t; });
    for (int i = 0; i < count; ++i) stack[top++] = children[i];
  }
  return true;
}

void Octree::pairs(PairCollector& collector) {
  for (ProxyId id = 0; id < entries_.size(); ++id) {
    if (entries_[id].node == kNone) continue;
    PairFromQuery c(id, collector);
    query(entries_[id].box, c);
  }
}

}  // namespace crux
