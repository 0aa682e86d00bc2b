// Tests of src/mesh/mesh_query.cpp: every mesh query through the BVH against the brute-force
// path, against the geometry layer applied triangle by triangle, and against the exact CGAL
// oracle, on seeded random meshes (integer grid and general position, with degenerate,
// duplicate and coplanar-overlapping triangles) and on real meshes; watertightness on closed
// integer-grid meshes; regression tests for the book's mesh errata; no heap allocation in the
// closest / any / boolean queries.

#include <crux/geometry/overlap.hpp>
#include <crux/geometry/raycast.hpp>
#include <crux/mesh/mesh_point_query.hpp>
#include <crux/mesh/mesh_query.hpp>
#include <crux/precondition.hpp>
#include <exact/exact.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <new>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "support/allocation_counter.hpp"  // allocationCount(): queries that must not allocate
#include "support/test_scale.hpp"          // CRUX_TEST_SCALE: fewer cases in the sanitizer stage
#include "support/bad_inputs.hpp"

namespace crux {
namespace {

constexpr Real kEps = std::numeric_limits<Real>::epsilon();

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
std::string str(const std::vector<std::uint32_t>& v) {
  std::string s = "[";
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + std::to_string(v[i]);
  return s + "]";
}
/// The whole mesh, for reproducing a failure.
std::string str(const Mesh& m) {
  std::string s = "mesh " + m.name() + " (" + std::to_string(m.triangleCount()) + " triangles):\n";
  if (m.triangleCount() > 400) return s + "  (too large to print)\n";
  for (std::uint32_t i = 0; i < m.triangleCount(); ++i) s += "  " + std::to_string(i) + ": " + str(m.triangle(i)) + "\n";
  return s;
}

// ---------------------------------------------------------------------------------------------
// Random meshes and query shapes.

/// The two property-test families of every query.
enum class Family { IntegerGrid, GeneralPosition };
const char* name(Family f) { return f == Family::IntegerGrid ? "integer grid" : "general position"; }

class Gen {
 public:
  Gen(Family family, std::uint64_t seed) : family_(family), rng_(seed) {}
  std::mt19937_64& rng() { return rng_; }
  bool integer() const { return family_ == Family::IntegerGrid; }

  int intIn(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }
  Real realIn(Real lo, Real hi) { return std::uniform_real_distribution<Real>(lo, hi)(rng_); }
  bool chance(double p) { return std::uniform_real_distribution<double>(0, 1)(rng_) < p; }

  /// A point of the mesh region: integers in [-r, r] or reals in [-r/6, r/6] (the general family
  /// lives at unit scale so its coordinates are not integers).
  Vec3 point(int r) {
    if (integer()) return Vec3(Real(intIn(-r, r)), Real(intIn(-r, r)), Real(intIn(-r, r)));
    const Real s = Real(r) / 6;
    return Vec3(realIn(-s, s), realIn(-s, s), realIn(-s, s));
  }
  /// A non-negative length: an integer in [0, r] or a real in [0, r/6].
  Real length(int r) { return integer() ? Real(intIn(0, r)) : realIn(0, Real(r) / 6); }
  /// A random unit quaternion (uniform on SO(3)).
  Quat rotation() {
    std::normal_distribution<double> n(0, 1);
    Eigen::Vector4d q(n(rng_), n(rng_), n(rng_), n(rng_));
    q.normalize();
    return Quat(Real(q[0]), Real(q[1]), Real(q[2]), Real(q[3])).normalized();
  }
  /// Axes of an OBB: a signed permutation (integer family) or a random rotation.
  Mat3 axes() {
    if (!integer()) return rotation().toRotationMatrix();
    int perm[3] = {0, 1, 2};
    std::shuffle(perm, perm + 3, rng_);
    Mat3 m = Mat3::Zero();
    for (int j = 0; j < 3; ++j) m(perm[j], j) = chance(0.5) ? 1 : -1;
    return m;
  }

