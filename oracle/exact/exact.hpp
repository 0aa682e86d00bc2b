#pragma once
/// @file exact.hpp  The exact oracle: CGAL's exact kernel (Epeck) applied to crux shapes.
///
/// Every input coordinate is converted exactly (float/double -> exact rational), so these
/// answers are the true answers for the shapes as given. Slow; used by tests, the `exact`
/// backend and the differential fuzzer. Degenerate inputs (collinear triangles, flat boxes,
/// zero radii) are mapped to the lower-dimensional CGAL objects they are, since CGAL's
/// predicates require non-degenerate arguments.
///
/// An OBB is the set {x : |u_i·(x − c)| <= h_i} of its axes u_i exactly as given (not
/// re-orthonormalised): what crux's geometry layer tests (box coordinates axesᵀ(x − c)), the
/// parallelepiped {c + Σ s_i h_i e_i : |s_i| <= 1} of the axes' dual basis e_i (u_i·e_j = δ_ij).
/// For exactly orthonormal axes (integer-grid cases: signed permutations) e_i = u_i; for axes
/// rounded to Real the two readings differ by ~1 ulp of the extents, and this one is native's.

#include <crux/geometry/convex.hpp>
#include <crux/geometry/shapes.hpp>
#include <crux/mesh/mesh.hpp>

#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

