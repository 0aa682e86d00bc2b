#include "bullet_peer.hpp"

#include <btBulletCollisionCommon.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace crux::bench {

static_assert(sizeof(btScalar) == sizeof(float), "the bench shares float arrays with Bullet: link the float build");

namespace {

/// ClosestRayResultCallback that also remembers the triangle index of the closest hit.
struct ClosestTriangleRay : btCollisionWorld::ClosestRayResultCallback {
  ClosestTriangleRay(const btVector3& from, const btVector3& to) : ClosestRayResultCallback(from, to) {}
  int triangle = -1;
  btScalar addSingleResult(btCollisionWorld::LocalRayResult& r, bool normalInWorldSpace) override {
    triangle = r.m_localShapeInfo ? r.m_localShapeInfo->m_triangleIndex : -1;
    return ClosestRayResultCallback::addSingleResult(r, normalInWorldSpace);
  }
};

/// Stops at the first hit: records it and sets the closest fraction to 0, so every later
/// triangle is rejected (Bullet's triangle callback skips hits beyond the current fraction).
struct FirstHitRay : btCollisionWorld::RayResultCallback {
  btScalar addSingleResult(btCollisionWorld::LocalRayResult& r, bool) override {
    m_collisionObject = r.m_collisionObject;
    m_closestHitFraction = 0;
    return 0;
  }
};

/// Records the smallest contact distance contactPairTest reports (positive: separated points
/// within Bullet's closest-point threshold; <= 0: touching or penetrating).
struct MinDistance : btCollisionWorld::ContactResultCallback {
  btScalar minDistance = BT_LARGE_FLOAT;
  bool reported = false;
  btScalar addSingleResult(btManifoldPoint& cp, const btCollisionObjectWrapper*, int, int, const btCollisionObjectWrapper*,
                           int, int) override {
    reported = true;
    minDistance = std::min(minDistance, cp.getDistance());
    return 0;
  }
};

void record(BulletOverlapInfo& info, std::size_t i, std::size_t n, const MinDistance& cb) {
  if (info.minDistance.size() != n) info.minDistance.assign(n, std::numeric_limits<float>::infinity());
  if (cb.reported) info.minDistance[i] = float(cb.minDistance);
  if (cb.reported && cb.minDistance > 0) ++info.separatedReports;
}

}  // namespace

struct BulletPeer::Impl {
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher{&configuration};
  btDbvtBroadphase broadphase;
  btCollisionWorld world{&dispatcher, &broadphase, &configuration};
  std::unique_ptr<btTriangleIndexVertexArray> vertexArray;
  std::unique_ptr<btBvhTriangleMeshShape> meshShape;
  btCollisionObject meshObject;
  btCollisionObject queryObject;
  const MeshArrays* mesh = nullptr;
};

BulletPeer::BulletPeer(const MeshArrays& mesh) : impl_(std::make_unique<Impl>()) {
  impl_->mesh = &mesh;
  // Bullet's interface takes non-const pointers but only reads the arrays.
  impl_->vertexArray = std::make_unique<btTriangleIndexVertexArray>(
      int(mesh.triangleCount()), reinterpret_cast<int*>(const_cast<std::uint32_t*>(mesh.indices.data())),
      int(3 * sizeof(std::uint32_t)), int(mesh.vertexCount()), const_cast<btScalar*>(mesh.positions.data()),
      int(3 * sizeof(float)));
  impl_->meshShape = std::make_unique<btBvhTriangleMeshShape>(impl_->vertexArray.get(), true, true);
  impl_->meshShape->setMargin(0);
  impl_->meshObject.setCollisionShape(impl_->meshShape.get());
  impl_->meshObject.getWorldTransform().setIdentity();
  impl_->world.addCollisionObject(&impl_->meshObject);
  impl_->world.updateAabbs();
  impl_->queryObject.getWorldTransform().setIdentity();
}

BulletPeer::~BulletPeer() { impl_->world.removeCollisionObject(&impl_->meshObject); }

Seconds BulletPeer::timeBuild() const {
  const Stopwatch watch;
  auto shape = std::make_unique<btBvhTriangleMeshShape>(impl_->vertexArray.get(), true, true);
  const Seconds elapsed = watch.elapsed();
  return elapsed;
}

