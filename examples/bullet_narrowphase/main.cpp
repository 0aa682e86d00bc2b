/// @file main.cpp  crux as the convex-vs-mesh narrow phase of a Bullet rigid-body world.
///
/// A btDiscreteDynamicsWorld holds a static real mesh (bunny00, scaled to tens of metres, a
/// btBvhTriangleMeshShape) and N spheres, boxes and capsules released from a grid layer inside it,
/// above its floor: the closed bunny is the container they fall into and settle in. Two narrow
/// phases run the same scene:
///   --narrowphase bullet  Bullet's own btConvexConcaveCollisionAlgorithm (GJK/EPA per triangle);
///   --narrowphase crux    `CruxMeshAlgorithm`, a btCollisionAlgorithm registered with the
///                         dispatcher for SPHERE/BOX/CAPSULE × TRIANGLE_MESH (both orders), which
///                         calls crux::contacts(mesh, ..., shape, ...) with the internal-edge
///                         correction (MeshQueryData) and feeds the points to the btManifoldResult.
/// Body–body pairs use Bullet's convex algorithms in both modes. After the run each body must be
/// at rest and still inside the closed mesh (a body outside it, or below its bounding box, fell
/// through the surface); the program prints steps/s and the bodies' gaps to the surface and exits
/// 1 on any failure, 77 when the mesh cannot be loaded, 2 on bad arguments. See README.md.

#include "common/bullet_crux.hpp"

#include <crux/error.hpp>
#include <crux/mesh/mesh.hpp>
#include <crux/mesh/mesh_contact.hpp>
#include <crux/mesh/mesh_volume.hpp>

#include <btBulletCollisionCommon.h>
#include <btBulletDynamicsCommon.h>
#include <BulletCollision/CollisionDispatch/btActivatingCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btInternalEdgeUtility.h>
#include <BulletCollision/CollisionShapes/btTriangleInfoMap.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <new>
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
constexpr double kTimeStep = 1.0 / 60.0;   ///< one fixed Bullet step per frame
constexpr double kMeshHeight = 20.0;       ///< the bunny is scaled to this height at least
constexpr double kSphereRadius = 0.25;
constexpr double kBoxHalf[3] = {0.3, 0.2, 0.15};
constexpr double kCapsuleRadius = 0.15;
constexpr double kCapsuleHalfHeight = 0.2;  ///< half the segment between the cap centres
/// Bounding radius of the largest body (the box): the spawn grid's spacing is 2× this + a gap.
constexpr double kBodyRadius = 0.391;
constexpr double kSpawnSpacing = 2 * kBodyRadius + 0.1;
constexpr double kFriction = 0.8;
constexpr int kSolverIterations = 20;       ///< Bullet's default is 10: piles settle sooner with 20
constexpr double kDeactivationTime = 1.0;   ///< s below the sleeping thresholds before sleeping (default 2)
constexpr double kRollingFriction = 0.1;    ///< spheres and capsules stop rolling on gentle slopes
constexpr double kLinearDamping = 0.2;      ///< fraction of the velocity lost per second (drag)
constexpr double kAngularDamping = 0.5;
/// A body is at rest when, over the last kRestWindow steps (1 s), its centre moved less than
/// kRestDisplacement (sleeping bodies do not move at all). Measured over a window, not by the
/// last step's speed: a settled pile jitters (the solver's residual) without going anywhere, and
/// a sphere may keep spinning in place (no spinning friction).
constexpr int kRestWindow = 60;
constexpr double kRestDisplacement = 0.05;  ///< m: a sixth of the smallest body dimension

/// Steps timed separately: the first second of simulated time (fall, impact, first bounces), in
/// which no body can fall asleep (it would have to be still for kDeactivationTime), so both modes
/// do the same work.
constexpr int kActiveSteps = 60;

using crux_example::kExitFailure;

// ---- crux inside Bullet's dispatcher -------------------------------------------------------------

