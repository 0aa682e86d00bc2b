/// @file exact_raycast.cpp  Exact (CGAL Epeck) ray casts and segment tests.
///
/// Ray results: the first intersection point is found with CGAL's exact intersection
/// constructions, its ray parameter s = (p - o)·d / |d|² is computed exactly and rounded to
/// double once (CGAL::exact, not the lazy 1e-5-accurate approximation), and the world distance
/// is t = s·sqrt(|d|²) in double: |t - t_true| <= ~3 ulps(double) of t. The ray–sphere
/// distance is irrational; its hit/miss is decided exactly and t is evaluated in double from
/// the exact (individually rounded) coefficients of the quadratic, a few ulps as well.
///
/// Degenerate inputs never reach a CGAL precondition: triangles become points/segments
/// (toSimplex), zero-length segments become points, and OBB faces that collapse are mapped
/// to the segment or point they are.

#include <CGAL/intersections.h>

#include <cmath>
#include <limits>
#include <type_traits>
#include <utility>

#include "exact/exact.hpp"
#include "exact/exact_kernel.hpp"

namespace crux::exact {
namespace {

using namespace detail;

/// x rounded to double within an ulp or two: the lazy interval's midpoint when that interval
/// is already that tight, else the exact value (CGAL's own to_double on lazy numbers accepts a
/// relative error of 1e-5, far too coarse for distances).
double toDouble(const FT& x) {
  const std::pair<double, double> i = CGAL::to_interval(x);
  const double mid = 0.5 * (i.first + i.second);
  if (i.second - i.first <= 2 * std::numeric_limits<double>::epsilon() * std::abs(mid)) return mid;
  return CGAL::to_double(CGAL::exact(x));
}

/// A ray kept as its exact source and direction vector.
struct ExactRay {
  Point o;
  Vector d;
  FT dd;  ///< |d|²
  Ray3 ray() const { return Ray3(o, d); }
  /// Parameter of a point on the ray's line.
  FT param(const Point& p) const { return (p - o) * d / dd; }
};

ExactRay toExactRay(const Ray& r) {
  ExactRay e{toPoint(r.origin), toVector(r.dir), 0};
  e.dd = e.d.squared_length();
  return e;
}

/// Smallest ray parameter over an intersection object (point, segment or ray).
template <class Obj>
FT firstParam(const ExactRay& r, const Obj& obj) {
  using T = std::decay_t<Obj>;
  if constexpr (std::is_same_v<T, Point>) {
    return r.param(obj);
  } else if constexpr (std::is_same_v<T, Segment3>) {
    return (CGAL::min)(r.param(obj.source()), r.param(obj.target()));
  } else {
    static_assert(std::is_same_v<T, Ray3>, "unexpected intersection type");
    return r.param(obj.source());
  }
}

/// First ray parameter of CGAL::intersection(ray, x), if any.
template <class X>
std::optional<FT> firstParamWith(const ExactRay& r, const X& x) {
  const Ray3 ray = r.ray();
  if (!CGAL::do_intersect(ray, x)) return std::nullopt;
  const auto res = CGAL::intersection(ray, x);
  if (!res) return std::nullopt;
#if CGAL_VERSION_NR >= 1060000000
  return std::visit([&](const auto& obj) { return firstParam(r, obj); }, *res);
#else
  return boost::apply_visitor([&](const auto& obj) { return firstParam(r, obj); }, *res);
#endif
}

/// First ray parameter at which the ray meets a point / segment / triangle.
std::optional<FT> firstParamSimplex(const ExactRay& r, const Simplex& s) {
  if (const Point* p = std::get_if<Point>(&s)) {
    if (!r.ray().has_on(*p)) return std::nullopt;
    return r.param(*p);
  }
  if (const Segment3* seg = std::get_if<Segment3>(&s)) return firstParamWith(r, *seg);
  return firstParamWith(r, std::get<Triangle3>(s));
}

/// A segment, or the point it is when start == end.
std::variant<Point, Segment3> toSegmentOrPoint(const Segment& s) {
  const Point a = toPoint(s.start), b = toPoint(s.end);
  if (a == b) return a;
  return Segment3(a, b);
}

/// Does the segment-or-point meet the point / segment / triangle?
bool meets(const std::variant<Point, Segment3>& q, const Simplex& s) {
  if (const Point* p = std::get_if<Point>(&q)) {
    if (const Point* sp = std::get_if<Point>(&s)) return *p == *sp;
    if (const Segment3* ss = std::get_if<Segment3>(&s)) return ss->has_on(*p);
    return std::get<Triangle3>(s).has_on(*p);
  }
  const Segment3& seg = std::get<Segment3>(q);
  if (const Point* sp = std::get_if<Point>(&s)) return seg.has_on(*sp);
  if (const Segment3* ss = std::get_if<Segment3>(&s)) return CGAL::do_intersect(seg, *ss);
  return CGAL::do_intersect(seg, std::get<Triangle3>(s));
}

/// The OBB parallelepiped: its 12 boundary triangles (two per face, possibly degenerate) and,
/// when it is solid (no zero extent; validated axes are linearly independent), the six face
/// planes for the containment test. For a flat box the faces cover the whole point set, so no
/// containment test is needed.
struct ExactObb {
  std::array<Point, 8> corner;
  std::array<Simplex, 12> faces;
  bool solid = false;
  Point center;

