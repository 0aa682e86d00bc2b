/// @file raycast.cpp  Ray casts and segment tests against the primitive shapes.
///
/// Every hit/miss decision is a sign of a low-degree polynomial of the inputs evaluated in
/// Wide, so it is exact on the integer grid (|coordinates| <= 64). The ray–triangle edge
/// signs are exact for all inputs (static filter + exact expansion fallback), which makes the
/// triangle test watertight at shared vertices as well as shared edges. Ray parameters are
/// kept as fractions num/den with den > 0 and compared by cross-multiplication (no division
/// before the answer is known); the reported distance is computed from the winning fraction
/// at the end.

#include <array>
#include <cmath>
#include <crux/geometry/predicates.hpp>
#include <crux/geometry/raycast.hpp>
#include <limits>

namespace crux {
namespace {

using W2 = Eigen::Matrix<Wide, 2, 1>;
using predicates::TriangleKind;

/// A ray parameter s = num / den with den > 0.
struct Fraction {
  Wide num = 0;
  Wide den = 1;
  Wide value() const {
    const Wide s = num / den;
    return s >= 0 ? s : Wide(0);  // also maps NaN (underflowed den) to 0
  }
};

bool less(const Fraction& a, const Fraction& b) { return a.num * b.den < b.num * a.den; }

/// A fraction p/q with q != 0 brought to a positive denominator.
Fraction fraction(Wide p, Wide q) { return q < 0 ? Fraction{-p, -q} : Fraction{p, q}; }

Wide cross2(const W2& a, const W2& b) { return a.x() * b.y() - a.y() * b.x(); }

/// The 2-D coordinates left after dropping axis `drop` (cyclic order, as predicates::orient2d).
W2 project(const WVec3& v, int drop) { return W2(v[(drop + 1) % 3], v[(drop + 2) % 3]); }

/// True when p lies in the closed 2-D triangle abc (non-degenerate).
bool insideTriangle2D(const W2& p, const W2& a, const W2& b, const W2& c) {
  const Wide e0 = cross2(b - a, p - a), e1 = cross2(c - b, p - b), e2 = cross2(a - c, p - c);
  return (e0 >= 0 && e1 >= 0 && e2 >= 0) || (e0 <= 0 && e1 <= 0 && e2 <= 0);
}

/// First s >= 0 with s*d (a 2-D ray from the origin) on the closed segment [p, q].
std::optional<Fraction> raySegment2D(const W2& d, const W2& p, const W2& q) {
  const W2 e = q - p;
  const Wide den = cross2(d, e);
  if (den == 0) {                                // parallel lines
    if (cross2(d, p) != 0) return std::nullopt;  // distinct lines
    const Wide dp = p.dot(d), dq = q.dot(d), dd = d.squaredNorm();
    if ((dp <= 0 && dq >= 0) || (dp >= 0 && dq <= 0)) return Fraction{0, 1};  // origin on [p, q]
    if (dp < 0) return std::nullopt;                                          // both endpoints behind
    return Fraction{dp < dq ? dp : dq, dd};
  }
  const Wide cp = cross2(d, p), cq = cross2(d, q);
  if ((cp > 0 && cq > 0) || (cp < 0 && cq < 0)) return std::nullopt;  // [p, q] misses the line
  // o + s d on line pq: s cross(d, e) = cross(p, e).
  const Fraction s = fraction(cross2(p, e), den);
  if (s.num < 0) return std::nullopt;
  return s;
}

/// First s >= 0 with s*d in the closed 2-D triangle abc (a ray in its plane). A triangle that
/// is degenerate here (possible when rounding v - o collapses a tiny triangle far from the
/// origin) is the union of its edges.
std::optional<Fraction> rayTriangle2D(const W2& d, const W2& a, const W2& b, const W2& c) {
  if (cross2(b - a, c - a) != 0 && insideTriangle2D(W2::Zero(), a, b, c)) return Fraction{0, 1};
  std::optional<Fraction> best;
  const W2* v[3] = {&a, &b, &c};
  for (int i = 0; i < 3; ++i) {
    const auto s = raySegment2D(d, *v[i], *v[(i + 1) % 3]);
    if (s && (!best || less(*s, *best))) best = s;
  }
  return best;
}

/// Error-free product: a·b = hi + lo exactly (no underflow assumed).
void twoProduct(Wide a, Wide b, Wide& hi, Wide& lo) {
  hi = a * b;
  lo = std::fma(a, b, -hi);
}

/// Error-free sum (Knuth's TwoSum): a + b = sum + err exactly.
void twoSum(Wide a, Wide b, Wide& sum, Wide& err) {
  sum = a + b;
  const Wide bv = sum - a, av = sum - bv;
  err = (a - av) + (b - bv);
}

/// Exact sign of d·(p × q) for any Wide inputs: the six products d_i p_j q_k are split into
/// four doubles each by error-free products and summed exactly as a floating-point expansion
/// (Shewchuk, "Adaptive Precision Floating-Point Arithmetic and Fast Robust Geometric
/// Predicates", 1997: Grow-Expansion with zero elimination); the sign of the expansion is
/// the sign of its largest component. Slow path of edgeFunction only.
int exactTripleSign(const WVec3& d, const WVec3& p, const WVec3& q) {
  std::array<Wide, 25> e{};
  int m = 0;
  auto grow = [&](Wide x) {
    int out = 0;
    for (int i = 0; i < m; ++i) {
      Wide sum, err;
      twoSum(x, e[i], sum, err);
      if (err != 0) e[out++] = err;
      x = sum;
    }
    e[out++] = x;
    m = out;
  };
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    for (int term = 0; term < 2; ++term) {
      Wide h, l, h1, l1, h2, l2;
      twoProduct(term == 0 ? p[j] : -p[k], term == 0 ? q[k] : q[j], h, l);
      twoProduct(d[i], h, h1, l1);
      twoProduct(d[i], l, h2, l2);
      grow(l2), grow(h2), grow(l1), grow(h1);
    }
  }
  for (int i = m - 1; i >= 0; --i)
    if (e[i] != 0) return predicates::sign(e[i]);
  return 0;
}

/// Forward error bound factor of d·(p × q) evaluated in Wide: |computed - exact| <=
/// kTripleProductErrorBound · Σ |d_i| (|p_j q_k| + |p_k q_j|) (5 roundings deep, rounded up).
constexpr Wide kTripleProductErrorBound = 4 * std::numeric_limits<Wide>::epsilon();

/// d·(p × q) for an edge (p, q) given relative to the ray origin, with an exact sign: a
/// static filter accepts the Wide value when it exceeds its error bound, else the sign comes
/// from exactTripleSign and the value is replaced by a number of that sign. Evaluated in a
/// canonical vertex order so that the reversed edge gives exactly the negated value whatever
/// the compiler does with the expression (e.g. FMA contraction). With exact, antisymmetric
/// signs the test is the exact line–mesh test of the mesh whose vertices are the (rounded)
/// v - o, which is closed whenever the input mesh is: no ray slips through a shared edge or
/// vertex.
Wide edgeFunction(const WVec3& d, const WVec3& p0, const WVec3& q0) {
  const bool swap =
      q0.x() < p0.x() || (q0.x() == p0.x() && (q0.y() < p0.y() || (q0.y() == p0.y() && q0.z() < p0.z())));
  const WVec3& p = swap ? q0 : p0;
  const WVec3& q = swap ? p0 : q0;
  const Wide yz = p.y() * q.z(), zy = p.z() * q.y(), zx = p.z() * q.x(), xz = p.x() * q.z(),
             xy = p.x() * q.y(), yx = p.y() * q.x();
  Wide value = d.x() * (yz - zy) + d.y() * (zx - xz) + d.z() * (xy - yx);
  const Wide permanent = std::abs(d.x()) * (std::abs(yz) + std::abs(zy)) +
                         std::abs(d.y()) * (std::abs(zx) + std::abs(xz)) +
                         std::abs(d.z()) * (std::abs(xy) + std::abs(yx));
  if (!(std::abs(value) > kTripleProductErrorBound * permanent) && permanent != 0) {
    const int s = exactTripleSign(d, p, q);
    if (predicates::sign(value) != s) value = s == 0 ? Wide(0) : s * std::numeric_limits<Wide>::min();
  }
  return swap ? -value : value;
}

/// First s >= 0 where s*d meets the closed segment [p, q] (all relative to the ray origin).
std::optional<Fraction> raySegment3D(const WVec3& d, const WVec3& p, const WVec3& q) {
  const WVec3 w = p.cross(q);
  if (d.dot(w) != 0) return std::nullopt;  // the ray's line and the segment are skew
  // Everything lies in one plane through the origin; pick its normal and project.
  WVec3 n = w;
  if (n.isZero(0)) n = d.cross(q - p);  // origin on the segment's line
  if (n.isZero(0)) {                    // all collinear: any plane containing d
    const WVec3 m = d.cwiseAbs();
    const int k = (m.x() <= m.y() && m.x() <= m.z()) ? 0 : (m.y() <= m.z() ? 1 : 2);
    n = d.cross(WVec3::Unit(k));
  }
  const int drop = predicates::dominantAxis(n);
  return raySegment2D(project(d, drop), project(p, drop), project(q, drop));
}

/// First s >= 0 where s*d passes through p (relative to the ray origin).
std::optional<Fraction> rayPoint3D(const WVec3& d, const WVec3& p) {
  if (!p.cross(d).isZero(0)) return std::nullopt;
  const Wide dp = p.dot(d);
  if (dp < 0) return std::nullopt;
  return Fraction{dp, d.squaredNorm()};
}

/// First parameter s >= 0 where o + s*d meets the closed (possibly degenerate) triangle.
/// `normal` receives a non-unit normal facing the origin for a proper triangle crossed by the
/// ray, the plane normal (either side) for a ray in the triangle's plane, zero otherwise.
std::optional<Fraction> firstHit(const WVec3& o, const WVec3& d, const Triangle& tri, WVec3& normal,
                                 int* crossingSign = nullptr) {
  normal.setZero();
  if (crossingSign) *crossingSign = 0;
  const predicates::TriangleShape shape = predicates::classify(tri);
  if (shape.kind == TriangleKind::Point) return rayPoint3D(d, shape.p - o);
  if (shape.kind == TriangleKind::Segment) return raySegment3D(d, shape.p - o, shape.q - o);

  const WVec3 A = wide(tri.a), B = wide(tri.b), C = wide(tri.c);
  const WVec3 a = A - o, b = B - o, c = C - o;
  // Plücker side products: u weighs a (edge bc), v weighs b (edge ca), w weighs c (edge ab).
  const Wide u = edgeFunction(d, b, c), v = edgeFunction(d, c, a), w = edgeFunction(d, a, b);
  if (!((u >= 0 && v >= 0 && w >= 0) || (u <= 0 && v <= 0 && w <= 0))) return std::nullopt;
  const WVec3 n = (B - A).cross(C - A);
  const Wide det = u + v + w;  // = d·n; zero only when u = v = w = 0
  if (det == 0) {
    // The ray's line lies in the triangle's plane: exact 2-D test in the dominant projection.
    normal = n;
    const int drop = predicates::dominantAxis(n);
    return rayTriangle2D(project(d, drop), project(a, drop), project(b, drop), project(c, drop));
  }
  // Parameter of the plane crossing, s = n·(A - o) / n·d (accurate: error ~ eps |A - o| / cos θ).
  // n·d equals det; should rounding make their signs differ (a ray nearly parallel to the
  // plane), use the barycentric form (u a + v b + w c) / det of the hit point instead.
  // In front or behind is decided by the exact sign of n·a = a·(b × c) (orient3d of the
  // triangle and the origin): rounding of n·a would otherwise reject rays starting exactly on
  // a corner or in the plane (found by the world sanity tests: ~15% of general-position rays
  // from a corner missed).
  if (crossingSign) *crossingSign = det > 0 ? 1 : -1;
  const int side = predicates::sign(edgeFunction(a, b, c));
  if (side == 0) {
    normal = det > 0 ? WVec3(-n) : n;
    return Fraction{0, 1};  // the origin lies in the triangle's plane (and the line meets it there)
  }
  if ((side > 0) != (det > 0)) return std::nullopt;  // the plane is behind the origin
  const Wide nd = n.dot(d);
  Fraction s = (nd != 0 && (nd > 0) == (det > 0))
                   ? fraction(n.dot(a), nd)
                   : fraction(u * a.dot(d) + v * b.dot(d) + w * c.dot(d), det * d.squaredNorm());
  if (s.num < 0) s.num = 0;  // rounding of a value whose exact sign is known to be >= 0
  normal = det > 0 ? WVec3(-n) : n;
  return s;
}

/// True when p lies in the closed (possibly degenerate) triangle.
bool contains(const Triangle& tri, const WVec3& p) {
  const predicates::TriangleShape shape = predicates::classify(tri);
  if (shape.kind == TriangleKind::Point) return p == shape.p;
  if (shape.kind == TriangleKind::Segment) {
    const WVec3 a = shape.p - p, b = shape.q - p;
    return a.cross(b).isZero(0) && a.dot(b) <= 0;
  }
  const WVec3 A = wide(tri.a), B = wide(tri.b), C = wide(tri.c);
  if (predicates::orient3d(A, B, C, p) != 0) return false;
  const int drop = predicates::dominantAxis((B - A).cross(C - A));
  return insideTriangle2D(project(p, drop), project(A, drop), project(B, drop), project(C, drop));
}

/// Entry parameter of a slab test and the axis whose slab set it (-1: the start point).
struct SlabEntry {
  Fraction s;
  int axis = -1;
};

/// Slab test (Kay & Kajiya 1986; RTCD 5.3.3) of o + s*d, 0 <= s <= sMax (unbounded when
/// sMax is empty), against {lo <= x <= hi}. Slab parameters are fractions with positive
/// denominators compared by cross-multiplication; a zero direction component rejects when
/// the origin lies outside that slab.
std::optional<SlabEntry> slabs(const WVec3& o, const WVec3& d, const WVec3& lo, const WVec3& hi,
                               std::optional<Fraction> exit) {
  SlabEntry enter;
  for (int i = 0; i < 3; ++i) {
    if (d[i] == 0) {
      if (o[i] < lo[i] || o[i] > hi[i]) return std::nullopt;
      continue;
    }
    const Fraction nearS = d[i] > 0 ? Fraction{lo[i] - o[i], d[i]} : Fraction{o[i] - hi[i], -d[i]};
    const Fraction farS = d[i] > 0 ? Fraction{hi[i] - o[i], d[i]} : Fraction{o[i] - lo[i], -d[i]};
    if (less(enter.s, nearS)) enter = {nearS, i};
    if (!exit || less(farS, *exit)) exit = farS;
    if (less(*exit, enter.s)) return std::nullopt;
  }
  return enter;
}

/// The hit at parameter s (world distance s|d|), or nullopt beyond maxT. A zero `normal`
/// means "no surface normal here" and becomes -d/|d|.
std::optional<RayHit> makeHit(const WVec3& o, const WVec3& d, Wide s, const WVec3& normal, Real maxT) {
  const Wide len = d.norm();
  RayHit hit;
  hit.t = Real(s * len);
  // A distance that overflows Real (found by fuzz_geometry: a ray almost parallel to a plane)
  // lies beyond every representable point: a miss, never a hit at t = inf.
  if (!(hit.t <= maxT) || !std::isfinite(hit.t)) return std::nullopt;
  hit.point = (o + s * d).cast<Real>();
  const Wide nn = normal.norm();
  hit.normal = (nn > 0 ? WVec3(normal / nn) : WVec3(-d / len)).cast<Real>();
  return hit;
}

/// The world coordinates of an OBB's frame applied to a vector: (u_i · v)_i.
WVec3 toBoxFrame(const Obb& b, const WVec3& v) {
  const Eigen::Matrix<Wide, 3, 3> axes = b.axes.cast<Wide>();
  return WVec3(axes.col(0).dot(v), axes.col(1).dot(v), axes.col(2).dot(v));
}

}  // namespace

