#pragma once
/// @file rigid_frame.hpp  Internal (model_detail): a model's rigid transform prepared for mapping
/// points and directions between its mesh space and the world. Public only because the scene
/// keeps one per model for its rays (Scene's private members); not part of the API.

#include <crux/geometry/axis_aligned.hpp>
#include <crux/math.hpp>

namespace crux {
class Mesh;
}

namespace crux::model_detail {

/// A rigid transform prepared for mapping many points: the rotation as a matrix (the exact
/// signed permutation when the rotation is axis-aligned).
class RigidFrame {
 public:
  explicit RigidFrame(const Transform& t);
  /// The identity frame.
  RigidFrame() : RigidFrame(Transform::identity()) {}

  /// Rotation axis-aligned and translation exactly zero: the mapping is skipped.
  bool identity() const { return identity_; }
  /// The rotation is a signed permutation: mapping is exact up to the rounding of p - t.
  bool axisAligned() const { return aligned_; }
  const Mat3& rotation() const { return r_; }
  const Vec3& translation() const { return t_; }

  /// World point to mesh space: Rᵀ(p - t).
  Vec3 toMesh(const Vec3& p) const { return r_.transpose() * (p - t_); }
  /// World direction to mesh space: Rᵀv.
  Vec3 toMeshVector(const Vec3& v) const { return r_.transpose() * v; }
  /// Mesh point to world: R p + t.
  Vec3 toWorld(const Vec3& p) const { return r_ * p + t_; }
  /// Mesh direction to world: R v.
  Vec3 toWorldVector(const Vec3& v) const { return r_ * v; }

 private:
  Mat3 r_;
  Vec3 t_;
  bool aligned_ = false;
  bool identity_ = false;
};

/// What a query needs of a placed model, in one cache line (float builds): its mesh and its
/// frame. The scene keeps one per model for its rays.
struct alignas(64) PreparedModel {
  const Mesh* mesh = nullptr;
  RigidFrame frame;
};

}  // namespace crux::model_detail
