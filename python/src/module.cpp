/// @file module.cpp  The extension module crux._crux (the Python package `crux` re-exports it).

#include "arrays.hpp"
#include "bindings.hpp"

#include <crux/math.hpp>
#include <crux/mesh/batch_query.hpp>

#include <pybind11/stl.h>

#include <chrono>
#include <optional>
#include <vector>

namespace crux::python {
namespace {

/// What the batch methods read: `obj` as rows of `width` Reals (for tests of the zero-copy rule).
py::array readRows(py::handle obj, std::size_t width) { return asRows(obj, width, "array").array; }

/// The reference of bench/python/bench_rays.py: wall seconds of each of `runs` calls of C++'s batch
/// raycastClosest (batch_query.hpp) on one thread over `rays`, into one output vector allocated
/// (and written) before the first call, as a C++ caller reusing its buffer would.
std::vector<double> rayClosestReferenceSeconds(const PyMesh& mesh, py::handle raysIn, int runs) {
  const Rows rows = asRows(raysIn, 6, "rays");
  validateRows<Ray>(rows);
  const Span<const Ray> rays(rows.as<Ray>(), rows.count);
  std::vector<std::optional<MeshRayHit>> out(rows.count);
  std::vector<double> seconds;
  py::gil_scoped_release release;
  for (int r = 0; r < runs; ++r) {
    const auto start = std::chrono::steady_clock::now();
    raycastClosest(mesh.mesh(), rays, Span<std::optional<MeshRayHit>>(out), {}, ParallelOptions{1, 0});
    seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return seconds;
}

}  // namespace
}  // namespace crux::python

PYBIND11_MODULE(_crux, m) {
  namespace py = pybind11;
  using namespace crux::python;
  m.doc() = "crux: exact collision detection and ray casting on triangle meshes (C++ extension).";
  m.attr("REAL") = py::dtype::of<crux::Real>();
  m.attr("DOUBLE_PRECISION") = py::bool_(std::is_same_v<crux::Real, double>);
  m.def("_read_rows", &readRows, py::arg("array"), py::arg("width"),
        "The array a batch method reads for `array` as rows of `width` Reals: the same memory when it is\n"
        "C-contiguous of dtype REAL (zero copy), else a converted copy.");
  m.def("_ray_closest_reference_seconds", &rayClosestReferenceSeconds, py::arg("mesh"), py::arg("rays"),
        py::arg("runs"),
        "Seconds of each of `runs` calls of C++'s batch raycastClosest on one thread over `rays`, into a\n"
        "reused output vector: the in-process reference of bench/python/bench_rays.py.");
  const ResultTypes& types = resultTypes();  // made at import; crux re-exports them (pickling)
  m.attr("RayHits") = types.rayHits;
  m.attr("RayHitsAll") = types.rayHitsAll;
  m.attr("ClosestPoints") = types.closestPoints;
  m.attr("MeshDistance") = types.meshDistance;
  m.attr("Contacts") = types.contacts;
  m.attr("SceneRayHits") = types.sceneRayHits;
  m.attr("CastHits") = types.castHits;
  m.attr("SceneCastHits") = types.sceneCastHits;
  m.attr("RegionHits") = types.regionHits;
  bindMesh(m);
  bindScene(m);
  bindCasts(m);
}
