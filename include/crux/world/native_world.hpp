#pragma once
/// @file native_world.hpp  The "native" backend: crux's own geometry and mesh layers behind the
/// CollisionWorld interface.

#include <crux/world/collision_world.hpp>

#include <limits>
#include <memory>

namespace crux {

/// A world answered by crux itself: primitive ops by the geometry layer (crux::closestPoint,
/// overlaps, raycast, intersects), mesh ops by the mesh layer's BVH queries
/// (crux::raycastClosest / raycastAny / raycastAll, intersects, overlaps, and BVH-vs-BVH
/// mesh–mesh), models and the scene by one crux::Scene (dynamic AABB tree broad phase, model
/// hierarchy, Scene::raycast / query / overlappingPairs), giving exactly their answers (Real
/// widened to double). It answers every op. Queries may run from several threads at once after
/// prepareConcurrentQueries() (concurrentQueries() is true); changes are exclusive.
std::unique_ptr<CollisionWorld> makeNativeWorld();

/// Accuracy of crux's distances and points (CollisionWorld::tolerance): 64 ulps of Real,
/// relative to the operands' magnitude; no absolute term, no minimum size (crux's tests are
/// scale-free).
inline constexpr WorldTolerance kNativeTolerance{64.0 * std::numeric_limits<Real>::epsilon(), 0, 0};

}  // namespace crux
