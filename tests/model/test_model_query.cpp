// Tests of src/model/model_query.cpp: every placed-mesh query against the same query run by
// the mesh layer on a copy of the mesh whose VERTICES were moved into world space, on seeded
// random meshes, placements and query shapes in two families:
//  - integer grid: axis-aligned rotations (Euler multiples of 90°) and integer translations,
//    so the world-space copy is exact; every answer must equal the exact CGAL oracle on the
//    world-space triangles (hit/miss exactly, t within rounding);
//  - general position: random rotations and float coordinates; the model answer must equal the
//    world-space answer unless the case lies within the rounding band (kAgreement·scale) of a
//    change of answer, which is then measured (distance margins, or the query grown and shrunk
//    by the band) and must be small, and such cases must be rare.
// Then regression tests for the book's model errata, exactness under quarter turns, world
// bounds, and no heap allocation in the boolean / closest / any queries.

#include <crux/geometry/closest_point.hpp>
#include <crux/geometry/overlap.hpp>
#include <crux/geometry/predicates.hpp>
#include <crux/geometry/raycast.hpp>
#include <crux/model/model_query.hpp>
#include <exact/exact.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <new>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "support/allocation_counter.hpp"  // allocationCount(): queries that must not allocate

namespace crux {
namespace {

constexpr double kEps = double(std::numeric_limits<Real>::epsilon());

/// Width of the rounding band in the general family, relative to the case's coordinate scale
/// S (largest magnitude among world vertices, translation and query). Moving the mesh's
/// vertices into world space rounds each coordinate by ½ulp(S); mapping the query into mesh
/// space, Rᵀ(p - t), rounds p - t (½ulp of 2S), takes R from the quaternion (≈4ε per entry) and
/// sums three products (≈3ε), i.e. at most ≈ (3·4 + 3 + 1)ε·2S ≈ 32εS in world distance.
/// The mesh layer's decisions are exact on the rounded inputs. 64εS is twice that bound.
constexpr double kAgreement = 64 * kEps;

// ---------------------------------------------------------------------------------------------
// Printing (17 significant digits, so a failing case can be pasted back).

std::string str(double x) {
  std::ostringstream os;
  os.precision(17);
  os << x;
  return os.str();
}
std::string str(const Vec3& v) {
  return "Vec3(" + str(double(v.x())) + ", " + str(double(v.y())) + ", " + str(double(v.z())) + ")";
}
std::string str(const Ray& r) { return "Ray{" + str(r.origin) + ", " + str(r.dir) + "}"; }
std::string str(const Segment& s) { return "Segment{" + str(s.start) + ", " + str(s.end) + "}"; }
std::string str(const Triangle& t) { return "Triangle{" + str(t.a) + ", " + str(t.b) + ", " + str(t.c) + "}"; }
std::string str(const Sphere& s) { return "Sphere{" + str(s.center) + ", " + str(double(s.radius)) + "}"; }
std::string str(const Aabb& b) { return "Aabb{" + str(b.min) + ", " + str(b.max) + "}"; }
std::string str(const Plane& p) { return "Plane{" + str(p.normal) + ", " + str(double(p.d)) + "}"; }
std::string str(const Obb& b) {
  return "Obb{" + str(b.center) + ", " + str(b.half) + ", axes " + str(Vec3(b.axes.col(0))) + " " +
         str(Vec3(b.axes.col(1))) + " " + str(Vec3(b.axes.col(2))) + "}";
}
std::string str(const Transform& t) {
  return "Transform{q=(" + str(double(t.rotation.w())) + ", " + str(double(t.rotation.x())) + ", " +
         str(double(t.rotation.y())) + ", " + str(double(t.rotation.z())) + "), " + str(t.translation) + "}";
}
std::string str(const std::optional<MeshRayHit>& h) {
  if (!h) return "miss";
  return "hit t=" + str(double(h->t)) + " triangle " + std::to_string(h->triangle) + " point " + str(h->point) +
         " normal " + str(h->normal);
}
std::string str(const Mesh& m) {
  std::string s = "mesh " + m.name() + " (" + std::to_string(m.triangleCount()) + " triangles):\n";
  for (std::uint32_t i = 0; i < m.triangleCount(); ++i) s += "  " + std::to_string(i) + ": " + str(m.triangle(i)) + "\n";
  return s;
}

// ---------------------------------------------------------------------------------------------
// Random meshes, placements and query shapes.

enum class Family { IntegerGrid, GeneralPosition };
const char* name(Family f) { return f == Family::IntegerGrid ? "integer grid" : "general position"; }
const Family kFamilies[] = {Family::IntegerGrid, Family::GeneralPosition};

class Gen {
 public:
  Gen(Family family, std::uint64_t seed) : family_(family), rng_(seed) {}
  bool integer() const { return family_ == Family::IntegerGrid; }
  int intIn(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }
  Real realIn(double lo, double hi) { return Real(std::uniform_real_distribution<double>(lo, hi)(rng_)); }
  bool chance(double p) { return std::uniform_real_distribution<double>(0, 1)(rng_) < p; }
  /// Integers in [-r, r] per coordinate, or reals in [-r·s, r·s] with s the general family's
  /// unit (general coordinates are not integers).
  Vec3 offset(int r) {
    if (integer()) return Vec3(Real(intIn(-r, r)), Real(intIn(-r, r)), Real(intIn(-r, r)));
    const double s = kUnit * r;
    return Vec3(realIn(-s, s), realIn(-s, s), realIn(-s, s));
  }
  /// A length in [0, r] (integer) or [0, r·s].
  Real length(int r) { return integer() ? Real(intIn(0, r)) : realIn(0, kUnit * r); }
  Quat randomRotation() {
    std::normal_distribution<double> n(0, 1);
    Eigen::Vector4d q(n(rng_), n(rng_), n(rng_), n(rng_));
    q.normalize();
    return Quat(Real(q[0]), Real(q[1]), Real(q[2]), Real(q[3]));
  }
  /// OBB axes: a signed permutation (integer family) or a random rotation.
  Mat3 axes() {
    if (!integer()) return randomRotation().toRotationMatrix();
    int perm[3] = {0, 1, 2};
    std::shuffle(perm, perm + 3, rng_);
    Mat3 m = Mat3::Zero();
    for (int j = 0; j < 3; ++j) m(perm[j], j) = chance(0.5) ? 1 : -1;
    return m;
  }
  static constexpr double kUnit = 0.37;

