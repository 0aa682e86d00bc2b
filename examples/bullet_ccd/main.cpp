/// @file main.cpp  crux's shape casts as the continuous collision detection of a Bullet world.
///
/// A btDiscreteDynamicsWorld holds two static targets, bunny00 (a closed mesh 1 m tall, a
/// btBvhTriangleMeshShape) and a thin wall (a 1 cm thick btBoxShape), and N small bodies
/// (spheres, boxes, capsules of 5–12 cm) thrown at them at 50–200 m/s: 0.8–3.3 m per step of
/// 1/60 s, many times their size. Three modes run the same throws:
///   --mode none    Bullet's discrete collision only;
///   --mode bullet  Bullet's own CCD (setCcdMotionThreshold + setCcdSweptSphereRadius);
///   --mode crux    crux's CCD (CruxCcd): after each internal step, each body's core (its shape
///                  shrunk by kSkin) is cast along the step's motion against the bunny
///                  (crux::castClosest) and the wall (crux::cast); on a hit before the end of the
///                  step the body is put back just before the time of impact and loses its
///                  velocity into the surface. A core already touching a surface at the start of
///                  the step falls back to a cast of the body's centre.
/// A body tunnelled when its centre crossed a target's surface during a step (the segment between
/// its centres before and after the step, the path of Bullet's integrator, meets the bunny's
/// triangles or the wall's box): a body stopped by the surface keeps its centre outside. The
/// program prints, per mode, the bodies thrown, those that tunnelled and the steps per second; it
/// exits 1 when a body tunnelled with crux's CCD, 77 when the mesh cannot be loaded, 2 on bad
/// arguments. See README.md.

#include "common/bullet_crux.hpp"

#include <crux/geometry/cast.hpp>
#include <crux/geometry/raycast.hpp>
#include <crux/mesh/mesh.hpp>
#include <crux/mesh/mesh_cast.hpp>
#include <crux/mesh/mesh_query.hpp>

#include <btBulletCollisionCommon.h>
#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace {

using crux::Real;
using crux::Vec3;
using crux_example::StaticMesh;
using crux_example::threadCpuSeconds;
using crux_example::toBt;
using crux_example::toCrux;
using crux_example::toCruxShape;

// ---- scene constants (SI units: metres, seconds, kilograms) --------------------------------------

constexpr double kGravity = 9.81;
constexpr double kTimeStep = 1.0 / 60.0;  ///< one fixed Bullet step per frame
constexpr double kBunnyHeight = 1.0;      ///< bunny00 scaled to this height, centred at the origin
const Vec3 kWallCentre{0, 0, 20};         ///< far from the bunny: no path meets both targets
const Vec3 kWallHalf{0.005, 1, 1};        ///< 1 cm thick, 2 m × 2 m, facing ±x
constexpr double kWallMargin = 0.001;     ///< Bullet's box margin (its default 0.04 m is > the half thickness)
constexpr double kSphereRadius = 0.05;
constexpr double kBoxHalf[3] = {0.05, 0.035, 0.025};
constexpr double kBoxMargin = 0.005;      ///< Bullet's default 0.04 m is > the box's half extents
constexpr double kCapsuleRadius = 0.03;
constexpr double kCapsuleHalfHeight = 0.03;  ///< half the segment between the cap centres
constexpr double kMass = 0.1;
constexpr double kFriction = 0.5;
constexpr double kMinSpeed = 50, kMaxSpeed = 200;       ///< m/s
constexpr double kMinDistance = 2, kMaxDistance = 12;   ///< m from the launch point to the aim point
constexpr double kSpawnClearance = 0.3;  ///< m between launch points (the bodies' sizes are < 0.13 m)
/// crux's CCD casts each body's core, its shape shrunk by kSkin (less than every body's inscribed
/// radius), so a body touching or resting on a surface (penetration < kSkin) starts its casts
/// separated and a cast only reports the surfaces the body moves into.
constexpr double kSkin = 0.01;
/// A stopped body is put back along its path to kBackOff of travel before its core's impact:
/// clear of every surface (a push out along the contact normal could go into the next triangle
/// in a crease).
constexpr double kBackOff = 0.5 * kSkin;
/// A body whose rotation over a step moves its farthest point by less than this is cast along the
/// translation alone: its core strays from the cast's by less than 1 µm, well inside kSkin.
constexpr double kTurnTolerance = 1e-6;
/// Bullet's CCD: a body moving more than its inscribed radius in a step is swept as a sphere of
/// kSweptFraction × that radius (Bullet's advice: a sphere inside the body).
constexpr double kSweptFraction = 0.8;