/// What the crux algorithm needs besides the two bodies: the crux copy of the static mesh (built
/// once from the same vertices as the btBvhTriangleMeshShape), its query data, and counters.
struct CruxMeshContext {
  const crux::Mesh* mesh = nullptr;
  const crux::MeshQueryData* queryData = nullptr;
  std::uint64_t queries = 0;  ///< crux::contacts calls
  std::uint64_t points = 0;   ///< contact points handed to Bullet
};

/// Convex (sphere, box, capsule) vs triangle mesh by crux::contacts. One persistent manifold per
/// pair, owned like Bullet's own algorithms own theirs (from the dispatcher's pool; body 0 the
/// convex body, body 1 the mesh, as in btConvexConcaveCollisionAlgorithm). Every step the crux
/// points (at most 4, each with its own normal) are added to it — btManifoldResult::addContactPoint
/// matches them with cached points, keeping the warm-starting impulses — and
/// refreshContactPoints drops the cached points that no longer hold.
///
/// Conventions. Bullet's addContactPoint(normalOnB, pointInWorld, depth) means: pointInWorld on
/// body B, normalOnB from B towards A, pointOnA = pointInWorld + normalOnB·depth, depth < 0
/// penetrating — crux's convention (normal from B to A, pointA − pointB = separation·normal) with
/// A and B named the other way round. And A/B are the *manifold's* body 0/1, not the order in
/// which the dispatcher passes the bodies (btManifoldResult only swaps the local frames when the
/// two differ). With the manifold (shape, mesh) and crux's (A = mesh, B = shape):
///   normalOnB = −crux normal (mesh → shape), pointInWorld = crux pointA (on the mesh),
///   depth = crux separation.
class CruxMeshAlgorithm final : public btActivatingCollisionAlgorithm {
 public:
  CruxMeshAlgorithm(const btCollisionAlgorithmConstructionInfo& info, const btCollisionObjectWrapper* body0,
                    const btCollisionObjectWrapper* body1, CruxMeshContext& context)
      : btActivatingCollisionAlgorithm(info, body0, body1), context_(context) {
    const bool meshFirst = isMesh(*body0);
    manifold_ = m_dispatcher->getNewManifold((meshFirst ? body1 : body0)->getCollisionObject(),
                                             (meshFirst ? body0 : body1)->getCollisionObject());
  }
  ~CruxMeshAlgorithm() override { m_dispatcher->releaseManifold(manifold_); }
  CruxMeshAlgorithm(const CruxMeshAlgorithm&) = delete;
  CruxMeshAlgorithm& operator=(const CruxMeshAlgorithm&) = delete;

  void processCollision(const btCollisionObjectWrapper* body0, const btCollisionObjectWrapper* body1,
                        const btDispatcherInfo&, btManifoldResult* result) override {
    const bool meshFirst = isMesh(*body0);
    const btCollisionObjectWrapper& meshBody = meshFirst ? *body0 : *body1;
    const btCollisionObjectWrapper& convexBody = meshFirst ? *body1 : *body0;
    crux::ConvexShape shape;
    if (!toCruxShape(*convexBody.getCollisionShape(), shape)) return;
    result->setPersistentManifold(manifold_);
    // Speculative contacts out to Bullet's contact breaking threshold of this pair, the distance
    // up to which addContactPoint keeps points anyway.
    const Real margin = Real(manifold_->getContactBreakingThreshold());
    crux::MeshContactManifold contacts;
    crux::contacts(*context_.mesh, toCrux(meshBody.getWorldTransform()), shape,
                   toCrux(convexBody.getWorldTransform()), margin, contacts, context_.queryData);
    ++context_.queries;
    context_.points += std::uint64_t(contacts.count);
    const bool meshIsA = manifold_->getBody0() == meshBody.getCollisionObject();  // false by construction
    for (int i = 0; i < contacts.count; ++i) {
      const crux::MeshContactPoint& p = contacts.points[i];
      if (meshFirst) result->setShapeIdentifiersA(0, int(p.triangle));  // in the dispatcher's order
      else result->setShapeIdentifiersB(0, int(p.triangle));
      if (meshIsA) result->addContactPoint(toBt(p.normal), toBt(p.pointB), btScalar(p.separation));
      else result->addContactPoint(toBt(Vec3(-p.normal)), toBt(p.pointA), btScalar(p.separation));
    }
    result->refreshContactPoints();
  }

