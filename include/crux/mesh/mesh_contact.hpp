#pragma once
/// @file mesh_contact.hpp  Contacts and distance between a triangle mesh and a convex shape
/// (sphere, capsule, box, triangle, convex hull) under rigid transforms, for engine narrow phases.
///
/// Both queries run in the mesh's frame through its BVH. contacts() maps the shape into the
/// mesh's frame once (the relative pose in double), computes, corrects, merges and reduces every
/// point there, and maps only the <= 4 reduced points to the world. Per candidate triangle it
/// calls a closed-form routine for spheres and capsules (geometry/triangle_contact.hpp), the
/// separating-axis box routine (geometry/box_triangle_contact.hpp) for boxes, and the generic
/// GJK/EPA + clipping `contacts()` of contact.hpp for triangles and hulls; all of them answer the
/// generic routine's manifold (same conventions, features and clipping) up to rounding, tested
/// in tests/geometry. distance() calls gjk.hpp's `distance()` per triangle, so its per-triangle
/// answers are exactly those of `distance(triangle, meshPose, shape, shapePose)`.
///
/// BVH pruning: nodes by the shape's axis-aligned box in the mesh frame grown by the margin; a
/// sphere by its own distance to the node box, a capsule also by its segment's distance to the
/// node box's circumscribed sphere; per triangle a plane test (and for capsules a bounding-sphere
/// test, for boxes the box's face axes) rejects before any closest-point work.
///
/// Convention (as contact.hpp): A is the mesh, B the convex shape. Every normal is the unit
/// direction from B to A, i.e. from the shape into the mesh: a shape resting on an upward facing
/// floor gets normal (0, 0, -1) (minus the floor's face normal). pointA − pointB =
/// separation·normal; separation < 0 is penetration.
///
/// Internal edges (ghost contacts). A shape sliding over a flat or concave seam between two
/// triangles touches the second triangle at its edge, and the convex routine gives that contact
/// the edge's normal (tilted), which makes bodies bump. As Bullet's btAdjustInternalEdgeContacts
/// and Jolt's "active edges" do, each contact whose normal lies outside its triangle's face
/// normal cone (kMeshFaceConeCos) and whose mesh point lies on an edge (within
/// kMeshFeatureRelativeTolerance) is classified with the triangle adjacency:
///   - the edge is *active* when it has no neighbour (boundary or non-manifold) or is convex
///     (the neighbour's opposite vertex is below the triangle's plane, on the side away from the
///     shape), decided once per mesh and side (MeshAdjacency::edgeActivity); a vertex contact
///     is active when either of the triangle's two edges at it is;
///   - an *inactive* (flat or concave) feature gets the face normal instead: the contact is
///     recomputed as the shape's deepest point along the face normal against the triangle's
///     plane, and dropped when its separation exceeds the margin or its projection on the plane
///     falls outside the triangle (then the triangle under that point reports it, with its own
///     face normal); so every reported point lies on both surfaces. One exception keeps the
///     manifold from getting shallower than the truth: when the deepest dropped point is deeper
///     than every point kept (or nothing was kept), it is reported uncorrected (its own
///     feature normal) — a thin shape poking through at a flat or saddle vertex is otherwise
///     reported by no triangle at all.
/// For a sphere the features a point lies on come from the sphere routine's Voronoi region
/// (sphereTriangleContact: a face-region point has the face normal and is never corrected; an
/// edge region's edge or a corner's two edges hold the point, other edges take the per-edge
/// test), the same rule with fewer closest-point tests (tested against a point capsule, which
/// takes the per-edge path).
/// The adjacency (`MeshAdjacency`, O(n log n)) is the contacts part of the caller-held
/// `MeshQueryData` (mesh_query_data.hpp), built once per mesh and kept by the caller (a Mesh is
/// immutable and shared: it holds no lazily built cache). Without it (nullptr) no correction is
/// made. Meshes with unmerged duplicate vertices have no adjacency across those seams (loadMesh
/// merges identical vertices). Queries walk the mesh's 4-wide BVH (a box tests four lanes at
/// once). The data records the mesh's geometryId: after Mesh::setVertices its activity bits and
/// tolerances describe the old positions, and a query given it throws InvalidInput
/// (requireCurrentGeometry) instead of reading them; MeshQueryData::refresh rebuilds it then.
///
/// Reduction: per-triangle points go to a fixed buffer (kMeshContactBuffer, deepest kept on
/// overflow); points with the same mesh position (within kMeshContactMergeRelativeTolerance ×
/// shape size) and normal (within kContactFaceAngleCos) are merged keeping the deeper; then at
/// most 4 are kept: the deepest (first), the farthest from it, the one of largest area with those
/// two, and the one adding most area outside that triangle — stopping early when the next point
/// would be coincident or collinear within the merge tolerance (a capsule lying on a seam gives 2,
/// not 4 collinear points). No heap allocation, no exceptions in the queries, except the exact
/// margin decision's rare spill (contact.hpp's contacts(): a sphere or capsule within rounding
/// of the margin whose sign the filter cannot decide).

