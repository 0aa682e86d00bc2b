/// @file exact_volume.cpp  ExactSolid: CGAL::Side_of_triangle_mesh with Epeck (see exact_volume.hpp).

#include "exact/exact_volume.hpp"

#include "exact/exact_kernel.hpp"

#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>

#include <array>
#include <stdexcept>
#include <string>
#include <vector>

namespace crux::exact {

using namespace detail;

struct ExactSolid::Impl {
  using SurfaceMesh = CGAL::Surface_mesh<Point>;
  SurfaceMesh mesh;
  std::unique_ptr<CGAL::Side_of_triangle_mesh<SurfaceMesh, K>> side;
};

ExactSolid::ExactSolid(const Mesh& mesh) : ExactSolid(mesh, ExactRigid()) {}

ExactSolid::ExactSolid(const Mesh& mesh, const ExactRigid& place) : impl_(std::make_unique<Impl>()) {
  std::vector<Point> points;
  points.reserve(mesh.vertexCount());
  for (const Vec3& v : mesh.vertices()) points.push_back(place.apply(v));
  std::vector<std::array<std::size_t, 3>> faces;
  faces.reserve(mesh.triangleCount());
  for (std::size_t i = 0; i < mesh.triangleCount(); ++i) {
    const TriangleIndices& t = mesh.triangles()[i];
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) continue;  // bounds nothing
    if (CGAL::collinear(points[t[0]], points[t[1]], points[t[2]]))
      throw std::runtime_error("triangle " + std::to_string(i) +
                               " has collinear corners (CGAL::Side_of_triangle_mesh needs non-degenerate faces)");
    faces.push_back({t[0], t[1], t[2]});
  }
  // Splits non-manifold vertices (keeps a consistent orientation, which a closed mesh has).
  CGAL::Polygon_mesh_processing::orient_polygon_soup(points, faces);
  CGAL::Polygon_mesh_processing::polygon_soup_to_polygon_mesh(points, faces, impl_->mesh);
  impl_->side = std::make_unique<CGAL::Side_of_triangle_mesh<Impl::SurfaceMesh, K>>(impl_->mesh);
}

ExactSolid::~ExactSolid() = default;

bool ExactSolid::contains(const Vec3& p) const { return contains(toPoint(p)); }
bool ExactSolid::contains(const Point& p) const { return (*impl_->side)(p) != CGAL::ON_UNBOUNDED_SIDE; }

}  // namespace crux::exact
