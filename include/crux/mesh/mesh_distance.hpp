#pragma once
/// @file mesh_distance.hpp  Distance and closest points between two triangle meshes under rigid
/// transforms (surfaces: a mesh wholly inside a closed mesh is at the distance of the surfaces).
///
/// Simultaneous best-first descent of both 4-wide BVHs (the bounding-volume-tree distance query of
/// Larsen, Gottschalk, Lin & Manocha, "Fast Proximity Queries with Swept Sphere Volumes", 1999):
/// subtree pairs wait in a fixed-capacity min-heap ordered by a lower bound, each popped pair is
/// followed down its nearest child pair (the larger subtree split into its four lanes), and the
/// search ends when the smallest pending bound exceeds the best distance. Bounds: b's box as an
/// OBB in a's frame (Euclidean box gaps); with the distance part of a MeshQueryData
/// (MeshDistanceAccel) on both sides instead the two oriented boxes (gap on the line of
/// centres, then, for pairs close against their size, Euclidean gaps in either box's frame); at
/// leaves, the triangles' corners projected on the line of centres. Leaf pairs call
/// closestPoints(Triangle, Triangle) (triangle_distance.hpp), so the answer is exactly the
/// minimum over all triangle pairs of that function (the brute-force path, QueryPath::BruteForce,
/// computes it literally). Intersecting surfaces give distance 0 with a common point.
/// No dynamic allocation and no exceptions on the query path (options are validated first).

#include <crux/geometry/raycast.hpp>
#include <crux/geometry/triangle_distance.hpp>
#include <crux/mesh/mesh.hpp>
#include <crux/mesh/mesh_query.hpp>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace crux {

class MeshQueryData;

/// Oriented boxes around every subtree of a mesh's 4-wide BVH (the root and every lane,
/// numbered as wideSubtree numbers them), fitted to the subtree's triangle corners (principal
/// axes of their covariance, Gottschalk, Lin & Manocha, "OBBTree", 1996), for the distance
/// query's bounds: a nearly flat surface patch gets a thin box, so pairs of patches are bounded
/// almost as tightly as FCL's RSS volumes do, where the BVH's axis-aligned boxes are as thick as
/// the patch is wide. Built once per mesh (O(n log n) time, 64 bytes per subtree and 36 per
/// triangle in float builds) as the distance part of the caller-held MeshQueryData
/// (mesh_query_data.hpp), which records the mesh's geometryId: after Mesh::setVertices (or
/// given with another mesh) the distance query refuses it with InvalidInput
/// (requireCurrentGeometry), never reading the old corners; MeshQueryData::refresh rebuilds it.
class MeshDistanceAccel {
 public:
  /// One subtree's box: centre, unit axes (columns), half extents along them; `child` is the
  /// wide node whose lanes are the subtree's children (subtrees wideLaneId(child, 0..3)), or
  /// kLeaf, or kUnused for an unused lane (a zero placeholder: the query with both meshes' data
  /// bounds it with the node's other lanes and masks it out, never reading the BVH's node). One
  /// cache line per box in float builds, so a pair's bound reads one line per side.
  struct alignas(64) Node {
    Mat3 axes = Mat3::Identity();
    Vec3 center = Vec3::Zero();
    Vec3 half = Vec3::Zero();
    std::uint32_t child = kLeaf;
  };
  static constexpr std::uint32_t kLeaf = 0xffffffffu;
  static constexpr std::uint32_t kUnused = 0xfffffffeu;
  MeshDistanceAccel() = default;
  /// Fits a box to every subtree of mesh.bvh() and copies the triangle corners in slot order.
  explicit MeshDistanceAccel(const Mesh& mesh);
  const std::vector<Node>& nodes() const { return nodes_; }
  /// The corners of the triangle in BVH slot k are corners()[3k], [3k+1], [3k+2] (a copy of
  /// Mesh::slotTriangle(k) laid out in leaf order: a leaf's triangles are read contiguously).
  const std::vector<Vec3>& corners() const { return corners_; }
  /// For a leaf (child == kLeaf): its triangles are slots [first, first + count) (the BVH
  /// leaf's, kept next to the boxes so the query reads no BVH node).
  struct Range {
    std::uint32_t first = 0, count = 0;
  };
  const std::vector<Range>& leafRanges() const { return ranges_; }
  /// Bytes held (boxes, corners, leaf ranges).
  std::size_t memoryBytes() const;

 private:
  std::vector<Node> nodes_;
  std::vector<Vec3> corners_;
  std::vector<Range> ranges_;
};