  /// No continuous collision: the scene's bodies move less than their size per step.
  btScalar calculateTimeOfImpact(btCollisionObject*, btCollisionObject*, const btDispatcherInfo&,
                                 btManifoldResult*) override {
    return btScalar(1);
  }

  void getAllContactManifolds(btManifoldArray& manifolds) override { manifolds.push_back(manifold_); }

  static bool isMesh(const btCollisionObjectWrapper& body) {
    return body.getCollisionShape()->getShapeType() == TRIANGLE_MESH_SHAPE_PROXYTYPE;
  }

 private:
  CruxMeshContext& context_;
  btPersistentManifold* manifold_ = nullptr;
};

/// Creates CruxMeshAlgorithm in the dispatcher's algorithm pool (the dispatcher destroys it with
/// ~btCollisionAlgorithm + freeCollisionAlgorithm). The algorithm tells the mesh by its shape type,
/// so one create function serves both orders of the pair.
struct CruxMeshCreateFunc final : btCollisionAlgorithmCreateFunc {
  explicit CruxMeshCreateFunc(CruxMeshContext& c) : context(&c) {}
  btCollisionAlgorithm* CreateCollisionAlgorithm(btCollisionAlgorithmConstructionInfo& info,
                                                 const btCollisionObjectWrapper* body0,
                                                 const btCollisionObjectWrapper* body1) override {
    void* memory = info.m_dispatcher1->allocateCollisionAlgorithm(int(sizeof(CruxMeshAlgorithm)));
    return new (memory) CruxMeshAlgorithm(info, body0, body1, *context);
  }
  CruxMeshContext* context;
};

/// CPU time spent in one kind of collision algorithm (both modes wrap their convex–mesh algorithm
/// in TimedAlgorithm, so the narrow phases are compared on the same calls).
struct AlgorithmTimer {
  double seconds = 0;
  std::uint64_t calls = 0;
};

/// Decorator: forwards to `inner` (created by another create function in the dispatcher's pool)
/// and adds the CPU time of processCollision to a timer.
class TimedAlgorithm final : public btCollisionAlgorithm {
 public:
  TimedAlgorithm(const btCollisionAlgorithmConstructionInfo& info, btCollisionAlgorithm* inner, AlgorithmTimer& timer)
      : btCollisionAlgorithm(info), inner_(inner), timer_(timer) {}
  ~TimedAlgorithm() override {
    inner_->~btCollisionAlgorithm();
    m_dispatcher->freeCollisionAlgorithm(inner_);
  }
  TimedAlgorithm(const TimedAlgorithm&) = delete;
  TimedAlgorithm& operator=(const TimedAlgorithm&) = delete;
  void processCollision(const btCollisionObjectWrapper* body0, const btCollisionObjectWrapper* body1,
                        const btDispatcherInfo& info, btManifoldResult* result) override {
    const double start = threadCpuSeconds();
    inner_->processCollision(body0, body1, info, result);
    timer_.seconds += threadCpuSeconds() - start;
    ++timer_.calls;
  }
  btScalar calculateTimeOfImpact(btCollisionObject* body0, btCollisionObject* body1, const btDispatcherInfo& info,
                                 btManifoldResult* result) override {
    return inner_->calculateTimeOfImpact(body0, body1, info, result);
  }
  void getAllContactManifolds(btManifoldArray& manifolds) override { inner_->getAllContactManifolds(manifolds); }

 private:
  btCollisionAlgorithm* inner_;
  AlgorithmTimer& timer_;
};

/// Create function of TimedAlgorithm around another create function.
struct TimedCreateFunc final : btCollisionAlgorithmCreateFunc {
  TimedCreateFunc(btCollisionAlgorithmCreateFunc& i, AlgorithmTimer& t) : inner(&i), timer(&t) {}
  btCollisionAlgorithm* CreateCollisionAlgorithm(btCollisionAlgorithmConstructionInfo& info,
                                                 const btCollisionObjectWrapper* body0,
                                                 const btCollisionObjectWrapper* body1) override {
    btCollisionAlgorithm* algorithm = inner->CreateCollisionAlgorithm(info, body0, body1);
    void* memory = info.m_dispatcher1->allocateCollisionAlgorithm(int(sizeof(TimedAlgorithm)));
    return new (memory) TimedAlgorithm(info, algorithm, *timer);
  }
  btCollisionAlgorithmCreateFunc* inner;
  AlgorithmTimer* timer;
};

