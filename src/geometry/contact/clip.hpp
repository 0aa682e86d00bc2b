// Reference-feature clipping shared by the generic contact (contact.cpp), the closed-form triangle
// contacts (triangle_contact.cpp) and the box–triangle SAT (box_triangle_contact.cpp): the clip
// polygon step, the reference clip that turns clipped points into contact points, and the merge
// of points coincident on both bodies.
#pragma once

#include <crux/geometry/contact.hpp>
#include <crux/geometry/triangle_class.hpp>
#include <crux/math.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

namespace crux::contact_detail {

// kOnFeatureUlps: triangle_class.hpp.

/// Rounding budget of a feature's coordinates: kOnFeatureUlps ulps of Real × the largest of
/// `scale` and its |coordinates|.
inline double coincidenceTolerance(const Eigen::Vector3d* v, int n, double scale) {
  for (int i = 0; i < n; ++i) scale = std::max(scale, v[i].cwiseAbs().maxCoeff());
  return kOnFeatureUlps * double(std::numeric_limits<Real>::epsilon()) * scale;
}

/// Removes the points of pts[0, count) that coincide with another on both bodies (pointA and
/// pointB within `tol` of it), keeping the deepest (smallest separation) of each such group, so
/// that an engine never gets two constraints at one place. Order is otherwise kept.
inline void removeCoincident(ContactPoint* pts, int& count, double tol) {
  int k = 0;
  for (int i = 0; i < count; ++i) {
    int same = -1;
    for (int j = 0; j < k && same < 0; ++j)
      if ((pts[i].pointA - pts[j].pointA).template cast<double>().norm() <= tol &&
          (pts[i].pointB - pts[j].pointB).template cast<double>().norm() <= tol)
        same = j;
    if (same < 0) pts[k++] = pts[i];
    else if (pts[i].separation < pts[same].separation) pts[same] = pts[i];
  }
  count = k;
}

/// A vertex of a clip polygon: a point (double) and the feature id it carries (its vertex's id,
/// or the incident feature's for a point cut out of an edge).
struct ClipVertex {
  Eigen::Vector3d p;
  std::uint32_t id;
};

/// One Sutherland–Hodgman step (Sutherland and Hodgman, "Reentrant polygon clipping", 1974),
/// generic over the vertex type V (a member `p`): keeps the part of polygon `in` (a closed loop
/// of n vertices; a segment when n == 2, a point when n == 1) where the affine `dist(p)` >= 0,
/// writing at most `capacity` vertices to `out`; a crossing edge a→b gives `cut(a, b, da, db)`
/// (the caller interpolates what its vertices carry). Returns the count.
template <class V, class Dist, class Cut>
int clipStep(const V* in, int n, Dist dist, Cut cut, V* out, int capacity) {
  if (n == 1) {
    if (dist(in[0].p) < 0) return 0;
    out[0] = in[0];
    return 1;
  }
  if (n == 2) {  // a segment: clip its parameter interval
    const double d0 = dist(in[0].p), d1 = dist(in[1].p);
    if (d0 < 0 && d1 < 0) return 0;
    int k = 0;
    if (d0 >= 0) out[k++] = in[0];
    if ((d0 < 0) != (d1 < 0)) out[k++] = cut(in[0], in[1], d0, d1);
    if (d1 >= 0) out[k++] = in[1];
    return k;
  }
  int k = 0;
  for (int i = 0; i < n; ++i) {
    const V& a = in[i];
    const V& b = in[(i + 1) % n];
    const double da = dist(a.p), db = dist(b.p);
    if (da >= 0 && k < capacity) out[k++] = a;
    if ((da < 0) != (db < 0) && k < capacity) out[k++] = cut(a, b, da, db);
  }
  return k;
}

/// clipStep against the half-space dot(x − o, m) >= 0; cut points carry `cutId`.
inline int clipPolygon(const ClipVertex* in, int n, const Eigen::Vector3d& o, const Eigen::Vector3d& m,
                       std::uint32_t cutId, ClipVertex* out, int capacity) {
  return clipStep(
      in, n, [&](const Eigen::Vector3d& p) { return (p - o).dot(m); },
      [&](const ClipVertex& a, const ClipVertex& b, double da, double db) {
        return ClipVertex{a.p + (b.p - a.p) * (da / (da - db)), cutId};
      },
      out, capacity);
}

/// Reference-feature clipping (the contact-manifold construction of Gregorius, "Robust Contact
/// Creation for Physics Simulations", GDC 2015): the incident feature `inc` clipped by the side
/// planes of the reference feature `ref` (a face's edge planes about its outward unit normal u,
/// or an edge's two end planes), then each clipped point measured along u from the reference
/// (for an edge reference, from its closest point on the edge). Points within `margin` of
/// touching become contact points (A's rounded by rA, B's by rB, along the pair normal n from B to
/// A), written to pts; points that coincide on both bodies within `tol` are merged (the deepest
/// kept). Returns the point count (0: none within the margin), or -1 when two edges within the
/// feature angle are skew (a clipped point farther than the rounding budget across the
/// reference edge: the caller falls back to its single closest pair). `Feature` has v[], vid[],
/// n and id; kCapacity bounds the clip polygons (2 × the feature size + 4 is enough).
template <int kCapacity, class Feature>
int clipToReference(const Feature& ref, const Feature& inc, bool refIsA, const Eigen::Vector3d& u,
                    const Eigen::Vector3d& n, double rA, double rB, double margin, double tol, ContactPoint* pts) {
  using V3 = Eigen::Vector3d;
  ClipVertex bufA[kCapacity], bufB[kCapacity];
  int cnt = inc.n;
  for (int i = 0; i < cnt; ++i) bufA[i] = {inc.v[i], inc.vid[i]};
  ClipVertex* cur = bufA;
  ClipVertex* nxt = bufB;
  if (ref.n >= 3) {
    for (int i = 0; i < ref.n && cnt > 0; ++i) {
      const V3 e = ref.v[(i + 1) % ref.n] - ref.v[i];
      cnt = clipPolygon(cur, cnt, ref.v[i], u.cross(e), inc.id, nxt, kCapacity);
      std::swap(cur, nxt);
    }
  } else {
    V3 e = ref.v[1] - ref.v[0];
    e -= u * u.dot(e);
    cnt = clipPolygon(cur, cnt, ref.v[0], e, inc.id, nxt, kCapacity);
    std::swap(cur, nxt);
    if (cnt > 0) cnt = clipPolygon(cur, cnt, ref.v[1], -e, inc.id, nxt, kCapacity);
    std::swap(cur, nxt);
  }
  // Edge reference: two edges within the feature angle but skew (offset across the normal) have
  // no common perpendicular there, and projecting along the normal would leave the reference
  // edge (points used to land outside a box); past the rounding budget (for a rounded
  // reference, the offset whose effect on its surface is that budget) the pair is skew.
  const double lateralTol = ref.n == 2 ? tol + std::sqrt(2 * (refIsA ? rA : rB) * tol) : 0;
  const V3 r0 = ref.v[0];
  int np = 0;
  for (int i = 0; i < cnt; ++i) {
    const V3 q = cur[i].p;
    double s = u.dot(q - r0);
    if (ref.n == 2) {
      const V3 e = ref.v[1] - ref.v[0];
      const double e2 = e.squaredNorm();
      const double t = e2 > 0 ? std::clamp(e.dot(q - r0) / e2, 0.0, 1.0) : 0.0;
      const V3 diff = q - (r0 + t * e);
      s = u.dot(diff);
      if (!((diff - s * u).norm() <= lateralTol)) return -1;
    }
    const double sep = s - rA - rB;
    if (!(sep <= margin)) continue;
    const V3 onRef = q - s * u;
    const V3 ca = refIsA ? onRef : q, cb = refIsA ? q : onRef;
    ContactPoint& c = pts[np++];
    c.pointA = (ca - n * rA).template cast<Real>();
    c.pointB = (cb + n * rB).template cast<Real>();
    c.separation = static_cast<Real>(sep);
    c.featureA = refIsA ? ref.id : cur[i].id;
    c.featureB = refIsA ? cur[i].id : ref.id;
  }
  removeCoincident(pts, np, tol);
  return np;
}

}  // namespace crux::contact_detail
