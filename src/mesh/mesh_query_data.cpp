// MeshQueryData: the caller-held per-mesh data of contact and distance queries, keyed to the
// mesh's geometry id (mesh_query_data.hpp).

#include <crux/mesh/mesh_query_data.hpp>

#include <crux/error.hpp>

#include <string>

namespace crux {

MeshQueryData::MeshQueryData(const Mesh& mesh, MeshQueryParts parts) : parts_(parts), geometryId_(mesh.geometryId()) {
  if (holds(parts, MeshQueryParts::Contacts)) adjacency_.emplace(mesh);
  if (holds(parts, MeshQueryParts::Distance)) distance_.emplace(mesh);
}

bool MeshQueryData::refresh(const Mesh& mesh) {
  if (parts_ == MeshQueryParts::None || geometryId_ == mesh.geometryId()) return false;
  *this = MeshQueryData(mesh, parts_);
  return true;
}

void MeshQueryData::require(const Mesh& mesh, MeshQueryParts part, const char* field) const {
  if (!holds(parts_, part))
    throw InvalidInput(std::string(field) + ": this MeshQueryData was built without its " +
                       (part == MeshQueryParts::Contacts ? "contacts" : "distance") +
                       " part (MeshQueryParts), which this query reads");
  requireCurrentGeometry(mesh, geometryId_, field);
}

const MeshAdjacency& MeshQueryData::adjacencyFor(const Mesh& mesh, const char* field) const {
  require(mesh, MeshQueryParts::Contacts, field);
  return *adjacency_;
}

const MeshDistanceAccel& MeshQueryData::distanceAccelFor(const Mesh& mesh, const char* field) const {
  require(mesh, MeshQueryParts::Distance, field);
  return *distance_;
}

std::size_t MeshQueryData::memoryBytes() const {
  return (adjacency_ ? adjacency_->memoryBytes() : 0) + (distance_ ? distance_->memoryBytes() : 0);
}

const MeshQueryData& MeshQueryDataOnDemand::get(MeshQueryParts part) const {
  if (part != MeshQueryParts::Contacts && part != MeshQueryParts::Distance)
    throw InvalidInput("MeshQueryDataOnDemand::get: part must be MeshQueryParts::Contacts or Distance");
  const int k = part == MeshQueryParts::Contacts ? 0 : 1;
  std::call_once(once_[k], [&] { data_[k] = std::make_unique<MeshQueryData>(*mesh_, part); });
  return *data_[k];
}

}  // namespace crux
