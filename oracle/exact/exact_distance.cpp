/// @file exact_distance.cpp  Exact signed distances and contacts of convex shapes and mesh
/// triangles (method: exact_distance.hpp; public entry points: exact.hpp).

#include "exact/exact_distance.hpp"

#include <crux/error.hpp>

#include <CGAL/Projection_traits_xy_3.h>
#include <CGAL/Projection_traits_xz_3.h>
#include <CGAL/Projection_traits_yz_3.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_2.h>
#include <CGAL/convex_hull_3.h>
#include <CGAL/intersections.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <queue>
#include <iterator>
#include <map>
#include <numeric>
#include <utility>

namespace crux::exact {
namespace detail {
namespace {

/// An exact number rounded once (to_double of the exact rational, not of the lazy interval,
/// whose to_double may stop at a relative precision of 1e-5).
double toDouble(const FT& x) { return CGAL::to_double(x.exact()); }

Vec3d toVec3d(const Vector& v) { return {toDouble(v.x()), toDouble(v.y()), toDouble(v.z())}; }

/// Unit vector of an exact direction, rounded (scaled first so tiny or huge ones normalise).
Vec3d unitOf(const Vector& v) {
  Vec3d d = toVec3d(v);
  const double m = d.cwiseAbs().maxCoeff();
  if (!(m > 0) || !std::isfinite(m)) return Vec3d::UnitZ();
  d /= m;
  return d.normalized();
}

struct LessXyz {
  bool operator()(const Point& a, const Point& b) const { return CGAL::compare_xyz(a, b) == CGAL::SMALLER; }
};

/// Σ w_k p_k (the weights sum to 1).
Point combine(const Point* const* points, const FT* weights, int count) {
  Vector sum = CGAL::NULL_VECTOR;
  for (int k = 0; k < count; ++k) sum = sum + (*points[k] - CGAL::ORIGIN) * weights[k];
  return CGAL::ORIGIN + sum;
}

/// Barycentric weights of the point of the non-degenerate triangle (a, b, c) closest to p: the
/// Voronoi-region case analysis of Ericson, Real-Time Collision Detection 5.1.5, in rationals.
std::array<FT, 3> closestWeights(const Point& p, const Point& a, const Point& b, const Point& c) {
  const Vector ab = b - a, ac = c - a, ap = p - a;
  const FT d1 = ab * ap, d2 = ac * ap;
  if (d1 <= 0 && d2 <= 0) return {FT(1), FT(0), FT(0)};
  const Vector bp = p - b;
  const FT d3 = ab * bp, d4 = ac * bp;
  if (d3 >= 0 && d4 <= d3) return {FT(0), FT(1), FT(0)};
  const FT vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const FT v = d1 / (d1 - d3);
    return {FT(1) - v, v, FT(0)};
  }
  const Vector cp = p - c;
  const FT d5 = ab * cp, d6 = ac * cp;
  if (d6 >= 0 && d5 <= d6) return {FT(0), FT(0), FT(1)};
  const FT vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const FT w = d2 / (d2 - d6);
    return {FT(1) - w, FT(0), w};
  }
  const FT va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const FT w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {FT(0), FT(1) - w, w};
  }
  const FT denom = va + vb + vc;
  const FT v = vb / denom, w = vc / denom;
  return {FT(1) - v - w, v, w};
}

/// The Minkowski difference's points a_i − b_j, each remembering one (i, j) it came from.
struct Difference {
  const ExactCore& a;
  const ExactCore& b;
  std::vector<Point> points;
  std::map<Point, std::pair<std::uint32_t, std::uint32_t>, LessXyz> source;

  Difference(const ExactCore& ca, const ExactCore& cb) : a(ca), b(cb) {
    points.reserve(a.points.size() * b.points.size());
    for (std::uint32_t i = 0; i < a.points.size(); ++i)
      for (std::uint32_t j = 0; j < b.points.size(); ++j) {
        const Point d = CGAL::ORIGIN + (a.points[i] - b.points[j]);
        if (source.emplace(d, std::make_pair(i, j)).second) points.push_back(d);
      }
  }

  /// The witnesses on A and B of Σ w_k v_k for difference points v_k.
  void witnesses(const Point* const* v, const FT* w, int count, CoreDistance& out) const {
    const Point* pa[3];
    const Point* pb[3];
    for (int k = 0; k < count; ++k) {
      const auto& ij = source.at(*v[k]);
      pa[k] = &a.points[ij.first];
      pb[k] = &b.points[ij.second];
    }
    out.pointA = combine(pa, w, count);
    out.pointB = combine(pb, w, count);
  }
};

Point centroid(const std::vector<Point>& pts) {
  Vector sum = CGAL::NULL_VECTOR;
  for (const Point& p : pts) sum = sum + (p - CGAL::ORIGIN);
  return CGAL::ORIGIN + sum / FT(int(pts.size()));
}

