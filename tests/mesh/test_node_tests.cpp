/// Tests of the mesh layer's internal node tests (src/mesh/node_tests.hpp) and the lane helpers
/// they use (src/mesh/lanes.hpp): ObbBoxTest against the scalar separating-axis test it replaced
/// (same answers, case by case) and against boxes that certainly meet (never "no").
#include "mesh/lanes.hpp"
#include "mesh/node_tests.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

namespace crux::mesh_detail {
namespace {

/// The scalar test ObbBoxTest::touches was, written out: the OBB's world box grown
/// by the pad against b, then the OBB's three face axes with |R| + kAxisPad, all doubled.
bool scalarTouches(const Mat3& axes, Real pad, const Vec3& center, const Vec3& half, const Aabb& b) {
  const Mat3 absR = axes.cwiseAbs().array() + kAxisPad;
  const Vec3 ext = absR * half + Vec3::Constant(pad);
  const Vec3 lo = center - ext, hi = center + ext, center2 = 2 * center, half2 = 2 * half;
  if ((lo.array() > b.max.array()).any() || (hi.array() < b.min.array()).any()) return false;
  const Vec3 t2 = center2 - (b.min + b.max);
  const Vec3 h2 = b.max - b.min;
  for (int j = 0; j < 3; ++j)
    if (std::fabs(t2.dot(axes.col(j))) > absR.col(j).dot(h2) + half2[j] + 2 * pad) return false;
  return true;
}

Mat3 randomRotation(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  return Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix().cast<Real>();
}

/// Quarter and half turns (signed permutations): integer-grid boxes then touch exactly.
Mat3 randomSignedPermutation(std::mt19937_64& rng) {
  int p[3] = {0, 1, 2};
  std::shuffle(p, p + 3, rng);
  Mat3 m = Mat3::Zero();
  for (int i = 0; i < 3; ++i) m(i, p[i]) = (rng() & 1) ? Real(1) : Real(-1);
  return m;
}

/// A wide node whose first n lanes hold boxes with corners from coordinate() (each axis's two
/// draws sorted) and whose other lanes are unused (empty boxes); the boxes are also written out.
template <class Coordinate>
WideBvhNode randomNode(int n, Coordinate coordinate, Aabb (&boxes)[4]) {
  WideBvhNode node;
  for (int l = 0; l < 4; ++l) {
    Aabb& b = boxes[l];
    if (l < n) {
      for (int k = 0; k < 3; ++k) {
        const Real a = coordinate(), c = coordinate();
        b.min[k] = std::min(a, c);
        b.max[k] = std::max(a, c);
      }
    } else {
      b = Aabb::empty();
    }
    node.minX[l] = b.min.x(), node.minY[l] = b.min.y(), node.minZ[l] = b.min.z();
    node.maxX[l] = b.max.x(), node.maxY[l] = b.max.y(), node.maxZ[l] = b.max.z();
    node.child[l] = l < n ? 0u : WideBvhNode::kEmpty;
    node.count[l] = l < n ? 1u : 0u;
  }
  return node;
}

TEST(ObbBoxTest, SameAnswersAsTheScalarTest) {
  std::mt19937_64 rng(15);
  std::uniform_real_distribution<Real> u(-2, 2), size(0, 1.5);
  std::uniform_int_distribution<int> grid(-3, 3), gridSize(0, 2);
  int yes = 0, no = 0;
  for (int i = 0; i < 200000; ++i) {
    const bool onGrid = i % 2 == 1;  // integer grid and signed permutations: exact ties
    const Mat3 axes = onGrid ? randomSignedPermutation(rng) : randomRotation(rng);
    const Real pad = onGrid ? Real(0) : Real(i % 3) * Real(1e-3);
    const Vec3 center = onGrid ? Vec3(Real(grid(rng)), Real(grid(rng)), Real(grid(rng))) : Vec3(u(rng), u(rng), u(rng));
    const Vec3 half = onGrid ? Vec3(Real(gridSize(rng)), Real(gridSize(rng)), Real(gridSize(rng)))
                             : Vec3(size(rng), size(rng), size(rng));
    Aabb b;
    for (int k = 0; k < 3; ++k) {
      const Real a = onGrid ? Real(grid(rng)) : u(rng), c = onGrid ? Real(grid(rng)) : u(rng);
      b.min[k] = std::min(a, c);
      b.max[k] = std::max(a, c);
    }
    const ObbBoxTest test(axes, pad);
    const bool got = test.touches(test.place(center, half), b);
    ASSERT_EQ(got, scalarTouches(axes, pad, center, half, b)) << "case " << i;
    (got ? yes : no) += 1;
  }
  // both answers well represented (the test is not vacuous)
  EXPECT_GT(yes, 20000);
  EXPECT_GT(no, 20000);
}

TEST(ObbBoxTest, FourLaneTestGivesEachBoxTheOneBoxAnswer) {
  // touches4 on a wide node whose lanes hold four boxes (or fewer: the rest empty) answers, bit
  // for bit, what touches answers for each box; the grid half gives exact ties
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<Real> u(-2, 2), size(0, 1.5);
  std::uniform_int_distribution<int> grid(-3, 3), gridSize(0, 2), used(1, 4);
  int yes = 0, no = 0;
  for (int i = 0; i < 50000; ++i) {
    const bool onGrid = i % 2 == 1;
    const Mat3 axes = onGrid ? randomSignedPermutation(rng) : randomRotation(rng);
    const Real pad = onGrid ? Real(0) : Real(i % 3) * Real(1e-3);
    const Vec3 center = onGrid ? Vec3(Real(grid(rng)), Real(grid(rng)), Real(grid(rng))) : Vec3(u(rng), u(rng), u(rng));
    const Vec3 half = onGrid ? Vec3(Real(gridSize(rng)), Real(gridSize(rng)), Real(gridSize(rng)))
                             : Vec3(size(rng), size(rng), size(rng));
    const ObbBoxTest test(axes, pad);
    const ObbBoxTest::Placed placed = test.place(center, half);
    const int n = used(rng);
    Aabb boxes[4];
    const WideBvhNode node = randomNode(n, [&] { return onGrid ? Real(grid(rng)) : u(rng); }, boxes);
    const unsigned mask = test.touches4(placed, node);
    for (int l = 0; l < 4; ++l) {
      const bool want = l < n && test.touches(placed, boxes[l]);
      ASSERT_EQ(bool(mask >> l & 1u), want) << "case " << i << " lane " << l << " of " << n;
      if (l < n) (want ? yes : no) += 1;
    }
    ASSERT_EQ(mask & ~15u, 0u);
  }
  EXPECT_GT(yes, 10000);
  EXPECT_GT(no, 10000);
}

TEST(ObbBoxTest, NeverSaysNoForBoxesThatMeet) {
  // a point inside the OBB and a box around it (possibly just touching it at that point)
  std::mt19937_64 rng(16);
  std::uniform_real_distribution<Real> u(-1, 1), size(0, 1);
  for (int i = 0; i < 100000; ++i) {
    const Mat3 axes = randomRotation(rng);
    const Vec3 center(u(rng), u(rng), u(rng)), half(size(rng), size(rng), size(rng));
    const Vec3 local(u(rng) * half.x(), u(rng) * half.y(), u(rng) * half.z());
    const Vec3 p = center + axes * local;
    Aabb b;
    for (int k = 0; k < 3; ++k) {
      const bool touchOnly = i % 4 == 0;  // p on the box's boundary
      b.min[k] = touchOnly && k == 0 ? p[k] : p[k] - size(rng);
      b.max[k] = p[k] + size(rng);
    }
    const Real pad = kNodeBoxPad * Real(4);  // the rounding of axes * local and the sums above
    const ObbBoxTest test(axes, pad);
    ASSERT_TRUE(test.touches(test.place(center, half), b)) << "case " << i;
  }
}

TEST(BoxSquaredDistance, FourLaneFormIsTheOneBoxFormBitForBit) {
  // boxSquaredDistances4 on a wide node's lanes (some empty) equals boxSquaredDistance of each
  // lane's box bit for bit (the closest-point walk's keys and the sphere collider's node test
  // rest on it), for points inside, on and outside the boxes; an empty lane gives +inf.
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<Real> u(-2, 2);
  std::uniform_int_distribution<int> grid(-3, 3), used(1, 4);
  int inside = 0, outside = 0;
  for (int i = 0; i < 50000; ++i) {
    const bool onGrid = i % 2 == 1;
    auto pick = [&] { return onGrid ? Real(grid(rng)) : u(rng); };
    const Vec3 p(pick(), pick(), pick());
    const int n = used(rng);
    Aabb boxes[4];
    const WideBvhNode node = randomNode(n, pick, boxes);
    const Lanes d = boxSquaredDistances4(node, p);
    for (int l = 0; l < 4; ++l) {
      if (l >= n) {
        ASSERT_EQ(d[l], std::numeric_limits<Real>::infinity()) << "case " << i << " lane " << l;
        continue;
      }
      const Real want = boxSquaredDistance(boxes[l], p), got = d[l];
      ASSERT_EQ(std::memcmp(&got, &want, sizeof want), 0) << "case " << i << " lane " << l << ": " << got << " vs " << want;
      (want == 0 ? inside : outside) += 1;
      // and it is the squared distance to the box's closest point, up to rounding
      const Real ref = (p.cwiseMax(boxes[l].min).cwiseMin(boxes[l].max) - p).squaredNorm();
      ASSERT_NEAR(want, ref, 8 * std::numeric_limits<Real>::epsilon() * (ref + 1));
    }
  }
  EXPECT_GT(inside, 5000);
  EXPECT_GT(outside, 50000);
}

TEST(Lanes, MaskHasOneBitPerLaneInOrder) {
  const Lanes a{1, 2, 3, 4}, b{0, 2, 5, 1};
  EXPECT_EQ(laneMask(a > b), 0b1001u);
  EXPECT_EQ(laneMask(a >= b), 0b1011u);
  EXPECT_EQ(laneMask(a < b), 0b0100u);
  EXPECT_FALSE(anyOf3(a < Lanes{0, 0, 0, 5}));  // lane 3 ignored
  EXPECT_TRUE(anyOf3(a < Lanes{0, 0, 4, 0}));
  const Lanes n{-1, 0, -0.0, -2.5};
  const Lanes m = lanesAbs(n);
  EXPECT_EQ(m[0], 1);
  EXPECT_EQ(m[2], 0);
  EXPECT_FALSE(std::signbit(m[2]));
  EXPECT_EQ(m[3], 2.5);
}

}  // namespace
}  // namespace crux::mesh_detail
