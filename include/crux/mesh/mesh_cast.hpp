#pragma once
/// @file mesh_cast.hpp  Shape casts against a triangle mesh: the first triangle a moving convex
/// shape touches (cast.hpp's semantics and tolerance, per triangle).
///
/// The shape (A) moves; the mesh (B, placed by meshPose) stays. Each triangle is cast exactly as
/// cast(shape, ..., ConvexShape(triangle), meshPose) does, so the answer is the triangle with the
/// smallest reported t (ties: the lowest triangle index), with that cast's points, normal (from
/// the mesh to the shape) and overlap flag. The BVH path (QueryPath::Bvh) and the brute-force path
/// give identical answers:
///  - BVH traversal (the mesh's 4-wide tree, nearest first) with swept bounds: the shape's box
///    in the mesh frame (linear casts; for rigid motions the box of the ball of radius
///    shape.size() about its origin) moved along the motion; a node is entered when that moving
///    box, grown by the contact tolerance and a rounding pad, meets the node's box, and its key
///    is the entry time, so nodes are visited nearest first and pruned once they are entered
///    after the best t;
///  - a triangle's cast is abandoned as soon as its advancement passes the best t (CastOptions'
///    earlyOut): casts that could still tie or win are computed in full.
/// Degenerate triangles are their segments or points. Queries never throw and never allocate;
/// they assume a validated shape and motion (validate(ConvexShape), validateMotion) and unit
/// rotations.

#include <crux/geometry/cast.hpp>
#include <crux/mesh/mesh.hpp>
#include <crux/mesh/mesh_query.hpp>

#include <cstdint>
#include <optional>

namespace crux {

/// A cast's first hit on a mesh: the pair cast's result against the triangle hit.
struct MeshCastHit {
  CastResult cast;
  std::uint32_t triangle = 0;
};

/// Linear cast of `shape` (at shapePose, translated by s·motion, s in [0, 1]) against the mesh
/// placed by meshPose: the first triangle touched, or nothing.
std::optional<MeshCastHit> castClosest(const Mesh& mesh, const Transform& meshPose, const ConvexShape& shape,
                                       const Transform& shapePose, const Vec3& motion,
                                       QueryPath path = QueryPath::Bvh);
/// Rigid cast (RigidMotion: slerp rotation, linear translation) against the mesh.
std::optional<MeshCastHit> castClosest(const Mesh& mesh, const Transform& meshPose, const ConvexShape& shape,
                                       const RigidMotion& motion, QueryPath path = QueryPath::Bvh);
/// Any hit: does the linear cast touch any triangle (stops at the first one found)?
bool castAny(const Mesh& mesh, const Transform& meshPose, const ConvexShape& shape, const Transform& shapePose,
             const Vec3& motion, QueryPath path = QueryPath::Bvh);
/// Any hit of the rigid cast.
bool castAny(const Mesh& mesh, const Transform& meshPose, const ConvexShape& shape, const RigidMotion& motion,
             QueryPath path = QueryPath::Bvh);

}  // namespace crux