 private:
  Family family_;
  std::mt19937_64 rng_;
};

/// A random triangle soup of `count` triangles with every kind of trouble: ordinary small
/// triangles, degenerate ones (collinear corners, repeated corners, a point), duplicates
/// (same vertex indices permuted, or same coordinates on fresh vertices), triangles sharing an
/// edge with an earlier one, and coplanar overlapping triangles in a few shared planes.
Mesh randomMesh(Gen& g, int count, const std::string& meshName) {
  std::vector<Vec3> v;
  std::vector<TriangleIndices> t;
  auto add = [&](Vec3 a, Vec3 b, Vec3 c) {  // by value: the corners may be elements of v
    const auto k = std::uint32_t(v.size());
    v.push_back(a), v.push_back(b), v.push_back(c);
    t.push_back({k, k + 1, k + 2});
  };
  auto offset = [&](int r) {
    return g.integer() ? Vec3(Real(g.intIn(-r, r)), Real(g.intIn(-r, r)), Real(g.intIn(-r, r)))
                       : Vec3(g.realIn(-Real(r) / 6, Real(r) / 6), g.realIn(-Real(r) / 6, Real(r) / 6),
                              g.realIn(-Real(r) / 6, Real(r) / 6));
  };
  // A few shared planes for coplanar triangles: axis-aligned, and (general family) a slanted
  // plane x + y + z = s whose points are built exactly from two free coordinates.
  const Real planeValue[3] = {g.integer() ? Real(g.intIn(-2, 2)) : g.realIn(-0.3f, 0.3f),
                              g.integer() ? Real(g.intIn(-2, 2)) : g.realIn(-0.3f, 0.3f),
                              g.integer() ? Real(g.intIn(-2, 2)) : g.realIn(-0.3f, 0.3f)};
  while (int(t.size()) < count) {
    const int kind = g.intIn(0, 9);
    if (kind <= 3 || t.empty()) {
      const Vec3 a = g.point(6);
      add(a, a + offset(3), a + offset(3));
    } else if (kind == 4) {
      // Exactly degenerate in both families: in general position the corners are rounded to
      // multiples of 2^-12 so that a + 2d is computed exactly.
      auto dyadic = [&](Vec3 p) { return g.integer() ? p : Vec3((p * Real(4096)).array().round() / Real(4096)); };
      const Vec3 a = dyadic(g.point(6)), d = dyadic(offset(2));
      switch (g.intIn(0, 3)) {
        case 0: add(a, a + d, a + 2 * d); break;  // collinear
        case 1: add(a, a - d, a + d); break;      // collinear, middle corner first
        case 2: add(a, a, a + d); break;          // repeated corner
        default: add(a, a, a); break;             // a point
      }
    } else if (kind == 5) {
      const TriangleIndices o = t[std::size_t(g.intIn(0, int(t.size()) - 1))];
      if (g.chance(0.5)) {
        t.push_back({o[1], o[2], o[0]});  // same vertices
      } else {
        add(v[o[2]], v[o[1]], v[o[0]]);   // same coordinates, reversed winding
      }
    } else if (kind == 6) {
      const TriangleIndices o = t[std::size_t(g.intIn(0, int(t.size()) - 1))];
      const auto k = std::uint32_t(v.size());
      const Vec3 p = v[o[0]] + offset(3);
      v.push_back(p);
      t.push_back({o[1], o[0], k});  // shares edge (o0, o1)
    } else {
      const int axis = g.intIn(0, 2);
      auto inPlane = [&]() {
        Vec3 p = g.point(5);
        p[axis] = planeValue[axis];
        return p;
      };
      const Vec3 a = inPlane();
      Vec3 b = a + offset(3), c = a + offset(3);
      b[axis] = c[axis] = planeValue[axis];
      add(a, b, c);
    }
  }
  return Mesh(v, t, meshName);
}

/// A random ray; 35% are aimed exactly at a vertex or an edge midpoint of the mesh (`aimed`).
Ray randomRay(Gen& g, const Mesh& mesh, bool* aimed = nullptr) {
  Ray r;
  r.origin = g.point(9);
  const bool aim = g.chance(0.35);
  if (aimed) *aimed = aim;
  if (aim) {
    // Aim exactly at a vertex or (integer family) an edge midpoint: the watertightness cases.
    const Triangle t = mesh.triangle(std::uint32_t(g.intIn(0, int(mesh.triangleCount()) - 1)));
    const int k = g.intIn(0, 3);
    const Vec3 target = k < 3 ? t[k] : Vec3((t.a + t.b) * Real(0.5));
    r.dir = target - r.origin;
  } else if (g.integer()) {
    r.dir = Vec3(Real(g.intIn(-3, 3)), Real(g.intIn(-3, 3)), Real(g.intIn(-3, 3)));
  } else {
    r.dir = Vec3(g.realIn(-1, 1), g.realIn(-1, 1), g.realIn(-1, 1));
  }
  if (r.dir.isZero(0)) r.dir = Vec3(1, 0, 0);
  return r;
}

Segment randomSegment(Gen& g) {
  const Vec3 s = g.point(9);
  return {s, g.chance(0.5) ? Vec3(s + g.point(6)) : g.point(5)};
}
Sphere randomSphere(Gen& g) { return {g.point(9), g.length(3)}; }
Aabb randomAabb(Gen& g) {
  const Vec3 a = g.point(9);
  return {a, a + Vec3(g.length(4), g.length(4), g.length(4))};
}
Obb randomObb(Gen& g) {
  Obb b;
  b.center = g.point(9);
  b.half = Vec3(g.length(3), g.length(3), g.length(3));
  b.axes = g.axes();
  return b;
}
Plane randomPlane(Gen& g) {
  Plane p;
  do {
    p.normal = g.integer() ? Vec3(Real(g.intIn(-2, 2)), Real(g.intIn(-2, 2)), Real(g.intIn(-2, 2)))
                           : Vec3(g.realIn(-1, 1), g.realIn(-1, 1), g.realIn(-1, 1));
  } while (p.normal.isZero(0));
  // Offsets spread so that about half the planes miss every triangle.
  p.d = g.integer() ? Real(g.intIn(-40, 40)) : g.realIn(-3, 3) * p.normal.norm();
  return p;
}
Triangle randomTriangle(Gen& g) {
  const Vec3 a = g.point(9);
  return {a, a + g.point(5), a + g.point(5)};
}

// ---------------------------------------------------------------------------------------------
// References: the geometry layer triangle by triangle, and the exact oracle.

/// The back-face rule of RayQueryOptions, written independently: ((b-a)×(c-a))·dir > 0.
bool backFacing(const Triangle& t, const Vec3& dir) {
  const WVec3 a = wide(t.a), b = wide(t.b), c = wide(t.c);
  return (b - a).cross(c - a).dot(wide(dir)) > 0;
}

/// Closest hit by looping over crux::raycast(Ray, Triangle).
std::optional<MeshRayHit> closestByGeometry(const Mesh& m, const Ray& r, const RayQueryOptions& o) {
  std::optional<MeshRayHit> best;
  for (std::uint32_t i = 0; i < m.triangleCount(); ++i) {
    const Triangle t = m.triangle(i);
    if (o.cullBackFaces && backFacing(t, r.dir)) continue;
    const std::optional<RayHit> h = raycast(r, t, o.maxDistance);
    if (h && (!best || h->t < best->t)) best = MeshRayHit{h->t, h->point, h->normal, i};
  }
  return best;
}

/// Indices of the triangles for which `test` holds, by looping over all of them.
template <class Test>
std::vector<std::uint32_t> touchingByLoop(const Mesh& m, Test test) {
  std::vector<std::uint32_t> out;
  for (std::uint32_t i = 0; i < m.triangleCount(); ++i)
    if (test(m.triangle(i))) out.push_back(i);
  return out;
}

bool sameHit(const std::optional<MeshRayHit>& a, const std::optional<MeshRayHit>& b) {
  if (a.has_value() != b.has_value()) return false;
  if (!a) return true;
  return a->t == b->t && a->triangle == b->triangle && a->point == b->point && a->normal == b->normal;
}

/// Hit-rate bookkeeping of a property test: the generators must stay meaningful.
struct Rate {
  int hits = 0, cases = 0;
  void add(bool hit) { hits += hit, ++cases; }
  double value() const { return cases ? double(hits) / cases : 0; }
};
void expectMeaningful(const Rate& r, const std::string& what) {
  std::printf("%-48s %6d cases, hit rate %.2f\n", what.c_str(), r.cases, r.value());
  EXPECT_GE(r.value(), 0.2) << what;
  EXPECT_LE(r.value(), 0.8) << what;
}

constexpr int kMeshesPerFamily = 4;
constexpr int kTrianglesPerMesh = 160;
constexpr int kQueriesPerMesh = 800;  // vs brute force and the geometry layer
constexpr int kOracleQueries = 240;          // of those, on the first mesh, also vs the exact oracle
constexpr int kOracleTrianglesPerMesh = 60;  // the first (oracle) mesh is smaller: CGAL is slow

const Family kFamilies[] = {Family::IntegerGrid, Family::GeneralPosition};

// Booleans of every shape under one name for the templates below.
bool overlapsOrIntersects(const Mesh& m, const Segment& s, QueryPath p) { return intersects(m, s, p); }
template <class Shape>
bool overlapsOrIntersects(const Mesh& m, const Shape& s, QueryPath p) {
  return overlaps(m, s, p);
}

// ---------------------------------------------------------------------------------------------
// Property tests: shapes.

/// Runs one shape query family: BVH boolean and list vs brute force, vs the geometry layer
/// loop, and on the first queries vs the exact oracle (on a smaller mesh).
template <class Shape, class MakeShape, class Geometry, class Exact>
void checkShapeQuery(const std::string& what, std::uint64_t seed, MakeShape makeShape, Geometry geometry,
                     Exact exactTest) {
  for (Family f : kFamilies) {
    Rate rate;
    for (int m = 0; m < kMeshesPerFamily; ++m) {
      Gen g(f, seed + 1000 * std::uint64_t(f == Family::GeneralPosition) + m);
      const bool oracleMesh = m == 0;
      const Mesh mesh = randomMesh(g, oracleMesh ? kOracleTrianglesPerMesh : kTrianglesPerMesh, "random");
      for (int q = 0; q < kQueriesPerMesh; ++q) {
        const Shape s = makeShape(g);
        const std::vector<std::uint32_t> bvh = touchingTriangles(mesh, s);
        const std::vector<std::uint32_t> brute = touchingTriangles(mesh, s, QueryPath::BruteForce);
        const std::vector<std::uint32_t> loop = touchingByLoop(mesh, [&](const Triangle& t) { return geometry(t, s); });
        const bool any = overlapsOrIntersects(mesh, s, QueryPath::Bvh);
        const bool anyBrute = overlapsOrIntersects(mesh, s, QueryPath::BruteForce);
        rate.add(!loop.empty());
        ASSERT_EQ(bvh, brute) << what << " (" << name(f) << ") BVH vs brute force: " << str(s) << "\n" << str(mesh);
        ASSERT_EQ(brute, loop) << what << " (" << name(f) << ") brute force vs geometry layer: " << str(s) << "\n"
                               << str(mesh);
        ASSERT_EQ(any, !loop.empty()) << what << " boolean (" << name(f) << "): " << str(s) << "\n" << str(mesh);
        ASSERT_EQ(anyBrute, !loop.empty()) << what << " boolean brute (" << name(f) << "): " << str(s);
        if (oracleMesh && q < kOracleQueries) {
          const std::vector<std::uint32_t> exact =
              touchingByLoop(mesh, [&](const Triangle& t) { return exactTest(t, s); });
          if (bvh != exact) {
            std::string diff;
            for (std::uint32_t i = 0; i < mesh.triangleCount(); ++i)
              if (geometry(mesh.triangle(i), s) != exactTest(mesh.triangle(i), s))
                diff += "\n  triangle " + std::to_string(i) + " " + str(mesh.triangle(i)) + ": crux " +
                        (geometry(mesh.triangle(i), s) ? "touch" : "apart") + ", exact the opposite";
            FAIL() << what << " (" << name(f) << ") vs the exact oracle: " << str(s) << diff;
          }
        }
      }
    }
    expectMeaningful(rate, what + " (" + name(f) + ")");
  }
}

TEST(MeshQueryProperty, SegmentMatchesBruteForceGeometryAndOracle) {
  checkShapeQuery<Segment>(
      "segment", 0x5E6, [](Gen& g) { return randomSegment(g); },
      [](const Triangle& t, const Segment& s) { return intersects(s, t); },
      [](const Triangle& t, const Segment& s) { return exact::intersects(s, t); });
}

TEST(MeshQueryProperty, SphereMatchesBruteForceGeometryAndOracle) {
  checkShapeQuery<Sphere>(
      "sphere", 0x5B4, [](Gen& g) { return randomSphere(g); },
      [](const Triangle& t, const Sphere& s) { return overlaps(t, s); },
      [](const Triangle& t, const Sphere& s) { return exact::overlaps(t, s); });
}

TEST(MeshQueryProperty, AabbMatchesBruteForceGeometryAndOracle) {
  checkShapeQuery<Aabb>(
      "aabb", 0xAABB, [](Gen& g) { return randomAabb(g); },
      [](const Triangle& t, const Aabb& b) { return overlaps(t, b); },
      [](const Triangle& t, const Aabb& b) { return exact::overlaps(t, b); });
}

TEST(MeshQueryProperty, ObbMatchesBruteForceGeometryAndOracle) {
  checkShapeQuery<Obb>(
      "obb", 0x0BB, [](Gen& g) { return randomObb(g); },
      [](const Triangle& t, const Obb& b) { return overlaps(t, b); },
      [](const Triangle& t, const Obb& b) { return exact::overlaps(t, b); });
}

TEST(MeshQueryProperty, PlaneMatchesBruteForceGeometryAndOracle) {
  checkShapeQuery<Plane>(
      "plane", 0x91A, [](Gen& g) { return randomPlane(g); },
      [](const Triangle& t, const Plane& p) { return overlaps(t, p); },
      [](const Triangle& t, const Plane& p) { return exact::overlaps(t, p); });
}

TEST(MeshQueryProperty, TriangleMatchesBruteForceGeometryAndOracle) {
  checkShapeQuery<Triangle>(
      "triangle", 0x7C1, [](Gen& g) { return randomTriangle(g); },
      [](const Triangle& t, const Triangle& q) { return overlaps(t, q); },
      [](const Triangle& t, const Triangle& q) { return exact::overlaps(t, q); });
}

// ---------------------------------------------------------------------------------------------
// Property tests: rays.

/// The triangles on which crux::raycast and the exact oracle disagree (for failure messages).
std::string disagreements(const Mesh& m, const Ray& r, const RayQueryOptions& o) {
  std::string s;
  for (std::uint32_t i = 0; i < m.triangleCount(); ++i) {
    const Triangle t = m.triangle(i);
    if (o.cullBackFaces && backFacing(t, r.dir)) continue;
    const std::optional<RayHit> h = raycast(r, t);
    const std::optional<double> e = exact::raycast(r, t);
    if (h.has_value() != e.has_value() || (h && std::abs(double(h->t) - *e) > 1e-4 * std::max(1.0, *e)))
      s += "\n  triangle " + std::to_string(i) + " " + str(t) + ": crux " +
           (h ? "t=" + str(double(h->t)) : std::string("miss")) + ", exact " + (e ? "t=" + str(*e) : std::string("miss"));
  }
  return s.empty() ? "\n  (every triangle agrees with the oracle)" : s;
}

/// Closest, any and all hits: BVH vs brute force (bit-identical), vs the geometry layer loop,
/// and vs the exact oracle (hit/miss exactly; t within a relative tolerance; the reported
/// triangle's exact t is the minimum).
void checkRays(const RayQueryOptions& options, const std::string& what, std::uint64_t seed) {
  for (Family f : kFamilies) {
    Rate rate;
    for (int m = 0; m < kMeshesPerFamily; ++m) {
      Gen g(f, seed + 1000 * std::uint64_t(f == Family::GeneralPosition) + m);
      const bool oracleMesh = m == 0;
      const Mesh mesh = randomMesh(g, oracleMesh ? kOracleTrianglesPerMesh : kTrianglesPerMesh, "random");
      for (int q = 0; q < kQueriesPerMesh; ++q) {
        bool aimed = false;
        const Ray r = randomRay(g, mesh, &aimed);
        RayQueryOptions o = options;
        if (std::isfinite(double(options.maxDistance))) o.maxDistance = g.length(18);
        const std::optional<MeshRayHit> bvh = raycastClosest(mesh, r, o);
        const std::optional<MeshRayHit> brute = raycastClosest(mesh, r, o, QueryPath::BruteForce);
        const std::optional<MeshRayHit> loop = closestByGeometry(mesh, r, o);
        rate.add(loop.has_value());
        // The case, printed only when an assertion fails (gtest evaluates `<<` lazily).
        auto ctx = [&] {
          return what + " (" + std::string(name(f)) + ") " + str(r) + " max " + str(double(o.maxDistance)) + "\n" +
                 str(mesh);
        };
        ASSERT_TRUE(sameHit(bvh, brute)) << "BVH " << str(bvh) << " vs brute " << str(brute) << ": " << ctx();
        ASSERT_TRUE(sameHit(brute, loop)) << "brute " << str(brute) << " vs geometry " << str(loop) << ": " << ctx();
        ASSERT_EQ(raycastAny(mesh, r, o), loop.has_value()) << "any: " << ctx();
        ASSERT_EQ(raycastAny(mesh, r, o, QueryPath::BruteForce), loop.has_value()) << "any brute: " << ctx();

        const std::vector<MeshRayHit> all = raycastAll(mesh, r, o);
        const std::vector<MeshRayHit> allBrute = raycastAll(mesh, r, o, QueryPath::BruteForce);
        ASSERT_EQ(all.size(), allBrute.size()) << "all: " << ctx();
        std::size_t expected = 0;
        for (std::uint32_t i = 0; i < mesh.triangleCount(); ++i) {
          const Triangle t = mesh.triangle(i);
          if (o.cullBackFaces && backFacing(t, r.dir)) continue;
          expected += raycast(r, t, o.maxDistance).has_value();
        }
        ASSERT_EQ(all.size(), expected) << "all vs geometry: " << ctx();
        for (std::size_t k = 0; k < all.size(); ++k) {
          ASSERT_TRUE(sameHit(all[k], allBrute[k])) << "all[" << k << "]: " << ctx();
          if (k) {
            ASSERT_TRUE(all[k - 1].t < all[k].t || (all[k - 1].t == all[k].t && all[k - 1].triangle < all[k].triangle));
          }
        }
        if (loop) {
          ASSERT_TRUE(sameHit(all.front(), loop)) << "all.front() is not the closest: " << ctx();
        }

        // The geometry layer decides exactly on the integer grid; in general position a float ray
        // aimed exactly at a vertex or an edge point is decided consistently (watertight), not
        // exactly, so those rays are compared with the oracle on the integer grid only.
        const bool exactCase = f == Family::IntegerGrid || !aimed;
        if (oracleMesh && q < kOracleQueries && exactCase) {
          // The exact first hit over all (non-culled) triangles within maxDistance.
          std::optional<double> exactBest;
          for (std::uint32_t i = 0; i < mesh.triangleCount(); ++i) {
            const Triangle t = mesh.triangle(i);
            if (o.cullBackFaces && backFacing(t, r.dir)) continue;
            const std::optional<double> e = exact::raycast(r, t);
            if (e && *e <= double(o.maxDistance) * (1 + 8 * double(kEps)) && (!exactBest || *e < *exactBest)) exactBest = e;
          }
          // Hits at distance exactly maxDistance may round either way; skip those cases.
          const bool borderline = exactBest && std::abs(*exactBest - double(o.maxDistance)) <=
                                                   16 * double(kEps) * std::max(1.0, *exactBest);
          if (!borderline) {
            ASSERT_EQ(bvh.has_value(), exactBest.has_value())
                << "vs oracle: " << str(bvh) << ": " << ctx() << disagreements(mesh, r, o);
            if (bvh) {
              const double scale = std::max(1.0, double(r.origin.norm()) + double(bvh->t));
              ASSERT_NEAR(double(bvh->t), *exactBest, 64 * double(kEps) * scale) << ctx() << disagreements(mesh, r, o);
              const std::optional<double> mine = exact::raycast(r, mesh.triangle(bvh->triangle));
              ASSERT_TRUE(mine.has_value()) << ctx();
              ASSERT_NEAR(*mine, *exactBest, 64 * double(kEps) * scale) << "reported triangle is not the nearest: " << ctx();
            }
          }
        }
      }
    }
    expectMeaningful(rate, what + " (" + name(f) + ")");
  }
}

TEST(MeshQueryProperty, RayClosestAnyAllMatchBruteForceGeometryAndOracle) {
  checkRays({}, "ray", 0x7A1);
}

TEST(MeshQueryProperty, RayWithMaxDistanceMatchesBruteForceGeometryAndOracle) {
  RayQueryOptions o;
  o.maxDistance = 1;  // replaced per query by a random finite distance
  checkRays(o, "ray, max distance", 0x7A2);
}

TEST(MeshQueryProperty, RayWithBackFaceCullingMatchesBruteForceGeometryAndOracle) {
  RayQueryOptions o;
  o.cullBackFaces = true;
  checkRays(o, "ray, back faces culled", 0x7A3);
}

// ---------------------------------------------------------------------------------------------
// Property tests: mesh vs mesh.

using Pairs = std::vector<std::pair<std::uint32_t, std::uint32_t>>;

/// b's triangle j seen in a's frame, mapped exactly as documented (ta⁻¹·tb).
Triangle mapped(const Mesh& b, std::uint32_t j, const Transform& rel) {
  const Triangle t = b.triangle(j);
  return {rel.apply(t.a), rel.apply(t.b), rel.apply(t.c)};
}

void checkMeshMesh(Family f, bool rigid, std::uint64_t seed, Rate& rate, int rounds) {
  for (int m = 0; m < rounds; ++m) {
    Gen g(f, seed + m);
    const Mesh a = randomMesh(g, 120, "a");
    const Mesh b = randomMesh(g, 120, "b");
    Transform ta, tb;
    if (rigid) {
      ta.rotation = g.rotation();
      ta.translation = g.point(12);
      tb.rotation = g.rotation();
      tb.translation = g.point(12);
    } else {
      // Identity rotations with integer (or general) translations: mapping is exact.
      ta.translation = g.point(12);
      tb.translation = g.point(12);
    }
    const Pairs bvh = touchingTrianglePairs(a, ta, b, tb);
    const Pairs brute = touchingTrianglePairs(a, ta, b, tb, QueryPath::BruteForce);
    const bool any = overlaps(a, ta, b, tb);
    const bool anyBrute = overlaps(a, ta, b, tb, QueryPath::BruteForce);
    auto ctx = [&] { return std::string(name(f)) + " ta " + str(ta) + " tb " + str(tb) + "\n" + str(a) + str(b); };
    rate.add(!brute.empty());
    ASSERT_EQ(bvh, brute) << "mesh–mesh BVH vs brute force: " << ctx();
    ASSERT_EQ(any, !brute.empty()) << ctx();
    ASSERT_EQ(anyBrute, !brute.empty()) << ctx();
    ASSERT_TRUE(std::is_sorted(bvh.begin(), bvh.end()));
    // Against the geometry layer on b's triangles mapped into a's frame. For pure translations
    // on the integer grid the mapping is exact, so the pairs must be the exact ones.
    const Transform rel = ta.inverse() * tb;
    const bool oracle = !rigid && f == Family::IntegerGrid && m < 3;
    Pairs reference, exactPairs;
    for (std::uint32_t i = 0; i < a.triangleCount(); ++i)
      for (std::uint32_t j = 0; j < b.triangleCount(); ++j) {
        const Triangle tj = mapped(b, j, rel);
        if (overlaps(a.triangle(i), tj)) reference.emplace_back(i, j);
        if (oracle && exact::overlaps(a.triangle(i), tj)) exactPairs.emplace_back(i, j);
      }
    ASSERT_EQ(brute, reference) << "vs the geometry layer: " << ctx();
    if (oracle) {
      ASSERT_EQ(brute, exactPairs) << "vs the exact oracle: " << ctx();
    }
  }
}

TEST(MeshMeshProperty, TranslatedMeshesMatchBruteForceGeometryAndOracle) {
  for (Family f : kFamilies) {
    Rate rate;
    checkMeshMesh(f, false, 0x3E5 + 100 * std::uint64_t(f == Family::GeneralPosition), rate,
                  test::scaledCases(100, 20));
    expectMeaningful(rate, std::string("mesh-mesh translated (") + name(f) + ")");
  }
}

TEST(MeshMeshProperty, RigidlyMovedMeshesMatchBruteForce) {
  for (Family f : kFamilies) {
    Rate rate;
    checkMeshMesh(f, true, 0x3E6 + 100 * std::uint64_t(f == Family::GeneralPosition), rate,
                  test::scaledCases(100, 20));
    expectMeaningful(rate, std::string("mesh-mesh rigid (") + name(f) + ")");
  }
}

TEST(MeshMesh, SameTransformOnBothIsTheIdentityAndExact) {
  // ta == tb (a rotation with rounding): the relative transform is skipped, so integer meshes
  // touching at a face, an edge or a vertex are still found, and separated ones are not.
  Gen g(Family::IntegerGrid, 11);
  const Mesh a = randomMesh(g, 100, "a");
  for (int k = 0; k < 20; ++k) {
    Transform t;
    t.rotation = g.rotation();
    t.translation = Vec3(g.realIn(-5, 5), g.realIn(-5, 5), g.realIn(-5, 5));
    const Pairs self = touchingTrianglePairs(a, t, a, t);
    const Pairs identity = touchingTrianglePairs(a, Transform::identity(), a, Transform::identity());
    EXPECT_EQ(self, identity) << str(t);
    for (std::uint32_t i = 0; i < a.triangleCount(); ++i)
      EXPECT_TRUE(std::binary_search(self.begin(), self.end(), std::make_pair(i, i))) << "triangle " << i << " vs itself";
  }
}

// ---------------------------------------------------------------------------------------------
// Closed integer-grid meshes: watertightness.

/// The surface of the cube [-n, n]^3, each face an 2n x 2n grid of unit squares split into two
/// triangles, diagonals alternating, wound counter-clockwise seen from outside.
Mesh subdividedCube(int n) {
  std::vector<Vec3> v;
  std::vector<TriangleIndices> t;
  auto vertexId = [&](const Vec3& p) {
    for (std::uint32_t i = 0; i < v.size(); ++i)
      if (v[i] == p) return i;
    v.push_back(p);
    return std::uint32_t(v.size() - 1);
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side = -1; side <= 1; side += 2) {
      const int u = (axis + 1) % 3, w = (axis + 2) % 3;
      for (int i = -n; i < n; ++i)
        for (int j = -n; j < n; ++j) {
          auto corner = [&](int di, int dj) {
            Vec3 p;
            p[axis] = Real(side * n);
            p[u] = Real(i + di);
            p[w] = Real(j + dj);
            return vertexId(p);
          };
          const std::uint32_t p00 = corner(0, 0), p10 = corner(1, 0), p11 = corner(1, 1), p01 = corner(0, 1);
          // (u, w, axis) is right-handed: counter-clockwise in (u, w) faces +axis.
          const bool flip = side < 0;
          const bool diag = ((i + j) & 1) != 0;
          auto add = [&](std::uint32_t x, std::uint32_t y, std::uint32_t z) {
            t.push_back(flip ? TriangleIndices{x, z, y} : TriangleIndices{x, y, z});
          };
          if (diag) {
            add(p00, p10, p11), add(p00, p11, p01);
          } else {
            add(p00, p10, p01), add(p10, p11, p01);
          }
        }
    }
  return Mesh(v, t, "subdivided cube");
}

/// The octahedron |x| + |y| + |z| = n, each face subdivided into n² triangles on the integer
/// lattice of the face (slanted faces: node boxes are not tight around them).
Mesh subdividedOctahedron(int n) {
  std::vector<Vec3> v;
  std::vector<TriangleIndices> t;
  auto vertexId = [&](const Vec3& p) {
    for (std::uint32_t i = 0; i < v.size(); ++i)
      if (v[i] == p) return i;
    v.push_back(p);
    return std::uint32_t(v.size() - 1);
  };
  for (int sx = -1; sx <= 1; sx += 2)
    for (int sy = -1; sy <= 1; sy += 2)
      for (int sz = -1; sz <= 1; sz += 2) {
        // Face points: (sx·i, sy·j, sz·(n-i-j)), i, j >= 0, i + j <= n.
        auto p = [&](int i, int j) { return vertexId(Vec3(Real(sx * i), Real(sy * j), Real(sz * (n - i - j)))); };
        const bool flip = sx * sy * sz < 0;
        auto add = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
          t.push_back(flip ? TriangleIndices{a, c, b} : TriangleIndices{a, b, c});
        };
        for (int i = 0; i < n; ++i)
          for (int j = 0; i + j < n; ++j) {
            add(p(i, j), p(i + 1, j), p(i, j + 1));
            if (i + j + 2 <= n) add(p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
          }
      }
  return Mesh(v, t, "subdivided octahedron");
}

/// Rays from many integer origins outside the mesh aimed exactly at every vertex and edge
/// midpoint: the BVH path must never miss (and agrees with brute force).
void checkWatertight(const Mesh& mesh, int originRange, int origins, std::uint64_t seed) {
  ASSERT_TRUE(mesh.stats().closed()) << mesh.name();
  std::vector<Vec3> targets(mesh.vertices().begin(), mesh.vertices().end());
  for (std::uint32_t i = 0; i < mesh.triangleCount(); ++i) {
    const Triangle t = mesh.triangle(i);
    for (int k = 0; k < 3; ++k) targets.push_back((t[k] + t[(k + 1) % 3]) * Real(0.5));
  }
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> coord(-originRange, originRange);
  const Aabb box = mesh.bounds();
  long rays = 0, misses = 0;
  for (int o = 0; o < origins; ++o) {
    Vec3 origin;
    do {
      origin = Vec3(Real(coord(rng)), Real(coord(rng)), Real(coord(rng)));
    } while ((origin.array() >= box.min.array()).all() && (origin.array() <= box.max.array()).all());
    for (const Vec3& target : targets) {
      const Ray r{origin, target - origin};
      const std::optional<MeshRayHit> h = raycastClosest(mesh, r);
      ++rays;
      if (!h) {
        ++misses;
        ADD_FAILURE() << mesh.name() << ": ray through a surface point missed: " << str(r);
        continue;
      }
      EXPECT_LE(double(h->t), double(r.dir.norm()) * (1 + 8 * double(kEps))) << str(r);
      EXPECT_TRUE(raycastAny(mesh, r)) << str(r);
      if (rays % 7 == 0) {
        EXPECT_TRUE(sameHit(h, raycastClosest(mesh, r, {}, QueryPath::BruteForce))) << str(r);
      }
      if (misses > 10) return;
    }
  }
  std::printf("%s: %ld rays at vertices and edge midpoints, %ld misses\n", mesh.name().c_str(), rays, misses);
  EXPECT_EQ(misses, 0);
}

TEST(MeshWatertight, RaysAtVerticesAndEdgeMidpointsOfASubdividedCubeNeverMiss) {
  checkWatertight(subdividedCube(3), 12, 40, 1);
}

TEST(MeshWatertight, RaysAtVerticesAndEdgeMidpointsOfASubdividedOctahedronNeverMiss) {
  checkWatertight(subdividedOctahedron(4), 10, 60, 2);
}

// ---------------------------------------------------------------------------------------------
// Regression tests (the book's mesh errata and the degenerate cases).

Mesh meshOf(const std::vector<Triangle>& tris, const std::string& meshName = "test") {
  std::vector<Vec3> v;
  std::vector<TriangleIndices> t;
  for (const Triangle& x : tris) {
    const auto k = std::uint32_t(v.size());
    v.push_back(x.a), v.push_back(x.b), v.push_back(x.c);
    t.push_back({k, k + 1, k + 2});
  }
  return Mesh(v, t, meshName);
}

TEST(MeshRayRegression, StackedTrianglesClosestHitIsTheNearerOne) {
  // The book returned the first hit found (t = 15), not the closest (t = 10). The far triangle
  // comes first in the index order so visiting order cannot hide the bug.
  const Mesh m = meshOf({{Vec3(-5, -5, 15), Vec3(5, -5, 15), Vec3(0, 5, 15)},
                         {Vec3(-5, -5, 10), Vec3(5, -5, 10), Vec3(0, 5, 10)}});
  const Ray r{Vec3(0, 0, 0), Vec3(0, 0, 1)};
  for (QueryPath p : {QueryPath::Bvh, QueryPath::BruteForce}) {
    const std::optional<MeshRayHit> h = raycastClosest(m, r, {}, p);
    ASSERT_TRUE(h);
    EXPECT_EQ(h->t, 10);
    EXPECT_EQ(h->triangle, 1u);
    EXPECT_EQ(h->point, Vec3(0, 0, 10));
    EXPECT_EQ(h->normal, Vec3(0, 0, -1));  // facing the origin
    const std::vector<MeshRayHit> all = raycastAll(m, r, {}, p);
    ASSERT_EQ(all.size(), 2u);
    EXPECT_EQ(all[0].t, 10);
    EXPECT_EQ(all[1].t, 15);
  }
}

TEST(MeshRayRegression, RayFromInsideAClosedMeshHitsWithoutCulling) {
  // The book culled back faces, so a ray from inside a closed mesh hit nothing.
  const Mesh cube = subdividedCube(2);
  const Ray r{Vec3(0.5f, 0.25f, 0), Vec3(1, 0, 0)};
  const std::optional<MeshRayHit> h = raycastClosest(cube, r);
  ASSERT_TRUE(h);
  EXPECT_EQ(h->t, Real(1.5));
  EXPECT_EQ(h->normal, Vec3(-1, 0, 0));  // facing the origin, i.e. inward here
  // With culling every face seen from inside is a back face (outward winding).
  RayQueryOptions cull;
  cull.cullBackFaces = true;
  EXPECT_FALSE(raycastClosest(cube, r, cull));
  EXPECT_FALSE(raycastAny(cube, r, cull));
  // From outside the front face is still hit with culling.
  const Ray outside{Vec3(-7, 0.25f, 0.5f), Vec3(1, 0, 0)};
  const std::optional<MeshRayHit> front = raycastClosest(cube, outside, cull);
  ASSERT_TRUE(front);
  EXPECT_EQ(front->t, 5);
  EXPECT_EQ(raycastAll(cube, outside, cull).size(), 1u);
  EXPECT_EQ(raycastAll(cube, outside).size(), 2u);
}

TEST(MeshRayRegression, EqualDistancePrefersTheLowestTriangleIndex) {
  // Duplicate triangles (and a shared edge hit exactly): ties in t go to the lowest index, on
  // both paths, whatever order the BVH visits them in.
  std::vector<Triangle> tris;
  for (int k = 0; k < 40; ++k) tris.push_back({Vec3(Real(k), 0, 5), Vec3(Real(k) + 1, 0, 5), Vec3(Real(k), 1, 5)});
  const Triangle target{Vec3(3, 3, 7), Vec3(4, 3, 7), Vec3(3, 4, 7)};
  tris.push_back(target);
  tris.push_back({Vec3(3, 3, 7), Vec3(3, 4, 7), Vec3(4, 3, 7)});  // same, reversed
  tris.push_back(target);
  const Mesh m = meshOf(tris);
  const Ray r{Vec3(3.25f, 3.25f, 0), Vec3(0, 0, 1)};
  for (QueryPath p : {QueryPath::Bvh, QueryPath::BruteForce}) {
    const std::optional<MeshRayHit> h = raycastClosest(m, r, {}, p);
    ASSERT_TRUE(h);
    EXPECT_EQ(h->triangle, 40u);
    const std::vector<MeshRayHit> all = raycastAll(m, r, {}, p);
    ASSERT_EQ(all.size(), 3u);
    EXPECT_EQ(all[0].triangle, 40u);
    EXPECT_EQ(all[1].triangle, 41u);
    EXPECT_EQ(all[2].triangle, 42u);
  }
  // A ray through (1, 0, 5), a corner of both triangle 0 and triangle 1: same t, lowest index.
  const Ray edge{Vec3(1, 0, 0), Vec3(0, 0, 1)};
  const std::optional<MeshRayHit> e = raycastClosest(m, edge);
  ASSERT_TRUE(e);
  EXPECT_EQ(e->triangle, 0u);
}

TEST(MeshRayRegression, MaxDistanceIgnoresFartherHitsAndKeepsHitsAtExactlyMax) {
  const Mesh m = meshOf({{Vec3(-5, -5, 15), Vec3(5, -5, 15), Vec3(0, 5, 15)},
                         {Vec3(-5, -5, 10), Vec3(5, -5, 10), Vec3(0, 5, 10)}});
  const Ray r{Vec3(0, 0, 0), Vec3(0, 0, 2)};
  RayQueryOptions o;
  o.maxDistance = 9.5f;
  EXPECT_FALSE(raycastClosest(m, r, o));
  EXPECT_FALSE(raycastAny(m, r, o));
  EXPECT_TRUE(raycastAll(m, r, o).empty());
  o.maxDistance = 10;  // closed: a hit at exactly maxDistance counts
  ASSERT_TRUE(raycastClosest(m, r, o));
  EXPECT_EQ(raycastClosest(m, r, o)->t, 10);
  EXPECT_EQ(raycastAll(m, r, o).size(), 1u);
  o.maxDistance = 15;
  EXPECT_EQ(raycastAll(m, r, o).size(), 2u);
}

TEST(MeshRayRegression, DegenerateTrianglesAreHitAsTheirSegmentsWithoutNaN) {
  // A collinear triangle (a segment) and a point triangle: hit where the ray meets them, with
  // finite t, point and normal.
  const Mesh m = meshOf({{Vec3(0, 0, 4), Vec3(2, 0, 4), Vec3(4, 0, 4)}, {Vec3(7, 7, 3), Vec3(7, 7, 3), Vec3(7, 7, 3)}});
  const Ray r1{Vec3(1, 0, 0), Vec3(0, 0, 1)};
  const std::optional<MeshRayHit> h1 = raycastClosest(m, r1);
  ASSERT_TRUE(h1);
  EXPECT_EQ(h1->t, 4);
  EXPECT_EQ(h1->triangle, 0u);
  EXPECT_TRUE(h1->normal.allFinite());
  const Ray r2{Vec3(7, 7, 0), Vec3(0, 0, 3)};
  const std::optional<MeshRayHit> h2 = raycastClosest(m, r2);
  ASSERT_TRUE(h2);
  EXPECT_EQ(h2->t, 3);
  EXPECT_EQ(h2->triangle, 1u);
  EXPECT_TRUE(h2->normal.allFinite() && h2->point.allFinite());
  const Ray miss{Vec3(1, 0.5f, 0), Vec3(0, 0, 1)};
  EXPECT_FALSE(raycastClosest(m, miss));
  // Degenerate triangles are never culled.
  RayQueryOptions cull;
  cull.cullBackFaces = true;
  EXPECT_TRUE(raycastClosest(m, r1, cull));
}

TEST(MeshRayRegression, AxisParallelRaysThroughNodeBoxFacesAreNotCulled) {
  // A grid of unit squares in z = 0; rays parallel to the plane lying in it (zero direction
  // components, origin exactly on node box faces: 0·inf in the slab test) and rays along grid
  // lines from above.
  std::vector<Triangle> tris;
  for (int x = 0; x < 8; ++x)
    for (int y = 0; y < 8; ++y) {
      const Vec3 p(Real(x), Real(y), 0);
      tris.push_back({p, p + Vec3(1, 0, 0), p + Vec3(1, 1, 0)});
      tris.push_back({p, p + Vec3(1, 1, 0), p + Vec3(0, 1, 0)});
    }
  const Mesh m = meshOf(tris, "grid");
  for (int k = 0; k <= 8; ++k) {
    const Ray inPlane{Vec3(-3, Real(k), 0), Vec3(1, 0, 0)};
    const std::optional<MeshRayHit> h = raycastClosest(m, inPlane);
    ASSERT_TRUE(h) << str(inPlane);
    EXPECT_EQ(h->t, 3) << str(inPlane);
    EXPECT_TRUE(sameHit(h, raycastClosest(m, inPlane, {}, QueryPath::BruteForce)));
    const Ray down{Vec3(Real(k), Real(k), 5), Vec3(0, 0, -1)};
    const std::optional<MeshRayHit> d = raycastClosest(m, down);
    ASSERT_TRUE(d) << str(down);
    EXPECT_EQ(d->t, 5);
    const Ray parallelAbove{Vec3(-3, Real(k), 0.5f), Vec3(1, 0, 0)};
    EXPECT_FALSE(raycastAny(m, parallelAbove)) << str(parallelAbove);
  }
}

TEST(MeshRayRegression, TinyAndHugeDirectionsFindTheSameHit) {
  // The slab test rescales the direction: neither 2^-100 nor 2^100 (nor subnormal) directions
  // may overflow or underflow the node culling.
  Gen g(Family::GeneralPosition, 99);
  const Mesh m = randomMesh(g, 300, "random");
  for (int q = 0; q < 300; ++q) {
    const Ray r = randomRay(g, m);
    const std::optional<MeshRayHit> ref = raycastClosest(m, r, {}, QueryPath::BruteForce);
    // Subnormal directions (float build; in double the ray would be invalid and is skipped):
    // the scaling may round them, so only BVH vs brute force is compared.
    const int subnormal = std::numeric_limits<Real>::min_exponent - 12;
    for (int e : {-100, -60, 60, 100, subnormal}) {
      const Ray ray{r.origin, Vec3(r.dir * std::ldexp(Real(1), e))};  // exact unless subnormal
      if (!(ray.dir.cast<Wide>().squaredNorm() > 0)) continue;
      const std::optional<MeshRayHit> h = raycastClosest(m, ray);
      const std::optional<MeshRayHit> hb = raycastClosest(m, ray, {}, QueryPath::BruteForce);
      ASSERT_TRUE(sameHit(h, hb)) << str(ray);
      if (e == subnormal) continue;
      ASSERT_EQ(h.has_value(), ref.has_value()) << str(ray);
      if (h) {
        EXPECT_NEAR(double(h->t), double(ref->t), 1e-4 * std::max(1.0, double(ref->t))) << str(ray);
      }
    }
  }
}

TEST(MeshQueryRegression, ShapesInsideAClosedMeshDoNotTouchItsSurface) {
  // Surface semantics: a sphere or box strictly inside the cube touches no triangle; one that
  // reaches the surface exactly (touching) does.
  const Mesh cube = subdividedCube(2);
  EXPECT_FALSE(overlaps(cube, Sphere{Vec3(0, 0, 0), 1}));
  EXPECT_TRUE(overlaps(cube, Sphere{Vec3(0, 0, 0), 2}));
  EXPECT_FALSE(overlaps(cube, Aabb{Vec3(-1, -1, -1), Vec3(1, 1, 1)}));
  EXPECT_TRUE(overlaps(cube, Aabb{Vec3(-1, -1, -1), Vec3(2, 1, 1)}));
  EXPECT_FALSE(intersects(cube, Segment{Vec3(-1, 0, 0), Vec3(1, 1, 1)}));
  EXPECT_TRUE(intersects(cube, Segment{Vec3(-1, 0, 0), Vec3(2, 1, 1)}));
  EXPECT_FALSE(overlaps(cube, Plane{Vec3(1, 0, 0), 3}));
  EXPECT_TRUE(overlaps(cube, Plane{Vec3(1, 0, 0), 2}));
  // The touching sphere touches exactly the triangles of face x = 2 that contain (2, 0, 0).
  const std::vector<std::uint32_t> touching = touchingTriangles(cube, Sphere{Vec3(0, 0, 0), 2});
  const std::vector<std::uint32_t> loop =
      touchingByLoop(cube, [](const Triangle& t) { return overlaps(t, Sphere{Vec3(0, 0, 0), 2}); });
  EXPECT_EQ(touching, loop);
  // The sphere touches each face only at its centre, a grid vertex in 4 triangles (one per
  // adjacent unit square, whichever way its diagonal runs).
  EXPECT_EQ(touching.size(), 24u);
}

TEST(MeshQueryRegression, ZeroLengthSegmentsArePointTests) {
  // start == end: the node culling has no direction to scale by; the segment is a point. Also a
  // mesh whose every vertex is the origin (zero coordinate scale, so zero node pads).
  const Mesh m = meshOf({{Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(0, 4, 0)}, {Vec3(0, 0, 0), Vec3(0, 0, 0), Vec3(0, 0, 0)}});
  const Mesh origin = meshOf({{Vec3(0, 0, 0), Vec3(0, 0, 0), Vec3(0, 0, 0)}}, "origin");
  for (QueryPath p : {QueryPath::Bvh, QueryPath::BruteForce}) {
    EXPECT_TRUE(intersects(m, Segment{Vec3(1, 1, 0), Vec3(1, 1, 0)}, p));
    EXPECT_FALSE(intersects(m, Segment{Vec3(1, 1, 1), Vec3(1, 1, 1)}, p));
    EXPECT_EQ(touchingTriangles(m, Segment{Vec3(0, 0, 0), Vec3(0, 0, 0)}, p), (std::vector<std::uint32_t>{0, 1}));
    EXPECT_EQ(touchingTriangles(m, Segment{Vec3(4, 0, 0), Vec3(4, 0, 0)}, p), (std::vector<std::uint32_t>{0}));
    EXPECT_TRUE(intersects(origin, Segment{Vec3(0, 0, 0), Vec3(0, 0, 0)}, p));
    EXPECT_FALSE(intersects(origin, Segment{Vec3(1, 0, 0), Vec3(1, 0, 0)}, p));
    EXPECT_TRUE(overlaps(origin, Sphere{Vec3(0, 0, 0), 0}, p));
    EXPECT_TRUE(raycastAny(origin, Ray{Vec3(-1, 0, 0), Vec3(1, 0, 0)}, {}, p));
  }
}

TEST(MeshQueryRegression, RefitAfterSetVerticesKeepsQueriesExact) {
  Gen g(Family::IntegerGrid, 5);
  Mesh m = randomMesh(g, 150, "deforming");
  std::vector<Vec3> v = m.vertices();
  for (Vec3& p : v) p = Vec3(p.y(), -p.x(), p.z() + 1);  // rotate 90° about z and lift: exact
  m.setVertices(v);
  for (int q = 0; q < 500; ++q) {
    const Sphere s = randomSphere(g);
    ASSERT_EQ(touchingTriangles(m, s), touchingTriangles(m, s, QueryPath::BruteForce)) << str(s);
    const Ray r = randomRay(g, m);
    ASSERT_TRUE(sameHit(raycastClosest(m, r), raycastClosest(m, r, {}, QueryPath::BruteForce))) << str(r);
  }
}

TEST(MeshQuery, ClosestAnyAndBooleanQueriesDoNotAllocate) {
  Gen g(Family::GeneralPosition, 77);
  const Mesh m = randomMesh(g, 400, "random");
  const Mesh other = randomMesh(g, 200, "other");
  std::vector<Ray> rays;
  std::vector<Sphere> spheres;
  std::vector<Obb> obbs;
  for (int i = 0; i < 200; ++i) rays.push_back(randomRay(g, m)), spheres.push_back(randomSphere(g)), obbs.push_back(randomObb(g));
  Transform tb;
  tb.rotation = g.rotation();
  tb.translation = Vec3(0.1f, 0.2f, 0.3f);
  int hits = 0;
  const long before = test::allocationCount();
  for (int i = 0; i < 200; ++i) {
    hits += raycastClosest(m, rays[i]).has_value();
    hits += raycastAny(m, rays[i]);
    hits += overlaps(m, spheres[i]);
    hits += overlaps(m, obbs[i]);
    hits += overlaps(m, Aabb{spheres[i].center, spheres[i].center + Vec3::Constant(spheres[i].radius)});
    hits += overlaps(m, Plane{rays[i].dir, spheres[i].radius});
    hits += overlaps(m, Triangle{rays[i].origin, spheres[i].center, obbs[i].center});
    hits += intersects(m, Segment{rays[i].origin, spheres[i].center});
  }
  hits += overlaps(m, Transform::identity(), other, tb);
  hits += overlaps(m, Transform::identity(), other, Transform::identity());
  const long allocations = test::allocationCount() - before;
  EXPECT_EQ(allocations, 0);
  EXPECT_GT(hits, 0);
}

// ---------------------------------------------------------------------------------------------
// Real meshes.

std::optional<Mesh> loadIfPresent(const std::string& path, const BvhBuildOptions& options = {}) {
  std::FILE* f = std::fopen(path.c_str(), "r");
  if (!f) return std::nullopt;
  std::fclose(f);
  return loadMesh(path, options);
}

/// Rays from a sphere around the mesh towards random points in its bounds (the bench's rays),
/// BVH vs brute force.
void checkRealMeshRays(const Mesh& m, int count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<Real> u(0, 1);
  std::normal_distribution<Real> n(0, 1);
  const Aabb b = m.bounds();
  const Vec3 c = b.center();
  const Real radius = (b.max - b.min).norm();
  Rate rate;
  for (int i = 0; i < count; ++i) {
    Vec3 dir(n(rng), n(rng), n(rng));
    const Vec3 origin = c + dir.normalized() * radius;
    const Vec3 target(b.min.x() + u(rng) * (b.max.x() - b.min.x()), b.min.y() + u(rng) * (b.max.y() - b.min.y()),
                      b.min.z() + u(rng) * (b.max.z() - b.min.z()));
    const Ray r{origin, target - origin};
    const std::optional<MeshRayHit> h = raycastClosest(m, r);
    ASSERT_TRUE(sameHit(h, raycastClosest(m, r, {}, QueryPath::BruteForce))) << m.name() << " " << str(r);
    ASSERT_EQ(raycastAny(m, r), h.has_value()) << str(r);
    rate.add(h.has_value());
  }
  std::printf("%s: %d rays, hit rate %.2f\n", m.name().c_str(), rate.cases, rate.value());
  EXPECT_GT(rate.hits, 0);
}

template <class Shape>
void checkRealMeshShapes(const Mesh& m, const std::vector<Shape>& shapes) {
  int hits = 0;
  for (const Shape& s : shapes) {
    const std::vector<std::uint32_t> bvh = touchingTriangles(m, s);
    ASSERT_EQ(bvh, touchingTriangles(m, s, QueryPath::BruteForce)) << m.name() << " " << str(s);
    ASSERT_EQ(overlapsOrIntersects(m, s, QueryPath::Bvh), !bvh.empty()) << str(s);
    hits += !bvh.empty();
  }
  EXPECT_GT(hits, 0);
  EXPECT_LT(hits, int(shapes.size()));
}

/// `rays` rays, then `shapes` queries of each shape kind, BVH vs brute force.
void checkRealMesh(const Mesh& m, int rays, int shapes, std::uint64_t seed) {
  checkRealMeshRays(m, rays, seed);
  std::mt19937_64 rng(seed + 1);
  std::uniform_real_distribution<Real> u(0, 1);
  const Aabb b = m.bounds();
  const Vec3 e = b.max - b.min;
  auto inBounds = [&]() { return Vec3(b.min + Vec3(u(rng) * e.x(), u(rng) * e.y(), u(rng) * e.z())); };
  std::vector<Sphere> spheres;
  std::vector<Aabb> boxes;
  std::vector<Obb> obbs;
  std::vector<Segment> segments;
  std::vector<Plane> planes;
  std::vector<Triangle> triangles;
  Gen g(Family::GeneralPosition, seed + 2);
  for (int i = 0; i < shapes; ++i) {
    const Vec3 p = inBounds();
    spheres.push_back({p, u(rng) * e.norm() * Real(0.05)});
    boxes.push_back({p, p + e * Real(0.05) * u(rng)});
    obbs.push_back({p, e * Real(0.03) * u(rng), g.rotation().toRotationMatrix()});
    segments.push_back({p, inBounds()});
    planes.push_back({Vec3(u(rng) - Real(0.5), u(rng) - Real(0.5), u(rng) - Real(0.5)), 0});
    planes.back().d = planes.back().normal.dot(i % 2 ? p : Vec3(b.max + e));
    triangles.push_back({p, p + e * Real(0.1) * u(rng), p + Vec3(0, e.y() * Real(0.1) * u(rng), 0)});
  }
  checkRealMeshShapes(m, spheres);
  checkRealMeshShapes(m, boxes);
  checkRealMeshShapes(m, obbs);
  checkRealMeshShapes(m, segments);
  checkRealMeshShapes(m, planes);
  checkRealMeshShapes(m, triangles);
}

TEST(MeshQueryRealMesh, Bunny00MatchesBruteForce) {
  const std::string path = std::string(CRUX_SOURCE_DIR) + "/data/meshes/bunny00.off";
  const std::optional<Mesh> m = loadIfPresent(path);
  if (!m) GTEST_SKIP() << "missing " << path << " (run scripts/setup)";
  // Each brute-force query tests all 75k triangles: CRUX_TEST_SCALE trims the counts under ASan.
  checkRealMesh(*m, test::scaledCases(300, 30), test::scaledCases(60, 10), 0xB077);
}

/// A real mesh deformed by setVertices (every vertex displaced smoothly): the refitted tree
/// answers every query as the brute-force path does, as the freshly built one did.
void checkAfterSetVertices(const std::string& path, int rays, int shapes, std::uint64_t seed) {
  std::optional<Mesh> m = loadIfPresent(path);
  if (!m) GTEST_SKIP() << "missing " << path;
  const std::vector<std::uint32_t> slots = m->bvh().primIndices;
  const Vec3 e = m->bounds().max - m->bounds().min;
  std::vector<Vec3> moved = m->vertices();
  for (Vec3& v : moved) v += Real(0.03) * e.norm() * Vec3(std::sin(v.y() * 7), std::cos(v.z() * 5), std::sin(v.x() * 3));
  m->setVertices(moved);
  ASSERT_EQ(m->bvh().primIndices, slots) << "refitted, not rebuilt";
  checkRealMesh(*m, rays, shapes, seed);
}

TEST(MeshQueryRealMesh, Bunny00AfterSetVerticesMatchesBruteForce) {
  // (at least 40 shapes of each kind: with fewer, a kind may touch the mesh nowhere, and the
  // check that each kind both hits and misses would fail for want of cases)
  checkAfterSetVertices(std::string(CRUX_SOURCE_DIR) + "/data/meshes/bunny00.off", test::scaledCases(300, 30),
                        test::scaledCases(60, 40), 0x3B1D);
}

TEST(MeshQueryRealMesh, AssimpSpiderObjAfterSetVerticesMatchesBruteForce) {
  checkAfterSetVertices("/usr/share/assimp/models/OBJ/spider.obj", 1000, 60, 0x3D1E);
}

TEST(MeshQueryRealMesh, AssimpSpiderObjMatchesBruteForce) {
  const std::string path = "/usr/share/assimp/models/OBJ/spider.obj";
  const std::optional<Mesh> m = loadIfPresent(path);
  if (!m) GTEST_SKIP() << "missing " << path << " (apt-get install assimp-testmodels)";
  checkRealMesh(*m, 1000, 60, 0x5B1D);
}

TEST(MeshQueryRealMesh, BunnyAgainstItselfMovedMatchesPerTriangleQueries) {
  // Mesh–mesh on 75k x 75k triangles cannot be brute-forced; instead every pair list must equal
  // the union over b's triangles (mapped into a's frame) of the per-triangle mesh query, which
  // the property tests check against brute force.
  const std::string path = std::string(CRUX_SOURCE_DIR) + "/data/meshes/bunny00.off";
  const std::optional<Mesh> m = loadIfPresent(path);
  if (!m) GTEST_SKIP() << "missing " << path << " (run scripts/setup)";
  Gen g(Family::GeneralPosition, 3);
  const Vec3 e = m->bounds().max - m->bounds().min;
  for (int k = 0; k < 2; ++k) {
    Transform tb;
    tb.rotation = g.rotation();
    tb.translation = e * Real(0.1) * Real(k + 1);
    const Pairs pairs = touchingTrianglePairs(*m, Transform::identity(), *m, tb);
    Pairs reference;
    const Transform rel = Transform::identity().inverse() * tb;
    for (std::uint32_t j = 0; j < m->triangleCount(); ++j)
      for (std::uint32_t i : touchingTriangles(*m, mapped(*m, j, rel))) reference.emplace_back(i, j);
    std::sort(reference.begin(), reference.end());
    std::printf("bunny vs moved bunny: %zu touching pairs\n", pairs.size());
    EXPECT_FALSE(pairs.empty());
    EXPECT_EQ(pairs, reference) << str(tb);
    EXPECT_EQ(overlaps(*m, Transform::identity(), *m, tb), !pairs.empty());
  }
}

// ---- preconditions: inputs that are not queryable get no answer, never UB -----------------------

/// A closed tetrahedron around the queries' good inputs.
Mesh preconditionTetrahedron() {
  return Mesh({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)}, {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
}

/// Each query family with NaN, +inf and -inf in every coordinate slot, a zero ray direction, a
/// negative radius, min > max and a negative half extent: no hit, no overlap, an empty list (and
/// before the entry checks, an infinite ray origin or OBB centre crashed the BVH walk).
TEST(MeshQueryPreconditions, InputsThatAreNotQueryableGetNoAnswer) {
  if (CRUX_CHECK_PRECONDITIONS) GTEST_SKIP() << "this build aborts instead (see DebugBuildsAbortNamingTheQuery)";
  const Mesh mesh = preconditionTetrahedron();
  const Real nan = std::numeric_limits<Real>::quiet_NaN(), inf = std::numeric_limits<Real>::infinity();
  int cases = 0;
  for (const QueryPath path : {QueryPath::Bvh, QueryPath::BruteForce}) {
    const auto expectNone = [&](const auto& shape, const char* what) {
      ++cases;
      EXPECT_FALSE(overlaps(mesh, shape, path)) << what;
      EXPECT_TRUE(touchingTriangles(mesh, shape, path).empty()) << what;
    };
    const auto expectNoRay = [&](const Ray& ray, const char* what) {
      ++cases;
      EXPECT_FALSE(raycastClosest(mesh, ray, {}, path).has_value()) << what;
      EXPECT_FALSE(raycastAny(mesh, ray, {}, path)) << what;
      EXPECT_TRUE(raycastAll(mesh, ray, {}, path).empty()) << what;
    };
    for (const Real bad : {nan, inf, -inf}) {
      for (int i = 0; i < 3; ++i) {
        Vec3 v(Real(0.2), Real(0.2), Real(-1));  // each good input below touches the mesh
        v[i] = bad;
        expectNoRay(Ray{v, Vec3(0, 0, 1)}, "ray origin");
        Vec3 d(0, 0, 1);
        d[i] = bad;
        expectNoRay(Ray{Vec3(Real(0.2), Real(0.2), -1), d}, "ray direction");
        ++cases;
        EXPECT_FALSE(intersects(mesh, Segment{v, Vec3(Real(0.2), Real(0.2), 2)}, path));
        EXPECT_TRUE(touchingTriangles(mesh, Segment{v, Vec3(Real(0.2), Real(0.2), 2)}, path).empty());
        Vec3 c = Vec3::Constant(Real(0.2));
        c[i] = bad;
        expectNone(Sphere{c, 1}, "sphere centre");
        expectNone(Aabb{c, Vec3::Constant(2)}, "aabb min");
        expectNone(Obb{c, Vec3::Ones(), Mat3::Identity()}, "obb centre");
        expectNone(Triangle{c, Vec3(1, 1, 1), Vec3(-1, 1, 0)}, "triangle corner");
        Vec3 n(1, 1, 1);
        n[i] = bad;
        expectNone(Plane{n, Real(0.5)}, "plane normal");
        ++cases;
        EXPECT_FALSE(closestPoint(mesh, c, kNoLimit, path).found);
      }
      expectNone(Sphere{Vec3::Constant(Real(0.2)), bad}, "sphere radius");
      expectNone(Plane{Vec3(1, 1, 1), bad}, "plane offset");
    }
    expectNoRay(Ray{Vec3(Real(0.2), Real(0.2), -1), Vec3::Zero()}, "zero direction");
    expectNone(Sphere{Vec3::Constant(Real(0.2)), -1}, "negative radius");
    expectNone(Aabb{Vec3(1, 0, 0), Vec3(0, 1, 1)}, "min > max");
    expectNone(Obb{Vec3::Constant(Real(0.2)), Vec3(1, -1, 1), Mat3::Identity()}, "negative half extent");
    expectNone(Plane{Vec3::Zero(), 0}, "zero normal");
    // the same inputs made good are answered
    EXPECT_TRUE(raycastClosest(mesh, Ray{Vec3(Real(0.2), Real(0.2), -1), Vec3(0, 0, 1)}, {}, path).has_value());
    EXPECT_TRUE(overlaps(mesh, Sphere{Vec3::Constant(Real(0.2)), 1}, path));
    EXPECT_TRUE(overlaps(mesh, Obb{Vec3::Constant(Real(0.2)), Vec3::Ones(), Mat3::Identity()}, path));
  }
  EXPECT_GT(cases, 150);
}

TEST(MeshQueryPreconditions, DebugBuildsAbortNamingTheQuery) {
  if (!CRUX_CHECK_PRECONDITIONS) GTEST_SKIP() << "CRUX_CHECK_PRECONDITIONS is off in this (release) build";
  const Mesh mesh = preconditionTetrahedron();
  EXPECT_DEATH(raycastClosest(mesh, Ray{Vec3::Zero(), Vec3::Zero()}), "precondition violated in raycastClosest");
  EXPECT_DEATH(overlaps(mesh, Sphere{Vec3::Zero(), -1}), "precondition violated in overlaps");
}


// Mesh–mesh overlap with a non-queryable pose: false and no pairs (it used to crash the walk).
TEST(MeshQueryPreconditions, MeshMeshWithANonQueryablePoseGetsNoAnswer) {
  if (CRUX_CHECK_PRECONDITIONS) GTEST_SKIP() << "this build aborts instead (precondition.hpp)";
  const Mesh mesh = preconditionTetrahedron();
  for (const Transform& pose : test_support::badPoses())
    for (const QueryPath path : {QueryPath::Bvh, QueryPath::BruteForce}) {
      EXPECT_FALSE(overlaps(mesh, Transform{}, mesh, pose, path));
      EXPECT_TRUE(touchingTrianglePairs(mesh, pose, mesh, Transform{}, path).empty());
    }
  EXPECT_TRUE(overlaps(mesh, Transform{}, mesh, Transform{}));
}

}  // namespace
}  // namespace crux