namespace crux::exact {

using Vec3d = Eigen::Vector3d;

// ---- overlaps (exact_overlap.cpp, exact_triangle.cpp) ----
bool overlaps(const Sphere& a, const Sphere& b);
bool overlaps(const Sphere& s, const Aabb& b);
bool overlaps(const Sphere& s, const Obb& b);
bool overlaps(const Sphere& s, const Plane& p);
bool overlaps(const Aabb& a, const Aabb& b);
bool overlaps(const Aabb& a, const Obb& b);
bool overlaps(const Aabb& b, const Plane& p);
bool overlaps(const Obb& a, const Obb& b);
bool overlaps(const Obb& b, const Plane& p);
bool overlaps(const Plane& a, const Plane& b);
bool overlaps(const Triangle& a, const Triangle& b);
bool overlaps(const Triangle& t, const Sphere& s);
bool overlaps(const Triangle& t, const Aabb& b);
bool overlaps(const Triangle& t, const Obb& b);
bool overlaps(const Triangle& t, const Plane& p);

// ---- closest points (exact_closest_point.cpp) ----
/// Exact closest point of the triangle to p, rounded to double at the end.
Vec3d closestPoint(const Triangle& t, const Vec3& p);
/// Exact squared distance from p to the triangle, rounded to double at the end.
double squaredDistance(const Triangle& t, const Vec3& p);

// ---- rays and segments (exact_raycast.cpp) ----
/// Exact first-hit distance along the ray in world units (rounded to double), or nullopt.
std::optional<double> raycast(const Ray& r, const Triangle& t);
std::optional<double> raycast(const Ray& r, const Sphere& s);
std::optional<double> raycast(const Ray& r, const Aabb& b);
std::optional<double> raycast(const Ray& r, const Obb& b);
std::optional<double> raycast(const Ray& r, const Plane& p);
bool intersects(const Segment& s, const Triangle& t);
bool intersects(const Segment& s, const Sphere& sp);
bool intersects(const Segment& s, const Aabb& b);
bool intersects(const Segment& s, const Obb& b);
bool intersects(const Segment& s, const Plane& p);

// ---- distances and contacts (exact_distance.cpp; method in exact_distance.hpp) ----
// Convex operands are crux's ConvexShape views (sphere, box, capsule, triangle incl. degenerate,
// hull: its vertices, as ConvexHull::build kept them), each a core point set plus a radius.
// Poses are read by ExactRigid with Rotation::Snapped (exact_rigid.hpp): the exact rotation of
// q/|q| (rational matrix, no square root), and a rotation within crux's
// kAxisAlignedRotationTolerance of one of the 24 axis-aligned ones is that signed permutation;
// so integer / half-integer grids under axis-aligned rotations are placed exactly. Everything is
// exact up to the final rounding: squared distances and depths are exact rationals, the distance
// is sqrt(double(squared)) − rA − rB in double, points and the unit normal are the exact witnesses
// rounded (within a few ulps of the operands' magnitude). Conventions are crux's (narrowphase.md):
// normal unit from B to A, pointA − pointB = distance·normal, distance < 0 = −penetration depth.

/// How the cores (the shapes without their radii) of a pair meet.
enum class Relation : std::uint8_t {
  Separated,    ///< cores apart
  Penetrating,  ///< cores overlap with a positive depth (the Minkowski difference is solid)
  Touching,     ///< cores touch: depth 0, the origin on the boundary of the solid difference
              ///< (normal: one of the facets through it)
  Flat,         ///< the Minkowski difference is flat (polygon, segment or point) and holds the
              ///< origin: depth 0; normal = its plane's normal (segment: ⊥ to it; point: any)
              ///< oriented by the core centroids, +z when they coincide
};

/// An exact signed distance rounded once (see above). triangleA / triangleB: the mesh triangle
/// realising it when that operand is a mesh (lowest index among exact ties).
struct ExactDistance {
  double distance = 0;
  Vec3d pointA = Vec3d::Zero(), pointB = Vec3d::Zero();
  Vec3d normal = Vec3d::UnitZ();
  Relation relation = Relation::Separated;
  std::uint32_t triangleA = 0, triangleB = 0;
};

/// A contact point (crux convention: pointA − pointB = −depth·normal; depth < 0 within the margin).
struct ExactContact {
  Vec3d pointA = Vec3d::Zero(), pointB = Vec3d::Zero();
  Vec3d normal = Vec3d::UnitZ();
  double depth = 0;
  std::uint32_t triangle = 0;  ///< the mesh triangle (mesh operands)
  Relation relation = Relation::Separated;
};

/// Exact signed distance of two convex shapes.
ExactDistance distance(const ConvexShape& a, const Transform& ta, const ConvexShape& b, const Transform& tb);
/// Signed distance of a mesh (A, its surface) and a convex shape (B): the minimum over the
/// triangles of the per-triangle exact signed distance (crux's contract: the deepest triangle).
/// Brute force: every triangle whose box is not provably farther than the best so far. Empty
/// mesh: InvalidInput.
ExactDistance distance(const Mesh& mesh, const Transform& meshPose, const ConvexShape& shape,
                       const Transform& shapePose);
/// Unsigned distance between two mesh surfaces: the exact minimum over all triangle pairs
/// (O(n·m) pairs, pruned by exact box gaps; 0 with a common point when they touch or cross),
/// or nothing when it exceeds maxDistance (compared exactly).
std::optional<ExactDistance> meshDistance(const Mesh& a, const Transform& ta, const Mesh& b, const Transform& tb,
                                          double maxDistance = std::numeric_limits<double>::infinity());
/// Contacts of two convex shapes: the signed distance's witness when it is <= margin (decided
/// exactly), else nothing.
std::vector<ExactContact> contacts(const ConvexShape& a, const Transform& ta, const ConvexShape& b,
                                   const Transform& tb, double margin);
/// Contacts of a mesh (A) and a convex shape (B): one per triangle whose exact signed distance
/// is <= margin (decided exactly), its witness, ascending triangle index; not reduced, no
/// internal-edge correction.
std::vector<ExactContact> contacts(const Mesh& mesh, const Transform& meshPose, const ConvexShape& shape,
                                   const Transform& shapePose, double margin);

// ---- casts (exact_cast.cpp) ----
/// An exact linear cast: hit or miss decided exactly; for polytope pairs (radii 0: boxes,
/// triangles incl. degenerate ones, hulls) the exact rational time of impact, rounded.
struct ExactCastResult {
  bool hit = false;
  bool timeExact = false;  ///< t is known (polytope pairs); rounded shapes get hit/miss only
  double t = 0;            ///< the exact TOI rounded to nearest (timeExact)
  double tLower = 0, tUpper = 0;  ///< doubles enclosing the exact TOI (timeExact)
};
/// Linear cast of A (at ta, translated by s·motion, s in [0, 1]) against B (at tb), with the
/// cores placed as distance() places them. Polytopes: t* = min t such that the cores share a
/// point, a linear program in the convex weights of the core points and t; rounded shapes: hit
/// iff the least squared core distance over the motion, a convex quadratic program, is
/// <= (rA + rB)². Both solved by CGAL's QP solver in exact rationals.
ExactCastResult cast(const ConvexShape& a, const Transform& ta, const Vec3& motion, const ConvexShape& b,
                     const Transform& tb);

}  // namespace crux::exact
