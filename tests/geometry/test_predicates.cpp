/// Tests of include/crux/geometry/predicates.hpp and expansion.hpp: the exact arithmetic
/// (identities that only exact arithmetic satisfies), the soundness of the forward-error
/// filter, and seeded near-degenerate families (ulp moves off vertices, edges and planes,
/// float denormals next to ordinary coordinates, 2^±100 scales mixed with denormals) on which
/// every boolean answer of the triangle tests must equal the exact CGAL oracle's.

#include <crux/geometry/overlap.hpp>
#include <crux/geometry/predicates.hpp>
#include <crux/geometry/raycast.hpp>

#include "exact/exact.hpp"
#include "support/test_scale.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <iomanip>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace {

using crux::Aabb;
using crux::Obb;
using crux::Plane;
using crux::Ray;
using crux::Real;
using crux::Segment;
using crux::Sphere;
using crux::Triangle;
using crux::Vec3;
using crux::Wide;
using crux::WVec3;
using crux::robust::Bounded;
using crux::robust::Expansion;

// ---- exact arithmetic ----------------------------------------------------------------------

/// A double with a random significand and an exponent anywhere in the finite range (incl.
/// denormals).
double wildDouble(std::mt19937_64& rng, int minExp = -1074, int maxExp = 1000) {
  std::uniform_int_distribution<int> e(minExp, maxExp);
  std::uniform_real_distribution<double> m(0.5, 1.0);
  const double x = std::ldexp(m(rng), e(rng));
  return (rng() & 1) ? x : -x;
}

TEST(Expansion, SumsAndProductsOfWildMagnitudesAreExact) {
  std::mt19937_64 rng(11);
  for (int i = 0; i < 20000; ++i) {
    const double a = wildDouble(rng, -1074, 300), b = wildDouble(rng, -1074, 300), c = wildDouble(rng, -300, 300);
    const Expansion A(a), B(b), C(c);
    // (a + b) - a - b = 0 and (a + b)(a - b) - (a² - b²) = 0 only in exact arithmetic.
    EXPECT_EQ(((A + B) - A - B).sign(), 0) << std::setprecision(17) << a << " " << b;
    EXPECT_EQ(((A + B) * (A - B) - (A * A - B * B)).sign(), 0) << std::setprecision(17) << a << " " << b;
    EXPECT_EQ(((A * B) * C - A * (B * C)).sign(), 0) << std::setprecision(17) << a << " " << b << " " << c;
    // A tiny term survives next to huge ones: sign((c + a) - c) = sign(a).
    EXPECT_EQ(((C + A) - C).sign(), (a > 0) - (a < 0)) << std::setprecision(17) << a << " " << c;
    EXPECT_EQ(((C * C + A * B) - C * C).sign(), ((a > 0) == (b > 0)) ? 1 : -1) << std::setprecision(17) << a << b << c;
  }
}

TEST(Expansion, EstimateIsCloseAndCompressKeepsTheValue) {
  std::mt19937_64 rng(12);
  for (int i = 0; i < 5000; ++i) {
    const double a = wildDouble(rng, -60, 60), b = wildDouble(rng, -60, 60);
    Expansion p = Expansion(a) * Expansion(b) + Expansion(a);
    const long double before = p.estimate();
    p.compress();
    EXPECT_EQ(p.estimate(), before);
    const double want = a * b + a;  // one rounding of two
    EXPECT_NEAR(double(p.estimate()), want, 4 * std::numeric_limits<double>::epsilon() * (std::abs(a * b) + std::abs(a)));
  }
  EXPECT_TRUE(crux::robust::kExpansionFullRange || sizeof(long double) == sizeof(double));
}

