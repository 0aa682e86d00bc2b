#pragma once
/// @file broad_phase.hpp  The scene's broad phase: a set of boxes keyed by id, answering which
/// boxes a query shape or a ray touches and which boxes overlap each other.
///
/// One interface, three implementations (see the headers next to this one):
///  - BruteForceBroadPhase: tests every box; the reference the tests compare against.
///  - Octree: a loose octree that grows to contain whatever is inserted (nothing is dropped).
///  - DynamicAabbTree: fattened boxes in an incrementally balanced binary tree (the default).
/// Every implementation answers exactly the same sets: the decision for one box is made by the
/// same function (the geometry layer's closed-set tests, or the ray slab test below) in all of
/// them; internal nodes only prune subtrees that cannot contain an answer.
///
/// Results reach the caller through collectors (one traversal per query kind, parameterised by
/// the collector), in no particular order unless stated. The free functions at the end return
/// sorted vectors for tests and tools. Region and ray queries never allocate and never throw
/// (the dynamic tree's pairs() reuses buffers it keeps); insert/remove/update validate their
/// arguments and throw crux::InvalidInput.

#include <crux/geometry/raycast.hpp>
#include <crux/geometry/shapes.hpp>

#include <cstdint>
#include <memory>
#include <string_view>
#include <utility>
#include <vector>

namespace crux {

/// Key of a box in a broad phase (the scene uses its ModelIds). Implementations index arrays by
/// id, so memory grows with the largest id in use: keep ids dense (ModelHierarchy reuses them).
using ProxyId = std::uint32_t;

/// Receives the ids whose boxes a region query touches, each once. Returning false stops the query.
class ProxyCollector {
 public:
  virtual ~ProxyCollector() = default;
  virtual bool add(ProxyId id) = 0;
};

/// Receives the ids whose boxes a ray enters within `maxT`, each once, with the entry distance
/// (world units along the ray; 0 when the origin is inside the box). Trees visit nearer subtrees
/// first; a collector that finds hits lowers `maxT` and every box entered beyond it is pruned
/// (a box entered exactly at maxT is still visited). Returning false stops the query.
class RayProxyCollector {
 public:
  virtual ~RayProxyCollector() = default;
  virtual bool add(ProxyId id, Real entryT) = 0;
  /// Boxes entered beyond this distance are skipped; read by the traversal before every test.
  Real maxT = kNoLimit;
  /// Every box is tested grown by this margin (>= 0) on every side; set once before the query.
  /// The scene uses it to absorb the rounding of the slab test far from the origin.
  Real boxMargin = 0;
};

/// Receives every pair of ids whose boxes overlap, each pair once, with a < b.
class PairCollector {
 public:
  virtual ~PairCollector() = default;
  virtual void add(ProxyId a, ProxyId b) = 0;
};

/// The available broad phases.
enum class BroadPhaseKind { BruteForce, Octree, DynamicAabbTree };

/// "brute_force", "octree", "dynamic_aabb_tree".
std::string_view broadPhaseName(BroadPhaseKind kind);

/// A set of closed axis-aligned boxes keyed by ProxyId.
class BroadPhase {
 public:
  virtual ~BroadPhase() = default;

  virtual BroadPhaseKind kind() const = 0;
  /// Adds a box. Throws InvalidInput when `id` is present or the box is invalid (validate(Aabb)).
  virtual void insert(ProxyId id, const Aabb& box) = 0;
  /// Removes a box. Throws InvalidInput when `id` is absent.
  virtual void remove(ProxyId id) = 0;
  /// Replaces the box of `id`. Throws InvalidInput when `id` is absent or the box is invalid.
  virtual void update(ProxyId id, const Aabb& box) = 0;
  /// Removes every box.
  virtual void clear() = 0;

  virtual bool contains(ProxyId id) const = 0;
  /// The box stored for `id` (exactly as inserted/updated). Precondition: contains(id).
  virtual const Aabb& bounds(ProxyId id) const = 0;
  /// Number of boxes.
  virtual std::size_t size() const = 0;

