#pragma once
/// @file exact_volume.hpp  The exact oracle of volume mode (point_inside, mesh_<shape> with
/// "volume": true): CGAL::Side_of_triangle_mesh over a CGAL::Surface_mesh with exact (Epeck)
/// points, so every answer is the true one for the mesh as given.
///
/// Side_of_triangle_mesh shoots rays from the query point through an AABB tree of the faces
/// and counts crossings, with exact predicates and its own handling of degenerate rays
/// (CGAL 5.x: it retries with another random ray when a ray meets an edge or vertex); points on
/// the surface are ON_BOUNDARY, which counts as inside (closed sets). This is an algorithm
/// independent of crux's (MeshVolume: exact ray parity along a fixed direction sequence).
///
/// The caller checks closedness first (the world uses crux::closedness for the refusal, so every
/// backend refuses the same meshes with the same message). Triangles repeating a vertex index
/// are dropped (they bound nothing); vertices shared by several sheets (non-manifold vertices of
/// a closed mesh) are split by CGAL::Polygon_mesh_processing::orient_polygon_soup so the soup
/// becomes a Surface_mesh. A face whose corners are collinear (distinct indices) is a
/// precondition violation for CGAL and throws std::runtime_error (reported by the world as
/// "exact failed on ...").

#include "exact/exact_rigid.hpp"

#include <crux/mesh/mesh.hpp>

#include <memory>

namespace crux::exact {

/// A closed mesh as an exact solid.
class ExactSolid {
 public:
  /// Builds the Surface_mesh and the AABB tree (O(n log n), exact points).
  explicit ExactSolid(const Mesh& mesh);
  /// The mesh placed by `place` (its vertices mapped exactly): the solid in world space, for
  /// mesh_mesh volume (each mesh by its own transform, as the exact surface test places them).
  ExactSolid(const Mesh& mesh, const detail::ExactRigid& place);
  ~ExactSolid();
  ExactSolid(const ExactSolid&) = delete;
  ExactSolid& operator=(const ExactSolid&) = delete;

  /// Is p inside the solid or on its surface?
  bool contains(const Vec3& p) const;
  bool contains(const detail::Point& p) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace crux::exact
