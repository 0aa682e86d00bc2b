#pragma once
/// @file mesh.hpp  Indexed triangle meshes: flat vertex and index arrays plus their BVH.
///
/// Topology is immutable; vertex positions may be replaced (deforming meshes), after which the
/// BVH is refitted, not rebuilt. Degenerate (zero-area) and duplicate triangles are kept: they
/// obey the geometry layer's semantics (a degenerate triangle is its segment/point) and never
/// produce NaN. Models share one Mesh (and so one BVH) by std::shared_ptr<const Mesh>.

#include <crux/geometry/shapes.hpp>
#include <crux/mesh/bvh.hpp>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace crux {

/// Three vertex indices of a triangle.
using TriangleIndices = std::array<std::uint32_t, 3>;

/// Watertightness report of a mesh (closedness()): every undirected edge of its triangles with
/// three distinct vertex indices must be used by exactly two of them, once in each direction
/// (consistently oriented). Triangles repeating a vertex index span no surface and are skipped
/// (their edges would cancel in pairs).
struct MeshClosedness {
  std::size_t boundaryEdges = 0;      ///< undirected edges used by exactly one triangle
  std::size_t nonManifoldEdges = 0;   ///< undirected edges used by more than two triangles
  std::size_t inconsistentEdges = 0;  ///< edges used twice in the same direction
  std::size_t skippedTriangles = 0;   ///< triangles repeating a vertex index (ignored)
  std::size_t effectiveTriangles = 0; ///< triangles with three distinct vertex indices
  /// First offending edge (smallest (i, j), i < j) and how many triangles use it; valid when
  /// !closed().
  std::uint32_t edgeI = 0, edgeJ = 0;
  std::size_t edgeUses = 0;
  bool edgeSameDirection = false;  ///< the offending edge is used twice in one direction
  /// Closed: at least one effective triangle, and every edge paired once in each direction.
  bool closed() const {
    return effectiveTriangles > 0 && boundaryEdges == 0 && nonManifoldEdges == 0 && inconsistentEdges == 0;
  }
  /// Human-readable reason for !closed() (empty when closed), naming the first offending edge.
  std::string reason(const std::string& meshName) const;
};

/// What a mesh is made of, for `crux info` and sanity checks.
struct MeshStats {
  std::size_t triangles = 0;
  std::size_t vertices = 0;
  Aabb bounds = Aabb::empty();
  std::size_t degenerateTriangles = 0;  ///< zero area (collinear or repeated corners), exact test
  std::size_t duplicateTriangles = 0;   ///< same vertex set as an earlier triangle (any order)
  MeshClosedness edges;                 ///< the edge census of closedness()
  /// Closed as MeshVolume requires it (edges.closed()).
  bool closed() const { return edges.closed(); }
};

/// An indexed triangle mesh with flat arrays and a BVH over its triangles.
class Mesh {
 public:
  /// Validates the arrays and builds the BVH. Throws InvalidInput (message starts with `name`)
  /// on an empty mesh, an index out of range (naming the triangle) or a non-finite vertex
  /// (naming the vertex).
  Mesh(std::vector<Vec3> vertices, std::vector<TriangleIndices> triangles, std::string name = "mesh",
       const BvhBuildOptions& options = {});

