#pragma once
/// @file triangle_distance.hpp  Closest points between two triangles (every degenerate case).
///
/// The distance between two triangles that do not intersect is realised either by a pair of
/// edges or by a vertex of one and the face of the other (Ericson, "Real-Time Collision
/// Detection" §5.1.9 segment–segment closest points and §5.1.5/§5.1.8 point–triangle; the same
/// case analysis as Eberly's "Distance Between Two Triangles in 3D"), so the answer is the minimum
/// over the 9 edge pairs and the 6 vertex–face projections that fall inside the face.
/// Intersecting triangles (decided by the exact triangle–triangle test, overlap.hpp) get
/// distance 0 and a common point (an edge of one crossing the other, found by the same edge
/// machinery). Degenerate triangles (collinear corners, repeated corners) are the segment or
/// point they span: their "edges" still cover them and they have no face. Parallel and coplanar
/// pairs need no special case: parallel edge pairs are clamped (RTCD 5.1.9) and the face
/// projections cover the interior. Everything is computed in double whatever Real is.
///
/// Preconditions: the primitive layer's (precondition.hpp, debugPreconditions): finite inputs,
/// non-zero ray directions and plane normals, radii and half extents >= 0, AABB min <= max.
/// Checked in debug builds (CRUX_CHECK_PRIMITIVE_PRECONDITIONS, on without NDEBUG): an abort
/// naming the query. Unchecked in release builds: an unspecified answer, never undefined behaviour.

#include <crux/geometry/contact.hpp>
#include <crux/geometry/shapes.hpp>

#include <cstdint>

namespace crux {

/// Closest points of two triangles. Feature ids are contact.hpp's featureId(kind, index):
/// Vertex i = corner i (a, b, c), Edge i = the edge from corner i to corner (i+1) mod 3,
/// Face 0 = the interior. A point at a segment end is reported as the vertex.
struct TriangleDistanceResult {
  Real distance = 0;           ///< Euclidean distance >= 0 (0: the triangles touch or cross)
  Vec3 pointA = Vec3::Zero();  ///< closest point on A (a common point when distance == 0)
  Vec3 pointB = Vec3::Zero();  ///< closest point on B; |pointA − pointB| == distance up to rounding
  std::uint32_t featureA = 0;  ///< feature of A holding pointA (featureId)
  std::uint32_t featureB = 0;  ///< feature of B holding pointB (featureId)
  bool intersecting = false;   ///< the exact test says the closed triangles share a point
};

/// Closest points between triangles a and b (see the file comment for the method). Never
/// throws, never allocates; finite input gives finite output (no NaN for degenerate input).
TriangleDistanceResult closestPoints(const Triangle& a, const Triangle& b);

/// Distance between triangles a and b as closestPoints(a, b).distance.
Real distance(const Triangle& a, const Triangle& b);

}  // namespace crux