using crux_example::kExitFailure;

enum class BodyKind { Sphere, Box, Capsule };
enum class Target { Bunny, Wall };
enum class Mode { None, Bullet, Crux };
const char* name(Mode m) { return m == Mode::None ? "none" : m == Mode::Bullet ? "bullet" : "crux"; }

/// Radius of the largest ball inside the body (about its centre).
double inscribedRadius(BodyKind k) {
  return k == BodyKind::Sphere ? kSphereRadius
         : k == BodyKind::Box  ? *std::min_element(std::begin(kBoxHalf), std::end(kBoxHalf))
                               : kCapsuleRadius;
}

/// One throw (the same in every mode): kind, target, launch pose and velocity.
struct Throw {
  BodyKind kind = BodyKind::Sphere;
  Target target = Target::Bunny;
  Vec3 position = Vec3::Zero();
  crux::Quat rotation = crux::Quat::Identity();
  Vec3 velocity = Vec3::Zero();
};

/// The two static targets in crux's form (the bunny as in Bullet, vertices rounded to btScalar).
struct Targets {
  StaticMesh bunny;
  crux::Obb wall;  ///< in the world frame
};

// ---- crux's CCD -----------------------------------------------------------------------------------

/// The body's core: its crux shape shrunk by kSkin (radius, or half extents).
crux::ConvexShape core(const btCollisionShape& shape) {
  crux::ConvexShape s;
  toCruxShape(shape, s);
  if (s.kind == crux::ConvexKind::Box) s.p[1] -= Vec3::Constant(Real(kSkin));
  else s.radius -= Real(kSkin);
  return s;
}

/// crux's CCD for the fast bodies of one world, run by Bullet's internal tick callbacks around
/// each internal step: the pre-tick callback records the poses, the post-tick callback casts each
/// awake body from its recorded pose to its new one (Bullet's integrator moves the centre along
/// that segment and turns the body about one axis by at most π/4: crux::RigidMotion's slerp) and
/// corrects the new pose:
///  1. the core's cast (the body shrunk by kSkin) hits at t < 1: the body goes back to the pose at
///     t less kBackOff of travel (its core clear of every surface: the cast's t is never late)
///     and loses its velocity into the surface (no restitution, Bullet's default);
///  2. the core starts in contact (the body penetrates by kSkin or more: Bullet's solver pushed
///     it there): the centre (a ball of radius 0) is cast along its path instead, and a hit stops
///     the body as in 1, kBackOff short of the centre's impact;
///  3. the centre starts on a surface (within the cast's tolerance): the body stays where it was
///     unless it moves out along the contact normal.
/// Either way the centre does not cross a surface (2 lets the body sink deeper than kSkin, down
/// to its centre); Bullet's contacts then push the body out.
struct CruxCcd {
  const Targets* targets = nullptr;
  std::vector<btRigidBody*> bodies;
  std::vector<crux::ConvexShape> cores;  ///< per body
  std::vector<crux::Transform> before;   ///< per body: the pose at the start of the step
  std::uint64_t casts = 0;               ///< body steps cast (each against both targets)
  std::uint64_t linearCasts = 0, rigidCasts = 0;  ///< of which translations, rigid motions
  std::uint64_t coreStops = 0;           ///< bodies stopped by their core's cast (1)
  std::uint64_t centreCasts = 0;         ///< fallbacks to the centre's cast (2)
  std::uint64_t centreStops = 0;         ///< bodies stopped by the centre's cast (2)
  std::uint64_t holds = 0;               ///< bodies kept at their pose (3)
  double seconds = 0;                    ///< CPU time in the callbacks

  /// The earlier of two casts' hits (the first when they tie).
  static std::optional<crux::CastResult> earlier(std::optional<crux::CastResult> a, const crux::CastResult& b) {
    return b.hit && (!a || b.t < a->t) ? std::optional<crux::CastResult>(b) : a;
  }
  /// The first hit on either target of `shape` moved by a rigid motion (the wall's cast gives up
  /// past the bunny's hit).
  std::optional<crux::CastResult> firstHit(const crux::ConvexShape& shape, const crux::RigidMotion& motion) const {
    std::optional<crux::CastResult> best;
    if (const auto hit = crux::castClosest(*targets->bunny.mesh, crux::Transform{}, shape, motion)) best = hit->cast;
    crux::CastOptions options;
    if (best) options.earlyOut = best->t;
    return earlier(best, crux::cast(shape, motion, targets->wall, crux::Transform{}, options));
  }
  /// The same for a translation.
  std::optional<crux::CastResult> firstHit(const crux::ConvexShape& shape, const crux::Transform& pose,
                                           const Vec3& translation) const {
    std::optional<crux::CastResult> best;
    if (const auto hit = crux::castClosest(*targets->bunny.mesh, crux::Transform{}, shape, pose, translation))
      best = hit->cast;
    crux::CastOptions options;
    if (best) options.earlyOut = best->t;
    return earlier(best, crux::cast(shape, pose, translation, targets->wall, crux::Transform{}, options));
  }

