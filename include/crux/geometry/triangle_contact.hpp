#pragma once
/// @file triangle_contact.hpp  Closed-form contact manifolds of a sphere or a capsule against one
/// triangle: the per-triangle fast path of the mesh narrow phase (mesh/mesh_contact.hpp).
///
/// Both routines answer what the generic `contacts(ConvexShape(tri), I, shape, I, margin, out)`
/// of contact.hpp answers (same normal convention, separations, points, clipping and feature
/// ids), without GJK/EPA: everything is in one frame (the caller's, e.g. the mesh's), in double
/// whatever Real is, on fixed-size data (no heap, no exceptions; but the exact margin decision
/// near the margin may spill its expansions to the heap, as contact.hpp's contacts()).
///
/// Conventions (contact.hpp): A is the triangle, B the sphere/capsule; `out.normal` is the unit
/// direction from B to A; pointA − pointB = separation·normal for every point; a point is
/// reported when its separation is <= margin (speculative contacts). featureA is the
/// triangle's supporting feature along −normal by contact.hpp's rule (the face — 0 front, normal
/// (b−a)×(c−a), 1 back — when within kContactFaceAngleCos of the normal, else an edge
/// featureId(Edge, min·64+max) when perpendicular to it within the same angle, else the vertex);
/// featureB is the sphere's Vertex 0, the capsule's end (Vertex 0/1) or its Edge (0·64+1) for a
/// point cut out of the segment by the clipping.
///
/// Degenerate triangles (kTriangleDegenerateRelative, triangle_class.hpp) are the segment or
/// point they span: no face, closest points over their three edges.
///
/// Preconditions: the primitive layer's (precondition.hpp, debugPreconditions): finite inputs,
/// non-zero ray directions and plane normals, radii and half extents >= 0, AABB min <= max.
/// Checked in debug builds (CRUX_CHECK_PRIMITIVE_PRECONDITIONS, on without NDEBUG): an abort
/// naming the query. Unchecked in release builds: an unspecified answer, never undefined behaviour.

#include <crux/geometry/contact.hpp>
#include <crux/geometry/triangle_class.hpp>

namespace crux {

/// Sphere (centre, radius >= 0) against a triangle: the closest point of the triangle to the
/// centre (Ericson, RTCD 5.1.5, Voronoi regions, in double; a degenerate triangle by its
/// edges; a thin triangle (kTriangleThinRelative), as closestPoint(Triangle) takes it:
/// no region tests), one contact point. When the centre lies on the triangle (within kGjkScaleTolerance ×
/// the pair's length scale, max|vertex| + |centre| + radius, the generic routine's flat case) the
/// normal is minus the front face normal: the sphere is taken to be on the front side,
/// deterministically (a degenerate triangle: a fixed perpendicular of its longest edge, or −z
/// when it is a point). A plane test rejects far triangles before any closest-point work.
/// Returns out.count > 0 (count is 0 or 1). `margin` must be >= 0 (not checked: fast path).
bool sphereTriangleContacts(const Triangle& tri, const Vec3& centre, Real radius, Real margin, ContactManifold& out);

/// One sphere–triangle contact without feature ids (the mesh narrow phase's form).
struct SphereTriangleContact {
  Vec3 pointA = Vec3::Zero();  ///< on the triangle
  Vec3 pointB = Vec3::Zero();  ///< on the sphere
  Vec3 normal = Vec3::UnitZ(); ///< unit, B→A
  Real separation = 0;         ///< signed, <= margin
  static constexpr int kFace = -1;        ///< region: the face (or the centre on the triangle)
  static constexpr int kDegenerate = -2;  ///< region: a degenerate triangle (no face, no regions)
  /// Where the closest point of the triangle lies (its Voronoi region, RTCD 5.1.5): kFace (the
  /// normal is ± the face normal), 0..2 the edge from corner i to corner i+1 (mod 3) (a, b, c
  /// = corners 0, 1, 2), 3..5 the corner region − 3, or kDegenerate.
  int region = kDegenerate;
  /// Unit face normal (b−a)×(c−a)/|…| (computed in double, rounded to Real) unless kDegenerate.
  Vec3 face = Vec3::UnitZ();
};

/// sphereTriangleContacts without the feature ids (featureA's computation is skipped): the
/// same point, normal and separation bit for bit, plus the closest point's region and the face
/// normal. For the mesh narrow phase, whose points carry the triangle index instead.
bool sphereTriangleContact(const Triangle& tri, const Vec3& centre, Real radius, Real margin,
                           SphereTriangleContact& out);

/// Capsule (segment [p0, p1] ⊕ ball of `radius`) against a triangle.
///   - Separated cores: the closest points of the segment and the triangle (the minimum over
///     the segment–edge pairs, RTCD 5.1.9, and the endpoint–face projections inside the face;
///     RTCD 5.1.10's decomposition). A thin triangle (kTriangleThinRelative) has an
///     unreliable plane: its endpoints' closest points as closestPoint(Triangle) takes them, no
///     plane reject, and crossing decided by the exact segment–triangle test.
///   - Crossing cores (the segment meets the triangle): the minimum translation of the core
///     pair by the separating-axis test on the faces of their Minkowski difference (a prism:
///     ±face normal, and ±(edge × segment) for the three edges), i.e. the EPA depth of the
///     generic routine, with its witness points.
/// Then, as contact.hpp: the triangle face (or a parallel edge) and the capsule's segment, when
/// the segment is perpendicular to the normal within kContactFaceAngleCos, are clipped against
/// each other (up to 2 points, a capsule lying along the face), else the one closest/deepest
/// pair; clipped points coinciding on both bodies (within contact.cpp's rounding budget) are
/// one, the deepest kept, as contact.cpp. Returns out.count > 0. `margin` must be >= 0 (not
/// checked: fast path).
bool capsuleTriangleContacts(const Triangle& tri, const Vec3& p0, const Vec3& p1, Real radius, Real margin,
                             ContactManifold& out);

}  // namespace crux