// ---- the scene ---------------------------------------------------------------------------------

enum class BodyKind { Sphere, Box, Capsule };
const char* name(BodyKind k) { return k == BodyKind::Sphere ? "sphere" : k == BodyKind::Box ? "box" : "capsule"; }

/// One body to drop: kind, start position and orientation (the same in both modes).
struct Spawn {
  BodyKind kind = BodyKind::Sphere;
  Vec3 position = Vec3::Zero();
  crux::Quat rotation = crux::Quat::Identity();
};

/// The lowest layer of grid cells (spacing kSpawnSpacing, in the scaled mesh's frame) whose ball
/// of radius kBodyRadius + a gap is inside the closed mesh and clear of its surface: one layer over
/// the container's floor, so that the bodies land on the mesh rather than on a heap of each other
/// (heaps of spheres and capsules keep slumping for many seconds, in both narrow phases). For a
/// mesh that is not closed: one layer above the mesh's bounding box instead.
std::vector<Vec3> spawnCells(const StaticMesh& m) {
  const crux::Aabb& b = m.mesh->bounds();
  std::vector<Vec3> cells;
  const double h = kSpawnSpacing;
  if (!m.volume) {
    const double y = double(b.max.y()) + 2 * h;
    for (double x = b.min.x() + h; x < b.max.x() - h; x += h)
      for (double z = b.min.z() + h; z < b.max.z() - h; z += h)
        cells.push_back(Vec3{static_cast<Real>(x), static_cast<Real>(y), static_cast<Real>(z)});
    return cells;
  }
  const crux::Transform identity;
  for (double y = b.min.y() + h / 2; y < b.max.y() && cells.empty(); y += h)
    for (double x = b.min.x() + h / 2; x < b.max.x(); x += h)
      for (double z = b.min.z() + h / 2; z < b.max.z(); z += h) {
        const Vec3 p{static_cast<Real>(x), static_cast<Real>(y), static_cast<Real>(z)};
        if (!m.volume->contains(p)) continue;
        const crux::Sphere ball{p, Real(kBodyRadius)};
        if (crux::distance(*m.mesh, identity, ball, identity, Real(0.1 * h)).found) continue;
        cells.push_back(p);
      }
  return cells;
}

/// gContactAddedCallback of the stock mode: Bullet's internal-edge correction for contacts with
/// the mesh (index of the mesh's triangle in the mesh's wrapper).
bool adjustInternalEdgeContacts(btManifoldPoint& point, const btCollisionObjectWrapper* body0, int part0, int index0,
                                const btCollisionObjectWrapper* body1, int part1, int index1) {
  if (body1->getCollisionShape()->getShapeType() == TRIANGLE_SHAPE_PROXYTYPE)
    btAdjustInternalEdgeContacts(point, body1, body0, part1, index1);
  else if (body0->getCollisionShape()->getShapeType() == TRIANGLE_SHAPE_PROXYTYPE)
    btAdjustInternalEdgeContacts(point, body0, body1, part0, index0);
  return true;
}

/// Result of one run of the scene.
struct RunResult {
  double seconds = 0;           ///< wall time in stepSimulation
  double cpuSeconds = 0;        ///< CPU time of this thread in stepSimulation (robust to a loaded machine)
  int activeSteps = 0;          ///< the first steps, while every body is still awake in both modes
  double activeCpuSeconds = 0;  ///< CPU time of those
  int steps = 0;
  int allAsleepAt = -1;         ///< first step after which every body slept (-1: never)
  int atRest = 0, sleeping = 0;
  int outsideMesh = 0;          ///< centre outside the closed mesh (fell through its surface)
  int belowBounds = 0;          ///< centre below the mesh's bounding box
  int fellThrough = 0;          ///< outside or below
  std::vector<double> gaps;     ///< per body: signed distance to the mesh surface (crux::distance)
  std::vector<int> failed;      ///< bodies that fell through or are not at rest
  std::vector<double> speeds, spins;  ///< per body at the end: |v| [m/s], |ω| [rad/s]
  std::vector<double> moved;          ///< per body: displacement over the last second [m]
  int states[6] = {0, 0, 0, 0, 0, 0}; ///< Bullet activation states 1..5 at the end
  std::uint64_t cruxQueries = 0, cruxPoints = 0;
  double meshPairSeconds = 0;   ///< CPU time in the convex–mesh algorithm's processCollision
  std::uint64_t meshPairCalls = 0;
};