/// Keeps the nearest of candidate closest points (weights over difference points).
struct Nearest {
  bool found = false;
  FT squared;
  std::array<const Point*, 3> v{};
  std::array<FT, 3> w;
  int count = 0;

  void offer(const Point& x, const std::array<const Point*, 3>& verts, const std::array<FT, 3>& weights, int n) {
    const FT d2 = (x - CGAL::ORIGIN).squared_length();
    if (found && !(d2 < squared)) return;
    found = true;
    squared = d2;
    v = verts;
    w = weights;
    count = n;
  }
};

/// Closest point of the triangle (a, b, c) to the origin, offered to `best`.
void offerTriangle(const Point& a, const Point& b, const Point& c, Nearest& best) {
  const std::array<FT, 3> w = closestWeights(CGAL::ORIGIN, a, b, c);
  const Point* v[3] = {&a, &b, &c};
  best.offer(combine(v, w.data(), 3), {&a, &b, &c}, w, 3);
}

/// Normal of a flat difference holding the origin, oriented by the core centroids.
Vector flatNormal(const Vector& candidate, const ExactCore& a, const ExactCore& b) {
  const Vector c = centroid(a.points) - centroid(b.points);
  return c * candidate < 0 ? -candidate : candidate;
}

}  // namespace

Vec3d toVec3d(const Point& p) { return {toDouble(p.x()), toDouble(p.y()), toDouble(p.z())}; }

ExactCore coreOf(const ConvexShape& shape, const ExactRigid& pose) {
  ExactCore core;
  core.radius = double(shape.radius);
  switch (shape.kind) {
    case ConvexKind::Sphere:
      core.points.push_back(pose.apply(shape.p[0]));
      break;
    case ConvexKind::Capsule:
      core.points.push_back(pose.apply(shape.p[0]));
      core.points.push_back(pose.apply(shape.p[1]));
      break;
    case ConvexKind::Triangle:
      for (int i = 0; i < 3; ++i) core.points.push_back(pose.apply(shape.p[i]));
      break;
    case ConvexKind::Box: {
      // Corner k has local signs (bit0, bit1, bit2) of k, as ConvexShape::vertex; computed exactly
      // along the box's edge vectors (exact_kernel.hpp: the OBB's semantics).
      const Point c = toPoint(shape.p[0]);
      const std::array<Vector, 3> e = edgeVectors(shape.axes);
      for (int k = 0; k < 8; ++k) {
        Vector off = CGAL::NULL_VECTOR;
        for (int i = 0; i < 3; ++i) {
          const FT h(double(shape.p[1][i]));
          off = off + e[i] * (((k >> i) & 1) ? h : -h);
        }
        core.points.push_back(pose.apply(c + off));
      }
      break;
    }
    case ConvexKind::Hull:
      for (const Vec3& v : shape.hull->vertices()) core.points.push_back(pose.apply(v));
      break;
  }
  for (const Point& p : core.points) core.box += p.bbox();
  return core;
}

ExactCore coreOf(const Point& a, const Point& b, const Point& c) {
  ExactCore core;
  core.points = {a, b, c};
  core.box = a.bbox() + b.bbox() + c.bbox();
  return core;
}

