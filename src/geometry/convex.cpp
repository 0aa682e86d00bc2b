// Capsule validation, the ConvexShape view and its support mapping, and the convex hull build
// (farthest-point incremental construction in the order of QuickHull, then coplanar-face merge).

#include <crux/geometry/convex.hpp>

#include "finite_lanes.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>

namespace crux {
namespace {

using V3 = Eigen::Vector3d;

std::string str(const Vec3& v) {
  std::ostringstream os;
  os.precision(17);
  os << "[" << v.x() << ", " << v.y() << ", " << v.z() << "]";
  return os.str();
}

/// 2-D convex hull (Andrew's monotone chain) of `idx` projected on (u, v); counter-clockwise
/// in that frame, collinear points dropped.
std::vector<std::uint32_t> hull2d(const std::vector<V3>& pts, std::vector<std::uint32_t> idx, const V3& u, const V3& v,
                                  double tol) {
  auto key = [&](std::uint32_t i) { return std::make_pair(pts[i].dot(u), pts[i].dot(v)); };
  std::sort(idx.begin(), idx.end(), [&](std::uint32_t a, std::uint32_t b) { return key(a) < key(b); });
  idx.erase(std::unique(idx.begin(), idx.end(), [&](std::uint32_t a, std::uint32_t b) { return key(a) == key(b); }),
            idx.end());
  if (idx.size() < 3) return idx;
  // Turn o -> a -> b, minus tol·|ob|: <= 0 when a is within tol of the line ob (collinear).
  auto cross = [&](std::uint32_t o, std::uint32_t a, std::uint32_t b) {
    const auto ko = key(o), ka = key(a), kb = key(b);
    return (ka.first - ko.first) * (kb.second - ko.second) - (ka.second - ko.second) * (kb.first - ko.first) -
           tol * std::hypot(kb.first - ko.first, kb.second - ko.second);
  };
  std::vector<std::uint32_t> h(2 * idx.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < idx.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], idx[i]) <= 0) --k;
    h[k++] = idx[i];
  }
  for (std::size_t i = idx.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross(h[k - 2], h[k - 1], idx[i]) <= 0) --k;
    h[k++] = idx[i];
  }
  h.resize(k - 1);
  return h;
}

/// An orthonormal pair (u, v) with u × v = n (n unit).
void basis(const V3& n, V3& u, V3& v) {
  u = (std::abs(n.x()) < 0.57 ? V3::UnitX() : V3::UnitY()).cross(n).normalized();
  v = n.cross(u);
}

}  // namespace

void validate(const Capsule& capsule, const std::string& name) {
  if (!capsule.a.allFinite()) throw InvalidInput(name + ".a has a non-finite coordinate: " + str(capsule.a));
  if (!capsule.b.allFinite()) throw InvalidInput(name + ".b has a non-finite coordinate: " + str(capsule.b));
  if (!std::isfinite(capsule.radius) || capsule.radius < 0) {
    std::ostringstream os;
    os.precision(17);
    os << name << ".radius must be finite and >= 0: " << capsule.radius;
    throw InvalidInput(os.str());
  }
}

// ---- ConvexShape -----------------------------------------------------------------------------

ConvexShape::ConvexShape(const Sphere& s) : kind(ConvexKind::Sphere), radius(s.radius) { p[0] = s.center; }
ConvexShape::ConvexShape(const Capsule& c) : kind(ConvexKind::Capsule), radius(c.radius) {
  p[0] = c.a;
  p[1] = c.b;
}
ConvexShape::ConvexShape(const Obb& b) : kind(ConvexKind::Box), axes(b.axes) {
  p[0] = b.center;
  p[1] = b.half;
}
ConvexShape::ConvexShape(const Triangle& t) : kind(ConvexKind::Triangle) {
  p[0] = t.a;
  p[1] = t.b;
  p[2] = t.c;
}
ConvexShape::ConvexShape(const ConvexHull& h) : kind(ConvexKind::Hull), hull(&h) {}

