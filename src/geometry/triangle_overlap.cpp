/// @file triangle_overlap.cpp  Boolean overlap of a triangle with a triangle, sphere, AABB, OBB
/// and plane.
///
/// Every decision is the sign of a division-free polynomial of the input coordinates, read by
/// a judge (predicates.hpp, expansion.hpp): each test is a template run first with the
/// forward-error filter and, only when some sign was uncertain, again with exact expansions.
/// The answers are therefore exact for any finite inputs (float and double builds; see
/// docs/geometry.md for the range). Degenerate triangles are classified exactly
/// (predicates::classify) and tested as the segment or point they are.

#include "geometry/unchecked.hpp"

#include <crux/error.hpp>
#include <crux/geometry/overlap.hpp>
#include <crux/geometry/predicates.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

namespace crux {
namespace {

using robust::lift;
using robust::V3;
using predicates::crossIsZero;
using predicates::nonzeroAxis;
using predicates::NumberOf;
using predicates::orient2dSign;
using predicates::orient3dSign;
using predicates::pointInTriangle2d;
using predicates::pointOnSegment;
using predicates::pointOnTriangle;
using predicates::TriangleKind;
using predicates::TriangleShape;

// ---------------------------------------------------------------------------------------------
// Low-dimensional pieces: points, segments and triangles as exact point sets.
// ---------------------------------------------------------------------------------------------

/// True when all of xs lie strictly on the right of the directed 2-D line uv.
template <class J, class T>
bool strictlyRightOf(J& judge, const V3<T>& u, const V3<T>& v, const V3<T>* xs, int n, int drop) {
  for (int i = 0; i < n; ++i) {
    if (orient2dSign(judge, u, v, xs[i], drop) >= 0) return false;
  }
  return true;
}

/// 2-D separating-axis test of a counter-clockwise triangle tri[3] against the convex set
/// spanned by xs[n] (n = 2: a segment, n = 3: a triangle): true when some edge line of tri
/// has all of xs strictly outside.
template <class J, class T>
bool separatedByEdges2d(J& judge, const V3<T>* tri, const V3<T>* xs, int n, int drop) {
  return strictlyRightOf(judge, tri[0], tri[1], xs, n, drop) || strictlyRightOf(judge, tri[1], tri[2], xs, n, drop) ||
         strictlyRightOf(judge, tri[2], tri[0], xs, n, drop);
}

/// Reorders a 2-D non-degenerate triangle counter-clockwise in the projection dropping `drop`.
template <class J, class T>
void makeCounterClockwise(J& judge, V3<T>* tri, int drop) {
  if (orient2dSign(judge, tri[0], tri[1], tri[2], drop) < 0) std::swap(tri[1], tri[2]);
}

/// Coplanar proper triangles: 2-D separating axes are the six edge normals (both are convex
/// polygons, so the edge normals are complete).
template <class J, class T>
bool coplanarTriangles(J& judge, const V3<T>* t1In, const V3<T>* t2In) {
  const int drop = nonzeroAxis(judge, (t1In[1] - t1In[0]).cross(t1In[2] - t1In[0]));
  if (drop < 0) return false;  // only under an uncertain filter sign
  V3<T> t1[3] = {t1In[0], t1In[1], t1In[2]};
  V3<T> t2[3] = {t2In[0], t2In[1], t2In[2]};
  makeCounterClockwise(judge, t1, drop);
  makeCounterClockwise(judge, t2, drop);
  return !separatedByEdges2d(judge, t1, t2, 3, drop) && !separatedByEdges2d(judge, t2, t1, 3, drop);
}

/// Segment [p, q] against the proper triangle abc, both in one plane: the triangle's three
/// edge lines and the segment's own line are a complete set of 2-D separating axes.
template <class J, class T>
bool coplanarSegmentTriangle(J& judge, const V3<T>& p, const V3<T>& q, const V3<T>& a, const V3<T>& b,
                             const V3<T>& c) {
  const int drop = nonzeroAxis(judge, (b - a).cross(c - a));
  if (drop < 0) return false;
  V3<T> tri[3] = {a, b, c};
  makeCounterClockwise(judge, tri, drop);
  const V3<T> seg[2] = {p, q};
  if (separatedByEdges2d(judge, tri, seg, 2, drop)) return false;
  const int sa = orient2dSign(judge, p, q, a, drop), sb = orient2dSign(judge, p, q, b, drop),
            sc = orient2dSign(judge, p, q, c, drop);
  return !((sa > 0 && sb > 0 && sc > 0) || (sa < 0 && sb < 0 && sc < 0));
}

/// Segment [p, q] (p != q) against the proper triangle abc in 3-D. If the segment crosses the
/// plane at one point, that point is in the triangle iff the line pq passes the three
/// directed edges on one side (triple products of one weak sign); a segment in the plane is
/// decided in 2-D.
template <class J, class T>
bool segmentTriangle(J& judge, const V3<T>& p, const V3<T>& q, const V3<T>& a, const V3<T>& b, const V3<T>& c) {
  const int sp = orient3dSign(judge, a, b, c, p), sq = orient3dSign(judge, a, b, c, q);
  if ((sp > 0 && sq > 0) || (sp < 0 && sq < 0)) return false;
  if (sp == 0 && sq == 0) return coplanarSegmentTriangle(judge, p, q, a, b, c);
  const int e1 = orient3dSign(judge, p, q, a, b), e2 = orient3dSign(judge, p, q, b, c),
            e3 = orient3dSign(judge, p, q, c, a);
  return (e1 >= 0 && e2 >= 0 && e3 >= 0) || (e1 <= 0 && e2 <= 0 && e3 <= 0);
}

/// Closed segments [p, q] and [r, s] (p != q, r != s) in 3-D: they must be coplanar; then
/// collinear segments overlap as intervals, parallel ones never meet, and crossing lines meet
/// inside both segments iff each segment straddles the other's line.
template <class J, class T>
bool segmentSegment(J& judge, const V3<T>& p, const V3<T>& q, const V3<T>& r, const V3<T>& s) {
  if (orient3dSign(judge, p, q, r, s) != 0) return false;
  const V3<T> d = q - p;
  const int drop = nonzeroAxis(judge, d.cross(s - r));
  if (drop < 0) {
    if (!crossIsZero(judge, d, r - p)) return false;  // parallel, distinct lines
    const int k = nonzeroAxis(judge, d);              // one line: compare intervals along it
    if (k < 0) return false;
    const bool pLow = judge(p[k] - q[k]) <= 0, rLow = judge(r[k] - s[k]) <= 0;
    const T& lo1 = pLow ? p[k] : q[k];
    const T& hi1 = pLow ? q[k] : p[k];
    const T& lo2 = rLow ? r[k] : s[k];
    const T& hi2 = rLow ? s[k] : r[k];
    return judge(lo1 - hi2) <= 0 && judge(lo2 - hi1) <= 0;
  }
  const int o1 = orient2dSign(judge, p, q, r, drop), o2 = orient2dSign(judge, p, q, s, drop);
  if ((o1 > 0 && o2 > 0) || (o1 < 0 && o2 < 0)) return false;
  const int o3 = orient2dSign(judge, r, s, p, drop), o4 = orient2dSign(judge, r, s, q, drop);
  return !((o3 > 0 && o4 > 0) || (o3 < 0 && o4 < 0));
}

// ---------------------------------------------------------------------------------------------
// Triangle–triangle: Guigue & Devillers 2003.
// ---------------------------------------------------------------------------------------------

/// Finds the corner k whose side of a plane is opposite to the other two (signs s of the three
/// corners, not all equal and non-zero, not all zero). On return s[k] >= 0 >= the others
/// after negating all signs when `flip` is set, and s[k] == 0 only when both others are
/// strictly negative (the triangle touches the plane at that corner alone).
void isolateCorner(const int s[3], int& k, bool& flip) {
  for (k = 0; k < 3; ++k) {
    const int a = s[k], b = s[(k + 1) % 3], c = s[(k + 2) % 3];
    if (a > 0 && b <= 0 && c <= 0) {
      flip = false;
      return;
    }
    if (a < 0 && b >= 0 && c >= 0) {
      flip = true;
      return;
    }
  }
  for (k = 0; k < 3; ++k) {
    const int b = s[(k + 1) % 3], c = s[(k + 2) % 3];
    if (b < 0 && c < 0) {
      flip = false;
      return;
    }
    if (b > 0 && c > 0) {
      flip = true;
      return;
    }
  }
  k = 0;  // unreachable for valid sign patterns
  flip = false;
}

/// Proper triangles t1, t2. Each triangle's corners are classified against the other's plane
/// (a triangle strictly on one side is rejected, coplanar pairs go to 2-D). Then t1 is rotated
/// so that p1 is alone on its side of plane 2 and t2 reversed if needed to put p1 on the
/// positive side; likewise t2 against plane 1 (reversing t1 keeps p1 alone). The triangles
/// meet the planes' common line L in [i, j] (i on p1q1, j on p1r1) and [k, l] (k on p2q2, l on
/// p2r2); with these orientations the order along L is j <= i and k <= l, so they overlap iff
/// k <= i and j <= l. The plane through p1, q1, p2 cuts L at i and holds p2, so the side of q2
/// gives the side of k: k <= i iff orient3d(p1, q1, p2, q2) <= 0; likewise j <= l iff
/// orient3d(p1, r1, r2, p2) <= 0. Touching configurations (zeros) fall on the closed side.
template <class J, class T>
bool triangleTriangle(J& judge, const V3<T>* t1In, const V3<T>* t2In) {
  int s1[3], s2[3];
  for (int i = 0; i < 3; ++i) s1[i] = orient3dSign(judge, t2In[0], t2In[1], t2In[2], t1In[i]);
  if ((s1[0] > 0 && s1[1] > 0 && s1[2] > 0) || (s1[0] < 0 && s1[1] < 0 && s1[2] < 0)) return false;
  for (int i = 0; i < 3; ++i) s2[i] = orient3dSign(judge, t1In[0], t1In[1], t1In[2], t2In[i]);
  if ((s2[0] > 0 && s2[1] > 0 && s2[2] > 0) || (s2[0] < 0 && s2[1] < 0 && s2[2] < 0)) return false;
  const bool coplanar1 = s1[0] == 0 && s1[1] == 0 && s1[2] == 0;
  const bool coplanar2 = s2[0] == 0 && s2[1] == 0 && s2[2] == 0;
  if (coplanar1 || coplanar2) return coplanarTriangles(judge, t1In, t2In);

  int o2[3] = {0, 1, 2};  // t2's corner order (reversed when flipped)
  int k1 = 0, k2 = 0;
  bool flip1 = false, flip2 = false;
  isolateCorner(s1, k1, flip1);
  if (flip1) {  // reversing t2 reverses the orientation of its plane
    std::swap(o2[1], o2[2]);
    std::swap(s2[1], s2[2]);
  }
  isolateCorner(s2, k2, flip2);
  const V3<T>& p1 = t1In[k1];
  const V3<T>* q1 = &t1In[(k1 + 1) % 3];
  const V3<T>* r1 = &t1In[(k1 + 2) % 3];
  if (flip2) std::swap(q1, r1);  // reversing t1 reverses the orientation of its plane
  const V3<T>& p2 = t2In[o2[k2]];
  const V3<T>& q2 = t2In[o2[(k2 + 1) % 3]];
  const V3<T>& r2 = t2In[o2[(k2 + 2) % 3]];
  return orient3dSign(judge, p1, *q1, p2, q2) <= 0 && orient3dSign(judge, p1, *r1, r2, p2) <= 0;
}

/// Exact bounding-box rejection: disjoint boxes mean disjoint triangles.
bool boundsDisjoint(const Triangle& a, const Triangle& b) {
  for (int i = 0; i < 3; ++i) {
    const Real minA = std::min({a.a[i], a.b[i], a.c[i]}), maxA = std::max({a.a[i], a.b[i], a.c[i]});
    const Real minB = std::min({b.a[i], b.b[i], b.c[i]}), maxB = std::max({b.a[i], b.b[i], b.c[i]});
    if (maxA < minB || maxB < minA) return true;
  }
  return false;
}

/// A degenerate-or-proper triangle: its exact class and its corners as numbers of type T.
template <class T>
struct Simplex {
  TriangleKind kind;
  V3<T> v[3];
  V3<T> p, q;  ///< segment endpoints / the point
};

/// The simplex of the corners x, y, z (Real or Wide vectors), classified as `shape`.
template <class T, class P>
Simplex<T> simplexOf(const TriangleShape& shape, const P& x, const P& y, const P& z) {
  return {shape.kind, {lift<T>(x), lift<T>(y), lift<T>(z)}, lift<T>(shape.p), lift<T>(shape.q)};
}

/// Point x against any simplex.
template <class J, class T>
bool pointOnSimplex(J& judge, const V3<T>& x, const Simplex<T>& s) {
  switch (s.kind) {
    case TriangleKind::Triangle:
      return pointOnTriangle(judge, x, s.v[0], s.v[1], s.v[2]);
    case TriangleKind::Segment:
      return pointOnSegment(judge, x, s.p, s.q);
    case TriangleKind::Point:
      break;
  }
  return nonzeroAxis(judge, x - s.p) < 0;  // x == p
}

/// Segment [p, q] (p != q) against any simplex.
template <class J, class T>
bool segmentOnSimplex(J& judge, const V3<T>& p, const V3<T>& q, const Simplex<T>& s) {
  switch (s.kind) {
    case TriangleKind::Triangle:
      return segmentTriangle(judge, p, q, s.v[0], s.v[1], s.v[2]);
    case TriangleKind::Segment:
      return segmentSegment(judge, p, q, s.p, s.q);
    case TriangleKind::Point:
      break;
  }
  return pointOnSegment(judge, s.p, p, q);
}

// ---------------------------------------------------------------------------------------------
// Triangle–sphere: squared distance <= r², division-free per Voronoi region.
// ---------------------------------------------------------------------------------------------

/// |x - [p, q]|² <= r2 for a segment (p == q allowed): vertex regions by the sign of the
/// projection parameter, the interior by |(x-p) × d|² <= r2 |d|².
template <class J, class T>
bool segmentWithinRadius(J& judge, const V3<T>& x, const V3<T>& p, const V3<T>& q, const T& r2) {
  const V3<T> d = q - p, w = x - p;
  const T t = w.dot(d);
  if (judge(t) <= 0) return judge(w.squaredNorm() - r2) <= 0;
  const T dd = d.squaredNorm();
  if (judge(t - dd) >= 0) return judge((x - q).squaredNorm() - r2) <= 0;
  return judge(w.cross(d).squaredNorm() - r2 * dd) <= 0;
}

/// Proper triangle abc: |x - T|² <= r2. The distance to a closed triangle is the plane
/// distance when x projects inside it, else the distance to the nearest edge, so: reject by
/// the plane distance (h² > r2|n|², a lower bound), accept when x projects inside (signs of
/// n·(e_i × (x - v_i))), else test the three edges as segments. Every sign is exact (degree
/// <= 6 in the inputs), so no sliver triangle needs special treatment.
template <class J, class T>
bool triangleWithinRadius(J& judge, const V3<T>& x, const V3<T>& a, const V3<T>& b, const V3<T>& c, const T& r2) {
  const V3<T> ab = b - a, bc = c - b, ca = a - c;
  const V3<T> n = ab.cross(c - a);
  const T h = n.dot(x - a);
  if (judge(h * h - r2 * n.squaredNorm()) > 0) return false;
  const int sa = judge(n.dot(ab.cross(x - a))), sb = judge(n.dot(bc.cross(x - b))), sc = judge(n.dot(ca.cross(x - c)));
  if (sa >= 0 && sb >= 0 && sc >= 0) return true;  // projects inside: the plane distance decides
  return segmentWithinRadius(judge, x, a, b, r2) || segmentWithinRadius(judge, x, b, c, r2) ||
         segmentWithinRadius(judge, x, c, a, r2);
}

/// |[p, q] - [u, v]|² <= r2 for two segments (either may be a point): an endpoint of one within
/// r of the other, or else the lines' closest points interior to both (RTCD 5.1.9's parameters
/// s = (b·g - e·f)/den, t = (a·g - b·f)/den, compared as numerators with den = |d1 × d2|² > 0)
/// and the lines' distance |w·(d1 × d2)|/|d1 × d2| within r. When the line minimum is outside
/// the unit square of parameters, or the lines are parallel, the minimum over the segments is on
/// that square's boundary: an endpoint against the other segment.
template <class J, class T>
bool segmentsWithinRadius(J& judge, const V3<T>& p, const V3<T>& q, const V3<T>& u, const V3<T>& v, const T& r2) {
  if (segmentWithinRadius(judge, p, u, v, r2) || segmentWithinRadius(judge, q, u, v, r2) ||
      segmentWithinRadius(judge, u, p, q, r2) || segmentWithinRadius(judge, v, p, q, r2))
    return true;
  const V3<T> d1 = q - p, d2 = v - u, w = p - u;
  const V3<T> c = d1.cross(d2);
  const T den = c.squaredNorm();
  if (judge(den) <= 0) return false;
  const T a = d1.dot(d1), b = d1.dot(d2), e = d2.dot(d2), f = d1.dot(w), g = d2.dot(w);
  const T sn = b * g - e * f, tn = a * g - b * f;
  if (judge(sn) <= 0 || judge(sn - den) >= 0 || judge(tn) <= 0 || judge(tn - den) >= 0) return false;
  const T h = w.dot(c);
  return judge(h * h - r2 * den) <= 0;
}

/// |x - S|² <= r2 for any simplex S.
template <class J, class T>
bool pointWithinSimplex(J& judge, const V3<T>& x, const Simplex<T>& s, const T& r2) {
  switch (s.kind) {
    case TriangleKind::Triangle:
      return triangleWithinRadius(judge, x, s.v[0], s.v[1], s.v[2], r2);
    case TriangleKind::Segment:
      return segmentWithinRadius(judge, x, s.p, s.q, r2);
    case TriangleKind::Point:
      break;
  }
  return judge((x - s.p).squaredNorm() - r2) <= 0;
}

/// |[p, q] - S|² <= r2 for any simplex S and p != q: 0 when they meet; else the distance of a
/// segment to a convex polygon is attained at one of its endpoints or against the polygon's
/// boundary (along the segment the distance to the plane is linear while the nearest point is
/// interior to the face, so it has no interior minimum there without a crossing).
template <class J, class T>
bool segmentWithinSimplex(J& judge, const V3<T>& p, const V3<T>& q, const Simplex<T>& s, const T& r2) {
  if (segmentOnSimplex(judge, p, q, s)) return true;
  switch (s.kind) {
    case TriangleKind::Triangle:
      return pointWithinSimplex(judge, p, s, r2) || pointWithinSimplex(judge, q, s, r2) ||
             segmentsWithinRadius(judge, p, q, s.v[0], s.v[1], r2) ||
             segmentsWithinRadius(judge, p, q, s.v[1], s.v[2], r2) ||
             segmentsWithinRadius(judge, p, q, s.v[2], s.v[0], r2);
    case TriangleKind::Segment:
      return segmentsWithinRadius(judge, p, q, s.p, s.q, r2);
    case TriangleKind::Point:
      break;
  }
  return segmentWithinRadius(judge, s.p, p, q, r2);
}

/// |A - B|² <= r2 for two simplices (points, segments, proper triangles): a point against the
/// other; a segment against the other (segmentWithinSimplex); two triangles: 0 when they meet,
/// else the distance of disjoint triangles is attained at a corner against the other triangle
/// or between two edges.
template <class J, class T>
bool simplicesWithin(J& judge, const Simplex<T>& a, const Simplex<T>& b, const T& r2) {
  if (a.kind == TriangleKind::Point) return pointWithinSimplex(judge, a.p, b, r2);
  if (b.kind == TriangleKind::Point) return pointWithinSimplex(judge, b.p, a, r2);
  if (a.kind == TriangleKind::Segment) return segmentWithinSimplex(judge, a.p, a.q, b, r2);
  if (b.kind == TriangleKind::Segment) return segmentWithinSimplex(judge, b.p, b.q, a, r2);
  if (triangleTriangle(judge, a.v, b.v)) return true;
  for (int i = 0; i < 3; ++i)
    if (triangleWithinRadius(judge, a.v[i], b.v[0], b.v[1], b.v[2], r2) ||
        triangleWithinRadius(judge, b.v[i], a.v[0], a.v[1], a.v[2], r2))
      return true;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (segmentsWithinRadius(judge, a.v[i], a.v[(i + 1) % 3], b.v[j], b.v[(j + 1) % 3], r2)) return true;
  return false;
}

/// The simplex of a core of n = 1..3 points (exact: coincident points are one point, collinear
/// corners the segment they span).
template <class T>
Simplex<T> coreSimplex(const WVec3* c, int n) {
  predicates::TriangleShape shape;
  if (n >= 3) {
    shape = predicates::classify(c[0], c[1], c[2]);
  } else if (n == 2 && c[0] != c[1]) {
    shape.kind = TriangleKind::Segment;
    shape.p = c[0];
    shape.q = c[1];
  } else {
    shape.kind = TriangleKind::Point;
    shape.p = shape.q = c[0];
  }
  const WVec3& x = c[0];
  const WVec3& y = c[n >= 2 ? 1 : 0];
  const WVec3& z = c[n >= 3 ? 2 : 0];
  return simplexOf<T>(shape, x, y, z);
}

// ---------------------------------------------------------------------------------------------
// Triangle–box: Akenine-Möller 2001 separating axes, box centred at the origin.
// ---------------------------------------------------------------------------------------------

/// |x| as a number, given the sign of x.
template <class T>
T absBySign(const T& x, int s) {
  return s < 0 ? -x : x;
}

/// True when the projections [min(p0, p1), max(p0, p1)] and [-r, r] are disjoint.
template <class J, class T>
bool separated(J& judge, const T& p0, const T& p1, const T& r) {
  return (judge(p0 - r) > 0 && judge(p1 - r) > 0) || (judge(p0 + r) < 0 && judge(p1 + r) < 0);
}

/// Triangle v[3] (box coordinates, any common positive scale) against the box [-h, h] (same
/// scale). Axes: the 9 products u_j × e_i and the triangle normal (zero for a degenerate
/// triangle: then it separates nothing, and the remaining axes are complete for a segment or
/// point); the 3 box normals are tested by the caller when `boxNormals` is false.
template <class J, class T>
bool triangleCenteredBox(J& judge, const V3<T>* v, const V3<T>& h, bool boxNormals) {
  if (boxNormals) {
    for (int i = 0; i < 3; ++i) {
      if (judge(v[0][i] - h[i]) > 0 && judge(v[1][i] - h[i]) > 0 && judge(v[2][i] - h[i]) > 0) return false;
      if (judge(v[0][i] + h[i]) < 0 && judge(v[1][i] + h[i]) < 0 && judge(v[2][i] + h[i]) < 0) return false;
    }
  }
  for (int i = 0; i < 3; ++i) {
    const V3<T>& v0 = v[i];            // edge start (the end projects to the same value)
    const V3<T>& v2 = v[(i + 2) % 3];  // the opposite corner
    const V3<T> e = v[(i + 1) % 3] - v0;
    const V3<T> ae = {absBySign(e.x, judge(e.x)), absBySign(e.y, judge(e.y)), absBySign(e.z, judge(e.z))};
    // u_x × e = (0, -e_z, e_y), u_y × e = (e_z, 0, -e_x), u_z × e = (-e_y, e_x, 0).
    if (separated(judge, e.y * v0.z - e.z * v0.y, e.y * v2.z - e.z * v2.y, h.y * ae.z + h.z * ae.y)) return false;
    if (separated(judge, e.z * v0.x - e.x * v0.z, e.z * v2.x - e.x * v2.z, h.x * ae.z + h.z * ae.x)) return false;
    if (separated(judge, e.x * v0.y - e.y * v0.x, e.x * v2.y - e.y * v2.x, h.x * ae.y + h.y * ae.x)) return false;
  }
  const V3<T> n = (v[1] - v[0]).cross(v[2] - v[0]);
  const V3<T> an = {absBySign(n.x, judge(n.x)), absBySign(n.y, judge(n.y)), absBySign(n.z, judge(n.z))};
  const T reach = h.dot(an), dist = n.dot(v[0]);
  return judge(dist - reach) <= 0 && judge(dist + reach) >= 0;
}

}  // namespace

namespace {

/// Lexicographic order of the nine coordinates: the canonical argument order of
/// overlaps(Triangle, Triangle).
bool precedes(const Triangle& x, const Triangle& y) {
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k)
      if (x[i][k] != y[i][k]) return x[i][k] < y[i][k];
  return false;
}

bool overlapsOrdered(const Triangle& a, const Triangle& b) {
  if (boundsDisjoint(a, b)) return false;
  const TriangleShape shapeA = predicates::classify(a), shapeB = predicates::classify(b);
  return robust::filtered([&](auto& judge) {
    using T = NumberOf<decltype(judge)>;
    const Simplex<T> sa = simplexOf<T>(shapeA, a.a, a.b, a.c), sb = simplexOf<T>(shapeB, b.a, b.b, b.c);
    switch (sa.kind) {
      case TriangleKind::Triangle:
        if (sb.kind == TriangleKind::Triangle) return triangleTriangle(judge, sa.v, sb.v);
        break;
      case TriangleKind::Segment:
        return segmentOnSimplex(judge, sa.p, sa.q, sb);
      case TriangleKind::Point:
        return pointOnSimplex(judge, sa.p, sb);
    }
    // a is a proper triangle, b is degenerate.
    if (sb.kind == TriangleKind::Segment) return segmentOnSimplex(judge, sb.p, sb.q, sa);
    return pointOnSimplex(judge, sb.p, sa);
  });
}

}  // namespace

