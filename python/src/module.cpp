/// @file module.cpp  The extension module crux._crux (the Python package `crux` re-exports it).

#include "arrays.hpp"
#include "bindings.hpp"

#include <crux/math.hpp>

namespace crux::python {
namespace {

/// What the batch methods read: `obj` as rows of `width` Reals (for tests of the zero-copy rule).
py::array readRows(py::handle obj, std::size_t width) { return asRows(obj, width, "array").array; }

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