std::optional<RayHit> raycast(const Ray& ray, const Triangle& t, Real maxT) {
  const WVec3 o = wide(ray.origin), d = wide(ray.dir);
  WVec3 normal;
  const auto s = firstHit(o, d, t, normal);
  if (!s) return std::nullopt;
  return makeHit(o, d, s->value(), normal, maxT);
}

std::optional<RayHit> raycast(const Ray& ray, const Sphere& sp, Real maxT) {
  const WVec3 o = wide(ray.origin), d = wide(ray.dir), c = wide(sp.center);
  const WVec3 m = o - c;
  const Wide r = sp.radius;
  const Wide c0 = m.squaredNorm() - r * r;
  if (c0 <= 0) return makeHit(o, d, 0, WVec3::Zero(), maxT);  // origin in the ball
  const Wide b = m.dot(d);
  if (b >= 0) return std::nullopt;  // outside and not approaching the centre
  // Discriminant b² - |d|² c0 = |d|² r² - |m × d|² (Lagrange identity): no cancellation of
  // the large terms b² and |d|²|m|², so it is accurate near tangency.
  const Wide disc = d.squaredNorm() * (r * r) - m.cross(d).squaredNorm();
  if (disc < 0) return std::nullopt;
  // Smaller root of a s² + 2 b s + c0 written without cancellation (-b > 0, c0 > 0).
  const Wide s = c0 / (-b + std::sqrt(disc));
  const WVec3 p = o + s * d;
  return makeHit(o, d, s, r > 0 ? WVec3(p - c) : WVec3::Zero(), maxT);
}

