#pragma once
/// @file mesh_volume.hpp  Closed (watertight) meshes as solids: closedness, point-in-mesh and
/// volume-mode overlap tests.
///
/// A closed mesh bounds a solid; volume mode treats the mesh as that closed solid (surface
/// included). FCL and Bullet only test surfaces, so a shape wholly inside a closed mesh is
/// reported free by them and overlapping by the volume tests here.
///
/// Point-in-mesh method: ray parity with exact predicates and no symbolic perturbation.
///  1. Surface: if the point lies on a triangle (exact test) it is inside (closed set).
///  2. Otherwise a ray is cast from the point along d(k) = c0 + k·c1 + k²·c2 (k = 0, 1, ...;
///     c0, c1, c2 fixed, linearly independent integer vectors) and its proper crossings of
///     triangle interiors are counted through the BVH (its nodes pruned four lanes at a time by
///     the mesh rays' padded slab test, which never drops a box the ray meets); odd = inside.
///     Every crossing decision is a sign of a triple product d·(A×B) or A·(B×C) of vertex
///     positions relative to the point, evaluated exactly (static filter, then a floating-point
///     expansion: Shewchuk 1997).
///  3. If the ray touches a triangle's edge or vertex, or runs inside a triangle's plane, the
///     direction is abandoned and k advances. Each such event confines d(k) to a fixed plane or
///     line through the origin, which a quadratic curve meets at most twice, so a direction
///     without degenerate events is found after at most 2·(4·triangles + vertices) + 1 tries
///     (in practice the first or second).
/// Why not the generalised winding number (Jacobson et al. 2013): its solid angles are
/// transcendental, so the answer near the surface rests on a threshold; ray parity needs only
/// signs, which are exact. Vertex positions relative to the point are formed once in `Wide`
/// (exact for integer-grid and most float inputs); a rounding there moves a vertex, shared by
/// all its triangles, so the tested mesh stays closed and the answer stays consistent.
/// On integer-grid inputs every answer equals the exact one.
///
/// Closedness is combinatorial (vertex indices, as `Mesh::stats`): triangles repeating a vertex
/// index are skipped (their edges cancel in pairs); geometrically degenerate triangles with
/// distinct indices (collinear corners) are ordinary triangles for closedness and are handled
/// exactly by the point test (a ray through one of them is a degenerate event).

#include <crux/mesh/mesh.hpp>

#include <cstdint>
#include <string>

namespace crux {

/// A closed mesh viewed as a solid. The constructor checks closedness once (throws
/// InvalidInput: `mesh "name" is not closed: edge (i,j) is used by 1 triangle`); queries then
/// neither allocate nor throw. Holds a reference: the mesh must outlive it and keep its
/// topology (vertex updates through Mesh::setVertices are fine as long as the surface stays
/// closed; self-intersecting surfaces are answered by parity).
class MeshVolume {
 public:
  explicit MeshVolume(const Mesh& mesh);
  MeshVolume(const Mesh&&) = delete;  ///< would dangle: the mesh must outlive the view
  const Mesh& mesh() const { return *mesh_; }

  /// Is p in the closed solid (surface points count as inside)? Ray parity, exact (see file).
  bool contains(const Vec3& p) const;
  /// Is p exactly on a triangle of the surface?
  bool onSurface(const Vec3& p) const;

  /// Volume-mode overlap: the shape touches the surface, or a point of it (sphere / OBB centre,
  /// AABB min corner, triangle corner a) is inside. (A connected shape not touching the
  /// surface is wholly inside or wholly outside.) FCL and Bullet report the inside case free.
  bool overlaps(const Sphere& s) const;
  bool overlaps(const Aabb& b) const;
  bool overlaps(const Obb& b) const;
  bool overlaps(const Triangle& t) const;

 private:
  const Mesh* mesh_;
};

/// Volume-mode mesh–mesh (a closed, placed by ta; b placed by tb, closed or not): does b touch
/// the solid of a? True when the surfaces touch or cross (crux::overlaps(Mesh, Transform, Mesh,
/// Transform), the exact BVH-vs-BVH surface test), or else when a vertex of b is in a's solid:
/// surfaces that do not touch leave every connected piece of b wholly inside or wholly outside
/// a, so one corner per triangle of b (consecutive repeats skipped) decides. b's vertices are
/// mapped into a's frame by the relative transform ta⁻¹·tb exactly as the surface test maps b's
/// triangles (identity skipped, axis-aligned rotations as exact signed permutations), so on
/// integer-grid meshes under such transforms the answer is exact. No allocation; cost
/// O(surface test + triangles(b) · point test) in the worst case (points outside a's bounds are
/// rejected by a box test first).
bool overlapsVolume(const MeshVolume& a, const Transform& ta, const Mesh& b, const Transform& tb);
/// Both closed: the solids touch. As above, plus a vertex of a inside b's solid (a wholly inside
/// b). One closed operand suffices for the overload above: the closed one is the solid and the
/// other is taken as its surface (a sheet wholly inside a closed mesh overlaps it).
bool overlapsVolume(const MeshVolume& a, const Transform& ta, const MeshVolume& b, const Transform& tb);

/// pointInside for a mesh not yet known to be closed: checks closedness (O(n log n),
/// allocates) then MeshVolume::contains. Throws InvalidInput when the mesh is not closed.
/// Use MeshVolume for repeated queries.
bool pointInside(const Mesh& mesh, const Vec3& p);

/// Volume-mode overlaps for a mesh not yet known to be closed (as pointInside: checks
/// closedness each call, throws InvalidInput if not closed). See MeshVolume::overlaps.
bool overlapsVolume(const Mesh& mesh, const Sphere& s);
bool overlapsVolume(const Mesh& mesh, const Aabb& b);
bool overlapsVolume(const Mesh& mesh, const Obb& b);
bool overlapsVolume(const Mesh& mesh, const Triangle& t);

}  // namespace crux
