/// @file fuzz_geometry.cpp  libFuzzer target fuzz_geometry: arbitrary Reals (NaN, Inf,
/// denormals, huge, integer-grid) into every geometry-layer query (include/crux/geometry).
///
/// Each input builds two of every shape. A shape that `validate` rejects must be rejected with
/// crux::InvalidInput (any other exception escapes and is a crash); valid shapes go through
/// every overlap, ray cast, segment test, closest point and squared distance. Checked:
///  - no crash, no UB (the fuzz build has ASan + UBSan);
///  - symmetry: overlaps(A, B) == overlaps(B, A) for every pair, including same-type pairs
///    (the only ones with a real second evaluation);
///  - a reported ray hit has 0 <= t <= maxT, and (inputs within kCoordinateLimit) finite t,
///    point and normal, the normal of unit length;
///  - within kCoordinateLimit: closest points and squared distances are finite, and the closest
///    point lies on the shape (triangle, sphere, AABB) within kOnShapeTolerance, and is no
///    farther from the query point than any triangle corner.

#include "fuzz_input.hpp"

#include <crux/error.hpp>
#include <crux/geometry/closest_point.hpp>
#include <crux/geometry/overlap.hpp>
#include <crux/geometry/raycast.hpp>
#include <crux/geometry/shapes.hpp>

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>