/// Builds the world (crux or Bullet narrow phase for convex–mesh pairs), drops the bodies, steps.
RunResult run(const StaticMesh& m, const std::vector<Spawn>& spawns, int steps, bool useCrux, bool trace) {
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher(&configuration);
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world(&dispatcher, &broadphase, &solver, &configuration);
  world.setGravity(btVector3(0, btScalar(-kGravity), 0));
  world.getSolverInfo().m_numIterations = kSolverIterations;
  gDeactivationTime = btScalar(kDeactivationTime);

  // Convex–mesh pairs, both orders: crux (CruxMeshAlgorithm) or Bullet's own create functions
  // (btConvexConcaveCollisionAlgorithm, and its swapped variant), each wrapped in the timer.
  CruxMeshContext context{m.mesh.get(), m.queryData.get()};
  CruxMeshCreateFunc cruxCreate(context);
  AlgorithmTimer timer;
  std::vector<std::unique_ptr<TimedCreateFunc>> timed;
  for (int convex : {SPHERE_SHAPE_PROXYTYPE, BOX_SHAPE_PROXYTYPE, CAPSULE_SHAPE_PROXYTYPE})
    for (const auto& [a, b] : {std::pair{convex, int(TRIANGLE_MESH_SHAPE_PROXYTYPE)},
                               std::pair{int(TRIANGLE_MESH_SHAPE_PROXYTYPE), convex}}) {
      btCollisionAlgorithmCreateFunc* inner =
          useCrux ? &cruxCreate : configuration.getCollisionAlgorithmCreateFunc(a, b);
      timed.push_back(std::make_unique<TimedCreateFunc>(*inner, timer));
      dispatcher.registerCollisionCreateFunc(a, b, timed.back().get());
    }

  const auto array = crux_example::bulletTriangles(m);
  btBvhTriangleMeshShape meshShape(array.get(), true, true);
  // Stock mode with Bullet's own ghost-contact fix (btInternalEdgeUtility), the counterpart of
  // crux's internal-edge correction (MeshQueryData): per-triangle edge angles, applied to each new contact point
  // by the contact-added callback.
  btTriangleInfoMap triangleInfo;
  if (!useCrux) btGenerateInternalEdgeInfo(&meshShape, &triangleInfo);
  btRigidBody meshBody(btRigidBody::btRigidBodyConstructionInfo(0, nullptr, &meshShape));
  if (!useCrux) {
    meshBody.setCollisionFlags(meshBody.getCollisionFlags() | btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK);
    gContactAddedCallback = adjustInternalEdgeContacts;
  }
  meshBody.setFriction(btScalar(kFriction));
  meshBody.setRollingFriction(btScalar(kRollingFriction));
  world.addRigidBody(&meshBody);

  btSphereShape sphere{btScalar(kSphereRadius)};
  btBoxShape box{btVector3(btScalar(kBoxHalf[0]), btScalar(kBoxHalf[1]), btScalar(kBoxHalf[2]))};
  btCapsuleShape capsule{btScalar(kCapsuleRadius), btScalar(2 * kCapsuleHalfHeight)};
  std::vector<std::unique_ptr<btRigidBody>> bodies;
  bodies.reserve(spawns.size());
  for (const Spawn& s : spawns) {
    btCollisionShape* shape = s.kind == BodyKind::Sphere ? static_cast<btCollisionShape*>(&sphere)
                              : s.kind == BodyKind::Box  ? static_cast<btCollisionShape*>(&box)
                                                         : static_cast<btCollisionShape*>(&capsule);
    const btScalar mass = 1;
    btVector3 inertia(0, 0, 0);
    shape->calculateLocalInertia(mass, inertia);
    btRigidBody::btRigidBodyConstructionInfo info(mass, nullptr, shape, inertia);
    const crux::Quat& q = s.rotation;
    info.m_startWorldTransform = btTransform(
        btQuaternion(btScalar(q.x()), btScalar(q.y()), btScalar(q.z()), btScalar(q.w())), toBt(s.position));
    info.m_friction = btScalar(kFriction);
    info.m_rollingFriction = btScalar(kRollingFriction);
    info.m_linearDamping = btScalar(kLinearDamping);
    info.m_angularDamping = btScalar(kAngularDamping);
    bodies.push_back(std::make_unique<btRigidBody>(info));
    world.addRigidBody(bodies.back().get());
  }

  RunResult r;
  r.steps = steps;
  const auto start = std::chrono::steady_clock::now();
  const double cpuStart = threadCpuSeconds();
  std::vector<btTransform> windowStart(bodies.size());
  for (int i = 0; i < steps; ++i) {
    if (i == std::max(0, steps - kRestWindow))
      for (std::size_t k = 0; k < bodies.size(); ++k) windowStart[k] = bodies[k]->getWorldTransform();
    world.stepSimulation(btScalar(kTimeStep), 1, btScalar(kTimeStep));
    if (i + 1 == std::min(steps, kActiveSteps)) {
      r.activeSteps = i + 1;
      r.activeCpuSeconds = threadCpuSeconds() - cpuStart;
    }
    if (r.allAsleepAt < 0 && std::all_of(bodies.begin(), bodies.end(), [](const auto& b) {
          return b->getActivationState() == ISLAND_SLEEPING;
        }))
      r.allAsleepAt = i + 1;
    if (trace && (i + 1) % 60 == 0) {
      int awake = 0, fastest = -1;
      double vmax = 0;
      for (std::size_t k = 0; k < bodies.size(); ++k) {
        if (bodies[k]->getActivationState() == ISLAND_SLEEPING) continue;
        ++awake;
        const double v = double(bodies[k]->getLinearVelocity().length());
        if (fastest < 0 || v > vmax) vmax = v, fastest = int(k);
      }
      std::printf("    step %4d: %3d awake, fastest body %d at %.3g m/s\n", i + 1, awake, fastest, vmax);
    }
  }
  r.cpuSeconds = threadCpuSeconds() - cpuStart;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.meshPairSeconds = timer.seconds;
  r.meshPairCalls = timer.calls;
  r.cruxQueries = context.queries;
  r.cruxPoints = context.points;

  const crux::Transform identity;
  const Real bottom = m.mesh->bounds().min.y();
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    const btRigidBody& body = *bodies[i];
    const bool sleeping = body.getActivationState() == ISLAND_SLEEPING;
    const btTransform& now = body.getWorldTransform();
    const double moved = double((now.getOrigin() - windowStart[i].getOrigin()).length());
    const bool slow = moved < kRestDisplacement;
    r.moved.push_back(moved);
    const crux::Transform pose = toCrux(body.getWorldTransform());
    const bool below = pose.translation.y() < bottom;
    const bool outside = m.volume ? !m.volume->contains(pose.translation) : below;
    crux::ConvexShape shape;
    toCruxShape(*body.getCollisionShape(), shape);
    r.gaps.push_back(double(crux::distance(*m.mesh, identity, shape, pose).distance));
    r.sleeping += sleeping;
    r.speeds.push_back(double(body.getLinearVelocity().length()));
    r.spins.push_back(double(body.getAngularVelocity().length()));
    r.states[std::min(5, std::max(0, body.getActivationState()))]++;
    r.atRest += sleeping || slow;
    r.outsideMesh += outside;
    r.belowBounds += below;
    r.fellThrough += outside || below;
    if (outside || below || !(sleeping || slow)) r.failed.push_back(int(i));
    world.removeRigidBody(bodies[i].get());
  }
  world.removeRigidBody(&meshBody);
  gContactAddedCallback = nullptr;
  return r;
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  const std::size_t k = std::min(v.size() - 1, std::size_t(q * double(v.size() - 1) + 0.5));
  std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(k), v.end());
  return v[k];
}

