// Tests of src/world/: the CollisionWorld edge (validation, mesh table, collectors, op names)
// and the native backend, which must give exactly the answers of the direct crux API; and,
// through the same interface, the native backend against the exact (CGAL) backend on seeded
// random cases in two families (integer grid: booleans must agree exactly; general position:
// booleans agree, distances and points within the declared tolerances).

#include <crux/geometry/closest_point.hpp>
#include <crux/geometry/overlap.hpp>
#include <crux/geometry/raycast.hpp>
#include <crux/mesh/mesh_query.hpp>
#include <crux/model/model_query.hpp>
#include <crux/scene/scene.hpp>
#include <crux/world/collision_world.hpp>
#include <crux/world/native_world.hpp>
#include <exact/exact_world.hpp>

#if __has_include("cli/batch.hpp")
#include "cli/batch.hpp"
#define CRUX_TEST_HAVE_CLI 1
#endif

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "support/test_scale.hpp"  // CRUX_TEST_SCALE: fewer cases in the sanitizer stage

namespace crux {
namespace {

// ---------------------------------------------------------------------------------------------
// Printing (17 significant digits, so a failing case can be pasted back).

std::string str(double x) {
  std::ostringstream os;
  os.precision(17);
  os << x;
  return os.str();
}
template <class V>
std::string str(const Eigen::MatrixBase<V>& v) {
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
std::string str(const Mesh& m) {
  std::string s = "mesh " + m.name() + " (" + std::to_string(m.triangleCount()) + " triangles):\n";
  for (std::uint32_t i = 0; i < m.triangleCount(); ++i) s += "  " + std::to_string(i) + ": " + str(m.triangle(i)) + "\n";
  return s;
}

// ---------------------------------------------------------------------------------------------
// Random cases.

enum class Family { IntegerGrid, GeneralPosition };
const char* name(Family f) { return f == Family::IntegerGrid ? "integer grid" : "general position"; }

class Gen {
 public:
  Gen(Family family, std::uint64_t seed) : family_(family), rng_(seed) {}
  bool integer() const { return family_ == Family::IntegerGrid; }
  int intIn(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }
  Real realIn(Real lo, Real hi) { return std::uniform_real_distribution<Real>(lo, hi)(rng_); }
  bool chance(double p) { return std::uniform_real_distribution<double>(0, 1)(rng_) < p; }

  /// A coordinate: an integer in [-r, r], or a real in [-r/4, r/4] (general position lives at
  /// a smaller scale so its coordinates are not integers).
  Real coord(int r) { return integer() ? Real(intIn(-r, r)) : realIn(-Real(r) / 4, Real(r) / 4); }
  Vec3 point(int r) { return Vec3(coord(r), coord(r), coord(r)); }
  /// A length in [0, r] (integer) or [0, r/4] (real).
  Real length(int r) { return integer() ? Real(intIn(0, r)) : realIn(0, Real(r) / 4); }
  Vec3 nonZero(int r) {
    for (;;) {
      const Vec3 v = point(r);
      if (!v.isZero(0)) return v;
    }
  }
  /// A triangle of corners near a point: degenerate now and then (collinear, repeated).
  Triangle triangle(int r) {
    const Vec3 a = point(r);
    if (integer() && chance(0.1)) {
      const Vec3 d = point(1);
      return chance(0.5) ? Triangle{a, a + d, a + 2 * d} : Triangle{a, a, a + d};
    }
    return {a, a + point(2), a + point(2)};
  }
  Quat rotation() {
    std::normal_distribution<double> n(0, 1);
    Eigen::Vector4d q(n(rng_), n(rng_), n(rng_), n(rng_));
    q.normalize();
    return Quat(Real(q[0]), Real(q[1]), Real(q[2]), Real(q[3])).normalized();
  }
  /// OBB axes: a signed permutation (integer family) or a random rotation.
  Mat3 axes() {
    if (!integer()) return rotation().toRotationMatrix();
    int perm[3] = {0, 1, 2};
    std::shuffle(perm, perm + 3, rng_);
    Mat3 m = Mat3::Zero();
    for (int j = 0; j < 3; ++j) m(perm[j], j) = chance(0.5) ? 1 : -1;
    return m;
  }
  Sphere sphere(int r, int rr) { return {point(r), length(rr)}; }
  Aabb aabb(int r, int e) {
    const Vec3 lo = point(r);
    return {lo, lo + Vec3(length(e), length(e), length(e))};
  }
  Obb obb(int r, int h) {
    Obb b;
    b.center = point(r);
    b.half = Vec3(length(h), length(h), length(h));
    b.axes = axes();
    return b;
  }
  Plane plane(int r) { return {nonZero(2), coord(r)}; }
  Ray ray(int r) { return {point(r), nonZero(2)}; }
  Segment segment(int r) { return {point(r), point(r)}; }

  /// A triangle soup of `count` triangles around the origin, with shared vertices, degenerate and
  /// coplanar triangles now and then.
  std::shared_ptr<const Mesh> mesh(int count, const std::string& meshName) {
    std::vector<Vec3> v;
    std::vector<TriangleIndices> t;
    while (int(t.size()) < count) {
      const auto k = std::uint32_t(v.size());
      if (!t.empty() && chance(0.3)) {  // share an edge with an earlier triangle
        const TriangleIndices o = t[std::size_t(intIn(0, int(t.size()) - 1))];
        v.push_back(v[o[0]] + point(2));
        t.push_back({o[1], o[0], k});
        continue;
      }
      const Triangle tri = triangle(4);
      v.push_back(tri.a), v.push_back(tri.b), v.push_back(tri.c);
      t.push_back({k, k + 1, k + 2});
    }
    return std::make_shared<const Mesh>(std::move(v), std::move(t), meshName);
  }

 private:
  Family family_;
  std::mt19937_64 rng_;
};

/// Hit-rate bookkeeping of one op in one family.
struct Rate {
  int cases = 0, hits = 0;
  void add(bool hit) {
    ++cases;
    hits += hit;
  }
  double value() const { return cases ? double(hits) / cases : 0; }
};

void expectRate(const std::map<std::string, Rate>& rates, Family f) {
  for (const auto& [op, r] : rates) {
    std::printf("  %-16s %-22s %5d cases, hit rate %.2f\n", name(f), op.c_str(), r.cases, r.value());
    EXPECT_GE(r.value(), 0.2) << op << " in " << name(f) << ": the generator has become meaningless";
    EXPECT_LE(r.value(), 0.8) << op << " in " << name(f) << ": the generator has become meaningless";
  }
}

WorldRayHit toWorld(const MeshRayHit& h) {
  WorldRayHit w;
  w.t = double(h.t);
  w.point = h.point.cast<double>();
  w.normal = h.normal.cast<double>();
  w.triangle = h.triangle;
  return w;
}

bool same(const WorldRayHit& a, const WorldRayHit& b) {
  return a.t == b.t && a.point == b.point && a.normal == b.normal && a.triangle == b.triangle && a.model == b.model;
}

// ---------------------------------------------------------------------------------------------
// The native backend is the direct API.

TEST(NativeWorld, PrimitiveOpsAreExactlyTheDirectApi) {
  for (const Family f : {Family::IntegerGrid, Family::GeneralPosition}) {
    Gen g(f, f == Family::IntegerGrid ? 11 : 12);
    const auto w = makeNativeWorld();
    for (int i = 0; i < 3000; ++i) {
      const Triangle t = g.triangle(3);
      const Vec3 p = g.point(4);
      const Sphere s = g.sphere(3, 3);
      const Aabb b = g.aabb(3, 3);
      const Obb o = g.obb(3, 2);
      const Plane pl = g.plane(4);
      const Triangle u = g.triangle(3);
      const Ray r = g.ray(4);
      const Segment sg = g.segment(4);
      const std::string c = std::string(name(f)) + " case " + std::to_string(i) + ": " + str(t);
      ASSERT_EQ(w->closestPoint(t, p), closestPoint(t, p).cast<double>()) << c << " " << str(p);
      ASSERT_EQ(w->overlaps(t, s), overlaps(t, s)) << c << " " << str(s);
      ASSERT_EQ(w->overlaps(s, t), overlaps(t, s)) << c << " " << str(s) << " (reversed)";
      ASSERT_EQ(w->overlaps(t, b), overlaps(t, b)) << c << " " << str(b);
      ASSERT_EQ(w->overlaps(t, o), overlaps(t, o)) << c << " " << str(o);
      ASSERT_EQ(w->overlaps(o, t), overlaps(t, o)) << c << " " << str(o) << " (reversed)";
      ASSERT_EQ(w->overlaps(t, pl), overlaps(t, pl)) << c << " " << str(pl);
      ASSERT_EQ(w->overlaps(t, u), overlaps(t, u)) << c << " " << str(u);
      ASSERT_EQ(w->intersects(sg, t), intersects(sg, t)) << c << " " << str(sg);
      const auto want = raycast(r, t);
      const auto got = w->raycast(r, t);
      ASSERT_EQ(got.has_value(), want.has_value()) << c << " " << str(r);
      if (want) {
        ASSERT_EQ(got->t, double(want->t)) << c << " " << str(r);
        ASSERT_EQ(got->point, want->point.cast<double>()) << c << " " << str(r);
        ASSERT_EQ(got->normal, want->normal.cast<double>()) << c << " " << str(r);
      }
    }
  }
}

TEST(NativeWorld, MeshOpsAreExactlyTheDirectApi) {
  for (const Family f : {Family::IntegerGrid, Family::GeneralPosition}) {
    Gen g(f, f == Family::IntegerGrid ? 21 : 22);
    const auto w = makeNativeWorld();
    for (int m = 0; m < 6; ++m) {
      const auto mesh = g.mesh(40, "m");
      const auto other = g.mesh(25, "n");
      const MeshHandle h = w->addMesh("m", mesh);
      const MeshHandle h2 = w->addMesh("n", other);
      for (int i = 0; i < 300; ++i) {
        const std::string c = std::string(name(f)) + " mesh " + std::to_string(m) + " case " + std::to_string(i);
        const Ray r = g.ray(6);
        RayQueryOptions options;
        if (g.chance(0.3)) options.maxDistance = g.length(6);
        options.cullBackFaces = g.chance(0.3);
        RayHitCollector closest(RayCollect::Closest), any(RayCollect::Any), all(RayCollect::All);
        w->raycast(h, r, closest, options);
        w->raycast(h, r, any, options);
        w->raycast(h, r, all, options);
        const auto want = raycastClosest(*mesh, r, options);
        ASSERT_EQ(closest.hit().has_value(), want.has_value()) << c << " " << str(r);
        if (want) {
          ASSERT_TRUE(same(*closest.hit(), toWorld(*want))) << c << " " << str(r);
        }
        ASSERT_EQ(any.hasHit(), raycastAny(*mesh, r, options)) << c << " " << str(r);
        const auto wantAll = raycastAll(*mesh, r, options);
        ASSERT_EQ(all.hits().size(), wantAll.size()) << c << " " << str(r);
        for (std::size_t k = 0; k < wantAll.size(); ++k)
          ASSERT_TRUE(same(all.hits()[k], toWorld(wantAll[k]))) << c << " " << str(r) << " hit " << k;

        const Segment s = g.segment(6);
        ASSERT_EQ(w->intersects(h, s), intersects(*mesh, s)) << c << " " << str(s);
        const Sphere sp = g.sphere(6, 3);
        ASSERT_EQ(w->overlaps(h, sp), overlaps(*mesh, sp)) << c << " " << str(sp);
        const Aabb b = g.aabb(6, 3);
        ASSERT_EQ(w->overlaps(h, b), overlaps(*mesh, b)) << c << " " << str(b);
        const Obb o = g.obb(6, 2);
        ASSERT_EQ(w->overlaps(h, o), overlaps(*mesh, o)) << c << " " << str(o);
        const Plane p = g.plane(6);
        ASSERT_EQ(w->overlaps(h, p), overlaps(*mesh, p)) << c << " " << str(p);
        const Triangle t = g.triangle(6);
        ASSERT_EQ(w->overlaps(h, t), overlaps(*mesh, t)) << c << " " << str(t);
        Transform ta, tb;
        ta.rotation = g.rotation();
        ta.translation = g.point(3);
        tb.translation = g.point(3);
        ASSERT_EQ(w->overlaps(h, ta, h2, tb), overlaps(*mesh, ta, *other, tb)) << c << " " << str(ta) << " " << str(tb);
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Native against exact through the interface.

/// Runs every boolean op on both worlds; booleans must agree exactly in both families (the
/// general family's random floats are not near-degenerate); ray distances and closest points
/// within the two backends' declared tolerances.
TEST(NativeWorld, AgreesWithTheExactBackend) {
  for (const Family f : {Family::IntegerGrid, Family::GeneralPosition}) {
    Gen g(f, f == Family::IntegerGrid ? 31 : 32);
    const auto native = makeNativeWorld();
    const auto exact = exact::makeExactWorld();
    std::map<std::string, Rate> rates;
    const double tol = 4 * (native->tolerance().relative + exact->tolerance().relative);
    auto check = [&](const std::string& op, bool a, bool b, const std::string& c) {
      rates[op].add(b);
      EXPECT_EQ(a, b) << op << " native " << a << " exact " << b << " — " << name(f) << ": " << c;
    };
    // Query shapes are placed near the triangle (around its first corner) so that hits and
    // misses are both frequent; in the integer family every coordinate stays an integer.
    for (int i = 0, n = test::scaledCases(4000, 400); i < n; ++i) {
      const Triangle t = g.triangle(3);
      const std::string c = str(t);
      const Vec3 p = g.point(4);
      const Vec3d cp = native->closestPoint(t, p), ce = exact->closestPoint(t, p);
      EXPECT_LE((cp - ce).cwiseAbs().maxCoeff(), tol * 8) << "closest point " << str(cp) << " vs " << str(ce) << ": " << c
                                                          << " " << str(p);
      const Sphere s{t.a + g.point(2), g.length(3)};
      check("triangle_sphere", native->overlaps(t, s), exact->overlaps(t, s), c + " " + str(s));
      const Vec3 bc = t.a + g.point(1);
      const Aabb b{bc - Vec3(g.length(2), g.length(2), g.length(2)), bc + Vec3(g.length(1), g.length(1), g.length(1))};
      check("triangle_aabb", native->overlaps(t, b), exact->overlaps(t, b), c + " " + str(b));
      Obb o = g.obb(2, 2);
      o.center += t.a;
      check("triangle_obb", native->overlaps(t, o), exact->overlaps(t, o), c + " " + str(o));
      Plane pl = g.plane(3);
      pl.d = pl.normal.dot(t.a + g.point(1));  // a plane near the triangle
      check("triangle_plane", native->overlaps(t, pl), exact->overlaps(t, pl), c + " " + str(pl));
      const Triangle u{t.a + g.point(2), t.b + g.point(2), t.c + g.point(2)};  // a perturbed copy
      check("triangle_triangle", native->overlaps(t, u), exact->overlaps(t, u), c + " " + str(u));
      Segment sg{t.a + g.point(2), Vec3::Zero()};
      sg.end = t.b + t.c - sg.start + g.point(1);  // through the middle of edge bc, give or take
      check("segment_triangle", native->intersects(sg, t), exact->intersects(sg, t), c + " " + str(sg));
      // Rays aimed at 3·centroid + noise (integer in the integer family), about half hit.
      Ray aimed{g.point(4), Vec3::Zero()};
      aimed.dir = t.a + t.b + t.c + g.point(2) - 3 * aimed.origin;
      if (aimed.dir.isZero(0)) continue;
      const auto rn = native->raycast(aimed, t), re = exact->raycast(aimed, t);
      check("ray_triangle", rn.has_value(), re.has_value(), c + " " + str(aimed));
      if (rn && re) {
        EXPECT_NEAR(rn->t, re->t, tol * 8) << c << " " << str(aimed);
      }
    }
    for (int m = 0, meshes = test::scaledCases(8, 2); m < meshes; ++m) {
      const auto mesh = g.mesh(30, "m");
      const auto other = g.mesh(20, "n");
      const MeshHandle hn = native->addMesh("m", mesh), he = exact->addMesh("m", mesh);
      const MeshHandle hn2 = native->addMesh("n", other), he2 = exact->addMesh("n", other);
      const std::string c = str(*mesh);
      auto vertex = [&] { return mesh->vertices()[std::size_t(g.intIn(0, int(mesh->vertexCount()) - 1))]; };
      for (int i = 0; i < 150; ++i) {
        Ray r{g.point(6), Vec3::Zero()};
        r.dir = vertex() + g.point(1) - r.origin;  // aimed at the mesh
        if (r.dir.isZero(0)) r.dir = Vec3::UnitX();
        RayHitCollector a, b;
        native->raycast(hn, r, a);
        exact->raycast(he, r, b);
        check("mesh_ray", a.hasHit(), b.hasHit(), str(r) + "\n" + c);
        if (a.hit() && b.hit()) {
          EXPECT_NEAR(a.hit()->t, b.hit()->t, tol * 16) << str(r) << "\n" << c;
        }
        // Integer family: half of the segments end exactly on a vertex of the mesh (touching).
        // General position: segments through the middle of a random triangle, give or take (not
        // ending on vertices: see RayFromATriangleVertexInGeneralPosition).
        Segment s{g.point(3), Vec3::Zero()};
        if (g.integer()) {
          s.end = vertex() + (g.chance(0.5) ? Vec3::Zero() : g.point(1));
        } else {
          const Triangle tk = mesh->triangle(std::uint32_t(g.intIn(0, int(mesh->triangleCount()) - 1)));
          s.end = Real(2) * (tk.a + tk.b + tk.c) / Real(3) - s.start + g.point(1);
        }
        check("mesh_segment", native->intersects(hn, s), exact->intersects(he, s), str(s) + "\n" + c);
        const Sphere sp{vertex() + g.point(3), g.length(2)};
        check("mesh_sphere", native->overlaps(hn, sp), exact->overlaps(he, sp), str(sp) + "\n" + c);
        const Aabb bx = g.aabb(5, 3);
        check("mesh_aabb", native->overlaps(hn, bx), exact->overlaps(he, bx), str(bx) + "\n" + c);
        const Obb o = g.obb(6, 2);
        check("mesh_obb", native->overlaps(hn, o), exact->overlaps(he, o), str(o) + "\n" + c);
        Plane p = g.plane(16);
        p.d = p.normal.dot(g.point(10));
        check("mesh_plane", native->overlaps(hn, p), exact->overlaps(he, p), str(p) + "\n" + c);
        const Vec3 at = vertex();
        const Triangle t{at + g.point(1), at + g.point(2), at + g.point(2)};
        check("mesh_triangle", native->overlaps(hn, t), exact->overlaps(he, t), str(t) + "\n" + c);
        // mesh_mesh: integer family, integer translations (crux maps b into a's frame exactly);
        // general family, one random rotation for both and random translations.
        Transform ta, tb;
        ta.translation = g.point(6);
        tb.translation = g.point(6);
        if (f == Family::GeneralPosition) ta.rotation = tb.rotation = g.rotation();
        check("mesh_mesh", native->overlaps(hn, ta, hn2, tb), exact->overlaps(he, ta, he2, tb),
              str(ta) + " " + str(tb) + "\n" + c + str(*other));
      }
    }
    expectRate(rates, f);
  }
}

/// Found while writing this suite, in crux's geometry layer (src/geometry/raycast.cpp, firstHit):
/// a ray or segment starting (or a segment ending) exactly at corner b or c of a triangle, in
/// general position, is reported as a miss about 15-20% of the time: the plane parameter
/// s = n·(a - o) / n·d is evaluated from corner a, n·(a - b) rounds to ±tiny instead of 0, and a
/// negative value reads as "plane behind the origin". The integer grid is unaffected (exact).
/// Fixed: the front/behind and segment-end decisions now use exact orientation signs.
TEST(NativeWorld, RayFromATriangleVertexInGeneralPosition) {
  const auto native = makeNativeWorld();
  const auto exact = exact::makeExactWorld();
  const Triangle t{Vec3(Real(-0.971948624f), Real(0.457676768f), Real(0.101573229f)),
                   Vec3(Real(-0.88655597f), Real(-0.633501053f), Real(-0.100397825f)),
                   Vec3(Real(-0.830846667f), Real(-0.975497186f), Real(-0.616194189f))};
  const Vec3 q(Real(-0.537918329f), Real(-0.731669307f), Real(-0.998784065f));
  for (int k = 0; k < 3; ++k) {
    const Ray r{t[k], q - t[k]};
    EXPECT_TRUE(exact->raycast(r, t).has_value());
    EXPECT_TRUE(native->raycast(r, t).has_value()) << "ray from corner " << k << ": " << str(t) << " " << str(r);
    EXPECT_TRUE(native->intersects(Segment{q, t[k]}, t)) << "segment ending at corner " << k;
    EXPECT_TRUE(native->intersects(Segment{t[k], q}, t)) << "segment starting at corner " << k;
  }
  // The same over random general-position triangles: every ray from a corner hits at t = 0.
  Gen g(Family::GeneralPosition, 41);
  int misses = 0;
  for (int i = 0; i < 2000; ++i) {
    const Triangle u = g.triangle(3);
    const Vec3 p = g.point(4);
    for (int k = 0; k < 3; ++k)
      if (p != u[k] && !native->raycast(Ray{u[k], p - u[k]}, u)) ++misses;
  }
  EXPECT_EQ(misses, 0);
}

// ---------------------------------------------------------------------------------------------
// The interface's edge.

TEST(RayHitCollector, ClosestKeepsTheNearestAndBreaksTiesByModelThenTriangle) {
  RayHitCollector c(RayCollect::Closest);
  EXPECT_FALSE(c.hasHit());
  EXPECT_EQ(c.earlyOut(), std::numeric_limits<double>::infinity());
  WorldRayHit h;
  h.t = 3, h.triangle = 7;
  c.add(h);
  EXPECT_EQ(c.earlyOut(), 3);
  h.t = 5, h.triangle = 1;
  c.add(h);
  EXPECT_EQ(c.hit()->triangle, 7u);
  h.t = 3, h.triangle = 2;
  c.add(h);
  EXPECT_EQ(c.hit()->triangle, 2u);
  h.t = 3, h.triangle = 5, h.model = ModelHandle{4};
  c.add(h);
  EXPECT_EQ(c.hit()->model, ModelHandle{4}) << "model before triangle (no model sorts last)";
  h.t = 3, h.triangle = 9, h.model = ModelHandle{1};
  c.add(h);
  EXPECT_EQ(c.hit()->model, ModelHandle{1});
  h.t = 3, h.triangle = 8, h.model = ModelHandle{1};
  c.add(h);
  EXPECT_EQ(c.hit()->triangle, 8u);
  EXPECT_EQ(c.hits().size(), 1u);
  EXPECT_FALSE(c.done());
  c.reset();
  EXPECT_FALSE(c.hasHit());
}

TEST(RayHitCollector, AnyIsDoneAfterTheFirstHitWithOrWithoutDetails) {
  RayHitCollector c(RayCollect::Any);
  EXPECT_FALSE(c.done());
  c.addAnonymousHit();
  EXPECT_TRUE(c.hasHit());
  EXPECT_TRUE(c.done());
  EXPECT_FALSE(c.hit().has_value());
  EXPECT_EQ(c.earlyOut(), -std::numeric_limits<double>::infinity());
  RayHitCollector d(RayCollect::Any);
  WorldRayHit h;
  h.t = 9;
  d.add(h);
  h.t = 1;
  d.add(h);
  EXPECT_EQ(d.hit()->t, 9) << "any keeps the first hit offered";
}

TEST(RayHitCollector, AllSortsByDistanceThenModelThenTriangle) {
  RayHitCollector c(RayCollect::All);
  const double ts[] = {4, 1, 4, 2};
  const std::uint32_t tris[] = {3, 9, 1, 5};
  for (int i = 0; i < 4; ++i) {
    WorldRayHit h;
    h.t = ts[i];
    h.triangle = tris[i];
    c.add(h);
  }
  ASSERT_EQ(c.hits().size(), 4u);
  EXPECT_EQ(c.hits()[0].t, 1);
  EXPECT_EQ(c.hits()[1].t, 2);
  EXPECT_EQ(c.hits()[2].triangle, 1u);
  EXPECT_EQ(c.hits()[3].triangle, 3u);
  EXPECT_EQ(c.earlyOut(), std::numeric_limits<double>::infinity());
  EXPECT_EQ(c.hit()->t, 1);
}

std::shared_ptr<const Mesh> unitTriangleMesh(const std::string& n) {
  return std::make_shared<const Mesh>(std::vector<Vec3>{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)},
                                      std::vector<TriangleIndices>{{0, 1, 2}}, n);
}

TEST(CollisionWorldMeshes, NamesHandlesReplacementAndRemoval) {
  const auto w = makeNativeWorld();
  const auto m1 = unitTriangleMesh("a");
  const MeshHandle a = w->addMesh("a", m1);
  const MeshHandle b = w->addMesh("b", unitTriangleMesh("b"));
  EXPECT_NE(a, b);
  EXPECT_EQ(w->meshHandle("a"), a);
  EXPECT_EQ(&w->mesh(a), m1.get());
  EXPECT_EQ(w->meshName(b), "b");
  // Redefining a name replaces the mesh; the old handle is gone and never reused.
  const MeshHandle a2 = w->addMesh("a", unitTriangleMesh("a"));
  EXPECT_NE(a2, a);
  EXPECT_NE(a2, b);
  EXPECT_EQ(w->meshHandle("a"), a2);
  EXPECT_THROW(w->mesh(a), InvalidInput);
  EXPECT_EQ(w->meshes(), (std::vector<MeshHandle>{b, a2}));
  w->removeMesh("b");
  EXPECT_FALSE(w->findMesh("b"));
  EXPECT_THROW(w->removeMesh(b), InvalidInput);
  w->removeMesh(a2);
  EXPECT_TRUE(w->meshes().empty());
  try {
    w->meshHandle("nope");
    FAIL() << "no exception";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("nope"), std::string::npos);
  }
  EXPECT_THROW(w->addMesh("", unitTriangleMesh("x")), InvalidInput);
  EXPECT_THROW(w->addMesh("x", nullptr), InvalidInput);
}

/// The error message of f's InvalidInput, or "" when it throws nothing.
std::string invalidInputMessage(const std::function<void()>& f) {
  try {
    f();
  } catch (const InvalidInput& e) {
    return e.what();
  }
  return "";
}

TEST(CollisionWorldEdge, InvalidInputIsRejectedNamingTheField) {
  const auto w = makeNativeWorld();
  const MeshHandle m = w->addMesh("m", unitTriangleMesh("m"));
  const Triangle t{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  const Real nan = std::numeric_limits<Real>::quiet_NaN();
  auto startsWith = [](const std::string& s, const std::string& p) { return s.rfind(p, 0) == 0; };
  EXPECT_TRUE(startsWith(invalidInputMessage([&] { w->overlaps(t, Sphere{Vec3::Zero(), -1}); }), "sphere")) ;
  EXPECT_TRUE(startsWith(invalidInputMessage([&] { w->overlaps(t, Triangle{Vec3(nan, 0, 0), t.b, t.c}); }), "b"));
  EXPECT_TRUE(startsWith(invalidInputMessage([&] { w->closestPoint(t, Vec3(0, nan, 0)); }), "point"));
  EXPECT_TRUE(startsWith(invalidInputMessage([&] { w->raycast(Ray{Vec3::Zero(), Vec3::Zero()}, t); }), "ray"));
  EXPECT_TRUE(startsWith(invalidInputMessage([&] { w->overlaps(m, Aabb{Vec3::Ones(), Vec3::Zero()}); }), "aabb"));
  Transform bad;
  bad.rotation = Quat(2, 0, 0, 0);
  EXPECT_TRUE(
      startsWith(invalidInputMessage([&] { w->overlaps(m, Transform{}, m, bad); }), "transform_b.rotation"));
  RayHitCollector hits;
  RayQueryOptions negative;
  negative.maxDistance = -1;
  EXPECT_TRUE(startsWith(invalidInputMessage([&] { w->raycast(m, Ray{}, hits, negative); }), "max"));
  EXPECT_TRUE(startsWith(invalidInputMessage([&] { w->overlaps(MeshHandle{99}, Sphere{}); }), "mesh"));
  EXPECT_TRUE(startsWith(invalidInputMessage([&] { w->overlaps(m, Transform{}, MeshHandle{99}, Transform{}); }), "b"));
  EXPECT_EQ(invalidInputMessage([&] { w->overlaps(m, Sphere{}); }), "");
}

TEST(CollisionWorldEdge, OpNamesRoundTrip) {
  for (const WorldOp op : allWorldOps()) {
    const auto parsed = parseOp(opName(op));
    ASSERT_TRUE(parsed) << opName(op);
    EXPECT_EQ(*parsed, op);
  }
  EXPECT_FALSE(parseOp("mesh_cone"));
  EXPECT_EQ(opName(WorldOp::ClosestPointTriangle), "closest_point_triangle");
  EXPECT_EQ(opName(WorldOp::ScenePairs), "scene_pairs");
}

#ifdef CRUX_TEST_HAVE_CLI
/// The world names exactly the ops of the batch protocol, plus the volume-mode variants (which
/// the protocol reaches through mesh_<shape> with "volume": true).
TEST(CollisionWorldEdge, OpsAreTheBatchProtocolOps) {
  std::vector<std::string_view> world;
  for (const WorldOp op : allWorldOps())
    if (!isVolumeVariant(op)) world.push_back(opName(op));
  std::sort(world.begin(), world.end());
  std::vector<std::string_view> protocol = cli::protocolOps();
  std::sort(protocol.begin(), protocol.end());
  EXPECT_EQ(world, protocol);
}
#endif

TEST(NativeWorld, SupportsEveryOp) {
  const auto w = makeNativeWorld();
  EXPECT_EQ(w->backend(), "native");
  for (const WorldOp op : allWorldOps()) EXPECT_TRUE(w->supports(op)) << opName(op);
  EXPECT_TRUE(w->scenePairs().empty());
  EXPECT_TRUE(w->concurrentQueries());
}

// ---------------------------------------------------------------------------------------------
// Models and the scene: the native world is a crux::Scene with names.

/// A closed axis-aligned box mesh [0, s]^3.
std::shared_ptr<const Mesh> boxMesh(Real s, const std::string& meshName) {
  std::vector<Vec3> v = {{0, 0, 0}, {s, 0, 0}, {s, s, 0}, {0, s, 0}, {0, 0, s}, {s, 0, s}, {s, s, s}, {0, s, s}};
  std::vector<TriangleIndices> t = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                                    {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  return std::make_shared<const Mesh>(std::move(v), std::move(t), meshName);
}

/// Runs a seeded random sequence of model edits on a native world and, identically, on a
/// crux::Scene, checking after every edit that every model, ray and scene query of the world
/// answers exactly what the scene answers.
TEST(NativeWorld, ModelAndSceneOpsAreExactlyTheScene) {
  for (const Family family : {Family::IntegerGrid, Family::GeneralPosition}) {
    Gen gen(family, 20261122);
    const auto w = makeNativeWorld();
    Scene scene;
    const std::shared_ptr<const Mesh> box = boxMesh(2, "box");
    const MeshHandle boxHandle = w->addMesh("box", box);
    std::map<ModelId, std::string> names;  // the scene's ids -> the world's names
    std::map<ModelId, ModelHandle> handles;
    int next = 0, rayHits = 0, rays = 0;
    const auto randomTransform = [&] {
      Transform t;
      t.translation = gen.point(6);
      if (!gen.integer()) t.rotation = gen.rotation();
      return t;
    };
    for (int step = 0; step < 60; ++step) {
      const int action = names.size() < 3 ? 0 : gen.intIn(0, 4);
      std::vector<ModelId> ids;
      for (const auto& [id, n] : names) ids.push_back(id);
      const ModelId some = ids.empty() ? kNoModel : ids[std::size_t(gen.intIn(0, int(ids.size()) - 1))];
      std::string what;
      if (action <= 1) {
        const Transform t = randomTransform();
        const ModelId parent = (!ids.empty() && gen.chance(0.4)) ? some : kNoModel;
        const std::string n = "m" + std::to_string(next++);
        const ModelId id = scene.add(box, t, parent);
        const ModelHandle h = w->addModel(n, boxHandle, t, parent == kNoModel ? std::nullopt
                                                                               : std::optional<ModelHandle>(handles.at(parent)));
        names[id] = n, handles[id] = h;
        what = "add " + n + " " + str(t);
      } else if (action == 2) {
        const Transform t = randomTransform();
        scene.setTransform(some, t);
        w->setTransform(handles.at(some), t);
        what = "set_transform " + names[some] + " " + str(t);
      } else if (action == 3) {
        const ModelId other = ids[std::size_t(gen.intIn(0, int(ids.size()) - 1))];
        const std::vector<ModelId> below = scene.models().descendants(some);
        if (other == some || std::binary_search(below.begin(), below.end(), other)) continue;
        const bool detach = gen.chance(0.3);
        scene.setParent(some, detach ? kNoModel : other);
        w->setParent(handles.at(some), detach ? std::nullopt : std::optional<ModelHandle>(handles.at(other)));
        what = "set_parent " + names[some] + " " + (detach ? std::string("null") : names[other]);
      } else {
        what = "remove " + names[some];
        scene.remove(some);
        w->removeModel(handles.at(some));
        names.erase(some), handles.erase(some);
      }
      SCOPED_TRACE("step " + std::to_string(step) + " (" + name(family) + "): " + what);

      for (const auto& [id, n] : names) {
        ASSERT_EQ(w->findModel(n), handles.at(id));
        std::vector<std::string> want;
        for (const ModelId d : scene.models().descendants(id)) want.push_back(names.at(d));
        std::sort(want.begin(), want.end());
        EXPECT_EQ(w->descendants(handles.at(id)), want) << n;
        const Ray r = gen.ray(6);
        RayHitCollector all(RayCollect::All);
        w->raycast(handles.at(id), r, all);
        const std::vector<MeshRayHit> direct = raycastAll(scene.placed(id), r);
        ASSERT_EQ(all.hits().size(), direct.size()) << n << " " << str(r);
        for (std::size_t k = 0; k < direct.size(); ++k) {
          WorldRayHit expected = toWorld(direct[k]);
          expected.model = handles.at(id);
          EXPECT_TRUE(same(all.hits()[k], expected)) << n << " " << str(r);
        }
        const Sphere sp = gen.sphere(6, 2);
        EXPECT_EQ(w->overlaps(handles.at(id), sp), overlaps(scene.placed(id), sp)) << n << " " << str(sp);
        const Segment sg = gen.segment(6);
        EXPECT_EQ(w->intersects(handles.at(id), sg), intersects(scene.placed(id), sg)) << n << " " << str(sg);
        const Triangle tr = gen.triangle(6);
        EXPECT_EQ(w->overlaps(handles.at(id), tr), overlaps(scene.placed(id), tr)) << n << " " << str(tr);
      }
      for (int k = 0; k < 4; ++k) {
        const Ray r = gen.ray(8);
        RayHitCollector closest;
        w->sceneRaycast(r, closest);
        const std::optional<SceneRayHit> direct = scene.raycast(r);
        ++rays;
        ASSERT_EQ(closest.hasHit(), direct.has_value()) << str(r);
        if (!direct) continue;
        ++rayHits;
        WorldRayHit expected = toWorld(direct->hit);
        expected.model = handles.at(direct->model);
        EXPECT_TRUE(same(*closest.hit(), expected)) << str(r);
        const Aabb b = gen.aabb(6, 3);
        for (const bool bounds : {false, true}) {
          std::vector<std::string> want;
          for (const ModelId id : scene.query(b, bounds ? RegionTest::Bounds : RegionTest::Triangles))
            want.push_back(names.at(id));
          std::sort(want.begin(), want.end());
          EXPECT_EQ(w->sceneQuery(b, bounds), want) << str(b) << " bounds " << bounds;
        }
      }
      std::vector<std::pair<std::string, std::string>> pairs;
      for (const auto& [a, b] : scene.overlappingPairs())
        pairs.emplace_back(std::min(names.at(a), names.at(b)), std::max(names.at(a), names.at(b)));
      std::sort(pairs.begin(), pairs.end());
      EXPECT_EQ(w->scenePairs(), pairs);
    }
    EXPECT_GE(rayHits, rays / 10) << name(family) << ": scene rays should hit now and then";
  }
}

TEST(NativeWorld, ModelErrorsNameTheField) {
  const auto w = makeNativeWorld();
  const MeshHandle box = w->addMesh("box", boxMesh(1, "box"));
  const ModelHandle a = w->addModel("a", box);
  const ModelHandle b = w->addModel("b", box, Transform{}, a);
  EXPECT_EQ(invalidInputMessage([&] { w->addModel("a", box); }), "name: a model named \"a\" already exists");
  EXPECT_EQ(invalidInputMessage([&] { w->addModel("", box); }), "name: a model name must not be empty");
  EXPECT_EQ(invalidInputMessage([&] { w->addModel("c", box, Transform{}, ModelHandle{77}); }),
            "parent: no model with handle 77 in this world");
  EXPECT_EQ(invalidInputMessage([&] { w->setParent(a, a); }), "parent: \"a\" is the model itself (a cycle)");
  EXPECT_EQ(invalidInputMessage([&] { w->setParent(a, b); }), "parent: \"b\" descends from \"a\" (a cycle)");
  EXPECT_EQ(invalidInputMessage([&] { w->setTransform(ModelHandle{5}, Transform{}); }),
            "model: no model with handle 5 in this world");
  EXPECT_EQ(invalidInputMessage([&] { w->overlaps(ModelHandle{5}, Sphere{}); }),
            "model: no model with handle 5 in this world");
  w->removeModel(a);
  EXPECT_FALSE(w->findModel("a"));
  EXPECT_EQ(invalidInputMessage([&] { w->descendants(a); }), "model: no model with handle 0 in this world");
  EXPECT_EQ(w->descendants(b), std::vector<std::string>{});
  // Removing the mesh keeps the models' geometry (meshes are shared).
  w->removeMesh("box");
  EXPECT_TRUE(w->overlaps(b, Sphere{Vec3(Real(0.5), Real(0.5), 0), 0}));
}

/// The extension listing the touching triangles is the mesh layer's.
TEST(NativeWorld, TouchingTrianglesAreTheMeshLayers) {
  Gen gen(Family::IntegerGrid, 7);
  const auto w = makeNativeWorld();
  const auto mesh = gen.mesh(40, "soup");
  const MeshHandle m = w->addMesh("soup", mesh);
  for (int i = 0; i < 200; ++i) {
    const Sphere s = gen.sphere(4, 2);
    EXPECT_EQ(w->touchingTriangles(m, s), std::optional(touchingTriangles(*mesh, s))) << str(s);
    const Segment g = gen.segment(4);
    EXPECT_EQ(w->touchingTriangles(m, g), std::optional(touchingTriangles(*mesh, g))) << str(g);
    const Transform ta, tb{Quat::Identity(), gen.point(2)};
    EXPECT_EQ(w->touchingTrianglePairs(m, ta, m, tb), std::optional(touchingTrianglePairs(*mesh, ta, *mesh, tb)));
  }
}

/// Queries from several threads at once after prepareConcurrentQueries() answer what one
/// thread answers (run under ThreadSanitizer to check for races).
TEST(NativeWorld, ConcurrentQueriesAfterPrepareMatchSerial) {
  Gen gen(Family::GeneralPosition, 99);
  const auto w = makeNativeWorld();
  const MeshHandle box = w->addMesh("box", boxMesh(1, "box"));
  std::vector<ModelHandle> models;
  for (int i = 0; i < 30; ++i) {
    Transform t;
    t.translation = gen.point(20);
    t.rotation = gen.rotation();
    models.push_back(w->addModel("m" + std::to_string(i), box, t, i % 3 ? std::optional(models.back()) : std::nullopt));
  }
  for (int i = 0; i < 30; i += 4) w->setTransform(models[std::size_t(i)], Transform{gen.rotation(), gen.point(20)});
  std::vector<Ray> rays;
  for (int i = 0; i < 400; ++i) rays.push_back(gen.ray(20));
  const auto answer = [&](std::size_t i) {
    RayHitCollector c;
    w->sceneRaycast(rays[i], c);
    const bool model = w->overlaps(models[i % models.size()], Sphere{rays[i].origin, 3});
    return std::make_pair(c.hit() ? c.hit()->t : -1.0, model);
  };
  w->prepareConcurrentQueries();
  std::vector<std::pair<double, bool>> serial(rays.size()), parallel(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) serial[i] = answer(i);
  w->setTransform(models[1], Transform{gen.rotation(), gen.point(20)});  // stale world transforms again
  w->setTransform(models[1], Transform{});
  for (std::size_t i = 0; i < rays.size(); ++i) serial[i] = answer(i);
  w->setTransform(models[1], Transform{gen.rotation(), gen.point(20)});
  w->setTransform(models[1], Transform{});
  w->prepareConcurrentQueries();
  std::vector<std::thread> threads;
  for (std::size_t k = 0; k < 4; ++k)
    threads.emplace_back([&, k] {
      for (std::size_t i = k; i < rays.size(); i += 4) parallel[i] = answer(i);
    });
  for (std::thread& t : threads) t.join();
  int hits = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    EXPECT_EQ(parallel[i], serial[i]) << str(rays[i]);
    hits += serial[i].first >= 0;
  }
  EXPECT_GT(hits, 0);
}

}  // namespace
}  // namespace crux