TEST(Bounded, CertainSignsAreTheExactSigns) {
  // Nearly cancelling a·b - c·d + e: whenever the filter claims a sign it must be the exact one.
  std::mt19937_64 rng(13);
  int certain = 0, uncertain = 0;
  for (int i = 0; i < 50000; ++i) {
    const double a = wildDouble(rng, -40, 40), b = wildDouble(rng, -40, 40);
    const double c = a * (1 + std::ldexp(double(int(rng() % 9) - 4), -50)), d = b;
    const double e = (rng() & 1) ? 0.0 : wildDouble(rng, -1074, -900);
    const Bounded f = Bounded(a) * Bounded(b) - Bounded(c) * Bounded(d) + Bounded(e);
    const int exact = (Expansion(a) * Expansion(b) - Expansion(c) * Expansion(d) + Expansion(e)).sign();
    const int s = f.certainSign();
    if (s == 2) {
      ++uncertain;
      continue;
    }
    ++certain;
    ASSERT_EQ(s, exact) << std::setprecision(17) << a << " " << b << " " << c << " " << d << " " << e;
  }
  EXPECT_GT(certain, 1000);
  EXPECT_GT(uncertain, 1000);
}

TEST(Predicates, Orient3dOfADenormalOffPlaneIsExact) {
  // The plane z = 0 through three ordinary points; a fourth point a denormal above or below.
  const Real tiny = std::numeric_limits<Real>::denorm_min();
  const WVec3 a(0, 0, 0), b(18, 0, 0), c(0, 12, 0);
  for (const Real z : {tiny, -tiny, Real(0)}) {
    const WVec3 d(7, 5, z);
    EXPECT_EQ(crux::predicates::orient3dExact(a, b, c, d), (z > 0) - (z < 0)) << double(z);
    // The same plane with its x and y scaled by 2^100 (exact): huge coordinates beside a denormal.
    const Wide big = std::ldexp(1.0, 100);
    const WVec3 s(big, big, 1);
    EXPECT_EQ(crux::predicates::orient3dExact(a.cwiseProduct(s), b.cwiseProduct(s), c.cwiseProduct(s), d.cwiseProduct(s)),
              (z > 0) - (z < 0))
        << double(z);
    EXPECT_EQ(crux::predicates::orient2dExact(a, b, d, 1), (z < 0) - (z > 0)) << double(z);
  }
  // Collinear with a denormal off the line: a proper (sliver) triangle.
  Triangle t{Vec3(0, 0, 0), Vec3(18, 0, 0), Vec3(9, tiny, 0)};
  EXPECT_EQ(crux::predicates::classify(t).kind, crux::predicates::TriangleKind::Triangle);
  t.c.y() = 0;
  const auto s = crux::predicates::classify(t);
  ASSERT_EQ(s.kind, crux::predicates::TriangleKind::Segment);
  EXPECT_EQ(s.p, WVec3(0, 0, 0));
  EXPECT_EQ(s.q, WVec3(18, 0, 0));
}

/// Whether the cross product (b − a) × (c − a) is exactly zero, in expansions.
bool exactlyCollinear(const WVec3& a, const WVec3& b, const WVec3& c) {
  crux::robust::ExactJudge judge;
  using V = crux::robust::V3<Expansion>;
  const V A = crux::robust::lift<Expansion>(a);
  return crux::predicates::crossIsZero(judge, crux::robust::lift<Expansion>(b) - A, crux::robust::lift<Expansion>(c) - A);
}