  const std::vector<Vec3>& vertices() const { return vertices_; }
  const std::vector<TriangleIndices>& triangles() const { return triangles_; }
  std::size_t triangleCount() const { return triangles_.size(); }
  std::size_t vertexCount() const { return vertices_.size(); }
  const std::string& name() const { return name_; }
  /// The mesh's tree: a 4-wide BVH (built by binned SAH, collapsed 4-wide: buildWideBvh; lane
  /// boxes stored by coordinate for one SIMD test of four), refitted by setVertices. Every mesh
  /// query walks it (docs/bvh.md).
  const WideBvh& bvh() const { return bvh_; }
  /// Identifies the current vertex positions: unique to each constructed mesh and renewed by
  /// every setVertices (copies share it). Caller-held accelerators record it and check it.
  std::uint64_t geometryId() const { return geometryId_; }
  /// Bounds of all vertices (= the union of the BVH root's lanes).
  const Aabb& bounds() const { return bounds_; }
  /// The largest |coordinate| of bounds(): the scale of the mesh queries' rounding pads, kept
  /// with the geometry so that no query recomputes it.
  Real scale() const { return scale_; }
  /// Corner positions of triangle i.
  Triangle triangle(std::uint32_t i) const {
    const TriangleIndices& t = triangles_[i];
    return {vertices_[t[0]], vertices_[t[1]], vertices_[t[2]]};
  }
  /// Corner positions of the triangle in BVH slot k, i.e. triangle(bvh().primIndices[k]), read
  /// from a copy of the index array in BVH leaf order, so a leaf's triangles are contiguous in
  /// memory (one cache line instead of one scattered load per triangle).
  Triangle slotTriangle(std::uint32_t k) const {
    const TriangleIndices& t = slotTriangles_[k];
    return {vertices_[t[0]], vertices_[t[1]], vertices_[t[2]]};
  }
  /// The vertex indices of the triangle in BVH slot k (slotTriangle(k)'s corners).
  const TriangleIndices& slotIndices(std::uint32_t k) const { return slotTriangles_[k]; }
  /// Every slot triangle's corners in BVH slot order: slotTriangle(k) at [3k, 3k + 3). The copy
  /// MeshDistanceAccel keeps so that a leaf's triangles are read contiguously, without the
  /// index gather.
  std::vector<Vec3> slotCorners() const;
  /// Replaces the vertex positions (same count, finite) and refits the BVH (refitWideBvhSlots,
  /// from the slot-ordered triangles: no gather, no allocation beyond the new array itself).
  void setVertices(std::vector<Vec3> vertices);
  /// Counts triangles, vertices, degenerate and duplicate triangles and edge manifoldness.
  MeshStats stats() const;
  /// Bytes held by the vertex and index arrays and the BVH.
  std::size_t memoryBytes() const;
  /// Seconds the last BVH build took (for `crux info`).
  double buildSeconds() const { return buildSeconds_; }

 private:
  void updateBounds();  ///< bounds_ and scale_ from the tree

  std::vector<Vec3> vertices_;
  std::vector<TriangleIndices> triangles_;
  std::vector<TriangleIndices> slotTriangles_;  ///< triangles_ permuted by bvh_.primIndices
  std::string name_;
  WideBvh bvh_;
  Aabb bounds_ = Aabb::empty();
  Real scale_ = 0;
  std::uint64_t geometryId_ = 0;
  double buildSeconds_ = 0;
};

/// Loads a triangle mesh: OFF by crux's own strict reader, every other format (OBJ, PLY, STL
/// ASCII/binary, glTF, ...) by assimp, in this process: polygons are triangulated, identical
/// vertices merged, every mesh of the file placed by its node transforms and concatenated.
/// Points and lines are ignored. Throws InvalidInput naming the file and the problem (missing,
/// unreadable or malformed file, no triangles, non-finite vertices, more memory than is
/// available). assimp 5.2 crashes on some malformed files (docs/fuzzing.md): for untrusted files
/// use loadMesh(path, LoadMeshOptions) with MeshImportIsolation::Subprocess (mesh_io.hpp).
Mesh loadMesh(const std::string& path, const BvhBuildOptions& options = {});

/// The one check of every caller-held object derived from a mesh's geometry (MeshQueryData,
/// mesh_query_data.hpp): throws InvalidInput unless `builtFrom`, the Mesh::geometryId the object
/// recorded when it was built, is `mesh`'s current one, i.e. the object was built from this mesh
/// (or a copy) and no setVertices has moved its vertices since. `object` names the object in the
/// message, which also names the mesh and says to rebuild it. No allocation unless it throws.
void requireCurrentGeometry(const Mesh& mesh, std::uint64_t builtFrom, const char* object);

/// Directed-edge census of the mesh's topology (sort-based, O(n log n)): the one rule of what
/// "closed" means, for Mesh::stats, MeshVolume and `crux info` (defined in mesh_volume.cpp,
/// beside the volume queries that require it).
MeshClosedness closedness(const Mesh& mesh);
/// closedness(mesh).closed().
bool isClosed(const Mesh& mesh);

}  // namespace crux
