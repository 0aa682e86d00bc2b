#pragma once
/// @file model_query.hpp  Queries against a mesh placed in the world by a rigid transform.
///
/// Each query maps its world-space shape into the mesh's space and runs the mesh query there;
/// hits are mapped back to world space. With R, t the world rotation and translation:
///  - points (ray origin, segment ends, sphere/box centres, triangle corners) map as
///    p' = Rᵀ(p - t); directions (ray direction, OBB axes, plane normal) as v' = Rᵀv;
///  - a ray keeps |dir| (R preserves length), so t and maxDistance stay world distances;
///  - a sphere keeps its radius; a plane {n·x = d} becomes {(Rᵀn)·x = d - n·t};
///  - an AABB becomes an OBB with axes Rᵀ (an AABB again when R is axis-aligned);
///  - hit points map back as R p + t, normals as R n.
/// Errata fixed: the book transformed a ray's origin as its direction, dropped the sphere
/// radius, and did not transform the plane distance.
///
/// Exactness: a rotation within kAxisAlignedRotationTolerance of one of the 24 axis-aligned
/// rotations (identity, quarter and half turns, cube-diagonal turns) is applied as its exact
/// signed-permutation matrix, and the identity transform skips the mapping. So with such a
/// rotation and an integer translation, integer-grid queries stay exact (p - t and a signed
/// permutation do not round); any other rotation rounds the mapped coordinates (relative
/// error of a few ulps), after which the mesh layer's decisions are exact on the rounded shape.
/// Snapping moves a rotation by at most the rounding of its own quaternion (a quarter turn's
/// √½ components are not representable).
///
/// Queries take validated shapes and a PlacedMesh with a non-null mesh and a unit rotation;
/// they never throw and (except raycastAll) never allocate.

#include <crux/geometry/axis_aligned.hpp>
#include <crux/mesh/mesh_distance.hpp>
#include <crux/mesh/mesh_query.hpp>

#include <limits>
#include <string>

namespace crux {

// ---- rigid transforms --------------------------------------------------------------------------

/// Relative tolerance on |q| accepted as a unit quaternion by validate(Transform):
/// | |q| - 1 | <= 1e-5. Text with 6+ significant digits (e.g. 0.707107) and every Real
/// rounding pass; a forgotten normalisation (|q| = 2, or 0.707 typed for √½) does not.
/// Accepted rotations are normalised when stored.
inline constexpr Real kUnitQuaternionTolerance = Real(1e-5);

// kAxisAlignedRotationTolerance: crux/geometry/axis_aligned.hpp.

/// Throws InvalidInput unless the translation is finite and the rotation a finite quaternion
/// with | |q| - 1 | <= kUnitQuaternionTolerance (the message names `name`.rotation or
/// `name`.translation and the value).
void validate(const Transform& transform, const std::string& name = "transform");

/// The rotation given by Euler angles in degrees, right-handed, counter-clockwise looking down
/// each axis towards the origin. Convention: extrinsic X, then Y, then Z — rotate by x about
/// the world X axis, then by y about the world Y axis, then by z about the world Z axis —
/// which is the same as intrinsic Z-Y′-X″ (yaw z, pitch y, roll x): q = q_z · q_y · q_x, i.e.
/// R = Rz(z)·Ry(y)·Rx(x) acting on column vectors. (The book used Z·X·Y with row vectors.)
/// Half angles are reduced exactly (fmod by 720°) and converted with π/180 rounded once in
/// double; half angles that are multiples of 45° use exact sines/cosines, and when all three
/// angles are multiples of 90° the result is the correctly rounded quaternion of the
/// signed-permutation rotation (errata: the book's folded DEG2RAD gave cos 90° ≈ -6.4e-7).
/// Throws InvalidInput for a non-finite angle.
Quat quatFromEulerDegrees(Real x, Real y, Real z);

// ---- placed meshes ----------------------------------------------------------------------------

/// A mesh and its world transform (a model's geometry at one instant). `mesh` must be non-null
/// and `world.rotation` a unit quaternion.
struct PlacedMesh {
  const Mesh* mesh = nullptr;
  Transform world;
};

/// Closest hit of a world-space ray on the placed mesh; t, point and normal in world space.
std::optional<MeshRayHit> raycastClosest(const PlacedMesh& m, const Ray& worldRay, const RayQueryOptions& options = {});
/// Any hit within options.maxDistance (world units).
bool raycastAny(const PlacedMesh& m, const Ray& worldRay, const RayQueryOptions& options = {});
/// Every hit, sorted by t (then triangle index); points and normals in world space.
std::vector<MeshRayHit> raycastAll(const PlacedMesh& m, const Ray& worldRay, const RayQueryOptions& options = {});
/// Does the world-space segment touch the placed mesh's surface?
bool intersects(const PlacedMesh& m, const Segment& s);
/// Does the world-space sphere touch the placed mesh's surface? (Radius kept in mesh space.)
bool overlaps(const PlacedMesh& m, const Sphere& s);
/// Does the world-space AABB touch the surface? (It is an OBB in mesh space.)
bool overlaps(const PlacedMesh& m, const Aabb& b);
/// Does the world-space OBB touch the surface?
bool overlaps(const PlacedMesh& m, const Obb& b);
/// Does the world-space plane {n·x = d} touch the surface? (d' = d - n·t in mesh space.)
bool overlaps(const PlacedMesh& m, const Plane& p);
/// Does the world-space triangle touch the surface? (Exact triangle–triangle test.)
bool overlaps(const PlacedMesh& m, const Triangle& t);
/// Model vs model: mesh–mesh (BVH vs BVH) with b expressed in a's frame by a⁻¹∘b, computed
/// exactly when both rotations are axis-aligned, so the mesh layer sees an exact relative
/// transform (it is exact in turn when that relative rotation has quaternion components in
/// {0, ±½, ±1}: the identity, half turns about axes, third turns about cube diagonals).
bool overlaps(const PlacedMesh& a, const PlacedMesh& b);
/// Model vs model distance: mesh–mesh distance (mesh_distance.hpp, BVH vs BVH) with b in a's
/// frame by the same exact-when-axis-aligned relative transform as overlaps(a, b); points are
/// returned in world space. Throws InvalidInput for NaN/negative option bounds.
MeshMeshDistanceResult distance(const PlacedMesh& a, const PlacedMesh& b, const MeshDistanceOptions& options = {});

/// Relative pad of the world bounds under a rotation that is not axis-aligned: the bounds grow
/// by kWorldBoundsPad·(max |mesh bound| + max |t|), 64 ulps, above the rounding of R·c + t and
/// |R|·h (about 25 ulps of that scale, R from the quaternion included).
inline constexpr Real kWorldBoundsPad = 64 * std::numeric_limits<Real>::epsilon();

/// World-space bounding box of a placed mesh: the mesh's local AABB as an OBB, bounded by
/// |R|·half around R·centre + t (RTCD 4.2.6), padded by kWorldBoundsPad so it contains every
/// world-space vertex. For an axis-aligned rotation it is the exact image of the local box,
/// with the additions of t rounded outwards (exact for integer input).
Aabb worldBounds(const PlacedMesh& m);
/// World-space oriented bounding box of a placed mesh: the local AABB under the transform
/// (axes = R; half extents padded like worldBounds when R is not axis-aligned).
Obb worldObb(const PlacedMesh& m);

}  // namespace crux