int ConvexShape::vertexCount() const {
  switch (kind) {
    case ConvexKind::Sphere: return 1;
    case ConvexKind::Capsule: return 2;
    case ConvexKind::Triangle: return 3;
    case ConvexKind::Box: return 8;
    case ConvexKind::Hull: return static_cast<int>(hull->vertices().size());
  }
  return 0;
}

Vec3 ConvexShape::vertex(int i) const {
  switch (kind) {
    case ConvexKind::Sphere:
    case ConvexKind::Capsule:
    case ConvexKind::Triangle: return p[i];
    case ConvexKind::Box: {
      const Vec3 s((i & 1) ? p[1].x() : -p[1].x(), (i & 2) ? p[1].y() : -p[1].y(), (i & 4) ? p[1].z() : -p[1].z());
      return p[0] + axes * s;
    }
    case ConvexKind::Hull: return hull->vertices()[static_cast<std::size_t>(i)];
  }
  return p[0];
}

Real ConvexShape::size() const {
  switch (kind) {
    case ConvexKind::Sphere: return p[0].norm() + radius;
    case ConvexKind::Capsule: return std::max(p[0].norm(), p[1].norm()) + radius;
    case ConvexKind::Triangle: return std::max({p[0].norm(), p[1].norm(), p[2].norm()});
    case ConvexKind::Box: return p[0].norm() + p[1].norm();
    case ConvexKind::Hull: return hull->boundingRadius();
  }
  return 0;
}

Vec3 supportCore(const ConvexShape& s, const Vec3& d, int* index) {
  int best = 0;
  switch (s.kind) {
    case ConvexKind::Sphere: break;
    case ConvexKind::Capsule: best = s.p[1].dot(d) > s.p[0].dot(d) ? 1 : 0; break;
    case ConvexKind::Triangle: {
      const Real d0 = s.p[0].dot(d), d1 = s.p[1].dot(d), d2 = s.p[2].dot(d);
      best = d1 > d0 ? (d2 > d1 ? 2 : 1) : (d2 > d0 ? 2 : 0);
      break;
    }
    case ConvexKind::Box: {
      const Vec3 l = s.axes.transpose() * d;
      best = (l.x() > 0 ? 1 : 0) | (l.y() > 0 ? 2 : 0) | (l.z() > 0 ? 4 : 0);
      break;
    }
    case ConvexKind::Hull: best = static_cast<int>(s.hull->supportIndex(d)); break;
  }
  if (index) *index = best;
  return s.vertex(best);
}

Vec3 support(const ConvexShape& s, const Vec3& d) {
  const Vec3 c = supportCore(s, d);
  const Real n = d.norm();
  return n > 0 ? Vec3(c + d * (s.radius / n)) : c;
}

// ---- ConvexHull ------------------------------------------------------------------------------

std::uint32_t ConvexHull::supportIndex(const Vec3& d) const {
  std::uint32_t best = 0;
  Real bestDot = vertices_[0].dot(d);
  for (std::uint32_t i = 1; i < vertices_.size(); ++i) {
    const Real t = vertices_[i].dot(d);
    if (t > bestDot) {
      bestDot = t;
      best = i;
    }
  }
  return best;
}

Real ConvexHull::volume() const {
  if (dimension_ < 3) return 0;
  double vol = 0;
  const V3 o = vertices_[0].cast<double>();
  for (const HullFace& f : faces_) {
    const V3 a = vertices_[faceVertices_[f.first]].cast<double>() - o;
    for (std::uint32_t k = 1; k + 1 < f.count; ++k) {
      const V3 b = vertices_[faceVertices_[f.first + k]].cast<double>() - o;
      const V3 c = vertices_[faceVertices_[f.first + k + 1]].cast<double>() - o;
      vol += a.dot(b.cross(c));
    }
  }
  return static_cast<Real>(vol / 6);
}

