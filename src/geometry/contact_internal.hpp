// Rules shared by the generic contact clipping (contact.cpp), the closed-form triangle contacts
// (triangle_contact.cpp) and the box–triangle SAT (box_triangle_contact.cpp, its clipping step),
// which must classify triangle features, clip and merge coincident points identically.
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

// kOnFeatureUlps and the reference-face rule (kTriangleFaceRelative): triangle_class.hpp.

/// sin of the feature angle (kContactFaceAngleCos, contact.hpp), from that same cosine, so the
/// face, edge and parallel-edge tests of every contact routine draw the line in one place.
inline const double kContactFaceAngleSin =
    std::sqrt(1 - double(kContactFaceAngleCos) * double(kContactFaceAngleCos));

/// The supporting-feature rule's edge test, written once for contact.cpp, triangle_contact.cpp
/// and box_triangle_contact.cpp: whether an edge e with e·d = ed and |e|² = e2 (d unit) is
/// within the feature angle of perpendicular to d and at least as near to it as bestCos (|cos|
/// of the best so far, starting at kContactFaceAngleSin), which it then becomes. The supporting
/// vertex then grows into that edge.
inline bool nearerPerpendicular(double ed, double e2, double& bestCos) {
  // Cheap reject (no square root): beyond the feature angle with room to spare for rounding, so
  // the exact test below would reject it too (bestCos only decreases from kContactFaceAngleSin).
  if (!(e2 > 0) || ed * ed > kContactFaceAngleSin * kContactFaceAngleSin * (1 + 1e-6) * e2) return false;
  const double len = std::sqrt(e2);
  if (!(len > 0)) return false;
  const double c = std::abs(ed) / len;
  if (!(c <= bestCos)) return false;
  bestCos = c;
  return true;
}

/// Of the edges (is, others[k]) of a shape whose vertex `is` supports the unit direction d, the
/// index k of the one nearerPerpendicular chooses, or -1 (the vertex is the feature). `vertex(i)`
/// gives vertex i.
template <class VertexAt>
int supportingEdge(const VertexAt& vertex, const Eigen::Vector3d& d, int is, const int* others, int nOthers) {
  const Eigen::Vector3d vs = vertex(is);
  int bestK = -1;
  double bestCos = kContactFaceAngleSin;
  for (int k = 0; k < nOthers; ++k) {
    const Eigen::Vector3d e = vertex(others[k]) - vs;
    if (nearerPerpendicular(e.dot(d), e.squaredNorm(), bestCos)) bestK = k;
  }
  return bestK;
}

/// Whether two edges are parallel within the feature angle (|ea × eb| <= sin·|ea|·|eb|): then they
/// are clipped against each other; crossing edges touch at one point.
inline bool edgesParallel(const Eigen::Vector3d& ea, const Eigen::Vector3d& eb) {
  return ea.cross(eb).norm() <= kContactFaceAngleSin * ea.norm() * eb.norm();
}

/// The 4-point manifold reduction, written once for contact.cpp and box_triangle_contact.cpp (the
/// mesh's reduction over the points of many triangles, mesh_contact.cpp, adds a merge tolerance
/// and ties by triangle): of count > 4 points keep the deepest (smallest separation, the first of
/// equals), the one farthest from it, and the two of largest and smallest signed area about the
/// axis u with those two; when all lie on one side, the one of largest |area| and then the point
/// adding most area outside that triangle. `pos(p)` is point p's position (double) and `sep(p)`
/// its separation. The kept four move to the front, in that order; count becomes 4.
template <class Point, class Pos, class Sep>
void reduceToFour(Point* pts, int& count, const Eigen::Vector3d& u, const Pos& pos, const Sep& sep) {
  using V3 = Eigen::Vector3d;
  if (count <= ContactManifold::kMaxContactPoints) return;
  const auto P = [&](int i) -> V3 { return pos(pts[i]); };
  int sel[4] = {0, -1, -1, -1};
  for (int i = 1; i < count; ++i)
    if (sep(pts[i]) < sep(pts[sel[0]])) sel[0] = i;
  double best = -1;
  for (int i = 0; i < count; ++i)
    if (i != sel[0] && (P(i) - P(sel[0])).squaredNorm() > best) {
      best = (P(i) - P(sel[0])).squaredNorm();
      sel[1] = i;
    }
  const auto area = [&](int i) { return (P(sel[1]) - P(sel[0])).cross(P(i) - P(sel[0])).dot(u); };
  int hi = -1, lo = -1;
  for (int i = 0; i < count; ++i) {
    if (i == sel[0] || i == sel[1]) continue;
    if (hi < 0 || area(i) > area(hi)) hi = i;
    if (lo < 0 || area(i) < area(lo)) lo = i;
  }
  sel[2] = hi;
  sel[3] = lo;
  if (lo == hi || area(hi) <= 0 || area(lo) >= 0) {  // all on one side: the largest triangle + the best 4th
    sel[2] = std::abs(area(hi)) >= std::abs(area(lo)) ? hi : lo;
    sel[3] = -1;
    double bestGain = -1;
    for (int i = 0; i < count; ++i) {
      if (i == sel[0] || i == sel[1] || i == sel[2]) continue;
      double gain = 0;  // the largest |area| outside one of the triangle's edges
      for (int e = 0; e < 3; ++e) {
        const V3 a = P(sel[e]), b = P(sel[(e + 1) % 3]);
        gain = std::max(gain, std::abs((b - a).cross(P(i) - a).dot(u)));
      }
      if (gain > bestGain) {
        bestGain = gain;
        sel[3] = i;
      }
    }
  }
  Point kept[4];
  for (int k = 0; k < 4; ++k) kept[k] = pts[sel[k]];
  for (int k = 0; k < 4; ++k) pts[k] = kept[k];
  count = 4;
}

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

/// The contact margin decision, separation <= margin, for a separation computed in double within
/// `band` of its exact value: certain outside the band, else `exact()` decides (withinDistance's
/// filtered exact predicates, overlap.hpp), so that touching on integer grids is reported exactly.
/// `clamp` tells that the pair is within the margin but its computed separation beyond it (the
/// callers then report the margin as its separation).
template <class Exact>
bool withinMargin(double separation, double margin, double band, const Exact& exact, bool& clamp) {
  clamp = false;
  if (!(separation <= margin + band)) return false;
  if (separation <= margin - band) return true;
  if (!exact()) return false;
  clamp = separation > margin;
  return true;
}

/// Whether a clipped manifold pts[0, np) keeps the closest (deepest) pair's separation `sep` (the
/// GJK/EPA one along the true contact normal): its smallest separation is at most sep plus the
/// face snapping's allowance, (1 − kContactFaceAngleCos)·|sep|, and the rounding budget tol. The
/// overlap along any direction is at least the minimum, so a reference face snapped to within
/// 2° measures its deepest support point at least that deep; but clipping cuts that point away
/// when it lies beyond the face's side planes (crux diff: a capsule's end past a tetrahedron's
/// edge read 6.6e-4 relative shallow, tests/regressions/native.crux-wrong.contacts.9301-8420).
/// The callers then report the single closest pair, along the true normal.
inline bool keepsClosest(const ContactPoint* pts, int np, double sep, double tol) {
  double least = std::numeric_limits<double>::infinity();
  for (int i = 0; i < np; ++i) least = std::min(least, double(pts[i].separation));
  return least <= sep + (1 - double(kContactFaceAngleCos)) * std::abs(sep) + tol;
}

}  // namespace crux::contact_detail
