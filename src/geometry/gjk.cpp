// GJK with the signed-volume distance subalgorithm (Montanari, Petrinic, Barbieri, ACM TOG 2017),
// closed-form point/segment core pairs (RTCD 5.1.9), and the public distance()/overlaps().

#include <crux/geometry/axis_aligned.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include <crux/precondition.hpp>

#include "geometry/closest_point_internal.hpp"
#include "geometry/gjk_internal.hpp"

namespace crux {
namespace detail {

// ---- Placed ------------------------------------------------------------------------------------

namespace {

/// The pose's rotation matrix in double. One of the 24 axis-aligned rotations (axis_aligned.hpp:
/// the rule the model and mesh layers and the exact backend use) is applied as its exact signed
/// permutation: a quarter turn's √½ quaternion components would otherwise round integer-grid
/// coordinates by a few ulps (a pair touching at separation == margin came out beyond it).
M3 poseRotation(const Quat& q) {
  if (q.w() == 1 && q.vec().isZero(0)) return M3::Identity();
  if (const std::optional<Quat> s = snapAxisAligned(q)) return signedPermutation(*s).cast<double>();
  return q.cast<double>().toRotationMatrix();
}

}  // namespace

// Both constructors initialise R and t in place and share placeCore (delegating one to the other
// copied the rotation matrix once more per query).
Placed::Placed(const ConvexShape& s, const Transform& pose)
    : shape(&s), R(poseRotation(pose.rotation)), t(pose.translation.cast<double>()), radius(double(s.radius)) {
  placeCore(s);
}

Placed::Placed(const ConvexShape& s, const M3& rotation, const V3& translation)
    : shape(&s), R(rotation), t(translation), radius(double(s.radius)) {
  placeCore(s);
}

void Placed::placeCore(const ConvexShape& s) {
  switch (s.kind) {
    case ConvexKind::Sphere: p[0] = R * s.p[0].cast<double>() + t; break;
    case ConvexKind::Capsule:
      for (int i = 0; i < 2; ++i) p[i] = R * s.p[i].cast<double>() + t;
      break;
    case ConvexKind::Triangle:
      for (int i = 0; i < 3; ++i) p[i] = R * s.p[i].cast<double>() + t;
      break;
    case ConvexKind::Box:
      p[0] = R * s.p[0].cast<double>() + t;
      axes = R * s.axes.cast<double>();
      half = s.p[1].cast<double>();
      break;
    case ConvexKind::Hull: break;
  }
  size = double(s.size());
}

V3 Placed::vertex(int i) const {
  switch (shape->kind) {
    case ConvexKind::Sphere:
    case ConvexKind::Capsule:
    case ConvexKind::Triangle: return p[i];
    case ConvexKind::Box: {
      const V3 sgn((i & 1) ? half.x() : -half.x(), (i & 2) ? half.y() : -half.y(), (i & 4) ? half.z() : -half.z());
      return p[0] + axes * sgn;
    }
    case ConvexKind::Hull: return R * shape->hull->vertices()[static_cast<std::size_t>(i)].cast<double>() + t;
  }
  return p[0];
}

V3 Placed::support(const V3& d, int* index) const {
  int best = 0;
  switch (shape->kind) {
    case ConvexKind::Sphere: break;
    case ConvexKind::Capsule: best = p[1].dot(d) > p[0].dot(d) ? 1 : 0; break;
    case ConvexKind::Triangle: {
      const double d0 = p[0].dot(d), d1 = p[1].dot(d), d2 = p[2].dot(d);
      best = d1 > d0 ? (d2 > d1 ? 2 : 1) : (d2 > d0 ? 2 : 0);
      break;
    }
    case ConvexKind::Box: {
      const V3 l = axes.transpose() * d;
      best = (l.x() > 0 ? 1 : 0) | (l.y() > 0 ? 2 : 0) | (l.z() > 0 ? 4 : 0);
      break;
    }
    case ConvexKind::Hull: {
      const V3 l = R.transpose() * d;
      const auto& vs = shape->hull->vertices();
      double bestDot = -std::numeric_limits<double>::infinity();
      for (std::size_t i = 0; i < vs.size(); ++i) {
        const double x = vs[i].cast<double>().dot(l);
        if (x > bestDot) {
          bestDot = x;
          best = static_cast<int>(i);
        }
      }
      break;
    }
  }
  *index = best;
  return vertex(best);
}

void Placed::growCoreBox(V3& lo, V3& hi) const {
  for (int i = 0; i < vertexCount(); ++i) {
    const V3 v = vertex(i);
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
}

V3 Placed::center() const {
  switch (shape->kind) {
    case ConvexKind::Sphere:
    case ConvexKind::Box: return p[0];
    case ConvexKind::Capsule: return (p[0] + p[1]) / 2;
    case ConvexKind::Triangle: return (p[0] + p[1] + p[2]) / 3;
    case ConvexKind::Hull: {
      V3 c = V3::Zero();
      const auto& vs = shape->hull->vertices();
      for (const Vec3& v : vs) c += v.cast<double>();
      return R * (c / double(vs.size())) + t;
    }
  }
  return t;
}

// ---- signed-volume subalgorithm ------------------------------------------------------------------

namespace {

bool sameSign(double a, double b) { return (a > 0 && b > 0) || (a < 0 && b < 0); }

/// Closest point of segment {s[i0], s[i1]} to the origin (Montanari S1D): writes the support set
/// and its barycentrics to out; returns the squared distance.
double s1d(const SupportPoint& s1, const SupportPoint& s2, Simplex& out) {
  const V3 t = s2.w - s1.w;
  const double tt = t.squaredNorm();
  if (!(tt > 0)) {
    out.n = 1;
    out.v[0] = s1;
    out.lambda[0] = 1;
    return s1.w.squaredNorm();
  }
  const V3 p0 = s1.w - (s1.w.dot(t) / tt) * t;  // projection of the origin on the line
  int k = 0;
  t.cwiseAbs().maxCoeff(&k);
  const double mu = s1.w[k] - s2.w[k];
  const double c1 = p0[k] - s2.w[k], c2 = s1.w[k] - p0[k];
  if (sameSign(mu, c1) && sameSign(mu, c2)) {
    out.n = 2;
    out.v[0] = s1;
    out.v[1] = s2;
    out.lambda[0] = c1 / mu;
    out.lambda[1] = c2 / mu;
    return out.closest().squaredNorm();
  }
  out.n = 1;
  out.v[0] = sameSign(mu, c1) ? s1 : s2;  // lambda of s1 positive: the projection is beyond s1
  out.lambda[0] = 1;
  return out.v[0].w.squaredNorm();
}

/// Closest point of the triangle to the origin (Montanari S2D).
double s2d(const SupportPoint& s1, const SupportPoint& s2, const SupportPoint& s3, Simplex& out) {
  const V3 n = (s2.w - s1.w).cross(s3.w - s1.w);
  const double nn = n.squaredNorm();
  const SupportPoint* s[3] = {&s1, &s2, &s3};
  if (nn > 0) {
    const V3 p0 = (s1.w.dot(n) / nn) * n;
    int k = 0;
    n.cwiseAbs().maxCoeff(&k);
    const int x = (k + 1) % 3, y = (k + 2) % 3;
    auto area = [&](const V3& a, const V3& b, const V3& c) {
      return (b[x] - a[x]) * (c[y] - a[y]) - (b[y] - a[y]) * (c[x] - a[x]);
    };
    const double mu = area(s1.w, s2.w, s3.w);
    const double c[3] = {area(p0, s2.w, s3.w), area(s1.w, p0, s3.w), area(s1.w, s2.w, p0)};
    if (sameSign(mu, c[0]) && sameSign(mu, c[1]) && sameSign(mu, c[2])) {
      out.n = 3;
      for (int i = 0; i < 3; ++i) {
        out.v[i] = *s[i];
        out.lambda[i] = c[i] / mu;
      }
      return out.closest().squaredNorm();
    }
    double best = std::numeric_limits<double>::infinity();
    for (int j = 0; j < 3; ++j) {
      if (sameSign(mu, c[j])) continue;
      Simplex cand;
      const double d = s1d(*s[(j + 1) % 3], *s[(j + 2) % 3], cand);
      if (d < best) {
        best = d;
        out = cand;
      }
    }
    if (best < std::numeric_limits<double>::infinity()) return best;
  }
  // Degenerate (collinear or coincident) triangle: the best of its edges.
  double best = std::numeric_limits<double>::infinity();
  for (int j = 0; j < 3; ++j) {
    Simplex cand;
    const double d = s1d(*s[(j + 1) % 3], *s[(j + 2) % 3], cand);
    if (d < best) {
      best = d;
      out = cand;
    }
  }
  return best;
}

/// Closest point of the tetrahedron to the origin (Montanari S3D); out.n == 4 when inside.
double s3d(const Simplex& in, Simplex& out) {
  const V3 &s1 = in.v[0].w, &s2 = in.v[1].w, &s3 = in.v[2].w, &s4 = in.v[3].w;
  const double c[4] = {s2.dot(s3.cross(s4)), -s1.dot((s3 - s1).cross(s4 - s1)), (s2 - s1).dot((-s1).cross(s4 - s1)),
                       (s2 - s1).dot((s3 - s1).cross(-s1))};
  const double det = c[0] + c[1] + c[2] + c[3];
  if (sameSign(det, c[0]) && sameSign(det, c[1]) && sameSign(det, c[2]) && sameSign(det, c[3])) {
    out = in;
    for (int i = 0; i < 4; ++i) out.lambda[i] = c[i] / det;
    out.n = 4;
    return 0;
  }
  double best = std::numeric_limits<double>::infinity();
  for (int pass = 0; pass < 2 && !(best < std::numeric_limits<double>::infinity()); ++pass) {
    for (int j = 0; j < 4; ++j) {
      if (pass == 0 && sameSign(det, c[j])) continue;
      Simplex cand;
      const int a = j == 0 ? 1 : 0, b = j <= 1 ? 2 : 1, d3 = j <= 2 ? 3 : 2;
      const double d = s2d(in.v[a], in.v[b], in.v[d3], cand);
      if (d < best) {
        best = d;
        out = cand;
      }
    }
  }
  return best;
}

/// Reduces `s` to the support set of its point closest to the origin; returns |v|².
double closestOnSimplex(Simplex& s) {
  Simplex out;
  double d = 0;
  switch (s.n) {
    case 1:
      s.lambda[0] = 1;
      return s.v[0].w.squaredNorm();
    case 2: d = s1d(s.v[1], s.v[0], out); break;  // newest first, as in the paper
    case 3: d = s2d(s.v[2], s.v[1], s.v[0], out); break;
    default: d = s3d(s, out); break;
  }
  s = out;
  return d;
}

}  // namespace

GjkResult gjk(const Placed& A, const Placed& B, double bound) {
  const double scale = pairScale(A, B);
  const double tolAbs = kGjkScaleTolerance * scale;
  GjkResult r;
  Simplex& s = r.simplex;
  V3 d = A.center() - B.center();
  if (!(d.squaredNorm() > 0)) d = V3::UnitX();
  s.v[0] = supportOf(A, B, -d);
  s.lambda[0] = 1;
  s.n = 1;
  V3 v = s.v[0].w;
  double vv = v.squaredNorm();
  for (r.iterations = 1; r.iterations <= kGjkMaxIterations; ++r.iterations) {
    if (vv <= tolAbs * tolAbs) {
      r.overlap = true;
      r.distance = 0;
      return r;
    }
    const SupportPoint w = supportOf(A, B, -v);
    const double vw = v.dot(w.w);
    const double vlen = std::sqrt(vv);
    if (vw > 0 && vw / vlen > bound) {
      r.separatedBeyondBound = true;
      r.distance = vlen;
      return r;
    }
    if (vv - vw <= kGjkRelativeTolerance * vv + tolAbs * vlen) break;  // converged
    bool duplicate = false;
    for (int i = 0; i < s.n; ++i) duplicate = duplicate || s.v[i].w == w.w;
    if (duplicate) break;
    const Simplex previous = s;
    s.v[s.n++] = w;
    const double nvv = closestOnSimplex(s);
    if (s.n == 4) {
      r.overlap = true;
      r.distance = 0;
      return r;
    }
    if (!(nvv < vv)) {  // no progress: rounding has taken over; keep the previous simplex
      s = previous;
      break;
    }
    vv = nvv;
    v = s.closest();
  }
  if (r.iterations > kGjkMaxIterations) r.capped = true;
  r.distance = std::sqrt(vv);
  if (r.distance <= tolAbs) {
    r.overlap = true;
    r.distance = 0;
  }
  return r;
}

namespace {

bool isPointOrSegment(const ConvexShape& s) { return s.kind == ConvexKind::Sphere || s.kind == ConvexKind::Capsule; }

/// Any unit vector perpendicular to e (e non-zero).
V3 perpendicular(const V3& e) {
  const V3 a = std::abs(e.x()) < 0.57 * e.norm() ? V3::UnitX() : V3::UnitY();
  return e.cross(a).normalized();
}

/// A B→A normal for touching/crossing point and segment cores (core distance 0): the normal of
/// the plane of two crossing segments, else the centre offset made perpendicular to the segments.
V3 touchingNormal(const Placed& A, const Placed& B) {
  const V3 eA = A.shape->kind == ConvexKind::Capsule ? V3(A.p[1] - A.p[0]) : V3::Zero();
  const V3 eB = B.shape->kind == ConvexKind::Capsule ? V3(B.p[1] - B.p[0]) : V3::Zero();
  V3 off = A.center() - B.center();
  const V3 c = eA.cross(eB);
  if (c.squaredNorm() > 1e-24 * eA.squaredNorm() * eB.squaredNorm() && c.squaredNorm() > 0)
    return c.dot(off) >= 0 ? V3(c.normalized()) : V3(-c.normalized());
  const V3 e = eA.squaredNorm() >= eB.squaredNorm() ? eA : eB;
  if (e.squaredNorm() > 0) off -= e * (off.dot(e) / e.squaredNorm());
  if (off.squaredNorm() > 0) return off.normalized();
  return e.squaredNorm() > 0 ? perpendicular(e) : V3::UnitZ();
}

}  // namespace

/// Core distance + normal + core points: the shared front of distance(), contacts() and the casts.
WideDistance coreQueryWide(const Placed& A, const Placed& B) {
  WideDistance out;
  V3 pa, pb, n;
  double dcore = 0;
  const double tolAbs = kGjkScaleTolerance * pairScale(A, B);
  if (isPointOrSegment(*A.shape) && isPointOrSegment(*B.shape)) {
    const int ja = A.shape->kind == ConvexKind::Capsule ? 1 : 0, jb = B.shape->kind == ConvexKind::Capsule ? 1 : 0;
    dcore = std::sqrt(closestSegmentSegment(A.p[0], A.p[ja], B.p[0], B.p[jb], pa, pb));
    if (dcore > tolAbs) {
      n = (pa - pb) / dcore;
      out.status = GjkStatus::Separated;
    } else {
      n = touchingNormal(A, B);
      dcore = 0;
      out.status = GjkStatus::Flat;
    }
    out.iterations = 0;
  } else {
    const GjkResult g = gjk(A, B, std::numeric_limits<double>::infinity());
    out.iterations = g.iterations;
    if (!g.overlap) {
      pa = g.simplex.pointA();
      pb = g.simplex.pointB();
      dcore = g.distance;
      n = (pa - pb) / std::max(dcore, std::numeric_limits<double>::min());
      if (!(n.squaredNorm() > 0.5)) n = g.simplex.closest().normalized();
      out.status = g.capped ? GjkStatus::IterationCap : GjkStatus::Separated;
    } else {
      const EpaResult e = epa(A, B, g.simplex);
      out.iterations += e.iterations;
      n = -e.n;
      dcore = -e.depth;
      pa = e.a;
      pb = e.b;
      out.status = e.capped ? GjkStatus::IterationCap : (e.flat ? GjkStatus::Flat : GjkStatus::Penetrating);
      if (e.flat) {  // orient the plane normal B→A by the centres
        if (n.dot(A.center() - B.center()) < 0) n = -n;
      }
    }
  }
  n.normalize();  // unit to the last ulp (the quotients above are off by a few)
  out.distance = dcore - A.radius - B.radius;
  out.normal = n;
  out.pointA = pa - n * A.radius;
  out.pointB = pb + n * B.radius;
  return out;
}

DistanceResult coreQuery(const Placed& A, const Placed& B) {
  const WideDistance w = coreQueryWide(A, B);
  DistanceResult out;
  out.distance = static_cast<Real>(w.distance);
  out.normal = w.normal.cast<Real>();
  out.pointA = w.pointA.cast<Real>();
  out.pointB = w.pointB.cast<Real>();
  out.iterations = w.iterations;
  out.status = w.status;
  return out;
}

}  // namespace detail

DistanceResult distance(const ConvexShape& a, const Transform& ta, const ConvexShape& b, const Transform& tb) {
  if (!detail::entryPreconditions("distance(ConvexShape, ConvexShape)", detail::rule::kShapesAtPoses,
                                  detail::ShapesAtPoses{a, ta, b, tb})) {
    DistanceResult none;
    none.distance = std::numeric_limits<Real>::quiet_NaN();
    return none;
  }
  const detail::Placed A(a, ta), B(b, tb);
  return detail::coreQuery(A, B);
}

bool overlaps(const ConvexShape& a, const Transform& ta, const ConvexShape& b, const Transform& tb) {
  if (!detail::entryPreconditions("overlaps(ConvexShape, ConvexShape)", detail::rule::kShapesAtPoses,
                                  detail::ShapesAtPoses{a, ta, b, tb})) return false;
  const detail::Placed A(a, ta), B(b, tb);
  const double tolAbs = kGjkScaleTolerance * detail::pairScale(A, B);
  const double reach = A.radius + B.radius + tolAbs;
  if (detail::isPointOrSegment(a) && detail::isPointOrSegment(b)) {
    detail::V3 pa, pb;
    const int ja = a.kind == ConvexKind::Capsule ? 1 : 0, jb = b.kind == ConvexKind::Capsule ? 1 : 0;
    return std::sqrt(detail::closestSegmentSegment(A.p[0], A.p[ja], B.p[0], B.p[jb], pa, pb)) <= reach;
  }
  const detail::GjkResult g = detail::gjk(A, B, reach);
  return !g.separatedBeyondBound && (g.overlap || g.distance <= reach);
}

}  // namespace crux