  void preTick() {
    const double start = threadCpuSeconds();
    for (std::size_t i = 0; i < bodies.size(); ++i) before[i] = toCrux(bodies[i]->getWorldTransform());
    seconds += threadCpuSeconds() - start;
  }

  /// Moves the body to `pose` and removes its velocity into the surface of normal n (target → body).
  static void stop(btRigidBody& body, const crux::Transform& pose, const Vec3& n) {
    body.setWorldTransform(toBt(pose));
    body.setInterpolationWorldTransform(body.getWorldTransform());
    const btVector3 normal = toBt(n);
    const btVector3 v = body.getLinearVelocity();
    const btScalar into = v.dot(normal);
    if (into < 0) body.setLinearVelocity(v - into * normal);
    body.setInterpolationLinearVelocity(body.getLinearVelocity());
  }

  /// The time kBackOff of travel before t (0 when the translation is shorter than that).
  static Real backOff(Real t, const Vec3& translation) {
    const Real length = translation.norm();
    return length > Real(kBackOff) ? std::max(Real(0), t - Real(kBackOff) / length) : Real(0);
  }

  void postTick() {
    const double start = threadCpuSeconds();
    for (std::size_t i = 0; i < bodies.size(); ++i) {
      btRigidBody& body = *bodies[i];
      if (!body.isActive()) continue;
      ++casts;
      const crux::RigidMotion motion{before[i], toCrux(body.getWorldTransform())};
      const Vec3 translation = motion.end.translation - motion.start.translation;
      // The rigid cast, or the linear one when the body turned by less than kTurnTolerance at its
      // farthest point (faster: tighter swept bounds, no rotation bound in the advancement).
      const Real turned = motion.start.rotation.angularDistance(motion.end.rotation) * cores[i].size();
      const std::optional<crux::CastResult> hit =
          turned < Real(kTurnTolerance) ? firstHit(cores[i], motion.start, translation) : firstHit(cores[i], motion);
      ++(turned < Real(kTurnTolerance) ? linearCasts : rigidCasts);
      if (!hit || hit->t >= Real(1)) continue;
      if (!hit->startsOverlapping) {  // 1
        stop(body, crux::poseAt(motion, backOff(hit->t, translation)), hit->normal);
        ++coreStops;
        continue;
      }
      ++centreCasts;  // 2
      const crux::ConvexShape centre = crux::Sphere{Vec3::Zero(), Real(0)};  // the centre, a point
      const std::optional<crux::CastResult> centreHit =
          firstHit(centre, crux::Transform{crux::Quat::Identity(), motion.start.translation}, translation);
      if (!centreHit || centreHit->t >= Real(1)) continue;
      if (!centreHit->startsOverlapping) {
        stop(body, crux::poseAt(motion, backOff(centreHit->t, translation)), centreHit->normal);
        ++centreStops;
      } else if (translation.dot(centreHit->normal) < 0) {  // 3
        stop(body, motion.start, centreHit->normal);
        ++holds;
      }
    }
    seconds += threadCpuSeconds() - start;
  }
};

void cruxPreTick(btDynamicsWorld* world, btScalar) { static_cast<CruxCcd*>(world->getWorldUserInfo())->preTick(); }
void cruxPostTick(btDynamicsWorld* world, btScalar) { static_cast<CruxCcd*>(world->getWorldUserInfo())->postTick(); }

// ---- a run ----------------------------------------------------------------------------------------

/// Result of one run of the throws.
struct RunResult {
  int steps = 0;
  double cpuSeconds = 0;  ///< CPU time of this thread in stepSimulation (crux's CCD included)
  int tunnelledBunny = 0, tunnelledWall = 0;
  int tunnelled = 0;      ///< bodies that crossed either target's surface (once or more)
  std::vector<int> failed;
  CruxCcd ccd;            ///< crux mode's counters
};

