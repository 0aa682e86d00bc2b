#pragma once
/// @file model_cast.hpp  Shape casts against a placed model (a mesh and its world transform):
/// mesh_cast.hpp's casts with the mesh placed by the model's world transform. The shape and its
/// motion are in world space; the hit's points and normal come back in world space.

#include <crux/mesh/mesh_cast.hpp>
#include <crux/model/model_query.hpp>

#include <optional>

namespace crux {

/// Linear cast of `shape` (at shapePose, translated by s·motion, s in [0, 1]) against the placed
/// mesh: the first triangle touched, or nothing.
std::optional<MeshCastHit> castClosest(const PlacedMesh& m, const ConvexShape& shape, const Transform& shapePose,
                                       const Vec3& motion);
/// Rigid cast (slerp rotation, linear translation) against the placed mesh.
std::optional<MeshCastHit> castClosest(const PlacedMesh& m, const ConvexShape& shape, const RigidMotion& motion);
/// Any hit of the linear cast.
bool castAny(const PlacedMesh& m, const ConvexShape& shape, const Transform& shapePose, const Vec3& motion);
/// Any hit of the rigid cast.
bool castAny(const PlacedMesh& m, const ConvexShape& shape, const RigidMotion& motion);

}  // namespace crux
