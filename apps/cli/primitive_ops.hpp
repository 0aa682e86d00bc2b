#pragma once
/// @file primitive_ops.hpp  Handlers of the batch protocol's primitive ops (one triangle and one
/// other shape; see docs/batch.md), answered by the batch's crux::CollisionWorld.

#include "cli/batch.hpp"

namespace crux::cli {

/// Adds closest_point_triangle, triangle_sphere, triangle_aabb, triangle_obb, triangle_plane,
/// triangle_triangle, ray_triangle and segment_triangle, answered by CollisionWorld::closestPoint,
/// overlaps, raycast and intersects (for native: crux::closestPoint, overlaps, raycast, intersects).
void addPrimitiveOps(OpTable& table);

}  // namespace crux::cli