TEST(Predicates, StaticCollinearityFilterCertifiesOnlyProperTriangles) {
  // Corners in Real at wild magnitudes: exactly collinear ones (c = a + k·(b − a) with k and
  // the coordinates small integers times one power of two, so every coordinate is exact),
  // coincident ones, collinear ones moved by one ulp, and random ones. The static filter may
  // say "proper" only when the exact cross product is non-zero, and must decide most random
  // triangles (else classify gains nothing).
  std::mt19937_64 rng(17);
  std::uniform_int_distribution<int> small(-64, 64), scaleExp(-60, 60), family(0, 3);
  std::uniform_real_distribution<double> unit(-1, 1);
  int claimed = 0, random = 0, randomClaimed = 0, collinear = 0;
  for (int i = 0; i < 200000; ++i) {
    const int f = family(rng);
    const double s = std::ldexp(1.0, scaleExp(rng));
    Vec3 a, b, c;
    for (int k = 0; k < 3; ++k) {
      a[k] = Real(small(rng) * s);
      b[k] = Real(small(rng) * s);
    }
    if (f == 0) {  // collinear on the grid: c = a + t (b − a), t in [-4, 4] in sixteenths
      const double t = small(rng) / 16.0;
      for (int k = 0; k < 3; ++k) c[k] = Real(double(a[k]) + t * (double(b[k]) - double(a[k])));
    } else if (f == 1) {  // coincident corners
      c = (rng() & 1) ? a : b;
      if (rng() & 1) b = a;
    } else if (f == 2) {  // a grid-collinear corner moved by one ulp
      const double t = small(rng) / 16.0;
      for (int k = 0; k < 3; ++k) c[k] = Real(double(a[k]) + t * (double(b[k]) - double(a[k])));
      const int k = int(rng() % 3);
      c[k] = std::nextafter(c[k], (rng() & 1) ? std::numeric_limits<Real>::max() : -std::numeric_limits<Real>::max());
    } else {  // random corners
      for (int k = 0; k < 3; ++k) c[k] = Real(unit(rng) * 64 * s);
    }
    const WVec3 A = crux::wide(a), B = crux::wide(b), C = crux::wide(c);
    const bool exact = exactlyCollinear(A, B, C);
    collinear += exact;
    const bool proper = crux::predicates::certainlyNotCollinear(A, B, C);
    if (proper) {
      ++claimed;
      ASSERT_FALSE(exact) << std::setprecision(17) << crux::wide(a).transpose() << " | " << B.transpose() << " | "
                          << C.transpose();
    }
    ASSERT_EQ(crux::predicates::classify(A, B, C).kind == crux::predicates::TriangleKind::Triangle, !exact);
    if (f == 3) {
      ++random;
      randomClaimed += proper;
    }
  }
  EXPECT_GT(collinear, 50000);
  EXPECT_GT(randomClaimed, random * 99 / 100);
  EXPECT_GT(claimed, randomClaimed);  // also some one-ulp slivers
}

TEST(Predicates, StaticCollinearityFilterIsNotFooledByRoundedDifferences) {
  // Exactly collinear corners whose differences and products round in double: two far points
  // ±A·(1, 3) (A = 2^k, k in [30, 120]) and one near the origin, x·(1, 3) with x a float of 21
  // significant bits (so 3x is exact), in a random plane z, axes permuted and corners shuffled.
  // The rounded cross product is often non-zero; the filter must still never call them proper.
  std::mt19937_64 rng(29);
  std::uniform_int_distribution<int> expo(30, 120), frac(1, (1 << 20) - 1), small(-40, 40);
  int roundedNonZero = 0;
  const int cases = 100000;
  for (int i = 0; i < cases; ++i) {
    const double A = std::ldexp(1.0, expo(rng));
    const double x = std::ldexp(1.0 + std::ldexp(double(frac(rng)), -20), small(rng));
    const double z = std::ldexp(double(frac(rng)), small(rng));
    double pts[3][3] = {{A, 3 * A, z}, {-A, -3 * A, z}, {x, 3 * x, z}};
    int axes[3] = {0, 1, 2};
    std::shuffle(axes, axes + 3, rng);
    std::shuffle(pts, pts + 3, rng);
    WVec3 v[3];
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 3; ++c) v[k][axes[c]] = Wide(Real(pts[k][c]));  // every value exact in Real
    ASSERT_TRUE(exactlyCollinear(v[0], v[1], v[2]));
    roundedNonZero += ((v[1] - v[0]).cross(v[2] - v[0]).array() != 0).any();
    ASSERT_FALSE(crux::predicates::certainlyNotCollinear(v[0], v[1], v[2]))
        << std::setprecision(17) << v[0].transpose() << " | " << v[1].transpose() << " | " << v[2].transpose();
    ASSERT_NE(crux::predicates::classify(v[0], v[1], v[2]).kind, crux::predicates::TriangleKind::Triangle);
  }
  // a filter that trusted the rounded cross product (no error bound) would fail here
  EXPECT_GT(roundedNonZero, cases / 20);
}

