#pragma once
/// @file convex.hpp  Convex shapes of the narrow phase: capsule, convex hull, and the one view
/// (`ConvexShape`) through which GJK, EPA and the contact generator see every convex shape.
///
/// Every convex shape is a polytope *core* (a point, a segment, a triangle, a box or a hull)
/// Minkowski-summed with a ball of radius `radius` (0 for the polytopes): a sphere is a point core,
/// a capsule a segment core. GJK and EPA run on the cores only; the radii are added in closed form
/// (van den Bergen, "Collision Detection in Interactive 3D Environments", 2003, §4.3.4), so the
/// iteration always terminates on polytopes and rounded shapes cost no extra iterations.

#include <crux/geometry/shapes.hpp>

#include <cmath>
#include <cstdint>
#include <vector>

namespace crux {

/// Closed capsule: every point within `radius` of the segment [a, b]; a == b is a sphere,
/// radius 0 a segment.
struct Capsule {
  Vec3 a = Vec3::Zero();
  Vec3 b = Vec3::Zero();
  Real radius = 0;
};

/// Throws InvalidInput unless finite with radius >= 0.
void validate(const Capsule& capsule, const std::string& name = "capsule");

/// One planar face of a ConvexHull: outward unit normal, plane offset (normal·x = offset on the
/// face) and a counter-clockwise (seen from outside) loop of vertex indices.
struct HullFace {
  Vec3 normal = Vec3::UnitZ();
  Real offset = 0;
  std::uint32_t first = 0;  ///< first entry of the loop in ConvexHull::faceVertices()
  std::uint32_t count = 0;  ///< loop length (>= 3)
};

/// Convex hull of a point set, built once (`ConvexHull::build`) and then immutable. Coplanar
/// triangles of the hull are merged into polygonal faces. Degenerate inputs give the lower-
/// dimensional hull they span: one point (dimension 0), a segment (1: two vertices, no faces),
/// a convex polygon (2: its vertices counter-clockwise around faces()[0].normal, and two faces,
/// one per side). Points within `tolerance()` of the hull built so far are dropped.
class ConvexHull {
 public:
  /// Relative tolerance of the hull build: a point is on the hull's plane (or line) when within
  /// kHullRelativeTolerance × (the bounding-box diagonal of the input) of it. 100 ulps of Real.
  static constexpr Real kHullRelativeTolerance = Real(100) * std::numeric_limits<Real>::epsilon();

  ConvexHull() = default;

  /// Builds the hull of `points` by the incremental farthest-point construction of QuickHull
  /// (Barber, Dobkin, Huhdanpaa, ACM TOMS 1996): start from an extreme simplex, repeatedly add
  /// the point farthest outside the current hull, replace its visible faces by a cone to the
  /// horizon; all tests in double with the scaled tolerance above, on the points relative to their
  /// bounding box's centre (so that hulls far from the origin are built on their own scale). Duplicates and coplanar
  /// points are handled; collinear / coplanar / single-point inputs give the segment / polygon
  /// / point. Throws InvalidInput naming `name[i]` for an empty set or a non-finite coordinate.
  static ConvexHull build(const std::vector<Vec3>& points, const std::string& name = "points");

  /// Hull vertices (a subset of the input points).
  const std::vector<Vec3>& vertices() const { return vertices_; }
  /// Faces (empty for dimension 0 and 1).
  const std::vector<HullFace>& faces() const { return faces_; }
  /// Concatenated vertex loops of the faces.
  const std::vector<std::uint32_t>& faceVertices() const { return faceVertices_; }
  /// 0 point, 1 segment, 2 polygon, 3 solid.
  int dimension() const { return dimension_; }
  /// Absolute tolerance used by the build (relative tolerance × input diagonal).
  Real tolerance() const { return tolerance_; }
  /// Index of the vertex maximising dot(v, dir) (the support mapping; linear scan).
  std::uint32_t supportIndex(const Vec3& dir) const;
  /// Volume (0 unless dimension 3) by the divergence theorem.
  Real volume() const;
  /// max |v| over the vertices: the radius of a ball about the local origin holding the hull.
  Real boundingRadius() const { return boundingRadius_; }

 private:
  std::vector<Vec3> vertices_;
  std::vector<HullFace> faces_;
  std::vector<std::uint32_t> faceVertices_;
  int dimension_ = 0;
  Real tolerance_ = 0;
  Real boundingRadius_ = 0;
};

/// What a ConvexShape's core is.
enum class ConvexKind : std::uint8_t { Sphere, Capsule, Box, Triangle, Hull };

/// A non-owning view of a convex shape in its body's local frame: a polytope core plus a radius.
/// Implicitly constructible from Sphere, Capsule, Obb, Triangle and ConvexHull, so every pair
/// query accepts those shapes directly. A ConvexHull must outlive the views of it.
struct ConvexShape {
  ConvexKind kind = ConvexKind::Sphere;
  Real radius = 0;
  Vec3 p[3] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};  ///< sphere: centre; capsule: a, b;
                                                           ///< triangle: a, b, c; box: centre, half
  Mat3 axes = Mat3::Identity();                             ///< box axes (columns)
  const ConvexHull* hull = nullptr;

  ConvexShape() = default;
  ConvexShape(const Sphere& s);      // NOLINT(google-explicit-constructor)
  ConvexShape(const Capsule& c);     // NOLINT
  ConvexShape(const Obb& b);         // NOLINT
  ConvexShape(const Triangle& t);    // NOLINT
  ConvexShape(const ConvexHull& h);  // NOLINT

  /// Number of core vertices (1 sphere, 2 capsule, 3 triangle, 8 box, hull vertex count).
  int vertexCount() const;
  /// Core vertex i in the local frame (box vertex i has local signs (bit0, bit1, bit2) of i).
  Vec3 vertex(int i) const;
  /// Radius of a ball about the local origin holding the shape: the length scale of the
  /// tolerances of the queries on it.
  Real size() const;
};

/// The cheap preconditions of the pair queries on a shape (shapes.hpp's queryable): finite core
/// points, axes and radius, radius and box half extents >= 0, a hull with points.
bool queryable(const ConvexShape& shape);

namespace detail {
/// A pair query's two shapes at their poses, as its entry check sees them.
struct ShapesAtPoses {
  const ConvexShape& a;
  const Transform& ta;
  const ConvexShape& b;
  const Transform& tb;
};
/// queryable(a) && queryable(ta) && queryable(b) && queryable(tb), with the finiteness of all 52
/// numbers tested together (one comparison: the pair queries check it on every call).
bool queryable(const ShapesAtPoses& pair);
}  // namespace detail

/// Support mapping of the core: the core vertex maximising dot(x, dir) in the local frame;
/// `index` receives its vertex index. dir need not be unit; a zero dir gives some vertex.
Vec3 supportCore(const ConvexShape& shape, const Vec3& dir, int* index = nullptr);
/// Support mapping of the whole (rounded) shape: supportCore + radius·dir/|dir|.
Vec3 support(const ConvexShape& shape, const Vec3& dir);

}  // namespace crux