/// Does the centre's path over one step, from a to b, cross the bunny's surface or enter the wall?
void crossings(const Targets& t, const Vec3& a, const Vec3& b, bool& bunny, bool& wall) {
  const crux::Segment path{a, b};
  bunny = crux::intersects(*t.bunny.mesh, path);
  wall = crux::intersects(path, t.wall);
}

RunResult run(const Targets& targets, const std::vector<Throw>& throws, Mode mode, int steps) {
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher(&configuration);
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world(&dispatcher, &broadphase, &solver, &configuration);
  world.setGravity(btVector3(0, btScalar(-kGravity), 0));

  const auto array = crux_example::bulletTriangles(targets.bunny);
  btBvhTriangleMeshShape bunnyShape(array.get(), true, true);
  btRigidBody bunny(btRigidBody::btRigidBodyConstructionInfo(0, nullptr, &bunnyShape));
  bunny.setFriction(btScalar(kFriction));
  world.addRigidBody(&bunny);

  btBoxShape wallShape(toBt(targets.wall.half));
  wallShape.setMargin(btScalar(kWallMargin));
  btRigidBody::btRigidBodyConstructionInfo wallInfo(0, nullptr, &wallShape);
  wallInfo.m_startWorldTransform.setOrigin(toBt(targets.wall.center));
  wallInfo.m_friction = btScalar(kFriction);
  btRigidBody wall(wallInfo);
  world.addRigidBody(&wall);

  btSphereShape sphere{btScalar(kSphereRadius)};
  btBoxShape box{btVector3(btScalar(kBoxHalf[0]), btScalar(kBoxHalf[1]), btScalar(kBoxHalf[2]))};
  box.setMargin(btScalar(kBoxMargin));
  btCapsuleShape capsule{btScalar(kCapsuleRadius), btScalar(2 * kCapsuleHalfHeight)};

  RunResult r;
  r.steps = steps;
  CruxCcd& ccd = r.ccd;
  ccd.targets = &targets;
  std::vector<std::unique_ptr<btRigidBody>> bodies;
  bodies.reserve(throws.size());
  for (const Throw& t : throws) {
    btCollisionShape* shape = t.kind == BodyKind::Sphere ? static_cast<btCollisionShape*>(&sphere)
                              : t.kind == BodyKind::Box  ? static_cast<btCollisionShape*>(&box)
                                                         : static_cast<btCollisionShape*>(&capsule);
    btVector3 inertia(0, 0, 0);
    shape->calculateLocalInertia(btScalar(kMass), inertia);
    btRigidBody::btRigidBodyConstructionInfo info(btScalar(kMass), nullptr, shape, inertia);
    info.m_startWorldTransform = toBt(crux::Transform{t.rotation, t.position});
    info.m_friction = btScalar(kFriction);
    bodies.push_back(std::make_unique<btRigidBody>(info));
    btRigidBody& body = *bodies.back();
    body.setLinearVelocity(toBt(t.velocity));
    if (mode == Mode::Bullet) {
      body.setCcdMotionThreshold(btScalar(inscribedRadius(t.kind)));
      body.setCcdSweptSphereRadius(btScalar(kSweptFraction * inscribedRadius(t.kind)));
    }
    world.addRigidBody(&body);
    ccd.bodies.push_back(&body);
    ccd.cores.push_back(core(*shape));
  }
  ccd.before.resize(bodies.size());
  if (mode == Mode::Crux) {
    world.setInternalTickCallback(cruxPreTick, &ccd, true);
    world.setInternalTickCallback(cruxPostTick, &ccd, false);
  }

  std::vector<Vec3> centres(bodies.size());
  std::vector<char> crossedBunny(bodies.size(), 0), crossedWall(bodies.size(), 0);
  for (int step = 0; step < steps; ++step) {
    for (std::size_t i = 0; i < bodies.size(); ++i) centres[i] = toCrux(bodies[i]->getWorldTransform().getOrigin());
    const double start = threadCpuSeconds();
    world.stepSimulation(btScalar(kTimeStep), 1, btScalar(kTimeStep));
    r.cpuSeconds += threadCpuSeconds() - start;
    for (std::size_t i = 0; i < bodies.size(); ++i) {
      bool bunnyCrossed = false, wallCrossed = false;
      crossings(targets, centres[i], toCrux(bodies[i]->getWorldTransform().getOrigin()), bunnyCrossed, wallCrossed);
      crossedBunny[i] |= char(bunnyCrossed);
      crossedWall[i] |= char(wallCrossed);
    }
  }
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    r.tunnelledBunny += crossedBunny[i];
    r.tunnelledWall += crossedWall[i];
    if (crossedBunny[i] || crossedWall[i]) {
      ++r.tunnelled;
      r.failed.push_back(int(i));
    }
    world.removeRigidBody(bodies[i].get());
  }
  world.removeRigidBody(&wall);
  world.removeRigidBody(&bunny);
  return r;
}

