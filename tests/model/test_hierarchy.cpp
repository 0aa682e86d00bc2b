// Tests of src/model/hierarchy.cpp (ModelHierarchy) and the transform helpers of
// src/model/rigid.cpp (validate(Transform), quatFromEulerDegrees): world = parent ∘ local
// against an independent double-precision composition, cycle rejection, re-parenting on remove
// and setParent keeping world poses, descendants at every level, a 10,000-deep chain, the
// moved set, id reuse, input validation, a long random operation sequence against a reference
// forest, and world transforms kept current by setLocal itself (eager; reads never write).

#include <crux/model/hierarchy.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "support/test_scale.hpp"  // CRUX_TEST_SCALE: fewer steps in the sanitizer stage

namespace crux {
namespace {

constexpr double kEps = double(std::numeric_limits<Real>::epsilon());

std::string str(double x) {
  std::ostringstream os;
  os.precision(17);
  os << x;
  return os.str();
}
std::string str(const Vec3& v) { return "(" + str(v.x()) + ", " + str(v.y()) + ", " + str(v.z()) + ")"; }
std::string str(const Transform& t) {
  return "Transform{q=(" + str(t.rotation.w()) + ", " + str(t.rotation.x()) + ", " + str(t.rotation.y()) + ", " +
         str(t.rotation.z()) + "), t=" + str(t.translation) + "}";
}

std::shared_ptr<const Mesh> triangleMesh() {
  static const auto mesh = std::make_shared<const Mesh>(
      std::vector<Vec3>{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)}, std::vector<TriangleIndices>{{0, 1, 2}}, "tri");
  return mesh;
}

Transform make(const Quat& q, const Vec3& t) {
  Transform x;
  x.rotation = q;
  x.translation = t;
  return x;
}

Transform translation(Real x, Real y, Real z) { return make(Quat::Identity(), Vec3(x, y, z)); }

Quat randomRotation(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0, 1);
  Eigen::Vector4d q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  return Quat(Real(q[0]), Real(q[1]), Real(q[2]), Real(q[3]));
}

Transform randomTransform(std::mt19937_64& rng, double range) {
  std::uniform_real_distribution<double> u(-range, range);
  return make(randomRotation(rng), Vec3(Real(u(rng)), Real(u(rng)), Real(u(rng))));
}

/// A rigid transform in double, composed independently of crux (Eigen isometries).
Eigen::Isometry3d toDouble(const Transform& t) {
  Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
  m.linear() = t.rotation.cast<double>().normalized().toRotationMatrix();
  m.translation() = t.translation.cast<double>();
  return m;
}

/// World transform composed in double from the locals along the parent chain.
Eigen::Isometry3d referenceWorld(const ModelHierarchy& h, ModelId id) {
  Eigen::Isometry3d w = Eigen::Isometry3d::Identity();
  for (ModelId a = id; a != kNoModel; a = h.parent(a)) w = toDouble(h.local(a)) * w;
  return w;
}

/// Largest distance between the images of a few probe points under a crux transform and a
/// double reference.
double mismatch(const Transform& t, const Eigen::Isometry3d& ref) {
  const Eigen::Vector3d probes[4] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  double worst = 0;
  for (const Eigen::Vector3d& p : probes) {
    const Eigen::Vector3d mine = t.apply(p.cast<Real>()).cast<double>();
    worst = std::max(worst, (mine - ref * p).norm());
  }
  return worst;
}

/// Tolerance of a composed world transform: each composition rounds the rotation matrix and
/// the rotated translation by a few ulps (quaternion product + normalisation ≈ 4ε, rotating a
/// vector ≈ 6ε relative to the magnitudes involved), so a chain of n locals with translations
/// up to `scale` is within about 10ε·n·scale; 32ε·n·scale is used.
double chainTolerance(int depth, double scale) { return 32 * kEps * (depth + 1) * (scale + 1); }

// ---------------------------------------------------------------------------------------------
// World transforms.