CoreDistance coreDistance(const ExactCore& ca, const ExactCore& cb) {
  const Difference diff(ca, cb);
  const std::vector<Point>& d = diff.points;
  CoreDistance out;
  const Point& p0 = d[0];

  // Affine dimension of the difference, exactly.
  std::size_t i1 = 1;
  while (i1 < d.size() && d[i1] == p0) ++i1;
  if (i1 == d.size()) {  // a point
    const Point* v[1] = {&p0};
    const FT w[1] = {FT(1)};
    diff.witnesses(v, w, 1, out);
    out.squared = (p0 - CGAL::ORIGIN).squared_length();
    if (CGAL::is_zero(out.squared)) {
      out.relation = CoreRelation::Flat;  // any direction: the centroids' offset, else +z
      const Vector c = centroid(ca.points) - centroid(cb.points);
      out.normal = c == CGAL::NULL_VECTOR ? Vector(0, 0, 1) : c;
    } else {
      out.relation = CoreRelation::Separated;
      out.normal = p0 - CGAL::ORIGIN;
    }
    return out;
  }
  const Point& p1 = d[i1];
  std::size_t i2 = i1 + 1;
  while (i2 < d.size() && CGAL::collinear(p0, p1, d[i2])) ++i2;
  if (i2 == d.size()) {  // a segment: its extreme points (lexicographic order is monotone on a line)
    const auto [lo, hi] = std::minmax_element(d.begin(), d.end(), LessXyz());
    const Vector u = *hi - *lo;
    FT t = -((*lo - CGAL::ORIGIN) * u) / u.squared_length();
    if (t < 0) t = 0;
    if (t > 1) t = 1;
    const Point* v[2] = {&*lo, &*hi};
    const FT w[2] = {FT(1) - t, t};
    diff.witnesses(v, w, 2, out);
    const Point x = combine(v, w, 2);
    out.squared = (x - CGAL::ORIGIN).squared_length();
    if (CGAL::is_zero(out.squared)) {
      out.relation = CoreRelation::Flat;
      // Perpendicular to the segment: the centroids' offset without its component along u, else
      // u × the axis u is least aligned with.
      const Vector c = centroid(ca.points) - centroid(cb.points);
      const Vector perp = c - u * ((c * u) / u.squared_length());
      if (perp != CGAL::NULL_VECTOR) {
        out.normal = perp;
      } else {
        int axis = 0;
        for (int k = 1; k < 3; ++k)
          if (CGAL::abs(u[k]) < CGAL::abs(u[axis])) axis = k;
        const Vector e(axis == 0 ? 1 : 0, axis == 1 ? 1 : 0, axis == 2 ? 1 : 0);
        out.normal = CGAL::cross_product(u, e);
      }
    } else {
      out.relation = CoreRelation::Separated;
      out.normal = x - CGAL::ORIGIN;
    }
    return out;
  }
  const Point& p2 = d[i2];
  std::size_t i3 = i2 + 1;
  while (i3 < d.size() && CGAL::orientation(p0, p1, p2, d[i3]) == CGAL::COPLANAR) ++i3;

  if (i3 == d.size()) {  // a polygon: 2D hull in the coordinate plane the normal is least parallel to
    const Vector n = CGAL::cross_product(p1 - p0, p2 - p0);
    int axis = 0;
    for (int k = 1; k < 3; ++k)
      if (CGAL::abs(n[axis]) < CGAL::abs(n[k])) axis = k;
    std::vector<Point> hull;
    if (axis == 0)
      CGAL::convex_hull_2(d.begin(), d.end(), std::back_inserter(hull), CGAL::Projection_traits_yz_3<K>());
    else if (axis == 1)
      CGAL::convex_hull_2(d.begin(), d.end(), std::back_inserter(hull), CGAL::Projection_traits_xz_3<K>());
    else
      CGAL::convex_hull_2(d.begin(), d.end(), std::back_inserter(hull), CGAL::Projection_traits_xy_3<K>());
    Nearest best;
    for (std::size_t k = 1; k + 1 < hull.size(); ++k) offerTriangle(hull[0], hull[k], hull[k + 1], best);
    diff.witnesses(best.v.data(), best.w.data(), best.count, out);
    out.squared = best.squared;
    if (CGAL::is_zero(out.squared)) {
      out.relation = CoreRelation::Flat;
      out.normal = flatNormal(n, ca, cb);
    } else {
      out.relation = CoreRelation::Separated;
      out.normal = out.pointA - out.pointB;
    }
    return out;
  }

  // A solid: its hull's facets, oriented outward with an interior point of the tetrahedron found.
  const Point inner = CGAL::centroid(p0, p1, p2, d[i3]);
  CGAL::Surface_mesh<Point> hull;
  CGAL::convex_hull_3(d.begin(), d.end(), hull);
  struct Facet {
    std::array<Point, 3> v;
    Vector n;  ///< outward
    FT h;      ///< n·(v0 − origin): >= 0 when the origin is on the inner side
  };
  std::vector<Facet> facets;
  facets.reserve(hull.number_of_faces());
  bool outside = false;
  for (const auto f : hull.faces()) {
    Facet fc;
    int k = 0;
    for (const auto v : CGAL::vertices_around_face(hull.halfedge(f), hull)) {
      if (k < 3) fc.v[k] = hull.point(v);
      ++k;
    }
    fc.n = CGAL::cross_product(fc.v[1] - fc.v[0], fc.v[2] - fc.v[0]);
    if (fc.n * (inner - fc.v[0]) > 0) fc.n = -fc.n;
    fc.h = fc.n * (fc.v[0] - CGAL::ORIGIN);
    if (fc.h < 0) outside = true;
    facets.push_back(std::move(fc));
  }
  if (outside) {
    Nearest best;
    for (const Facet& fc : facets) offerTriangle(fc.v[0], fc.v[1], fc.v[2], best);
    diff.witnesses(best.v.data(), best.w.data(), best.count, out);
    out.relation = CoreRelation::Separated;
    out.squared = best.squared;
    out.normal = out.pointA - out.pointB;
    return out;
  }
  // Inside: the nearest facet plane; among facets at that depth, the one holding the projection.
  FT depth2 = 0;
  bool first = true;
  for (const Facet& fc : facets) {
    const FT q = fc.h * fc.h / fc.n.squared_length();
    if (first || q < depth2) depth2 = q;
    first = false;
  }
  for (const Facet& fc : facets) {
    if (fc.h * fc.h / fc.n.squared_length() != depth2) continue;
    const Point x = CGAL::ORIGIN + fc.n * (fc.h / fc.n.squared_length());
    const std::array<FT, 3> w = closestWeights(x, fc.v[0], fc.v[1], fc.v[2]);
    const Point* v[3] = {&fc.v[0], &fc.v[1], &fc.v[2]};
    if (combine(v, w.data(), 3) != x) continue;
    diff.witnesses(v, w.data(), 3, out);
    out.squared = depth2;
    out.relation = CGAL::is_zero(depth2) ? CoreRelation::Touching : CoreRelation::Penetrating;
    out.normal = -fc.n;
    return out;
  }
  CGAL_error_msg("exact penetration: no facet holds the projection of the origin");
  return out;
}

