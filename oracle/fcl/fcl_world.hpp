#pragma once
/// @file fcl_world.hpp  The "fcl" backend: FCL 0.7 (Flexible Collision Library) behind the
/// CollisionWorld interface.

#include <crux/world/collision_world.hpp>

#include <memory>

namespace crux::fcl_oracle {

/// A world answered by FCL 0.7. Each mesh becomes a fcl::BVHModel<OBBRSSd> (vertices widened
/// to double exactly; beginModel / addSubModel / endModel); a triangle of a primitive op becomes
/// a one-triangle BVHModel, since fcl::TriangleP is not in 0.7's collision dispatch tables.
/// Overlaps are fcl::collide (one contact, no details) against fcl::Sphered, Boxd (an AABB is
/// an unrotated box, an OBB a rotated one), Planed (the plane itself, not a half-space) or
/// another BVHModel; mesh_mesh collides the two models under their transforms (rotation of
/// the double-normalised quaternion). closest_point_triangle is fcl::distance to a Sphered of
/// radius 0 with nearest points enabled.
///
/// Models: each an fcl::CollisionObjectd over its mesh's shared BVHModel at its world pose
/// (hierarchy and poses from oracle::ModelTable), all registered in one
/// fcl::DynamicAABBTreeCollisionManagerd (registerObject / update / unregisterObject).
/// model_sphere / aabb / obb / plane / triangle: fcl::collide of the placed object as above.
/// scene_query: manager.collide(query object) with fcl::collide as narrow phase (bounds-only:
/// the query shape against FCL's own AABB of each candidate, as a Boxd); scene_pairs:
/// manager.collide (self) with fcl::collide on each pair of overlapping AABBs.
///
/// FCL has no ray or segment query: ray_triangle, segment_triangle, mesh_ray, mesh_segment,
/// model_ray, model_segment and scene_ray throw Unsupported. FCL's mesh tests are surface-only
/// (triangle against shape), like crux's. See oracle/README.md for its known disagreements.
std::unique_ptr<CollisionWorld> makeFclWorld();

/// CollisionWorld::tolerance of the fcl backend: double arithmetic (relative 1e-12) plus
/// libccd's GJK/EPA tolerance, which FCL sets as an absolute 1e-6.
inline constexpr WorldTolerance kFclTolerance{1e-12, 1e-6, 0};

}  // namespace crux::fcl_oracle
