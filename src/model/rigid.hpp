#pragma once
/// @file rigid.hpp  Internal: rigid maps between a model's mesh space and the world, exact for
/// the 24 axis-aligned rotations (RigidFrame, model/rigid_frame.hpp), transform composition
/// built on them, and the mesh ray under a prepared frame.

#include <crux/geometry/axis_aligned.hpp>
#include <crux/math.hpp>
#include <crux/mesh/mesh_query.hpp>
#include <crux/model/rigid_frame.hpp>

#include <optional>

namespace crux::model_detail {

// The 24 axis-aligned rotations live in the geometry layer (axis_aligned.hpp).
using crux::signedPermutation;
using crux::snapAxisAligned;

/// a ∘ b (b applied first), with the rotation renormalised and snapped to the exact
/// axis-aligned quaternion when within tolerance, and b's translation rotated exactly when a's
/// rotation is axis-aligned.
Transform compose(const Transform& a, const Transform& b);

/// a⁻¹ ∘ b: b expressed in a's frame (exact under the same conditions as compose).
Transform relative(const Transform& a, const Transform& b);

/// The rotation normalised and snapped (as compose does), for storing user input.
Quat canonicalRotation(const Quat& q);

/// a + b rounded towards -inf / +inf (TwoSum error term decides the direction).
Real addDown(Real a, Real b);
Real addUp(Real a, Real b);

/// raycastClosest(PlacedMesh{&mesh, t}, worldRay, options) with RigidFrame(t) already made:
/// the public query is this with the frame made on the spot, so both give the same answers;
/// the scene keeps one frame per model (made when the model moves) and casts through this.
std::optional<MeshRayHit> raycastClosest(const Mesh& mesh, const RigidFrame& frame, const Ray& worldRay,
                                         const RayQueryOptions& options);

}  // namespace crux::model_detail