namespace {
/// −1, 0, +1: the sign of the signed core distance.
int signOf(const CoreDistance& d) {
  if (d.relation == CoreRelation::Separated) return 1;
  return d.relation == CoreRelation::Penetrating ? -1 : 0;
}
}  // namespace

bool closer(const CoreDistance& x, const CoreDistance& y) {
  const int sx = signOf(x), sy = signOf(y);
  if (sx != sy) return sx < sy;
  if (sx > 0) return x.squared < y.squared;
  if (sx < 0) return y.squared < x.squared;
  return false;
}

bool withinMargin(const CoreDistance& d, double radiusA, double radiusB, double margin) {
  if (d.relation != CoreRelation::Separated) return true;  // signed core distance <= 0 <= margin
  const FT reach = FT(margin) + FT(radiusA) + FT(radiusB);
  return d.squared <= reach * reach;
}

RoundedDistance rounded(const CoreDistance& d, double radiusA, double radiusB) {
  RoundedDistance r;
  r.relation = d.relation;
  const double core = std::sqrt(toDouble(d.squared));
  r.distance = (d.relation == CoreRelation::Separated ? core : -core) - radiusA - radiusB;
  if (r.distance == 0) r.distance = 0;  // no -0 (touching cores without radii)
  r.normal = unitOf(d.normal);
  r.pointA = toVec3d(d.pointA) - radiusA * r.normal;
  r.pointB = toVec3d(d.pointB) + radiusB * r.normal;
  return r;
}

Point commonPoint(const ExactCore& a, const ExactCore& b) {
  const auto simplex = [](const ExactCore& c) {
    const std::vector<Point>& p = c.points;
    return simplexOf(p[0], p[std::min<std::size_t>(1, p.size() - 1)], p[std::min<std::size_t>(2, p.size() - 1)]);
  };
  const Simplex sa = simplex(a), sb = simplex(b);
  if (const Point* p = std::get_if<Point>(&sa)) return *p;
  if (const Point* p = std::get_if<Point>(&sb)) return *p;
  const auto edges = [](const Simplex& s) {
    std::vector<Segment3> out;
    if (const Segment3* g = std::get_if<Segment3>(&s)) out.push_back(*g);
    if (const Triangle3* t = std::get_if<Triangle3>(&s))
      for (int k = 0; k < 3; ++k) out.emplace_back((*t)[k], (*t)[(k + 1) % 3]);
    return out;
  };
  const auto cut = [](const Segment3& e, const Simplex& s) -> std::optional<Point> {
    if (const Triangle3* t = std::get_if<Triangle3>(&s)) {
      if (const auto r = CGAL::intersection(e, *t)) {
        if (const Point* p = boost::get<Point>(&*r)) return *p;
        if (const Segment3* g = boost::get<Segment3>(&*r)) return g->source();
      }
    } else if (const Segment3* g = std::get_if<Segment3>(&s)) {
      if (const auto r = CGAL::intersection(e, *g)) {
        if (const Point* p = boost::get<Point>(&*r)) return *p;
        if (const Segment3* h = boost::get<Segment3>(&*r)) return h->source();
      }
    }
    return std::nullopt;
  };
  for (const Segment3& e : edges(sa))
    if (const auto p = cut(e, sb)) return *p;
  for (const Segment3& e : edges(sb))
    if (const auto p = cut(e, sa)) return *p;
  CGAL_error_msg("exact commonPoint: the cores do not overlap");
  return a.points[0];
}

FT squaredGap(const CGAL::Bbox_3& a, const CGAL::Bbox_3& b) {
  FT sum = 0;
  for (int k = 0; k < 3; ++k) {
    if (a.max(k) < b.min(k)) sum += CGAL::square(FT(b.min(k)) - FT(a.max(k)));
    else if (b.max(k) < a.min(k)) sum += CGAL::square(FT(a.min(k)) - FT(b.max(k)));
  }
  return sum;
}

}  // namespace detail

// ---- public entry points (exact.hpp) ----------------------------------------------------------