#include <crux/geometry/contact.hpp>
#include <crux/geometry/raycast.hpp>
#include <crux/mesh/mesh.hpp>
#include <crux/mesh/mesh_query.hpp>

#include <cstdint>
#include <limits>
#include <vector>

namespace crux {

class MeshQueryData;

/// Edge adjacency of a mesh: for triangle t and edge i (from corner i to corner (i+1) mod 3)
/// the index of the one other triangle sharing that undirected edge, or kNone when the edge is a
/// boundary (one triangle) or non-manifold (more than two). Built by sorting the edges. Callers
/// hold it as the contacts part of a MeshQueryData, which keys it to the mesh's geometry.
class MeshAdjacency {
 public:
  static constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  MeshAdjacency() = default;
  /// Builds the adjacency of `mesh` (vertex indices, not positions, decide sharing).
  explicit MeshAdjacency(const Mesh& mesh);
  /// Neighbour of triangle `t` across edge `edge` (0..2), or kNone.
  std::uint32_t neighbor(std::uint32_t t, int edge) const { return neighbors_[3 * std::size_t(t) + edge]; }
  /// The neighbour's vertex opposite that edge (a vertex index of the mesh), or kNone when there
  /// is no neighbour or it has no third vertex (degenerate). Kept next to the neighbour so that
  /// the contact correction reads one array instead of two (fewer cache misses per query).
  std::uint32_t oppositeVertex(std::uint32_t t, int edge) const { return opposite_[3 * std::size_t(t) + edge]; }
  /// Which edges of triangle t are active (see the internal-edge rule above), decided once here
  /// instead of per contact: bit 2·edge is set when the edge is active for a shape on the
  /// triangle's front side (the side its corner order's normal (b − a) × (c − a) points to),
  /// bit 2·edge + 1 for a shape on its back side. An edge with no neighbour is active on both
  /// sides; otherwise it is active on a side when the neighbour's opposite vertex lies below the
  /// plane, seen from that side, by more than meshFeatureTolerance(triangle) (the unit normal
  /// and that distance computed in Real, as the contact correction computes its face normal). A
  /// zero-area triangle has no face cone (its contacts are never corrected): all bits set.
  std::uint8_t edgeActivity(std::uint32_t t) const { return activity_[t]; }
  /// edgeActivity of the triangle in BVH slot k (mesh.bvh().primIndices[k]): the same data in
  /// the BVH's leaf order, read by the BVH query next to the slot's triangle (cache locality:
  /// one byte per triangle instead of the neighbour's vertex).
  std::uint8_t edgeActivityBySlot(std::uint32_t k) const { return bySlot_[k].activity; }
  /// meshFeatureTolerance of the triangle in BVH slot k, computed once here from the mesh's own
  /// triangle (the same value a query would compute: a square root and nine maxima per
  /// triangle, 2-4 % of a box-vs-mesh contact query when recomputed, docs/narrowphase.md).
  Real featureToleranceBySlot(std::uint32_t k) const { return bySlot_[k].tolerance; }
  /// Triangle count of the mesh it was built from.
  std::size_t triangleCount() const { return neighbors_.size() / 3; }
  /// Bytes held (neighbours, opposite vertices, activity, per-slot data).
  std::size_t memoryBytes() const;