ConvexHull ConvexHull::build(const std::vector<Vec3>& input, const std::string& name) {
  if (input.empty()) throw InvalidInput(name + " is empty: a convex hull needs at least one point");
  for (std::size_t i = 0; i < input.size(); ++i)
    if (!input[i].allFinite())
      throw InvalidInput(name + "[" + std::to_string(i) + "] has a non-finite coordinate: " + str(input[i]));

  // Unique points, in double.
  std::vector<Vec3> uniq(input);
  auto lex = [](const Vec3& a, const Vec3& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  };
  std::sort(uniq.begin(), uniq.end(), lex);
  uniq.erase(std::unique(uniq.begin(), uniq.end()), uniq.end());
  std::vector<V3> pts(uniq.size());
  V3 lo = V3::Constant(INFINITY), hi = V3::Constant(-INFINITY);
  for (std::size_t i = 0; i < uniq.size(); ++i) {
    pts[i] = uniq[i].cast<double>();
    lo = lo.cwiseMin(pts[i]);
    hi = hi.cwiseMax(pts[i]);
  }
  const double diag = (hi - lo).norm();
  const double tol = double(kHullRelativeTolerance) * diag;
  // The build works on the points relative to their box's centre, on the hull's own scale: a
  // plane test n·p − d at coordinates far larger than the hull rounds beyond tol (double builds:
  // a hull of extent 50 at 2^18 from the origin came out with missing faces and ConvexShape
  // contacts between touching hulls were missed). The difference of two doubles is rounded once,
  // relative to the result.
  const V3 origin = 0.5 * (lo + hi);
  for (V3& q : pts) q -= origin;

  ConvexHull h;
  h.tolerance_ = static_cast<Real>(tol);
  auto finish = [&](const std::vector<std::uint32_t>& used) {
    for (std::uint32_t i : used) h.vertices_.push_back(uniq[i]);
    for (const Vec3& v : h.vertices_) h.boundingRadius_ = std::max(h.boundingRadius_, v.norm());
  };

  // Extreme simplex: the farthest pair among the six axis-extreme points, then the point
  // farthest from their line, then the one farthest from that plane.
  std::array<std::uint32_t, 6> ext{};
  for (std::uint32_t i = 0; i < pts.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      if (pts[i][k] < pts[ext[2 * k]][k]) ext[2 * k] = i;
      if (pts[i][k] > pts[ext[2 * k + 1]][k]) ext[2 * k + 1] = i;
    }
  std::uint32_t i0 = 0, i1 = 0;
  double best = -1;
  for (std::uint32_t a : ext)
    for (std::uint32_t b : ext)
      if ((pts[a] - pts[b]).squaredNorm() > best) {
        best = (pts[a] - pts[b]).squaredNorm();
        i0 = a;
        i1 = b;
      }
  if (std::sqrt(best) <= tol || pts.size() == 1) {
    h.dimension_ = 0;
    finish({i0});
    return h;
  }
  const V3 e = (pts[i1] - pts[i0]).normalized();
  std::uint32_t i2 = i0;
  best = -1;
  for (std::uint32_t i = 0; i < pts.size(); ++i) {
    const double d = (pts[i] - pts[i0]).cross(e).squaredNorm();
    if (d > best) {
      best = d;
      i2 = i;
    }
  }
  if (std::sqrt(best) <= tol) {  // collinear: the two extreme points along e
    std::uint32_t lo_i = 0, hi_i = 0;
    for (std::uint32_t i = 0; i < pts.size(); ++i) {
      if (pts[i].dot(e) < pts[lo_i].dot(e)) lo_i = i;
      if (pts[i].dot(e) > pts[hi_i].dot(e)) hi_i = i;
    }
    h.dimension_ = 1;
    finish({lo_i, hi_i});
    return h;
  }
  V3 n = (pts[i1] - pts[i0]).cross(pts[i2] - pts[i0]).normalized();
  std::uint32_t i3 = i0;
  best = -1;
  for (std::uint32_t i = 0; i < pts.size(); ++i) {
    const double d = std::abs((pts[i] - pts[i0]).dot(n));
    if (d > best) {
      best = d;
      i3 = i;
    }
  }
  if (best <= tol) {  // coplanar: a polygon with a face on each side
    std::vector<std::uint32_t> all(pts.size());
    for (std::uint32_t i = 0; i < pts.size(); ++i) all[i] = i;
    V3 u, v;
    basis(n, u, v);
    const std::vector<std::uint32_t> loop = hull2d(pts, all, u, v, tol);
    h.dimension_ = 2;
    finish(loop);
    const auto m = static_cast<std::uint32_t>(loop.size());
    const double off = pts[loop[0]].dot(n) + n.dot(origin);
    h.faces_.push_back({n.cast<Real>(), static_cast<Real>(off), 0, m});
    h.faces_.push_back({(-n).cast<Real>(), static_cast<Real>(-off), m, m});
    for (std::uint32_t i = 0; i < m; ++i) h.faceVertices_.push_back(i);
    for (std::uint32_t i = m; i-- > 0;) h.faceVertices_.push_back(i);
    return h;
  }

  // 3-D: incremental hull, farthest point first.
  struct Face {
    std::array<std::uint32_t, 3> v;
    V3 n;
    double d;
    bool alive;
  };
  std::vector<Face> faces;
  auto addFace = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    V3 fn = (pts[b] - pts[a]).cross(pts[c] - pts[a]);
    const double len = fn.norm();
    fn = len > 0 ? V3(fn / len) : V3::Zero();
    faces.push_back({{a, b, c}, fn, fn.dot(pts[a]), true});
  };
  const V3 centroid = (pts[i0] + pts[i1] + pts[i2] + pts[i3]) / 4;
  {
    const std::array<std::array<std::uint32_t, 3>, 4> tet = {{{i0, i1, i2}, {i0, i3, i1}, {i1, i3, i2}, {i2, i3, i0}}};
    const bool flip = (pts[i1] - pts[i0]).cross(pts[i2] - pts[i0]).dot(centroid - pts[i0]) > 0;
    for (const auto& t : tet) flip ? addFace(t[0], t[2], t[1]) : addFace(t[0], t[1], t[2]);
  }
  std::vector<std::uint32_t> cand;
  for (std::uint32_t i = 0; i < pts.size(); ++i)
    if (i != i0 && i != i1 && i != i2 && i != i3) cand.push_back(i);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> edges, horizon;
  for (;;) {
    double far = tol;
    std::size_t farK = cand.size();
    std::size_t keep = 0;
    for (std::size_t k = 0; k < cand.size(); ++k) {
      double m = -INFINITY;
      for (const Face& f : faces)
        if (f.alive) m = std::max(m, f.n.dot(pts[cand[k]]) - f.d);
      if (m <= tol) continue;  // inside for good: the hull only grows
      cand[keep] = cand[k];
      if (m > far) {
        far = m;
        farK = keep;
      }
      ++keep;
    }
    cand.resize(keep);
    if (farK >= cand.size()) break;
    const std::uint32_t q = cand[farK];
    cand.erase(cand.begin() + static_cast<std::ptrdiff_t>(farK));
    edges.clear();
    for (Face& f : faces)
      if (f.alive && f.n.dot(pts[q]) - f.d > tol) {
        f.alive = false;
        for (int k = 0; k < 3; ++k) edges.emplace_back(f.v[k], f.v[(k + 1) % 3]);
      }
    horizon.clear();
    for (const auto& ed : edges)
      if (std::find(edges.begin(), edges.end(), std::make_pair(ed.second, ed.first)) == edges.end())
        horizon.push_back(ed);
    for (const auto& ed : horizon) addFace(ed.first, ed.second, q);
  }

  // Merge coplanar triangles into polygons; keep the vertices the polygons use.
  std::vector<std::size_t> alive;
  for (std::size_t i = 0; i < faces.size(); ++i)
    if (faces[i].alive && faces[i].n.squaredNorm() > 0) alive.push_back(i);
  std::vector<bool> done(faces.size(), false);
  std::vector<std::uint32_t> remap(pts.size(), UINT32_MAX), used;
  h.dimension_ = 3;
  for (std::size_t fi : alive) {
    if (done[fi]) continue;
    const Face& f = faces[fi];
    V3 nsum = V3::Zero();
    std::vector<std::uint32_t> group;
    for (std::size_t gi : alive) {
      if (done[gi]) continue;
      const Face& g = faces[gi];
      if (g.n.dot(f.n) <= 0) continue;
      bool coplanar = true;
      for (std::uint32_t vtx : g.v) coplanar = coplanar && std::abs(f.n.dot(pts[vtx]) - f.d) <= tol;
      if (!coplanar) continue;
      done[gi] = true;
      nsum += (pts[g.v[1]] - pts[g.v[0]]).cross(pts[g.v[2]] - pts[g.v[0]]);
      group.insert(group.end(), g.v.begin(), g.v.end());
    }
    const V3 fn = nsum.norm() > 0 ? V3(nsum.normalized()) : f.n;
    V3 u, v;
    basis(fn, u, v);
    const std::vector<std::uint32_t> loop = hull2d(pts, group, u, v, tol);
    if (loop.size() < 3) continue;
    double off = -INFINITY;
    HullFace hf;
    hf.first = static_cast<std::uint32_t>(h.faceVertices_.size());
    hf.count = static_cast<std::uint32_t>(loop.size());
    for (std::uint32_t p : loop) {
      off = std::max(off, fn.dot(pts[p]));
      if (remap[p] == UINT32_MAX) {
        remap[p] = static_cast<std::uint32_t>(used.size());
        used.push_back(p);
      }
      h.faceVertices_.push_back(remap[p]);
    }
    hf.normal = fn.cast<Real>();
    hf.offset = static_cast<Real>(off + fn.dot(origin));
    h.faces_.push_back(hf);
  }
  finish(used);
  return h;
}