 private:
  Family family_;
  std::mt19937_64 rng_;
};

/// A small triangle soup: ordinary triangles, degenerate ones (collinear, repeated corner,
/// point; dyadic coordinates in general position so they are exactly degenerate), triangles
/// sharing an edge with an earlier one, and (integer grid) coplanar ones in z = const.
Mesh randomMesh(Gen& g, int count, const std::string& meshName) {
  std::vector<Vec3> v;
  std::vector<TriangleIndices> t;
  auto add = [&](Vec3 a, Vec3 b, Vec3 c) {
    const auto k = std::uint32_t(v.size());
    v.push_back(a), v.push_back(b), v.push_back(c);
    t.push_back({k, k + 1, k + 2});
  };
  auto dyadic = [&](Vec3 p) { return g.integer() ? p : Vec3((p * Real(1024)).array().round() / Real(1024)); };
  const Real planeZ = g.integer() ? Real(g.intIn(-2, 2)) : Real(0);
  while (int(t.size()) < count) {
    const int kind = g.intIn(0, 9);
    if (kind <= 5 || t.empty()) {
      const Vec3 a = g.offset(3);
      add(a, a + g.offset(2), a + g.offset(2));
    } else if (kind == 6) {
      const Vec3 a = dyadic(g.offset(3)), d = dyadic(g.offset(1));
      switch (g.intIn(0, 2)) {
        case 0: add(a, a + d, a + 2 * d); break;
        case 1: add(a, a, a + d); break;
        default: add(a, a, a); break;
      }
    } else if (kind <= 8) {
      const TriangleIndices o = t[std::size_t(g.intIn(0, int(t.size()) - 1))];
      const auto k = std::uint32_t(v.size());
      v.push_back(v[o[0]] + g.offset(2));
      t.push_back({o[1], o[0], k});
    } else if (g.integer()) {
      auto inPlane = [&] { Vec3 p = g.offset(3); p.z() = planeZ; return p; };
      add(inPlane(), inPlane(), inPlane());
    } else {
      const Vec3 a = g.offset(3);
      add(a, a + g.offset(2), a + g.offset(2));
    }
  }
  return Mesh(std::move(v), std::move(t), meshName);
}

/// A model placement and the rotation used to build the world-space copy independently: the
/// exact integer matrix Rz·Ry·Rx of the Euler multiples of 90° (integer grid), or the double
/// rotation of the (normalised) quaternion (general position).
struct Placement {
  Transform world;
  Eigen::Matrix3d rotation;
};

int cos90(int n) { return std::array<int, 4>{1, 0, -1, 0}[std::size_t(((n % 4) + 4) % 4)]; }
int sin90(int n) { return std::array<int, 4>{0, 1, 0, -1}[std::size_t(((n % 4) + 4) % 4)]; }

/// Rz(90k)·Ry(90j)·Rx(90i) with integer arithmetic.
Eigen::Matrix3i quarterTurns(int i, int j, int k) {
  Eigen::Matrix3i rx, ry, rz;
  rx << 1, 0, 0, 0, cos90(i), -sin90(i), 0, sin90(i), cos90(i);
  ry << cos90(j), 0, sin90(j), 0, 1, 0, -sin90(j), 0, cos90(j);
  rz << cos90(k), -sin90(k), 0, sin90(k), cos90(k), 0, 0, 0, 1;
  return rz * ry * rx;
}

Placement axisAlignedPlacement(int i, int j, int k, const Vec3& t) {
  Placement p;
  p.world.rotation = quatFromEulerDegrees(Real(90 * i), Real(90 * j), Real(90 * k));
  p.world.translation = t;
  p.rotation = quarterTurns(i, j, k).cast<double>();
  return p;
}

Placement randomPlacement(Gen& g) {
  if (g.integer()) return axisAlignedPlacement(g.intIn(0, 3), g.intIn(0, 3), g.intIn(0, 3), g.offset(5));
  Placement p;
  p.world.rotation = g.randomRotation();
  p.world.translation = g.offset(6);
  p.rotation = p.world.rotation.cast<double>().normalized().toRotationMatrix();
  return p;
}

Vec3 placePoint(const Placement& p, const Vec3& v) {
  return (p.rotation * v.cast<double>() + p.world.translation.cast<double>()).cast<Real>();
}

/// The mesh with its vertices moved into world space (exact on the integer grid).
Mesh worldCopy(const Mesh& m, const Placement& p) {
  std::vector<Vec3> v;
  for (const Vec3& x : m.vertices()) v.push_back(placePoint(p, x));
  return Mesh(v, m.triangles(), m.name() + " in world space");
}

Real absMax(const Vec3& v) { return v.cwiseAbs().maxCoeff(); }
double maxAbs(const Aabb& b) { return std::max(double(absMax(b.min)), double(absMax(b.max))); }

/// Query shapes near the placed model: centred on its translation, spread so that about half
/// the queries touch the mesh.
Sphere randomSphere(Gen& g, const Placement& p, const Mesh&) {
  return {p.world.translation + g.offset(4), g.integer() ? Real(g.intIn(0, 3)) : g.realIn(0, 0.9)};
}
Aabb randomAabb(Gen& g, const Placement& p, const Mesh&) {
  const Vec3 c = p.world.translation + g.offset(4);
  const Vec3 h(g.length(2), g.length(2), g.length(2));
  return {c - h, c + h};
}
Obb randomObb(Gen& g, const Placement& p, const Mesh&) {
  Obb b;
  b.center = p.world.translation + g.offset(4);
  b.half = Vec3(g.length(2), g.length(2), g.length(2));
  b.axes = g.axes();
  return b;
}
Plane randomPlane(Gen& g, const Placement& p, const Mesh&) {
  Plane pl;
  do {
    pl.normal = g.integer() ? g.offset(2) : Vec3(g.realIn(-1, 1), g.realIn(-1, 1), g.realIn(-1, 1));
  } while (pl.normal.isZero(0));
  const Vec3 through = p.world.translation + g.offset(6);
  pl.d = Real(pl.normal.cast<double>().dot(through.cast<double>()));
  return pl;
}
/// A point near the world-space mesh: a corner of a random triangle moved by up to one unit
/// (integer grid), or a random point of a random triangle moved a little (general position).
Vec3 nearMesh(Gen& g, const Mesh& world) {
  const Triangle t = world.triangle(std::uint32_t(g.intIn(0, int(world.triangleCount()) - 1)));
  if (g.integer()) return t[g.intIn(0, 2)] + g.offset(1);
  Real u = g.realIn(0, 1), v = g.realIn(0, 1);
  if (u + v > 1) u = 1 - u, v = 1 - v;
  return t.a + (t.b - t.a) * u + (t.c - t.a) * v + g.offset(1) * Real(0.3);
}
/// Half the segments pass through (or end at) a point near the mesh.
Segment randomSegment(Gen& g, const Placement& p, const Mesh& world) {
  const Vec3 a = p.world.translation + g.offset(4);
  if (g.chance(0.5)) return {a, p.world.translation + g.offset(4)};
  const Vec3 target = nearMesh(g, world);
  return {a, g.chance(0.5) ? target : Vec3(2 * target - a)};
}
Triangle randomTriangle(Gen& g, const Placement& p, const Mesh&) {
  const Vec3 t = p.world.translation;
  return {t + g.offset(4), t + g.offset(4), t + g.offset(4)};
}
/// Half the rays are aimed at a point near the mesh.
Ray randomRay(Gen& g, const Placement& p, const Mesh& world) {
  Ray r;
  r.origin = p.world.translation + g.offset(6);
  do {
    r.dir = g.chance(0.5) ? Vec3(nearMesh(g, world) - r.origin) : Vec3((p.world.translation + g.offset(3)) - r.origin);
  } while (r.dir.isZero(0));
  return r;
}

/// Scale of a query shape's coordinates (for the rounding band).
double scaleOf(const Sphere& s) { return absMax(s.center) + s.radius; }
double scaleOf(const Aabb& b) { return maxAbs(b); }
double scaleOf(const Obb& b) { return absMax(b.center) + b.half.sum(); }
double scaleOf(const Plane& p) { return std::fabs(double(p.d)) / p.normal.cast<double>().norm(); }
double scaleOf(const Segment& s) { return std::max(absMax(s.start), absMax(s.end)); }
double scaleOf(const Triangle& t) { return std::max({absMax(t.a), absMax(t.b), absMax(t.c)}); }
double scaleOf(const Ray& r) { return absMax(r.origin); }

// ---------------------------------------------------------------------------------------------
// Margins: how far a general-position case is from a change of answer (computed in long double
// or by the exact oracle, so they resolve distances far below the rounding band).

using LVec = Eigen::Matrix<long double, 3, 1>;
LVec ld(const Vec3& v) { return v.cast<long double>(); }

/// Distance between segments [p1, q1] and [p2, q2] (RTCD 5.1.9, with the degenerate cases).
long double segmentDistance(const Vec3& p1_, const Vec3& q1_, const Vec3& p2_, const Vec3& q2_) {
  const LVec p1 = ld(p1_), p2 = ld(p2_), d1 = ld(q1_) - p1, d2 = ld(q2_) - p2, r = p1 - p2;
  const long double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  long double s = 0, t = 0;
  auto clamp01 = [](long double x) { return std::min<long double>(1, std::max<long double>(0, x)); };
  if (a == 0 && e == 0) return r.norm();
  if (a == 0) {
    t = clamp01(f / e);
  } else {
    const long double c = d1.dot(r);
    if (e == 0) {
      s = clamp01(-c / a);
    } else {
      const long double b = d1.dot(d2), denom = a * e - b * b;
      s = denom > 0 ? clamp01((b * f - c * e) / denom) : 0;
      t = (b * s + f) / e;
      if (t < 0) t = 0, s = clamp01(-c / a);
      else if (t > 1) t = 1, s = clamp01((b - c) / a);
    }
  }
  return ((p1 + d1 * s) - (p2 + d2 * t)).norm();
}

/// Distance from p to the closed triangle (RTCD 5.1.5 in long double; an exactly degenerate
/// triangle is the union of its edges).
long double pointTriangleDistance(const Vec3& p_, const Triangle& t) {
  const LVec p = ld(p_), a = ld(t.a), b = ld(t.b), c = ld(t.c);
  const LVec ab = b - a, ac = c - a;
  if (ab.cross(ac).isZero(0)) {
    long double m = std::numeric_limits<long double>::infinity();
    for (int i = 0; i < 3; ++i) m = std::min(m, segmentDistance(p_, p_, t[i], t[(i + 1) % 3]));
    return m;
  }
  const LVec ap = p - a;
  const long double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return (p - a).norm();
  const LVec bp = p - b;
  const long double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return (p - b).norm();
  const long double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + ab * (d1 / (d1 - d3)))).norm();
  const LVec cp = p - c;
  const long double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return (p - c).norm();
  const long double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + ac * (d2 / (d2 - d6)))).norm();
  const long double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return (p - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))))).norm();
  const long double denom = 1 / (va + vb + vc);
  return (p - (a + ab * (vb * denom) + ac * (vc * denom))).norm();
}

