// Tests of src/geometry/overlap.cpp (the non-triangle pairs): regression tests named after the
// configuration they pin down, and seeded property tests against CGAL's exact answers
// (oracle/exact) in an integer-grid family (exact agreement required: touching, flat and
// coincident cases are frequent there) and a general-position family (random floats, random
// rotations), each with its hit rate checked to lie in [20%, 80%].

#include <gtest/gtest.h>

#include <cmath>
#include <crux/geometry/overlap.hpp>
#include <cstdio>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <utility>

#include "exact/exact.hpp"
#include "support/test_scale.hpp"
#include <crux/precondition.hpp>
#include "geometry/unchecked.hpp"
#include "support/bad_inputs.hpp"

namespace crux {
namespace {

// ---- printing (17 significant digits, so every case can be reproduced) -----------------------

std::string str(const Vec3& v) {
  std::ostringstream os;
  os.precision(17);
  os << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return os.str();
}
std::string str(Real x) {
  std::ostringstream os;
  os.precision(17);
  os << x;
  return os.str();
}
std::string str(const Sphere& s) { return "Sphere{center " + str(s.center) + ", radius " + str(s.radius) + "}"; }
std::string str(const Aabb& b) { return "Aabb{min " + str(b.min) + ", max " + str(b.max) + "}"; }
std::string str(const Obb& b) {
  return "Obb{center " + str(b.center) + ", half " + str(b.half) + ", axes " + str(Vec3(b.axes.col(0))) + " " +
         str(Vec3(b.axes.col(1))) + " " + str(Vec3(b.axes.col(2))) + "}";
}
std::string str(const Plane& p) { return "Plane{normal " + str(p.normal) + ", d " + str(p.d) + "}"; }

/// A hair's breadth: moving a touching configuration by 2^-20 must separate it. For the
/// magnitudes used in these tests (< 16), x ± 2^-20 is exact in float, and every predicate
/// polynomial of it is exact in double, so the expected answer is the true one in both
/// precisions. (A one-ulp move of a double is below what the Wide evaluation resolves in
/// double builds; the integer-grid guarantee does not cover it.)
constexpr Real kHair = Real(1.0 / (1 << 20));
Real below(Real x) { return x - kHair; }
Real above(Real x) { return x + kHair; }

Mat3 rotation(Real angle, const Vec3& axis) {
  return Quat(Eigen::AngleAxis<Real>(angle, axis.normalized())).toRotationMatrix();
}

/// Asserts overlaps(a, b) == want in both argument orders.
template <class A, class B>
::testing::AssertionResult overlapIs(bool want, const A& a, const B& b) {
  const bool ab = overlaps(a, b), ba = overlaps(b, a);
  if (ab == want && ba == want) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << str(a) << " vs " << str(b) << ": overlaps(a, b) = " << ab
                                       << ", overlaps(b, a) = " << ba << ", want " << want;
}

// ---- spheres ---------------------------------------------------------------------------------

TEST(OverlapSphereSphere, TouchingSpheres) {
  EXPECT_TRUE(overlapIs(true, Sphere{Vec3(0, 0, 0), 1}, Sphere{Vec3(3, 0, 0), 2}));
  EXPECT_TRUE(overlapIs(false, Sphere{Vec3(0, 0, 0), 1}, Sphere{Vec3(3, 0, 0), below(2)}));
  // A 3-4-5 diagonal contact.
  EXPECT_TRUE(overlapIs(true, Sphere{Vec3(1, 1, 1), 2}, Sphere{Vec3(4, 5, 1), 3}));
  EXPECT_TRUE(overlapIs(false, Sphere{Vec3(1, 1, 1), 2}, Sphere{Vec3(4, 5, 1), below(3)}));
}

TEST(OverlapSphereSphere, OneInsideTheOther) {
  // Balls, not spherical shells: containment intersects.
  EXPECT_TRUE(overlapIs(true, Sphere{Vec3(0, 0, 0), 10}, Sphere{Vec3(1, 0, 0), 1}));
}

TEST(OverlapSphereSphere, ZeroRadiusSpheresArePoints) {
  EXPECT_TRUE(overlapIs(true, Sphere{Vec3(2, 3, 4), 0}, Sphere{Vec3(2, 3, 4), 0}));
  EXPECT_TRUE(overlapIs(false, Sphere{Vec3(2, 3, 4), 0}, Sphere{Vec3(2, 3, above(4)), 0}));
  EXPECT_TRUE(overlapIs(true, Sphere{Vec3(0, 0, 5), 0}, Sphere{Vec3(0, 0, 0), 5}));  // point on the surface
}

TEST(OverlapSphereAabb, SphereTouchingABoxCorner) {
  const Aabb box{Vec3(0, 0, 0), Vec3(1, 1, 1)};
  // Corner (1,1,1); centre (3,3,2) is at distance sqrt(4 + 4 + 1) = 3.
  EXPECT_TRUE(overlapIs(true, Sphere{Vec3(3, 3, 2), 3}, box));
  EXPECT_TRUE(overlapIs(false, Sphere{Vec3(3, 3, 2), below(3)}, box));
}

TEST(OverlapSphereAabb, SphereTouchingAFaceAndInside) {
  const Aabb box{Vec3(0, 10, 20), Vec3(1, 11, 21)};  // per-axis bounds differ (the book's clamp bug)
  EXPECT_TRUE(overlapIs(true, Sphere{Vec3(Real(0.5), Real(10.5), 23), 2}, box));
  EXPECT_TRUE(overlapIs(false, Sphere{Vec3(Real(0.5), Real(10.5), 23), below(2)}, box));
  EXPECT_TRUE(overlapIs(true, Sphere{Vec3(Real(0.5), Real(10.5), Real(20.5)), 0}, box));  // point inside
}

TEST(OverlapSphereAabb, FlatBox) {
  const Aabb flat{Vec3(0, 0, 0), Vec3(2, 2, 0)};
  EXPECT_TRUE(overlapIs(true, Sphere{Vec3(1, 1, 3), 3}, flat));
  EXPECT_TRUE(overlapIs(false, Sphere{Vec3(1, 1, 3), below(3)}, flat));
}

TEST(OverlapSphereObb, SphereTouchingARotatedBoxCorner) {
  // Signed-permutation axes: local x = world -y, local y = world z, local z = world x.
  Mat3 axes;
  axes << 0, 0, 1, -1, 0, 0, 0, 1, 0;
  const Obb box{Vec3(1, 1, 1), Vec3(1, 2, 3), axes};
  // World corner at local (+1, +2, +3) = world (1 + 3, 1 - 1, 1 + 2) = (4, 0, 3).
  EXPECT_TRUE(overlapIs(true, Sphere{Vec3(6, -2, 4), 3}, box));  // distance sqrt(4 + 4 + 1)
  EXPECT_TRUE(overlapIs(false, Sphere{Vec3(6, -2, 4), below(3)}, box));
}

TEST(OverlapSphereObb, CentreInsideARotatedBox) {
  const Obb box{Vec3(1, 2, 3), Vec3(3, Real(0.5), 1), rotation(Real(0.8), Vec3(1, 1, 0))};
  EXPECT_TRUE(overlapIs(true, Sphere{Vec3(1, 2, 3), 0}, box));
}

TEST(OverlapSpherePlane, TangentSphere) {
  const Plane plane{Vec3(0, 0, 3), 6};  // z = 2, non-unit normal
  EXPECT_TRUE(overlapIs(true, Sphere{Vec3(5, 5, 0), 2}, plane));
  EXPECT_TRUE(overlapIs(false, Sphere{Vec3(5, 5, 0), below(2)}, plane));
  EXPECT_TRUE(overlapIs(true, Sphere{Vec3(5, 5, 4), 2}, plane));  // from the other side: not a half-space
  EXPECT_TRUE(overlapIs(false, Sphere{Vec3(5, 5, 4), below(2)}, plane));
  EXPECT_TRUE(overlapIs(true, Sphere{Vec3(7, -1, 2), 0}, plane));  // a point in the plane
}

// ---- boxes -----------------------------------------------------------------------------------

TEST(OverlapAabbAabb, BoxesTouchingAtAFaceAnEdgeAndACorner) {
  const Aabb a{Vec3(0, 0, 0), Vec3(1, 1, 1)};
  EXPECT_TRUE(overlapIs(true, a, Aabb{Vec3(1, 0, 0), Vec3(2, 1, 1)}));  // face
  EXPECT_TRUE(overlapIs(true, a, Aabb{Vec3(1, 1, 0), Vec3(2, 2, 1)}));  // edge
  EXPECT_TRUE(overlapIs(true, a, Aabb{Vec3(1, 1, 1), Vec3(2, 2, 2)}));  // corner
  EXPECT_TRUE(overlapIs(false, a, Aabb{Vec3(above(1), 1, 1), Vec3(2, 2, 2)}));
  EXPECT_TRUE(overlapIs(true, a, Aabb{Vec3(1, 1, 1), Vec3(1, 1, 1)}));  // a point box on the corner
}

TEST(OverlapAabbObb, BoxesTouchingAtAFaceAnEdgeAndACorner) {
  const Aabb a{Vec3(0, 0, 0), Vec3(2, 2, 2)};
  Mat3 swapXY;
  swapXY << 0, 1, 0, 1, 0, 0, 0, 0, 1;
  EXPECT_TRUE(overlapIs(true, a, Obb{Vec3(3, 1, 1), Vec3(1, 1, 1), swapXY}));  // face x = 2
  EXPECT_TRUE(overlapIs(true, a, Obb{Vec3(3, 3, 1), Vec3(1, 1, 1), swapXY}));  // edge x = y = 2
  // Local half extents (2, 1, 3) are world (1, 2, 3): x in [2,4], y in [2,6], z in [2,8].
  EXPECT_TRUE(overlapIs(true, a, Obb{Vec3(3, 4, 5), Vec3(2, 1, 3), swapXY}));  // corner (2,2,2)
  EXPECT_TRUE(overlapIs(false, a, Obb{Vec3(3, 4, above(5)), Vec3(2, 1, 3), swapXY}));
  EXPECT_TRUE(overlapIs(false, a, Obb{Vec3(3, above(3), 1), Vec3(1, 1, 1), swapXY}));
}

TEST(OverlapAabbObb, SeparatedOnlyByAnEdgeEdgeAxis) {
  // The box's nearest edge runs along (1,-1,0) just past the AABB's vertical edge at x = y = 1;
  // only the cross axis z × (1,-1,0) ∥ (1,1,0) separates them (gap 2·0.25 along it). The
  // book's SAT crossed each box's axes with its own and reported an overlap.
  const Real s = std::sqrt(Real(0.5));
  Mat3 axes;
  axes.col(0) = Vec3(s, -s, 0);
  axes.col(1) = Vec3(Real(0.5), Real(0.5), s);
  axes.col(2) = Vec3(Real(0.5), Real(0.5), -s);
  const Real h = 1, gap = Real(0.25);
  const Obb b{Vec3(1 + gap + h, 1 + gap + h, 0), Vec3(h, h, h), axes};
  EXPECT_TRUE(overlapIs(false, Aabb{Vec3(-1, -1, -1), Vec3(1, 1, 1)}, b));
  // Moved back by twice the gap along the diagonal, they overlap.
  const Obb closer{b.center - Vec3(2 * gap, 2 * gap, 0), b.half, axes};
  EXPECT_TRUE(overlapIs(true, Aabb{Vec3(-1, -1, -1), Vec3(1, 1, 1)}, closer));
}

TEST(OverlapObbObb, SeparatedOnlyByAnEdgeEdgeAxisWhereTheBooksSatSaysYes) {
  // As above with A an OBB, and both boxes then rotated together about an arbitrary axis.
  const Real s = std::sqrt(Real(0.5));
  Mat3 axes;
  axes.col(0) = Vec3(s, -s, 0);
  axes.col(1) = Vec3(Real(0.5), Real(0.5), s);
  axes.col(2) = Vec3(Real(0.5), Real(0.5), -s);
  const Mat3 r = rotation(Real(1.1), Vec3(2, -1, 3));
  const Obb a{Vec3(0, 0, 0), Vec3(1, 1, 1), r};
  const Obb b{r * Vec3(Real(2.25), Real(2.25), 0), Vec3(1, 1, 1), r * axes};
  EXPECT_TRUE(overlapIs(false, a, b));
  const Obb closer{r * Vec3(Real(1.75), Real(1.75), 0), Vec3(1, 1, 1), r * axes};
  EXPECT_TRUE(overlapIs(true, a, closer));
}

TEST(OverlapObbObb, BoxesTouchingAtAFaceAnEdgeAndACorner) {
  Mat3 p;  // signed permutation: local x = -z, local y = x, local z = -y
  p << 0, 1, 0, 0, 0, -1, -1, 0, 0;
  const Obb a{Vec3(0, 0, 0), Vec3(1, 2, 3), Mat3::Identity()};  // x in [-1,1], y in [-2,2], z in [-3,3]
  // b's world half extents: x 2 (its local y), y 3 (its local z), z 1 (its local x).
  const Vec3 half(1, 2, 3);
  EXPECT_TRUE(overlapIs(true, a, Obb{Vec3(3, 0, 0), half, p}));  // face x = 1
  EXPECT_TRUE(overlapIs(true, a, Obb{Vec3(3, 5, 0), half, p}));  // edge x = 1, y = 2
  EXPECT_TRUE(overlapIs(true, a, Obb{Vec3(3, 5, 4), half, p}));  // corner (1, 2, 3)
  EXPECT_TRUE(overlapIs(false, a, Obb{Vec3(3, 5, above(4)), half, p}));
  EXPECT_TRUE(overlapIs(false, a, Obb{Vec3(above(3), 0, 0), half, p}));
}

TEST(OverlapObbObb, ParallelEdgesHaveZeroCrossAxes) {
  // Both boxes turned about z: three of the nine cross axes vanish; the face axes decide.
  const Mat3 r = rotation(Real(0.4), Vec3(0, 0, 1));
  const Obb a{Vec3(0, 0, 0), Vec3(1, 1, 1), r};
  EXPECT_TRUE(overlapIs(false, a, Obb{r * Vec3(Real(2.5), 0, 0), Vec3(Real(0.5), 4, 4), r}));
  EXPECT_TRUE(overlapIs(true, a, Obb{r * Vec3(Real(1.25), 0, 0), Vec3(Real(0.5), 4, 4), r}));
  // Identical orientations stacked with a gap in z.
  EXPECT_TRUE(overlapIs(false, a, Obb{Vec3(0, 0, Real(2.5)), Vec3(1, 1, Real(0.25)), r}));
}

TEST(OverlapObbObb, FlatBoxesInTheSamePlane) {
  // Two squares in z = 0, one turned 45°: they touch only when the turned square's corner
  // reaches the other's edge (exact for the axis-aligned pair of flat boxes below).
  const Obb a{Vec3(0, 0, 0), Vec3(1, 1, 0), Mat3::Identity()};
  EXPECT_TRUE(overlapIs(true, a, Obb{Vec3(2, 0, 0), Vec3(1, 1, 0), Mat3::Identity()}));
  EXPECT_TRUE(overlapIs(false, a, Obb{Vec3(above(2), 0, 0), Vec3(1, 1, 0), Mat3::Identity()}));
  EXPECT_TRUE(overlapIs(false, a, Obb{Vec3(0, 0, Real(0.5)), Vec3(1, 1, 0), Mat3::Identity()}));
  EXPECT_TRUE(overlapIs(true, a, Obb{Vec3(Real(1.5), 0, 0), Vec3(1, 1, 0), rotation(Real(0.7854), Vec3(0, 0, 1))}));
}

TEST(OverlapAabbPlane, PlaneThroughACorner) {
  const Aabb box{Vec3(0, 0, 0), Vec3(1, 1, 1)};
  EXPECT_TRUE(overlapIs(true, box, Plane{Vec3(1, 1, 1), 3}));  // only (1,1,1)
  EXPECT_TRUE(overlapIs(false, box, Plane{Vec3(1, 1, 1), above(3)}));
  EXPECT_TRUE(overlapIs(true, box, Plane{Vec3(-2, 1, 1), 2}));  // only (0,1,1)
  EXPECT_TRUE(overlapIs(false, box, Plane{Vec3(-2, 1, 1), above(2)}));
}

TEST(OverlapAabbPlane, FlatBoxInAndBesideThePlane) {
  const Aabb flat{Vec3(0, 0, 5), Vec3(3, 3, 5)};
  EXPECT_TRUE(overlapIs(true, flat, Plane{Vec3(0, 0, -2), -10}));
  EXPECT_TRUE(overlapIs(false, flat, Plane{Vec3(0, 0, 1), above(5)}));
}

TEST(OverlapObbPlane, PlaneThroughARotatedBoxCorner) {
  Mat3 p;
  p << 0, 0, 1, 1, 0, 0, 0, 1, 0;                  // local x = world y, local y = world z, local z = world x
  const Obb box{Vec3(1, 1, 1), Vec3(1, 2, 3), p};  // world x in [-2,4], y in [0,2], z in [-1,3]
  EXPECT_TRUE(overlapIs(true, box, Plane{Vec3(1, 1, 1), 9}));  // corner (4, 2, 3)
  EXPECT_TRUE(overlapIs(false, box, Plane{Vec3(1, 1, 1), above(9)}));
  EXPECT_TRUE(overlapIs(true, box, Plane{Vec3(1, 1, 1), -3}));  // corner (-2, 0, -1)
  EXPECT_TRUE(overlapIs(false, box, Plane{Vec3(1, 1, 1), below(-3)}));
}

// ---- planes ----------------------------------------------------------------------------------

TEST(OverlapPlanePlane, ParallelDistinctPlanes) {
  EXPECT_TRUE(overlapIs(false, Plane{Vec3(0, 0, 1), 1}, Plane{Vec3(0, 0, 2), 3}));     // z = 1, z = 1.5
  EXPECT_TRUE(overlapIs(false, Plane{Vec3(1, 2, 3), 1}, Plane{Vec3(-2, -4, -6), 3}));  // opposite normals
}

TEST(OverlapPlanePlane, CoincidentPlanesWithScaledNormals) {
  EXPECT_TRUE(overlapIs(true, Plane{Vec3(0, 0, 2), 2}, Plane{Vec3(0, 0, -1), -1}));
  EXPECT_TRUE(overlapIs(true, Plane{Vec3(1, 2, 3), 4}, Plane{Vec3(3, 6, 9), 12}));
  EXPECT_TRUE(overlapIs(true, Plane{Vec3(1, 2, 3), 0}, Plane{Vec3(-3, -6, -9), 0}));
}

TEST(OverlapPlanePlane, NonParallelPlanesAlwaysMeet) {
  EXPECT_TRUE(overlapIs(true, Plane{Vec3(0, 0, 1), 100}, Plane{Vec3(0, 1, 1), -50}));
  // Almost parallel, but not exactly: they still meet (far away).
  EXPECT_TRUE(overlapIs(true, Plane{Vec3(1, 0, 0), 0}, Plane{Vec3(1, 0, Real(1) / 1024), 1}));
}

// ---- property tests against the exact oracle -------------------------------------------------

/// Number of cases per family and pair.
const int kCases = crux::test::scaledCases(100000);  // CRUX_TEST_SCALE (support/test_scale.hpp)

/// Draws cases with gen, compares crux (both argument orders) with the exact oracle, and
/// checks the family's hit rate. Stops after 10 reported mismatches.
template <class Gen>
void checkFamily(const char* name, std::uint64_t seed, Gen gen) {
  std::mt19937_64 rng(seed);
  long hits = 0;
  int failures = 0;
  for (int i = 0; i < kCases && failures < 10; ++i) {
    const auto [a, b] = gen(rng);
    const bool want = exact::overlaps(a, b);
    const bool ab = overlaps(a, b), ba = overlaps(b, a);
    hits += want;
    if (ab != want || ba != want) {
      ++failures;
      ADD_FAILURE() << name << " case " << i << ": " << str(a) << " vs " << str(b) << ": exact " << want
                    << ", crux overlaps(a, b) " << ab << ", overlaps(b, a) " << ba;
    }
  }
  EXPECT_EQ(failures, 0) << name;
  const double rate = double(hits) / kCases;
  std::printf("%-28s %d cases, hit rate %.3f\n", name, kCases, rate);
  EXPECT_GE(rate, 0.2) << name;
  EXPECT_LE(rate, 0.8) << name;
}

// Integer grid: small integers, sometimes scaled by up to 10 so that coordinates reach the
// guaranteed range (|x| <= 64); OBB axes are signed permutations. Touching, flat (zero extent),
// zero-radius and coincident configurations are all frequent.
struct Grid {
  std::mt19937_64& rng;
  int scale;

