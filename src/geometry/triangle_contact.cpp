// Closed-form sphere–triangle and capsule–triangle contact manifolds (the mesh narrow phase's
// per-triangle fast path), with contact.hpp's feature selection and clipping rules. Double
// precision, fixed-size data, no exceptions.

#include "geometry/unchecked.hpp"

#include <crux/geometry/triangle_contact.hpp>
#include <crux/geometry/overlap.hpp>
#include <crux/geometry/raycast.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

#include "geometry/closest_point_internal.hpp"
#include "geometry/contact/clip.hpp"
#include "geometry/contact/margin.hpp"
#include "geometry/contact/supporting_feature.hpp"
#include "geometry/gjk_internal.hpp"

namespace crux {
namespace {


using detail::V3;


/// The triangle in double with its (unnormalised) normal and degeneracy.
struct TriD {
  V3 p[3];
  V3 m;         // (b - a) × (c - a)
  double len = 0;   // |m|
  bool degenerate = true;
  /// Not degenerate, but thinner than kTriangleThinRelative (triangle_class.hpp): its plane from m is
  /// unreliable (the region tests and plane distances cancel; see closestOnSliver).
  bool sliver = false;
  TriD() = default;
  explicit TriD(const Triangle& t) {
    p[0] = t.a.cast<double>();
    p[1] = t.b.cast<double>();
    p[2] = t.c.cast<double>();
    const V3 ab = p[1] - p[0], ac = p[2] - p[0];
    m = ab.cross(ac);
    finish(ab, ac);
  }
  /// len and degenerate from p and m = ab × ac.
  void finish(const V3& ab, const V3& ac) {
    len = m.norm();
    classify(std::max({ab.squaredNorm(), ac.squaredNorm(), (p[2] - p[1]).squaredNorm()}));
  }
  /// degenerate and sliver from len and the longest edge's squared length (classifyTriangle).
  void classify(double longest2) {
    const TriangleClass c = classifyTriangle(len, longest2);
    degenerate = c.degenerate;
    sliver = c.thin;
  }
  double maxAbs() const { return std::max({p[0].norm(), p[1].norm(), p[2].norm()}); }
  V3 centroid() const { return (p[0] + p[1] + p[2]) / 3; }
};

/// A supporting feature of the triangle or the capsule (at most 3 vertices), as contact.cpp's.
struct Feature {
  V3 v[3];
  std::uint32_t vid[3];
  int n = 0;
  V3 normal = V3::Zero();
  double align = 0;
  std::uint32_t id = 0;
};

std::uint32_t vertexId(int i) { return featureId(FeatureKind::Vertex, static_cast<std::uint32_t>(i)); }

/// Vertex `is` of `p`, or the edge (is, others[k]) perpendicular to d within the feature angle
/// (contact_detail::vertexOrEdge).
void vertexOrEdge(const V3* p, const V3& d, int is, const int* others, int nOthers, Feature& f) {
  contact_detail::vertexOrEdge([p](int i) { return p[i]; }, d, is, others, nOthers, 0, f);
}


/// The triangle's feature supporting direction d (contact.cpp's rule for a Triangle core against
/// a shape without faces: a sliver's face is replaced by its supporting edge or vertex).
void triangleFeature(const TriD& t, const V3& d, Feature& f) {
  const double d0 = t.p[0].dot(d), d1 = t.p[1].dot(d), d2 = t.p[2].dot(d);
  const int is = d1 > d0 ? (d2 > d1 ? 2 : 1) : (d2 > d0 ? 2 : 0);
  const double longest2 = std::max({(t.p[1] - t.p[0]).squaredNorm(), (t.p[2] - t.p[1]).squaredNorm(),
                                    (t.p[0] - t.p[2]).squaredNorm()});
  const bool sliver = !classifyTriangle(t.len, longest2).referenceFace;  // contact.cpp's rule
  // (a degenerate triangle has no face: its computed normal is rounding noise)
  if (!t.degenerate && !sliver && contact_detail::faceSupports(t.m.dot(d), t.len)) {
    const V3 m = t.m / t.len;
    const bool front = m.dot(d) > 0;
    const int order[3] = {0, front ? 1 : 2, front ? 2 : 1};
    f.n = 3;
    for (int k = 0; k < 3; ++k) {
      f.v[k] = t.p[order[k]];
      f.vid[k] = vertexId(order[k]);
    }
    f.normal = front ? m : V3(-m);
    f.align = std::abs(m.dot(d));
    f.id = featureId(FeatureKind::Face, front ? 0 : 1);
    return;
  }
  const int others[2] = {(is + 1) % 3, (is + 2) % 3};
  vertexOrEdge(t.p, d, is, others, 2, f);
}

/// Closest point of segment [a, b] to p.
V3 closestOnSegment(const V3& a, const V3& b, const V3& p) {
  const V3 ab = b - a;
  const double l2 = ab.squaredNorm();
  if (!(l2 > 0)) return a;
  return a + ab * std::clamp(ab.dot(p - a) / l2, 0.0, 1.0);
}

/// A fixed unit perpendicular of e (e non-zero).
V3 perpendicularOf(const V3& e) {
  const V3 a = std::abs(e.x()) < 0.57 * e.norm() ? V3::UnitX() : V3::UnitY();
  return e.cross(a).normalized();
}

/// The longest edge of a degenerate triangle (a point: zero).
V3 longestEdge(const TriD& t) {
  V3 best = t.p[1] - t.p[0];
  for (int i = 1; i < 3; ++i) {
    const V3 e = t.p[(i + 1) % 3] - t.p[i];
    if (e.squaredNorm() > best.squaredNorm()) best = e;
  }
  return best;
}

/// The normal (B→A) of a shape whose core touches/lies on the triangle: minus the front face
/// normal; for a degenerate triangle a fixed perpendicular of its longest edge, or −z.
V3 onTriangleNormal(const TriD& t) {
  if (!t.degenerate) return -t.m / t.len;
  const V3 e = longestEdge(t);
  if (e.squaredNorm() > 0) return -perpendicularOf(e);
  return -V3::UnitZ();
}

/// Fills the single-point manifold (the closest / deepest pair) with contact.cpp's features.
void singlePoint(const TriD& t, const V3& n, const V3& pa, const V3& pbCore, double dcore, double r, Real margin,
                 std::uint32_t featureB, ContactManifold& out) {
  Feature fa;
  triangleFeature(t, -n, fa);
  out.normal = n.cast<Real>();
  out.count = 1;
  ContactPoint& c = out.points[0];
  c.pointA = pa.cast<Real>();
  c.pointB = (pbCore + n * r).cast<Real>();
  c.separation = static_cast<Real>(dcore - r);
  c.featureA = fa.id;
  c.featureB = featureB;
  (void)margin;
}

}  // namespace

namespace {

/// The closest-point core shared by sphereTriangleContacts and sphereTriangleContact: false when
/// the triangle is beyond radius + margin; else the triangle in double, the closest point q,
/// the unit normal n (B→A), the centre's distance d (0 in the flat case) and the region of q
/// (SphereTriangleContact::region).
bool sphereCore(const Triangle& tri, const V3& p, double r, double m, TriD& t, V3& q, V3& n, double& d, int& region) {
  // (the triangle in double and its cross product are computed once, for the test and for t)
  // (from locals, not read back from t: a 16-byte load spanning two of the stores just made
  // to t.p misses store forwarding and showed as sphereCore's hottest instruction)
  const V3 a = tri.a.cast<double>(), b = tri.b.cast<double>(), c = tri.c.cast<double>();
  t.p[0] = a;
  t.p[1] = b;
  t.p[2] = c;
  const V3 ab = b - a, ac = c - a;
  const V3 mm = ab.cross(ac);
  t.m = mm;
  const double bound = std::max({tri.a.cwiseAbs().maxCoeff(), tri.b.cwiseAbs().maxCoeff(), tri.c.cwiseAbs().maxCoeff()});
  const double pMax = p.cwiseAbs().maxCoeff();
  {
    // Early plane reject, before anything else (most candidate triangles of a mesh end here):
    // |(b−a)×(c−a)·(p−a)| > (r + margin + slack)·|(b−a)×(c−a)|, squared, no root. The slack
    // bounds the tolerance below from above (∞-norms × √3 >= Euclidean norms).
    // The rounding of the cross product (<= 8 ulps × |ab|₁|ac|₁ per unit of |p − a|₁) is
    // added, so that nearly collinear triangles, whose computed normal is noise, are never
    // rejected wrongly.
    const V3 ap = p - a;
    const double h = mm.dot(ap);
    const double slack = kGjkScaleTolerance * (1.7320508075688773 * (bound + pMax) + r);
    const double reach = r + m + slack;
    const double err = 8 * std::numeric_limits<double>::epsilon() * ab.lpNorm<1>() * ac.lpNorm<1>() * ap.lpNorm<1>();
    const double lhs = std::abs(h) - err;
    if (lhs > 0 && lhs * lhs > reach * reach * mm.squaredNorm()) return false;
  }
  // t.finish(ab, ac) from the locals
  t.len = mm.norm();
  t.classify(std::max({ab.squaredNorm(), ac.squaredNorm(), (c - b).squaredNorm()}));
  region = SphereTriangleContact::kDegenerate;
  if (!t.degenerate) {
    // a sliver takes no region tests (they cancel: closest_detail::closestOnSliver), and its
    // face point comes from there (the better-conditioned normal), not from the plane of mm
    region = t.sliver ? closest_detail::closestOnSliver(a, b, c, p, q) : closest_detail::closestRegionOnTriangle(a, b, c, p, q);
    if (region == SphereTriangleContact::kFace && !t.sliver) {  // exact projection: distance and normal from the plane, not from q - p
      const V3 mh = mm / t.len;
      const double h = mh.dot(p - a);
      d = std::abs(h);
      q = p - h * mh;
      n = h > 0 ? V3(-mh) : V3(mh);
    } else {
      const V3 qp = q - p;
      const double d2 = qp.squaredNorm();
      // clearly beyond radius + margin + the margin decision's band below (the rounding of q and
      // d, on the scale of the coordinates, not of the radius: a small sphere far from the origin
      // touching an edge computes d off by ~|p|·ulp): out before the root and the division
      const double reach = r + m + kGjkScaleTolerance * (bound + pMax + r + m);
      if (d2 > reach * reach) return false;
      d = std::sqrt(d2);
      n = d > 0 ? V3(qp * (1 / d)) : V3::Zero();
    }
  } else {
    q = closestOnSegment(t.p[0], t.p[1], p);
    for (int i = 1; i < 3; ++i) {
      const V3 e = closestOnSegment(t.p[i], t.p[(i + 1) % 3], p);
      if ((e - p).squaredNorm() < (q - p).squaredNorm()) q = e;
    }
    d = (q - p).norm();
    n = d > 0 ? V3((q - p) / d) : V3::Zero();
  }
  {
    // The margin decision: d - r <= m, exactly (withinDistance) when d is within its rounding
    // (kGjkScaleTolerance of the scale) of the bound, so that touching is reported exactly on
    // integer grids (a float d may round either way: found by crux diff for the capsule).
    // A distance found within the margin but computed beyond it is clamped to r + m.
    const double band = kGjkScaleTolerance * (bound + pMax + r + m);  // (bound: the corners' largest |coordinate|)
    bool clamp = false;
    if (!contact_detail::withinMargin(
            d - r, m, band,
            [&] { return unchecked::withinDistance(tri, Vec3(p.cast<Real>()), static_cast<Real>(r), static_cast<Real>(m)); }, clamp))
      return false;
    if (clamp) d = r + m;
  }
  // The flat case: the centre on the triangle within kGjkScaleTolerance × the pair's scale
  // (max |vertex| + |centre| + radius; its square roots are taken only when d is below a bound
  // of that tolerance from ∞-norms: 2·|x|∞ > √3·|x|∞ >= |x|).
  const double upper = 2 * (bound + pMax) + r;
  if (d <= kGjkScaleTolerance * upper && d <= kGjkScaleTolerance * (t.maxAbs() + p.norm() + r)) {
    d = 0;  // centre on the triangle: a deterministic normal
    n = onTriangleNormal(t);
    q = p;
    if (!t.degenerate) region = SphereTriangleContact::kFace;
  }
  // n is unit (to rounding) on every path: ±the unit face normal, (q − p)/|q − p|, or
  // onTriangleNormal's; the degenerate path's (q − p)/d below a point or segment
  return true;
}

}  // namespace

bool unchecked::sphereTriangleContacts(const Triangle& tri, const Vec3& centre, Real radius, Real margin, ContactManifold& out) {
  out.count = 0;
  const V3 p = centre.cast<double>();
  const double r = double(radius);
  TriD t;
  V3 q, n;
  double d = 0;
  int region = 0;
  if (!sphereCore(tri, p, r, double(margin), t, q, n, d, region)) return false;
  singlePoint(t, n, q, p, d, r, margin, vertexId(0), out);
  return true;
}

bool unchecked::sphereTriangleContact(const Triangle& tri, const Vec3& centre, Real radius, Real margin,
                           SphereTriangleContact& out) {
  const V3 p = centre.cast<double>();
  const double r = double(radius);
  TriD t;
  V3 q, n;
  double d = 0;
  if (!sphereCore(tri, p, r, double(margin), t, q, n, d, out.region)) return false;
  if (!t.degenerate) out.face = (t.m * (1 / t.len)).cast<Real>();
  // as singlePoint, without the feature ids
  out.normal = n.cast<Real>();
  out.pointA = q.cast<Real>();
  out.pointB = (p + n * r).cast<Real>();
  out.separation = static_cast<Real>(d - r);
  return true;
}

bool unchecked::capsuleTriangleContacts(const Triangle& tri, const Vec3& p0In, const Vec3& p1In, Real radius, Real margin,
                             ContactManifold& out) {
  out.count = 0;
  const V3 s[2] = {p0In.cast<double>(), p1In.cast<double>()};
  const double r = double(radius), mg = double(margin);
  {
    // Early plane reject (as sphereTriangleContacts): both ends beyond radius + margin on the
    // same side of the triangle's plane, squared, no root.
    const V3 a = tri.a.cast<double>();
    const V3 ab = tri.b.cast<double>() - a, ac = tri.c.cast<double>() - a;
    const V3 mm = ab.cross(ac);
    const double g0 = mm.dot(s[0] - a), g1 = mm.dot(s[1] - a);
    const double bound = std::max({tri.a.cwiseAbs().maxCoeff(), tri.b.cwiseAbs().maxCoeff(), tri.c.cwiseAbs().maxCoeff()});
    const double slack = kGjkScaleTolerance *
                         (1.7320508075688773 * (bound + std::max(p0In.cwiseAbs().maxCoeff(), p1In.cwiseAbs().maxCoeff())) + r);
    const double reach = r + mg + slack;
    // (the cross product's rounding, as in sphereTriangleContacts)
    const double e8 = 8 * std::numeric_limits<double>::epsilon() * ab.lpNorm<1>() * ac.lpNorm<1>();
    const double l0 = std::abs(g0) - e8 * (s[0] - a).lpNorm<1>(), l1 = std::abs(g1) - e8 * (s[1] - a).lpNorm<1>();
    const double lmin = std::min(l0, l1);
    if (g0 * g1 > 0 && lmin > 0 && lmin * lmin > reach * reach * mm.squaredNorm()) return false;
    // Bounding-sphere reject: the segment farther from the centroid than the triangle's
    // circumscribing radius (about the centroid) plus the reach.
    const V3 b = tri.b.cast<double>(), c = tri.c.cast<double>();
    const V3 g = (a + b + c) / 3;
    const double rad = std::sqrt(std::max({(a - g).squaredNorm(), (b - g).squaredNorm(), (c - g).squaredNorm()}));
    const double lim = rad + reach;
    if ((closestOnSegment(s[0], s[1], g) - g).squaredNorm() > lim * lim) return false;
  }
  const TriD t(tri);
  const double scale = t.maxAbs() + std::max(s[0].norm(), s[1].norm()) + r;
  const double tolAbs = kGjkScaleTolerance * scale;
  V3 mh = V3::Zero();
  double h0 = 0, h1 = 0;
  if (!t.degenerate) {
    mh = t.m / t.len;
    h0 = mh.dot(s[0] - t.p[0]);
    h1 = mh.dot(s[1] - t.p[0]);
    // Both ends beyond the plane on one side by more than radius + margin: nothing to report (not
    // for a sliver, whose plane is unreliable: a scratch search found capsules rejected there).
    if (!t.sliver && ((h0 > 0 && h1 > 0 && std::min(h0, h1) - r > mg + tolAbs) ||
                      (h0 < 0 && h1 < 0 && std::min(-h0, -h1) - r > mg + tolAbs)))
      return false;
  }
  // ---- core distance: segment vs triangle (RTCD 5.1.10's decomposition).
  V3 pa, pb;
  double best2 = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    V3 ca, cb;
    const double d2 = detail::closestSegmentSegment(t.p[i], t.p[(i + 1) % 3], s[0], s[1], ca, cb);
    if (d2 < best2) {
      best2 = d2;
      pa = ca;
      pb = cb;
    }
  }
  bool crossing = false;
  if (t.sliver) {
    // the ends' closest points on the sliver without its plane (closestOnSliver), and whether the
    // segment crosses it by the exact segment-triangle test
    for (int k = 0; k < 2; ++k) {
      V3 q;
      closest_detail::closestOnSliver(t.p[0], t.p[1], t.p[2], s[k], q);
      const double d2 = (q - s[k]).squaredNorm();
      if (d2 < best2) {
        best2 = d2;
        pa = q;
        pb = s[k];
      }
    }
    crossing = unchecked::intersects(Segment{p0In, p1In}, tri);
  } else if (!t.degenerate) {
    // x on the plane: inside the closed triangle
    auto inside = [&](const V3& x) { return closest_detail::projectsInside(t.p, t.m, x); };
    const double h[2] = {h0, h1};
    for (int k = 0; k < 2; ++k) {
      const V3 proj = s[k] - h[k] * mh;
      if (std::abs(h[k]) * std::abs(h[k]) < best2 && inside(proj)) {
        best2 = h[k] * h[k];
        pa = proj;
        pb = s[k];
      }
    }
    if ((h0 < 0 && h1 > 0) || (h0 > 0 && h1 < 0)) {
      const V3 x = s[0] + (s[1] - s[0]) * (h0 / (h0 - h1));
      crossing = inside(x);
    }
  }
  double dcore = crossing ? 0.0 : std::sqrt(best2);
  // The margin decision: dcore - r <= mg, exactly (withinDistance) when dcore is within its
  // rounding (tolAbs) of the bound: touching is reported exactly on integer grids (crux diff found
  // a capsule touching a segment triangle at distance 1 computed as 1 + 2e-16, and dropped). A
  // core distance found within the margin but computed beyond it is clamped to r + mg.
  auto inMargin = [&](double& core) {
    bool clamp = false;
    if (!contact_detail::withinMargin(
            core - r, mg, tolAbs, [&] { return unchecked::withinDistance(tri, p0In, p1In, radius, margin); }, clamp))
      return false;
    if (clamp) core = r + mg;
    return true;
  };
  V3 n;
  if (dcore > tolAbs) {
    if (!inMargin(dcore)) return false;
    n = (pa - pb) / dcore;
  } else {
    // ---- crossing cores: minimum translation over the faces of the Minkowski difference (SAT).
    const V3 dseg = s[1] - s[0];
    double hBest = std::numeric_limits<double>::infinity();
    V3 uBest = V3::Zero();
    int axisBest = -1;  // 3: face normal, 0..2: edge i × segment
    auto consider = [&](const V3& u, int axis) {
      const double maxA = std::max({u.dot(t.p[0]), u.dot(t.p[1]), u.dot(t.p[2])});
      const double minB = std::min(u.dot(s[0]), u.dot(s[1]));
      const double hu = maxA - minB;
      // The cores meet (distance <= tolAbs), so no axis separates them: an axis that seems to is
      // the rounding noise of a nearly collinear triangle's normal and is skipped.
      if (hu < -tolAbs) return;
      if (hu < hBest) {
        hBest = hu;
        uBest = u;
        axisBest = axis;
      }
    };
    if (!t.degenerate) {
      consider(mh, 3);
      consider(-mh, 3);
    }
    const double dl2 = dseg.squaredNorm();
    for (int i = 0; i < 3; ++i) {
      const V3 e = t.p[(i + 1) % 3] - t.p[i];
      const V3 c = e.cross(dseg);
      const double c2 = c.squaredNorm();
      if (!(c2 > 1e-24 * e.squaredNorm() * dl2)) continue;  // parallel: not a face of the prism
      const V3 u = c / std::sqrt(c2);
      consider(u, i);
      consider(-u, i);
    }
    // Flat: the Minkowski difference has no thickness along the best axis (the segment lies in
    // the triangle's plane, or a degenerate triangle and the segment are coplanar): core depth
    // 0 along that plane's normal, deterministically oriented (for the face: minus the front
    // normal, the capsule on the front side); the common point found above.
    bool flat = axisBest < 0;
    if (!flat) {
      const double maxA = std::max({-uBest.dot(t.p[0]), -uBest.dot(t.p[1]), -uBest.dot(t.p[2])});
      const double minB = std::min(-uBest.dot(s[0]), -uBest.dot(s[1]));
      flat = hBest + (maxA - minB) <= 2 * tolAbs;
    }
    if (flat) {
      if (axisBest < 0) {
        // no face of the Minkowski difference at all (a degenerate triangle along the segment,
        // or a point on it): a fixed perpendicular of the segment (of the triangle's longest
        // edge for a point capsule), so that the shape is pushed sideways off it
        n = dseg.squaredNorm() > 0 ? V3(-perpendicularOf(dseg)) : onTriangleNormal(t);
      } else if (axisBest == 3) {
        n = onTriangleNormal(t);
      } else {
        const V3 c = (t.p[(axisBest + 1) % 3] - t.p[axisBest]).cross(dseg);
        n = -c.normalized();
      }
      dcore = 0;
      if (crossing) pa = pb = s[0] + (s[1] - s[0]) * (h0 / (h0 - h1));
    } else {
      n = -uBest;
      dcore = -hBest;
      if (axisBest == 3) {
        const int k = uBest.dot(s[1]) < uBest.dot(s[0]) ? 1 : 0;  // the deepest end
        pb = s[k];
        pa = pb + hBest * uBest;
      } else {
        detail::closestSegmentSegment(t.p[axisBest], t.p[(axisBest + 1) % 3], s[0], s[1], pa, pb);
      }
    }
    if (!inMargin(dcore)) return false;
  }
  n.normalize();  // unit to the last ulp, as the generic routine's
  // ---- features and clipping (contact.cpp's rules for a triangle and a segment).
  Feature fa, fb;
  triangleFeature(t, -n, fa);
  {
    const int is = s[1].dot(n) > s[0].dot(n) ? 1 : 0;
    const int other[1] = {1 - is};
    vertexOrEdge(s, n, is, other, 1, fb);
  }
  bool clipFeatures = fa.n >= 2 && fb.n >= 2;
  if (clipFeatures && fa.n == 2) {
    const V3 ea = fa.v[1] - fa.v[0], eb = fb.v[1] - fb.v[0];
    clipFeatures = contact_detail::edgesParallel(ea, eb);
  }
  if (clipFeatures) {
    const bool refIsA = fa.n >= 3;
    const Feature& ref = refIsA ? fa : fb;
    const Feature& inc = refIsA ? fb : fa;
    V3 u = refIsA ? V3(-n) : n;
    V3 nn = n;
    if (refIsA) {
      u = ref.normal.normalized();
      nn = -u;
    }
    // The rounding budget, as contact.cpp's (for the segment reference, widened for the radius
    // by clipToReference).
    double scale = r + mg;
    for (int i = 0; i < ref.n; ++i) scale = std::max(scale, ref.v[i].cwiseAbs().maxCoeff());
    const double tol = contact_detail::coincidenceTolerance(inc.v, inc.n, scale);
    // (a segment clipped stays at most 2 points)
    const int np = contact_detail::clipToReference<4>(ref, inc, refIsA, u, nn, 0.0, r, mg, tol, out.points);
    // (the clip lost the closest pair: that pair alone, below, as contacts())
    if (np > 0 && contact_detail::keepsClosest(out.points, np, dcore - r, tol)) {
      out.normal = nn.cast<Real>();
      out.count = np;
      return true;
    }
  }
  singlePoint(t, n, pa, pb, dcore, r, margin, fb.id, out);
  return true;
}

}  // namespace crux
