// Box–triangle contact manifold by the separating-axis test (13 axes), reference-face clipping
// and edge–edge closest points. Fixed-size buffers only; falls back to contacts() (GJK/EPA) when
// the SAT axis does not realise the distance.

#include "geometry/unchecked.hpp"

#include <crux/geometry/box_triangle_contact.hpp>
#include <crux/precondition.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "geometry/contact/clip.hpp"
#include "geometry/contact/reduce.hpp"
#include "geometry/contact/supporting_feature.hpp"
#include "geometry/gjk_internal.hpp"

namespace crux {
namespace {

using V = Eigen::Vector3d;

/// cos and sin of contact.hpp's feature angle (2°).
constexpr double kFeatureCos = double(kContactFaceAngleCos);
using contact_detail::kContactFaceAngleSin;
using contact_detail::faceSupports;
using contact_detail::nearerPerpendicular;

/// The SAT answer is accepted when it realises the axis' separation: an edge–edge pair whose
/// closest points differ along the axis only, and (separated pairs) a clipped point at the
/// axis' separation, within this × scale (scaled units); otherwise the generic routine answers.
constexpr double kRealiseTolerance = 1e-9;

/// Slack (scaled units, coordinates <= 1) of the clearance bound that skips the edge axes (see
/// its use): far above their rounding (tens of ulps), far below kBoxTriangleFaceBias.
constexpr double kEdgeBoundSlack = 1e-12;

/// (i + 1) mod 3 for i in [0, 4], by a table (the comparisons it replaces were branches,
/// mispredicted about once per call).
constexpr int kNextMod3[5] = {1, 2, 0, 1, 2};

/// Clip buffers: a triangle clipped by 4 planes or a box face by 3 has at most 7 vertices.
constexpr int kMaxClip = 12;

struct ClipVertex {
  V p;
  double sep;  // separation along the reference normal, interpolated linearly along cuts
  std::uint32_t id;
};

std::uint32_t vertexId(int i) { return featureId(FeatureKind::Vertex, static_cast<std::uint32_t>(i)); }
std::uint32_t edgeId(int i, int j) { return contact_detail::edgeFeatureId(i, j); }
bool isVertex(std::uint32_t id) { return (id >> 24) == static_cast<std::uint32_t>(FeatureKind::Vertex); }

/// Id of a point cut out of the segment between two clip vertices: the edge when both are
/// vertices (adjacent in every loop clipped here), else the incident feature.
std::uint32_t cutId(const ClipVertex& a, const ClipVertex& b, std::uint32_t featureId) {
  if (isVertex(a.id) && isVertex(b.id)) return edgeId(int(a.id & 0xFFFFFFu), int(b.id & 0xFFFFFFu));
  return featureId;
}

/// contact_detail::clipStep against {x : dist(x) >= 0} (dist affine) for vertices carrying a
/// separation, interpolated along cuts; `snap` (axis >= 0) puts cut points exactly on the
/// axis-aligned plane x[axis] = value.
template <class Dist>
int clip(const ClipVertex* in, int n, Dist dist, int snapAxis, double snapValue, std::uint32_t feature,
         ClipVertex* out) {
  return contact_detail::clipStep(
      in, n, dist,
      [&](const ClipVertex& a, const ClipVertex& b, double da, double db) {
        const double t = da / (da - db);
        ClipVertex c{a.p + (b.p - a.p) * t, a.sep + (b.sep - a.sep) * t, cutId(a, b, feature)};
        if (snapAxis >= 0) c.p[snapAxis] = snapValue;
        return c;
      },
      out, kMaxClip);
}

/// A contact point in the scaled double frame (no initialisation: filled before use).
struct Point {
  V a, b;
  double sep;
  std::uint32_t fa, fb;
};

/// Box vertex i in the local frame: signs (bit0, bit1, bit2) of i.
V boxVertex(const V& h, int i) {
  return V((i & 1) ? h.x() : -h.x(), (i & 2) ? h.y() : -h.y(), (i & 4) ? h.z() : -h.z());
}

/// The box's supporting feature along unit d (contact.hpp's rule), as a clip polygon.
int boxFeature(const V& h, const V& d, ClipVertex* f, std::uint32_t& id) {
  int k = 0;
  d.cwiseAbs().maxCoeff(&k);
  if (faceSupports(d[k], 1)) {
    const bool pos = d[k] > 0;
    int idx[4];
    contact_detail::boxFaceLoop(k, pos, idx);
    for (int q = 0; q < 4; ++q) f[q] = {boxVertex(h, idx[q]), 0, vertexId(idx[q])};
    id = featureId(FeatureKind::Face, static_cast<std::uint32_t>(2 * k + (pos ? 1 : 0)));
    return 4;
  }
  const int is = (d.x() >= 0 ? 1 : 0) | (d.y() >= 0 ? 2 : 0) | (d.z() >= 0 ? 4 : 0);
  // the edge test of the rule on the unit axes (|e·d|/|e| = |d_i| exactly), flat axes excluded
  int bestAxis = -1;
  double bestCos = kContactFaceAngleSin;
  for (int i = 0; i < 3; ++i)
    if (h[i] > 0 && nearerPerpendicular(d[i], 1, bestCos)) bestAxis = i;
  f[0] = {boxVertex(h, is), 0, vertexId(is)};
  if (bestAxis < 0) {
    id = f[0].id;
    return 1;
  }
  const int other = is ^ (1 << bestAxis);
  f[1] = {boxVertex(h, other), 0, vertexId(other)};
  id = edgeId(is, other);
  return 2;
}

/// The triangle's supporting feature along unit d (contact.hpp's rule), as a clip polygon;
/// `m` is its normal (b−a)×(c−a) and mLen its length, 0 when degenerate.
int triangleFeature(const V* t, const V& m, double mLen, const V& d, ClipVertex* f, std::uint32_t& id) {
  if (mLen > 0 && faceSupports(m.dot(d), mLen)) {
    for (int i = 0; i < 3; ++i) f[i] = {t[i], 0, vertexId(i)};
    id = featureId(FeatureKind::Face, m.dot(d) > 0 ? 0u : 1u);
    return 3;
  }
  int is = 0;
  double best = t[0].dot(d);
  for (int i = 1; i < 3; ++i)
    if (t[i].dot(d) > best) {
      best = t[i].dot(d);
      is = i;
    }
  const int others[2] = {(is + 1) % 3, (is + 2) % 3};
  const int k = contact_detail::supportingEdge([t](int i) { return t[i]; }, d, is, others, 2);
  const int bestK = k < 0 ? -1 : others[k];
  f[0] = {t[is], 0, vertexId(is)};
  if (bestK < 0) {
    id = f[0].id;
    return 1;
  }
  f[1] = {t[bestK], 0, vertexId(bestK)};
  id = edgeId(is, bestK);
  return 2;
}

/// triangleFeature's choice for d = dk·unit(k) (dk = ±1, finite inputs), on the corners t, read
/// by component: every dot product with d is then ±one component, exactly (the other terms are
/// ±0), so the choice is the same. Returns 3 (the face; `front` whether
/// m·d > 0), 2 (the edge is–other) or 1 (the corner is).
int triangleFeatureAlongAxis(const V* t, const double* L, const V& m, double mLen, int k, double dk,
                             int& is, int& other, bool& front) {
  if (mLen > 0 && faceSupports(m[k], mLen)) {
    front = m[k] * dk > 0;
    return 3;
  }
  const double p0 = t[0][k] * dk, p1 = t[1][k] * dk, p2 = t[2][k] * dk;
  // the first of the largest (no branches: their outcomes are unpredictable)
  const bool over0 = p1 > p0;
  const bool over1 = p2 > std::max(p0, p1);  // (std::max: `p1 > p0 ? p1 : p0`)
  is = int(over1) << 1 | (int(over0) & ~int(over1));
  int bestK = -1;
  double bestCos = kContactFaceAngleSin;
  for (int kk = 1; kk <= 2; ++kk) {
    const int o = kNextMod3[is + kk - 1];
    // The edge is → o is ±E_j, j = is (kk = 1) or o (kk = 2): the same |e·d| and |e|² = L[j].
    const int j = kk == 1 ? is : o, j1 = kNextMod3[j];
    if (nearerPerpendicular((t[j1][k] - t[j][k]) * dk, L[j], bestCos)) bestK = o;
  }
  other = bestK;
  return bestK < 0 ? 1 : 2;
}

enum class AxisKind { BoxFace, TriangleFace, Edge };

struct Axis {
  AxisKind kind = AxisKind::BoxFace;
  int i = 0, j = 0;  // box axis; triangle edge (Edge)
  double sep = -std::numeric_limits<double>::infinity();
  V n = V::UnitZ();  // unit, box -> triangle
};

/// scale = 2^−e and unscale = 2^e with S·scale in [0.5, 1) (frexp's exponent e; 1 and 1 for
/// S = 0, inf or NaN), by the bits of S when both are normal doubles, else by frexp/ldexp.
inline void powerOfTwoScale(double S, double& scale, double& unscale) {
  if (!(S > 0) || !std::isfinite(S)) return;
  std::uint64_t bits;
  std::memcpy(&bits, &S, sizeof bits);
  const int e = int((bits >> 52) & 0x7FF) - 1022;  // S normal: S = m·2^e, m in [0.5, 1)
  if (e >= -1021 && e <= 1022) {  // 2^±e both normal (else frexp/ldexp, as before)
    const std::uint64_t down = std::uint64_t(1023 - e) << 52, up = std::uint64_t(1023 + e) << 52;
    std::memcpy(&scale, &down, sizeof scale);
    std::memcpy(&unscale, &up, sizeof unscale);
    return;
  }
  int exponent = 0;
  std::frexp(S, &exponent);
  scale = std::ldexp(1.0, -exponent);
  unscale = std::ldexp(1.0, exponent);
}

/// Edge axis a = e_I × e (box axis I, triangle edge e): the separation numerators of its two
/// sides, `pos` (the triangle beyond the box along +a) and `neg` (along −a). A vertex p projects
/// to a·p = (e × p)_I = e_u p_v − e_v p_u (u, v the two other axes; Eigen's cross product's
/// component I, operation for operation); the box's radius is h_u|e_v| + h_v|e_u|.
inline void edgeAxisSides(int I, const V& e, const V* t, const V& h, double& pos, double& neg) {
  const int u = kNextMod3[I], v = kNextMod3[I + 1];
  const double p0 = e[u] * t[0][v] - e[v] * t[0][u], p1 = e[u] * t[1][v] - e[v] * t[1][u],
               p2 = e[u] * t[2][v] - e[v] * t[2][u];
  const double lo = std::min(p0, std::min(p1, p2)), hi = std::max(p0, std::max(p1, p2));
  const double r = h[u] * std::abs(e[v]) + h[v] * std::abs(e[u]);
  pos = lo - r;
  neg = -r - hi;
}

/// num / sqrt(a2) > bound, without the square root or the division (a2 > 0).
inline bool exceeds(double num, double a2, double bound) {
  const double nn = num * num, bb = bound * bound * a2;
  return num >= 0 ? ((bound < 0) | (nn > bb)) : ((bound < 0) & (nn < bb));
}

/// The edge axes of the box axes in `groups` (bit i: the 3 axes e_i × E_j; see the call): false
/// when one separates beyond the margin, else `best` becomes the edge axis exceeding face.sep +
/// bias the most, if any.
// (Always inlined: called from both instantiations below, GCC would otherwise call it, ~1 ns.)
[[gnu::always_inline]] inline bool edgeAxes(const V* t, const V* E, const V& h, double m, double bias,
                                            unsigned groups, const Axis& face, Axis& best) {
  // The edge axes a = e_i × E_j of the groups asked for (RTCD §5.2.9 with the triple-product
  // form of Akenine-Möller's triangle–box test: edgeAxisSides), axis k = 3j + i: the separation
  // numerator (the larger side; separation = num / |a|), |a|² = E_u² + E_v², whether it is
  // usable (not parallel: |a|² > (kBoxTriangleParallelSin |E_j|)²; NaN fails) and whether it
  // separates beyond the margin (num / |a| > m). The edge's own two vertices project to the same
  // value in exact arithmetic; both are kept, so rounding treats the 3 vertices alike (a segment
  // triangle's two copies of its edge tie, and the first wins). Only the groups' own projections
  // are computed (a group is a third of the cross products E_j × t_k).
  double num[9], a2[9];
  unsigned valid = 0;  // bit k: axis k is usable
  bool separated = false;
  const double m2 = m * m;
  for (unsigned g = groups; g != 0; g &= g - 1) {
    const int i = __builtin_ctz(g), u = kNextMod3[i], v = kNextMod3[i + 1];
    for (int j = 0; j < 3; ++j) {
      const V& e = E[j];
      const double minA2 = kBoxTriangleParallelSin * kBoxTriangleParallelSin * e.squaredNorm();
      double pos, neg;
      edgeAxisSides(i, e, t, h, pos, neg);
      const double nm = std::max(pos, neg), aa = e[v] * e[v] + e[u] * e[u];
      const int k = 3 * j + i;
      num[k] = nm;
      a2[k] = aa;
      const bool ok = aa > minA2;
      valid |= unsigned(ok) << k;
      separated |= ok & (nm >= 0) & (nm * nm > m2 * aa);
    }
  }
  if (separated) return false;
  double bound = face.sep + bias;  // an edge axis must exceed this
  // the axes beating the initial bound, bit k for axis k (the bound only grows, and exceeds()
  // is monotone in it, so no other axis can beat a later one); then those in order
  unsigned candidates = 0;
  for (unsigned rest = valid; rest != 0; rest &= rest - 1) {
    const int k = __builtin_ctz(rest);
    candidates |= unsigned(exceeds(num[k], a2[k], bound)) << k;
  }
  for (; candidates != 0; candidates &= candidates - 1) {
    const int k = __builtin_ctz(candidates);
    if (!exceeds(num[k], a2[k], bound)) continue;
    const double len = std::sqrt(a2[k]);
    const double sep = num[k] / len;
    if (!(sep > bound)) continue;
    const int i = k % 3, j = k / 3;
    const int u = (i + 1) % 3, v = (i + 2) % 3;
    V a = V::Zero();  // unit(i) × E[j], exact
    a[u] = -E[j][v];
    a[v] = E[j][u];
    bound = sep;
    best.kind = AxisKind::Edge;
    best.i = i;
    best.j = j;
    best.sep = sep;
    best.n = a * (1 / len);  // its side: below, for the winner only
  }
  if (best.kind == AxisKind::Edge) {
    // the winner's side, as the loop above found its numerator (pos >= neg: +a)
    double pos = 0, neg = 0;
    edgeAxisSides(best.i, E[best.j], t, h, pos, neg);
    // −n when !(pos >= neg), as a product (x·−1 is −x exactly, signed zeros included): no branch
    best.n *= double(2 * int(pos >= neg) - 1);
  }
  return true;
}

/// The GJK/EPA pair (gjk.hpp's distance() without its entry check: detail::coreQuery, as
/// contacts() uses it): one point, the closest (or deepest) pair, with the features supporting
/// the normal (contact.hpp's rule), when the signed distance is <= m. Unlike contacts(), no
/// clipping: its edge–edge and sliver-plane clipping can put points off the shapes
/// (docs/narrowphase.md). A pair distance()'s entry rule rejects gets no contact (this routine is
/// the primitive layer's: no abort, and no GJK on non-finite input).
bool fallback(const Vec3& half, const Triangle& tri, double m, const V* t, const V& h, const V& normal,
              double normalLen, double unscale, ContactManifold& out) {
  Obb box;
  box.half = half;
  const ConvexShape a(tri), b(box);
  const Transform identity{};
  out.count = 0;
  if (!detail::queryable(detail::ShapesAtPoses{a, identity, b, identity})) return false;
  const DistanceResult d = detail::coreQuery(detail::Placed(a, identity), detail::Placed(b, identity));
  out.normal = d.normal;
  if (!(double(d.distance) <= m * unscale)) return false;
  const V n = d.normal.template cast<double>();
  ClipVertex f[4];
  std::uint32_t idA = 0, idB = 0;
  triangleFeature(t, normal, normalLen, -n, f, idA);
  boxFeature(h, n, f, idB);
  ContactPoint& c = out.points[0];
  c.pointA = d.pointA;
  c.pointB = d.pointB;
  c.separation = d.distance;
  c.featureA = idA;
  c.featureB = idB;
  out.count = 1;
  return true;
}


/// The routine; kShortcuts = false computes every axis and takes the general paths (the full
/// SAT, detail::boxTriangleContactsFullSat), which the shortcuts must match bit for bit.
template <bool kShortcuts>
bool boxTriangleContactsImpl(const Vec3& half, const Triangle& tri, Real margin, ContactManifold& out) {
  out.count = 0;
  if (!(margin >= 0)) margin = 0;
  // Exact power-of-two rescaling to a length scale in [0.5, 1).
  double S = std::max({double(half.cwiseAbs().maxCoeff()), double(tri.a.cwiseAbs().maxCoeff()),
                       double(tri.b.cwiseAbs().maxCoeff()), double(tri.c.cwiseAbs().maxCoeff())});
  // The shortcuts assume finite inputs (x − x is 0 for finite x, NaN otherwise).
  const bool fast = kShortcuts && ((half - half) + (tri.a - tri.a) + (tri.b - tri.b) + (tri.c - tri.c)).sum() == 0;
  double scale = 1, unscale = 1;
  powerOfTwoScale(S, scale, unscale);
  // Scalars first (the vectors below are built from registers, not reloaded from memory).
  const double ax = double(tri.a[0]) * scale, ay = double(tri.a[1]) * scale, az = double(tri.a[2]) * scale;
  const double bx = double(tri.b[0]) * scale, by = double(tri.b[1]) * scale, bz = double(tri.b[2]) * scale;
  const double cx = double(tri.c[0]) * scale, cy = double(tri.c[1]) * scale, cz = double(tri.c[2]) * scale;
  const double hx = std::abs(double(half[0])) * scale, hy = std::abs(double(half[1])) * scale,
               hz = std::abs(double(half[2])) * scale;
  const V h(hx, hy, hz);
  const V t[3] = {V(ax, ay, az), V(bx, by, bz), V(cx, cy, cz)};
  const double m = std::isfinite(double(margin)) ? double(margin) * scale : std::numeric_limits<double>::infinity();

  // ---- separating axes ----
  // Written out in scalars, in Eigen's evaluation order for 3-vectors (dot: (x + y) + z).
  const double e0x = bx - ax, e0y = by - ay, e0z = bz - az;  // E[0] = t[1] − t[0]
  const double e1x = cx - bx, e1y = cy - by, e1z = cz - bz;  // E[1] = t[2] − t[1]
  const double e2x = ax - cx, e2y = ay - cy, e2z = az - cz;  // E[2] = t[0] − t[2]
  const V E[3] = {V(e0x, e0y, e0z), V(e1x, e1y, e1z), V(e2x, e2y, e2z)};
  const double fx = cx - ax, fy = cy - ay, fz = cz - az;  // t[2] − t[0]
  const double nx = e0y * fz - e0z * fy, ny = e0z * fx - e0x * fz, nz = e0x * fy - e0y * fx;  // E[0] × (t[2] − t[0])
  const V normal(nx, ny, nz);
  const double L[3] = {(e0x * e0x + e0y * e0y) + e0z * e0z, (e1x * e1x + e1y * e1y) + e1z * e1z,
                       (e2x * e2x + e2y * e2y) + e2z * e2z};  // |E_j|²
  const double longest = std::max({L[0], L[1], L[2]});
  const double normalLen = std::sqrt((nx * nx + ny * ny) + nz * nz);
  const TriangleClass shape = classifyTriangle(normalLen, longest);
  const bool hasFace = !shape.degenerate && normalLen > 0;
  const bool referenceFace = hasFace && shape.referenceFace;  // (triangle_class.hpp)
  const double featureLen = referenceFace ? normalLen : 0.0;  // the fallback's feature: no thin face

  // The triangle's separation from each box face pair: beyond the +k face (posSep) and beyond
  // the −k face (negSep).
  double posSep[3], negSep[3];
  for (int k = 0; k < 3; ++k) {
    const double lo = std::min(t[0][k], std::min(t[1][k], t[2][k])), hi = std::max(t[0][k], std::max(t[1][k], t[2][k]));
    posSep[k] = lo - h[k], negSep[k] = -h[k] - hi;
  }
  Axis face;  // best box face: the first of the largest separations (NaN never wins)
  {
    // selected without branches (which face wins is unpredictable: each branch here was
    // mispredicted about once per call); the same choice as comparing in order with `>`
    double sep[3];
    bool positive[3];
    for (int k = 0; k < 3; ++k) {
      sep[k] = std::max(posSep[k], negSep[k]);
      positive[k] = posSep[k] >= negSep[k];
    }
    // (std::max(a, b) is b when a < b, else a: `b > a ? b : a`, compiled to maxsd)
    const bool w0 = sep[0] > face.sep;
    const double s0 = std::max(face.sep, sep[0]);
    const bool w1 = sep[1] > s0;
    const double s1 = std::max(s0, sep[1]);
    const bool w2 = sep[2] > s1;
    const int k = int(w2) << 1 | (int(w1) & ~int(w2));  // w2 ? 2 : w1 ? 1 : 0
    if (w0 | w1 | w2) {  // (false only when every separation is NaN)
      face.i = k;
      face.sep = std::max(s1, sep[2]);
      face.n = V::Unit(k) * (positive[k] ? 1.0 : -1.0);
    }
  }
  out.normal = face.n.cast<Real>();
  if (!(face.sep <= m)) return false;        // a separating axis: distance >= face.sep > margin
  const double bias = kBoxTriangleFaceBias;  // × scale, which is ~1 after rescaling
  if (hasFace) {
    // The separation numerator along the normal (the larger of the two sides; separation =
    // numerator / |normal|), written out in scalars.
    const double p0 = (nx * ax + ny * ay) + nz * az, p1 = (nx * bx + ny * by) + nz * bz,
                 p2 = (nx * cx + ny * cy) + nz * cz;
    const double lo = std::min(p0, std::min(p1, p2)), hi = std::max(p0, std::max(p1, p2));
    const double r = (hx * std::abs(nx) + hy * std::abs(ny)) + hz * std::abs(nz);
    const double pos = lo - r, neg = -r - hi;
    const double sign = pos >= neg ? 1.0 : -1.0;
    const double num = std::max(pos, neg);
    const double sep = num / normalLen;
    if (!(sep <= m)) return false;  // a separating axis beyond the margin (never biased away)
    if (sep >= face.sep - bias) {
      face.kind = AxisKind::TriangleFace;
      face.sep = sep;
      face.n = normal * (sign / normalLen);
    }
  }
  Axis best = face;
  // The edge axes of box axis I (a = e_I × E_j, so a_I = 0) cannot win when a triangle vertex
  // lies deeply enough inside the box's two other slabs: for a vertex v with clearance d_I =
  // min_{k≠I} (h_k − |v_k|) >= 0, both sides' separation numerators are at most
  // Σ_{k≠I}|a_k|(|v_k| − h_k) <= −d_I·Σ|a_k| <= −d_I·|a|, so those axes separate by at most
  // −d_I. A group is skipped when −d_I (d_I the best vertex's) stays below both the bound an edge
  // axis must exceed (face.sep + bias) and the margin m by kEdgeBoundSlack, which covers the edge
  // axes' rounding (their projections carry errors of a few ulps of |a|, the coordinates being
  // <= 1 here): the full test would then keep `face` too, and no edge axis of the group would
  // separate beyond m (m = 0 needs d_I >= kEdgeBoundSlack), bit for bit (test_box_triangle_contact
  // checks it against detail::boxTriangleContactsFullSat).
  unsigned groups = 7u;
  if (fast) {
    double clearance[3] = {-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                           -std::numeric_limits<double>::infinity()};
    for (int i = 0; i < 3; ++i) {
      const double q0 = h[0] - std::abs(t[i][0]), q1 = h[1] - std::abs(t[i][1]), q2 = h[2] - std::abs(t[i][2]);
      clearance[0] = std::max(clearance[0], std::min(q1, q2));
      clearance[1] = std::max(clearance[1], std::min(q0, q2));
      clearance[2] = std::max(clearance[2], std::min(q0, q1));
    }
    const double limit = std::min(face.sep + bias, m) - kEdgeBoundSlack;
    for (int i = 0; i < 3; ++i)  // (no branch: its outcome was mispredicted about once per call)
      groups &= ~(unsigned((clearance[i] >= 0) & (-clearance[i] <= limit)) << i);
  }
  if (groups != 0 && !edgeAxes(t, E, h, m, bias, groups, face, best)) return false;
  // An edge axis within the feature angle of the best face axis gives way to that face, as
  // contact.cpp turns a normal within 2° of a face into that face's normal: a face contact (2–4
  // points) rather than one edge–edge point, at most 2° off the minimum-penetration direction.
  if (best.kind == AxisKind::Edge && best.n.dot(face.n) >= kFeatureCos) best = face;
  // A thin triangle is never the reference face (classifyTriangle's referenceFace, the rule of
  // contacts() and the capsule path): when its face is the best axis, the box face within the
  // feature angle of its normal becomes the axis and the reference, the triangle clipped against
  // it (as contacts() clips a sliver against the other shape's face); with no such box face, the
  // fallback's single closest or deepest pair.
  if (best.kind == AxisKind::TriangleFace && !referenceFace) {
    int k = 0;
    best.n.cwiseAbs().maxCoeff(&k);
    if (!(std::abs(best.n[k]) >= kFeatureCos)) return fallback(half, tri, m, t, h, normal, featureLen, unscale, out);
    const double s = best.n[k] > 0 ? 1.0 : -1.0;
    best.kind = AxisKind::BoxFace;
    best.i = k;
    best.n = V::Unit(k) * s;
    best.sep = s > 0 ? posSep[k] : negSep[k];
  }
  out.normal = best.n.cast<Real>();

  // ---- points ----
  const V& n = best.n;
  Point pts[kMaxClip];
  int np = 0;
  double minSep = std::numeric_limits<double>::infinity();  // scaled units
  ClipVertex bufA[kMaxClip], bufB[kMaxClip];
  ClipVertex* cur = bufA;
  ClipVertex* nxt = bufB;
  std::uint32_t incId = 0;
  V u = n;  // outward normal of the reference face

  if (best.kind == AxisKind::BoxFace) {
    const int k = best.i;
    const double s = n[k];  // ±1
    int cnt;
    if (fast) {
      int is = 0, other = 0;
      bool front = false;
      const int kind = triangleFeatureAlongAxis(t, L, normal, hasFace ? normalLen : 0.0, k, -s, is, other, front);
      if (kind == 1) {
        // A single corner (the usual case), in scalars: the four side planes' tests as clip()
        // makes them, the point and the output as below.
        const V& p = t[is];
        const double sep = s * p[k] - h[k];
        const int a1 = kNextMod3[k], a2 = kNextMod3[k + 1];
        const bool inside =
            !(int(p[a1] + h[a1] < 0) | int(h[a1] - p[a1] < 0) | int(p[a2] + h[a2] < 0) | int(h[a2] - p[a2] < 0));
        if (!inside || !(sep <= m) || (best.sep > 0 && sep > best.sep + kRealiseTolerance))
          return fallback(half, tri, m, t, h, normal, featureLen, unscale, out);
        out.normal = n.cast<Real>();
        out.count = 1;
        ContactPoint& c = out.points[0];
        c.pointA = Vec3(static_cast<Real>(p[0] * unscale), static_cast<Real>(p[1] * unscale),
                        static_cast<Real>(p[2] * unscale));
        // pointB: pointA moved onto the face's plane, (s·h_k)·unscale (set in place: a run-time
        // indexed local array read back right after its stores stalls store forwarding)
        c.pointB = c.pointA;
        c.pointB[k] = static_cast<Real>((s * h[k]) * unscale);
        c.separation = static_cast<Real>(sep * unscale);
        c.featureA = vertexId(is);
        c.featureB = featureId(FeatureKind::Face, static_cast<std::uint32_t>(2 * k + (s > 0 ? 1 : 0)));
        return true;
      }
      if (kind == 3) {
        for (int i = 0; i < 3; ++i) cur[i] = {t[i], 0, vertexId(i)};
        incId = featureId(FeatureKind::Face, front ? 0u : 1u);
        cnt = 3;
      } else {
        cur[0] = {t[is], 0, vertexId(is)};
        cur[1] = {t[other], 0, vertexId(other)};
        incId = edgeId(is, other);
        cnt = 2;
      }
    } else {
      cnt = triangleFeature(t, normal, hasFace ? normalLen : 0.0, -n, cur, incId);
    }
    for (int q = 0; q < cnt; ++q) cur[q].sep = s * cur[q].p[k] - h[k];
    const bool vertex = cnt == 1;
    if (vertex) {  // a vertex (the usual case): the four side planes' tests, as clip() makes them
      const int a1 = (k + 1) % 3, a2 = (k + 2) % 3;
      const V& p = cur[0].p;
      if (p[a1] + h[a1] < 0 || h[a1] - p[a1] < 0 || p[a2] + h[a2] < 0 || h[a2] - p[a2] < 0) cnt = 0;
    }
    for (int side = 1; side <= 2 && cnt > 0 && !vertex; ++side) {  // an edge or the face
      const int a = (k + side) % 3;
      const double ha = h[a];
      cnt = clip(
          cur, cnt, [&](const V& p) { return p[a] + ha; }, a, -ha, incId, nxt);
      std::swap(cur, nxt);
      if (cnt == 0) break;
      cnt = clip(
          cur, cnt, [&](const V& p) { return ha - p[a]; }, a, ha, incId, nxt);
      std::swap(cur, nxt);
    }
    const std::uint32_t refId = featureId(FeatureKind::Face, static_cast<std::uint32_t>(2 * k + (s > 0 ? 1 : 0)));
    for (int q = 0; q < cnt; ++q) {
      if (!(cur[q].sep <= m)) continue;
      minSep = std::min(minSep, cur[q].sep);
      Point& c = pts[np++];
      c.a = cur[q].p;
      c.b = cur[q].p;
      c.b[k] = s * h[k];
      c.sep = cur[q].sep;
      c.fa = cur[q].id;
      c.fb = refId;
    }
  } else if (best.kind == AxisKind::TriangleFace) {
    u = -n;  // the triangle's face toward the box
    const double sigma = normal.dot(u) > 0 ? 1.0 : -1.0;
    const double inv = sigma / normalLen;
    int cnt = boxFeature(h, n, cur, incId);
    for (int q = 0; q < cnt; ++q) cur[q].sep = normal.dot(cur[q].p - t[0]) * inv;
    const int order[3] = {0, sigma > 0 ? 1 : 2, sigma > 0 ? 2 : 1};  // counter-clockwise about u
    const V un = normal * sigma;                                     // u, unnormalised
    for (int e = 0; e < 3 && cnt > 0; ++e) {
      const V& o = t[order[e]];
      const V w = un.cross(t[order[(e + 1) % 3]] - o);  // inward side normal
      cnt = clip(
          cur, cnt, [&](const V& p) { return w.dot(p - o); }, -1, 0.0, incId, nxt);
      std::swap(cur, nxt);
    }
    const std::uint32_t refId = featureId(FeatureKind::Face, sigma > 0 ? 0u : 1u);
    for (int q = 0; q < cnt; ++q) {
      if (!(cur[q].sep <= m)) continue;
      minSep = std::min(minSep, cur[q].sep);
      Point& c = pts[np++];
      c.a = cur[q].p - cur[q].sep * u;
      c.b = cur[q].p;
      c.sep = cur[q].sep;
      c.fa = refId;
      c.fb = cur[q].id;
    }
  } else {
    // Edge–edge: the box edge along axis i supporting +n, the triangle edge j.
    const int i = best.i, j = best.j;
    int idx = 0;
    for (int k = 0; k < 3; ++k)
      if (k != i && n[k] >= 0) idx |= 1 << k;
    const int idx2 = idx | (1 << i);
    const V b0 = boxVertex(h, idx), b1 = boxVertex(h, idx2);
    const int j2 = (j + 1) % 3;
    V pa, pb;
    detail::closestSegmentSegment(t[j], t[j2], b0, b1, pa, pb);  // gjk_internal.hpp (RTCD 5.1.9)
    const V d = pa - pb;
    const double along = d.dot(n);
    if ((d - along * n).norm() <= kRealiseTolerance && std::abs(along - best.sep) <= kRealiseTolerance) {
      minSep = best.sep;
      Point& c = pts[np++];
      c.a = pa;
      c.b = pa - best.sep * n;
      c.sep = best.sep;
      const bool endA = (pa - t[j]).squaredNorm() == 0 || (pa - t[j2]).squaredNorm() == 0;
      c.fa = endA ? vertexId((pa - t[j]).squaredNorm() == 0 ? j : j2) : edgeId(j, j2);
      c.fb = edgeId(idx, idx2);
    }
  }
  if (np == 0) return fallback(half, tri, m, t, h, normal, featureLen, unscale, out);
  if (best.sep > 0) {  // separated: the SAT bound is the distance only if a point realises it
    if (minSep > best.sep + kRealiseTolerance)
      return fallback(half, tri, m, t, h, normal, featureLen, unscale, out);
  }
  // No coincidence tolerance here (the clipper merges nothing): 0 keeps every point that adds area.
  contact_detail::reduceToFour(pts, np, u, 0.0, [](const Point& p) { return p.b; }, [](const Point& p) { return p.sep; });
  out.normal = n.cast<Real>();
  out.count = np;
  for (int q = 0; q < np; ++q) {
    ContactPoint& c = out.points[q];
    c.pointA = (pts[q].a * unscale).cast<Real>();
    c.pointB = (pts[q].b * unscale).cast<Real>();
    c.separation = static_cast<Real>(pts[q].sep * unscale);
    c.featureA = pts[q].fa;
    c.featureB = pts[q].fb;
  }
  return true;
}

}  // namespace

bool unchecked::boxTriangleContacts(const Vec3& half, const Triangle& tri, Real margin, ContactManifold& out) {
  return boxTriangleContactsImpl<true>(half, tri, margin, out);
}

namespace detail {
bool boxTriangleContactsFullSat(const Vec3& half, const Triangle& tri, Real margin, ContactManifold& out) {
  detail::debugPreconditions("boxTriangleContactsFullSat(half extents, Triangle)", Aabb{-half, half}, tri);
  return boxTriangleContactsImpl<false>(half, tri, margin, out);
}
}  // namespace detail

}  // namespace crux
