/// @file raycast.cpp  Ray casts and segment tests against the primitive shapes.
///
/// Ray/segment–triangle decisions are exact for any finite inputs: signs of polynomials of the
/// input coordinates read by a judge (predicates.hpp, expansion.hpp), first through the
/// forward-error filter and, when a sign is uncertain, with exact expansions. This also makes
/// the triangle test watertight at shared vertices and edges. The other shapes' decisions are
/// signs of low-degree polynomials evaluated in Wide: exact on the integer grid (|coordinates|
/// <= 64). Ray parameters are kept as fractions num/den with den > 0 and compared by
/// cross-multiplication (no division before the answer is known); the reported distance is
/// computed from the winning fraction at the end.

#include "geometry/unchecked.hpp"

#include <array>
#include <cmath>
#include <crux/geometry/predicates.hpp>
#include <crux/geometry/raycast.hpp>

#include "geometry/ray_triangle.hpp"
#include <limits>
#include <type_traits>

namespace crux {
namespace {

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

// ---------------------------------------------------------------------------------------------
// Ray/segment against a (possibly degenerate) triangle, exact: templates over a judge
// (predicates.hpp), run with the filter and, when some sign is uncertain, with expansions.
// Coordinates relative to the ray origin are differences of inputs, formed inside the number
// type (bounded or exact), never rounded before a sign is read.
// ---------------------------------------------------------------------------------------------

using robust::lift;
using robust::V3;
using predicates::NumberOf;

/// A ray parameter s = num / den with den > 0 (exact in the exact stage).
template <class T>
struct Frac {
  T num, den;
  /// Approximate value, >= 0 (a NaN from an underflowed denominator maps to 0).
  Wide value() const {
    const Wide s = robust::approx(num) / robust::approx(den);
    return s > 0 ? s : Wide(0);  // also -0
  }
};

template <class T>
struct P2 {
  T x, y;
  friend P2 operator-(const P2& a, const P2& b) { return {a.x - b.x, a.y - b.y}; }
  T dot(const P2& b) const { return x * b.x + y * b.y; }
};

template <class T>
T cross2(const P2<T>& a, const P2<T>& b) {
  return a.x * b.y - a.y * b.x;
}

/// The 2-D coordinates left after dropping axis `drop` (cyclic order, as predicates::orient2d).
template <class T>
P2<T> project(const V3<T>& v, int drop) {
  return {v[(drop + 1) % 3], v[(drop + 2) % 3]};
}

template <class J, class T>
bool lessThan(J& judge, const Frac<T>& a, const Frac<T>& b) {
  return judge(a.num * b.den - b.num * a.den) < 0;
}

/// p/q with q != 0 brought to a positive denominator.
template <class J, class T>
Frac<T> fraction(J& judge, const T& p, const T& q) {
  return judge(q) < 0 ? Frac<T>{-p, -q} : Frac<T>{p, q};
}

template <class T>
Frac<T> zeroFraction() {
  return {T(Wide(0)), T(Wide(1))};
}

/// True when the origin lies in the closed 2-D triangle abc (non-degenerate).
template <class J, class T>
bool originInTriangle2D(J& judge, const P2<T>& a, const P2<T>& b, const P2<T>& c) {
  const int e0 = judge(cross2(a, b)), e1 = judge(cross2(b, c)), e2 = judge(cross2(c, a));
  return (e0 >= 0 && e1 >= 0 && e2 >= 0) || (e0 <= 0 && e1 <= 0 && e2 <= 0);
}

/// First s >= 0 with s*d (a 2-D ray from the origin) on the closed segment [p, q].
template <class J, class T>
std::optional<Frac<T>> raySegment2D(J& judge, const P2<T>& d, const P2<T>& p, const P2<T>& q) {
  const P2<T> e = q - p;
  const T den = cross2(d, e);
  if (judge(den) == 0) {                                 // parallel lines
    if (judge(cross2(d, p)) != 0) return std::nullopt;  // distinct lines
    const T dp = p.dot(d), dq = q.dot(d);
    const int sp = judge(dp), sq = judge(dq);
    if ((sp <= 0 && sq >= 0) || (sp >= 0 && sq <= 0)) return zeroFraction<T>();  // origin on [p, q]
    if (sp < 0) return std::nullopt;                                             // both behind
    return Frac<T>{judge(dp - dq) < 0 ? dp : dq, d.dot(d)};
  }
  const int cp = judge(cross2(d, p)), cq = judge(cross2(d, q));
  if ((cp > 0 && cq > 0) || (cp < 0 && cq < 0)) return std::nullopt;  // [p, q] misses the line
  // o + s d on line pq: s cross(d, e) = cross(p, e).
  const Frac<T> s = fraction(judge, cross2(p, e), den);
  if (judge(s.num) < 0) return std::nullopt;
  return s;
}

/// First s >= 0 with s*d in the closed 2-D triangle abc (a ray in its plane; abc is proper
/// in this projection).
template <class J, class T>
std::optional<Frac<T>> rayTriangle2D(J& judge, const P2<T>& d, const P2<T>& a, const P2<T>& b, const P2<T>& c) {
  if (originInTriangle2D(judge, a, b, c)) return zeroFraction<T>();
  std::optional<Frac<T>> best;
  const P2<T>* v[3] = {&a, &b, &c};
  for (int i = 0; i < 3; ++i) {
    auto s = raySegment2D(judge, d, *v[i], *v[(i + 1) % 3]);
    if (s && (!best || lessThan(judge, *s, *best))) best = std::move(s);
  }
  return best;
}

/// First s >= 0 where s*d meets the closed segment [p, q] (all relative to the ray origin).
template <class J, class T>
std::optional<Frac<T>> raySegment3D(J& judge, const V3<T>& d, const V3<T>& p, const V3<T>& q) {
  const V3<T> w = p.cross(q);
  if (judge(d.dot(w)) != 0) return std::nullopt;  // the ray's line and the segment are skew
  // Everything lies in one plane through the origin; find an axis its normal does not vanish on.
  int drop = predicates::nonzeroAxis(judge, w);
  if (drop < 0) drop = predicates::nonzeroAxis(judge, d.cross(q - p));  // origin on the segment's line
  if (drop < 0) {                                                         // all collinear: a plane containing d
    const WVec3 m = robust::approx(d).cwiseAbs();
    const int k = (m.x() <= m.y() && m.x() <= m.z()) ? 0 : (m.y() <= m.z() ? 1 : 2);
    V3<T> unit = {T(Wide(0)), T(Wide(0)), T(Wide(0))};
    unit[k] = T(Wide(1));
    drop = predicates::nonzeroAxis(judge, d.cross(unit));
    if (drop < 0) return std::nullopt;  // only under an uncertain filter sign
  }
  return raySegment2D(judge, project(d, drop), project(p, drop), project(q, drop));
}

/// First s >= 0 where s*d passes through p (relative to the ray origin).
template <class J, class T>
std::optional<Frac<T>> rayPoint3D(J& judge, const V3<T>& d, const V3<T>& p) {
  if (!predicates::crossIsZero(judge, p, d)) return std::nullopt;
  const T dp = p.dot(d);
  if (judge(dp) < 0) return std::nullopt;
  return Frac<T>{dp, d.squaredNorm()};
}

/// v scaled by a power of two (exact) to a largest |component| in [1, 2) when |v|² would
/// overflow or underflow Wide (a largest component beyond 2^±400); v itself otherwise, and when
/// it is zero or not finite. Normalising the result gives the same bits as normalising v
/// wherever |v|² fits Wide, and a unit vector where it does not.
WVec3 powerOfTwoScaled(const WVec3& v) {
  const Wide m = v.cwiseAbs().maxCoeff();
  if (!(m > 0) || !std::isfinite(m) || (m > 0x1p-400 && m < 0x1p400)) return v;
  return v * std::ldexp(Wide(1), -std::ilogb(m));
}

/// |v| without overflow in |v|² (powerOfTwoScaled, then the scale put back).
Wide scaledNorm(const WVec3& v) {
  const WVec3 s = powerOfTwoScaled(v);
  if (s == v) return v.norm();
  return std::ldexp(s.norm(), std::ilogb(v.cwiseAbs().maxCoeff()));
}

/// A normal of the proper triangle tri along (b − a) × (c − a) that stays finite where that
/// product overflows Wide (double builds beyond ~1.3e154): the edges halved (exact) so that their
/// differences cannot overflow and scaled by powers of two (powerOfTwoScaled) before the cross
/// product. Used only when the exact normal's approximation is not finite.
WVec3 scaledEdgeNormal(const Triangle& tri) {
  const WVec3 a = Wide(0.5) * wide(tri.a);
  const WVec3 e1 = powerOfTwoScaled(Wide(0.5) * wide(tri.b) - a), e2 = powerOfTwoScaled(Wide(0.5) * wide(tri.c) - a);
  return e1.cross(e2);
}

/// The answer of firstHit.
template <class T>
struct TriangleHit {
  std::optional<Frac<T>> s;  ///< first parameter, or none
  WVec3 normal = WVec3::Zero();
  int crossing = 0;  ///< sign of d·n when the line crosses the plane of a proper triangle
};

/// First parameter s >= 0 where o + s*d meets the closed (possibly degenerate) triangle.
/// `normal` is a non-unit normal facing the origin for a proper triangle crossed by the ray,
/// the plane normal (either side) for a ray in the triangle's plane, zero otherwise. The hit
/// is decided by the signs of the Plücker side products u = d·(b × c), v = d·(c × a),
/// w = d·(a × b) (a, b, c the corners relative to o), exact and antisymmetric, so the test is
/// watertight at shared edges and vertices.
template <class J, class T>
TriangleHit<T> firstHit(J& judge, const V3<T>& o, const V3<T>& d, const Triangle& tri,
                        const predicates::TriangleShape& shape) {
  TriangleHit<T> r;
  if (shape.kind == TriangleKind::Point) {
    r.s = rayPoint3D(judge, d, lift<T>(shape.p) - o);
    return r;
  }
  if (shape.kind == TriangleKind::Segment) {
    r.s = raySegment3D(judge, d, lift<T>(shape.p) - o, lift<T>(shape.q) - o);
    return r;
  }
  const V3<T> A = lift<T>(tri.a), B = lift<T>(tri.b), C = lift<T>(tri.c);
  const V3<T> a = A - o, b = B - o, c = C - o;
  const int u = judge(d.dot(b.cross(c))), v = judge(d.dot(c.cross(a))), w = judge(d.dot(a.cross(b)));
  if (!((u >= 0 && v >= 0 && w >= 0) || (u <= 0 && v <= 0 && w <= 0))) return r;
  const V3<T> n = (B - A).cross(C - A);
  const int det = u + v + w > 0 ? 1 : (u + v + w < 0 ? -1 : 0);  // sign of d·n = u + v + w
  WVec3 nApprox = robust::approx(n);
  if (!nApprox.allFinite()) nApprox = scaledEdgeNormal(tri);  // |n| beyond Wide: the direction only
  if (det == 0) {
    // The ray's line lies in the triangle's plane: exact 2-D test in a projection keeping it.
    r.normal = nApprox;
    const int drop = predicates::nonzeroAxis(judge, n);
    if (drop < 0) return r;  // only under an uncertain filter sign
    r.s = rayTriangle2D(judge, project(d, drop), project(a, drop), project(b, drop), project(c, drop));
    return r;
  }
  r.crossing = det;
  r.normal = det > 0 ? WVec3(-nApprox) : nApprox;
  // In front or behind: the sign of n·a = a·(b × c) (orient3d of the triangle and the origin).
  const int side = judge(a.dot(b.cross(c)));
  if (side == 0) {
    r.s = zeroFraction<T>();  // the origin lies in the triangle's plane (and the line meets it there)
    return r;
  }
  if ((side > 0) != (det > 0)) return r;  // the plane is behind the origin
  // s = n·a / n·d; n·d has the sign det (a filter that cannot see it falls back to exact).
  const T nd = n.dot(d);
  if (judge(nd) != det) return r;
  r.s = det > 0 ? Frac<T>{n.dot(a), nd} : Frac<T>{-n.dot(a), -nd};
  return r;
}

/// True when p lies in the closed (possibly degenerate) triangle.
template <class J, class T>
bool contains(J& judge, const Triangle& tri, const predicates::TriangleShape& shape, const V3<T>& p) {
  if (shape.kind == TriangleKind::Point) return predicates::nonzeroAxis(judge, p - lift<T>(shape.p)) < 0;
  if (shape.kind == TriangleKind::Segment) return predicates::pointOnSegment(judge, p, lift<T>(shape.p), lift<T>(shape.q));
  return predicates::pointOnTriangle(judge, p, lift<T>(tri.a), lift<T>(tri.b), lift<T>(tri.c));
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
/// len: scaledNorm(d), d.norm() but finite where |d|² overflows (geometry_detail::rayLength).
std::optional<RayHit> makeHit(const WVec3& o, const WVec3& d, Wide s, const WVec3& normal, Real maxT, Wide len) {
  RayHit hit;
  hit.t = Real(s * len);
  // A distance that overflows Real (found by fuzz_geometry: a ray almost parallel to a plane)
  // lies beyond every representable point: a miss, never a hit at t = inf.
  if (!(hit.t <= maxT) || !std::isfinite(hit.t)) return std::nullopt;
  hit.point = (o + s * d).cast<Real>();
  // (normalised after a power-of-two scaling: |normal|² may overflow Wide far from the origin)
  const WVec3 ns = powerOfTwoScaled(normal);
  const Wide nn = ns.norm();
  hit.normal = (nn > 0 && std::isfinite(nn) ? WVec3(ns / nn) : WVec3(-d / len)).cast<Real>();
  return hit;
}
std::optional<RayHit> makeHit(const WVec3& o, const WVec3& d, Wide s, const WVec3& normal, Real maxT) {
  return makeHit(o, d, s, normal, maxT, scaledNorm(d));
}

/// The world coordinates of an OBB's frame applied to a vector: (u_i · v)_i.
WVec3 toBoxFrame(const Obb& b, const WVec3& v) {
  const Eigen::Matrix<Wide, 3, 3> axes = b.axes.cast<Wide>();
  return WVec3(axes.col(0).dot(v), axes.col(1).dot(v), axes.col(2).dot(v));
}

/// Whether the filter stage's hit parameter s = num / den (num >= 0 and den > 0, both certain;
/// `s` its value) of a ray crossing the plane of triangle tri may miss the exact parameter by
/// more than kRayParameterUlps ulps of Real × (S + t) / cos θ (S: the larger |coordinate| of the
/// origin and the first corner, t = s|d| the hit distance, θ the angle between the ray and the
/// plane's normal n, whose approximation is `normal`). The bound is the filter's own (Bounded):
/// to first order s·(num.e/num + den.e/den), so the hit distance's error times cos θ =
/// |n·d| / (|n||d|) is (num.e + s·den.e) / |n|. Conservative without square roots: |d| and |n|
/// enter as their largest components, at most the norms. The bound is small for a proper
/// triangle, but grows as L/h on a sliver (height h, longest edge L), whose normal is the cross
/// product of two nearly antiparallel edges (`crux diff`'s flat caps, docs/diff.md): such hits
/// are recomputed by the exact stage. A NaN or infinite bound (overflow) is imprecise too.
/// numError, denError: the bounds on num and den.
bool imprecise(Wide numError, Wide denError, Wide s, const WVec3& normal, const Ray& ray, const Triangle& tri) {
  const Wide S = std::max(wide(ray.origin).cwiseAbs().maxCoeff(), wide(tri.a).cwiseAbs().maxCoeff());
  const Wide t = s * wide(ray.dir).cwiseAbs().maxCoeff();  // <= s|d|
  const Wide allowed = Wide(kRayParameterUlps) * Wide(std::numeric_limits<Real>::epsilon()) * (S + t);
  return !(numError + s * denError <= allowed * normal.cwiseAbs().maxCoeff());
}
bool imprecise(const Frac<robust::Bounded>& f, Wide s, const WVec3& normal, const Ray& ray, const Triangle& tri) {
  return imprecise(f.num.e, f.den.e, s, normal, ray, tri);
}

/// A static forward error bound (Higham, Accuracy and Stability of Numerical Algorithms, 2002,
/// ch. 3) on n·v evaluated in Wide as V3's dot of n = (b − a) × (c − a) (V3's cross) with v,
/// every input exact in Wide and every difference formed once: each n_i is off by at most
/// γ₄·P_i (P_i = the sum of |products| forming it, from the rounded edges), the dot adds γ₃ on
/// Σ|n_i v_i|, so |error| <= γ₈·Σ P_i|v_i| for rounded v = x − o as well. Taken as 16u·Q·(1 +
/// 8u) with Q = Σ P_i|v_i| computed in Wide, plus an absolute term for underflowed products
/// (each at most the smallest subnormal, carried through one more product). vAbs: |v| per
/// axis; p: P per axis.
Wide staticDotCrossBound(const WVec3& p, const WVec3& vAbs) {
  constexpr Wide u = std::numeric_limits<Wide>::epsilon() / 2;
  constexpr Wide tiny = std::numeric_limits<Wide>::denorm_min();
  const Wide q = p.dot(vAbs);
  return 16 * u * q * (1 + 8 * u) + tiny * (8 * vAbs.sum() + 8);
}

}  // namespace


namespace geometry_detail {

std::optional<RayCrossing> rayTriangleCrossing(const Ray& ray, const Triangle& t) {
  const predicates::TriangleShape shape = predicates::classify(t);
  Wide s = 0;
  WVec3 normal;
  const bool hit = robust::filtered([&](auto& judge) {
    using T = NumberOf<decltype(judge)>;
    const TriangleHit<T> h = firstHit(judge, lift<T>(ray.origin), lift<T>(ray.dir), t, shape);
    if (!h.s) return false;
    const Wide value = h.s->value();
    if constexpr (std::is_same_v<T, robust::Bounded>) {
      // a hit parameter the filter cannot bound well enough (slivers): the exact stage instead
      if (h.crossing != 0 && imprecise(*h.s, value, h.normal, ray, t)) {
        judge.uncertain = true;
        return false;
      }
    }
    s = value;
    normal = h.normal;
    // Beyond the exact range (double builds, coordinates past ~√max Wide) n·a and n·d overflow
    // and their ratio is no parameter: it is taken from the (scaled) plane normal instead.
    if (h.crossing != 0 && !(std::isfinite(robust::approx(h.s->num)) && std::isfinite(robust::approx(h.s->den)))) {
      const Wide num = normal.dot(wide(t.a) - wide(ray.origin)), den = normal.dot(wide(ray.dir));
      s = num / den > 0 ? num / den : Wide(0);
    }
    return true;
  });
  if (!hit) return std::nullopt;
  return RayCrossing{s, normal};
}

int properRayTriangleCrossing(const Ray& ray, const Triangle& t, int det, RayCrossing& out) {
  // firstHit's expressions for a crossing of the plane in Wide (the values of its filter stage:
  // the same bits whenever raycast's filter stage decides; where it is unsure of another sign,
  // raycast's exact stage may round the parameter differently, both within kRayParameterUlps),
  // with static error bounds in place of Bounded's running ones
  const V3<Wide> o = lift<Wide>(ray.origin), d = lift<Wide>(ray.dir);
  const V3<Wide> A = lift<Wide>(t.a), B = lift<Wide>(t.b), C = lift<Wide>(t.c);
  const V3<Wide> a = A - o, e1 = B - A, e2 = C - A;
  const V3<Wide> n = e1.cross(e2);
  // n·a = a·(b × c) exactly (b, c the other corners relative to o): the origin's side
  const Wide na = n.dot(a), nd = n.dot(d);
  if (!std::isfinite(na) || !std::isfinite(nd)) return -1;
  using std::abs;
  const WVec3 p(abs(e1.y * e2.z) + abs(e1.z * e2.y), abs(e1.z * e2.x) + abs(e1.x * e2.z),
                abs(e1.x * e2.y) + abs(e1.y * e2.x));
  const Wide naError = staticDotCrossBound(p, WVec3(abs(a.x), abs(a.y), abs(a.z)));
  const Wide ndError = staticDotCrossBound(p, WVec3(abs(d.x), abs(d.y), abs(d.z)));
  // certain signs, with Bounded's safety factor on the comparison
  constexpr Wide kSafety = robust::Bounded::kSafety;
  if (!(abs(na) > naError * kSafety)) return -1;  // near or in the plane: raycast's own path
  if ((na > 0) != (det > 0)) return 0;           // the plane is behind the origin
  if (!(abs(nd) > ndError * kSafety) || (nd > 0) != (det > 0)) return -1;
  const WVec3 nApprox(n.x, n.y, n.z);
  if (!nApprox.allFinite()) return -1;
  // Frac::value of (na, nd) or (−na, −nd): the same quotient (0 if it underflowed)
  const Wide quotient = na / nd;
  const Wide value = quotient > 0 ? quotient : Wide(0);
  if (imprecise(naError, ndError, value, nApprox, ray, t)) return -1;
  out.s = value;
  out.normal = det > 0 ? WVec3(-nApprox) : nApprox;
  return 1;
}

Wide rayLength(const Vec3& dir) { return scaledNorm(wide(dir)); }

std::optional<RayHit> rayHitAt(const Ray& ray, const RayCrossing& c, Real maxT) {
  return makeHit(wide(ray.origin), wide(ray.dir), c.s, c.normal, maxT);
}

std::optional<RayHit> rayHitAt(const Ray& ray, const RayCrossing& c, Real maxT, Wide length) {
  return makeHit(wide(ray.origin), wide(ray.dir), c.s, c.normal, maxT, length);
}

}  // namespace geometry_detail

std::optional<RayHit> unchecked::raycast(const Ray& ray, const Triangle& t, Real maxT) {
  const std::optional<geometry_detail::RayCrossing> c = geometry_detail::rayTriangleCrossing(ray, t);
  if (!c) return std::nullopt;
  return geometry_detail::rayHitAt(ray, *c, maxT);
}


std::optional<RayHit> unchecked::raycast(const Ray& ray, const Sphere& sp, Real maxT) {
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

std::optional<RayHit> unchecked::raycast(const Ray& ray, const Aabb& box, Real maxT) {
  const WVec3 o = wide(ray.origin), d = wide(ray.dir);
  const auto e = slabs(o, d, wide(box.min), wide(box.max), std::nullopt);
  if (!e) return std::nullopt;
  WVec3 normal = WVec3::Zero();
  if (e->axis >= 0) normal[e->axis] = d[e->axis] > 0 ? -1 : 1;
  return makeHit(o, d, e->s.value(), normal, maxT);
}

std::optional<RayHit> unchecked::raycast(const Ray& ray, const Obb& box, Real maxT) {
  const WVec3 o = wide(ray.origin), d = wide(ray.dir);
  const WVec3 lo = toBoxFrame(box, o - wide(box.center)), ld = toBoxFrame(box, d);
  const WVec3 h = wide(box.half);
  const auto e = slabs(lo, ld, -h, h, std::nullopt);
  if (!e) return std::nullopt;
  WVec3 normal = WVec3::Zero();
  if (e->axis >= 0) normal = box.axes.col(e->axis).cast<Wide>() * (ld[e->axis] > 0 ? Wide(-1) : Wide(1));
  return makeHit(o, d, e->s.value(), normal, maxT);
}

std::optional<RayHit> unchecked::raycast(const Ray& ray, const Plane& p, Real maxT) {
  const WVec3 o = wide(ray.origin), d = wide(ray.dir), n = wide(p.normal);
  const Wide f = n.dot(o) - Wide(p.d);  // signed distance times |n|
  const Wide nd = n.dot(d);
  if (f == 0) return makeHit(o, d, 0, nd > 0 ? WVec3(-n) : n, maxT);  // origin on the plane
  if (nd == 0 || (f > 0) == (nd > 0)) return std::nullopt;            // parallel or receding
  return makeHit(o, d, -f / nd, f > 0 ? n : WVec3(-n), maxT);
}

bool unchecked::intersects(const Segment& seg, const Triangle& t) {
  const predicates::TriangleShape shape = predicates::classify(t);
  return robust::filtered([&](auto& judge) {
    using T = NumberOf<decltype(judge)>;
    const V3<T> o = lift<T>(seg.start), e = lift<T>(seg.end);
    if (seg.start == seg.end) return contains(judge, t, shape, o);
    const TriangleHit<T> h = firstHit(judge, o, e - o, t, shape);
    if (!h.s) return false;
    if (h.crossing == 0 || judge(h.s->num) == 0) return judge(h.s->num - h.s->den) <= 0;
    // Does the segment reach the plane? The side of the end point: s <= 1 iff the end is on
    // the plane or on the far side (opposite to the crossing direction's start side).
    const V3<T> A = lift<T>(t.a) - e, B = lift<T>(t.b) - e, C = lift<T>(t.c) - e;
    const int endSide = judge(A.dot(B.cross(C)));
    return endSide == 0 || (endSide > 0) != (h.crossing > 0);
  });
}

bool unchecked::intersects(const Segment& seg, const Sphere& sp) {
  const WVec3 a = wide(seg.start), b = wide(seg.end), c = wide(sp.center);
  const Wide rr = Wide(sp.radius) * Wide(sp.radius);
  const WVec3 e = b - a, m = c - a;
  const Wide len2 = e.squaredNorm(), proj = m.dot(e);
  if (len2 == 0 || proj <= 0) return m.squaredNorm() <= rr;  // nearest point: start
  if (proj >= len2) return (c - b).squaredNorm() <= rr;      // nearest point: end
  // Interior nearest point: dist² = |m × e|² / |e|² (Lagrange identity, no cancellation).
  return m.cross(e).squaredNorm() <= rr * len2;
}

bool unchecked::intersects(const Segment& seg, const Aabb& box) {
  const WVec3 o = wide(seg.start), d = wide(seg.end) - o;
  return slabs(o, d, wide(box.min), wide(box.max), Fraction{1, 1}).has_value();
}

bool unchecked::intersects(const Segment& seg, const Obb& box) {
  const WVec3 c = wide(box.center), h = wide(box.half);
  const WVec3 a = toBoxFrame(box, wide(seg.start) - c), b = toBoxFrame(box, wide(seg.end) - c);
  return slabs(a, b - a, -h, h, Fraction{1, 1}).has_value();
}

bool unchecked::intersects(const Segment& seg, const Plane& p) {
  const WVec3 n = wide(p.normal);
  const Wide f0 = n.dot(wide(seg.start)) - Wide(p.d), f1 = n.dot(wide(seg.end)) - Wide(p.d);
  return !((f0 > 0 && f1 > 0) || (f0 < 0 && f1 < 0));
}

}  // namespace crux
