// Closest-point routines shared inside the geometry layer: the closest point of a sliver
// triangle (closestPoint(Triangle) in closest_point.cpp and the sphere–triangle contact in
// triangle_contact.cpp, which also needs the point's region), the one point–triangle region
// routine (the same two), the one point–triangle closest point built from them
// (closestPoint(Triangle) and triangle–triangle distance), the one face-inside test (triangle–
// triangle distance, the capsule–triangle contact) and the one segment–segment
// closest-point routine (GJK's core pairs, the contacts, triangle–triangle distance).
#pragma once

#include <crux/math.hpp>

#include "geometry/bits.hpp"

#include <crux/geometry/triangle_class.hpp>

namespace crux::closest_detail {

// A triangle thinner than kTriangleThinRelative (triangle_class.hpp) takes closestOnSliver:
// RTCD 5.1.5's region tests can cancel on it.

/// Closest point q of the sliver triangle (a, b, c) to p, without RTCD's region tests, whose
/// products cancel on slivers (fuzz_geometry: an edge of 1.6e-28 against edges of 75 read its
/// dot products with p − a and p − b, ±|ab|² exactly, as 0, and its region was taken, 110 from p
/// with a corner 66 from it; a scratch search: a tiny edge near the origin against edges of 0.07
/// made vc, vb, va cancel, the face region was taken and p projected onto the plane 0.016 off the
/// triangle, nearer to p than the triangle is). The nearest boundary point, or the projection of
/// p onto the plane when it lies inside (each edge's half-plane within 64 ulps of the coordinates'
/// scale, and within half the height of the boundary: beyond a needle's sharp corner the long
/// edges' half-planes stay within that slack for a long way) and is nearer; the plane's normal is the cross product of the two shorter edges (at the
/// corner opposite the longest), which is well conditioned for a needle (one tiny edge). A flat
/// cap (an angle near 180°) whose shorter edges' sine is below 1e-7 has a normal off by up to
/// eps/sine: it is taken as its boundary, within half its height (< 1e-7 × its longest edge) of
/// every point of it. Returns the region as SphereTriangleContact names it: −1 the face, i the
/// edge from corner i to corner i+1 (mod 3), 3 + i corner i.
int closestOnSliver(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                    const Eigen::Vector3d& p, Eigen::Vector3d& q);

/// Closest point q of a non-degenerate triangle to p (RTCD 5.1.5, Voronoi regions) and its
/// region: -1 the face, 0..2 the edge from corner i to corner i+1 (mod 3), 3..5 the vertex
/// region − 3. For the face q is left untouched (sphereCore computes it from the plane).
/// RTCD's tests in RTCD's order with RTCD's formulas, but every dot product is taken first and
/// the region is the first of the six conditions that holds, combined without branches: the
/// region of a mesh's candidate triangles is unpredictable, and the mispredicted chain of early
/// returns cost more than the dot products it skipped.
/// (Inline: the sphere–triangle contact calls it for every candidate triangle of a mesh.)
inline int closestRegionOnTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                   const Eigen::Vector3d& p, Eigen::Vector3d& q) {
  using V3 = Eigen::Vector3d;
  const V3 ab = b - a, ac = c - a, ap = p - a, bp = p - b, cp = p - c;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  const double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
  const double e43 = d4 - d3, e56 = d5 - d6;
  // RTCD's conditions in its order (& on bools, not &&: no branches)
  const unsigned c3 = unsigned(d1 <= 0) & unsigned(d2 <= 0);
  const unsigned c4 = unsigned(d3 >= 0) & unsigned(d4 <= d3);
  const unsigned c0 = unsigned(vc <= 0) & unsigned(d1 >= 0) & unsigned(d3 <= 0);
  const unsigned c5 = unsigned(d6 >= 0) & unsigned(d5 <= d6);
  const unsigned c2 = unsigned(vb <= 0) & unsigned(d2 >= 0) & unsigned(d6 <= 0);
  const unsigned c1 = unsigned(va <= 0) & unsigned(e43 >= 0) & unsigned(e56 >= 0);
  // the first condition that holds, as a bit index in that order (7: none, the face)
  const unsigned bits = c3 | c4 << 1 | c0 << 2 | c5 << 3 | c2 << 4 | c1 << 5 | 1u << 6;
  static constexpr signed char kRegion[7] = {3, 4, 0, 5, 2, 1, -1};
  const int region = kRegion[detail::lowestBit(bits)];
  // The point without branches either: the edge's formula (by region; any edge for the others,
  // its result then unused) and the vertex, one of the two picked by index.
  static constexpr unsigned char kEdge[7] = {0, 0, 1, 2, 0, 0, 0}, kVertex[7] = {0, 0, 0, 0, 0, 1, 2};
  const unsigned k = kEdge[region + 1];
  const V3 cb = c - b;
  const V3* base[3] = {&a, &b, &a};
  const V3* dir[3] = {&ab, &cb, &ac};
  const double num[3] = {d1, e43, d2}, den[3] = {d1 - d3, e43 + e56, d2 - d6};
  // In an edge region 0 <= num <= den; den = 0 (then num = 0) when p lies so far from a tiny
  // triangle that p − a and p − b round to the same vector: any point of the edge is as near, a
  // is taken rather than 0/0 (fuzz_geometry: corners 1e-30 apart, p 64 away).
  const double param = den[k] > 0 ? num[k] / den[k] : 0.0;
  V3 cand[2];
  cand[0] = *base[k] + *dir[k] * param;
  const V3* corner[3] = {&a, &b, &c};
  cand[1] = *corner[kVertex[region + 1]];
  q = cand[region >= 3];
  return region;
}