// Symmetric by construction: the pair is evaluated in one canonical order (the signs are exact,
// so both orders agree; the canonical order keeps the filter's work identical too).
bool unchecked::overlaps(const Triangle& a, const Triangle& b) {
  return precedes(b, a) ? overlapsOrdered(b, a) : overlapsOrdered(a, b);
}

bool unchecked::overlaps(const Triangle& t, const Sphere& s) {
  // Cheap rejection: the sphere's box misses the triangle's box on some axis, by a margin the
  // filter certifies (no exact stage here: an uncertain margin just goes on to the full test).
  for (int i = 0; i < 3; ++i) {
    const robust::Bounded c(Wide(s.center[i])), r(Wide(s.radius));
    const robust::Bounded hi(Wide(std::max({t.a[i], t.b[i], t.c[i]}))), lo(Wide(std::min({t.a[i], t.b[i], t.c[i]})));
    if (((c - hi) - r).certainSign() == 1 || ((lo - c) - r).certainSign() == 1) return false;
  }
  const TriangleShape shape = predicates::classify(t);
  return robust::filtered([&](auto& judge) {
    using T = NumberOf<decltype(judge)>;
    const T r = T(Wide(s.radius));
    return pointWithinSimplex(judge, lift<T>(s.center), simplexOf<T>(shape, t.a, t.b, t.c), r * r);
  });
}