 private:
  std::vector<std::uint32_t> neighbors_;
  std::vector<std::uint32_t> opposite_;
  std::vector<std::uint8_t> activity_;
  /// What a BVH query reads per triangle, in slot order, side by side (one array, not two; no
  /// speed difference was measured between the two layouts).
  struct SlotData {
    Real tolerance;
    std::uint8_t activity;
  };
  std::vector<SlotData> bySlot_;
};

/// Cosine of the face normal cone: a contact normal within acos(kMeshFaceConeCos) of the
/// triangle's normal is never corrected. The cone is the face normal itself up to rounding
/// (100 ulps of Real: 0.28° in float), because even a slightly tilted normal at a seam (a rounded
/// end just past a flat internal edge) makes a body bump.
inline constexpr Real kMeshFaceConeCos = Real(1) - Real(100) * std::numeric_limits<Real>::epsilon();
/// A mesh contact point lies on a triangle edge when within this × (the triangle's length scale:
/// longest edge + largest |coordinate|) of it: 1000 ulps of Real.
inline constexpr Real kMeshFeatureRelativeTolerance = Real(1000) * std::numeric_limits<Real>::epsilon();
/// That tolerance for one triangle: kMeshFeatureRelativeTolerance × (longest edge + largest
/// |coordinate|).
Real meshFeatureTolerance(const Triangle& tri);
/// Two candidate points merge when their mesh points are within this × the shape's size.
inline constexpr Real kMeshContactMergeRelativeTolerance = Real(1e-3);
/// Capacity of the candidate buffer before reduction.
inline constexpr int kMeshContactBuffer = 64;

/// One mesh contact point: its own normal (meshes are not planar), the triangle it lies on.
struct MeshContactPoint {
  Vec3 pointA = Vec3::Zero();  ///< world position on the mesh
  Vec3 pointB = Vec3::Zero();  ///< world position on the shape
  Vec3 normal = Vec3::UnitZ(); ///< unit, from the shape (B) to the mesh (A)
  Real separation = 0;         ///< signed: > 0 apart (speculative), < 0 penetrating
  std::uint32_t triangle = 0;  ///< triangle index in the mesh (feature id of A)
  std::uint32_t featureB = 0;  ///< feature of the shape (featureId, contact.hpp)
};

/// Up to 4 reduced points. Plain value, no heap.
struct MeshContactManifold {
  static constexpr int kMaxContactPoints = 4;
  int count = 0;
  MeshContactPoint points[kMaxContactPoints];
  /// Deepest penetration: max(0, -min separation); 0 when empty.
  Real depth() const;
};

/// Contact points between `mesh` (A, placed by meshPose) and `shape` (B, placed by shapePose)
/// with separation <= margin (>= 0): BVH query of the shape's AABB in the mesh frame grown by
/// the margin, `contacts(triangle, ...)` per candidate, internal-edge correction when `data`
/// (a MeshQueryData with the contacts part, current for this mesh: one built from another mesh,
/// or before the mesh's last setVertices, throws InvalidInput) is given, reduction to 4. `path`
/// BruteForce tests every triangle (reference). Returns out.count > 0. Throws InvalidInput for a
/// margin that is negative or not finite (validateContactMargin) or data that is stale, foreign
/// or without the contacts part; otherwise never throws and does not allocate (but for the exact
/// margin decision's rare spill, see above).
bool contacts(const Mesh& mesh, const Transform& meshPose, const ConvexShape& shape, const Transform& shapePose,
              Real margin, MeshContactManifold& out, const MeshQueryData* data = nullptr,
              QueryPath path = QueryPath::Bvh);

/// Result of distance(mesh, ..., shape, ...).
struct MeshDistanceResult {
  bool found = false;          ///< a triangle within maxDistance exists
  Real distance = kNoLimit;    ///< signed (min over triangles): separation, or -penetration depth
  Vec3 pointA = Vec3::Zero();  ///< closest point on the mesh (world)
  Vec3 pointB = Vec3::Zero();  ///< closest point on the shape (world)
  Vec3 normal = Vec3::UnitZ(); ///< unit, from the shape to the mesh
  std::uint32_t triangle = 0;  ///< triangle realising it (lowest index among equal distances)
};

/// Slack of distance()'s separating-axis pruning, relative to the pair's length scale (|mesh and
/// shape translations| + shape size + |coordinates| of the shape's box): above GJK/EPA's 1e-6
/// relative error and the bound's rounding, so pruning never changes the result.
inline constexpr Real kMeshDistancePruneRelativeTolerance = Real(1e-5);

/// Minimum over the triangles of the signed convex distance (gjk.hpp) to the shape, with BVH
/// pruning: subtrees whose box is farther from the shape's box (both in the mesh frame) than the
/// best distance so far — initially `maxDistance`, the early-out upper bound — are skipped
/// (nearest child first); a triangle whose box overlaps the shape's is skipped when a
/// separating-axis lower bound on its signed distance (its plane; a box's face axes) exceeds the
/// best by more than kMeshDistancePruneRelativeTolerance × the pair's scale (so penetrating
/// queries do not run EPA on every overlapped triangle). found == false when nothing is within
/// maxDistance. Never allocates; a NaN maxDistance throws InvalidInput.
MeshDistanceResult distance(const Mesh& mesh, const Transform& meshPose, const ConvexShape& shape,
                            const Transform& shapePose, Real maxDistance = kNoLimit,
                            QueryPath path = QueryPath::Bvh);

}  // namespace crux
