#pragma once
/// @file scene_ops.hpp  Handlers of the batch protocol's model and scene ops (see docs/batch.md):
/// models by name (BatchState::models), held and queried by the batch's crux::CollisionWorld.

#include "cli/batch.hpp"

namespace crux::cli {

/// Adds `add_model`, `set_transform`, `set_parent`, `remove_model` (CollisionWorld::addModel,
/// setTransform, setParent, removeModel), `children` (descendants), `model_ray`,
/// `model_segment`, `model_sphere`, `model_aabb`, `model_obb`, `model_plane`, `model_triangle`
/// (the world's model queries), `scene_ray`, `scene_query` and `scene_pairs` (sceneRaycast,
/// sceneQuery, scenePairs). For native these are crux::Scene's edits and queries.
void addSceneOps(OpTable& table);

}  // namespace crux::cli