TEST(Hierarchy, WorldIsParentComposedWithLocalOverThreeLevels) {
  std::mt19937_64 rng(0x41E);
  for (int round = 0; round < 200; ++round) {
    ModelHierarchy h;
    const Transform l0 = randomTransform(rng, 10), l1 = randomTransform(rng, 10), l2 = randomTransform(rng, 10);
    const ModelId a = h.add(triangleMesh(), l0);
    const ModelId b = h.add(triangleMesh(), l1, a);
    const ModelId c = h.add(triangleMesh(), l2, b);
    const Eigen::Isometry3d ref = toDouble(l0) * toDouble(l1) * toDouble(l2);
    ASSERT_LE(mismatch(h.world(c), ref), chainTolerance(3, 30)) << str(l0) << " " << str(l1) << " " << str(l2);
    ASSERT_LE(mismatch(h.world(b), toDouble(l0) * toDouble(l1)), chainTolerance(2, 20));
    ASSERT_LE(mismatch(h.world(a), toDouble(l0)), chainTolerance(1, 10));
    // placed() carries the same transform and the shared mesh.
    const PlacedMesh p = h.placed(c);
    EXPECT_EQ(p.mesh, triangleMesh().get());
    EXPECT_EQ(p.world.translation, h.world(c).translation);
  }
}

TEST(Hierarchy, QuarterTurnsComposeExactly) {
  // A parent turned 90° about z at (10, 0, 0); a child at local (1, 2, 3) turned 90° about x; a
  // grandchild at local (4, 5, 6). With exact quarter turns every world translation is an
  // integer vector, computed here with integer matrices.
  ModelHierarchy h;
  const Quat qz = quatFromEulerDegrees(0, 0, 90), qx = quatFromEulerDegrees(90, 0, 0);
  const ModelId a = h.add(triangleMesh(), make(qz, Vec3(10, 0, 0)));
  const ModelId b = h.add(triangleMesh(), make(qx, Vec3(1, 2, 3)), a);
  const ModelId c = h.add(triangleMesh(), translation(4, 5, 6), b);
  Eigen::Matrix3i rz, rx;
  rz << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  rx << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  const Eigen::Vector3i tb = rz * Eigen::Vector3i(1, 2, 3) + Eigen::Vector3i(10, 0, 0);
  const Eigen::Vector3i tc = rz * rx * Eigen::Vector3i(4, 5, 6) + tb;
  EXPECT_EQ(h.world(b).translation, tb.cast<Real>()) << str(h.world(b));
  EXPECT_EQ(h.world(c).translation, tc.cast<Real>()) << str(h.world(c));
  // The rotation of c is the exact quaternion of rz·rx.
  const Eigen::Matrix3d m = h.world(c).rotation.cast<double>().toRotationMatrix();
  EXPECT_LE((m - (rz * rx).cast<double>()).cwiseAbs().maxCoeff(), 4 * kEps);
}

TEST(Hierarchy, WorldCacheFollowsEveryAncestorMove) {
  std::mt19937_64 rng(0x41F);
  ModelHierarchy h;
  const ModelId a = h.add(triangleMesh(), randomTransform(rng, 5));
  const ModelId b = h.add(triangleMesh(), randomTransform(rng, 5), a);
  const ModelId c = h.add(triangleMesh(), randomTransform(rng, 5), b);
  for (int round = 0; round < 100; ++round) {
    (void)h.world(c);  // fill the cache, then move one ancestor (or c)
    const ModelId moved = std::array<ModelId, 3>{a, b, c}[std::size_t(round % 3)];
    h.setLocal(moved, randomTransform(rng, 5));
    ASSERT_LE(mismatch(h.world(c), referenceWorld(h, c)), chainTolerance(3, 15)) << "round " << round;
    ASSERT_LE(mismatch(h.world(b), referenceWorld(h, b)), chainTolerance(2, 10)) << "round " << round;
  }
  h.setLocal(a, translation(100, 0, 0));
  h.refreshWorld();
  EXPECT_LE(mismatch(h.world(c), referenceWorld(h, c)), chainTolerance(3, 115));
}

// ---------------------------------------------------------------------------------------------
// Parents, cycles, removal.

