#pragma once
/// @file bullet_world.hpp  The "bullet" backend: Bullet 3.24 (Debian's single-precision build)
/// behind the CollisionWorld interface.

#include <crux/world/collision_world.hpp>

#include <memory>

namespace crux::bullet_oracle {

/// A world answered by Bullet's collision module. Every collision margin is set to zero.
///  - A mesh becomes a btBvhTriangleMeshShape (quantized BVH) over a btTriangleIndexVertexArray
///    of float copies of its arrays; a triangle of a primitive op becomes a one-triangle
///    btBvhTriangleMeshShape, so triangle ops and mesh ops take the same Bullet path.
///  - Rays and segments: btCollisionWorld::rayTestSingle from the origin to a point past the
///    mesh's bounds (or to maxDistance), hits through a RayResultCallback (closest / any / all;
///    cullBackFaces = kF_FilterBackfaces); t = hit fraction × segment length.
///  - Sphere, box (AABB and OBB) and triangle against a mesh: contactPairTest of a btSphereShape,
///    btBoxShape or btTriangleShape against the mesh object; a hit is a reported contact of
///    distance <= 0.
///  - triangle_plane: a btTriangleShape against two btStaticPlaneShape half-spaces (n, d) and
///    (-n, -d): Bullet's plane is a half-space, the protocol's plane is the plane itself, and a
///    triangle meets the plane iff it meets both closed half-spaces. mesh_plane is Unsupported
///    (a static plane against a static mesh has no Bullet algorithm).
///  - mesh_mesh: btGImpactMeshShape for both meshes, in a collision world with
///    btDbvtBroadphase, found by performDiscreteCollisionDetection (contactPairTest reports
///    nothing for GImpact pairs).
///  - closest_point_triangle: btVoronoiSimplexSolver::closestPtPointTriangle.
///  - Models (hierarchy and poses from oracle::ModelTable): each has a btCollisionObject over the
///    mesh's btBvhTriangleMeshShape in a scene btCollisionWorld (btDbvtBroadphase) — model_ray /
///    model_segment by rayTestSingle, model_sphere / aabb / obb / triangle by contactPairTest,
///    scene_ray by rayTest, scene_query by contactTest (bounds-only: the Dbvt's candidates, the
///    query against each model's getAabb box) — and one over its btGImpactMeshShape in a pairs
///    world, for scene_pairs by performDiscreteCollisionDetection (contacts of distance <= 0).
///    model_plane: Unsupported, as mesh_plane.
/// Coordinates are rounded to float on the way in. Known disagreements (plane endpoints of rays, fattened edges, float rounding) in oracle/README.md.
std::unique_ptr<CollisionWorld> makeBulletWorld();

/// CollisionWorld::tolerance of the bullet backend. Relative: float arithmetic through GJK/EPA
/// and the triangle ray test, whose edges are fattened by 1e-4·|n|² (about 1e-4 of the
/// triangle's size). Absolute: btGjkEpa2's fixed accuracies (GJK/EPA epsilons of 1e-4).
/// Minimum feature: penetrating boxes and triangles of size 0.01 get no contact at all
/// (measured by the sanity suite; 0.015 still works), so shapes below 0.05 units are outside
/// Bullet's working range.
inline constexpr WorldTolerance kBulletTolerance{2e-4, 1e-4, 0.05};

}  // namespace crux::bullet_oracle