bool unchecked::overlaps(const Triangle& t, const Aabb& b) {
  // Box normals first, on the inputs themselves (exact comparisons).
  for (int i = 0; i < 3; ++i) {
    if (t.a[i] > b.max[i] && t.b[i] > b.max[i] && t.c[i] > b.max[i]) return false;
    if (t.a[i] < b.min[i] && t.b[i] < b.min[i] && t.c[i] < b.min[i]) return false;
  }
  // The remaining axes in box coordinates scaled by 2 (no halving): v = 2x - (min + max),
  // h = max - min.
  return robust::filtered([&](auto& judge) {
    using T = NumberOf<decltype(judge)>;
    const V3<T> lo = lift<T>(b.min), hi = lift<T>(b.max);
    const V3<T> mid = lo + hi;
    const V3<T> a = lift<T>(t.a), bb = lift<T>(t.b), c = lift<T>(t.c);
    const V3<T> v[3] = {(a + a) - mid, (bb + bb) - mid, (c + c) - mid};
    return triangleCenteredBox(judge, v, hi - lo, false);
  });
}

bool unchecked::overlaps(const Triangle& t, const Obb& b) {
  // Box coordinates v = axesᵀ (x - center) with the caller's axes as given (exactly).
  return robust::filtered([&](auto& judge) {
    using T = NumberOf<decltype(judge)>;
    const V3<T> c = lift<T>(b.center);
    V3<T> axis[3];
    for (int i = 0; i < 3; ++i) axis[i] = lift<T>(Vec3(b.axes.col(i)));
    const auto toBox = [&](const Vec3& x) {
      const V3<T> d = lift<T>(x) - c;
      return V3<T>{axis[0].dot(d), axis[1].dot(d), axis[2].dot(d)};
    };
    const V3<T> v[3] = {toBox(t.a), toBox(t.b), toBox(t.c)};
    return triangleCenteredBox(judge, v, lift<T>(b.half), true);
  });
}

