#pragma once
/// @file brute_force_broad_phase.hpp  The reference broad phase: every query tests every box.

#include <crux/scene/broad_phase.hpp>

#include <vector>

namespace crux {

/// Boxes in one dense array; queries are linear, pairs quadratic (all n(n-1)/2 box pairs).
/// Kept deliberately simple: it is what the tests compare the trees with ("can be used as a
/// reference", as Jolt's BroadPhaseBruteForce). Rays are reported in id-insertion order, not
/// front to back.
class BruteForceBroadPhase final : public BroadPhase {
 public:
  BroadPhaseKind kind() const override { return BroadPhaseKind::BruteForce; }
  void insert(ProxyId id, const Aabb& box) override;
  void remove(ProxyId id) override;
  void update(ProxyId id, const Aabb& box) override;
  void clear() override;
  bool contains(ProxyId id) const override;
  const Aabb& bounds(ProxyId id) const override;
  std::size_t size() const override { return ids_.size(); }

  bool query(const Aabb& box, ProxyCollector& collector) const override;
  bool query(const Sphere& sphere, ProxyCollector& collector) const override;
  bool query(const Obb& box, ProxyCollector& collector) const override;
  bool raycast(const Ray& ray, RayProxyCollector& collector) const override;
  void pairs(PairCollector& collector) override;

 private:
  template <class Shape>
  bool queryShape(const Shape& shape, ProxyCollector& collector) const;

  std::vector<ProxyId> ids_;            // dense: live ids
  std::vector<Aabb> boxes_;             // dense: their boxes
  std::vector<std::uint32_t> slotOf_;   // id -> index into ids_/boxes_, or kNoSlot
};

}  // namespace crux