namespace mesh_detail {

/// Internal (declared here for the tests): the first node-pair bound of the accelerated distance
/// query, for the up to 4 child pairs of one expansion together in SIMD lanes (GCC/Clang vector
/// extension: SSE on x86-64 in either precision; unused lanes are the caller's to mask). For pair l,
/// oriented boxes a[l] (mesh a's frame) and b[l] (b's frame, placed in a's by x_a = R·x_b + t):
///  - d[·][l] = (R·b.center + t) − a.center, the centre offset in a's frame;
///  - e[·][l] = b.center + Rᵀ·(t − a.center), the same offset in b's frame (≈ Rᵀ·d);
///  - dA[·][l] = a.axesᵀ·d and dB[·][l] = b.axesᵀ·e (in each box's own frame);
///  - len2[l] = |dA|², extent[l] = a.half·|dA| + b.half·|dB| (both radii on d, times |d|);
///  - bound[l]: the separating-axis gap on the line of centres (|dA| − extent/|dA|) − pad
///    (Gottschalk, Lin & Manocha's OBB test on one axis); +inf when len2 − extent > keep·|dA|
///    (the pair is farther than keep; no division needed), −inf when dA = 0.
/// Sums are taken left to right ((x0·y0 + x1·y1) + x2·y2; extent = (radius A) + (radius B)), so
/// a scalar evaluation in that order gives the same bits in every lane (tested).
struct ObbPairOffsets {
  Real d[3][4];  ///< [component][pair], as every member
  Real e[3][4];
  Real dA[3][4];
  Real dB[3][4];
  Real len2[4];
  Real extent[4];
  Real bound[4];
};
void obbPairOffsets(const MeshDistanceAccel::Node* const (&a)[4], const MeshDistanceAccel::Node* const (&b)[4],
                    const Mat3& R, const Vec3& t, Real keep, Real pad, ObbPairOffsets& out);

}  // namespace mesh_detail

/// Parameters of distance(Mesh, Transform, Mesh, Transform, options).
struct MeshDistanceOptions {
  /// Only pairs at distance <= maxDistance are searched: when none exists the answer is
  /// found == false ("no pair closer than maxDistance"), usually after visiting few nodes.
  Real maxDistance = kNoLimit;
  /// Early out: stop as soon as a pair at distance <= stopDistance is found (then `distance`
  /// is an upper bound on the true distance, itself <= stopDistance). 0 (default): exact
  /// minimum, except that a pair at distance exactly 0 ends the search.
  Real stopDistance = 0;
  QueryPath path = QueryPath::Bvh;  ///< BruteForce: every triangle pair (the reference)
  /// Optional per-mesh data (mesh_query_data.hpp) of mesh a / mesh b with the distance part,
  /// current for that mesh (one built from another mesh, or before the mesh's last setVertices,
  /// throws InvalidInput naming the field). Same answer, fewer node pairs visited near contact
  /// (fewest with both).
  const MeshQueryData* dataA = nullptr;
  const MeshQueryData* dataB = nullptr;
};

/// Result of mesh–mesh distance. Points in world space.
struct MeshMeshDistanceResult {
  bool found = false;          ///< a triangle pair within maxDistance exists
  Real distance = kNoLimit;    ///< minimum over triangle pairs (>= 0; 0 when the surfaces touch)
  Vec3 pointA = Vec3::Zero();  ///< closest point on mesh a (world)
  Vec3 pointB = Vec3::Zero();  ///< closest point on mesh b (world)
  std::uint32_t triangleA = 0; ///< triangle of a realising it
  std::uint32_t triangleB = 0; ///< triangle of b realising it
  std::uint32_t featureA = 0;  ///< feature of triangleA (featureId, triangle_distance.hpp)
  std::uint32_t featureB = 0;  ///< feature of triangleB
  bool stoppedEarly = false;   ///< ended by stopDistance (distance is then an upper bound)
};

/// Distance between mesh a (placed by ta) and mesh b (placed by tb), computed in a's frame
/// (b mapped by ta⁻¹∘tb). Among pairs at equal distance the one found first is kept (not
/// necessarily the lowest indices). Throws InvalidInput when maxDistance or stopDistance is NaN
/// or negative (naming the field); otherwise never throws, never allocates.
MeshMeshDistanceResult distance(const Mesh& a, const Transform& ta, const Mesh& b, const Transform& tb,
                                const MeshDistanceOptions& options = {});

}  // namespace crux
