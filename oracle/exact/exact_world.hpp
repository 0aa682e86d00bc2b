#pragma once
/// @file exact_world.hpp  The "exact" backend: CGAL's exact kernel (Epeck), brute force over
/// triangles. The arbiter of the differential fuzzer; slow by design.

#include <crux/world/collision_world.hpp>

#include <limits>
#include <memory>

namespace crux::exact {

/// A world answered by the exact oracle (exact.hpp): every primitive op by the CGAL function
/// of the same op; every mesh op by brute force over the mesh's triangles (no BVH, so no
/// culling that could be wrong); mesh–mesh by all triangle pairs, O(n·m) exact tests after a
/// conservative interval-box filter — fine for the small meshes the fuzzer makes, slow for
/// real ones (a 10k × 10k pair is 10^8 box tests). Transforms of mesh_mesh are applied
/// exactly: the rotation is the exact rational matrix of q/|q| (the rotation the quaternion
/// denotes), the translation is added exactly.
///
/// Models and the scene: names and the hierarchy are oracle::ModelTable's (remove and
/// set_parent keep the world pose by recomputing the local transform in Real, as crux does);
/// world transforms are composed EXACTLY from the local ones (exact_rigid.hpp: rational
/// rotation matrices, Hamilton products), with crux's axis-aligned snapping applied to every
/// local and composed rotation, and each model's triangles are placed exactly and cached until
/// the model or an ancestor changes. Model ops test the placed triangles brute force; scene_ray
/// offers every model's hits (ties: RayHitCollector's (t, model, triangle)); scene_query tests
/// triangles, or with boundsOnly the exact axis-aligned box of the placed vertices (crux pads
/// its boxes, so its bounds-only answers may be a superset); scene_pairs tests every model pair
/// (exact box pre-check, then all triangle pairs).
///
/// Volume mode (point_inside, "volume": true on mesh_* and model_*): CGAL::Side_of_triangle_mesh on
/// the exactly placed closed mesh (exact_volume.hpp). Narrow phase (contacts, distance,
/// mesh_distance, model_distance): exact_distance.hpp — convex operands as exact core points plus
/// a radius, distances and penetration depths from the exact hull of their differences, mesh
/// operands brute force over triangles (contacts: one per triangle within the margin, unreduced).
///
/// Booleans are exact. Distances are exact values rounded once (a few ulps of double); the
/// choice among ray hits whose exact distances differ by less than that (and the max-distance
/// cut) is made on the rounded distances.
std::unique_ptr<CollisionWorld> makeExactWorld();

/// CollisionWorld::tolerance of the exact backend: booleans exact, numbers within 16 ulps of
/// double of the operands' magnitude.
inline constexpr WorldTolerance kExactTolerance{16.0 * std::numeric_limits<double>::epsilon(), 0, 0};

}  // namespace crux::exact