// ---- the throws ----------------------------------------------------------------------------------

/// N throws, alternately at the bunny and at the wall, kinds in turn; launch points kMinDistance
/// to kMaxDistance from the aim point (a random vertex of the bunny; a random point of the wall's
/// +x face, away from its rim), directions random (towards the wall: within 45° of −x), speeds
/// kMinSpeed to kMaxSpeed; the launch velocity is aimed up by ½·g·(flight time), so the
/// ballistic path reaches the aim point. Launch points at least kSpawnClearance apart.
std::vector<Throw> makeThrows(const Targets& targets, int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(-1, 1), fraction(0, 1);
  std::normal_distribution<double> gauss;
  const crux::Mesh& bunny = *targets.bunny.mesh;
  std::uniform_int_distribution<std::size_t> vertex(0, bunny.vertexCount() - 1);
  std::vector<Throw> throws;
  throws.reserve(std::size_t(count));
  while (int(throws.size()) < count) {
    Throw t;
    t.kind = BodyKind(throws.size() % 3);
    t.target = throws.size() % 2 == 0 ? Target::Bunny : Target::Wall;
    Vec3 aim, dir;
    if (t.target == Target::Bunny) {
      aim = bunny.vertices()[vertex(rng)];
      dir = Vec3(Real(gauss(rng)), Real(gauss(rng)), Real(gauss(rng)));
    } else {
      const crux::Obb& w = targets.wall;
      aim = w.center + Vec3(w.half.x(), Real(0.8 * unit(rng)) * w.half.y(), Real(0.8 * unit(rng)) * w.half.z());
      dir = Vec3(-1, Real(unit(rng)), Real(unit(rng)));  // within 45° of −x (a square cone)
    }
    if (dir.norm() < Real(1e-3)) continue;
    dir.normalize();
    const double distance = kMinDistance + (kMaxDistance - kMinDistance) * fraction(rng);
    const double speed = kMinSpeed + (kMaxSpeed - kMinSpeed) * fraction(rng);
    t.position = aim - dir * Real(distance);
    if (targets.bunny.volume && targets.bunny.volume->contains(t.position)) continue;
    if (std::any_of(throws.begin(), throws.end(), [&](const Throw& o) {
          return (o.position - t.position).norm() < Real(kSpawnClearance);
        }))
      continue;
    const double flight = distance / speed;
    t.velocity = dir * Real(speed) + Vec3(0, Real(0.5 * kGravity * flight), 0);
    crux::Quat q(Real(unit(rng)), Real(unit(rng)), Real(unit(rng)), Real(unit(rng)));
    t.rotation = q.norm() > Real(1e-3) ? q.normalized() : crux::Quat::Identity();
    throws.push_back(t);
  }
  return throws;
}

// ---- command line ----------------------------------------------------------------------------------

constexpr const char* kUsage =
    "usage: bullet_ccd [--mode none|bullet|crux|all] [--bodies N] [--steps N] [--seed N] [--mesh FILE]\n";

