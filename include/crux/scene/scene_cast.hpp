#pragma once
/// @file scene_cast.hpp  Shape casts against a scene: the model a moving convex shape touches
/// first (model_cast.hpp per model; ties: the lowest model id).
///
/// ScenePath::BroadPhase walks the broad phase with the path of the shape's origin (a ray from
/// its start to its end translation) against the model boxes grown by the shape's size (the
/// shape stays within shape.size() of its origin under any rigid motion) plus the casts' contact
/// tolerance at the scene's largest scale, nearest box first, and prunes the boxes entered after
/// the best impact; a pure rotation (or no motion) asks the broad phase for the boxes touching the
/// ball the shape sweeps. ScenePath::BruteForce casts against every model. Both give identical
/// answers. Queries never throw: a non-finite shape, pose or motion gets no hit (precondition.hpp;
/// debug builds abort naming the query).

#include <crux/model/model_cast.hpp>
#include <crux/scene/scene.hpp>

#include <optional>

namespace crux {

/// A scene cast's first hit: the model and its mesh cast hit (world space).
struct SceneCastHit {
  ModelId model = kNoModel;
  MeshCastHit hit;
};

/// Linear cast against every model of the scene: the first model touched, or nothing.
std::optional<SceneCastHit> castClosest(const Scene& scene, const ConvexShape& shape, const Transform& shapePose,
                                        const Vec3& motion, ScenePath path = ScenePath::BroadPhase);
/// Rigid cast (slerp rotation, linear translation) against every model of the scene.
std::optional<SceneCastHit> castClosest(const Scene& scene, const ConvexShape& shape, const RigidMotion& motion,
                                        ScenePath path = ScenePath::BroadPhase);
/// Any hit of the linear cast (stops at the first model hit).
bool castAny(const Scene& scene, const ConvexShape& shape, const Transform& shapePose, const Vec3& motion,
             ScenePath path = ScenePath::BroadPhase);
/// Any hit of the rigid cast (stops at the first model hit).
bool castAny(const Scene& scene, const ConvexShape& shape, const RigidMotion& motion,
             ScenePath path = ScenePath::BroadPhase);

}  // namespace crux