bool unchecked::overlaps(const Triangle& t, const Plane& p) {
  return robust::filtered([&](auto& judge) {
    using T = NumberOf<decltype(judge)>;
    const V3<T> n = lift<T>(p.normal);
    const T d = T(Wide(p.d));
    const int sa = judge(n.dot(lift<T>(t.a)) - d), sb = judge(n.dot(lift<T>(t.b)) - d),
              sc = judge(n.dot(lift<T>(t.c)) - d);
    return std::min({sa, sb, sc}) <= 0 && std::max({sa, sb, sc}) >= 0;
  });
}

bool withinDistance(const WVec3* a, int na, const WVec3* b, int nb, Wide radiusA, Wide radiusB, Wide margin) {
  if (na < 1 || na > 3 || nb < 1 || nb > 3)
    throw InvalidInput("withinDistance: cores of 1 to 3 points, got " + std::to_string(na) + " and " + std::to_string(nb));
  return robust::filtered([&](auto& judge) {
    using T = NumberOf<decltype(judge)>;
    const T reach = (T(radiusA) + T(radiusB)) + T(margin);
    return simplicesWithin(judge, coreSimplex<T>(a, na), coreSimplex<T>(b, nb), reach * reach);
  });
}

bool unchecked::withinDistance(const Triangle& t, const Vec3& x, Real radius, Real margin) {
  const WVec3 tri[3] = {wide(t.a), wide(t.b), wide(t.c)}, point = wide(x);
  return crux::withinDistance(tri, 3, &point, 1, Wide(radius), 0, Wide(margin));
}

bool unchecked::withinDistance(const Triangle& t, const Vec3& p, const Vec3& q, Real radius, Real margin) {
  const WVec3 tri[3] = {wide(t.a), wide(t.b), wide(t.c)}, segment[2] = {wide(p), wide(q)};
  return crux::withinDistance(tri, 3, segment, 2, Wide(radius), 0, Wide(margin));
}

}  // namespace crux