/// Distance from a segment to a triangle's boundary-and-corners structure: the answers of
/// segment–triangle tests change only when an end point crosses the triangle or the segment
/// crosses one of its edges.
long double segmentMargin(const Vec3& a, const Vec3& b, const Triangle& t) {
  long double m = std::min(pointTriangleDistance(a, t), pointTriangleDistance(b, t));
  for (int i = 0; i < 3; ++i) m = std::min(m, segmentDistance(a, b, t[i], t[(i + 1) % 3]));
  return m;
}

long double triangleMargin(const Triangle& q, const Triangle& t) {
  long double m = std::numeric_limits<long double>::infinity();
  for (int i = 0; i < 3; ++i) {
    m = std::min(m, segmentMargin(q[i], q[(i + 1) % 3], t));
    m = std::min(m, segmentMargin(t[i], t[(i + 1) % 3], q));
  }
  return m;
}

// ---------------------------------------------------------------------------------------------
// Hit-rate bookkeeping.

struct Rate {
  int hits = 0, cases = 0, nearBand = 0, geometryDefects = 0;
  void add(bool hit) { hits += hit, ++cases; }
  double value() const { return cases ? double(hits) / cases : 0; }
};
void expectMeaningful(const Rate& r, const std::string& what) {
  std::printf("%-44s %6d cases, hit rate %.2f, %d within the rounding band, %d geometry-layer defects\n",
              what.c_str(), r.cases, r.value(), r.nearBand, r.geometryDefects);
  EXPECT_GE(r.value(), 0.2) << what;
  EXPECT_LE(r.value(), 0.8) << what;
  // Cases near a change of answer must stay rare, or agreement would prove little.
  EXPECT_LE(r.nearBand, r.cases / 100 + 1) << what;
  // Geometry-layer defects found here (sliver triangle–sphere, collinear triangle–OBB) were
  // fixed and have regression tests in tests/geometry/test_triangle_overlap.cpp: any new one fails.
  EXPECT_EQ(r.geometryDefects, 0) << what;
}

constexpr int kPlacements = 300;  // per family
constexpr int kQueriesPerPlacement = 20;
constexpr int kTrianglesPerMesh = 12;

// ---------------------------------------------------------------------------------------------
// Property tests: boolean shape queries.

// ---- Attributing a disagreement: model layer or geometry layer ----------------------------------
// The general family compares two computations that both end in the geometry layer's
// per-triangle tests. When they disagree outside the rounding band, the exact oracle decides
// which one is wrong: if the model agrees with the oracle on the world-space copy, the copy's
// answer was wrong; otherwise the query is mapped into mesh space by the test itself (long
// double, rounded once) and the geometry layer is compared with the oracle triangle by
// triangle there. A per-triangle mismatch on either side is a geometry-layer defect, printed
// (GEOMETRY-LAYER DEFECT) and counted; a disagreement with no such mismatch fails the test as
// a model-layer error.

/// The test's own world -> mesh mapping, in long double and rounded once.
struct MeshFrame {
  Eigen::Matrix<long double, 3, 3> r;
  LVec t;
  explicit MeshFrame(const Placement& p)
      : r(p.world.rotation.cast<long double>().normalized().toRotationMatrix()), t(ld(p.world.translation)) {}
  Vec3 point(const Vec3& x) const { return (r.transpose() * (ld(x) - t)).cast<Real>(); }
  Vec3 vector(const Vec3& v) const { return (r.transpose() * ld(v)).cast<Real>(); }
  Mat3 axes(const Mat3& a) const { return (r.transpose() * a.cast<long double>()).cast<Real>(); }
  Real planeD(const Plane& p) const { return Real((long double)p.d - ld(p.normal).dot(t)); }
};

/// The same mapping evaluated in Real the way model_query.hpp documents it (R from the
/// quaternion, Rᵀ(p - t)). A geometry-layer defect near a degenerate configuration can depend
/// on the last bits of the mapped shape, so both mappings are tried when attributing one.
struct RealFrame {
  Mat3 r;
  Vec3 t;
  explicit RealFrame(const Placement& p) : r(p.world.rotation.toRotationMatrix()), t(p.world.translation) {}
  Vec3 point(const Vec3& x) const { return r.transpose() * (x - t); }
  Vec3 vector(const Vec3& v) const { return r.transpose() * v; }
  Mat3 axes(const Mat3& a) const { return r.transpose() * a; }
  Real planeD(const Plane& p) const { return Real(Wide(p.d) - wide(p.normal).dot(wide(t))); }
};

/// The first triangle of `m` on which the geometry layer and the oracle disagree, or "".
template <class Shape, class Crux, class Exact>
std::string firstDefect(const Mesh& m, const Shape& s, Crux crux, Exact exact) {
  for (std::uint32_t i = 0; i < m.triangleCount(); ++i) {
    const Triangle t = m.triangle(i);
    const bool c = crux(t, s), e = exact(t, s);
    if (c != e)
      return "triangle " + std::to_string(i) + " " + str(t) + " vs " + str(s) + ": geometry layer " +
             (c ? "touch" : "apart") + ", exact " + (e ? "touch" : "apart");
  }
  return "";
}
/// The geometry layer's per-triangle decision of each mesh query.
bool cruxTriangle(const Triangle& t, const Segment& s) { return intersects(s, t); }
template <class Shape>
bool cruxTriangle(const Triangle& t, const Shape& s) {
  return overlaps(t, s);
}
const auto kCruxOverlap = [](const Triangle& t, const auto& s) { return overlaps(t, s); };
const auto kExactOverlap = [](const Triangle& t, const auto& s) { return exact::overlaps(t, s); };