/// Prints one mode's figures; returns true when every body is at rest inside the mesh.
bool report(const char* mode, const RunResult& r, const std::vector<Spawn>& spawns, const StaticMesh& m) {
  std::printf("narrowphase %-6s: %d steps: %.1f steps/s by CPU time (%.3f ms/step; wall %.3f s, %.1f steps/s); "
              "first %d steps (all awake): %.1f steps/s\n",
              mode, r.steps, r.steps / r.cpuSeconds, 1e3 * r.cpuSeconds / r.steps, r.seconds, r.steps / r.seconds,
              r.activeSteps, r.activeSteps / r.activeCpuSeconds);
  std::printf("  at rest %d/%zu (sleeping %d, all asleep from step %d); fell through: %d (outside the closed mesh %d, below its bounds %d)\n",
              r.atRest, spawns.size(), r.sleeping, r.allAsleepAt, r.fellThrough, r.outsideMesh, r.belowBounds);
  const double touch = 0.02;  // a body within 2 cm of the surface rests on it (else on other bodies)
  const long touching = std::count_if(r.gaps.begin(), r.gaps.end(), [&](double g) { return g <= touch; });
  std::printf("  gap to the mesh surface [m]: min %.4f  median %.4f  max %.4f; on the surface (gap <= %.2f): %ld\n",
              quantile(r.gaps, 0), quantile(r.gaps, 0.5), quantile(r.gaps, 1), touch, touching);
  std::printf("  last second: moved median %.3g max %.3g m; at the end |v| median %.3g max %.3g m/s, |w| median "
              "%.3g max %.3g rad/s; Bullet states active/sleeping/wants-sleep %d/%d/%d\n",
              quantile(r.moved, 0.5), quantile(r.moved, 1), quantile(r.speeds, 0.5), quantile(r.speeds, 1),
              quantile(r.spins, 0.5), quantile(r.spins, 1), r.states[ACTIVE_TAG], r.states[ISLAND_SLEEPING],
              r.states[WANTS_DEACTIVATION]);
  std::printf("  convex-mesh narrow phase: %llu pair updates, %.2f us each, %.1f%% of the step time\n",
              (unsigned long long)r.meshPairCalls, 1e6 * r.meshPairSeconds / double(std::max<std::uint64_t>(1, r.meshPairCalls)),
              100 * r.meshPairSeconds / r.cpuSeconds);
  if (r.cruxQueries)
    std::printf("  crux::contacts: %llu queries, %.2f points per query\n", (unsigned long long)r.cruxQueries,
                double(r.cruxPoints) / double(r.cruxQueries));
  for (int i : r.failed) {
    const Spawn& s = spawns[std::size_t(i)];
    std::printf("  FAILED body %d (%s, spawned at %.17g %.17g %.17g): gap %.17g, moved %.3g m in the last second, |v| %.3g, |w| %.3g%s\n", i,
                name(s.kind), double(s.position.x()), double(s.position.y()), double(s.position.z()),
                r.gaps[std::size_t(i)], r.moved[std::size_t(i)], r.speeds[std::size_t(i)], r.spins[std::size_t(i)],
                m.volume ? "" : " (mesh not closed)");
  }
  return r.failed.empty();
}

