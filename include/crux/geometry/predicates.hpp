#pragma once
/// @file predicates.hpp  Sign-exact orientation predicates and degeneracy classification.
///
/// Every boolean decision of the geometry layer is the sign of a polynomial of the input
/// coordinates. The `*Sign` templates below take a judge (robust::FilterJudge or
/// robust::ExactJudge, see expansion.hpp) and points of its number type; run through
/// robust::filtered they return the exact sign for ANY finite inputs (Shewchuk 1997: a
/// forward-error filter in Wide, exact floating-point expansions when it cannot decide).
/// Coordinate differences are never rounded before a sign is taken: the filter bounds their
/// rounding, the expansions form them exactly.
///
/// The plain `orient3d` / `orient2d` values (Wide arithmetic) remain for callers that need a
/// magnitude or work on the integer grid only (|coordinates| <= 64, where they are exact).

#include <crux/geometry/expansion.hpp>
#include <crux/geometry/shapes.hpp>

#include <type_traits>

namespace crux::predicates {

/// (b-a)·((c-a)×(d-a)) — six times the signed volume of tetrahedron abcd; positive when d
/// lies on the side of plane abc that the counter-clockwise normal points to. Rounded (Wide);
/// exact on the integer grid. Use orient3dExact for the exact sign of arbitrary inputs.
inline Wide orient3d(const WVec3& a, const WVec3& b, const WVec3& c, const WVec3& d) {
  return (b - a).cross(c - a).dot(d - a);
}

/// 2-D orientation of (a, b, c) after dropping coordinate `drop` (0, 1 or 2): twice the
/// signed area, positive for counter-clockwise order in the (u, v) = remaining axes in
/// cyclic order ((y,z), (z,x), (x,y)). Rounded (Wide); exact on the integer grid.
inline Wide orient2d(const WVec3& a, const WVec3& b, const WVec3& c, int drop) {
  const int u = (drop + 1) % 3;
  const int v = (drop + 2) % 3;
  return (b[u] - a[u]) * (c[v] - a[v]) - (b[v] - a[v]) * (c[u] - a[u]);
}

/// Index of the largest-magnitude component of n (ties: lowest index): the axis to drop when
/// projecting a plane with normal n to 2-D without collapsing it.
inline int dominantAxis(const WVec3& n) {
  const WVec3 m = n.cwiseAbs();
  return (m.x() >= m.y() && m.x() >= m.z()) ? 0 : (m.y() >= m.z() ? 1 : 2);
}

/// Sign of x as -1, 0 or +1.
inline int sign(Wide x) { return (x > 0) - (x < 0); }

// ---------------------------------------------------------------------------------------------
// Sign templates over a judge (exact when run through robust::filtered).
// ---------------------------------------------------------------------------------------------

/// Sign of orient3d(a, b, c, d) as read by the judge.
template <class J, class T>
int orient3dSign(J& judge, const robust::V3<T>& a, const robust::V3<T>& b, const robust::V3<T>& c,
                 const robust::V3<T>& d) {
  return judge((b - a).cross(c - a).dot(d - a));
}

/// Sign of orient2d(a, b, c, drop) as read by the judge.
template <class J, class T>
int orient2dSign(J& judge, const robust::V3<T>& a, const robust::V3<T>& b, const robust::V3<T>& c, int drop) {
  const int u = (drop + 1) % 3;
  const int v = (drop + 2) % 3;
  return judge((b[u] - a[u]) * (c[v] - a[v]) - (b[v] - a[v]) * (c[u] - a[u]));
}

/// An axis k with n_k != 0 (as read by the judge), preferring the largest |n_k| (by the
/// approximate value, so the projection dropping k is well conditioned); -1 when n = 0. This is
/// the exact replacement of dominantAxis: dropping k projects the plane with normal n onto a
/// coordinate plane bijectively.
template <class J, class T>
int nonzeroAxis(J& judge, const robust::V3<T>& n) {
  const Wide m[3] = {std::abs(robust::approx(n.x)), std::abs(robust::approx(n.y)), std::abs(robust::approx(n.z))};
  int order[3] = {0, 1, 2};
  if (m[order[1]] > m[order[0]]) std::swap(order[0], order[1]);
  if (m[order[2]] > m[order[1]]) std::swap(order[1], order[2]);
  if (m[order[1]] > m[order[0]]) std::swap(order[0], order[1]);
  for (const int k : order)
    if (judge(n[k]) != 0) return k;
  return -1;
}

/// True when u × v = 0 (parallel or a zero vector), as read by the judge.
template <class J, class T>
bool crossIsZero(J& judge, const robust::V3<T>& u, const robust::V3<T>& v) {
  return nonzeroAxis(judge, u.cross(v)) < 0;
}

/// Point x on the closed segment [p, q] (p == q allowed): collinear and between the endpoints.
template <class J, class T>
bool pointOnSegment(J& judge, const robust::V3<T>& x, const robust::V3<T>& p, const robust::V3<T>& q) {
  const robust::V3<T> d = q - p, w = x - p;
  if (!crossIsZero(judge, d, w)) return false;
  return judge(w.dot(d)) >= 0 && judge((x - q).dot(d)) <= 0 && (judge(d.x) != 0 || judge(d.y) != 0 || judge(d.z) != 0 || judge(w.squaredNorm()) == 0);
}

/// Point x in the closed 2-D triangle abc (non-degenerate after dropping axis `drop`).
template <class J, class T>
bool pointInTriangle2d(J& judge, const robust::V3<T>& x, const robust::V3<T>& a, const robust::V3<T>& b,
                       const robust::V3<T>& c, int drop) {
  const int o1 = orient2dSign(judge, a, b, x, drop);
  const int o2 = orient2dSign(judge, b, c, x, drop);
  const int o3 = orient2dSign(judge, c, a, x, drop);
  return (o1 >= 0 && o2 >= 0 && o3 >= 0) || (o1 <= 0 && o2 <= 0 && o3 <= 0);
}

/// Point x on the proper triangle abc: in its plane and inside in a projection that keeps it
/// non-degenerate.
template <class J, class T>
bool pointOnTriangle(J& judge, const robust::V3<T>& x, const robust::V3<T>& a, const robust::V3<T>& b,
                     const robust::V3<T>& c) {
  if (orient3dSign(judge, a, b, c, x) != 0) return false;
  const int drop = nonzeroAxis(judge, (b - a).cross(c - a));
  if (drop < 0) return false;  // not proper (only under an uncertain filter sign)
  return pointInTriangle2d(judge, x, a, b, c, drop);
}

/// The number type of a judge.
template <class J>
using NumberOf = typename std::decay_t<J>::Number;

/// Exact sign of orient3d(a, b, c, d) for any finite inputs.
inline int orient3dExact(const WVec3& a, const WVec3& b, const WVec3& c, const WVec3& d) {
  return robust::filtered([&](auto& judge) {
    using T = NumberOf<decltype(judge)>;
    return orient3dSign(judge, robust::lift<T>(a), robust::lift<T>(b), robust::lift<T>(c), robust::lift<T>(d));
  });
}

/// Exact sign of orient2d(a, b, c, drop) for any finite inputs.
inline int orient2dExact(const WVec3& a, const WVec3& b, const WVec3& c, int drop) {
  return robust::filtered([&](auto& judge) {
    using T = NumberOf<decltype(judge)>;
    return orient2dSign(judge, robust::lift<T>(a), robust::lift<T>(b), robust::lift<T>(c), drop);
  });
}

/// What a triangle's corner set really is.
enum class TriangleKind { Triangle, Segment, Point };

/// A triangle classified exactly: a proper triangle, the segment [p, q] its collinear corners
/// span (two corners extreme along an axis where they differ), or the point p its coincident
/// corners are. p and q are input corners (exact).
struct TriangleShape {
  TriangleKind kind = TriangleKind::Triangle;
  WVec3 p, q;  ///< Segment endpoints (Segment), the point (Point, in p).
};

/// Static filter of classify (Shewchuk 1997's static filters): true when a component n_i of
/// u × v (u = b − a, v = c − a, evaluated in Wide) is certainly non-zero, so the corners are
/// certainly not collinear; false when it cannot tell. With unit roundoff kUlp/2 per operation,
/// the exact component differs from the computed n_i by at most
/// 1.6·kUlp·(|u_j v_k| + |u_k v_j|) + kUlp/2·|n_i| + 2·denorm_min (the differences, the
/// products and the component rounded once each); the test asks for
/// |n_i| > (4·kUlp·(|u_j v_k| + |u_k v_j|) + 2·kTiny)·kSafety, which also covers the bound's
/// own rounding. It only saves classify's filtered evaluation (about ten times its cost):
/// classify's result is the same either way.
inline bool certainlyNotCollinear(const WVec3& a, const WVec3& b, const WVec3& c) {
  using B = robust::Bounded;
  const WVec3 u = b - a, v = c - a;
  const WVec3 p = u.cwiseProduct(WVec3(v.y(), v.z(), v.x()));  // u_x v_y, u_y v_z, u_z v_x
  const WVec3 q = WVec3(u.y(), u.z(), u.x()).cwiseProduct(v);  // u_y v_x, u_z v_y, u_x v_z
  const WVec3 n = p - q;                                       // n_z, n_x, n_y
  constexpr Wide kRel = 4 * B::kUlp * (1 + 4 * B::kUlp);
  const WVec3 bound = (p.cwiseAbs() + q.cwiseAbs()) * kRel + WVec3::Constant(2 * B::kTiny);
  return ((n.cwiseAbs() - bound * B::kSafety).array() > 0).any();
}

/// Classifies the corners a, b, c exactly for any finite values: the cross product of the
/// edges is exactly zero iff the corners are collinear (certainlyNotCollinear first, then the
/// filtered, and if need be exact, test of the cross product).
inline TriangleShape classify(const WVec3& a, const WVec3& b, const WVec3& c) {
  TriangleShape s;
  if (certainlyNotCollinear(a, b, c)) return s;  // kind Triangle
  const bool proper = robust::filtered([&](auto& judge) {
    using T = NumberOf<decltype(judge)>;
    const robust::V3<T> A = robust::lift<T>(a);
    return !crossIsZero(judge, robust::lift<T>(b) - A, robust::lift<T>(c) - A);
  });
  if (proper) {
    s.kind = TriangleKind::Triangle;
    return s;
  }
  if (a == b && b == c) {
    s.kind = TriangleKind::Point;
    s.p = s.q = a;
    return s;
  }
  s.kind = TriangleKind::Segment;
  // Collinear: the extremes along an axis where the corners differ span the set.
  const WVec3* v[3] = {&a, &b, &c};
  int k = 0;
  while (a[k] == b[k] && b[k] == c[k]) ++k;
  int lo = 0, hi = 0;
  for (int i = 1; i < 3; ++i) {
    if ((*v[i])[k] < (*v[lo])[k]) lo = i;
    if ((*v[i])[k] > (*v[hi])[k]) hi = i;
  }
  s.p = *v[lo];
  s.q = *v[hi];
  return s;
}

/// Classifies t exactly (classify of its corners).
inline TriangleShape classify(const Triangle& t) { return classify(wide(t.a), wide(t.b), wide(t.c)); }

}  // namespace crux::predicates
