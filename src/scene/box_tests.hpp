#pragma once
// Shared by the broad phases (internal): id validation and the box tests every implementation
// uses, so that all of them decide each box identically.

#include <crux/error.hpp>
#include <crux/geometry/overlap.hpp>
#include <crux/mesh/bvh.hpp>
#include <crux/scene/broad_phase.hpp>

#include "../mesh/lanes.hpp"

#include <string>

namespace crux::detail {

/// Throws InvalidInput naming the broad phase and the id.
[[noreturn]] inline void badProxy(const char* what, ProxyId id, const char* problem) {
  throw InvalidInput(std::string(what) + ": proxy id " + std::to_string(id) + " " + problem);
}

/// Closed box overlap, the same decision as crux::overlaps(Aabb, Aabb) (RTCD 4.2.1), inlined:
/// the broad phases make it once per visited node.
inline bool boxesTouch(const Aabb& a, const Aabb& b) {
  return a.min.x() <= b.max.x() && b.min.x() <= a.max.x() && a.min.y() <= b.max.y() && b.min.y() <= a.max.y() &&
         a.min.z() <= b.max.z() && b.min.z() <= a.max.z();
}

/// Box containment (closed): inner inside outer.
inline bool containsBox(const Aabb& outer, const Aabb& inner) {
  return (outer.min.array() <= inner.min.array()).all() && (inner.max.array() <= outer.max.array()).all();
}

/// A region query shape with its test against a leaf's exact box and a conservative test
/// against a node's bounds (never false when some box inside the node passes the leaf test).
struct AabbRegion {
  const Aabb& shape;
  bool leaf(const Aabb& box) const { return boxesTouch(box, shape); }
  bool node(const Aabb& bounds) const { return boxesTouch(bounds, shape); }
};
struct SphereRegion {
  const Sphere& shape;
  // overlaps(Sphere, Aabb) accumulates per-axis excesses that only shrink as the box grows
  // (rounding is monotone), so the node test is conservative.
  bool leaf(const Aabb& box) const { return overlaps(shape, box); }
  bool node(const Aabb& bounds) const { return overlaps(shape, bounds); }
};
struct ObbRegion {
  const Obb& shape;
  Aabb enclosing;
  explicit ObbRegion(const Obb& s) : shape(s), enclosing(enclosingBox(s)) {}
  // Nodes are pruned by the OBB's enclosing box (exact comparisons, so conservative); the SAT
  // decides leaves only.
  bool leaf(const Aabb& box) const { return boxesTouch(box, enclosing) && overlaps(box, shape); }
  bool node(const Aabb& bounds) const { return boxesTouch(bounds, enclosing); }
};

/// rayBoxEntry for the four lane boxes of a wide node at once: bit i of the result is
/// rayBoxEntry(ray, node.laneBounds(i), maxT, entry[i]), entry[i] its entry distance. Each lane
/// goes through the same operations in the same order (grow by the margin, slab parameters,
/// NaN-free max and min), so the answers are rayBoxEntry's, bit for bit; unused lanes (empty
/// boxes) are never entered. Like rayBoxEntry it is monotone in the box, so a lane whose box
/// contains a leaf's box is entered whenever the leaf's is, and no earlier entry is missed.
inline unsigned rayLaneEntry(const RaySlabs& ray, const WideBvhNode& node, Real maxT, Real (&entry)[4]) {
  using namespace mesh_detail;
  const Real* mins[3] = {node.minX, node.minY, node.minZ};
  const Real* maxs[3] = {node.maxX, node.maxY, node.maxZ};
  Lanes tNear = {0, 0, 0, 0}, tFar = {maxT, maxT, maxT, maxT};
  LaneBits inside = {-1, -1, -1, -1};
  for (int i = 0; i < 3; ++i) {
    const Lanes lo = lanesLoad(mins[i]) - ray.margin, hi = lanesLoad(maxs[i]) + ray.margin;
    const Real o = ray.origin[i];
    if (ray.parallel[i]) {
      inside &= (lo <= o) & (o <= hi);
      continue;
    }
    const Lanes t1 = ((ray.negative[i] ? hi : lo) - o) * ray.invDir[i];
    const Lanes t2 = ((ray.negative[i] ? lo : hi) - o) * ray.invDir[i];
    tNear = lanesSelect(t1 > tNear, t1, tNear);
    tFar = lanesSelect(t2 < tFar, t2, tFar);
  }
  std::memcpy(entry, &tNear, sizeof entry);
  return laneMask(inside & (tNear <= tFar));
}

}  // namespace crux::detail
