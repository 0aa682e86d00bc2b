#pragma once
/// @file relative_frame.hpp  Internal: mesh b's geometry in mesh a's frame, by the one rule every
/// two-mesh query uses (mesh_query.cpp's mesh–mesh overlap, mesh_volume.cpp's volume mode), so
/// that "touching" is decided on the same mapped coordinates everywhere.

#include <crux/geometry/axis_aligned.hpp>
#include <crux/geometry/shapes.hpp>

#include <optional>

namespace crux::mesh_detail {

/// b's triangles seen in a's frame: the relative transform ta⁻¹·tb, skipped (exactly) when it
/// is the identity. When it is one of the 24 axis-aligned rotations (axis_aligned.hpp) it is
/// applied as the exact signed permutation, and when ta's rotation is axis-aligned the relative
/// translation Pᵀ(t_b - t_a) is rounded once: integer-grid meshes under quarter and half turns
/// stay exact (a quaternion rotation by √½ components would round their vertices).
class RelativeFrame {
 public:
  RelativeFrame(const Transform& ta, const Transform& tb) {
    const bool same = ta.rotation.coeffs() == tb.rotation.coeffs() && ta.translation == tb.translation;
    rel_ = ta.inverse() * tb;
    if (const std::optional<Quat> s = snapAxisAligned(rel_.rotation.normalized())) {
      aligned_ = true;
      rel_.rotation = *s;
      if (const std::optional<Quat> sa = snapAxisAligned(ta.rotation.normalized()))
        rel_.translation = signedPermutation(*sa).transpose() * (tb.translation - ta.translation);
    }
    identity_ = same || (rel_.rotation.vec().isZero(0) && rel_.translation.isZero(0));
    rotation_ = identity_ ? Mat3::Identity()
                          : (aligned_ ? signedPermutation(rel_.rotation) : Mat3(rel_.rotation.toRotationMatrix()));
  }
  bool identity() const { return identity_; }
  const Mat3& rotation() const { return rotation_; }
  const Transform& transform() const { return rel_; }
  Triangle map(const Triangle& t) const {
    if (identity_) return t;
    if (aligned_) return {mapPoint(t.a), mapPoint(t.b), mapPoint(t.c)};
    return {rel_.apply(t.a), rel_.apply(t.b), rel_.apply(t.c)};
  }
  /// p by the rotation matrix and translation (node centres; for an axis-aligned frame the
  /// exact rule, else within rounding of map(Vec3)).
  Vec3 mapPoint(const Vec3& p) const { return identity_ ? p : Vec3(rotation_ * p + rel_.translation); }
  /// A vertex of b by exactly the rule map(Triangle) applies to each corner.
  Vec3 map(const Vec3& p) const {
    if (identity_) return p;
    if (aligned_) return mapPoint(p);
    return rel_.apply(p);
  }

 private:
  Transform rel_;
  Mat3 rotation_;
  bool identity_ = true;
  bool aligned_ = false;
};

}  // namespace crux::mesh_detail