namespace {
using namespace detail;

/// The one copy of a rounded distance's point pair, normal and relation into an ExactDistance
/// or ExactContact (which differ in the rest: signed distance vs depth, triangle ids).
template <class Out>
Out withPoints(const RoundedDistance& r) {
  Out out;
  out.pointA = r.pointA;
  out.pointB = r.pointB;
  out.normal = r.normal;
  out.relation = r.relation;
  return out;
}

ExactDistance toDistance(const RoundedDistance& r) {
  ExactDistance d = withPoints<ExactDistance>(r);
  d.distance = r.distance;
  return d;
}

ExactContact toContact(const RoundedDistance& r, std::uint32_t triangle) {
  ExactContact c = withPoints<ExactContact>(r);
  c.depth = -r.distance;
  c.triangle = triangle;
  return c;
}

/// Indices 0..n-1 sorted by a double estimate of each one's lower bound (only the order of
/// work: every prune below is decided exactly).
template <class Bound>
std::vector<std::uint32_t> byBound(std::size_t n, const Bound& bound) {
  std::vector<double> key(n);
  for (std::size_t i = 0; i < n; ++i) key[i] = bound(i);
  std::vector<std::uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), [&](std::uint32_t x, std::uint32_t y) { return key[x] < key[y]; });
  return order;
}

/// Squared gap of two boxes in double (an estimate for ordering and a filter with slack).
double approxGap(const CGAL::Bbox_3& a, const CGAL::Bbox_3& b) {
  double sum = 0;
  for (int k = 0; k < 3; ++k) {
    const double g = std::max({0.0, b.min(k) - a.max(k), a.min(k) - b.max(k)});
    sum += g * g;
  }
  return sum;
}

const ExactRigid::Rotation kRule = ExactRigid::Rotation::Snapped;

/// A mesh's triangles placed exactly on demand. Every vertex first gets a conservative double box
/// from the pose's interval entries (ExactRigid::enclosures): x_i = Σ_j r_ij v_j + t_i with r_ij in
/// [mid ± rad], so |x_i − Σ mid_ij v_j − mid_i| <= Σ rad_ij |v_j| + rad_i, plus the double
/// evaluation's rounding (bounded by 8ε of the sum of magnitudes) and a 1e-6 relative safety.
/// Only triangles those boxes cannot rule out are placed exactly (ExactRigid::apply, coreOf):
/// placing all of bunny00's 37k vertices as lazy exact points was ~0.25 s a query, nearly all of
/// it allocation and handle counting. The decisions on the triangles placed are unchanged; a
/// triangle skipped by its box is one the exact tests would have found beyond reach (or farther
/// than the best), since its box encloses its exactly placed corners.
class LazyPlaced {
 public:
  LazyPlaced(const Mesh& mesh, const ExactRigid& pose) : mesh_(mesh), pose_(pose), cores_(mesh.triangleCount()) {
    double rLo[3][3], rHi[3][3], tLo[3], tHi[3];
    pose.enclosures(rLo, rHi, tLo, tHi);
    const double eps = std::numeric_limits<double>::epsilon();
    boxes_.reserve(mesh.vertexCount());
    for (const Vec3& vr : mesh.vertices()) {
      const double v[3] = {double(vr.x()), double(vr.y()), double(vr.z())};
      double lo[3], hi[3];
      for (int i = 0; i < 3; ++i) {
        const double tm = 0.5 * tLo[i] + 0.5 * tHi[i];
        double x = tm, magnitude = std::fabs(tm), err = 0.5 * (tHi[i] - tLo[i]);
        for (int j = 0; j < 3; ++j) {
          const double m = 0.5 * rLo[i][j] + 0.5 * rHi[i][j];
          x += m * v[j];
          magnitude += std::fabs(m * v[j]);
          err += 0.5 * (rHi[i][j] - rLo[i][j]) * std::fabs(v[j]);
        }
        err = (err + 8 * eps * magnitude) * (1 + 1e-6) + std::numeric_limits<double>::denorm_min();
        lo[i] = x - err;
        hi[i] = x + err;
      }
      boxes_.emplace_back(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
    }
  }
  /// A box enclosing triangle t's exactly placed corners.
  CGAL::Bbox_3 bound(std::uint32_t t) const {
    const TriangleIndices& f = mesh_.triangles()[t];
    return boxes_[f[0]] + boxes_[f[1]] + boxes_[f[2]];
  }
  /// Triangle t placed exactly (computed once).
  const ExactCore& triangle(std::uint32_t t) {
    std::optional<ExactCore>& c = cores_[t];
    if (!c) {
      const TriangleIndices& f = mesh_.triangles()[t];
      c = coreOf(pose_.apply(mesh_.vertices()[f[0]]), pose_.apply(mesh_.vertices()[f[1]]),
                 pose_.apply(mesh_.vertices()[f[2]]));
    }
    return *c;
  }
  std::size_t size() const { return cores_.size(); }
  /// The conservative box of corner k of triangle t.
  const CGAL::Bbox_3& corner(std::uint32_t t, int k) const { return boxes_[mesh_.triangles()[t][std::size_t(k)]]; }

 private:
  const Mesh& mesh_;
  const ExactRigid& pose_;
  std::vector<CGAL::Bbox_3> boxes_;
  std::vector<std::optional<ExactCore>> cores_;
};

/// Whether the squared double gap `g` of two boxes certainly exceeds `limit2` (the double
/// differences are correctly rounded, so g is within a few ulps of the exact squared gap).
bool certainlyBeyond(double g, double limit2) { return g > limit2 * (1 + 1e-9) + std::numeric_limits<double>::denorm_min(); }

/// A lower bound on the squared distance of triangles i of `a` and j of `b` (their exactly placed
/// corners) from their corners' conservative boxes, in double: the gap between the two triangles'
/// projections on each one's approximate normal (from the boxes' centres; any direction gives a
/// lower bound, and this one is sharp for a triangle far from the other's plane, where the box gap
/// is not: a big triangle's box holds everything near it). Each projection is rounded outward
/// by 8 ulps of its terms' magnitude; 0 when no bound is found (degenerate, non-finite).
double planeGap(const LazyPlaced& a, std::uint32_t i, const LazyPlaced& b, std::uint32_t j) {
  const double eps = std::numeric_limits<double>::epsilon();
  auto centre = [](const CGAL::Bbox_3& x, int k) { return 0.5 * x.min(k) + 0.5 * x.max(k); };
  // the projection interval of a triangle's three corner boxes on n
  auto project = [&](const LazyPlaced& m, std::uint32_t t, const double* n, double& lo, double& hi) {
    lo = HUGE_VAL;
    hi = -HUGE_VAL;
    for (int c = 0; c < 3; ++c) {
      const CGAL::Bbox_3& x = m.corner(t, c);
      double l = 0, h = 0, mag = 0;
      for (int k = 0; k < 3; ++k) {
        const double p = n[k] * x.min(k), q = n[k] * x.max(k);
        l += std::min(p, q);
        h += std::max(p, q);
        mag += std::max(std::fabs(p), std::fabs(q));
      }
      lo = std::min(lo, l - 8 * eps * mag);
      hi = std::max(hi, h + 8 * eps * mag);
    }
  };
  double best = 0;
  for (int side = 0; side < 2; ++side) {
    const LazyPlaced& m = side == 0 ? a : b;
    const std::uint32_t t = side == 0 ? i : j;
    double p[3][3];
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) p[c][k] = centre(m.corner(t, c), k);
    const double u[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
    const double v[3] = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
    const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    const double n2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    if (!(n2 > 0) || !std::isfinite(n2)) continue;
    double loA, hiA, loB, hiB;
    project(a, i, n, loA, hiA);
    project(b, j, n, loB, hiB);
    const double gap = std::max(loB - hiA, loA - hiB);
    if (gap > 0 && std::isfinite(gap)) best = std::max(best, gap * gap / n2);
  }
  return best;
}

/// A binary tree over a LazyPlaced mesh's conservative triangle boxes (flat, children of an inner
/// node at left and left + 1; leaves of <= 4 triangles, `items[first, first + count)`), split at
/// the median of the box centres along the longest axis of their spread. Only an order of work
/// and a conservative prune for the exact mesh–mesh distance: every decision on a triangle pair
/// stays exact. The oracle's own tree, not crux::Bvh: crux::Bvh holds Real boxes, which cannot
/// hold the conservative double enclosures as they are, and an arbiter's pruning must not rest
/// on the native structure it judges.
struct BoxTree {
  struct Node {
    CGAL::Bbox_3 box;
    std::uint32_t first = 0, count = 0;  // a leaf's items (count > 0)
    std::uint32_t left = 0;              // an inner node's first child
  };
  std::vector<Node> nodes;
  std::vector<std::uint32_t> items;

