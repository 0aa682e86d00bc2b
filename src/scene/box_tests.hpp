#pragma once
// Shared by the broad phases (internal): id validation and the box tests every implementation
// uses, so that all of them decide each box identically.

#include <crux/error.hpp>
#include <crux/geometry/overlap.hpp>
#include <crux/scene/broad_phase.hpp>

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

}  // namespace crux::detail