TEST(Hierarchy, SetLocalUpdatesEveryDescendantEagerly) {
  // World transforms are recomputed by setLocal itself (const reads never write, so they are
  // thread-safe). After random moves in a random forest, every world transform must match the
  // double-precision composition of the current locals, and a copy taken before reading must
  // hold the very same values (nothing was left to refresh).
  std::mt19937_64 rng(0xEA6E);
  ModelHierarchy h;
  std::vector<ModelId> ids;
  for (int i = 0; i < 300; ++i) {
    std::uniform_int_distribution<int> pick(-1, int(ids.size()) - 1);
    const int p = ids.empty() ? -1 : pick(rng);
    ids.push_back(h.add(triangleMesh(), randomTransform(rng, 3), p < 0 ? kNoModel : ids[std::size_t(p)]));
  }
  std::uniform_int_distribution<std::size_t> any(0, ids.size() - 1);
  for (int round = 0; round < 20; ++round) {
    for (int k = 0; k < 10; ++k) h.setLocal(ids[any(rng)], randomTransform(rng, 3));
    const ModelHierarchy before = h;
    for (const ModelId id : ids) {
      int depth = 0;
      for (ModelId a = h.parent(id); a != kNoModel; a = h.parent(a)) ++depth;
      const Transform &w = h.world(id), &b = before.world(id);
      ASSERT_LE(mismatch(w, referenceWorld(h, id)), chainTolerance(depth + 1, 3 * (depth + 1)))
          << "round " << round << " model " << id << " depth " << depth << " " << str(w);
      ASSERT_EQ(w.translation, b.translation) << "round " << round << " model " << id;
      ASSERT_EQ(w.rotation.coeffs(), b.rotation.coeffs()) << "round " << round << " model " << id;
    }
  }
}

