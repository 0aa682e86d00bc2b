#pragma once
/// @file shape_bounds.hpp  Internal: a convex shape's axis-aligned box in a mesh's frame, and the
/// slack that keeps rounding from pruning a triangle (mesh_contact.cpp's distance, mesh_cast.cpp).

#include <crux/geometry/convex.hpp>
#include <crux/mesh/mesh_contact.hpp>

#include <algorithm>

namespace crux::mesh_detail {

/// The shape's AABB in the mesh frame (rel maps shape-local to mesh-local), by six supports.
inline Aabb shapeBoundsIn(const ConvexShape& shape, const Transform& rel) {
  Aabb box = Aabb::empty();
  const Quat inv = rel.rotation.conjugate();
  for (int k = 0; k < 3; ++k) {
    Vec3 e = Vec3::Zero();
    e[k] = 1;
    box.grow(rel.apply(support(shape, inv * e)));
    box.grow(rel.apply(support(shape, inv * (-e))));
  }
  return box;
}

/// Conservative slack added to computed boxes so rounding never prunes a triangle the
/// per-triangle routine would report: 1000 ulps of Real × the coordinates' magnitude.
inline Real boxSlack(const Aabb& box) {
  const Real scale = std::max(box.min.cwiseAbs().maxCoeff(), box.max.cwiseAbs().maxCoeff()) +
                     (box.max - box.min).maxCoeff();
  return kMeshFeatureRelativeTolerance * scale;
}

}  // namespace crux::mesh_detail