// ---- near-degenerate families against the exact oracle ------------------------------------

std::string num(double x) {
  std::ostringstream s;
  s << std::setprecision(17) << x;
  return s.str();
}
std::string str(const Vec3& v) { return "[" + num(v.x()) + ", " + num(v.y()) + ", " + num(v.z()) + "]"; }
std::string str(const Triangle& t) { return "[" + str(t.a) + ", " + str(t.b) + ", " + str(t.c) + "]"; }

/// Case generator: a small-integer triangle and a feature point on it (a corner or an edge
/// midpoint), a query shape built touching that point, then one to three of all the case's
/// coordinates moved: 1–4 ulps (std::nextafter), a zero replaced by ±k·denorm_min, or the
/// whole case scaled by 2^±100 (exact) before such a move (huge/tiny mixed with denormals).
struct Family {
  std::mt19937_64 rng;
  explicit Family(std::uint64_t seed) : rng(seed) {}

  int small(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); }
  Vec3 gridPoint(int r = 6) { return Vec3(Real(small(-r, r)), Real(small(-r, r)), Real(small(-r, r))); }
  Triangle triangle() {
    Triangle t{gridPoint(), gridPoint(), gridPoint()};
    if (small(0, 9) == 0) t.c = t.a + (t.b - t.a) * Real(2);  // collinear
    return t;
  }
  /// A corner or an edge midpoint of t (exact in Real).
  Vec3 feature(const Triangle& t) {
    const int k = small(0, 5);
    if (k < 3) return t[k];
    return (t[k - 3] + t[(k - 2) % 3]) * Real(0.5);
  }
  /// Moves some of the values: the near-degenerate part.
  void perturb(std::vector<Real*>& values) {
    const Real scale = std::ldexp(Real(1), (small(0, 2) - 1) * 100);  // 2^-100, 1, 2^100
    if (small(0, 2) == 0)
      for (Real* v : values) *v *= scale;
    const int moves = small(1, 3);
    for (int m = 0; m < moves; ++m) {
      Real& v = *values[std::size_t(small(0, int(values.size()) - 1))];
      const int kind = small(0, 2);
      if (v == 0 || kind == 0) {
        v = Real(small(1, 4)) * std::numeric_limits<Real>::denorm_min() * (small(0, 1) ? 1 : -1);
      } else {
        const Real to = small(0, 1) ? std::numeric_limits<Real>::infinity() : -std::numeric_limits<Real>::infinity();
        for (int i = small(1, 4); i > 0; --i) v = std::nextafter(v, to);
      }
    }
  }
};

void collect(Triangle& t, std::vector<Real*>& v) {
  for (Vec3* p : {&t.a, &t.b, &t.c})
    for (int i = 0; i < 3; ++i) v.push_back(&(*p)[i]);
}
void collect(Vec3& p, std::vector<Real*>& v) {
  for (int i = 0; i < 3; ++i) v.push_back(&p[i]);
}

/// Runs `cases` cases; `check` returns an empty string when native equals exact, else the
/// printed case. Counts hits to check that the family is not one-sided.
void runFamily(const char* name, int cases, std::uint64_t seed,
               const std::function<std::string(Family&, int& hits)>& check) {
  Family f(seed);
  int hits = 0, failures = 0;
  for (int i = 0; i < cases; ++i) {
    const std::string bad = check(f, hits);
    if (!bad.empty() && ++failures <= 5) ADD_FAILURE() << name << " case " << i << ": " << bad;
  }
  EXPECT_EQ(failures, 0) << name;
  EXPECT_GT(hits, cases / 20) << name << ": hit rate too low to mean anything";
  EXPECT_LT(hits, cases - cases / 20) << name << ": miss rate too low to mean anything";
}