template <class Frame>
std::string meshSpaceDefect(const Mesh& m, const Frame& f, const Sphere& s) {
  return firstDefect(m, Sphere{f.point(s.center), s.radius}, kCruxOverlap, kExactOverlap);
}
template <class Frame>
std::string meshSpaceDefect(const Mesh& m, const Frame& f, const Aabb& b) {
  return firstDefect(m, Obb{f.point(b.center()), b.half(), f.axes(Mat3::Identity())}, kCruxOverlap, kExactOverlap);
}
template <class Frame>
std::string meshSpaceDefect(const Mesh& m, const Frame& f, const Obb& b) {
  return firstDefect(m, Obb{f.point(b.center), b.half, f.axes(b.axes)}, kCruxOverlap, kExactOverlap);
}
template <class Frame>
std::string meshSpaceDefect(const Mesh& m, const Frame& f, const Plane& p) {
  return firstDefect(m, Plane{f.vector(p.normal), f.planeD(p)}, kCruxOverlap, kExactOverlap);
}
template <class Frame>
std::string meshSpaceDefect(const Mesh& m, const Frame& f, const Triangle& q) {
  return firstDefect(m, Triangle{f.point(q.a), f.point(q.b), f.point(q.c)}, kCruxOverlap, kExactOverlap);
}
template <class Frame>
std::string meshSpaceDefect(const Mesh& m, const Frame& f, const Segment& s) {
  return firstDefect(
      m, Segment{f.point(s.start), f.point(s.end)}, [](const Triangle& t, const Segment& x) { return intersects(x, t); },
      [](const Triangle& t, const Segment& x) { return exact::intersects(x, t); });
}

/// A geometry-layer defect in mesh space under either mapping, or "".
template <class Shape>
std::string meshSpaceDefectEitherMapping(const Mesh& m, const Placement& p, const Shape& s) {
  const std::string real = meshSpaceDefect(m, RealFrame(p), s);
  return real.empty() ? meshSpaceDefect(m, MeshFrame(p), s) : real;
}

/// One boolean query kind: the model answer vs the world-space copy (both families) and vs the
/// exact oracle on the world-space triangles (integer grid). `nearBand(worldMesh, shape, band)`
/// says whether a general-position case lies within `band` of a change of answer.
template <class Shape, class Make, class ModelQuery, class MeshQuery, class ExactTriangle, class NearBand>
void checkShape(const std::string& what, std::uint64_t seed, Make make, ModelQuery modelQuery, MeshQuery meshQuery,
                ExactTriangle exactTriangle, NearBand nearBand) {
  for (Family f : kFamilies) {
    Rate rate;
    for (int k = 0; k < kPlacements; ++k) {
      Gen g(f, seed + 7919 * std::uint64_t(f == Family::GeneralPosition) + std::uint64_t(k));
      const Mesh mesh = randomMesh(g, kTrianglesPerMesh, "model");
      const Placement p = randomPlacement(g);
      const Mesh world = worldCopy(mesh, p);
      const PlacedMesh placed{&mesh, p.world};
      for (int q = 0; q < kQueriesPerPlacement; ++q) {
        const Shape s = make(g, p, world);
        const bool model = modelQuery(placed, s);
        const bool copy = meshQuery(world, s);
        auto ctx = [&] {
          return what + " (" + name(f) + ") " + str(s) + " placed by " + str(p.world) + "\n" + str(mesh) + str(world);
        };
        auto exactOnCopy = [&] {
          bool exact = false;
          for (std::uint32_t i = 0; i < world.triangleCount() && !exact; ++i) exact = exactTriangle(world.triangle(i), s);
          return exact;
        };
        if (f == Family::IntegerGrid) {
          const bool exact = exactOnCopy();
          rate.add(exact);
          ASSERT_EQ(model, exact) << "model query vs the exact oracle: " << ctx();
          ASSERT_EQ(copy, exact) << "world-space copy vs the exact oracle: " << ctx();
          continue;
        }
        rate.add(copy);
        const double band = kAgreement * std::max({maxAbs(world.bounds()), double(absMax(p.world.translation)), scaleOf(s)});
        const bool near = nearBand(world, s, band);
        rate.nearBand += near;
        if (near || model == copy) continue;
        const bool exact = exactOnCopy();
        const std::string defect =
            model == exact ? firstDefect(world, s, [](const Triangle& t, const Shape& x) { return cruxTriangle(t, x); },
                                         exactTriangle)
                           : meshSpaceDefectEitherMapping(mesh, p, s);
        ASSERT_FALSE(defect.empty()) << "model query vs the world-space copy, outside the rounding band " << str(band)
                                     << " (exact on the copy: " << exact << "): " << ctx();
        ++rate.geometryDefects;
        std::printf("GEOMETRY-LAYER DEFECT (%s; the model layer is not at fault): %s\n  case: %s placed by %s\n",
                    model == exact ? "on the world-space copy" : "in mesh space", defect.c_str(), str(s).c_str(),
                    str(p.world).c_str());
      }
    }
    expectMeaningful(rate, what + " (" + name(f) + ")");
  }
}

/// Near-band test by growing and shrinking a solid query by the band: if both give the same
/// answer on the world-space copy, every shape between them (the model's rounded view of the
/// query included) has that answer too.
template <class Shape, class Grow>
bool solidNearBand(const Mesh& world, const Shape& s, double band, Grow grow) {
  const std::optional<Shape> bigger = grow(s, band);
  const std::optional<Shape> smaller = grow(s, -band);
  const bool outer = overlaps(world, *bigger);
  const bool inner = smaller ? overlaps(world, *smaller) : false;
  return outer != inner;
}

TEST(ModelQueryProperty, SphereMatchesTheWorldSpaceCopyAndTheOracle) {
  checkShape<Sphere>(
      "sphere", 0x5A1, randomSphere, [](const PlacedMesh& m, const Sphere& s) { return overlaps(m, s); },
      [](const Mesh& m, const Sphere& s) { return overlaps(m, s); },
      [](const Triangle& t, const Sphere& s) { return exact::overlaps(t, s); },
      [](const Mesh& world, const Sphere& s, double band) {
        long double d = std::numeric_limits<long double>::infinity();
        for (std::uint32_t i = 0; i < world.triangleCount(); ++i)
          d = std::min(d, pointTriangleDistance(s.center, world.triangle(i)));
        return std::fabs(d - (long double)s.radius) <= band;
      });
}

TEST(ModelQueryProperty, AabbMatchesTheWorldSpaceCopyAndTheOracle) {
  checkShape<Aabb>(
      "aabb", 0x5A2, randomAabb, [](const PlacedMesh& m, const Aabb& b) { return overlaps(m, b); },
      [](const Mesh& m, const Aabb& b) { return overlaps(m, b); },
      [](const Triangle& t, const Aabb& b) { return exact::overlaps(t, b); },
      [](const Mesh& world, const Aabb& b, double band) {
        return solidNearBand(world, b, band, [](const Aabb& x, double by) -> std::optional<Aabb> {
          const Aabb y{x.min - Vec3::Constant(Real(by)), x.max + Vec3::Constant(Real(by))};
          if (y.isEmpty()) return std::nullopt;
          return y;
        });
      });
}

TEST(ModelQueryProperty, ObbMatchesTheWorldSpaceCopyAndTheOracle) {
  checkShape<Obb>(
      "obb", 0x5A3, randomObb, [](const PlacedMesh& m, const Obb& b) { return overlaps(m, b); },
      [](const Mesh& m, const Obb& b) { return overlaps(m, b); },
      [](const Triangle& t, const Obb& b) { return exact::overlaps(t, b); },
      [](const Mesh& world, const Obb& b, double band) {
        return solidNearBand(world, b, band, [](const Obb& x, double by) -> std::optional<Obb> {
          Obb y = x;
          y.half = x.half + Vec3::Constant(Real(by));
          if ((y.half.array() < 0).any()) return std::nullopt;
          return y;
        });
      });
}

TEST(ModelQueryProperty, PlaneMatchesTheWorldSpaceCopyAndTheOracle) {
  checkShape<Plane>(
      "plane", 0x5A4, randomPlane, [](const PlacedMesh& m, const Plane& p) { return overlaps(m, p); },
      [](const Mesh& m, const Plane& p) { return overlaps(m, p); },
      [](const Triangle& t, const Plane& p) { return exact::overlaps(t, p); },
      [](const Mesh& world, const Plane& p, double band) {
        // A triangle–plane answer changes only when a corner crosses the plane.
        const LVec n = ld(p.normal);
        for (const Vec3& v : world.vertices())
          if (std::fabs(n.dot(ld(v)) - (long double)p.d) / n.norm() <= band) return true;
        return false;
      });
}

