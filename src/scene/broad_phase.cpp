#include <crux/scene/broad_phase.hpp>

#include <crux/scene/brute_force_broad_phase.hpp>
#include <crux/scene/dynamic_aabb_tree.hpp>
#include <crux/scene/octree.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace crux {
namespace {

/// Relative padding of enclosingBox's Wide computation (a few rounding errors of the sums).
constexpr Wide kEnclosingPadding = 16 * std::numeric_limits<Wide>::epsilon();

Real roundDown(Wide x) {
  Real r = static_cast<Real>(x);
  if (Wide(r) > x) r = std::nextafter(r, -std::numeric_limits<Real>::infinity());
  return r;
}
Real roundUp(Wide x) {
  Real r = static_cast<Real>(x);
  if (Wide(r) < x) r = std::nextafter(r, std::numeric_limits<Real>::infinity());
  return r;
}

class VectorCollector final : public ProxyCollector {
 public:
  std::vector<ProxyId> ids;
  bool add(ProxyId id) override {
    ids.push_back(id);
    return true;
  }
};

class RayVectorCollector final : public RayProxyCollector {
 public:
  std::vector<std::pair<ProxyId, Real>> hits;
  bool add(ProxyId id, Real t) override {
    hits.emplace_back(id, t);
    return true;
  }
};

class PairVectorCollector final : public PairCollector {
 public:
  std::vector<std::pair<ProxyId, ProxyId>> pairs;
  void add(ProxyId a, ProxyId b) override { pairs.emplace_back(a, b); }
};

template <class Shape>
std::vector<ProxyId> sortedQuery(const BroadPhase& broadPhase, const Shape& shape) {
  VectorCollector c;
  broadPhase.query(shape, c);
  std::sort(c.ids.begin(), c.ids.end());
  return std::move(c.ids);
}

}  // namespace

std::string_view broadPhaseName(BroadPhaseKind kind) {
  switch (kind) {
    case BroadPhaseKind::BruteForce: return "brute_force";
    case BroadPhaseKind::Octree: return "octree";
    case BroadPhaseKind::DynamicAabbTree: return "dynamic_aabb_tree";
  }
  return "unknown";
}

std::unique_ptr<BroadPhase> makeBroadPhase(BroadPhaseKind kind) {
  switch (kind) {
    case BroadPhaseKind::BruteForce: return std::make_unique<BruteForceBroadPhase>();
    case BroadPhaseKind::Octree: return std::make_unique<Octree>();
    case BroadPhaseKind::DynamicAabbTree: return std::make_unique<DynamicAabbTree>();
  }
  return std::make_unique<DynamicAabbTree>();
}

RaySlabs::RaySlabs(const Ray& ray, Real boxMargin) : origin(ray.origin), margin(boxMargin) {
  const WVec3 d = wide(ray.dir);
  const WVec3 u = d / d.norm();
  for (int i = 0; i < 3; ++i) {
    const Real ui = static_cast<Real>(u[i]);
    const Real inv = Real(1) / ui;
    parallel[i] = ui == 0 || !std::isfinite(inv);
    invDir[i] = parallel[i] ? Real(0) : inv;
    negative[i] = invDir[i] < 0;
  }
}

Aabb enclosingBox(const Obb& box) {
  Aabb out;
  for (int i = 0; i < 3; ++i) {
    Wide e = 0;
    for (int j = 0; j < 3; ++j) e += std::abs(Wide(box.axes(i, j))) * Wide(box.half[j]);
    const Wide c = box.center[i];
    const Wide pad = kEnclosingPadding * (std::abs(c) + e);
    out.min[i] = roundDown(c - e - pad);
    out.max[i] = roundUp(c + e + pad);
  }
  return out;
}

std::vector<ProxyId> queryIds(const BroadPhase& broadPhase, const Aabb& box) { return sortedQuery(broadPhase, box); }
std::vector<ProxyId> queryIds(const BroadPhase& broadPhase, const Sphere& sphere) {
  return sortedQuery(broadPhase, sphere);
}
std::vector<ProxyId> queryIds(const BroadPhase& broadPhase, const Obb& box) { return sortedQuery(broadPhase, box); }

std::vector<std::pair<ProxyId, Real>> rayCandidates(const BroadPhase& broadPhase, const Ray& ray, Real maxT) {
  RayVectorCollector c;
  c.maxT = maxT;
  broadPhase.raycast(ray, c);
  std::sort(c.hits.begin(), c.hits.end());
  return std::move(c.hits);
}

std::vector<std::pair<ProxyId, ProxyId>> overlappingPairs(BroadPhase& broadPhase) {
  PairVectorCollector c;
  broadPhase.pairs(c);
  std::sort(c.pairs.begin(), c.pairs.end());
  return std::move(c.pairs);
}

}  // namespace crux