  explicit BoxTree(const LazyPlaced& placed) {
    const std::uint32_t n = std::uint32_t(placed.size());
    std::vector<CGAL::Bbox_3> boxes(n);
    std::vector<std::array<double, 3>> centre(n);
    for (std::uint32_t t = 0; t < n; ++t) {
      boxes[t] = placed.bound(t);
      for (int k = 0; k < 3; ++k) centre[t][std::size_t(k)] = 0.5 * boxes[t].min(k) + 0.5 * boxes[t].max(k);
    }
    items.resize(n);
    std::iota(items.begin(), items.end(), 0u);
    nodes.reserve(2 * std::size_t(n));
    nodes.push_back(Node{});
    nodes[0].first = 0;
    nodes[0].count = n;
    std::vector<std::uint32_t> work{0};
    while (!work.empty()) {
      const std::uint32_t at = work.back();
      work.pop_back();
      const std::uint32_t first = nodes[at].first, count = nodes[at].count;
      CGAL::Bbox_3 box = boxes[items[first]];
      double lo[3], hi[3];
      for (int k = 0; k < 3; ++k) lo[k] = hi[k] = centre[items[first]][std::size_t(k)];
      for (std::uint32_t u = first; u < first + count; ++u) {
        box += boxes[items[u]];
        for (int k = 0; k < 3; ++k) {
          lo[k] = std::min(lo[k], centre[items[u]][std::size_t(k)]);
          hi[k] = std::max(hi[k], centre[items[u]][std::size_t(k)]);
        }
      }
      nodes[at].box = box;
      if (count <= 4) continue;
      int axis = 0;
      for (int k = 1; k < 3; ++k)
        if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
      const std::uint32_t half = count / 2;
      std::nth_element(items.begin() + first, items.begin() + first + half, items.begin() + first + count,
                       [&](std::uint32_t x, std::uint32_t y) {
                         const double cx = centre[x][std::size_t(axis)], cy = centre[y][std::size_t(axis)];
                         return cx < cy || (cx == cy && x < y);
                       });
      const std::uint32_t left = std::uint32_t(nodes.size());
      Node l, r;
      l.first = first;
      l.count = half;
      r.first = first + half;
      r.count = count - half;
      nodes.push_back(l);
      nodes.push_back(r);
      nodes[at].count = 0;
      nodes[at].left = left;
      work.push_back(left);
      work.push_back(left + 1);
    }
  }
  /// A node box's size, to choose which of two to split (the sum of its sides).
  static double extent(const CGAL::Bbox_3& b) { return (b.xmax() - b.xmin()) + (b.ymax() - b.ymin()) + (b.zmax() - b.zmin()); }
};
}  // namespace

