#pragma once
/// @file mesh_query_data.hpp  The one caller-held object of per-mesh data that contact and
/// distance queries read: MeshQueryData.
///
/// A Mesh is immutable in its topology and shared (by models, scenes, threads): it holds no
/// lazily built cache. What some queries need beyond the mesh and its BVH is built once per mesh
/// and kept by the caller next to it, in one MeshQueryData with up to two parts:
///   - contacts: the edge adjacency (MeshAdjacency, mesh_contact.hpp) that removes ghost contacts
///     on internal edges in contacts(Mesh, ..., ConvexShape, ...);
///   - distance: oriented boxes per BVH subtree and the triangle corners in slot order
///     (MeshDistanceAccel, mesh_distance.hpp) that speed up mesh–mesh distance near contact.
///
/// Keyed to the geometry. The object records Mesh::geometryId() when built; every query given it
/// checks that id against the mesh queried (requireCurrentGeometry, mesh.hpp) and throws
/// InvalidInput when it differs — after Mesh::setVertices, or for another mesh — so stale edge
/// flags, tolerances, boxes or corners are never read. refresh(mesh) rebuilds the parts held
/// when the id changed and is a no-op otherwise: call it after moving the vertices.
///
/// Threads. A const MeshQueryData is read-only: any number of threads may query with it at once
/// (it never builds lazily behind a const reference). refresh() and assignment mutate it and must
/// not run while a query reads it (as Mesh::setVertices must not run while the mesh is queried).

#include <crux/mesh/mesh.hpp>
#include <crux/mesh/mesh_contact.hpp>
#include <crux/mesh/mesh_distance.hpp>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>

namespace crux {

/// The parts a MeshQueryData builds (bit flags; combine with |).
enum class MeshQueryParts : std::uint8_t {
  None = 0,
  Contacts = 1,  ///< the edge adjacency of contacts() (internal-edge correction)
  Distance = 2,  ///< the oriented boxes and corners of mesh–mesh distance
  All = 3,
};
/// Union of two part sets.
constexpr MeshQueryParts operator|(MeshQueryParts a, MeshQueryParts b) {
  return MeshQueryParts(std::uint8_t(a) | std::uint8_t(b));
}
/// True when `parts` includes every part of `part`.
constexpr bool holds(MeshQueryParts parts, MeshQueryParts part) {
  return (std::uint8_t(parts) & std::uint8_t(part)) == std::uint8_t(part);
}

/// Per-mesh data of the contact and distance queries, built up front for the parts asked for and
/// checked against the mesh's geometry on every use (see the file comment). A query given data
/// without the part it needs, or data for another geometry, throws InvalidInput; a query given
/// no data (nullptr) runs without it (no internal-edge correction; axis-aligned distance bounds).
class MeshQueryData {
 public:
  /// Empty: holds no part (every query given it throws InvalidInput); refresh() cannot fill it.
  MeshQueryData() = default;
  /// Builds `parts` of `mesh` now (contacts: O(n log n) edge sort; distance: one box fit per BVH
  /// subtree) and records mesh.geometryId().
  explicit MeshQueryData(const Mesh& mesh, MeshQueryParts parts = MeshQueryParts::All);

  /// Makes the data current for `mesh`: when mesh.geometryId() differs from the one recorded
  /// (Mesh::setVertices ran, or another mesh is given) every part held is rebuilt from `mesh`.
  /// Returns whether it rebuilt. Not safe while another thread queries with this object.
  bool refresh(const Mesh& mesh);

  /// Mesh::geometryId of the mesh (and vertex positions) the parts were built from.
  std::uint64_t geometryId() const { return geometryId_; }
  /// Whether the parts describe `mesh`'s current geometry (queries accept the data for it).
  bool isCurrentFor(const Mesh& mesh) const {
    return parts_ != MeshQueryParts::None && geometryId_ == mesh.geometryId();
  }
  /// The parts held.
  MeshQueryParts parts() const { return parts_; }

  /// The contacts part for a query on `mesh`: throws InvalidInput, naming `field`, when it is not
  /// held or the data is not current for `mesh` (requireCurrentGeometry). The one check of the
  /// contact queries.
  const MeshAdjacency& adjacencyFor(const Mesh& mesh, const char* field = "data") const;
  /// The distance part for a query on `mesh`, checked as adjacencyFor.
  const MeshDistanceAccel& distanceAccelFor(const Mesh& mesh, const char* field = "data") const;

  /// Bytes held by the parts.
  std::size_t memoryBytes() const;

 private:
  /// Throws InvalidInput unless `part` is held and the data is current for `mesh`.
  void require(const Mesh& mesh, MeshQueryParts part, const char* field) const;

  std::optional<MeshAdjacency> adjacency_;
  std::optional<MeshDistanceAccel> distance_;
  MeshQueryParts parts_ = MeshQueryParts::None;
  std::uint64_t geometryId_ = 0;
};

/// The query data of one mesh whose vertices never move, one MeshQueryData per part, each built
/// on its first use: a holder that only asks for contacts builds no distance boxes, and the
/// other way round. Safe for concurrent first uses (std::call_once: one build, every caller
/// waits for it). For holders that own an immutable mesh, such as the native world's meshes
/// and Python's `crux.Mesh`; after Mesh::setVertices its data would be refused as stale.
class MeshQueryDataOnDemand {
 public:
  /// `mesh` must outlive this object and keep its vertices.
  explicit MeshQueryDataOnDemand(const Mesh& mesh) : mesh_(&mesh) {}
  /// The data holding the one part `part`: MeshQueryParts::Contacts or Distance (anything else
  /// throws InvalidInput).
  const MeshQueryData& get(MeshQueryParts part) const;

 private:
  const Mesh* mesh_;
  mutable std::once_flag once_[2];                  // contacts, distance
  mutable std::unique_ptr<MeshQueryData> data_[2];  // contacts, distance
};

}  // namespace crux
