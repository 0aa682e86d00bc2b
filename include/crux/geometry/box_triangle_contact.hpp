#pragma once
/// @file box_triangle_contact.hpp  Closed-form contact manifold of an axis-aligned box (in its
/// own frame) against one triangle by the separating-axis test: the box fast path of the mesh
/// narrow phase (mesh/mesh_contact.hpp), without GJK/EPA.
///
/// Conventions (contact.hpp): A is the triangle, B the box; `out.normal` is the unit direction
/// from B to A; pointA − pointB = separation·normal for every point; a point is reported when its
/// separation is <= margin. featureA is a triangle feature (Vertex i, Edge featureId(Edge,
/// min·64+max) of its corners, Face 0 front — normal (b−a)×(c−a) — or 1 back), featureB a box
/// feature numbered as contact.cpp / ConvexShape::vertex number them (Face 2·axis + (side > 0),
/// Vertex by sign bits, Edge min·64+max of its two vertex indices).
///
/// Preconditions: the primitive layer's (precondition.hpp, debugPreconditions): finite inputs,
/// non-zero ray directions and plane normals, radii and half extents >= 0, AABB min <= max.
/// Checked in debug builds (CRUX_CHECK_PRIMITIVE_PRECONDITIONS, on without NDEBUG): an abort
/// naming the query. Unchecked in release builds: an unspecified answer, never undefined
/// behaviour.

#include <crux/geometry/contact.hpp>
#include <crux/geometry/triangle_class.hpp>

namespace crux {

/// An edge–edge axis must beat the best face axis (box face or triangle normal) by more than
/// this × the pair's length scale (max |half_i|, max |corner coordinate|, rounded up to a power
/// of two) to be chosen; the triangle normal is preferred over a box face within the same band.
/// Face contacts stay face contacts when the axes tie (a box edge lying on the triangle's plane,
/// a triangle edge on a box face), as the relative face bias of Box2D's and Bullet's box–box
/// does. A separating axis is never biased away (the verdict is unaffected). In addition, an
/// edge axis within contact.hpp's feature angle (2°) of the best face axis gives way to that
/// face, as contact.cpp turns a normal within 2° of a face into the face's normal: then the
/// depth along the normal exceeds the minimum penetration (by design, as in contact.cpp).
inline constexpr double kBoxTriangleFaceBias = 1e-6;

/// A box-axis × triangle-edge cross product shorter than this × |edge| is skipped as parallel
/// (those cross products are exact — a permutation of the edge's components — so only parallel
/// and near-parallel edges are skipped; the face axes cover them up to this × |edge|).
inline constexpr double kBoxTriangleParallelSin = 1e-9;

// A degenerate triangle (kTriangleDegenerateRelative, triangle_class.hpp) is the segment or
// point it spans: its normal axis drops out (its edges remain). A thin triangle (not a
// reference face, kTriangleFaceRelative) keeps its normal axis for the verdict but is never the
// reference face, as in contacts() and the capsule routine: when its normal is the chosen axis,
// the box face within the feature angle of that normal becomes the axis and the reference (the
// triangle is clipped against it); with no such face the answer is the single GJK/EPA pair, in
// which the triangle's feature is an edge or a corner.

/// Contact manifold of a triangle (A) against a box (B) given in the box's frame: the box is
/// centred at the origin, axis-aligned, with half extents `half` (>= 0; a zero half extent is a
/// flat box, a closed set). The triangle may be degenerate (a segment or a point).
///
/// Separating-axis test (Gottschalk, Lin & Manocha, OBBTree 1996; Akenine-Möller 2001; Eberly;
/// Ericson, Real-Time Collision Detection §5.2.9): the 3 box face normals, the triangle normal
/// and the 9 box-axis × triangle-edge cross products, projected unnormalised (so on integer-grid
/// inputs the signs are exact and touching gives separation exactly 0). The axis of maximum
/// separation (minimum penetration; with a margin, the maximum separation, which must be <=
/// margin) is chosen with the face biases above. Points: a face axis clips the other shape's
/// supporting feature along the normal (contact.hpp's rule: face within 2°, else a perpendicular
/// edge, else a vertex) against the reference face's side planes (Sutherland–Hodgman, as
/// contact.cpp does), keeping the points with separation <= margin and reducing more than 4 to
/// the deepest plus the area-maximising ones; an edge axis gives the closest points of the two
/// edges. When the SAT axis does not realise the pair's distance (separated pairs whose closest
/// features are not a face and a point over it, or nothing survives the clip) the routine
/// answers with one point, the GJK/EPA pair of gjk.hpp's `distance()` (what `contacts()` uses for
/// its normal), with the features supporting that normal; so the verdict is always the generic
/// one's: a contact iff the distance is <= margin.
///
/// Returns out.count > 0. Never throws, never allocates; a NaN or negative margin counts as 0.
/// Everything runs in double whatever Real is, after an exact power-of-two rescaling of the
/// inputs (no overflow or NaN for finite inputs).
///
/// Shortcuts (same output bit for bit as the full test, checked against it by
/// test_box_triangle_contact on random and integer-grid cases): the 3 edge axes of a box axis
/// (e_i × each triangle edge) are skipped when a triangle corner lies deeply enough inside the
/// box's two other slabs that none of them can win or separate (clearance bound, see the
/// source); along a box face the triangle's supporting feature is chosen on single components; a
/// single-corner contact is written out directly.
bool boxTriangleContacts(const Vec3& half, const Triangle& tri, Real margin, ContactManifold& out);

namespace detail {
/// boxTriangleContacts without its shortcuts (every axis, the general feature and clipping
/// paths): the reference the shortcuts are tested against, bit for bit. Not for production use.
bool boxTriangleContactsFullSat(const Vec3& half, const Triangle& tri, Real margin, ContactManifold& out);
}  // namespace detail

}  // namespace crux