ExactDistance distance(const ConvexShape& a, const Transform& ta, const ConvexShape& b, const Transform& tb) {
  const ExactCore ca = coreOf(a, ExactRigid(ta, kRule)), cb = coreOf(b, ExactRigid(tb, kRule));
  return toDistance(rounded(coreDistance(ca, cb), ca.radius, cb.radius));
}

ExactDistance distance(const Mesh& mesh, const Transform& meshPose, const ConvexShape& shape,
                       const Transform& shapePose) {
  if (mesh.triangleCount() == 0) throw InvalidInput("mesh: the mesh has no triangles");
  const ExactRigid pose(meshPose, kRule);
  LazyPlaced placed(mesh, pose);
  const ExactCore core = coreOf(shape, ExactRigid(shapePose, kRule));
  const std::vector<std::uint32_t> order =
      byBound(placed.size(), [&](std::size_t t) { return approxGap(placed.bound(std::uint32_t(t)), core.box); });
  std::optional<CoreDistance> best;
  double bestApprox = 0;  // best->squared in double (Separated), 0 otherwise: a filter only
  std::uint32_t bestIndex = 0;
  for (const std::uint32_t t : order) {
    // certainly farther than the best (or apart when the best touches): not placed at all
    if (best && certainlyBeyond(approxGap(placed.bound(t), core.box), bestApprox)) continue;
    const ExactCore& tri = placed.triangle(t);
    if (best) {
      const FT gap = squaredGap(tri.box, core.box);  // the triangle is at least this far (squared)
      if (best->relation != CoreRelation::Separated ? !CGAL::is_zero(gap) : best->squared < gap) continue;
    }
    const CoreDistance d = coreDistance(tri, core);
    if (!best || closer(d, *best) || (!closer(*best, d) && t < bestIndex)) {
      best = d;
      bestIndex = t;
      bestApprox = best->relation == CoreRelation::Separated ? CGAL::to_double(best->squared) : 0.0;
    }
  }
  ExactDistance out = toDistance(rounded(*best, 0.0, core.radius));
  out.triangleA = bestIndex;
  return out;
}

std::optional<ExactDistance> meshDistance(const Mesh& a, const Transform& ta, const Mesh& b, const Transform& tb,
                                          double maxDistance) {
  return detail::meshDistance(a, ExactRigid(ta, kRule), b, ExactRigid(tb, kRule), maxDistance);
}