  explicit Grid(std::mt19937_64& r) : rng(r), scale(pick(0, 3) == 0 ? pick(2, 10) : 1) {}
  int pick(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); }
  Real n(int lo, int hi) { return Real(pick(lo, hi) * scale); }
  Vec3 v(int lo, int hi) { return Vec3(n(lo, hi), n(lo, hi), n(lo, hi)); }
  Sphere sphere() { return {v(-2, 2), n(0, 3)}; }
  Aabb aabb() {
    const Vec3 lo = v(-2, 2);
    return {lo, lo + v(0, 4)};
  }
  Mat3 signedPermutation() {
    int perm[3] = {0, 1, 2};
    std::shuffle(perm, perm + 3, rng);
    Mat3 m = Mat3::Zero();
    for (int i = 0; i < 3; ++i) m(perm[i], i) = pick(0, 1) ? Real(1) : Real(-1);
    return m;
  }
  Obb obb() { return {v(-2, 2), v(0, 2), signedPermutation()}; }
  Vec3 normal() {
    Vec3 nrm;
    do {
      nrm = Vec3(Real(pick(-2, 2)), Real(pick(-2, 2)), Real(pick(-2, 2)));
    } while (nrm.isZero());
    return nrm;
  }
  Plane plane() { return {normal(), n(-6, 6)}; }
};

// General position: random floats; OBBs with uniformly random rotations.
struct General {
  std::mt19937_64& rng;