TEST(Hierarchy, SetParentRejectsCyclesThroughSelfChildAndGrandchild) {
  ModelHierarchy h;
  const ModelId a = h.add(triangleMesh());
  const ModelId b = h.add(triangleMesh(), translation(1, 0, 0), a);
  const ModelId c = h.add(triangleMesh(), translation(0, 1, 0), b);
  for (const ModelId p : {a, b, c}) {
    try {
      h.setParent(a, p);
      FAIL() << "setParent(a, " << p << ") was accepted";
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find("cycle"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(h.setParent(b, c), InvalidInput);
  // Nothing changed.
  EXPECT_EQ(h.parent(a), kNoModel);
  EXPECT_EQ(h.parent(b), a);
  EXPECT_EQ(h.parent(c), b);
  EXPECT_EQ(h.descendants(a), (std::vector<ModelId>{b, c}));
  // A legal move: c to the root, then under a.
  h.setParent(c, kNoModel);
  EXPECT_EQ(h.parent(c), kNoModel);
  h.setParent(c, a);
  EXPECT_EQ(h.children(a), (std::vector<ModelId>{b, c}));
}

TEST(Hierarchy, SetParentKeepsTheWorldPose) {
  std::mt19937_64 rng(0x420);
  for (int round = 0; round < 200; ++round) {
    ModelHierarchy h;
    const ModelId p1 = h.add(triangleMesh(), randomTransform(rng, 10));
    const ModelId p2 = h.add(triangleMesh(), randomTransform(rng, 10));
    const ModelId m = h.add(triangleMesh(), randomTransform(rng, 10), p1);
    const ModelId child = h.add(triangleMesh(), randomTransform(rng, 10), m);
    const Transform before = h.world(m), childBefore = h.world(child);
    h.setParent(m, p2);
    EXPECT_EQ(h.parent(m), p2);
    // The world pose is kept as it was, bit for bit (cached), and so are the descendants'.
    ASSERT_EQ(h.world(m).translation, before.translation);
    ASSERT_EQ(h.world(m).rotation.coeffs(), before.rotation.coeffs());
    ASSERT_EQ(h.world(child).translation, childBefore.translation);
    // The new local reproduces it under the new parent (up to rounding).
    ASSERT_LE(mismatch(before, referenceWorld(h, m)), chainTolerance(2, 40)) << str(before);
    // Later moves of the new parent carry the model along.
    h.setLocal(p2, randomTransform(rng, 10));
    ASSERT_LE(mismatch(h.world(child), referenceWorld(h, child)), chainTolerance(3, 40));
  }
}

TEST(Hierarchy, RemoveReparentsChildrenKeepingTheirWorldPose) {
  std::mt19937_64 rng(0x421);
  for (int round = 0; round < 100; ++round) {
    ModelHierarchy h;
    const ModelId top = h.add(triangleMesh(), randomTransform(rng, 10));
    const ModelId mid = h.add(triangleMesh(), randomTransform(rng, 10), top);
    const ModelId k1 = h.add(triangleMesh(), randomTransform(rng, 10), mid);
    const ModelId k2 = h.add(triangleMesh(), randomTransform(rng, 10), mid);
    const ModelId g = h.add(triangleMesh(), randomTransform(rng, 10), k1);
    const Transform w1 = h.world(k1), w2 = h.world(k2), wg = h.world(g);
    h.remove(mid);
    EXPECT_FALSE(h.contains(mid));
    EXPECT_EQ(h.parent(k1), top);
    EXPECT_EQ(h.parent(k2), top);
    EXPECT_EQ(h.parent(g), k1);
    EXPECT_EQ(h.children(top), (std::vector<ModelId>{k1, k2}));
    EXPECT_EQ(h.descendants(top), (std::vector<ModelId>{k1, k2, g}));
    ASSERT_EQ(h.world(k1).translation, w1.translation);
    ASSERT_EQ(h.world(k2).rotation.coeffs(), w2.rotation.coeffs());
    ASSERT_EQ(h.world(g).translation, wg.translation);
    ASSERT_LE(mismatch(w1, referenceWorld(h, k1)), chainTolerance(2, 40));
    ASSERT_LE(mismatch(w2, referenceWorld(h, k2)), chainTolerance(2, 40));
    // Removing a root makes its children roots whose local is their world transform.
    h.remove(top);
    EXPECT_EQ(h.parent(k1), kNoModel);
    EXPECT_EQ(h.local(k1).translation, w1.translation);
    EXPECT_EQ(h.world(g).translation, wg.translation);
    EXPECT_EQ(h.ids(), (std::vector<ModelId>{k1, k2, g}));
  }
}

TEST(Hierarchy, DescendantsCoverEveryLevelInAscendingOrder) {
  std::mt19937_64 rng(0x422);
  for (int round = 0; round < 50; ++round) {
    ModelHierarchy h;
    std::vector<ModelId> live;
    for (int i = 0; i < 60; ++i) {
      const ModelId parent = live.empty() || rng() % 5 == 0 ? kNoModel : live[rng() % live.size()];
      live.push_back(h.add(triangleMesh(), {}, parent));
    }
    // Reference: x is a descendant of y iff y is a proper ancestor of x.
    for (const ModelId y : live) {
      std::vector<ModelId> expected, direct;
      for (const ModelId x : live) {
        if (h.parent(x) == y) direct.push_back(x);
        for (ModelId a = h.parent(x); a != kNoModel; a = h.parent(a))
          if (a == y) {
            expected.push_back(x);
            break;
          }
      }
      ASSERT_EQ(h.descendants(y), expected) << "model " << y;
      ASSERT_EQ(h.children(y), direct) << "model " << y;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Depth 10,000.

TEST(Hierarchy, ChainTenThousandDeepNeedsNoRecursion) {
  constexpr int kDepth = 10000;
  ModelHierarchy h;
  // Every level turns 90° about z and steps (1, 0, 0): exact, so the leaf's world transform
  // is known exactly (an integer walk around a square).
  const Transform step = make(quatFromEulerDegrees(0, 0, 90), Vec3(1, 0, 0));
  std::vector<ModelId> chain;
  chain.push_back(h.add(triangleMesh(), step));
  for (int i = 1; i < kDepth; ++i) chain.push_back(h.add(triangleMesh(), step, chain.back()));
  Eigen::Vector3i position(0, 0, 0);
  Eigen::Matrix3i rotation = Eigen::Matrix3i::Identity(), rz;
  rz << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  for (int i = 0; i < kDepth; ++i) {
    position += rotation * Eigen::Vector3i(1, 0, 0);
    rotation = rotation * rz;
  }
  EXPECT_EQ(h.world(chain.back()).translation, position.cast<Real>()) << str(h.world(chain.back()));

  const std::vector<ModelId> d = h.descendants(chain.front());
  ASSERT_EQ(d.size(), std::size_t(kDepth - 1));
  EXPECT_TRUE(std::is_sorted(d.begin(), d.end()));
  EXPECT_EQ(d.front(), chain[1]);
  EXPECT_THROW(h.setParent(chain.front(), chain.back()), InvalidInput);

  // Moving the root moves everything.
  (void)h.takeMoved();
  h.setLocal(chain.front(), make(quatFromEulerDegrees(0, 0, 90), Vec3(2, 0, 0)));
  EXPECT_EQ(h.takeMoved().size(), std::size_t(kDepth));
  position += Eigen::Vector3i(1, 0, 0);  // the first step grew by one along x
  EXPECT_EQ(h.world(chain.back()).translation, position.cast<Real>());

  // Removing the middle keeps the leaf where it is; the chain is then two levels shorter... by one.
  const Transform leaf = h.world(chain.back());
  h.remove(chain[kDepth / 2]);
  EXPECT_EQ(h.parent(chain[kDepth / 2 + 1]), chain[kDepth / 2 - 1]);
  EXPECT_EQ(h.world(chain.back()).translation, leaf.translation);
  EXPECT_EQ(h.descendants(chain.front()).size(), std::size_t(kDepth - 2));

  // The same depth with general rotations (inexact): only the absence of recursion matters.
  ModelHierarchy g;
  std::mt19937_64 rng(0x423);
  ModelId last = g.add(triangleMesh(), randomTransform(rng, 1));
  const ModelId root = last;
  for (int i = 1; i < kDepth; ++i) last = g.add(triangleMesh(), randomTransform(rng, 1), last);
  g.setLocal(root, randomTransform(rng, 1));
  EXPECT_TRUE(g.world(last).translation.allFinite());
  EXPECT_EQ(g.descendants(root).size(), std::size_t(kDepth - 1));
}

// ---------------------------------------------------------------------------------------------
// The moved set.

TEST(Hierarchy, TakeMovedAfterMovingAGrandparentIncludesAllDescendants) {
  ModelHierarchy h;
  const ModelId other = h.add(triangleMesh());
  const ModelId gp = h.add(triangleMesh());
  const ModelId p1 = h.add(triangleMesh(), {}, gp);
  const ModelId unrelated = h.add(triangleMesh(), {}, other);
  const ModelId c1 = h.add(triangleMesh(), {}, p1);
  const ModelId p2 = h.add(triangleMesh(), {}, gp);
  const ModelId c2 = h.add(triangleMesh(), {}, p1);
  EXPECT_TRUE(h.takeMoved().empty()) << "new models are not reported";

  h.setLocal(gp, translation(1, 2, 3));
  EXPECT_EQ(h.takeMoved(), (std::vector<ModelId>{gp, p1, c1, p2, c2}));
  EXPECT_TRUE(h.takeMoved().empty());
  EXPECT_EQ(h.world(c2).translation, Vec3(1, 2, 3));

  // Repeated and nested moves are reported once, ascending.
  h.setLocal(c1, translation(0, 0, 1));
  h.setLocal(p1, translation(0, 1, 0));
  h.setLocal(c1, translation(0, 0, 2));
  h.setLocal(p1, translation(0, 2, 0));
  EXPECT_EQ(h.takeMoved(), (std::vector<ModelId>{p1, c1, c2}));
  // Moved while still stale (world never read), then moved again under a moved ancestor.
  h.setLocal(p1, translation(0, 3, 0));
  h.setLocal(gp, translation(5, 0, 0));
  EXPECT_EQ(h.takeMoved(), (std::vector<ModelId>{gp, p1, c1, p2, c2}));
  EXPECT_EQ(h.world(c1).translation, Vec3(5, 3, 2));
  (void)unrelated;

  // Re-parenting keeps world poses: nothing to report. Removing a moved model drops it.
  h.setParent(c1, other);
  EXPECT_TRUE(h.takeMoved().empty());
  h.setLocal(p2, translation(1, 1, 1));
  h.remove(p2);
  EXPECT_TRUE(h.takeMoved().empty());
  // A moved parent's children stay reported after the parent is removed.
  h.setLocal(p1, translation(9, 9, 9));
  h.remove(p1);
  EXPECT_EQ(h.takeMoved(), (std::vector<ModelId>{c2}));
  EXPECT_EQ(h.world(c2).translation, Vec3(14, 9, 9));
}

TEST(Hierarchy, IdsAreReusedAfterRemoveWithANewGeneration) {
  ModelHierarchy h;
  const ModelId a = h.add(triangleMesh());
  const ModelId b = h.add(triangleMesh(), translation(1, 0, 0), a);
  const ModelId c = h.add(triangleMesh());
  EXPECT_EQ(h.size(), 3u);
  EXPECT_EQ(h.generation(b), 0u);
  h.setLocal(b, translation(2, 0, 0));
  h.remove(b);
  EXPECT_FALSE(h.contains(b));
  EXPECT_EQ(h.size(), 2u);
  EXPECT_EQ(h.generation(b), 1u);
  EXPECT_THROW(h.world(b), InvalidInput);
  const ModelId d = h.add(triangleMesh(), translation(0, 0, 7), c);
  EXPECT_EQ(d, b) << "the freed id is reused";
  EXPECT_TRUE(h.contains(d));
  EXPECT_EQ(h.parent(d), c);
  EXPECT_EQ(h.world(d).translation, Vec3(0, 0, 7));
  EXPECT_TRUE(h.children(a).empty());
  EXPECT_EQ(h.children(c), (std::vector<ModelId>{d}));
  EXPECT_TRUE(h.takeMoved().empty()) << "the removed model's move is not reported for the new one";
  EXPECT_EQ(h.ids(), (std::vector<ModelId>{a, b, c}));
  const ModelId e = h.add(triangleMesh());
  EXPECT_EQ(e, 3u);
}

// ---------------------------------------------------------------------------------------------
// Validation.

template <class F>
std::string errorOf(F f) {
  try {
    f();
  } catch (const InvalidInput& e) {
    return e.what();
  }
  return "(no exception)";
}

bool mentions(const std::string& message, const std::string& word) { return message.find(word) != std::string::npos; }

TEST(Hierarchy, InvalidInputsAreRejectedWithTheProblemNamed) {
  ModelHierarchy h;
  const ModelId a = h.add(triangleMesh());
  EXPECT_TRUE(mentions(errorOf([&] { h.add(nullptr); }), "null"));
  EXPECT_TRUE(mentions(errorOf([&] { h.add(triangleMesh(), {}, 42); }), "42 does not exist"));
  EXPECT_TRUE(mentions(errorOf([&] { h.remove(7); }), "7 does not exist"));
  EXPECT_TRUE(mentions(errorOf([&] { h.setLocal(7, {}); }), "setLocal"));
  EXPECT_TRUE(mentions(errorOf([&] { h.setParent(7, a); }), "does not exist"));
  EXPECT_TRUE(mentions(errorOf([&] { h.setParent(a, 7); }), "parent"));
  EXPECT_TRUE(mentions(errorOf([&] { h.world(kNoModel); }), "kNoModel"));
  EXPECT_TRUE(mentions(errorOf([&] { h.descendants(3); }), "does not exist"));

  const Transform doubled = make(Quat(2, 0, 0, 0), Vec3::Zero());
  EXPECT_TRUE(mentions(errorOf([&] { h.setLocal(a, doubled); }), "not a unit quaternion"));
  EXPECT_TRUE(mentions(errorOf([&] { h.add(triangleMesh(), doubled); }), "rotation"));
  const Real nan = std::numeric_limits<Real>::quiet_NaN();
  EXPECT_TRUE(mentions(errorOf([&] { h.setLocal(a, translation(0, nan, 0)); }), "translation"));
  EXPECT_TRUE(mentions(errorOf([&] { h.setLocal(a, make(Quat(nan, 0, 0, 0), Vec3::Zero())); }), "non-finite"));
  // Three digits for √½ are too few (|q| - 1 ≈ -1.5e-4); six are enough (≈ 4e-7).
  EXPECT_THROW(validate(make(Quat(Real(0.707), 0, 0, Real(0.707)), Vec3::Zero())), InvalidInput);
  EXPECT_NO_THROW(validate(make(Quat(Real(0.707107), 0, 0, Real(0.707107)), Vec3::Zero())));
  // An accepted rotation is stored normalised.
  h.setLocal(a, make(Quat(Real(0.707107), 0, 0, Real(0.707107)), Vec3::Zero()));
  EXPECT_NEAR(double(h.local(a).rotation.norm()), 1.0, 2 * kEps);
  // Failed calls changed nothing.
  EXPECT_EQ(h.ids(), (std::vector<ModelId>{a}));
}

// ---------------------------------------------------------------------------------------------
// Euler angles.

TEST(EulerAngles, ConventionIsExtrinsicXThenYThenZ) {
  // Independent reference: Eigen's angle-axis products, R = Rz(z)·Ry(y)·Rx(x).
  std::mt19937_64 rng(0xE71);
  std::uniform_real_distribution<double> deg(-400, 400);
  for (int i = 0; i < 2000; ++i) {
    const Real x = Real(deg(rng)), y = Real(deg(rng)), z = Real(deg(rng));
    const double r = M_PI / 180;
    const Eigen::Matrix3d ref = (Eigen::AngleAxisd(double(z) * r, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(double(y) * r, Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(double(x) * r, Eigen::Vector3d::UnitX()))
                                    .toRotationMatrix();
    const Quat q = quatFromEulerDegrees(x, y, z);
    // The quaternion is the double result rounded to Real: matrix entries within a few ulps.
    ASSERT_NEAR(double(q.norm()), 1.0, 4 * kEps);
    ASSERT_LE((q.cast<double>().toRotationMatrix() - ref).cwiseAbs().maxCoeff(), 8 * kEps)
        << str(x) << " " << str(y) << " " << str(z);
  }
  // Named cases: +90° about z takes x to y; about x takes y to z; about y takes z to x.
  const Vec3 ex = Vec3::UnitX(), ey = Vec3::UnitY(), ez = Vec3::UnitZ();
  EXPECT_LE((quatFromEulerDegrees(0, 0, 90) * ex - ey).norm(), 4 * kEps);
  EXPECT_LE((quatFromEulerDegrees(90, 0, 0) * ey - ez).norm(), 4 * kEps);
  EXPECT_LE((quatFromEulerDegrees(0, 90, 0) * ez - ex).norm(), 4 * kEps);
  // Order: x first, then z (extrinsic): (90, 0, 90) takes y to z, and z to... x rotated: y → z → z.
  EXPECT_LE((quatFromEulerDegrees(90, 0, 90) * ey - ez).norm(), 4 * kEps);
  EXPECT_LE((quatFromEulerDegrees(90, 0, 90) * ex - ey).norm(), 4 * kEps);
  EXPECT_THROW(quatFromEulerDegrees(std::numeric_limits<Real>::infinity(), 0, 0), InvalidInput);
}

TEST(EulerAngles, MultiplesOfNinetyDegreesGiveExactQuaternions) {
  // Errata: the book's folded DEG2RAD gave cos 90° ≈ -6.4e-7. Every component must be exactly
  // 0, ±½, ±√½ or ±1 (√½ correctly rounded), and the rotation a signed permutation.
  const Real h = std::sqrt(Real(0.5));
  const Real allowed[] = {0, Real(0.5), h, 1};
  EXPECT_EQ(quatFromEulerDegrees(90, 0, 0).coeffs(), Quat(h, h, 0, 0).coeffs());
  EXPECT_EQ(quatFromEulerDegrees(180, 0, 0).coeffs(), Quat(0, 1, 0, 0).coeffs());
  EXPECT_EQ(quatFromEulerDegrees(0, 0, -90).coeffs(), Quat(h, 0, 0, -h).coeffs());
  EXPECT_EQ(quatFromEulerDegrees(0, 720, 0).coeffs(), Quat(1, 0, 0, 0).coeffs());
  std::set<std::vector<int>> distinct;
  for (int i = -1; i <= 4; ++i)
    for (int j = -1; j <= 4; ++j)
      for (int k = -1; k <= 4; ++k) {
        const Quat q = quatFromEulerDegrees(Real(90 * i), Real(90 * j), Real(90 * k));
        for (int c = 0; c < 4; ++c) {
          const Real v = std::fabs(q.coeffs()[c]);
          ASSERT_TRUE(std::find(std::begin(allowed), std::end(allowed), v) != std::end(allowed))
              << i << " " << j << " " << k << ": component " << str(q.coeffs()[c]);
        }
        const Eigen::Matrix3d m = q.cast<double>().toRotationMatrix();
        std::vector<int> key;
        for (int r = 0; r < 3; ++r)
          for (int s = 0; s < 3; ++s) {
            ASSERT_NEAR(m(r, s), std::round(m(r, s)), 4 * kEps);
            key.push_back(int(std::round(m(r, s))));
          }
        distinct.insert(key);
      }
  EXPECT_EQ(distinct.size(), 24u) << "the 24 axis-aligned rotations";
  // Non-multiples are not snapped: 89° differs from 90° visibly.
  EXPECT_GT(std::fabs(quatFromEulerDegrees(89, 0, 0).w() - h), Real(1e-3));
}

// ---------------------------------------------------------------------------------------------
// A long random sequence of operations against a reference forest.

TEST(HierarchyProperty, RandomOperationsMatchAReferenceForest) {
  std::mt19937_64 rng(0x5EED);
  ModelHierarchy h;
  std::map<ModelId, ModelId> parentOf;  // reference structure
  std::set<ModelId> movedRef;
  std::map<ModelId, Transform> snapshot;  // worlds at the last takeMoved
  auto isAncestor = [&](ModelId a, ModelId x) {
    for (ModelId p = parentOf.at(x); p != kNoModel; p = parentOf.at(p))
      if (p == a) return true;
    return false;
  };
  auto depthOf = [&](ModelId x) {
    int d = 0;
    for (ModelId p = parentOf.at(x); p != kNoModel; p = parentOf.at(p)) ++d;
    return d;
  };
  auto randomLive = [&]() {
    auto it = parentOf.begin();
    std::advance(it, std::ptrdiff_t(rng() % parentOf.size()));
    return it->first;
  };
  auto randomLocal = [&]() {
    // Half the time an exact transform (quarter turns, integer translation).
    if (rng() % 2) {
      const int i = int(rng() % 4), j = int(rng() % 4), k = int(rng() % 4);
      return make(quatFromEulerDegrees(Real(90 * i), Real(90 * j), Real(90 * k)),
                  Vec3(Real(int(rng() % 7) - 3), Real(int(rng() % 7) - 3), Real(int(rng() % 7) - 3)));
    }
    return randomTransform(rng, 3);
  };
  int cycles = 0, takes = 0;
  const int steps = test::scaledCases(20000);
  for (int step = 0; step < steps; ++step) {
    const int op = parentOf.size() < 5 ? 0 : int(rng() % 10);
    if (op <= 2 && parentOf.size() < 80) {  // add
      const ModelId parent = parentOf.empty() || rng() % 4 == 0 ? kNoModel : randomLive();
      const ModelId id = h.add(triangleMesh(), randomLocal(), parent);
      ASSERT_EQ(parentOf.count(id), 0u);
      parentOf[id] = parent;
    } else if (op == 3) {  // remove
      const ModelId id = randomLive();
      const ModelId p = parentOf.at(id);
      h.remove(id);
      for (auto& [x, px] : parentOf)
        if (px == id) px = p;
      parentOf.erase(id);
      movedRef.erase(id);
      snapshot.erase(id);
    } else if (op <= 6) {  // setLocal
      const ModelId id = randomLive();
      h.setLocal(id, randomLocal());
      movedRef.insert(id);
      for (const auto& [x, px] : parentOf)
        if (isAncestor(id, x)) movedRef.insert(x);
    } else if (op <= 8) {  // setParent (cycles must be rejected)
      const ModelId id = randomLive();
      const ModelId parent = rng() % 5 == 0 ? kNoModel : randomLive();
      const bool cycle = parent != kNoModel && (parent == id || isAncestor(id, parent));
      if (cycle) {
        ++cycles;
        ASSERT_THROW(h.setParent(id, parent), InvalidInput);
      } else {
        h.setParent(id, parent);
        parentOf[id] = parent;
      }
    } else {  // takeMoved: exactly the reference set; unreported models kept their world bit for bit
      ++takes;
      const std::vector<ModelId> moved = h.takeMoved();
      ASSERT_EQ(moved, std::vector<ModelId>(movedRef.begin(), movedRef.end())) << "step " << step;
      for (const auto& [x, w] : snapshot)
        if (!movedRef.count(x)) {
          ASSERT_EQ(h.world(x).translation, w.translation) << "model " << x << " step " << step;
          ASSERT_EQ(h.world(x).rotation.coeffs(), w.rotation.coeffs()) << "model " << x << " step " << step;
        }
      movedRef.clear();
      snapshot.clear();
      for (const auto& [x, px] : parentOf) snapshot[x] = h.world(x);
    }
    // Structure and world transforms after every step.
    std::vector<ModelId> ids;
    for (const auto& [x, px] : parentOf) ids.push_back(x);
    ASSERT_EQ(h.ids(), ids) << "step " << step;
    ASSERT_EQ(h.size(), ids.size());
    for (const auto& [x, px] : parentOf) {
      ASSERT_EQ(h.parent(x), px) << "model " << x << " step " << step;
      const double scale = 6 * (depthOf(x) + 1);
      ASSERT_LE(mismatch(h.world(x), referenceWorld(h, x)), chainTolerance(depthOf(x) + 1, scale))
          << "model " << x << " depth " << depthOf(x) << " step " << step;
    }
    if (step % 50 == 0) {
      const ModelId y = randomLive();
      std::vector<ModelId> expected;
      for (const auto& [x, px] : parentOf)
        if (isAncestor(y, x)) expected.push_back(x);
      ASSERT_EQ(h.descendants(y), expected) << "step " << step;
    }
  }
  EXPECT_GT(cycles, steps / 200);
  EXPECT_GT(takes, steps / 40);
}

}  // namespace
}  // namespace crux