std::optional<RayHit> raycast(const Ray& ray, const Aabb& box, Real maxT) {
  const WVec3 o = wide(ray.origin), d = wide(ray.dir);
  const auto e = slabs(o, d, wide(box.min), wide(box.max), std::nullopt);
  if (!e) return std::nullopt;
  WVec3 normal = WVec3::Zero();
  if (e->axis >= 0) normal[e->axis] = d[e->axis] > 0 ? -1 : 1;
  return makeHit(o, d, e->s.value(), normal, maxT);
}

std::optional<RayHit> raycast(const Ray& ray, const Obb& box, Real maxT) {
  const WVec3 o = wide(ray.origin), d = wide(ray.dir);
  const WVec3 lo = toBoxFrame(box, o - wide(box.center)), ld = toBoxFrame(box, d);
  const WVec3 h = wide(box.half);
  const auto e = slabs(lo, ld, -h, h, std::nullopt);
  if (!e) return std::nullopt;
  WVec3 normal = WVec3::Zero();
  if (e->axis >= 0) normal = box.axes.col(e->axis).cast<Wide>() * (ld[e->axis] > 0 ? Wide(-1) : Wide(1));
  return makeHit(o, d, e->s.value(), normal, maxT);
}

std::optional<RayHit> raycast(const Ray& ray, const Plane& p, Real maxT) {
  const WVec3 o = wide(ray.origin), d = wide(ray.dir), n = wide(p.normal);
  const Wide f = n.dot(o) - Wide(p.d);  // signed distance times |n|
  const Wide nd = n.dot(d);
  if (f == 0) return makeHit(o, d, 0, nd > 0 ? WVec3(-n) : n, maxT);  // origin on the plane
  if (nd == 0 || (f > 0) == (nd > 0)) return std::nullopt;            // parallel or receding
  return makeHit(o, d, -f / nd, f > 0 ? n : WVec3(-n), maxT);
}