/// Closest point q of a non-degenerate triangle to p and its region (closestRegionOnTriangle's
/// numbering: -1 the face, i the edge from corner i to corner i+1 (mod 3), 3 + i corner i): a
/// thin triangle (`thin`, kTriangleThinRelative) by closestOnSliver, any other by RTCD 5.1.5's
/// regions, the face's point by the orthogonal projection onto the plane of n = (b − a) × (c − a)
/// (not from va/vb/vc, whose cancellation grows with the distance of p). A normal too small to be
/// formed takes the sliver's boundary. closestPoint(Triangle) and triangle–triangle distance's
/// crossing points both come here.
inline int closestOnProperTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                   const Eigen::Vector3d& p, bool thin, Eigen::Vector3d& q) {
  if (thin) return closestOnSliver(a, b, c, p, q);
  const int region = closestRegionOnTriangle(a, b, c, p, q);
  if (region >= 0) return region;  // an edge or a vertex
  const Eigen::Vector3d n = (b - a).cross(c - a);
  const double nn = n.squaredNorm();
  if (!(nn > 0)) return closestOnSliver(a, b, c, p, q);
  q = p - n * (n.dot(p - a) / nn);
  return -1;
}

/// Whether x, a point on the plane of the triangle (v[0], v[1], v[2]) with normal n (any length,
/// n·((v1 − v0) × (v2 − v0)) > 0), lies in the closed triangle: the three edge functions
/// ((v[i+1] − v[i]) × (x − v[i]))·n are >= 0 (RTCD 3.4, barycentric signs). A point on an edge
/// or corner is inside. Triangle–triangle distance's vertex–face candidates and the capsule's
/// segment-end projections and plane crossing take it.
inline bool projectsInside(const Eigen::Vector3d* v, const Eigen::Vector3d& n, const Eigen::Vector3d& x) {
  for (int i = 0; i < 3; ++i)
    if ((v[(i + 1) % 3] - v[i]).cross(x - v[i]).dot(n) < 0) return false;
  return true;
}

/// Closest points of the segments p1 + s·d1 and p2 + t·d2, s, t in [0, 1] (Ericson, Real-Time
/// Collision Detection, 5.1.9 ClosestPtSegmentSegment); a zero-length segment is its point.
/// Parallel segments (a·e − b² = 0) fix s = 0, then clamp t and s in turn. No tolerance on the
/// parallel test: for nearly parallel segments the rounded s may land anywhere on the overlap,
/// where the distance varies by less than the rounding, whereas treating them as parallel (s = 0)
/// is off by up to the angle × their length (1e-6 × L for a tolerance of 1e-12 on sin², measured
/// on capsule pairs). Sets s and t; returns the squared distance.
inline double segmentSegment(const Eigen::Vector3d& p1, const Eigen::Vector3d& d1, const Eigen::Vector3d& p2,
                             const Eigen::Vector3d& d2, double& s, double& t) {
  using V = Eigen::Vector3d;
  const auto clamp01 = [](double x) { return x < 0 ? 0.0 : (x > 1 ? 1.0 : x); };
  const V r = p1 - p2;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  if (a <= 0 && e <= 0) {
    s = t = 0;
  } else if (a <= 0) {
    s = 0;
    t = clamp01(f / e);
  } else {
    const double c = d1.dot(r);
    if (e <= 0) {
      t = 0;
      s = clamp01(-c / a);
    } else {
      const double b = d1.dot(d2);
      const double denom = a * e - b * b;
      s = denom > 0 ? clamp01((b * f - c * e) / denom) : 0.0;
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = clamp01(-c / a);
      } else if (t > 1) {
        t = 1;
        s = clamp01((b - c) / a);
      }
    }
  }
  return (p1 + s * d1 - (p2 + t * d2)).squaredNorm();
}

}  // namespace crux::closest_detail
