#include <crux/scene/brute_force_broad_phase.hpp>

#include "box_tests.hpp"

namespace crux {
namespace {
constexpr std::uint32_t kNoSlot = 0xffffffffu;
constexpr const char* kName = "BruteForceBroadPhase";
}  // namespace

void BruteForceBroadPhase::insert(ProxyId id, const Aabb& box) {
  validate(box, "box");
  if (contains(id)) detail::badProxy(kName, id, "is already present");
  if (id >= slotOf_.size()) slotOf_.resize(std::size_t(id) + 1, kNoSlot);
  slotOf_[id] = static_cast<std::uint32_t>(ids_.size());
  ids_.push_back(id);
  boxes_.push_back(box);
}

void BruteForceBroadPhase::remove(ProxyId id) {
  if (!contains(id)) detail::badProxy(kName, id, "is not present");
  const std::uint32_t slot = slotOf_[id];
  const ProxyId last = ids_.back();
  ids_[slot] = last;
  boxes_[slot] = boxes_.back();
  slotOf_[last] = slot;
  ids_.pop_back();
  boxes_.pop_back();
  slotOf_[id] = kNoSlot;
}

void BruteForceBroadPhase::update(ProxyId id, const Aabb& box) {
  validate(box, "box");
  if (!contains(id)) detail::badProxy(kName, id, "is not present");
  boxes_[slotOf_[id]] = box;
}

void BruteForceBroadPhase::clear() {
  ids_.clear();
  boxes_.clear();
  slotOf_.clear();
}

bool BruteForceBroadPhase::contains(ProxyId id) const { return id < slotOf_.size() && slotOf_[id] != kNoSlot; }

const Aabb& BruteForceBroadPhase::bounds(ProxyId id) const { return boxes_[slotOf_[id]]; }

template <class Shape>
bool BruteForceBroadPhase::queryShape(const Shape& shape, ProxyCollector& collector) const {
  for (std::size_t i = 0; i < ids_.size(); ++i)
    if (shape.leaf(boxes_[i]) && !collector.add(ids_[i])) return false;
  return true;
}

bool BruteForceBroadPhase::query(const Aabb& box, ProxyCollector& collector) const {
  return queryShape(detail::AabbRegion{box}, collector);
}
bool BruteForceBroadPhase::query(const Sphere& sphere, ProxyCollector& collector) const {
  return queryShape(detail::SphereRegion{sphere}, collector);
}
bool BruteForceBroadPhase::query(const Obb& box, ProxyCollector& collector) const {
  return queryShape(detail::ObbRegion(box), collector);
}

bool BruteForceBroadPhase::raycast(const Ray& ray, RayProxyCollector& collector) const {
  const RaySlabs slabs(ray, collector.boxMargin);
  for (std::size_t i = 0; i < ids_.size(); ++i) {
    Real t;
    if (rayBoxEntry(slabs, boxes_[i], collector.maxT, t) && !collector.add(ids_[i], t)) return false;
  }
  return true;
}

void BruteForceBroadPhase::pairs(PairCollector& collector) {
  for (std::size_t i = 0; i < ids_.size(); ++i)
    for (std::size_t j = i + 1; j < ids_.size(); ++j)
      if (detail::boxesTouch(boxes_[i], boxes_[j]))
        ids_[i] < ids_[j] ? collector.add(ids_[i], ids_[j]) : collector.add(ids_[j], ids_[i]);
}

}  // namespace crux