  /// Ids whose boxes touch the shape (closed sets: touching counts). Returns false when the
  /// collector stopped the query.
  virtual bool query(const Aabb& box, ProxyCollector& collector) const = 0;
  virtual bool query(const Sphere& sphere, ProxyCollector& collector) const = 0;
  virtual bool query(const Obb& box, ProxyCollector& collector) const = 0;
  /// Ids whose boxes the ray enters within collector.maxT (rayBoxEntry decides), nearer first
  /// where the structure allows. Returns false when the collector stopped the query.
  virtual bool raycast(const Ray& ray, RayProxyCollector& collector) const = 0;
  /// Every pair of ids whose boxes overlap (overlaps(Aabb, Aabb)). Not const: the dynamic tree
  /// brings its persistent pair cache up to date; the others keep no state for it.
  virtual void pairs(PairCollector& collector) = 0;
};

/// Makes a broad phase of the given kind with default parameters.
std::unique_ptr<BroadPhase> makeBroadPhase(BroadPhaseKind kind);

/// A ray prepared for many box tests: unit direction and its reciprocal, and the margin every
/// box is grown by. A component whose reciprocal is not finite is treated as parallel to that
/// slab.
struct RaySlabs {
  Vec3 origin = Vec3::Zero();
  Vec3 invDir = Vec3::Ones();
  bool parallel[3] = {false, false, false};
  bool negative[3] = {false, false, false};  ///< invDir[i] < 0: the ray enters through max[i]
  Real margin = 0;

  explicit RaySlabs(const Ray& ray, Real boxMargin = 0);
};

/// The slab test (Kay & Kajiya 1986; RTCD 5.3.3) in world units: the distance at which the ray
/// enters the closed box grown by ray.margin (0 if the origin is inside), when it does so within
/// [0, maxT].
/// Evaluated with the same rounding for every box, so a box containing another is never
/// entered later or left earlier: pruning by a node's box never loses a leaf the brute force
/// reports. Every broad phase decides rays with this function.
inline bool rayBoxEntry(const RaySlabs& ray, const Aabb& box, Real maxT, Real& entryT) {
  Real tNear = 0, tFar = maxT;
  for (int i = 0; i < 3; ++i) {
    const Real lo = box.min[i] - ray.margin, hi = box.max[i] + ray.margin;
    if (ray.parallel[i]) {
      if (ray.origin[i] < lo || ray.origin[i] > hi) return false;
      continue;
    }
    const Real t1 = ((ray.negative[i] ? hi : lo) - ray.origin[i]) * ray.invDir[i];
    const Real t2 = ((ray.negative[i] ? lo : hi) - ray.origin[i]) * ray.invDir[i];
    tNear = t1 > tNear ? t1 : tNear;
    tFar = t2 < tFar ? t2 : tFar;
  }
  if (!(tNear <= tFar)) return false;
  entryT = tNear;
  return true;
}

/// An axis-aligned box containing the OBB, rounded outwards (trees prune by it; the exact
/// box–OBB decision is overlaps(Aabb, Obb) at the leaves).
Aabb enclosingBox(const Obb& box);

/// Sorted ids whose boxes touch the shape.
std::vector<ProxyId> queryIds(const BroadPhase& broadPhase, const Aabb& box);
std::vector<ProxyId> queryIds(const BroadPhase& broadPhase, const Sphere& sphere);
std::vector<ProxyId> queryIds(const BroadPhase& broadPhase, const Obb& box);
/// (id, entry distance) of every box the ray enters within maxT, sorted by id.
std::vector<std::pair<ProxyId, Real>> rayCandidates(const BroadPhase& broadPhase, const Ray& ray,
                                                    Real maxT = kNoLimit);
/// Every overlapping pair (a < b), sorted.
std::vector<std::pair<ProxyId, ProxyId>> overlappingPairs(BroadPhase& broadPhase);

}  // namespace crux
