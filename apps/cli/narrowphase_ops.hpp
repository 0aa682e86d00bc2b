#pragma once
/// @file narrowphase_ops.hpp  Handlers of the batch protocol's narrow-phase and volume ops
/// (documented in docs/batch.md, "Contacts, distance and volumes"): `contacts`, `distance`,
/// `mesh_distance`, `model_distance`, `point_inside`, and the shape casts `cast`, `model_cast`,
/// `scene_cast` (docs/batch.md, "Shape casts"). Each reads its fields, resolves mesh and model
/// names, and asks the batch's crux::CollisionWorld (CollisionWorld::contacts, distance,
/// meshDistance, modelDistance, pointInside, cast, modelCast, sceneCast).

#include "cli/batch.hpp"

namespace crux::cli {

/// Adds contacts, distance, mesh_distance, model_distance, point_inside and cast to the table.
void addNarrowPhaseOps(OpTable& table);

/// Reads a contacts/distance operand (field `key` of the request): an object with exactly one
/// shape member — "sphere", "box" (the obb encoding), "capsule" {"a","b","radius"}, "hull"
/// {"points": [...]}, "triangle", or "mesh" (a mesh name) — and an optional "transform".
/// Mesh names are resolved in `state`'s world (unknown: an error naming "<key>.mesh").
WorldOperand readOperand(const Json& request, const std::string& key, const BatchState& state);

}  // namespace crux::cli
