#pragma once
/// @file bvh_build.hpp  The mesh's entry to the BVH builder (internal).

#include <crux/mesh/bvh.hpp>

#include <array>
#include <cstdint>
#include <vector>

namespace crux::detail {

/// buildWideBvh over the boxes of triangles (vertices[t[0]], vertices[t[1]], vertices[t[2]]),
/// each box computed as the builder reads it instead of from an array of boxes. The caller has
/// checked the triangles: indices in range, vertices finite.
WideBvh buildTriangleWideBvh(const std::vector<Vec3>& vertices, const std::vector<std::array<std::uint32_t, 3>>& triangles,
                             const BvhBuildOptions& options);

}  // namespace crux::detail