constexpr const char* kUsage =
    "usage: bullet_narrowphase [--narrowphase bullet|crux|both] [--mode both] [--bodies N]\n"
    "                          [--steps N] [--seed N] [--mesh FILE] [--trace]\n";

struct Options : crux_example::CommonOptions {
  bool runBullet = true, runCrux = true;
  bool trace = false;  ///< print the awake count every second of simulated time
  Options() {
    program = "bullet_narrowphase";
    usageText = kUsage;
    mesh = CRUX_EXAMPLE_DEFAULT_MESH;
    bodies = 200;
    steps = 600;
  }
};

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "--help" || flag == "-h") {
      std::printf("bullet_narrowphase: crux vs Bullet as the convex-vs-mesh narrow phase (README.md)\n%s", kUsage);
      std::exit(0);
    }
    if (flag == "--trace") {
      o.trace = true;
      continue;
    }
    if (i + 1 >= argc) o.usage(flag + ": missing value");
    const std::string value = argv[++i];
    if (flag == "--narrowphase" || flag == "--mode") {
      if (value == "bullet") o.runCrux = false, o.runBullet = true;
      else if (value == "crux") o.runCrux = true, o.runBullet = false;
      else if (value == "both") o.runCrux = o.runBullet = true;
      else o.usage(flag + ": expected bullet, crux or both, got '" + value + "'");
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

  // Scale the mesh to kMeshHeight (y up, as bunny00), more if the lowest layer of the grid inside
  // it has too few cells (the floor's area grows as the scale squared).
  const double height = double(loaded->bounds().max.y() - loaded->bounds().min.y());
  double scale = kMeshHeight / height;
  StaticMesh m;
  std::vector<Vec3> cells;
  for (int attempt = 0;; ++attempt) {
    m = crux_example::makeStaticMesh(*loaded, scale, crux_example::Winding::Reverse);
    cells = spawnCells(m);
    if (int(cells.size()) >= options.bodies) break;
    if (attempt == 20) {
      std::fprintf(stderr, "bullet_narrowphase: no room for %d bodies in %s\n", options.bodies, options.mesh.c_str());
      return kExitFailure;
    }
    scale *= std::sqrt(1.05 * options.bodies / std::max<double>(1, double(cells.size())));
  }

  std::mt19937 rng(options.seed);
  std::uniform_real_distribution<double> unit(-1, 1);
  std::vector<Spawn> spawns(std::size_t(options.bodies));
  int counts[3] = {0, 0, 0};
  for (std::size_t i = 0; i < spawns.size(); ++i) {
    Spawn& s = spawns[i];
    s.kind = BodyKind(i % 3);
    ++counts[i % 3];
    s.position = cells[i];
    crux::Quat q(Real(unit(rng)), Real(unit(rng)), Real(unit(rng)), Real(unit(rng)));
    s.rotation = q.norm() > Real(1e-3) ? q.normalized() : crux::Quat::Identity();
  }
  const crux::Aabb& b = m.mesh->bounds();
  std::printf("spawn grid: spacing %.3f m, %zu free cells %s the mesh, used %d at heights %.2f..%.2f m above its "
              "lowest point\n",
              kSpawnSpacing, cells.size(), m.volume ? "inside" : "above", options.bodies, double(cells.front().y() - b.min.y()),
              double(cells[std::size_t(options.bodies) - 1].y() - b.min.y()));
  std::printf("mesh %s: %zu triangles, scaled x%.3g to %.2f x %.2f x %.2f m (%s)\n", options.mesh.c_str(),
              m.mesh->triangleCount(), scale, double(b.max.x() - b.min.x()), double(b.max.y() - b.min.y()),
              double(b.max.z() - b.min.z()),
              m.volume ? "closed: bodies are released inside it" : "not closed: bodies are dropped on it");
  std::printf("bodies: %d spheres (r %.2f), %d boxes (%.2f x %.2f x %.2f), %d capsules (r %.2f, segment %.2f); "
              "%d steps of %.4f s; crux Real is %s, Bullet's btScalar %s\n",
              counts[0], kSphereRadius, counts[1], 2 * kBoxHalf[0], 2 * kBoxHalf[1], 2 * kBoxHalf[2], counts[2],
              kCapsuleRadius, 2 * kCapsuleHalfHeight, options.steps, kTimeStep,
              sizeof(Real) == 8 ? "double" : "float", sizeof(btScalar) == 8 ? "double" : "float");

  bool ok = true;
  if (options.runBullet) ok &= report("bullet", run(m, spawns, options.steps, false, options.trace), spawns, m);
  if (options.runCrux) ok &= report("crux", run(m, spawns, options.steps, true, options.trace), spawns, m);
  std::printf("%s\n", ok ? "OK: every body at rest, none fell through" : "FAILED");
  return ok ? 0 : kExitFailure;
}