void BulletPeer::closestHits(const RayQuery* rays, std::size_t n, RayAnswer* out) const {
  for (std::size_t i = 0; i < n; ++i) {
    const RayQuery& q = rays[i];
    const btVector3 from(q.origin[0], q.origin[1], q.origin[2]);
    const btVector3 to = from + btVector3(q.dir[0], q.dir[1], q.dir[2]) * q.length;
    ClosestTriangleRay cb(from, to);
    impl_->world.rayTest(from, to, cb);
    if (cb.hasHit()) {
      const btVector3 d = to - from;
      const double len = std::sqrt(double(d.x()) * d.x() + double(d.y()) * d.y() + double(d.z()) * d.z());
      out[i] = {float(cb.m_closestHitFraction * len),
                cb.triangle >= 0 ? std::uint32_t(cb.triangle) : kNoTriangle, 1};
    } else {
      out[i] = {0.0f, kNoTriangle, 0};
    }
  }
}

void BulletPeer::anyHits(const RayQuery* rays, std::size_t n, std::uint8_t* out) const {
  for (std::size_t i = 0; i < n; ++i) {
    const RayQuery& q = rays[i];
    const btVector3 from(q.origin[0], q.origin[1], q.origin[2]);
    const btVector3 to = from + btVector3(q.dir[0], q.dir[1], q.dir[2]) * q.length;
    FirstHitRay cb;
    impl_->world.rayTest(from, to, cb);
    out[i] = cb.hasHit();
  }
}

void BulletPeer::segmentHits(const SegmentQuery* segments, std::size_t n, std::uint8_t* out) const {
  for (std::size_t i = 0; i < n; ++i) {
    const SegmentQuery& q = segments[i];
    const btVector3 from(q.start[0], q.start[1], q.start[2]), to(q.end[0], q.end[1], q.end[2]);
    FirstHitRay cb;
    impl_->world.rayTest(from, to, cb);
    out[i] = cb.hasHit();
  }
}

Seconds BulletPeer::refit() {
  const Stopwatch watch;
  const float* p = impl_->mesh->positions.data();
  btVector3 lo(p[0], p[1], p[2]), hi = lo;
  for (std::size_t i = 1, nv = impl_->mesh->vertexCount(); i < nv; ++i) {
    const btVector3 v(p[3 * i], p[3 * i + 1], p[3 * i + 2]);
    lo.setMin(v);
    hi.setMax(v);
  }
  impl_->meshShape->refitTree(lo, hi);
  impl_->world.updateSingleAabb(&impl_->meshObject);
  return watch.elapsed();
}

void BulletPeer::sphereOverlaps(const SphereQuery* q, std::size_t n, std::uint8_t* out, BulletOverlapInfo* info) const {
  btCollisionObject& obj = impl_->queryObject;
  for (std::size_t i = 0; i < n; ++i) {
    btSphereShape sphere(q[i].radius);
    obj.setCollisionShape(&sphere);
    obj.getWorldTransform().setOrigin(btVector3(q[i].center[0], q[i].center[1], q[i].center[2]));
    MinDistance cb;
    impl_->world.contactPairTest(&obj, &impl_->meshObject, cb);
    out[i] = cb.reported && cb.minDistance <= 0;
    if (info) record(*info, i, n, cb);
  }
  obj.setCollisionShape(nullptr);
}

void BulletPeer::boxOverlaps(const BoxQuery* q, std::size_t n, std::uint8_t* out, BulletOverlapInfo* info) const {
  btCollisionObject& obj = impl_->queryObject;
  for (std::size_t i = 0; i < n; ++i) {
    const BoxQuery& b = q[i];
    btBoxShape box(btVector3(b.half[0], b.half[1], b.half[2]));
    box.setMargin(0);
    obj.setCollisionShape(&box);
    // btMatrix3x3 takes rows; column i of the rotation is box axis i.
    const float* a = b.axes;
    btTransform& tf = obj.getWorldTransform();
    tf.setBasis(btMatrix3x3(a[0], a[3], a[6], a[1], a[4], a[7], a[2], a[5], a[8]));
    tf.setOrigin(btVector3(b.center[0], b.center[1], b.center[2]));
    MinDistance cb;
    impl_->world.contactPairTest(&obj, &impl_->meshObject, cb);
    out[i] = cb.reported && cb.minDistance <= 0;
    if (info) record(*info, i, n, cb);
  }
  obj.setCollisionShape(nullptr);
}

float BulletPeer::meshMargin() const { return float(impl_->meshShape->getMargin()); }

std::size_t BulletPeer::bvhBytes() const {
  const btOptimizedBvh* bvh = impl_->meshShape->getOptimizedBvh();
  return bvh ? bvh->calculateSerializeBufferSize() : 0;
}

std::string bulletVersion() {
  const int v = btGetVersion();
  std::string s = std::to_string(v / 100) + "." + std::to_string(v % 100);
  s += sizeof(btScalar) == sizeof(double) ? " double" : " float";
  return s;
}

}  // namespace crux::bench