TEST(ModelQueryProperty, SegmentMatchesTheWorldSpaceCopyAndTheOracle) {
  checkShape<Segment>(
      "segment", 0x5A5, randomSegment, [](const PlacedMesh& m, const Segment& s) { return intersects(m, s); },
      [](const Mesh& m, const Segment& s) { return intersects(m, s); },
      [](const Triangle& t, const Segment& s) { return exact::intersects(s, t); },
      [](const Mesh& world, const Segment& s, double band) {
        for (std::uint32_t i = 0; i < world.triangleCount(); ++i)
          if (segmentMargin(s.start, s.end, world.triangle(i)) <= band) return true;
        return false;
      });
}

TEST(ModelQueryProperty, TriangleMatchesTheWorldSpaceCopyAndTheOracle) {
  checkShape<Triangle>(
      "triangle", 0x5A6, randomTriangle, [](const PlacedMesh& m, const Triangle& t) { return overlaps(m, t); },
      [](const Mesh& m, const Triangle& t) { return overlaps(m, t); },
      [](const Triangle& t, const Triangle& q) { return exact::overlaps(t, q); },
      [](const Mesh& world, const Triangle& q, double band) {
        for (std::uint32_t i = 0; i < world.triangleCount(); ++i)
          if (triangleMargin(q, world.triangle(i)) <= band) return true;
        return false;
      });
}

// ---------------------------------------------------------------------------------------------
// Property tests: rays.

/// Unit normal of a (non-degenerate) triangle in double.
Eigen::Vector3d unitNormal(const Triangle& t) {
  const Eigen::Vector3d a = t.a.cast<double>();
  return (t.b.cast<double>() - a).cross(t.c.cast<double>() - a).normalized();
}

/// How far a ray is from changing which triangles it hits: its origin's distance to the
/// triangles and its distance (as a long segment) to their edges.
long double rayMargin(const Mesh& world, const Ray& r) {
  const Vec3 far = r.origin + r.dir * Real(1000 / r.dir.norm());
  long double m = std::numeric_limits<long double>::infinity();
  for (std::uint32_t i = 0; i < world.triangleCount(); ++i) m = std::min(m, segmentMargin(r.origin, far, world.triangle(i)));
  return m;
}

TEST(ModelQueryProperty, RaysMatchTheWorldSpaceCopyAndTheOracle) {
  for (Family f : kFamilies) {
    Rate rate;
    for (int k = 0; k < kPlacements; ++k) {
      Gen g(f, 0x7A1 + 7919 * std::uint64_t(f == Family::GeneralPosition) + std::uint64_t(k));
      const Mesh mesh = randomMesh(g, kTrianglesPerMesh, "model");
      const Placement p = randomPlacement(g);
      const Mesh world = worldCopy(mesh, p);
      const PlacedMesh placed{&mesh, p.world};
      for (int q = 0; q < kQueriesPerPlacement; ++q) {
        const Ray r = randomRay(g, p, world);
        const std::optional<MeshRayHit> model = raycastClosest(placed, r);
        const std::optional<MeshRayHit> copy = raycastClosest(world, r);
        const std::vector<MeshRayHit> all = raycastAll(placed, r);
        auto ctx = [&] {
          return std::string(name(f)) + " " + str(r) + " placed by " + str(p.world) + "\nmodel " + str(model) +
                 "\ncopy " + str(copy) + "\n" + str(mesh) + str(world);
        };
        ASSERT_EQ(raycastAny(placed, r), model.has_value()) << ctx();
        ASSERT_EQ(all.empty(), !model.has_value()) << ctx();
        if (model) {
          ASSERT_EQ(all.front().t, model->t) << ctx();
          ASSERT_EQ(all.front().triangle, model->triangle) << ctx();
        }
        const double dirNorm = r.dir.cast<double>().norm();
        if (f == Family::IntegerGrid) {
          // Exact first hit over the world-space triangles.
          std::optional<double> best;
          std::size_t hitCount = 0;
          for (std::uint32_t i = 0; i < world.triangleCount(); ++i)
            if (const std::optional<double> e = exact::raycast(r, world.triangle(i))) {
              ++hitCount;
              if (!best || *e < *best) best = e;
            }
          rate.add(best.has_value());
          ASSERT_EQ(model.has_value(), best.has_value()) << "vs the exact oracle: " << ctx();
          ASSERT_EQ(all.size(), hitCount) << "raycastAll vs the exact oracle: " << ctx();
          if (!model) continue;
          // t is rounded after an exact decision: within 64ε of the ray's scale, as in the mesh
          // layer's tests; the point lies on the ray at t; the normal is the world-space
          // triangle's, facing the origin.
          const double scale = std::max(1.0, double(absMax(r.origin)) + *best);
          ASSERT_NEAR(double(model->t), *best, 64 * kEps * scale) << ctx();
          const std::optional<double> reported = exact::raycast(r, world.triangle(model->triangle));
          ASSERT_TRUE(reported.has_value()) << ctx();
          ASSERT_NEAR(*reported, *best, 64 * kEps * scale) << "not the nearest triangle: " << ctx();
          const Eigen::Vector3d onRay = r.origin.cast<double>() + r.dir.cast<double>() * (*best / dirNorm);
          ASSERT_LE((model->point.cast<double>() - onRay).norm(), 64 * kEps * scale) << ctx();
          const Triangle wt = world.triangle(model->triangle);
          if (predicates::classify(wt).kind != predicates::TriangleKind::Triangle) continue;
          const Eigen::Vector3d n = unitNormal(wt);
          const Eigen::Vector3d facing = n.dot(r.dir.cast<double>()) > 0 ? Eigen::Vector3d(-n) : n;
          const Eigen::Vector3d a = wt.a.cast<double>();  // exact integer normal for the edge-on test
          if ((wt.b.cast<double>() - a).cross(wt.c.cast<double>() - a).dot(r.dir.cast<double>()) != 0) {
            ASSERT_LE((model->normal.cast<double>() - facing).norm(), 16 * kEps) << ctx();
          }
        } else {
          rate.add(copy.has_value());
          const double band =
              kAgreement * std::max({maxAbs(world.bounds()), double(absMax(p.world.translation)), scaleOf(r)});
          if (rayMargin(world, r) <= band) {
            ++rate.nearBand;
            continue;
          }
          ASSERT_EQ(model.has_value(), copy.has_value()) << "outside the band " << str(band) << ": " << ctx();
          const std::vector<MeshRayHit> allCopy = raycastAll(world, r);
          ASSERT_EQ(all.size(), allCopy.size()) << ctx();
          if (!model) continue;
          // Same first triangle unless two hits tie within the band; t moves by at most
          // band / |cos| where cos is the angle between the ray and the triangle's normal.
          const Triangle wt = world.triangle(copy->triangle);
          const double cosine = std::fabs(unitNormal(wt).dot(r.dir.cast<double>() / dirNorm));
          const double tTolerance = band / std::max(cosine, 1e-300) + band;
          ASSERT_LE(std::fabs(double(model->t) - double(copy->t)), tTolerance) << ctx();
          ASSERT_LE((model->point - copy->point).cast<double>().norm(), 2 * tTolerance) << ctx();
          if (model->triangle == copy->triangle) {
            // The unit normal of a triangle whose corners move by `band` turns by at most
            // 2·band·(|e1| + |e2|) / |e1 × e2| (plus the rotation's few ulps).
            const Eigen::Vector3d e1 = (wt.b - wt.a).cast<double>(), e2 = (wt.c - wt.a).cast<double>();
            const double turn = 2 * band * (e1.norm() + e2.norm()) / e1.cross(e2).norm() + 16 * kEps;
            ASSERT_LE((model->normal - copy->normal).cast<double>().norm(), 2 * turn) << ctx();
          }
          for (std::size_t i = 0; i < all.size(); ++i) {
            const Triangle ti = world.triangle(allCopy[i].triangle);
            const double c = std::fabs(unitNormal(ti).dot(r.dir.cast<double>() / dirNorm));
            ASSERT_LE(std::fabs(double(all[i].t) - double(allCopy[i].t)), band / std::max(c, 1e-300) + band) << ctx();
          }
        }
      }
    }
    expectMeaningful(rate, std::string("ray (") + name(f) + ")");
  }
}

