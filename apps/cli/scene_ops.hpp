#pragma once
/// @file scene_ops.hpp  Handlers of the batch protocol's model and scene ops (see docs/batch.md):
/// models by name in BatchState's crux::Scene, queried through the model and scene layers.

#include "cli/batch.hpp"

namespace crux::cli {

/// Adds `add_model`, `set_transform`, `set_parent`, `remove_model` (crux::Scene edits),
/// `model_ray`, `model_segment`, `model_sphere`, `model_aabb`, `model_obb`, `model_plane`,
/// `model_triangle` (the PlacedMesh queries of include/crux/model/model_query.hpp), `children`
/// (ModelHierarchy::descendants), `scene_ray`, `scene_query` and `scene_pairs` (Scene::raycast,
/// Scene::query, Scene::overlappingPairs).
void addSceneOps(OpTable& table);

}  // namespace crux::cli