  explicit General(std::mt19937_64& r) : rng(r) {}
  Real u(double lo, double hi) { return Real(std::uniform_real_distribution<double>(lo, hi)(rng)); }
  Vec3 v(double lo, double hi) { return Vec3(u(lo, hi), u(lo, hi), u(lo, hi)); }
  Sphere sphere() { return {v(-3, 3), u(0.5, 3)}; }
  Aabb aabb() {
    const Vec3 lo = v(-4, 2);
    return {lo, lo + v(0.5, 5)};
  }
  Mat3 rotation() {
    std::normal_distribution<double> g(0, 1);
    Eigen::Quaterniond q(g(rng), g(rng), g(rng), g(rng));
    return q.normalized().toRotationMatrix().cast<Real>();
  }
  Obb obb() { return {v(-3, 3), v(0.3, 2.5), rotation()}; }
  Plane plane() {
    std::normal_distribution<double> g(0, 1);
    const Vec3 nrm(Real(g(rng)), Real(g(rng)), Real(g(rng)));
    return {nrm, nrm.dot(v(-3, 3))};  // through a random point of the region
  }
};

TEST(OverlapProperty, SphereSphere) {
  checkFamily("sphere-sphere grid", 101, [](std::mt19937_64& r) {
    Grid g(r);
    return std::pair{g.sphere(), g.sphere()};
  });
  checkFamily("sphere-sphere general", 102, [](std::mt19937_64& r) {
    General g(r);
    return std::pair{g.sphere(), g.sphere()};
  });
}

TEST(OverlapProperty, SphereAabb) {
  checkFamily("sphere-aabb grid", 201, [](std::mt19937_64& r) {
    Grid g(r);
    return std::pair{g.sphere(), g.aabb()};
  });
  checkFamily("sphere-aabb general", 202, [](std::mt19937_64& r) {
    General g(r);
    return std::pair{g.sphere(), g.aabb()};
  });
}

TEST(OverlapProperty, SphereObb) {
  checkFamily("sphere-obb grid", 301, [](std::mt19937_64& r) {
    Grid g(r);
    return std::pair{g.sphere(), g.obb()};
  });
  checkFamily("sphere-obb general", 302, [](std::mt19937_64& r) {
    General g(r);
    return std::pair{g.sphere(), g.obb()};
  });
}

TEST(OverlapProperty, SpherePlane) {
  checkFamily("sphere-plane grid", 401, [](std::mt19937_64& r) {
    Grid g(r);
    return std::pair{g.sphere(), g.plane()};
  });
  checkFamily("sphere-plane general", 402, [](std::mt19937_64& r) {
    General g(r);
    return std::pair{g.sphere(), g.plane()};
  });
}

TEST(OverlapProperty, AabbAabb) {
  checkFamily("aabb-aabb grid", 501, [](std::mt19937_64& r) {
    Grid g(r);
    return std::pair{g.aabb(), g.aabb()};
  });
  checkFamily("aabb-aabb general", 502, [](std::mt19937_64& r) {
    General g(r);
    return std::pair{g.aabb(), g.aabb()};
  });
}

TEST(OverlapProperty, AabbObb) {
  checkFamily("aabb-obb grid", 601, [](std::mt19937_64& r) {
    Grid g(r);
    return std::pair{g.aabb(), g.obb()};
  });
  checkFamily("aabb-obb general", 602, [](std::mt19937_64& r) {
    General g(r);
    return std::pair{g.aabb(), g.obb()};
  });
}

TEST(OverlapProperty, AabbPlane) {
  checkFamily("aabb-plane grid", 701, [](std::mt19937_64& r) {
    Grid g(r);
    return std::pair{g.aabb(), g.plane()};
  });
  checkFamily("aabb-plane general", 702, [](std::mt19937_64& r) {
    General g(r);
    return std::pair{g.aabb(), g.plane()};
  });
}

TEST(OverlapProperty, ObbObb) {
  checkFamily("obb-obb grid", 801, [](std::mt19937_64& r) {
    Grid g(r);
    return std::pair{g.obb(), g.obb()};
  });
  checkFamily("obb-obb general", 802, [](std::mt19937_64& r) {
    General g(r);
    return std::pair{g.obb(), g.obb()};
  });
}

TEST(OverlapProperty, ObbPlane) {
  checkFamily("obb-plane grid", 901, [](std::mt19937_64& r) {
    Grid g(r);
    return std::pair{g.obb(), g.plane()};
  });
  checkFamily("obb-plane general", 902, [](std::mt19937_64& r) {
    General g(r);
    return std::pair{g.obb(), g.plane()};
  });
}

TEST(OverlapProperty, PlanePlane) {
  // Random planes are almost never parallel, so both families make parallel pairs on purpose:
  // the second normal is the first times a multiplier that keeps it exact (an integer in the
  // grid, ±2^k in general position), and half of those pairs are made coincident the same way.
  checkFamily("plane-plane grid", 1001, [](std::mt19937_64& r) {
    Grid g(r);
    const Plane a = g.plane();
    Plane b = g.plane();
    if (g.pick(0, 9) < 7) {
      const int k = g.pick(0, 1) ? g.pick(1, 2) : -g.pick(1, 2);
      b.normal = a.normal * Real(k);
      if (g.pick(0, 1)) b.d = a.d * Real(k);
    }
    return std::pair{a, b};
  });
  checkFamily("plane-plane general", 1002, [](std::mt19937_64& r) {
    General g(r);
    const Plane a = g.plane();
    Plane b = g.plane();
    const int mode = std::uniform_int_distribution<int>(0, 2)(r);
    if (mode > 0) {
      const Real k = std::ldexp(Real(1), std::uniform_int_distribution<int>(-3, 3)(r)) * (r() % 2 ? 1 : -1);
      b.normal = a.normal * k;
      if (mode == 2) b.d = a.d * k;
    }
    return std::pair{a, b};
  });
}

// Non-queryable inputs (precondition.hpp, rule::kPrimitive): the routines behind the public entries
// (geometry/unchecked.hpp, what those entries run in release builds and the mesh, scene and contact
// layers call) give an unspecified answer, but return without undefined behaviour, which the
// sanitizer stage checks here.
TEST(OverlapPreconditions, NonQueryableInputsReturnWithoutUndefinedBehaviour) {
  const test_support::BadPrimitives bad = test_support::badPrimitives();
  const Sphere sphere{Vec3::Zero(), 1};
  const Aabb box{Vec3::Constant(-1), Vec3::Constant(1)};
  const Obb obb{Vec3::Zero(), Vec3::Ones(), Mat3::Identity()};
  const Plane plane{};
  int calls = 0;
  // each pair in the layer's order (Triangle < Sphere < Aabb < Obb < Plane: the routines have no
  // reversed form; the public one is derived in overlap.hpp)
  const auto pair = [](const auto& x, const auto& y) {
    using X = std::decay_t<decltype(x)>;
    using Y = std::decay_t<decltype(y)>;
    if constexpr (detail::ShapeRank<X>::value <= detail::ShapeRank<Y>::value)
      return unchecked::overlaps(x, y);
    else
      return unchecked::overlaps(y, x);
  };
  const auto all = [&](const auto& shape) {
    calls += 4;
    (void)pair(sphere, shape), (void)pair(box, shape), (void)pair(obb, shape), (void)pair(plane, shape);
  };
  for (const Sphere& s : bad.spheres) all(s);
  for (const Aabb& b : bad.aabbs) all(b);
  for (const Obb& b : bad.obbs) all(b);
  for (const Plane& p : bad.planes) all(p);
  EXPECT_GT(calls, 150);
  EXPECT_TRUE(unchecked::overlaps(sphere, box) && unchecked::overlaps(box, obb) && unchecked::overlaps(obb, plane) && unchecked::overlaps(sphere, plane));
}

// In debug builds (CRUX_CHECK_PRIMITIVE_PRECONDITIONS, on without NDEBUG) a non-queryable input
// aborts with a message naming the query.
TEST(OverlapPreconditions, DebugBuildsAbortNamingTheQuery) {
  if (!CRUX_CHECK_PRIMITIVE_PRECONDITIONS)
    GTEST_SKIP() << "the primitive check is off in this build (NDEBUG)";
  EXPECT_DEATH((void)overlaps(Sphere{Vec3::Zero(), -1}, Aabb{Vec3::Zero(), Vec3::Ones()}),
               "precondition violated in overlaps\\(Sphere, Aabb\\)");
  EXPECT_DEATH((void)overlaps(Plane{Vec3::Zero(), 0}, Plane{}),
               "precondition violated in overlaps\\(Plane, Plane\\)");
}

}  // namespace
}  // namespace crux
