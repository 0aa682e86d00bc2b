#pragma once
/// @file primitive_ops.hpp  Handlers of the batch protocol's primitive ops (one triangle and one
/// other shape; see docs/batch.md), answered by the crux geometry layer.

#include "cli/batch.hpp"

namespace crux::cli {

/// Adds closest_point_triangle, triangle_sphere, triangle_aabb, triangle_obb, triangle_plane,
/// triangle_triangle, ray_triangle and segment_triangle, answered by crux::closestPoint,
/// crux::overlaps, crux::raycast and crux::intersects.
void addPrimitiveOps(OpTable& table);

}  // namespace crux::cli