  explicit ExactObb(const Obb& b)
      : corner(corners(b)),
        solid(b.half.x() > 0 && b.half.y() > 0 && b.half.z() > 0),
        center(toPoint(b.center)) {
    int f = 0;
    for (int i = 0; i < 3; ++i) {
      const int j = (i + 1) % 3, k = (i + 2) % 3;
      for (int side = 0; side < 2; ++side) {
        const int base = side << i;
        const Point& q00 = corner[base];
        const Point& q10 = corner[base | (1 << j)];
        const Point& q11 = corner[base | (1 << j) | (1 << k)];
        const Point& q01 = corner[base | (1 << k)];
        if (solid) {  // independent axes and positive extents: no face degenerates
          faces[f++] = Triangle3(q00, q10, q11);
          faces[f++] = Triangle3(q00, q11, q01);
        } else {
          faces[f++] = simplexOf(q00, q10, q11);
          faces[f++] = simplexOf(q00, q11, q01);
        }
      }
    }
  }

  /// Closed containment in the solid parallelepiped: on the centre's side of (or on) each
  /// face plane. Only meaningful when `solid`.
  bool contains(const Point& p) const {
    for (int f = 0; f < 12; f += 2) {  // one triangle per face spans its plane
      const Triangle3& t = std::get<Triangle3>(faces[f]);
      const CGAL::Orientation op = CGAL::orientation(t[0], t[1], t[2], p);
      if (op != CGAL::COPLANAR && op != CGAL::orientation(t[0], t[1], t[2], center)) return false;
    }
    return true;
  }
};

std::optional<double> worldDistance(const ExactRay& r, const std::optional<FT>& s) {
  if (!s) return std::nullopt;
  return toDouble(*s) * std::sqrt(toDouble(r.dd));
}

}  // namespace

namespace detail {

std::optional<FT> rayParamSimplex(const Ray& r, const Simplex& s) { return firstParamSimplex(toExactRay(r), s); }

double rayDistance(const Ray& r, const FT& s) { return toDouble(s) * std::sqrt(toDouble(toExactRay(r).dd)); }

bool withinRayDistance(const Ray& r, const FT& s, double maxDistance) {
  if (std::isnan(maxDistance) || maxDistance < 0) return false;
  if (std::isinf(maxDistance)) return true;
  const FT m(maxDistance);
  return s * s * toExactRay(r).dd <= m * m;
}

bool intersectsSimplex(const Segment& seg, const Simplex& s) { return meets(toSegmentOrPoint(seg), s); }

}  // namespace detail

std::optional<double> raycast(const Ray& r, const Triangle& t) {
  const ExactRay er = toExactRay(r);
  return worldDistance(er, firstParamSimplex(er, toSimplex(t)));
}

std::optional<double> raycast(const Ray& r, const Sphere& s) {
  const ExactRay er = toExactRay(r);
  const Point c = toPoint(s.center);
  const FT rr = FT(double(s.radius)) * FT(double(s.radius));
  if (CGAL::squared_distance(c, er.ray()) > rr) return std::nullopt;
  const Vector m = er.o - c;
  const FT c0 = m.squared_length() - rr;
  if (c0 <= 0) return 0.0;  // origin in the ball
  // Outside and the ray's closest approach is within r: the smaller root of
  // |d|² s² + 2 b s + c0 = 0 with b = m·d < 0 (else the closest point would be the origin).
  const FT b = m * er.d;
  const FT disc = b * b - er.dd * c0;
  const double sv = toDouble(c0) / (-toDouble(b) + std::sqrt(toDouble(disc)));
  return sv * std::sqrt(toDouble(er.dd));
}

std::optional<double> raycast(const Ray& r, const Aabb& b) {
  const ExactRay er = toExactRay(r);
  return worldDistance(er, firstParamWith(er, Cuboid(toPoint(b.min), toPoint(b.max))));
}

std::optional<double> raycast(const Ray& r, const Obb& b) {
  const ExactRay er = toExactRay(r);
  const ExactObb box(b);
  if (box.solid && box.contains(er.o)) return 0.0;
  std::optional<FT> best;
  for (const Simplex& f : box.faces) {
    const auto s = firstParamSimplex(er, f);
    if (s && (!best || *s < *best)) best = s;
  }
  return worldDistance(er, best);
}

std::optional<double> raycast(const Ray& r, const Plane& p) {
  const ExactRay er = toExactRay(r);
  const Vector n = toVector(p.normal);
  const Plane3 plane(n.x(), n.y(), n.z(), -FT(double(p.d)));
  return worldDistance(er, firstParamWith(er, plane));
}

bool intersects(const Segment& s, const Triangle& t) { return intersectsSimplex(s, toSimplex(t)); }

bool intersects(const Segment& s, const Sphere& sp) {
  const Point c = toPoint(sp.center);
  const FT rr = FT(double(sp.radius)) * FT(double(sp.radius));
  const auto q = toSegmentOrPoint(s);
  if (const Point* p = std::get_if<Point>(&q)) return CGAL::squared_distance(*p, c) <= rr;
  return CGAL::squared_distance(std::get<Segment3>(q), c) <= rr;
}

bool intersects(const Segment& s, const Aabb& b) {
  const Cuboid box(toPoint(b.min), toPoint(b.max));
  const auto q = toSegmentOrPoint(s);
  if (const Point* p = std::get_if<Point>(&q)) return !box.has_on_unbounded_side(*p);
  return CGAL::do_intersect(std::get<Segment3>(q), box);
}

bool intersects(const Segment& s, const Obb& b) {
  const ExactObb box(b);
  const auto q = toSegmentOrPoint(s);
  const Point start = toPoint(s.start);
  if (box.solid && box.contains(start)) return true;
  for (const Simplex& f : box.faces)
    if (meets(q, f)) return true;
  return false;
}

bool intersects(const Segment& s, const Plane& p) {
  const Vector n = toVector(p.normal);
  const Plane3 plane(n.x(), n.y(), n.z(), -FT(double(p.d)));
  const auto q = toSegmentOrPoint(s);
  if (const Point* pt = std::get_if<Point>(&q)) return plane.has_on(*pt);
  return CGAL::do_intersect(std::get<Segment3>(q), plane);
}

}  // namespace crux::exact
