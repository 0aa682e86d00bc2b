// Casts through the peers' worlds (oracle/bullet/bullet_world.cpp: convexSweepTest's
// objectQuerySingle; oracle/fcl/fcl_world.cpp: fcl::continuousCollide by conservative
// advancement) against the native world, on UNAMBIGUOUS cases: the shape's centre aimed through
// the target's centre from a separated start (a hit well inside the motion), or passing the
// target at more than both sizes plus a gap (a miss). There the peers must give native's verdict
// and a time of impact within their declared tolerance as a distance along the motion
// (kPeerCastSlack). Shapes are centred on their pose's origin, so the peers' rigid motions
// (rotation about the shape's own origin) are crux's. The peers' documented defects on the
// boundary (a cast that starts touching or overlapping; FCL against meshes) are checked as such.

#include <gtest/gtest.h>

#include <crux/model/model_query.hpp>
#include <crux/world/collision_world.hpp>
#include <crux/world/native_world.hpp>
#include <world_factory.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <variant>
#include <vector>

namespace crux {
namespace {

bool built(std::string_view backend) {
  const auto& b = builtBackends();
  return std::find(b.begin(), b.end(), backend) != b.end();
}

/// How far (as a distance along the motion) a peer's time of impact may be from native's on a
/// head-on cast: Bullet's declared 2e-4·s + 1e-4 (oracle/README.md) at the sizes here (s <= 8),
/// doubled; FCL stops its advancement when the step falls under 1e-4 of the motion bound.
constexpr double kPeerCastSlack = 4e-3;

struct Rng {
  std::mt19937 gen;
  explicit Rng(unsigned seed) : gen(seed) {}
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(gen); }
  Vec3 unit() {
    Vec3 v;
    do v = Vec3(Real(uniform(-1, 1)), Real(uniform(-1, 1)), Real(uniform(-1, 1)));
    while (v.norm() < Real(0.1) || v.norm() > 1);
    return v.normalized();
  }
  Quat rotation() {
    Quat q(Real(uniform(-1, 1)), Real(uniform(-1, 1)), Real(uniform(-1, 1)), Real(uniform(-1, 1)));
    return q.normalized();
  }
};

/// A convex shape centred on its frame's origin, of size (bounding radius) at most `size`.
OperandShape centredShape(Rng& rng, int kind, double size) {
  const Real s = Real(size);
  switch (kind % 4) {
    case 0: return Sphere{Vec3::Zero(), s};
    case 1: return Obb{Vec3::Zero(), Vec3(s, Real(0.6) * s, Real(0.4) * s) / Real(1.3), Mat3::Identity()};
    case 2: return Capsule{Vec3(0, 0, -s / 2), Vec3(0, 0, s / 2), s / 2};
    default: {
      std::vector<Vec3> points;
      for (int i = 0; i < 12; ++i) points.push_back(rng.unit() * s);
      return ConvexHull::build(points);
    }
  }
}

struct Tally {
  int hits = 0, misses = 0;
  double worstSlack = 0;
  double worstUnchecked = 0;  ///< FCL's rigid casts (verdict only)
};

/// One unambiguous cast of a (centred, size sa) from `start` against a target centred at
/// `centre` (size sb), at least sa + sb + 0.5 apart: a hit aimed through the centre, or a miss
/// whose line passes the centre at 1.05 (sa + sb + 0.25).
WorldMotion aimedMotion(Rng& rng, const Vec3& start, const Vec3& centre, bool hit, double sa, double sb) {
  const Vec3 to = centre - start;
  Vec3 side = to.cross(rng.unit());
  side.normalize();
  WorldMotion m;
  if (hit) {
    m.translation = to * Real(rng.uniform(1.0, 1.6));
  } else {
    // the line start + s·(to + x·side) passes the centre at x|to| / sqrt(|to|² + x²)
    const double gap = sa + sb + 0.25, d = double(to.norm());
    const double x = 1.05 * gap * d / std::sqrt(d * d - gap * gap);
    m.translation = (to + side * Real(x)) * Real(2);
  }
  return m;
}

/// The length of a cast's path (of the operand's origin).
double pathLength(const WorldOperand& a, const WorldMotion& motion) {
  return motion.end ? double((motion.end->translation - a.pose.translation).norm()) : double(motion.translation.norm());
}

/// Compares a peer's cast with native's on an unambiguous case: the verdict, and (with `time`)
/// t as a distance along the path within kPeerCastSlack.
void compare(const WorldCast& peer, const WorldCast& native, bool hit, double length, const std::string& what,
             Tally& tally, bool time = true) {
  ASSERT_EQ(native.hit, hit) << "native: " << what;
  EXPECT_EQ(peer.hit, hit) << what;
  if (!hit || !peer.hit) {
    tally.misses += !hit;
    return;
  }
  ++tally.hits;
  ASSERT_TRUE(peer.timeKnown) << what;
  const double slack = std::abs(peer.t - native.t) * std::max(length, 1.0);
  if (!time) {
    tally.worstUnchecked = std::max(tally.worstUnchecked, slack);
    return;
  }
  tally.worstSlack = std::max(tally.worstSlack, slack);
  EXPECT_LE(slack, kPeerCastSlack) << what << ": peer t " << peer.t << ", native t " << native.t;
}

TEST(PeerCasts, ConvexPairsAgreeWithNativeOnClearHitsAndMisses) {
  for (const char* name : {"bullet", "fcl"}) {
    if (!built(name)) continue;
    const auto peer = makeWorld(name);
    const auto native = makeNativeWorld();
    Rng rng(17);
    Tally tally;
    // FCL 0.7 misses some clear hits of a sphere or capsule (7 of ~180 here; boxes and hulls
    // never): its advancement step (ShapeConservativeAdvancementTraversalNode::leafTesting) is
    // the distance over a motion bound along the direction between shapeDistance's nearest
    // points, and for these pairs it steps past the contact to toc = 1 (which of the points is
    // off was not traced). Counted here; crux diff names the cause cast-rounded-miss
    // (oracle/README.md, "Pitfalls").
    int fclRoundedMisses = 0;
    for (int i = 0; i < 400; ++i) {
      const double sa = rng.uniform(0.2, 1), sb = rng.uniform(0.2, 1.5);
      WorldOperand a{centredShape(rng, i, sa), Transform{}};
      WorldOperand b{centredShape(rng, i / 4, sb), Transform{}};
      b.pose.rotation = rng.rotation();
      b.pose.translation = rng.unit() * Real(rng.uniform(0, 2));
      a.pose.rotation = rng.rotation();
      a.pose.translation = b.pose.translation + rng.unit() * Real(sa + sb + rng.uniform(0.5, 4));
      const bool hit = i % 3 != 0;
      WorldMotion motion = aimedMotion(rng, a.pose.translation, b.pose.translation, hit, sa, sb);
      if (i % 2 == 1) {  // a rigid motion: the same path, turning by up to 40° as it goes (Bullet
                         // clamps an integration step's rotation at 45°: ANGULAR_MOTION_THRESHOLD)
        Transform end = a.pose;
        end.translation += motion.translation;
        end.rotation = (Quat(Eigen::AngleAxis<Real>(Real(rng.uniform(0, 0.7)), rng.unit())) * a.pose.rotation).normalized();
        motion = WorldMotion{Vec3::Zero(), end};
      }
      const std::string what = std::string(name) + " case " + std::to_string(i);
      const WorldCast p = peer->cast(a, motion, b);
      EXPECT_EQ(native->cast(a, motion, b, CastFind::Any).hit, hit) << "native any: " << what;
      const bool rounded = std::holds_alternative<Sphere>(a.shape) || std::holds_alternative<Capsule>(a.shape) ||
                           std::holds_alternative<Sphere>(b.shape) || std::holds_alternative<Capsule>(b.shape);
      if (std::string(name) == "fcl" && rounded && hit && !p.hit) {
        ++fclRoundedMisses;  // FCL's defect, below
        continue;
      }
      // FCL's rigid casts (InterpMotion): the verdict only. Their t differs from crux's and
      // Bullet's (which agree) by up to 0.06 of the path on some turning boxes and hulls (the
      // double build's cases; 7.5e-4 in the float build's): cause not traced (its advancement
      // stops when a step falls under 1e-4 of a motion bound that rotation makes loose).
      const bool time = !(std::string(name) == "fcl" && motion.end);
      compare(p, native->cast(a, motion, b), hit, pathLength(a, motion), what, tally, time);
    }
    std::printf("%s: %d hits, %d misses, worst |t - native t| x length %.3g (rigid, unchecked: %.3g); rounded "
                "hits missed: %d\n",
                name, tally.hits, tally.misses, tally.worstSlack, tally.worstUnchecked, fclRoundedMisses);
    EXPECT_LT(fclRoundedMisses, 20) << name;
    EXPECT_GT(tally.hits, 200) << name;
    EXPECT_GT(tally.misses, 100) << name;
  }
}

/// The 2 x 1 x 1 box [0,2]×[0,1]×[0,1] as 12 triangles.
std::shared_ptr<const Mesh> boxMesh() {
  std::vector<Vec3> v;
  for (int i = 0; i < 8; ++i) v.emplace_back(Real((i & 1) * 2), Real((i >> 1) & 1), Real((i >> 2) & 1));
  const std::vector<TriangleIndices> t = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                                          {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return std::make_shared<const Mesh>(v, t, "box");
}

TEST(PeerCasts, BulletMeshModelAndSceneCastsAgreeWithNativeOnClearHitsAndMisses) {
  if (!built("bullet")) GTEST_SKIP() << "bullet backend not built";
  const auto peer = makeWorld("bullet");
  const auto native = makeNativeWorld();
  const MeshHandle meshP = peer->addMesh("box", boxMesh()), meshN = native->addMesh("box", boxMesh());
  Rng rng(23);
  // three models far apart (no cast below passes near two of them)
  std::vector<std::pair<ModelHandle, ModelHandle>> models;
  std::vector<Transform> poses;
  for (int m = 0; m < 3; ++m) {
    Transform pose;
    pose.rotation = rng.rotation();
    pose.translation = Vec3(Real(40 * m), 0, 0) - pose.rotation * Vec3(1, Real(0.5), Real(0.5));  // centred at (40m,0,0)
    poses.push_back(pose);
    const std::string name = "m" + std::to_string(m);
    models.emplace_back(peer->addModel(name, meshP, pose), native->addModel(name, meshN, pose));
  }
  const double sb = std::sqrt(1.5);  // the box's bounding radius
  Tally tally;
  for (int i = 0; i < 300; ++i) {
    const std::size_t m = std::size_t(i % 3);
    const Vec3 centre(Real(40 * int(m)), 0, 0);
    const double sa = rng.uniform(0.1, 0.6);
    WorldOperand a{centredShape(rng, i, sa), Transform{}};
    a.pose.rotation = rng.rotation();
    a.pose.translation = centre + rng.unit() * Real(sa + sb + rng.uniform(0.5, 4));
    const bool hit = i % 3 != 1;
    WorldMotion motion = aimedMotion(rng, a.pose.translation, centre, hit, sa, sb);
    const std::string what = "case " + std::to_string(i);
    switch (i % 4) {
      case 0: {  // the mesh at the model's pose, as a cast operand
        const WorldOperand bP{meshP, poses[m]}, bN{meshN, poses[m]};
        EXPECT_EQ(native->cast(a, motion, bN, CastFind::Any).hit, hit) << "native any: " << what;
        EXPECT_EQ(peer->cast(a, motion, bP, CastFind::Any).hit, hit) << "bullet any: " << what;
        compare(peer->cast(a, motion, bP), native->cast(a, motion, bN), hit, pathLength(a, motion), what + " mesh",
                tally);
        break;
      }
      case 1:
      case 2:
        compare(peer->modelCast(a, motion, models[m].first), native->modelCast(a, motion, models[m].second), hit,
                pathLength(a, motion), what + " model", tally);
        break;
      default: {
        const WorldCast p = peer->sceneCast(a, motion), n = native->sceneCast(a, motion);
        compare(p, n, hit, pathLength(a, motion), what + " scene", tally);
        if (hit && p.hit) {
          EXPECT_EQ(p.model, models[m].first) << what;
          EXPECT_EQ(n.model, models[m].second) << what;
        }
      }
    }
  }
  std::printf("bullet meshes: %d hits, %d misses, worst |t - native t| x length %.3g\n", tally.hits, tally.misses,
              tally.worstSlack);
  EXPECT_GT(tally.hits, 150);
  EXPECT_GT(tally.misses, 60);
}

TEST(PeerCasts, BulletMissesACastThatStartsTouchingOrOverlapping) {
  // Recorded as oracle/known-peer-disagreements/bullet.cast-start.jsonl: Bullet's convex sweeps
  // (btContinuousConvexCollision, allowed penetration 0) report nothing for a pair that touches
  // or overlaps at t = 0 and separates, where a cast of closed sets hits at t = 0.
  if (!built("bullet")) GTEST_SKIP() << "bullet backend not built";
  const auto peer = makeWorld("bullet");
  const auto native = makeNativeWorld();
  const Obb unit{Vec3(Real(0.5), Real(0.5), Real(0.5)), Vec3::Constant(Real(0.5)), Mat3::Identity()};
  const Obb small{Vec3::Zero(), Vec3::Constant(Real(0.25)), Mat3::Identity()};
  WorldMotion up;
  up.translation = Vec3(0, 0, 3);
  for (const double z : {0.5, 1.25}) {  // inside, then resting on the top face
    const WorldOperand a{small, [&] {
                           Transform t;
                           t.translation = Vec3(Real(0.5), Real(0.5), Real(z));
                           return t;
                         }()};
    const WorldCast n = native->cast(a, up, WorldOperand{unit, Transform{}});
    EXPECT_TRUE(n.hit);
    EXPECT_EQ(n.t, 0);
    EXPECT_TRUE(n.startsOverlapping);
    EXPECT_FALSE(peer->cast(a, up, WorldOperand{unit, Transform{}}).hit) << "z " << z << ": Bullet changed";
  }
}

TEST(PeerCasts, FclCastsConvexPairsOnlyAndReportsTheTimeAlone) {
  if (!built("fcl")) GTEST_SKIP() << "fcl backend not built";
  const auto peer = makeWorld("fcl");
  const MeshHandle mesh = peer->addMesh("box", boxMesh());
  const ModelHandle model = peer->addModel("m", mesh, Transform{});
  const WorldOperand a{Sphere{Vec3::Zero(), Real(0.25)}, [] {
                         Transform t;
                         t.translation = Vec3(1, Real(0.5), 3);
                         return t;
                       }()};
  WorldMotion down;
  down.translation = Vec3(0, 0, -4);
  const WorldCast c = peer->cast(a, down, WorldOperand{Sphere{Vec3(1, Real(0.5), Real(0.5)), Real(0.5)}, Transform{}});
  ASSERT_TRUE(c.hit);
  EXPECT_NEAR(c.t, 0.4375, 1e-3);  // the centres 2.5 apart, less the radii 0.75: 1.75 of 4
  EXPECT_FALSE(c.witnessKnown);
  try {
    peer->cast(a, down, WorldOperand{mesh, Transform{}});
    ADD_FAILURE() << "a mesh cast answered";
  } catch (const BackendFailure& e) {
    EXPECT_NE(std::string(e.what()).find("conservative advancement against a triangle mesh"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(peer->supports(WorldOp::ModelCast));
  EXPECT_FALSE(peer->supports(WorldOp::SceneCast));
  EXPECT_THROW(peer->modelCast(a, down, model), Unsupported);
  EXPECT_THROW(peer->sceneCast(a, down), Unsupported);
}

}  // namespace
}  // namespace crux