namespace {

/// The differences x − x of a shape's core points and axes (finite_lanes.hpp).
geometry_detail::FiniteLanes shapeDifferences(const ConvexShape& shape) {
  return geometry_detail::finiteDifferences(shape.p) + geometry_detail::finiteDifferences(shape.axes);
}

/// A shape's other rules: a finite radius >= 0, box half extents >= 0, a hull with points.
bool shapeRules(const ConvexShape& shape) {
  if (!(shape.radius >= 0 && shape.radius <= std::numeric_limits<Real>::max())) return false;
  if (shape.kind == ConvexKind::Box) return shape.p[1].minCoeff() >= 0;
  if (shape.kind == ConvexKind::Hull) return shape.hull != nullptr && !shape.hull->vertices().empty();
  return true;
}

}  // namespace

bool queryable(const ConvexShape& shape) {
  return geometry_detail::allZero(shapeDifferences(shape)) && shapeRules(shape);
}

namespace detail {

bool queryable(const ShapesAtPoses& q) {
  // queryable(a), (ta), (b), (tb) with one comparison for the finiteness of all of them
  const geometry_detail::FiniteLanes sum = shapeDifferences(q.a) + shapeDifferences(q.b) +
                                           geometry_detail::poseDifferences(q.ta) +
                                           geometry_detail::poseDifferences(q.tb);
  return geometry_detail::allZero(sum) && shapeRules(q.a) && shapeRules(q.b) &&
         geometry_detail::nonZero(q.ta.rotation.coeffs()) && geometry_detail::nonZero(q.tb.rotation.coeffs());
}

}  // namespace detail

}  // namespace crux