const int kCases = crux::test::scaledCases(3000, 300);

TEST(NearDegenerate, TriangleSphereEqualsExact) {
  runFamily("triangle_sphere", kCases, 101, [](Family& f, int& hits) -> std::string {
    Triangle t = f.triangle();
    Sphere s{f.feature(t), Real(f.small(0, 1))};
    if (s.radius > 0) s.center += Vec3(Real(f.small(-1, 1)), Real(f.small(-1, 1)), Real(f.small(-1, 1)));
    std::vector<Real*> v;
    collect(t, v);
    collect(s.center, v);
    v.push_back(&s.radius);
    f.perturb(v);
    if (s.radius < 0) s.radius = -s.radius;
    const bool native = crux::overlaps(t, s), exact = crux::exact::overlaps(t, s);
    hits += exact;
    if (native == exact) return {};
    return "triangle " + str(t) + " sphere " + str(s.center) + " r " + num(s.radius) + " native " +
           std::to_string(native);
  });
}

TEST(NearDegenerate, TriangleAabbEqualsExact) {
  runFamily("triangle_aabb", kCases, 102, [](Family& f, int& hits) -> std::string {
    Triangle t = f.triangle();
    const Vec3 p = f.feature(t);
    Vec3 lo = p, hi = p;
    for (int i = 0; i < 3; ++i) {
      const int k = f.small(-1, 1);
      if (k < 0) lo[i] -= Real(f.small(1, 2));
      if (k > 0) hi[i] += Real(f.small(1, 2));
    }
    std::vector<Real*> v;
    collect(t, v);
    collect(lo, v);
    collect(hi, v);
    f.perturb(v);
    Aabb b{lo.cwiseMin(hi), lo.cwiseMax(hi)};
    const bool native = crux::overlaps(t, b), exact = crux::exact::overlaps(t, b);
    hits += exact;
    if (native == exact) return {};
    return "triangle " + str(t) + " aabb " + str(b.min) + " " + str(b.max) + " native " + std::to_string(native);
  });
}

TEST(NearDegenerate, TriangleObbEqualsExact) {
  runFamily("triangle_obb", kCases, 103, [](Family& f, int& hits) -> std::string {
    Triangle t = f.triangle();
    Obb b;
    b.center = f.feature(t);
    b.half = Vec3(Real(f.small(0, 2)), Real(f.small(0, 2)), Real(f.small(0, 2)));
    // Signed permutation axes (exactly orthonormal) so that corners land on grid features.
    int perm[3] = {0, 1, 2};
    std::shuffle(perm, perm + 3, f.rng);
    b.axes.setZero();
    for (int i = 0; i < 3; ++i) b.axes(perm[i], i) = f.small(0, 1) ? Real(1) : Real(-1);
    b.center += b.axes * Vec3(b.half.x() * Real(f.small(-1, 1)), b.half.y() * Real(f.small(-1, 1)), b.half.z() * Real(f.small(-1, 1)));
    std::vector<Real*> v;
    collect(t, v);
    collect(b.center, v);
    collect(b.half, v);
    f.perturb(v);
    b.half = b.half.cwiseAbs();
    const bool native = crux::overlaps(t, b), exact = crux::exact::overlaps(t, b);
    hits += exact;
    if (native == exact) return {};
    return "triangle " + str(t) + " obb center " + str(b.center) + " half " + str(b.half) + " axes " +
           str(b.axes.col(0)) + str(b.axes.col(1)) + str(b.axes.col(2)) + " native " + std::to_string(native);
  });
}

