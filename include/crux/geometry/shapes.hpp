#pragma once
/// @file shapes.hpp  The primitive shapes of the geometry layer: small value types.
///
/// Every shape is a closed point set (touching counts as intersecting). Degenerate shapes are
/// the lower-dimensional sets they collapse to: a sphere of radius 0 is a point, an AABB or OBB
/// with a zero extent is flat, a triangle with collinear or repeated corners is the segment or
/// point it spans, a segment with start == end is a point.
///
/// Shapes are aggregates; query functions assume valid shapes. `validate(shape)` (and the
/// batch protocol, which calls it) checks the documented preconditions and throws
/// crux::InvalidInput naming the field.

#include <crux/error.hpp>
#include <crux/math.hpp>

#include <limits>
#include <string>

namespace crux {

/// Half-line {origin + s*dir : s >= 0}. `dir` is non-zero and need not be unit; distances
/// reported along a ray (t) are in world units, i.e. s*|dir|.
struct Ray {
  Vec3 origin = Vec3::Zero();
  Vec3 dir = Vec3::UnitX();
};

/// Closed segment {start + s*(end-start) : 0 <= s <= 1}; start == end is a point.
struct Segment {
  Vec3 start = Vec3::Zero();
  Vec3 end = Vec3::Zero();
};

/// Closed ball {x : |x - center| <= radius}; radius >= 0 (0 is a point).
struct Sphere {
  Vec3 center = Vec3::Zero();
  Real radius = 0;
};

/// Closed axis-aligned box {x : min <= x <= max per axis}; a zero extent is a flat box.
struct Aabb {
  Vec3 min = Vec3::Zero();
  Vec3 max = Vec3::Zero();

  /// The empty box (min = +inf, max = -inf): the identity of `grow`. Not a valid query shape.
  static Aabb empty() {
    constexpr Real inf = std::numeric_limits<Real>::infinity();
    return {Vec3::Constant(inf), Vec3::Constant(-inf)};
  }
  /// True for the empty box (some min > max).
  bool isEmpty() const { return (min.array() > max.array()).any(); }
  Vec3 center() const { return (min + max) * Real(0.5); }
  /// Half extents (max - min) / 2.
  Vec3 half() const { return (max - min) * Real(0.5); }
  /// Grows the box to contain p.
  void grow(const Vec3& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  /// Grows the box to contain b.
  void grow(const Aabb& b) {
    min = min.cwiseMin(b.min);
    max = max.cwiseMax(b.max);
  }
  /// Surface area (0 for the empty box); the cost measure of the SAH.
  Real area() const {
    if (isEmpty()) return 0;
    const Vec3 e = max - min;
    return 2 * (e.x() * e.y() + e.y() * e.z() + e.z() * e.x());
  }
};

/// Closed oriented box {center + axes*s : |s_i| <= half_i}. The columns of `axes` are the world
/// directions of the box's local x, y, z and are orthonormal; half >= 0. Axes rounded to Real
/// are orthonormal only to a few ulps (validate accepts kObbOrthonormalityTolerance): the
/// overlap, ray and closest-point routines then take the box as {x : |axesᵀ(x − center)|_i <=
/// half_i}, its axes as face normals, as the exact oracle does; the convex routines (GJK/EPA,
/// ConvexShape's support) take the span above, ~1 ulp of the extents away (docs/geometry.md).
struct Obb {
  Vec3 center = Vec3::Zero();
  Vec3 half = Vec3::Zero();
  Mat3 axes = Mat3::Identity();
};

/// The plane {x : dot(normal, x) = d} itself (not a half-space). `normal` is non-zero and
/// need not be unit.
struct Plane {
  Vec3 normal = Vec3::UnitZ();
  Real d = 0;
};

/// The closed 2-D triangle with corners a, b, c (not its plane). Collinear or repeated corners
/// make it the segment or point they span.
struct Triangle {
  Vec3 a = Vec3::Zero();
  Vec3 b = Vec3::Zero();
  Vec3 c = Vec3::Zero();

  const Vec3& operator[](int i) const { return i == 0 ? a : (i == 1 ? b : c); }
};

/// Relative tolerance on |axesᵀ·axes - I| accepted by validate(Obb): 1000 ulps of Real.
inline constexpr Real kObbOrthonormalityTolerance = Real(1000) * std::numeric_limits<Real>::epsilon();

/// Throws InvalidInput unless every coordinate is finite and dir is non-zero.
void validate(const Ray& ray, const std::string& name = "ray");
/// Throws InvalidInput unless every coordinate is finite.
void validate(const Segment& segment, const std::string& name = "segment");
/// Throws InvalidInput unless finite with radius >= 0.
void validate(const Sphere& sphere, const std::string& name = "sphere");
/// Throws InvalidInput unless finite with min <= max on every axis.
void validate(const Aabb& box, const std::string& name = "aabb");
/// Throws InvalidInput unless finite, half >= 0 and axes orthonormal within
/// kObbOrthonormalityTolerance.
void validate(const Obb& box, const std::string& name = "obb");
/// Throws InvalidInput unless finite with a non-zero normal.
void validate(const Plane& plane, const std::string& name = "plane");
/// Throws InvalidInput unless every coordinate is finite (degenerate triangles are valid).
void validate(const Triangle& triangle, const std::string& name = "triangle");
/// Throws InvalidInput unless every coordinate of p is finite.
void validatePoint(const Vec3& p, const std::string& name = "point");

/// The cheap preconditions of the queries, without throwing: every coordinate finite, a ray's
/// direction and a plane's normal non-zero (squared length > 0 in double), a radius and half
/// extents >= 0, an AABB's min <= max. validate(...) checks the same (and an OBB's orthonormal
/// axes) and throws InvalidInput naming the field. Queries given an input that fails these answer
/// nothing (no hit, no overlap, an empty list) and, in builds with CRUX_CHECK_PRECONDITIONS
/// (precondition.hpp), abort with a message naming the query.
bool queryable(const Ray& ray);
bool queryable(const Segment& segment);
bool queryable(const Sphere& sphere);
bool queryable(const Aabb& box);
bool queryable(const Obb& box);
bool queryable(const Plane& plane);
bool queryable(const Triangle& triangle);
bool queryable(const Vec3& point);
/// A pose: finite translation and rotation, the rotation non-zero (its unit length is
/// validate(Transform)'s rule, model_query.hpp).
bool queryable(const Transform& pose);

/// Bounding box of a triangle.
inline Aabb bounds(const Triangle& t) {
  Aabb b{t.a, t.a};
  b.grow(t.b);
  b.grow(t.c);
  return b;
}

}  // namespace crux
