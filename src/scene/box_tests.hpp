#pragma once
// Shared by the broad phases (internal): id validation and the box tests every implementation
// uses, so that all of them decide each box identically.

#include <crux/error.hpp>
#include <crux/geometry/overlap.hpp>
#include <crux/mesh/bvh.hpp>
#include <crux/scene/broad_phase.hpp>

#include "geometry/unchecked.hpp"
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
  bool leaf(const Aabb& box) const { return unchecked::overlaps(shape, box); }
  bool node(const Aabb& bounds) const { return unchecked::overlaps(shape, bounds); }
};
struct ObbRegion {
  const Obb& shape;
  Aabb enclosing;
  explicit ObbRegion(const Obb& s) : shape(s), enclosing(enclosingBox(s)) {}
  // Nodes are pruned by the OBB's enclosing box (exact comparisons, so conservative); the SAT
  // decides leaves only.
  bool leaf(const Aabb& box) const { return boxesTouch(box, enclosing) && unchecked::overlaps(box, shape); }
  bool node(const Aabb& bounds) const { return boxesTouch(bounds, enclosing); }
};

/// rayBoxEntry for the four lane boxes of a wide node at once, for one ray: enter() sets bit i
/// of its result exactly when rayBoxEntry(ray, node.laneBounds(i), maxT, entry[i]) enters lane
/// i's box, with entry[i] its entry distance. Each lane goes through the same operations in the
/// same order (the plane grown by the margin, minus the origin, times the inverse direction;
/// NaN-free max and min), so the answers are rayBoxEntry's, bit for bit; unused lanes (empty
/// boxes) are never entered. Like rayBoxEntry it is monotone in the box, so a lane whose box
/// contains a leaf's box is entered whenever the leaf's is, and no earlier entry is missed.
/// What depends on the ray alone (which coordinate array holds each axis's entry and exit
/// planes, the signed margins, the origin and inverse direction in all four lanes) is set up
/// once per ray; an axis parallel to the ray takes rayBoxEntry's containment test instead.
class RayLaneTest {
 public:
  explicit RayLaneTest(const RaySlabs& ray) : ray_(ray) {
    using namespace mesh_detail;
    for (int i = 0; i < 3; ++i) {
      parallel_ = parallel_ || ray.parallel[i];
      // WideBvhNode's coordinate arrays: minX, minY, minZ, maxX, maxY, maxZ (4 Reals each).
      // rayBoxEntry's lo = min - margin and hi = max + margin, as plane + (-margin) and
      // plane + margin (the same IEEE operation).
      near_[i] = ray.negative[i] ? 4 * (3 + i) : 4 * i;
      far_[i] = ray.negative[i] ? 4 * i : 4 * (3 + i);
      nearMargin_[i] = ray.negative[i] ? lanesSplat(ray.margin) : lanesSplat(-ray.margin);
      farMargin_[i] = ray.negative[i] ? lanesSplat(-ray.margin) : lanesSplat(ray.margin);
      origin_[i] = lanesSplat(ray.origin[i]);
      invDir_[i] = lanesSplat(ray.invDir[i]);
    }
  }

  unsigned enter(const WideBvhNode& node, Real maxT, Real (&entry)[4]) const {
    using namespace mesh_detail;
    if (parallel_) return enterParallel(node, maxT, entry);
    const Real* coords = node.minX;
    Lanes tNear = {0, 0, 0, 0}, tFar = lanesSplat(maxT);
    for (int i = 0; i < 3; ++i) {
      const Lanes t1 = ((lanesLoad(coords + near_[i]) + nearMargin_[i]) - origin_[i]) * invDir_[i];
      const Lanes t2 = ((lanesLoad(coords + far_[i]) + farMargin_[i]) - origin_[i]) * invDir_[i];
      tNear = lanesMax(t1, tNear);  // t1 > tNear ? t1 : tNear, as rayBoxEntry
      tFar = lanesMin(t2, tFar);    // t2 < tFar ? t2 : tFar
    }
    std::memcpy(entry, &tNear, sizeof entry);
    return laneMask(tNear <= tFar);
  }

 private:
  /// The general form (some axis parallel to the ray: containment on that axis).
  unsigned enterParallel(const WideBvhNode& node, Real maxT, Real (&entry)[4]) const {
    using namespace mesh_detail;
    const Real* mins[3] = {node.minX, node.minY, node.minZ};
    const Real* maxs[3] = {node.maxX, node.maxY, node.maxZ};
    Lanes tNear = {0, 0, 0, 0}, tFar = lanesSplat(maxT);
    LaneBits inside = {-1, -1, -1, -1};
    for (int i = 0; i < 3; ++i) {
      const Lanes lo = lanesLoad(mins[i]) - ray_.margin, hi = lanesLoad(maxs[i]) + ray_.margin;
      const Real o = ray_.origin[i];
      if (ray_.parallel[i]) {
        inside &= (lo <= o) & (o <= hi);
        continue;
      }
      const Lanes t1 = ((ray_.negative[i] ? hi : lo) - o) * ray_.invDir[i];
      const Lanes t2 = ((ray_.negative[i] ? lo : hi) - o) * ray_.invDir[i];
      tNear = lanesMax(t1, tNear);
      tFar = lanesMin(t2, tFar);
    }
    std::memcpy(entry, &tNear, sizeof entry);
    return laneMask(inside & (tNear <= tFar));
  }

  const RaySlabs& ray_;
  bool parallel_ = false;
  int near_[3], far_[3];
  mesh_detail::Lanes nearMargin_[3], farMargin_[3], origin_[3], invDir_[3];
};

}  // namespace crux::detail