TEST(NearDegenerate, TrianglePlaneEqualsExact) {
  runFamily("triangle_plane", kCases, 104, [](Family& f, int& hits) -> std::string {
    Triangle t = f.triangle();
    Plane p;
    do p.normal = f.gridPoint(3);
    while (p.normal == Vec3::Zero());
    p.d = p.normal.dot(f.feature(t));
    std::vector<Real*> v;
    collect(t, v);
    collect(p.normal, v);
    v.push_back(&p.d);
    f.perturb(v);
    if (!crux::queryable(p)) return {};  // (a normal whose square underflows is out of the domain)
    const bool native = crux::overlaps(t, p), exact = crux::exact::overlaps(t, p);
    hits += exact;
    if (native == exact) return {};
    return "triangle " + str(t) + " plane " + str(p.normal) + " d " + num(p.d) + " native " + std::to_string(native);
  });
}

TEST(NearDegenerate, TriangleTriangleEqualsExact) {
  runFamily("triangle_triangle", kCases, 105, [](Family& f, int& hits) -> std::string {
    Triangle t = f.triangle();
    Triangle u = f.triangle();
    u.a = f.feature(t);
    if (f.small(0, 2) == 0) u.b = f.feature(t);  // sharing an edge or coplanar-ish
    std::vector<Real*> v;
    collect(t, v);
    collect(u, v);
    f.perturb(v);
    const bool native = crux::overlaps(t, u), exact = crux::exact::overlaps(t, u);
    hits += exact;
    if (native != exact) return "triangles " + str(t) + " " + str(u) + " native " + std::to_string(native);
    if (crux::overlaps(u, t) != native) return "asymmetric: " + str(t) + " " + str(u);
    return {};
  });
}

TEST(NearDegenerate, RayTriangleEqualsExact) {
  runFamily("ray_triangle", kCases, 106, [](Family& f, int& hits) -> std::string {
    Triangle t = f.triangle();
    Ray r;
    Vec3 target = f.feature(t);
    do r.origin = f.gridPoint(8);
    while (r.origin == target);
    r.dir = target - r.origin;
    if (f.small(0, 3) == 0) r.origin = target;  // starting on the triangle
    std::vector<Real*> v;
    collect(t, v);
    collect(r.origin, v);
    collect(r.dir, v);
    f.perturb(v);
    if (!crux::queryable(r)) return {};  // (a direction whose square underflows is out of the domain)
    const auto native = crux::raycast(r, t);
    const auto exact = crux::exact::raycast(r, t);
    hits += exact.has_value();
    if (native.has_value() != exact.has_value())
      return "triangle " + str(t) + " ray " + str(r.origin) + " dir " + str(r.dir) + " native " +
             std::to_string(native.has_value());
    // The distance reported with a hit is that of the exact first hit up to rounding: relative
    // to t (the final rounding to Real) and to the inputs' magnitude (n·(v - o) is evaluated in
    // Wide from the inputs, so its absolute error scales with them, not with t).
    if (native) {
      double scale = 0;
      for (const Vec3* p : {&t.a, &t.b, &t.c, &r.origin}) scale = std::max(scale, double(p->cwiseAbs().maxCoeff()));
      const double tol = 64 * std::numeric_limits<Real>::epsilon() * (std::abs(*exact) + scale);
      if (!(std::abs(double(native->t) - *exact) <= tol))
        return "t " + num(native->t) + " exact " + num(*exact) + " triangle " + str(t) + " ray " + str(r.origin) +
               " dir " + str(r.dir);
    }
    return {};
  });
}

