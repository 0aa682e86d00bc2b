#pragma once
/// @file local_shape.hpp  Internal: a convex shape placed in a mesh's frame, in the form the mesh
/// contact colliders (triangle_colliders.hpp) and the mesh distance query take it.

#include <crux/geometry/axis_aligned.hpp>
#include <crux/geometry/convex.hpp>
#include <crux/mesh/mesh_contact.hpp>

#include "mesh/shape_bounds.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

namespace crux::mesh_detail {

/// The convex shape in the mesh's frame, in the form the per-triangle routines take: sphere
/// centre, capsule ends, box centre/axes, or the generic view with the relative pose.
struct LocalShape {
  const ConvexShape& shape;
  Transform rel;   // shape-local -> mesh-local (generic path)
  Mat3 relR;       // its rotation matrix
  Vec3 p[2];       // sphere: centre; capsule: ends; box: centre (p[0])
  Mat3 axes = Mat3::Identity();  // box: axes in the mesh frame (columns)
  Vec3 half = Vec3::Zero();       // box half extents
  Real radius = 0;
  Eigen::Matrix3d boxToLocal = Eigen::Matrix3d::Identity();  // box: mesh frame -> box frame rotation
  Eigen::Vector3d boxCentre = Eigen::Vector3d::Zero();       // box: centre in the mesh frame
  double boxSlack = 0;  // box: rounding slack of the face-axis reject (1000 ulps of Real × scale)
  bool boxMirrored = false;  // box: its frame is left-handed (det < 0): triangles turn over in it
  bool aligned = false;  // the relative rotation is axis-aligned (applied exactly)
  bool ownFrame = false;  // a box in its own frame (OwnFrame): support and projection by signs
  Triangle mappedTriangle;  // a triangle shape under an aligned rotation, mapped exactly

  /// A box (`box`: centre 0, identity axes) in its own frame, set directly (no pose to read):
  /// the frame in which BoxCollider (triangle_colliders.hpp) reports its points.
  struct OwnFrame {};
  LocalShape(const ConvexShape& box, OwnFrame) : shape(box), relR(Mat3::Identity()), half(box.p[1]) {
    p[0] = p[1] = Vec3::Zero();
    aligned = true;
    ownFrame = true;
  }

  LocalShape(const ConvexShape& s, const Transform& meshPose, const Transform& shapePose) : shape(s) {
    // rel = meshPose⁻¹ ∘ shapePose in double, rounded once.
    const Eigen::Quaterniond qm = meshPose.rotation.cast<double>(), qs = shapePose.rotation.cast<double>();
    const Eigen::Quaterniond qr = (qm.conjugate() * qs).normalized();
    Eigen::Matrix3d Rr = qr.toRotationMatrix();
    const Eigen::Vector3d dt = shapePose.translation.cast<double>() - meshPose.translation.cast<double>();
    Eigen::Vector3d tr = qm.conjugate() * dt;
    rel.rotation = qr.cast<Real>();
    // The mesh layer's rule (relative_frame.hpp): an axis-aligned relative rotation (quarter and
    // half turns) is applied as the exact signed permutation, and with an axis-aligned mesh
    // rotation the relative translation is rounded once, so integer-grid shapes stay on the grid
    // and touching stays touching (a √½ quaternion would round their coordinates).
    if (const std::optional<Quat> snapped = snapAxisAligned(rel.rotation.normalized())) {
      aligned = true;
      rel.rotation = *snapped;
      Rr = signedPermutation(*snapped).cast<double>();
      if (const std::optional<Quat> sm = snapAxisAligned(meshPose.rotation.normalized()))
        tr = signedPermutation(*sm).cast<double>().transpose() * dt;
    }
    rel.translation = tr.cast<Real>();
    relR = Rr.cast<Real>();
    if (aligned && s.kind == ConvexKind::Triangle)
      mappedTriangle = {(Rr * s.p[0].cast<double>() + tr).cast<Real>(), (Rr * s.p[1].cast<double>() + tr).cast<Real>(),
                        (Rr * s.p[2].cast<double>() + tr).cast<Real>()};
    radius = s.radius;
    switch (s.kind) {
      case ConvexKind::Sphere: p[0] = (Rr * s.p[0].cast<double>() + tr).cast<Real>(); break;
      case ConvexKind::Capsule:
        for (int i = 0; i < 2; ++i) p[i] = (Rr * s.p[i].cast<double>() + tr).cast<Real>();
        break;
      case ConvexKind::Box:
        p[0] = (Rr * s.p[0].cast<double>() + tr).cast<Real>();
        axes = (Rr * s.axes.cast<double>()).cast<Real>();
        half = s.p[1];
        boxCentre = Rr * s.p[0].cast<double>() + tr;
        boxToLocal = (Rr * s.axes.cast<double>()).transpose();
        boxSlack = double(kMeshFeatureRelativeTolerance) * (boxCentre.norm() + double(half.norm()) + 1);
        boxMirrored = boxToLocal.determinant() < 0;
        break;
      default: break;
    }
  }

  /// Support point of the whole (rounded) shape along `dir` (mesh frame), as support() does.
  Vec3 support(const Vec3& dir) const {
    // a box in its own frame: the corner of dir's sign pattern (what the generic path computes
    // through the identity pose, without the pose)
    if (ownFrame)
      return {dir.x() > 0 ? half.x() : -half.x(), dir.y() > 0 ? half.y() : -half.y(),
              dir.z() > 0 ? half.z() : -half.z()};
    switch (shape.kind) {
      case ConvexKind::Sphere: return p[0] + radius * dir.normalized();
      case ConvexKind::Capsule:
        return (p[1].dot(dir) > p[0].dot(dir) ? p[1] : p[0]) + radius * dir.normalized();
      default: return rel.apply(crux::support(shape, rel.rotation.conjugate() * dir));
    }
  }

  /// Projection interval [lo, hi] of the shape on the unit direction u (mesh frame).
  void project(const Vec3& u, Real& lo, Real& hi) const {
    if (ownFrame) {  // a box in its own frame: centre 0, identity axes
      hi = half.x() * std::abs(u.x()) + half.y() * std::abs(u.y()) + half.z() * std::abs(u.z());
      lo = -hi;
      return;
    }
    switch (shape.kind) {
      case ConvexKind::Sphere: lo = hi = u.dot(p[0]); break;
      case ConvexKind::Capsule: {
        const Real a = u.dot(p[0]), b = u.dot(p[1]);
        lo = std::min(a, b);
        hi = std::max(a, b);
        break;
      }
      case ConvexKind::Box: {
        const Real c = u.dot(p[0]);
        const Vec3 l = axes.transpose() * u;
        const Real e = half.x() * std::abs(l.x()) + half.y() * std::abs(l.y()) + half.z() * std::abs(l.z());
        lo = c - e;
        hi = c + e;
        return;
      }
      default:
        hi = u.dot(support(u));
        lo = u.dot(support(-u));
        return;
    }
    lo -= radius;
    hi += radius;
  }

  /// The shape's AABB in the mesh frame.
  Aabb bounds() const {
    switch (shape.kind) {
      case ConvexKind::Sphere: return {p[0].array() - radius, p[0].array() + radius};
      case ConvexKind::Capsule:
        return {p[0].cwiseMin(p[1]).array() - radius, p[0].cwiseMax(p[1]).array() + radius};
      case ConvexKind::Box: {
        const Vec3 e = axes.cwiseAbs() * half;
        return {p[0] - e, p[0] + e};
      }
      default: return shapeBoundsIn(shape, rel);
    }
  }
};

}  // namespace crux::mesh_detail