namespace crux::fuzz {
namespace {

/// The coordinate magnitude up to which crux documents meaningful answers (docs/limits.md, "Limits").
constexpr Wide kCoordinateLimit = 1e15;
/// Closest points may leave their shape by this many ulps of the operands' magnitude...
constexpr Wide kOnShapeUlps = 256;
/// ...plus this absolute floor: below sqrt(min normal Real) products underflow, so a distance
/// there is only known absolutely.
const Wide kOnShapeFloor = 64 * std::sqrt(Wide(std::numeric_limits<Real>::min()));

std::string str(const Vec3& v) {
  std::ostringstream os;
  os.precision(17);
  os << "[" << v.x() << ", " << v.y() << ", " << v.z() << "]";
  return os.str();
}
std::string str(const Triangle& t) { return "triangle{" + str(t.a) + ", " + str(t.b) + ", " + str(t.c) + "}"; }
std::string str(const Sphere& s) {
  std::ostringstream os;
  os.precision(17);
  os << "sphere{" << str(s.center) << ", r " << s.radius << "}";
  return os.str();
}
std::string str(const Aabb& b) { return "aabb{" + str(b.min) + ", " + str(b.max) + "}"; }
std::string str(const Obb& b) {
  return "obb{c " + str(b.center) + ", h " + str(b.half) + ", axes " + str(Vec3(b.axes.col(0))) + " " +
         str(Vec3(b.axes.col(1))) + " " + str(Vec3(b.axes.col(2))) + "}";
}
std::string str(const Plane& p) {
  std::ostringstream os;
  os.precision(17);
  os << "plane{" << str(p.normal) << ", d " << p.d << "}";
  return os.str();
}
std::string str(const Ray& r) { return "ray{" + str(r.origin) + ", dir " + str(r.dir) + "}"; }
std::string str(const Segment& s) { return "segment{" + str(s.start) + ", " + str(s.end) + "}"; }

Wide magnitude(const Vec3& v) { return wide(v).cwiseAbs().maxCoeff(); }
Wide magnitude(const Triangle& t) { return std::max({magnitude(t.a), magnitude(t.b), magnitude(t.c)}); }
Wide magnitude(const Sphere& s) { return std::max(magnitude(s.center), Wide(std::abs(s.radius))); }
Wide magnitude(const Aabb& b) { return std::max(magnitude(b.min), magnitude(b.max)); }
Wide magnitude(const Obb& b) { return std::max(magnitude(b.center), magnitude(b.half)); }
/// A plane's magnitude includes its distance from the origin |d|/|n| (a tiny normal puts it far away).
Wide magnitude(const Plane& p) {
  return std::max({magnitude(p.normal), Wide(std::abs(p.d)), std::abs(Wide(p.d)) / wide(p.normal).norm()});
}
Wide magnitude(const Ray& r) { return std::max(magnitude(r.origin), magnitude(r.dir)); }
Wide magnitude(const Segment& s) { return std::max(magnitude(s.start), magnitude(s.end)); }

/// A shape that is either valid or absent: `validate` must accept it or throw InvalidInput.
template <class Shape>
std::optional<Shape> checked(const Shape& s) {
  try {
    validate(s);
  } catch (const InvalidInput&) {
    return std::nullopt;
  }
  return s;
}

Triangle readTriangle(Input& in) {
  Triangle t;
  t.a = in.vec3();
  t.b = in.vec3();
  t.c = in.vec3();
  return t;
}

Sphere readSphere(Input& in) {
  Sphere s;
  s.center = in.vec3();
  s.radius = in.real();
  return s;
}

Aabb readAabb(Input& in) {
  Aabb b;
  b.min = in.vec3();
  b.max = in.vec3();
  return b;
}

/// OBB axes: a signed permutation of the identity (exact), a normalised quaternion, or nine
/// raw Reals (mostly rejected by validate, which is part of what is tested).
Obb readObb(Input& in) {
  Obb b;
  b.center = in.vec3();
  b.half = in.vec3();
  const std::uint8_t kind = in.byte();
  if (kind % 3 == 0) {
    static const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    const int* perm = perms[(kind / 3) % 6];
    b.axes.setZero();
    for (int i = 0; i < 3; ++i) b.axes(perm[i], i) = (kind >> (5 + i % 3)) & 1 ? Real(-1) : Real(1);
  } else if (kind % 3 == 1) {
    const Real w = in.real(), x = in.real(), y = in.real(), z = in.real();
    Quat q(w, x, y, z);
    const Real n = q.norm();
    if (std::isfinite(n) && n > 0) q.coeffs() /= n;
    b.axes = q.toRotationMatrix();
  } else {
    for (int i = 0; i < 9; ++i) b.axes(i / 3, i % 3) = in.real();
  }
  return b;
}

Plane readPlane(Input& in) {
  Plane p;
  p.normal = in.vec3();
  p.d = in.real();
  return p;
}

Ray readRay(Input& in) {
  Ray r;
  r.origin = in.vec3();
  r.dir = in.vec3();
  return r;
}

Segment readSegment(Input& in) {
  Segment s;
  s.start = in.vec3();
  s.end = in.vec3();
  return s;
}

struct Shapes {
  std::optional<Triangle> tri[2];
  std::optional<Sphere> sph[2];
  std::optional<Aabb> box[2];
  std::optional<Obb> obb[2];
  std::optional<Plane> pl[2];
};

template <class A, class B>
void checkSymmetric(const std::optional<A>& a, const std::optional<B>& b) {
  if (!a || !b) return;
  const bool ab = overlaps(*a, *b);
  const bool ba = overlaps(*b, *a);
  if (ab != ba) fail("overlaps(A, B) = " + std::to_string(ab) + " but overlaps(B, A) = " + std::to_string(ba) +
                     " for A = " + str(*a) + ", B = " + str(*b));
}

template <class A>
void checkWithAll(const std::optional<A>& a, const Shapes& s) {
  for (int j = 0; j < 2; ++j) {
    checkSymmetric(a, s.tri[j]);
    checkSymmetric(a, s.sph[j]);
    checkSymmetric(a, s.box[j]);
    checkSymmetric(a, s.obb[j]);
    checkSymmetric(a, s.pl[j]);
  }
}

template <class Shape>
void checkRaycast(const Ray& ray, const std::optional<Shape>& shape, Real maxT) {
  if (!shape) return;
  const std::optional<RayHit> hit = raycast(ray, *shape, maxT);
  if (!hit) return;
  const auto where = [&] {
    std::ostringstream os;
    os.precision(17);
    os << " for " << str(ray) << ", " << str(*shape) << ", maxT " << maxT << ": t " << hit->t << ", point "
       << str(hit->point) << ", normal " << str(hit->normal);
    return os.str();
  };
  if (!(hit->t >= 0) || !(hit->t <= maxT)) fail("ray hit outside [0, maxT]" + where());
  if (std::max(magnitude(ray), magnitude(*shape)) > kCoordinateLimit) return;
  if (!std::isfinite(hit->t) || !hit->point.allFinite() || !hit->normal.allFinite())
    fail("non-finite ray hit" + where());
  const Wide n = wide(hit->normal).norm();
  if (!(std::abs(n - 1) <= 1e-3)) fail("ray hit normal not unit" + where());
}

template <class Shape>
void checkSegment(const Segment& seg, const std::optional<Shape>& shape) {
  if (shape) (void)intersects(seg, *shape);
}

Wide onShapeTolerance(Wide scale) {
  return kOnShapeUlps * Wide(std::numeric_limits<Real>::epsilon()) * scale + kOnShapeFloor;
}

/// The closest point q of a triangle to p lies on the triangle and is no farther from p than
/// any corner. The in-triangle check (signed in-plane distance of q from each edge line) is
/// made only for triangles whose area is not tiny against their edge lengths.
void checkClosestOnTriangle(const Triangle& t, const Vec3& p) {
  const Vec3 q = closestPoint(t, p);
  const Real d2 = squaredDistance(t, p);
  const Wide scale = std::max(magnitude(t), magnitude(p));
  if (scale > kCoordinateLimit) return;
  const auto where = [&] { return " for " + str(t) + ", p " + str(p) + ": q " + str(q); };
  if (!q.allFinite()) fail("non-finite closest point" + where());
  if (!std::isfinite(d2)) fail("non-finite squared distance" + where());
  const Wide tol = onShapeTolerance(scale);
  const WVec3 wp = wide(p), wq = wide(q);
  const Wide dq = (wp - wq).norm();
  for (int i = 0; i < 3; ++i)
    if (dq > (wp - wide(t[i])).norm() + tol) fail("closest point farther than corner " + std::to_string(i) + where());
  const WVec3 a = wide(t.a), b = wide(t.b), c = wide(t.c);
  const WVec3 n = (b - a).cross(c - a);
  const Wide longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
  // Degenerate or sliver (height below 1e-3 of the longest edge): the in-triangle test's edge
  // normals are noise. Every point of a triangle is within half its height h of the boundary, so
  // q must be that near the boundary and no nearer to p than the boundary is minus h/2 (a
  // projection onto the plane 0.016 off a sliver passed the corner test above).
  if (!(n.norm() > 1e-3 * longest * longest)) {
    const Wide halfHeight = longest > 0 ? Wide(0.5) * n.norm() / longest : Wide(0);
    const auto toBoundary = [&](const WVec3& x) {
      Wide d = std::numeric_limits<Wide>::infinity();
      for (int i = 0; i < 3; ++i) {
        const WVec3 u = wide(t[i]), e = wide(t[(i + 1) % 3]) - u;
        const Wide l2 = e.squaredNorm();
        const Wide s = l2 > 0 ? std::clamp((x - u).dot(e) / l2, Wide(0), Wide(1)) : Wide(0);
        d = std::min(d, (u + s * e - x).norm());
      }
      return d;
    };
    if (toBoundary(wq) > halfHeight + tol) fail("closest point off the sliver" + where());
    if (dq < toBoundary(wp) - halfHeight - tol) fail("closest point nearer than the sliver" + where());
    return;
  }
  const WVec3 un = n.normalized();
  if (std::abs(un.dot(wq - a)) > tol) fail("closest point off the triangle's plane" + where());
  const WVec3 corners[3] = {a, b, c};
  for (int i = 0; i < 3; ++i) {
    const WVec3& u = corners[i];
    const WVec3& v = corners[(i + 1) % 3];
    const WVec3 e = v - u;
    const Wide inside = e.cross(wq - u).dot(un) / e.norm();  // > 0: on the triangle's side of edge uv
    if (inside < -tol) fail("closest point outside edge " + std::to_string(i) + where());
  }
}

void checkClosestOnSphere(const Sphere& s, const Vec3& p) {
  const Vec3 q = closestPoint(s, p);
  const Wide scale = std::max(magnitude(s), magnitude(p));
  if (scale > kCoordinateLimit) return;
  if (!q.allFinite() || !std::isfinite(squaredDistance(s, p)))
    fail("non-finite closest point or distance for " + str(s) + ", p " + str(p));
  if ((wide(q) - wide(s.center)).norm() > Wide(s.radius) + onShapeTolerance(scale))
    fail("closest point outside " + str(s) + ", p " + str(p) + ": q " + str(q));
}

void checkClosestOnAabb(const Aabb& b, const Vec3& p) {
  const Vec3 q = closestPoint(b, p);
  const Wide scale = std::max(magnitude(b), magnitude(p));
  if (scale > kCoordinateLimit) return;
  if (!q.allFinite() || !std::isfinite(squaredDistance(b, p)))
    fail("non-finite closest point or distance for " + str(b) + ", p " + str(p));
  // The clamp is exact: no tolerance.
  if ((q.array() < b.min.array()).any() || (q.array() > b.max.array()).any())
    fail("closest point outside " + str(b) + ", p " + str(p) + ": q " + str(q));
}

template <class Shape>
void checkClosestFinite(const Shape& s, const Vec3& p) {
  const Vec3 q = closestPoint(s, p);
  const Real d2 = squaredDistance(s, p);
  if (std::max(magnitude(s), magnitude(p)) > kCoordinateLimit) return;
  if (!q.allFinite() || !std::isfinite(d2))
    fail("non-finite closest point or distance for " + str(s) + ", p " + str(p) + ": q " + str(q));
}

}  // namespace

void run(const std::uint8_t* data, std::size_t size) {
  Input in(data, size);
  Shapes s;
  for (int i = 0; i < 2; ++i) {
    s.tri[i] = checked(readTriangle(in));
    s.sph[i] = checked(readSphere(in));
    s.box[i] = checked(readAabb(in));
    s.obb[i] = checked(readObb(in));
    s.pl[i] = checked(readPlane(in));
  }
  const std::optional<Ray> ray = checked(readRay(in));
  const std::optional<Segment> seg = checked(readSegment(in));
  Real maxT = in.real();
  if (std::isnan(maxT)) maxT = kNoLimit;
  Vec3 p = in.vec3();
  const bool pValid = p.allFinite();

  for (int i = 0; i < 2; ++i) {
    checkWithAll(s.tri[i], s);
    checkWithAll(s.sph[i], s);
    checkWithAll(s.box[i], s);
    checkWithAll(s.obb[i], s);
    checkWithAll(s.pl[i], s);
    if (ray) {
      checkRaycast(*ray, s.tri[i], maxT);
      checkRaycast(*ray, s.sph[i], maxT);
      checkRaycast(*ray, s.box[i], maxT);
      checkRaycast(*ray, s.obb[i], maxT);
      checkRaycast(*ray, s.pl[i], maxT);
    }
    if (seg) {
      checkSegment(*seg, s.tri[i]);
      checkSegment(*seg, s.sph[i]);
      checkSegment(*seg, s.box[i]);
      checkSegment(*seg, s.obb[i]);
      checkSegment(*seg, s.pl[i]);
    }
    if (pValid) {
      if (s.tri[i]) checkClosestOnTriangle(*s.tri[i], p);
      if (s.sph[i]) checkClosestOnSphere(*s.sph[i], p);
      if (s.box[i]) checkClosestOnAabb(*s.box[i], p);
      if (s.obb[i]) checkClosestFinite(*s.obb[i], p);
      if (s.pl[i]) checkClosestFinite(*s.pl[i], p);
    }
  }
  if (pValid && ray) checkClosestFinite(*ray, p);
  if (pValid && seg) checkClosestFinite(*seg, p);
}

}  // namespace crux::fuzz

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  crux::fuzz::run(data, size);
  return 0;
}