std::optional<ExactDistance> detail::meshDistance(const Mesh& a, const ExactRigid& ta, const Mesh& b,
                                                  const ExactRigid& tb, double maxDistance) {
  if (a.triangleCount() == 0 || b.triangleCount() == 0) throw InvalidInput("mesh: the mesh has no triangles");
  LazyPlaced pa(a, ta), pb(b, tb);
  const BoxTree treeA(pa), treeB(pb);
  const bool bounded = std::isfinite(maxDistance);
  const FT max2 = bounded ? CGAL::square(FT(maxDistance)) : FT(0);
  const double max2Approx = bounded ? maxDistance * maxDistance : HUGE_VAL;
  std::optional<CoreDistance> best;
  double bestApprox = HUGE_VAL;  // the best squared distance rounded (a filter only)
  std::uint32_t bestI = 0, bestJ = 0;
  // Branch and bound over the two trees, nearest node pair first (Larsen et al. 1999's scheme
  // with boxes): a pair is dropped only when its conservative boxes are certainly farther than
  // the best (or the limit), so every triangle pair that could beat or tie the best is reached
  // and decided exactly as before (the nearest; ties: the lowest (a, b) index pair).
  struct Pending {
    double gap;
    std::uint32_t na, nb;
    bool operator<(const Pending& o) const { return gap > o.gap; }  // min-heap on the gap
  };
  std::priority_queue<Pending> queue;
  queue.push({approxGap(treeA.nodes[0].box, treeB.nodes[0].box), 0, 0});
  auto pairOf = [&](std::uint32_t i, std::uint32_t j) {
    const double limit = std::min(bestApprox, max2Approx);
    if (certainlyBeyond(approxGap(pa.bound(i), pb.bound(j)), limit)) return;
    if (certainlyBeyond(planeGap(pa, i, pb, j), limit)) return;
    const ExactCore &ca = pa.triangle(i), &cb = pb.triangle(j);
    // A double filter on the exact cores' boxes (its rounding is far below the 1e-9 slack), then
    // the exact prune.
    if (certainlyBeyond(approxGap(ca.box, cb.box), limit)) return;
    const FT gap = squaredGap(ca.box, cb.box);
    if (bounded && max2 < gap) return;
    if (best && best->squared < gap) return;
    const CoreDistance d = coreDistance(ca, cb);
    const bool tie = best && !closer(*best, d) && !closer(d, *best);
    if (!best || closer(d, *best) || (tie && std::make_pair(i, j) < std::make_pair(bestI, bestJ))) {
      best = d;
      bestApprox = CGAL::to_double(d.relation == CoreRelation::Separated ? d.squared : FT(0));
      bestI = i;
      bestJ = j;
    }
  };
  while (!queue.empty()) {
    const Pending top = queue.top();
    queue.pop();
    // every pair left is at least this far: done when it is certainly beyond the best
    if (certainlyBeyond(top.gap, std::min(bestApprox, max2Approx))) break;
    const BoxTree::Node &x = treeA.nodes[top.na], &y = treeB.nodes[top.nb];
    if (x.count > 0 && y.count > 0) {
      for (std::uint32_t u = x.first; u < x.first + x.count; ++u) {
        for (std::uint32_t v = y.first; v < y.first + y.count; ++v) {
          pairOf(treeA.items[u], treeB.items[v]);
          if (best && best->relation != CoreRelation::Separated) break;  // distance 0: nothing is nearer
        }
        if (best && best->relation != CoreRelation::Separated) break;
      }
      if (best && best->relation != CoreRelation::Separated) break;
      continue;
    }
    // split the inner node (of two inner nodes, the larger box; A on a tie)
    const bool splitA = y.count > 0 || (x.count == 0 && BoxTree::extent(x.box) >= BoxTree::extent(y.box));
    if (splitA) {
      for (std::uint32_t c = x.left; c < x.left + 2; ++c)
        queue.push({approxGap(treeA.nodes[c].box, y.box), c, top.nb});
    } else {
      for (std::uint32_t c = y.left; c < y.left + 2; ++c)
        queue.push({approxGap(x.box, treeB.nodes[c].box), top.na, c});
    }
  }
  if (!best || (bounded && best->relation == CoreRelation::Separated && max2 < best->squared)) return std::nullopt;
  CoreDistance d = *best;
  if (d.relation == CoreRelation::Penetrating) d.pointA = d.pointB = commonPoint(pa.triangle(bestI), pb.triangle(bestJ));
  if (d.relation != CoreRelation::Separated) d.squared = 0;
  ExactDistance out = toDistance(rounded(d, 0.0, 0.0));
  out.distance = std::abs(out.distance);  // unsigned: 0 when the surfaces touch or cross
  out.triangleA = std::uint32_t(bestI);
  out.triangleB = std::uint32_t(bestJ);
  return out;
}

std::vector<ExactContact> contacts(const ConvexShape& a, const Transform& ta, const ConvexShape& b,
                                   const Transform& tb, double margin) {
  const ExactCore ca = coreOf(a, ExactRigid(ta, kRule)), cb = coreOf(b, ExactRigid(tb, kRule));
  const CoreDistance d = coreDistance(ca, cb);
  if (!withinMargin(d, ca.radius, cb.radius, margin)) return {};
  return {toContact(rounded(d, ca.radius, cb.radius), 0)};
}

std::vector<ExactContact> contacts(const Mesh& mesh, const Transform& meshPose, const ConvexShape& shape,
                                   const Transform& shapePose, double margin) {
  const ExactRigid pose(meshPose, kRule);
  LazyPlaced placed(mesh, pose);
  const ExactCore core = coreOf(shape, ExactRigid(shapePose, kRule));
  const FT reach = FT(margin) + FT(core.radius);
  const double reachApprox = (margin + core.radius) * (1 + 1e-9);
  std::vector<ExactContact> out;
  for (std::uint32_t t = 0; t < placed.size(); ++t) {
    if (certainlyBeyond(approxGap(placed.bound(t), core.box), reachApprox * reachApprox)) continue;
    const ExactCore& tri = placed.triangle(t);
    if (reach * reach < squaredGap(tri.box, core.box)) continue;
    const CoreDistance d = coreDistance(tri, core);
    if (withinMargin(d, 0.0, core.radius, margin)) out.push_back(toContact(rounded(d, 0.0, core.radius), t));
  }
  return out;
}

}  // namespace crux::exact
