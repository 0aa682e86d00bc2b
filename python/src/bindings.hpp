#pragma once
/// @file bindings.hpp  The objects the Python module wraps and the functions that bind them.

#include <crux/mesh/mesh.hpp>
#include <crux/mesh/mesh_contact.hpp>
#include <crux/mesh/mesh_query_data.hpp>
#include <crux/mesh/mesh_volume.hpp>
#include <crux/scene/scene.hpp>

#include <pybind11/pybind11.h>

#include <map>
#include <memory>
#include <mutex>
#include <shared_mutex>

namespace crux::python {

namespace py = pybind11;

/// A Python `crux.Mesh`: an immutable crux::Mesh (shared with the scenes it is added to) plus the
/// per-mesh structures some queries need, built on first use and kept: the solid view
/// (closedness checked once) and the query data of contacts (edge adjacency) and of mesh–mesh
/// distance (oriented boxes).
class PyMesh {
 public:
  explicit PyMesh(std::shared_ptr<const Mesh> mesh) : mesh_(std::move(mesh)), queryData_(*mesh_) {}
  const Mesh& mesh() const { return *mesh_; }
  const std::shared_ptr<const Mesh>& shared() const { return mesh_; }
  /// The mesh as a solid; throws InvalidInput (crux's message) when it is not closed.
  const MeshVolume& volume() const;
  /// Whether the mesh is closed (crux::isClosed, computed once).
  bool closed() const;
  /// Query data holding the one part `part` (MeshQueryParts::Contacts or Distance), each built
  /// on its first use; the mesh is immutable, so it stays current.
  const MeshQueryData& queryData(MeshQueryParts part) const { return queryData_.get(part); }

 private:
  std::shared_ptr<const Mesh> mesh_;
  mutable std::mutex lock_;
  mutable int closed_ = -1;  // unknown, 0, 1
  mutable std::unique_ptr<MeshVolume> volume_;
  MeshQueryDataOnDemand queryData_;
};

/// A Python `crux.Scene`: a crux::Scene behind a reader–writer lock (scene_bindings.cpp).
struct PyScene {
  Scene scene;
  std::map<ModelId, std::shared_ptr<PyMesh>> meshes;  // the Python meshes of the models (pickling)
  /// The local pose each model was last given (add, set_transform(s)), before the hierarchy
  /// normalised it: pickled instead of the stored one, so that the restored scene normalises the
  /// same numbers and holds the same bits. Dropped when the hierarchy recomputes the local pose
  /// (set_parent, removal of the parent); the stored pose is pickled then.
  std::map<ModelId, Transform> given;
  mutable std::shared_mutex lock;
};

/// Named tuple types of the answers, made once at import.
struct ResultTypes {
  py::object rayHits, rayHitsAll, closestPoints, meshDistance, contacts, sceneRayHits, regionHits, castHits,
      sceneCastHits;
};
const ResultTypes& resultTypes();

void bindMesh(py::module_& m);
void bindScene(py::module_& m);
/// The casts of Mesh and Scene (cast_bindings.cpp); after bindMesh and bindScene.
void bindCasts(py::module_& m);

}  // namespace crux::python