struct Options : crux_example::CommonOptions {
  std::vector<Mode> modes{Mode::None, Mode::Bullet, Mode::Crux};
  Options() {
    program = "bullet_ccd";
    usageText = kUsage;
    mesh = CRUX_EXAMPLE_DEFAULT_MESH;
    bodies = 300;
    steps = 90;
  }
};

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "--help" || flag == "-h") {
      std::printf("bullet_ccd: fast bodies vs a thin wall and bunny00, without CCD, with Bullet's and with crux's "
                  "(README.md)\n%s",
                  kUsage);
      std::exit(0);
    }
    if (i + 1 >= argc) o.usage(flag + ": missing value");
    const std::string value = argv[++i];
    if (flag == "--mode") {
      if (value == "none") o.modes = {Mode::None};
      else if (value == "bullet") o.modes = {Mode::Bullet};
      else if (value == "crux") o.modes = {Mode::Crux};
      else if (value == "all") o.modes = {Mode::None, Mode::Bullet, Mode::Crux};
      else o.usage(flag + ": expected none, bullet, crux or all, got '" + value + "'");
    } else {
      o.read(flag, value);
    }
  }
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  const Options options = parse(argc, argv);
  const std::optional<crux::Mesh> loaded = crux_example::loadMeshOrSkip(options.mesh, options.program);
  if (!loaded) return crux_example::kExitSkip;
  const double height = double(loaded->bounds().max.y() - loaded->bounds().min.y());
  if (!(height > 0) || loaded->vertexCount() == 0) {
    std::fprintf(stderr, "bullet_ccd: %s has no height along y\n", options.mesh.c_str());
    return kExitFailure;
  }
  Targets targets;
  targets.bunny = crux_example::makeStaticMesh(*loaded, kBunnyHeight / height, crux_example::Winding::Keep);
  targets.wall.center = kWallCentre;
  targets.wall.half = kWallHalf;
  const std::vector<Throw> throws = makeThrows(targets, options.bodies, options.seed);

  const crux::Aabb& b = targets.bunny.mesh->bounds();
  std::printf("bunny %s: %zu triangles, %.2f x %.2f x %.2f m at the origin (%s); wall %.3f x %.1f x %.1f m at "
              "(%.0f, %.0f, %.0f)\n",
              options.mesh.c_str(), targets.bunny.mesh->triangleCount(), double(b.max.x() - b.min.x()),
              double(b.max.y() - b.min.y()), double(b.max.z() - b.min.z()),
              targets.bunny.volume ? "closed" : "not closed", 2 * double(kWallHalf.x()), 2 * double(kWallHalf.y()),
              2 * double(kWallHalf.z()), double(kWallCentre.x()), double(kWallCentre.y()), double(kWallCentre.z()));
  std::printf("throws: %d bodies (spheres r %.2f, boxes %.2f x %.2f x %.2f, capsules r %.2f segment %.2f), half at "
              "each target, %.0f-%.0f m/s from %.0f-%.0f m; %d steps of %.4f s\n",
              options.bodies, kSphereRadius, 2 * kBoxHalf[0], 2 * kBoxHalf[1], 2 * kBoxHalf[2], kCapsuleRadius,
              2 * kCapsuleHalfHeight, kMinSpeed, kMaxSpeed, kMinDistance, kMaxDistance, options.steps, kTimeStep);

  bool ok = true;
  for (Mode mode : options.modes) {
    const RunResult r = run(targets, throws, mode, options.steps);
    std::printf("ccd %-6s: %zu thrown, tunnelled %d (bunny %d, wall %d); %.1f steps/s by CPU time (%.3f ms/step)\n",
                name(mode), throws.size(), r.tunnelled, r.tunnelledBunny, r.tunnelledWall, r.steps / r.cpuSeconds,
                1e3 * r.cpuSeconds / r.steps);
    if (mode == Mode::Crux) {
      const CruxCcd& c = r.ccd;
      std::printf("  crux: %llu body steps cast (%llu linear, %llu rigid; %.2f us each, %.1f%% of the step time); "
                  "stopped by the core's cast %llu; core starting in contact %llu, then stopped by the centre's cast "
                  "%llu, held %llu\n",
                  (unsigned long long)c.casts, (unsigned long long)c.linearCasts, (unsigned long long)c.rigidCasts,
                  1e6 * c.seconds / double(std::max<std::uint64_t>(1, c.casts)), 100 * c.seconds / r.cpuSeconds,
                  (unsigned long long)c.coreStops, (unsigned long long)c.centreCasts,
                  (unsigned long long)c.centreStops, (unsigned long long)c.holds);
    }
    if (mode != Mode::None) {
      for (int i : r.failed) {
        const Throw& t = throws[std::size_t(i)];
        std::printf("  TUNNELLED body %d (%s at the %s, from %.9g %.9g %.9g at %.9g %.9g %.9g m/s)\n", i,
                    t.kind == BodyKind::Sphere ? "sphere" : t.kind == BodyKind::Box ? "box" : "capsule",
                    t.target == Target::Bunny ? "bunny" : "wall", double(t.position.x()), double(t.position.y()),
                    double(t.position.z()), double(t.velocity.x()), double(t.velocity.y()), double(t.velocity.z()));
      }
    }
    if (mode == Mode::Crux) ok &= r.tunnelled == 0;
  }
  std::printf("%s\n", ok ? "OK: no body tunnelled with crux's CCD" : "FAILED: bodies tunnelled with crux's CCD");
  return ok ? 0 : kExitFailure;
}