// ---------------------------------------------------------------------------------------------
// Property tests: model vs model.

/// Whether the relative rotation of two axis-aligned rotations is an even signed permutation
/// (quaternion components in {0, ±½, ±1}), for which the mesh layer maps exactly.
bool evenPermutation(const Eigen::Matrix3d& r) {
  int perm[3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (r(i, j) != 0) perm[i] = j;
  int inversions = (perm[0] > perm[1]) + (perm[0] > perm[2]) + (perm[1] > perm[2]);
  return inversions % 2 == 0;
}

TEST(ModelQueryProperty, ModelVsModelMatchesTheWorldSpaceCopiesAndTheOracle) {
  constexpr int kPairs = 2000;
  for (Family f : kFamilies) {
    Rate rate;
    for (int k = 0; k < kPairs; ++k) {
      Gen g(f, 0x3E5 + 7919 * std::uint64_t(f == Family::GeneralPosition) + std::uint64_t(k));
      const Mesh a = randomMesh(g, 10, "a");
      const Mesh b = randomMesh(g, 10, "b");
      const Placement pa = randomPlacement(g);
      Placement pb = randomPlacement(g);
      if (g.integer()) {
        // Keep b near a, and the relative rotation even (the mesh layer is exact there).
        while (!evenPermutation(pa.rotation.transpose() * pb.rotation)) pb = randomPlacement(g);
        pb.world.translation = pa.world.translation + g.offset(4);
      } else {
        pb.world.translation = pa.world.translation + g.offset(4);
      }
      const Mesh wa = worldCopy(a, pa), wb = worldCopy(b, pb);
      const bool model = overlaps(PlacedMesh{&a, pa.world}, PlacedMesh{&b, pb.world});
      const bool copy = overlaps(wa, Transform::identity(), wb, Transform::identity());
      auto ctx = [&] {
        return std::string(name(f)) + " a placed by " + str(pa.world) + ", b by " + str(pb.world) + "\n" + str(a) +
               str(b) + str(wa) + str(wb);
      };
      if (f == Family::IntegerGrid) {
        bool exact = false;
        for (std::uint32_t i = 0; i < wa.triangleCount() && !exact; ++i)
          for (std::uint32_t j = 0; j < wb.triangleCount() && !exact; ++j)
            exact = exact::overlaps(wa.triangle(i), wb.triangle(j));
        rate.add(exact);
        ASSERT_EQ(model, exact) << "model vs model against the exact oracle: " << ctx();
        ASSERT_EQ(copy, exact) << ctx();
      } else {
        rate.add(copy);
        if (model == copy) continue;
        // Disagreement: allowed only within the rounding band (where it is counted).
        const double band = kAgreement * std::max({maxAbs(wa.bounds()), maxAbs(wb.bounds()),
                                                   double(absMax(pa.world.translation)),
                                                   double(absMax(pb.world.translation))});
        long double margin = std::numeric_limits<long double>::infinity();
        for (std::uint32_t i = 0; i < wa.triangleCount(); ++i)
          for (std::uint32_t j = 0; j < wb.triangleCount(); ++j)
            margin = std::min(margin, triangleMargin(wa.triangle(i), wb.triangle(j)));
        ASSERT_LE(double(margin), band) << "model vs model disagrees outside the band: " << ctx();
        ++rate.nearBand;
      }
    }
    expectMeaningful(rate, std::string("model vs model (") + name(f) + ")");
  }
}

// ---------------------------------------------------------------------------------------------
// World bounds.

TEST(ModelBounds, WorldBoundsAndObbContainEveryWorldVertexAndAreTight) {
  for (Family f : kFamilies) {
    for (int k = 0; k < 500; ++k) {
      Gen g(f, 0xB0 + 7919 * std::uint64_t(f == Family::GeneralPosition) + std::uint64_t(k));
      const Mesh mesh = randomMesh(g, kTrianglesPerMesh, "model");
      const Placement p = randomPlacement(g);
      const PlacedMesh placed{&mesh, p.world};
      const Aabb box = worldBounds(placed);
      const Obb obb = worldObb(placed);
      // Exact world box of the vertices (long double; exact on the integer grid).
      Eigen::Matrix<long double, 3, 1> lo = LVec::Constant(INFINITY), hi = LVec::Constant(-INFINITY);
      const Eigen::Matrix<long double, 3, 3> r = p.rotation.cast<long double>();
      for (const Vec3& v : mesh.vertices()) {
        const LVec w = r * ld(v) + ld(p.world.translation);
        lo = lo.cwiseMin(w), hi = hi.cwiseMax(w);
        for (int i = 0; i < 3; ++i) {
          ASSERT_LE((long double)box.min[i], w[i]) << str(p.world);
          ASSERT_GE((long double)box.max[i], w[i]) << str(p.world);
        }
        const LVec local = obb.axes.cast<long double>().transpose() * (w - ld(obb.center));
        for (int i = 0; i < 3; ++i) ASSERT_LE(std::fabs(local[i]), (long double)obb.half[i]) << str(p.world);
      }
      if (f == Family::IntegerGrid) {
        // Axis-aligned rotation, integer translation: the exact box.
        ASSERT_EQ(box.min.cast<long double>(), lo) << str(p.world);
        ASSERT_EQ(box.max.cast<long double>(), hi) << str(p.world);
      } else {
        // Padded by kWorldBoundsPad·scale, and the mesh's local box is not tight after rotation,
        // so compare with the rotated local box (RTCD 4.2.6) rather than the vertices.
        const Aabb lb = mesh.bounds();
        const LVec c = r * ((ld(lb.min) + ld(lb.max)) / 2) + ld(p.world.translation);
        const LVec e = r.cwiseAbs() * ((ld(lb.max) - ld(lb.min)) / 2);
        const long double pad = 2 * (long double)kWorldBoundsPad * (maxAbs(lb) + absMax(p.world.translation));
        for (int i = 0; i < 3; ++i) {
          ASSERT_GE((long double)box.min[i], c[i] - e[i] - pad) << str(p.world);
          ASSERT_LE((long double)box.max[i], c[i] + e[i] + pad) << str(p.world);
        }
      }
    }
  }
}

TEST(ModelBounds, AxisAlignedRotationGivesTheExactImageOfTheLocalBox) {
  // Box [0,1]×[0,2]×[0,3] turned 90° about z ((x, y, z) -> (-y, x, z)) and moved by (10, 0, 0):
  // [8, 10]×[0, 1]×[0, 3].
  const Mesh m({Vec3(0, 0, 0), Vec3(1, 2, 3), Vec3(1, 0, 3)}, {{0, 1, 2}}, "box corners");
  const PlacedMesh placed{&m, {quatFromEulerDegrees(0, 0, 90), Vec3(10, 0, 0)}};
  const Aabb b = worldBounds(placed);
  EXPECT_EQ(b.min, Vec3(8, 0, 0));
  EXPECT_EQ(b.max, Vec3(10, 1, 3));
  const Obb o = worldObb(placed);
  EXPECT_EQ(o.center, Vec3(9, Real(0.5), Real(1.5)));
  EXPECT_EQ(o.half, Vec3(Real(0.5), 1, Real(1.5)));
  EXPECT_EQ(o.axes.col(0), Vec3(0, 1, 0));
}

TEST(ModelBounds, ZeroSizeMeshIsAPoint) {
  const Mesh m({Vec3(1, 2, 3)}, {{0, 0, 0}}, "point");
  const PlacedMesh placed{&m, {quatFromEulerDegrees(90, 0, 0), Vec3(5, 5, 5)}};
  // (1, 2, 3) turned 90° about x is (1, -3, 2); moved: (6, 2, 7).
  const Aabb b = worldBounds(placed);
  EXPECT_EQ(b.min, Vec3(6, 2, 7));
  EXPECT_EQ(b.max, Vec3(6, 2, 7));
  EXPECT_TRUE(overlaps(placed, Sphere{Vec3(6, 2, 8), 1}));
  EXPECT_FALSE(overlaps(placed, Sphere{Vec3(6, 2, 9), 1}));
  EXPECT_TRUE(intersects(placed, Segment{Vec3(6, 0, 7), Vec3(6, 4, 7)}));
}

// ---------------------------------------------------------------------------------------------
// Regression tests: the book's model errata.

/// Triangle (-1,-1,0), (1,-1,0), (0,1,0): in the z = 0 plane of mesh space.
Mesh flatTriangle() { return Mesh({Vec3(-1, -1, 0), Vec3(1, -1, 0), Vec3(0, 1, 0)}, {{0, 1, 2}}, "flat"); }

TEST(ModelQueryRegression, RayOriginIsMappedAsAPointNotAsADirection) {
  const Mesh m = flatTriangle();
  // Turned 90° about z and moved to (10, 20, 0): the ray straight down onto (10, 20, 0). The
  // book mapped the origin like a direction (no translation): (20, -10, 5) in mesh space, a miss.
  const PlacedMesh placed{&m, {quatFromEulerDegrees(0, 0, 90), Vec3(10, 20, 0)}};
  const Ray down{Vec3(10, 20, 5), Vec3(0, 0, -2)};
  const std::optional<MeshRayHit> h = raycastClosest(placed, down);
  ASSERT_TRUE(h.has_value());
  EXPECT_EQ(h->t, 5) << "t is a world distance (|dir| = 2 does not scale it)";
  EXPECT_EQ(h->point, Vec3(10, 20, 0));
  EXPECT_EQ(h->normal, Vec3(0, 0, 1));
  EXPECT_TRUE(raycastAny(placed, down));
  EXPECT_FALSE(raycastAny(placed, Ray{Vec3(20, -10, 5), Vec3(0, 0, -1)}));
  // max distance in world units.
  RayQueryOptions o;
  o.maxDistance = 5;
  EXPECT_TRUE(raycastAny(placed, down, o));
  o.maxDistance = Real(4.5);
  EXPECT_FALSE(raycastAny(placed, down, o));
  // Back-face culling follows the rotated winding: the front face (+z in mesh space) still faces
  // up after the quarter turn about z, and faces down after a half turn about x.
  RayQueryOptions cull;
  cull.cullBackFaces = true;
  EXPECT_TRUE(raycastAny(placed, down, cull));
  EXPECT_FALSE(raycastAny(placed, Ray{Vec3(10, 20, -5), Vec3(0, 0, 1)}, cull));
  const PlacedMesh flipped{&m, {quatFromEulerDegrees(180, 0, 0), Vec3(10, 20, 0)}};
  EXPECT_FALSE(raycastAny(flipped, down, cull));
  EXPECT_TRUE(raycastAny(flipped, Ray{Vec3(10, 20, -5), Vec3(0, 0, 1)}, cull));
  EXPECT_EQ(raycastClosest(flipped, down)->normal, Vec3(0, 0, 1)) << "normals face the ray origin";
}

TEST(ModelQueryRegression, RayUnderGeneralRotationHitsWhereTheWorldTriangleIs) {
  const Mesh m = flatTriangle();
  Gen g(Family::GeneralPosition, 0xA11);
  for (int i = 0; i < 500; ++i) {
    const Transform w{g.randomRotation(), g.offset(20)};
    const PlacedMesh placed{&m, w};
    // From 3 units above the centroid (mesh space (0, -1/3, 3)) towards the centroid.
    const Vec3 target = w.apply(Vec3(0, Real(-1.0 / 3), 0)), from = w.apply(Vec3(0, Real(-1.0 / 3), 3));
    const std::optional<MeshRayHit> h = raycastClosest(placed, Ray{from, (target - from) * Real(7)});
    ASSERT_TRUE(h.has_value()) << str(w);
    const double scale = 1 + absMax(w.translation);
    EXPECT_NEAR(double(h->t), 3, 64 * kEps * scale) << str(w);
    EXPECT_LE((h->point - target).cast<double>().norm(), 64 * kEps * scale) << str(w);
    EXPECT_LE((h->normal - w.applyVector(Vec3::UnitZ())).cast<double>().norm(), 16 * kEps) << str(w);
  }
}

TEST(ModelQueryRegression, SphereRadiusIsKeptInModelSpace) {
  const Mesh m = flatTriangle();
  for (const Quat& q : {Quat::Identity(), quatFromEulerDegrees(0, 0, 90), quatFromEulerDegrees(180, 0, 270)}) {
    const PlacedMesh placed{&m, {q, Vec3(100, 0, 0)}};
    // The triangle lies in z = 0 around (100, 0, 0) (the turns keep that plane).
    EXPECT_TRUE(overlaps(placed, Sphere{Vec3(100, 0, 3), 3})) << "touching";
    EXPECT_FALSE(overlaps(placed, Sphere{Vec3(100, 0, 3), std::nextafter(Real(3), Real(0))}));
    EXPECT_FALSE(overlaps(placed, Sphere{Vec3(100, 0, 3), 1})) << "the book's radius 1 must not be used";
    EXPECT_TRUE(overlaps(placed, Sphere{Vec3(100, 0, 30), 31}));
  }
}

TEST(ModelQueryRegression, PlaneAtXEquals100TouchesAModelAtXEquals100) {
  // Triangle spanning x in [-1, 1] around its model origin, placed at x = 100 (and turned half
  // way around z, which maps x in [-1, 1] to itself). The book rotated the normal only, so it
  // tested the plane x = 100 against the triangle near x = 0.
  const Mesh m({Vec3(-1, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 1)}, {{0, 1, 2}}, "span");
  for (const Quat& q : {Quat::Identity(), quatFromEulerDegrees(0, 0, 180), quatFromEulerDegrees(90, 0, 0)}) {
    const PlacedMesh placed{&m, {q, Vec3(100, 0, 0)}};
    EXPECT_TRUE(overlaps(placed, Plane{Vec3(1, 0, 0), 100}));
    EXPECT_TRUE(overlaps(placed, Plane{Vec3(2, 0, 0), 202})) << "touches a corner (x = 101)";
    EXPECT_FALSE(overlaps(placed, Plane{Vec3(1, 0, 0), 102}));
    EXPECT_FALSE(overlaps(placed, Plane{Vec3(1, 0, 0), 0}));
  }
}

TEST(ModelQueryRegression, AabbBecomesAnObbUnderRotation) {
  // A thin triangle along the mesh diagonal x = y, turned -45° about z: in world space it lies
  // along the x axis, just below y = 0. The world box [-1, 1]×[0.5, 1.5] misses it by 0.5, but
  // in mesh space that box is a diamond whose axis-aligned bounds reach across the diagonal:
  // a query kept axis-aligned in mesh space would report a hit.
  const Mesh m({Vec3(-4, -4, 0), Vec3(4, 4, 0), Vec3(Real(4.2), Real(3.8), 0)}, {{0, 1, 2}}, "diagonal");
  const PlacedMesh placed{&m, {quatFromEulerDegrees(0, 0, -45), Vec3(0, 0, 0)}};
  const Aabb above{Vec3(-1, Real(0.5), -1), Vec3(1, Real(1.5), 1)};
  EXPECT_TRUE(overlaps(worldBounds(placed), above)) << "the box is inside the model's world bounds";
  EXPECT_FALSE(overlaps(placed, above));
  EXPECT_TRUE(overlaps(placed, Aabb{Vec3(-1, Real(-0.5), -1), Vec3(1, Real(0.5), 1)}));
  // Same answers as the world-space copy.
  const Placement p{placed.world, placed.world.rotation.cast<double>().toRotationMatrix()};
  EXPECT_FALSE(overlaps(worldCopy(m, p), above));
}

TEST(ModelQueryRegression, CoplanarTrianglesSharingAnEdgeUnderAQuarterTurn) {
  // Mesh triangle (0,0,0), (4,0,0), (0,4,0) turned 90° about x and moved to (1, 2, 3): world
  // corners (1,2,3), (5,2,3), (1,2,7), in the plane y = 2 with hypotenuse x + z = 8. A rounded
  // quarter turn would move the mapped query off the shared edge by ~1e-7.
  const Mesh m({Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(0, 4, 0)}, {{0, 1, 2}}, "right");
  const PlacedMesh placed{&m, {quatFromEulerDegrees(90, 0, 0), Vec3(1, 2, 3)}};
  EXPECT_TRUE(overlaps(placed, Triangle{Vec3(5, 2, 3), Vec3(1, 2, 7), Vec3(9, 2, 9)})) << "shares the hypotenuse";
  EXPECT_FALSE(overlaps(placed, Triangle{Vec3(6, 2, 4), Vec3(2, 2, 8), Vec3(10, 2, 10)})) << "x + z = 10 side";
  EXPECT_TRUE(overlaps(placed, Triangle{Vec3(3, 2, 5), Vec3(3, 9, 5), Vec3(3, 9, 9)})) << "touches the hypotenuse midpoint";
  // Sphere touching the corner (5, 2, 3) from distance 5 along (3, 0, -4), in its Voronoi region.
  EXPECT_TRUE(overlaps(placed, Sphere{Vec3(8, 2, -1), 5}));
  EXPECT_FALSE(overlaps(placed, Sphere{Vec3(8, 2, -1), std::nextafter(Real(5), Real(0))}));
  // Segment grazing the corner, and one missing it by one unit.
  EXPECT_TRUE(intersects(placed, Segment{Vec3(5, 0, 3), Vec3(5, 9, 3)}));
  EXPECT_FALSE(intersects(placed, Segment{Vec3(6, 0, 3), Vec3(6, 9, 3)}));
  // An AABB whose corner is the triangle's corner; an OBB face on the plane y = 2.
  EXPECT_TRUE(overlaps(placed, Aabb{Vec3(5, 2, 0), Vec3(8, 4, 3)}));
  EXPECT_FALSE(overlaps(placed, Aabb{Vec3(6, 2, 0), Vec3(8, 4, 3)}));
  EXPECT_TRUE(overlaps(placed, Obb{Vec3(3, 3, 5), Vec3(1, 1, 1), Mat3::Identity()}));
  EXPECT_FALSE(overlaps(placed, Obb{Vec3(3, 4, 5), Vec3(1, 1, 1), Mat3::Identity()}));
  // Ray along the plane's edge direction through the corner.
  const std::optional<MeshRayHit> h = raycastClosest(placed, Ray{Vec3(5, 2, 0), Vec3(0, 0, 1)});
  ASSERT_TRUE(h.has_value());
  EXPECT_EQ(h->t, 3);
}

TEST(ModelQueryRegression, ModelVsModelTouchingFacesUnderQuarterTurns) {
  // Two cubes [-1, 1]³ (12 triangles each); the turns map each cube onto itself, but the model
  // queries still map every coordinate through them.
  std::vector<Vec3> v;
  for (int i = 0; i < 8; ++i) v.emplace_back(Real(i & 1 ? 1 : -1), Real(i & 2 ? 1 : -1), Real(i & 4 ? 1 : -1));
  const Mesh cube(v,
                  {{0, 1, 3}, {0, 3, 2}, {4, 6, 7}, {4, 7, 5}, {0, 4, 5}, {0, 5, 1},
                   {2, 3, 7}, {2, 7, 6}, {0, 2, 6}, {0, 6, 4}, {1, 5, 7}, {1, 7, 3}},
                  "cube");
  const Quat rz = quatFromEulerDegrees(0, 0, 90), rx = quatFromEulerDegrees(90, 0, 0), ry = quatFromEulerDegrees(0, 180, 0);
  const PlacedMesh a{&cube, {rz, Vec3(0, 0, 0)}};
  EXPECT_TRUE(overlaps(a, PlacedMesh{&cube, {rx, Vec3(2, 0, 0)}})) << "faces touch at x = 1";
  EXPECT_FALSE(overlaps(a, PlacedMesh{&cube, {rx, Vec3(3, 0, 0)}}));
  EXPECT_TRUE(overlaps(a, PlacedMesh{&cube, {ry, Vec3(2, 2, 2)}})) << "corners touch at (1, 1, 1)";
  EXPECT_FALSE(overlaps(a, PlacedMesh{&cube, {ry, Vec3(2, 2, 3)}}));
  EXPECT_TRUE(overlaps(a, PlacedMesh{&cube, {rz, Vec3(Real(0.5), 0, 0)}})) << "same rotation, overlapping";
  EXPECT_TRUE(overlaps(a, a)) << "itself";
}

TEST(ModelQuery, IdentityPlacementGivesTheMeshAnswersBitForBit) {
  Gen g(Family::GeneralPosition, 0x1D);
  const Mesh m = randomMesh(g, 40, "m");
  const PlacedMesh placed{&m, Transform::identity()};
  const Placement p{Transform::identity(), Eigen::Matrix3d::Identity()};
  for (int i = 0; i < 300; ++i) {
    const Ray r = randomRay(g, p, m);
    const std::optional<MeshRayHit> a = raycastClosest(placed, r), b = raycastClosest(m, r);
    ASSERT_EQ(a.has_value(), b.has_value());
    if (a) {
      ASSERT_EQ(a->t, b->t);
      ASSERT_EQ(a->point, b->point);
      ASSERT_EQ(a->normal, b->normal);
    }
    const Sphere s = randomSphere(g, p, m);
    ASSERT_EQ(overlaps(placed, s), overlaps(m, s));
    const Aabb box = randomAabb(g, p, m);
    ASSERT_EQ(overlaps(placed, box), overlaps(m, box));
  }
}

TEST(ModelQuery, ClosestAnyAndBooleanQueriesDoNotAllocate) {
  Gen g(Family::GeneralPosition, 0xA110C);
  const Mesh m = randomMesh(g, 200, "m");
  const Mesh other = randomMesh(g, 100, "other");
  const Placement p = randomPlacement(g);
  const Placement aligned = axisAlignedPlacement(1, 0, 1, Vec3(1, 2, 3));
  std::vector<Ray> rays;
  std::vector<Sphere> spheres;
  std::vector<Obb> obbs;
  for (int i = 0; i < 100; ++i) rays.push_back(randomRay(g, p, m)), spheres.push_back(randomSphere(g, p, m)), obbs.push_back(randomObb(g, p, m));
  int hits = 0;
  const long before = test::allocationCount();
  for (const Transform& w : {p.world, aligned.world, Transform::identity()}) {
    const PlacedMesh placed{&m, w};
    for (int i = 0; i < 100; ++i) {
      hits += raycastClosest(placed, rays[i]).has_value();
      hits += raycastAny(placed, rays[i]);
      hits += overlaps(placed, spheres[i]);
      hits += overlaps(placed, obbs[i]);
      hits += overlaps(placed, Aabb{spheres[i].center, spheres[i].center + Vec3::Constant(spheres[i].radius)});
      hits += overlaps(placed, Plane{rays[i].dir, spheres[i].radius});
      hits += overlaps(placed, Triangle{rays[i].origin, spheres[i].center, obbs[i].center});
      hits += intersects(placed, Segment{rays[i].origin, spheres[i].center});
    }
    hits += overlaps(placed, PlacedMesh{&other, p.world});
    hits += overlaps(placed, PlacedMesh{&other, aligned.world});
    hits += worldBounds(placed).isEmpty();
  }
  const long allocations = test::allocationCount() - before;
  EXPECT_EQ(allocations, 0);
  EXPECT_GT(hits, 0);
}

}  // namespace
}  // namespace crux
