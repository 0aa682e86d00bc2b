#pragma once
/// @file contact.hpp  Contact manifolds of convex pairs for rigid-body engines.
///
/// `contacts(a, ta, b, tb, margin, out)` fills a fixed-capacity manifold (no heap) with up to 4
/// points. The normal comes from GJK/EPA (gjk.hpp); the points from reference-face clipping: the
/// supporting features of A (along -normal) and B (along +normal) are taken — a face when its
/// normal is within kContactFaceAngleCos of the contact normal, else an edge when one is
/// perpendicular to it within the same angle, else a vertex — and the incident feature is
/// clipped against the side planes of the reference feature (Sutherland–Hodgman, as in
/// Gottschalk's and Catto's box–box clipping; Box2D `b2ClipPolygons`, Bullet btBoxBoxDetector),
/// keeping points whose separation along the normal is <= margin. More than 4 points are
/// reduced to the deepest, the farthest from it, the one spanning the largest triangle with them
/// and the one adding most area outside it (Gregorius, GDC 2015; the same rule as mesh contacts),
/// stopping early on points coincident or collinear within rounding.
///
/// Ill-conditioned features: a sliver triangle (|(b−a)×(c−a)| small against its longest
/// edge squared, so its computed plane is off by more than a few ulps) is never the reference
/// face — it is clipped against the other shape's face, or as its supporting edge. Two edges
/// within the feature angle are clipped only when every clipped point's closest point on the
/// reference edge lies along the normal within a few ulps of the scale (else — skew edges —
/// the pair reports the single GJK/EPA point), so every point lies on both shapes.
///
/// Conventions: `normal` is the unit direction from B to A; for every point,
/// pointA - pointB = separation·normal (separation < 0 is penetration; depth = -separation).
/// Rounded shapes (sphere, capsule) report points on their surfaces. Poses are applied as in
/// gjk.hpp: an axis-aligned rotation (quarter and half turns) as its exact signed permutation, so
/// a grid pair at separation exactly = margin has its contact.

#include <crux/geometry/gjk.hpp>

namespace crux {

/// Feature ids: (kind << 24) | index, kind one of these. A box's faces are 2·axis + (side > 0),
/// its vertices as ConvexShape::vertex; a hull's are its face and vertex indices; a triangle's
/// faces are 0 (front: normal (b-a)×(c-a)) and 1 (back). A mesh layer can put its triangle
/// index in the shape-level id it keeps alongside.
enum class FeatureKind : std::uint32_t { Vertex = 1, Edge = 2, Face = 3 };
/// Packs a feature id.
inline std::uint32_t featureId(FeatureKind kind, std::uint32_t index) {
  return (static_cast<std::uint32_t>(kind) << 24) | (index & 0xFFFFFFu);
}

/// One contact point.
struct ContactPoint {
  Vec3 pointA = Vec3::Zero();  ///< world position on A
  Vec3 pointB = Vec3::Zero();  ///< world position on B
  Real separation = 0;         ///< signed: > 0 apart (speculative), < 0 penetrating
  std::uint32_t featureA = 0;  ///< feature of A the point lies on (featureId)
  std::uint32_t featureB = 0;  ///< feature of B
};

/// Up to kMaxContactPoints points sharing one normal. Plain value, no heap.
struct ContactManifold {
  static constexpr int kMaxContactPoints = 4;
  Vec3 normal = Vec3::UnitZ();  ///< unit, from B to A
  int count = 0;
  ContactPoint points[kMaxContactPoints];

  /// Deepest penetration: max(0, -min separation); 0 for an empty manifold.
  Real depth() const;
};

/// Cosine of the angle within which a face (or edge) counts as aligned with (perpendicular to)
/// the contact normal when choosing the clipping features: cos(2°).
inline constexpr Real kContactFaceAngleCos = Real(0.99939082701909573);

/// Contact manifold of A and B: the points within `margin` (>= 0; separation <= margin) along
/// the GJK/EPA normal. Returns out.count > 0. Never throws (but std::bad_alloc below), and
/// allocates only in one rare case: when the distance is within rounding of the margin, the
/// margin is decided exactly — for a core of 1-3 points (sphere, capsule, triangle, hull of <= 3
/// vertices) by withinDistance (overlap.hpp), against a box or larger hull with its boundary
/// triangles, and for two boxes or hulls by containment or a pair of boundary triangles
/// (polytopesWithin, contact.cpp) — and when the filter cannot decide, the exact expansions may
/// outgrow their inline storage (12 limbs; not seen on the tests' grid cases).
bool contacts(const ConvexShape& a, const Transform& ta, const ConvexShape& b, const Transform& tb, Real margin,
              ContactManifold& out);

/// Throws InvalidInput("margin: ...") unless the contact margin is finite and >= 0 (every
/// contacts() query checks its margin with it before looking at the shapes).
void validateContactMargin(Real margin);

}  // namespace crux