bool intersects(const Segment& seg, const Triangle& t) {
  const WVec3 o = wide(seg.start), d = wide(seg.end) - o;
  if (d.isZero(0)) return contains(t, o);
  WVec3 normal;
  int crossing = 0;  // sign of d·n when the segment's line crosses the plane, 0 otherwise
  const auto s = firstHit(o, d, t, normal, &crossing);
  if (!s) return false;
  if (crossing == 0 || s->num == 0) return s->num <= s->den;
  // Does the segment reach the plane? Exact sign of n·(A - E) against d·n, E = o + d (the
  // end point; exact in float builds, where d = end - start is exact in Wide): s <= 1.
  const WVec3 e = o + d;
  const WVec3 A = wide(t.a) - e, B = wide(t.b) - e, C = wide(t.c) - e;
  const int endSide = predicates::sign(edgeFunction(A, B, C));
  return endSide == 0 || (endSide > 0) != (crossing > 0);
}

bool intersects(const Segment& seg, const Sphere& sp) {
  const WVec3 a = wide(seg.start), b = wide(seg.end), c = wide(sp.center);
  const Wide rr = Wide(sp.radius) * Wide(sp.radius);
  const WVec3 e = b - a, m = c - a;
  const Wide len2 = e.squaredNorm(), proj = m.dot(e);
  if (len2 == 0 || proj <= 0) return m.squaredNorm() <= rr;  // nearest point: start
  if (proj >= len2) return (c - b).squaredNorm() <= rr;      // nearest point: end
  // Interior nearest point: dist² = |m × e|² / |e|² (Lagrange identity, no cancellation).
  return m.cross(e).squaredNorm() <= rr * len2;
}

bool intersects(const Segment& seg, const Aabb& box) {
  const WVec3 o = wide(seg.start), d = wide(seg.end) - o;
  return slabs(o, d, wide(box.min), wide(box.max), Fraction{1, 1}).has_value();
}

bool intersects(const Segment& seg, const Obb& box) {
  const WVec3 c = wide(box.center), h = wide(box.half);
  const WVec3 a = toBoxFrame(box, wide(seg.start) - c), b = toBoxFrame(box, wide(seg.end) - c);
  return slabs(a, b - a, -h, h, Fraction{1, 1}).has_value();
}

bool intersects(const Segment& seg, const Plane& p) {
  const WVec3 n = wide(p.normal);
  const Wide f0 = n.dot(wide(seg.start)) - Wide(p.d), f1 = n.dot(wide(seg.end)) - Wide(p.d);
  return !((f0 > 0 && f1 > 0) || (f0 < 0 && f1 < 0));
}

}  // namespace crux