TEST(NearDegenerate, SegmentTriangleEqualsExact) {
  runFamily("segment_triangle", kCases, 107, [](Family& f, int& hits) -> std::string {
    Triangle t = f.triangle();
    Segment s;
    s.start = f.gridPoint(8);
    s.end = f.feature(t);
    if (f.small(0, 2) == 0) s.end = s.end + (s.end - s.start);  // through it
    if (f.small(0, 5) == 0) s.start = s.end;                       // a point
    std::vector<Real*> v;
    collect(t, v);
    collect(s.start, v);
    collect(s.end, v);
    f.perturb(v);
    const bool native = crux::intersects(s, t), exact = crux::exact::intersects(s, t);
    hits += exact;
    if (native == exact) return {};
    return "triangle " + str(t) + " segment " + str(s.start) + " " + str(s.end) + " native " + std::to_string(native);
  });
}

TEST(NearDegenerate, SphereAndPlanePairsEqualExact) {
  runFamily("sphere_plane", kCases, 108, [](Family& f, int& hits) -> std::string {
    const Vec3 x = f.gridPoint();
    Plane p;
    do p.normal = f.gridPoint(3);
    while (p.normal == Vec3::Zero());
    p.d = p.normal.dot(x);
    Sphere s{x + Vec3(Real(f.small(-1, 1)), Real(f.small(-1, 1)), Real(f.small(-1, 1))), Real(f.small(0, 1))};
    std::vector<Real*> v;
    collect(p.normal, v);
    v.push_back(&p.d);
    collect(s.center, v);
    v.push_back(&s.radius);
    f.perturb(v);
    s.radius = std::abs(s.radius);
    if (!crux::queryable(p)) return {};  // (a normal whose square underflows is out of the domain)
    const bool native = crux::overlaps(s, p), exact = crux::exact::overlaps(s, p);
    hits += exact;
    if (native == exact) return {};
    return "sphere " + str(s.center) + " r " + num(s.radius) + " plane " + str(p.normal) + " d " + num(p.d);
  });
  runFamily("sphere_aabb", kCases, 109, [](Family& f, int& hits) -> std::string {
    Vec3 lo = f.gridPoint(), hi = lo + Vec3(Real(f.small(0, 2)), Real(f.small(0, 2)), Real(f.small(0, 2)));
    Sphere s{lo + Vec3(Real(f.small(-2, 4)), Real(f.small(-2, 4)), Real(f.small(-2, 4))), Real(f.small(0, 2))};
    std::vector<Real*> v;
    collect(lo, v);
    collect(hi, v);
    collect(s.center, v);
    v.push_back(&s.radius);
    f.perturb(v);
    s.radius = std::abs(s.radius);
    const Aabb b{lo.cwiseMin(hi), lo.cwiseMax(hi)};
    const bool native = crux::overlaps(s, b), exact = crux::exact::overlaps(s, b);
    hits += exact;
    if (native == exact) return {};
    return "sphere " + str(s.center) + " r " + num(s.radius) + " aabb " + str(b.min) + " " + str(b.max);
  });
  runFamily("aabb_plane", kCases, 110, [](Family& f, int& hits) -> std::string {
    Vec3 lo = f.gridPoint(), hi = lo + Vec3(Real(f.small(0, 2)), Real(f.small(0, 2)), Real(f.small(0, 2)));
    Plane p;
    do p.normal = f.gridPoint(3);
    while (p.normal == Vec3::Zero());
    p.d = p.normal.dot(f.small(0, 1) ? lo : hi);
    std::vector<Real*> v;
    collect(lo, v);
    collect(hi, v);
    collect(p.normal, v);
    v.push_back(&p.d);
    f.perturb(v);
    if (!crux::queryable(p)) return {};  // (a normal whose square underflows is out of the domain)
    const Aabb b{lo.cwiseMin(hi), lo.cwiseMax(hi)};
    const bool native = crux::overlaps(b, p), exact = crux::exact::overlaps(b, p);
    hits += exact;
    if (native == exact) return {};
    return "aabb " + str(b.min) + " " + str(b.max) + " plane " + str(p.normal) + " d " + num(p.d);
  });
}

}  // namespace
