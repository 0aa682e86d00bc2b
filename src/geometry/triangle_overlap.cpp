/// @file triangle_overlap.cpp  Boolean overlap of a triangle with a triangle, sphere, AABB, OBB
/// and plane.
///
/// Every decision is the sign of a division-free polynomial of the input coordinates evaluated
/// in Wide (see predicates.hpp): exact for integer inputs of magnitude <= 64. Degenerate
/// triangles are classified exactly (predicates::classify) and tested as the segment or point
/// they are.

#include <crux/geometry/overlap.hpp>
#include <crux/geometry/predicates.hpp>

#include <algorithm>
#include <cmath>
#include <utility>

namespace crux {
namespace {

using predicates::dominantAxis;
using predicates::orient2d;
using predicates::orient3d;
using predicates::TriangleKind;
using predicates::TriangleShape;

// ---------------------------------------------------------------------------------------------
// Low-dimensional pieces: points, segments and triangles as exact point sets.
// ---------------------------------------------------------------------------------------------

/// Point x on the closed segment [p, q] (p != q): collinear and between the endpoints.
bool pointOnSegment(const WVec3& x, const WVec3& p, const WVec3& q) {
  const WVec3 d = q - p;
  if (!d.cross(x - p).isZero(0)) return false;
  return (x - p).dot(d) >= 0 && (x - q).dot(d) <= 0;
}

/// Point x in the closed 2-D triangle abc (non-degenerate after dropping axis `drop`).
bool pointInTriangle2d(const WVec3& x, const WVec3& a, const WVec3& b, const WVec3& c, int drop) {
  const Wide o1 = orient2d(a, b, x, drop);
  const Wide o2 = orient2d(b, c, x, drop);
  const Wide o3 = orient2d(c, a, x, drop);
  return (o1 >= 0 && o2 >= 0 && o3 >= 0) || (o1 <= 0 && o2 <= 0 && o3 <= 0);
}

/// Point x on the proper triangle abc: in its plane and inside in the dominant projection.
bool pointOnTriangle(const WVec3& x, const WVec3& a, const WVec3& b, const WVec3& c) {
  if (orient3d(a, b, c, x) != 0) return false;
  return pointInTriangle2d(x, a, b, c, dominantAxis((b - a).cross(c - a)));
}

/// True when all of xs lie strictly on the right of the directed 2-D line uv.
bool strictlyRightOf(const WVec3& u, const WVec3& v, const WVec3* xs, int n, int drop) {
  for (int i = 0; i < n; ++i) {
    if (orient2d(u, v, xs[i], drop) >= 0) return false;
  }
  return true;
}

/// 2-D separating-axis test of a counter-clockwise triangle tri[3] against the convex set
/// spanned by xs[n] (n = 2: a segment, n = 3: a triangle): true when some edge line of tri
/// has all of xs strictly outside.
bool separatedByEdges2d(const WVec3* tri, const WVec3* xs, int n, int drop) {
  return strictlyRightOf(tri[0], tri[1], xs, n, drop) ||
         strictlyRightOf(tri[1], tri[2], xs, n, drop) ||
         strictlyRightOf(tri[2], tri[0], xs, n, drop);
}

/// Reorders a 2-D non-degenerate triangle counter-clockwise in the projection dropping `drop`.
void makeCounterClockwise(WVec3* tri, int drop) {
  if (orient2d(tri[0], tri[1], tri[2], drop) < 0) std::swap(tri[1], tri[2]);
}

/// Coplanar proper triangles: 2-D separating axes are the six edge normals (both are convex
/// polygons, so the edge normals are complete).
bool coplanarTriangles(const WVec3& a1, const WVec3& b1, const WVec3& c1, const WVec3& a2,
                       const WVec3& b2, const WVec3& c2) {
  const int drop = dominantAxis((b1 - a1).cross(c1 - a1));
  WVec3 t1[3] = {a1, b1, c1};
  WVec3 t2[3] = {a2, b2, c2};
  makeCounterClockwise(t1, drop);
  makeCounterClockwise(t2, drop);
  return !separatedByEdges2d(t1, t2, 3, drop) && !separatedByEdges2d(t2, t1, 3, drop);
}

/// Segment [p, q] against the proper triangle abc, both in one plane: the triangle's three
/// edge lines and the segment's own line are a complete set of 2-D separating axes.
bool coplanarSegmentTriangle(const WVec3& p, const WVec3& q, const WVec3& a, const WVec3& b,
                             const WVec3& c) {
  const int drop = dominantAxis((b - a).cross(c - a));
  WVec3 tri[3] = {a, b, c};
  makeCounterClockwise(tri, drop);
  const WVec3 seg[2] = {p, q};
  if (separatedByEdges2d(tri, seg, 2, drop)) return false;
  const Wide sa = orient2d(p, q, a, drop), sb = orient2d(p, q, b, drop),
             sc = orient2d(p, q, c, drop);
  return !((sa > 0 && sb > 0 && sc > 0) || (sa < 0 && sb < 0 && sc < 0));
}

/// Segment [p, q] (p != q) against the proper triangle abc in 3-D. If the segment crosses the
/// plane at one point, that point is in the triangle iff the line pq passes the three
/// directed edges on one side (triple products of one weak sign); a segment in the plane is
/// decided in 2-D.
bool segmentTriangle(const WVec3& p, const WVec3& q, const WVec3& a, const WVec3& b,
                     const WVec3& c) {
  const Wide sp = orient3d(a, b, c, p), sq = orient3d(a, b, c, q);
  if ((sp > 0 && sq > 0) || (sp < 0 && sq < 0)) return false;
  if (sp == 0 && sq == 0) return coplanarSegmentTriangle(p, q, a, b, c);
  const Wide e1 = orient3d(p, q, a, b), e2 = orient3d(p, q, b, c), e3 = orient3d(p, q, c, a);
  return (e1 >= 0 && e2 >= 0 && e3 >= 0) || (e1 <= 0 && e2 <= 0 && e3 <= 0);
}

/// Closed segments [p, q] and [r, s] (p != q, r != s) in 3-D: they must be coplanar; then
/// collinear segments overlap as intervals, parallel ones never meet, and crossing lines meet
/// inside both segments iff each segment straddles the other's line.
bool segmentSegment(const WVec3& p, const WVec3& q, const WVec3& r, const WVec3& s) {
  if (orient3d(p, q, r, s) != 0) return false;
  const WVec3 d = q - p;
  const WVec3 n = d.cross(s - r);
  if (n.isZero(0)) {
    if (!d.cross(r - p).isZero(0)) return false;  // parallel, distinct lines
    const int k = dominantAxis(d);                // one line: compare intervals along it
    const Wide lo1 = std::min(p[k], q[k]), hi1 = std::max(p[k], q[k]);
    const Wide lo2 = std::min(r[k], s[k]), hi2 = std::max(r[k], s[k]);
    return lo1 <= hi2 && lo2 <= hi1;
  }
  const int drop = dominantAxis(n);
  const Wide o1 = orient2d(p, q, r, drop), o2 = orient2d(p, q, s, drop);
  if ((o1 > 0 && o2 > 0) || (o1 < 0 && o2 < 0)) return false;
  const Wide o3 = orient2d(r, s, p, drop), o4 = orient2d(r, s, q, drop);
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
bool triangleTriangle(const WVec3 t1In[3], const WVec3 t2In[3]) {
  int s1[3], s2[3];
  for (int i = 0; i < 3; ++i)
    s1[i] = predicates::sign(orient3d(t2In[0], t2In[1], t2In[2], t1In[i]));
  if ((s1[0] > 0 && s1[1] > 0 && s1[2] > 0) || (s1[0] < 0 && s1[1] < 0 && s1[2] < 0)) return false;
  for (int i = 0; i < 3; ++i)
    s2[i] = predicates::sign(orient3d(t1In[0], t1In[1], t1In[2], t2In[i]));
  if ((s2[0] > 0 && s2[1] > 0 && s2[2] > 0) || (s2[0] < 0 && s2[1] < 0 && s2[2] < 0)) return false;
  const bool coplanar1 = s1[0] == 0 && s1[1] == 0 && s1[2] == 0;
  const bool coplanar2 = s2[0] == 0 && s2[1] == 0 && s2[2] == 0;
  if (coplanar1 || coplanar2) {
    return coplanarTriangles(t1In[0], t1In[1], t1In[2], t2In[0], t2In[1], t2In[2]);
  }

  WVec3 t2[3] = {t2In[0], t2In[1], t2In[2]};
  int k1 = 0, k2 = 0;
  bool flip1 = false, flip2 = false;
  isolateCorner(s1, k1, flip1);
  if (flip1) {  // reversing t2 reverses the orientation of its plane
    std::swap(t2[1], t2[2]);
    std::swap(s2[1], s2[2]);
  }
  isolateCorner(s2, k2, flip2);
  const WVec3& p1 = t1In[k1];
  const WVec3* q1 = &t1In[(k1 + 1) % 3];
  const WVec3* r1 = &t1In[(k1 + 2) % 3];
  if (flip2) std::swap(q1, r1);  // reversing t1 reverses the orientation of its plane
  const WVec3& p2 = t2[k2];
  const WVec3& q2 = t2[(k2 + 1) % 3];
  const WVec3& r2 = t2[(k2 + 2) % 3];
  return orient3d(p1, *q1, p2, q2) <= 0 && orient3d(p1, *r1, r2, p2) <= 0;
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

/// A degenerate-or-proper triangle with its corners promoted to Wide.
struct Simplex {
  TriangleShape shape;
  WVec3 v[3];
};

Simplex toSimplex(const Triangle& t) {
  return {predicates::classify(t), {wide(t.a), wide(t.b), wide(t.c)}};
}

/// Point x against any simplex.
bool pointOnSimplex(const WVec3& x, const Simplex& s) {
  switch (s.shape.kind) {
    case TriangleKind::Triangle:
      return pointOnTriangle(x, s.v[0], s.v[1], s.v[2]);
    case TriangleKind::Segment:
      return pointOnSegment(x, s.shape.p, s.shape.q);
    case TriangleKind::Point:
      break;
  }
  return x == s.shape.p;
}

/// Segment [p, q] (p != q) against any simplex.
bool segmentOnSimplex(const WVec3& p, const WVec3& q, const Simplex& s) {
  switch (s.shape.kind) {
    case TriangleKind::Triangle:
      return segmentTriangle(p, q, s.v[0], s.v[1], s.v[2]);
    case TriangleKind::Segment:
      return segmentSegment(p, q, s.shape.p, s.shape.q);
    case TriangleKind::Point:
      break;
  }
  return pointOnSegment(s.shape.p, p, q);
}

// ---------------------------------------------------------------------------------------------
// Triangle–sphere: squared distance <= r², division-free per Voronoi region.
// ---------------------------------------------------------------------------------------------

/// |x - [p, q]|² <= r2 for a segment (p == q allowed): vertex regions by the sign of the
/// projection parameter, the interior by |(x-p) × d|² <= r2 |d|².
bool segmentWithinRadius(const WVec3& x, const WVec3& p, const WVec3& q, Wide r2) {
  const WVec3 d = q - p, w = x - p;
  const Wide t = w.dot(d);
  if (t <= 0) return w.squaredNorm() <= r2;
  const Wide dd = d.squaredNorm();
  if (t >= dd) return (x - q).squaredNorm() <= r2;
  return w.cross(d).squaredNorm() <= r2 * dd;
}

/// Proper triangle abc: |x - T|² <= r2. The distance to a closed triangle is the plane
/// distance when x projects inside it, else the distance to the nearest edge, so: reject by
/// the plane distance (h² > r2|n|², a lower bound), accept when x projects inside (exact
/// orientation signs n·(e_i × (x - v_i))), else test the three edges as segments. Unlike
/// RTCD 5.1.5's region classification by products of dot products, nothing here cancels
/// catastrophically on sliver triangles; on the integer grid every sign is exact.
/// A triangle whose corner angle at a has sin² below this is a sliver whose computed normal is
/// rounding noise (relative error ~1e-16 / sin): it is measured by its edges alone, which moves
/// the answer by at most its width (~1e-12 of its edges). Never reached on the integer grid,
/// where sin² >= 1 / (3·128²)².
constexpr Wide kSliverSine2 = 1e-24;

bool triangleWithinRadius(const WVec3& x, const WVec3& a, const WVec3& b, const WVec3& c, Wide r2) {
  const WVec3 ab = b - a, bc = c - b, ca = a - c;
  const WVec3 n = ab.cross(c - a);
  if (n.squaredNorm() <= kSliverSine2 * ab.squaredNorm() * ca.squaredNorm())
    return segmentWithinRadius(x, a, b, r2) || segmentWithinRadius(x, b, c, r2) ||
           segmentWithinRadius(x, c, a, r2);
  const Wide h = n.dot(x - a);
  if (h * h > r2 * n.squaredNorm()) return false;
  const Wide sa = n.dot(ab.cross(x - a)), sb = n.dot(bc.cross(x - b)), sc = n.dot(ca.cross(x - c));
  if (sa >= 0 && sb >= 0 && sc >= 0) return true;  // projects inside: the plane distance decides
  return segmentWithinRadius(x, a, b, r2) || segmentWithinRadius(x, b, c, r2) ||
         segmentWithinRadius(x, c, a, r2);
}

// ---------------------------------------------------------------------------------------------
// Triangle–box: Akenine-Möller 2001 separating axes, box centred at the origin.
// ---------------------------------------------------------------------------------------------

/// True when the projections [min(p0, p1), max(p0, p1)] and [-r, r] are disjoint.
inline bool separated(Wide p0, Wide p1, Wide r) {
  return std::min(p0, p1) > r || std::max(p0, p1) < -r;
}

/// Triangle v[3] (box coordinates) against the box [-h, h]. Axes: the 3 box normals, the 9
/// products u_j × e_i, and the triangle normal when `proper`. A degenerate triangle (classified
/// exactly in world coordinates by the caller) skips the normal axis: after mapping into a
/// rotated box frame its computed normal is rounding noise, not an axis; the remaining axes
/// (box normals, u_j × segment direction) are complete for a segment or point.
bool triangleCenteredBox(const WVec3 v[3], const WVec3& h, bool proper) {
  for (int i = 0; i < 3; ++i) {
    if (std::min({v[0][i], v[1][i], v[2][i]}) > h[i]) return false;
    if (std::max({v[0][i], v[1][i], v[2][i]}) < -h[i]) return false;
  }
  for (int i = 0; i < 3; ++i) {
    const WVec3& v0 = v[i];            // edge start (the end projects to the same value)
    const WVec3& v2 = v[(i + 2) % 3];  // the opposite corner
    const WVec3 e = v[(i + 1) % 3] - v0;
    // u_x × e = (0, -e_z, e_y), u_y × e = (e_z, 0, -e_x), u_z × e = (-e_y, e_x, 0).
    if (separated(e.y() * v0.z() - e.z() * v0.y(), e.y() * v2.z() - e.z() * v2.y(),
                  h.y() * std::abs(e.z()) + h.z() * std::abs(e.y())))
      return false;
    if (separated(e.z() * v0.x() - e.x() * v0.z(), e.z() * v2.x() - e.x() * v2.z(),
                  h.x() * std::abs(e.z()) + h.z() * std::abs(e.x())))
      return false;
    if (separated(e.x() * v0.y() - e.y() * v0.x(), e.x() * v2.y() - e.y() * v2.x(),
                  h.x() * std::abs(e.y()) + h.y() * std::abs(e.x())))
      return false;
  }
  if (!proper) return true;
  const WVec3 n = (v[1] - v[0]).cross(v[2] - v[0]);
  return std::abs(n.dot(v[0])) <= h.dot(n.cwiseAbs());
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
  const Simplex sa = toSimplex(a), sb = toSimplex(b);
  switch (sa.shape.kind) {
    case TriangleKind::Triangle:
      if (sb.shape.kind == TriangleKind::Triangle) return triangleTriangle(sa.v, sb.v);
      break;
    case TriangleKind::Segment:
      return segmentOnSimplex(sa.shape.p, sa.shape.q, sb);
    case TriangleKind::Point:
      return pointOnSimplex(sa.shape.p, sb);
  }
  // a is a proper triangle, b is degenerate.
  if (sb.shape.kind == TriangleKind::Segment) return segmentOnSimplex(sb.shape.p, sb.shape.q, sa);
  return pointOnSimplex(sb.shape.p, sa);
}

}  // namespace

// Symmetric by construction: the two argument orders evaluate different predicates, which agree
// exactly on the integer grid but may round differently elsewhere (found by fuzz_geometry,
// docs/fuzzing.md), so the pair is evaluated in one canonical order.
bool overlaps(const Triangle& a, const Triangle& b) {
  return precedes(b, a) ? overlapsOrdered(b, a) : overlapsOrdered(a, b);
}

bool overlaps(const Triangle& t, const Sphere& s) {
  const WVec3 x = wide(s.center);
  const Wide r = s.radius;
  const Wide r2 = r * r;
  const TriangleShape shape = predicates::classify(t);
  switch (shape.kind) {
    case TriangleKind::Triangle:
      return triangleWithinRadius(x, wide(t.a), wide(t.b), wide(t.c), r2);
    case TriangleKind::Segment:
      return segmentWithinRadius(x, shape.p, shape.q, r2);
    case TriangleKind::Point:
      break;
  }
  return (x - shape.p).squaredNorm() <= r2;
}

bool overlaps(const Triangle& t, const Aabb& b) {
  const WVec3 c = (wide(b.min) + wide(b.max)) * Wide(0.5);
  const WVec3 h = (wide(b.max) - wide(b.min)) * Wide(0.5);
  const WVec3 v[3] = {wide(t.a) - c, wide(t.b) - c, wide(t.c) - c};
  return triangleCenteredBox(v, h, predicates::classify(t).kind == TriangleKind::Triangle);
}

bool overlaps(const Triangle& t, const Obb& b) {
  const WVec3 c = wide(b.center);
  const Eigen::Matrix<Wide, 3, 3> rt = b.axes.cast<Wide>().transpose();
  const WVec3 v[3] = {rt * (wide(t.a) - c), rt * (wide(t.b) - c), rt * (wide(t.c) - c)};
  return triangleCenteredBox(v, wide(b.half), predicates::classify(t).kind == TriangleKind::Triangle);
}

bool overlaps(const Triangle& t, const Plane& p) {
  const WVec3 n = wide(p.normal);
  const Wide d = p.d;
  const Wide sa = n.dot(wide(t.a)) - d, sb = n.dot(wide(t.b)) - d, sc = n.dot(wide(t.c)) - d;
  return std::min({sa, sb, sc}) <= 0 && std::max({sa, sb, sc}) >= 0;
}

}  // namespace crux
