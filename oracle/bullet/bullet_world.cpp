/// @file bullet_world.cpp  The "bullet" backend (see bullet_world.hpp): crux shapes converted to
/// Bullet collision shapes with zero margins, every answer straight from Bullet's collision
/// module.

#include "bullet/bullet_world.hpp"

#include <btBulletCollisionCommon.h>
#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <BulletCollision/NarrowPhaseCollision/btRaycastCallback.h>
#include <BulletCollision/NarrowPhaseCollision/btVoronoiSimplexSolver.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

namespace crux::bullet_oracle {
namespace {

/// A float or double Eigen 3-vector as a Bullet vector (rounded to btScalar).
template <class V>
btVector3 toBt(const Eigen::MatrixBase<V>& v) {
  return btVector3(btScalar(v.x()), btScalar(v.y()), btScalar(v.z()));
}
Vec3d toD(const btVector3& v) { return Vec3d(double(v.x()), double(v.y()), double(v.z())); }

/// A crux transform as a Bullet one (btQuaternion takes x, y, z, w).
btTransform toBt(const Transform& t) {
  const Eigen::Quaterniond q = t.rotation.cast<double>().normalized();
  return btTransform(btQuaternion(btScalar(q.x()), btScalar(q.y()), btScalar(q.z()), btScalar(q.w())),
                     toBt(t.translation));
}

/// A triangle mesh as Bullet sees it: float copies of the arrays, the striding interface over
/// them, a btBvhTriangleMeshShape (margin 0), and a collision object at the identity.
struct BulletMesh {
  std::vector<int> indices;
  std::vector<btScalar> positions;
  std::unique_ptr<btTriangleIndexVertexArray> array;
  std::unique_ptr<btBvhTriangleMeshShape> shape;
  std::unique_ptr<btGImpactMeshShape> gimpact;  ///< built on first use by mesh_mesh
  btCollisionObject object;
  Vec3d boundsMin = Vec3d::Zero(), boundsMax = Vec3d::Zero();

  BulletMesh(const std::vector<Vec3>& vertices, const std::vector<TriangleIndices>& triangles) {
    positions.reserve(3 * vertices.size());
    boundsMin = boundsMax = vertices.front().cast<double>();
    for (const Vec3& v : vertices) {
      for (int i = 0; i < 3; ++i) positions.push_back(btScalar(v[i]));
      boundsMin = boundsMin.cwiseMin(v.cast<double>());
      boundsMax = boundsMax.cwiseMax(v.cast<double>());
    }
    indices.reserve(3 * triangles.size());
    for (const TriangleIndices& t : triangles)
      for (int i = 0; i < 3; ++i) indices.push_back(int(t[i]));
    array = std::make_unique<btTriangleIndexVertexArray>(int(triangles.size()), indices.data(), int(3 * sizeof(int)),
                                                         int(vertices.size()), positions.data(),
                                                         int(3 * sizeof(btScalar)));
    shape = std::make_unique<btBvhTriangleMeshShape>(array.get(), true, true);
    shape->setMargin(0);
    object.setCollisionShape(shape.get());
    object.getWorldTransform().setIdentity();
  }

  /// The GImpact shape over the same arrays, margin 0 (GImpact's default is 0.01).
  btGImpactMeshShape& gimpactShape() {
    if (!gimpact) {
      gimpact = std::make_unique<btGImpactMeshShape>(array.get());
      gimpact->setMargin(0);
      gimpact->updateBound();
    }
    return *gimpact;
  }

  /// Length of a ray from o that certainly passes every point of the mesh: twice the distance
  /// to the farthest corner of the bounds (1 when the mesh is the single point o).
  double rayLength(const Vec3d& o) const {
    double far2 = 0;
    for (int k = 0; k < 8; ++k) {
      const Vec3d c((k & 1) ? boundsMax.x() : boundsMin.x(), (k & 2) ? boundsMax.y() : boundsMin.y(),
                    (k & 4) ? boundsMax.z() : boundsMin.z());
      far2 = std::max(far2, (c - o).squaredNorm());
    }
    return far2 > 0 ? 2 * std::sqrt(far2) : 1.0;
  }
};

std::unique_ptr<BulletMesh> oneTriangleMesh(const Triangle& t) {
  return std::make_unique<BulletMesh>(std::vector<Vec3>{t.a, t.b, t.c}, std::vector<TriangleIndices>{{0, 1, 2}});
}

/// Records the smallest contact distance contactPairTest reports (Bullet also reports
/// separated closest points within its contact threshold: those have distance > 0).
struct MinDistance : btCollisionWorld::ContactResultCallback {
  btScalar minDistance = BT_LARGE_FLOAT;
  bool reported = false;
  btScalar addSingleResult(btManifoldPoint& cp, const btCollisionObjectWrapper*, int, int, const btCollisionObjectWrapper*,
                           int, int) override {
    reported = true;
    minDistance = std::min(minDistance, cp.getDistance());
    return 0;
  }
  bool touching() const { return reported && minDistance <= 0; }
};

/// Feeds Bullet's ray hits to a RayHitCollector. Closest: returns the hit's fraction so Bullet
/// only looks for nearer ones; Any: returns 0 after the first hit; All: keeps the full segment.
struct CollectingRay : btCollisionWorld::RayResultCallback {
  CollectingRay(const Vec3d& origin, const Vec3d& unitDir, double length, RayHitCollector* hits)
      : origin(origin), dir(unitDir), length(length), hits(hits) {}

  btScalar addSingleResult(btCollisionWorld::LocalRayResult& r, bool) override {
    // The mesh object sits at the identity, so local normals are world normals.
    anyHit = true;
    if (hits) {
      WorldRayHit hit;
      hit.t = double(r.m_hitFraction) * length;
      hit.point = origin + hit.t * dir;
      const Vec3d n = toD(r.m_hitNormalLocal);
      hit.normal = n.norm() > 0 ? Vec3d(n / n.norm()) : Vec3d(-dir);
      hit.triangle = r.m_localShapeInfo ? std::uint32_t(r.m_localShapeInfo->m_triangleIndex) : 0;
      hits->add(hit);
      if (hits->mode() == RayCollect::Closest) m_closestHitFraction = r.m_hitFraction;
      if (hits->mode() == RayCollect::Any) m_closestHitFraction = 0;
    } else {
      m_closestHitFraction = 0;  // a yes/no question: stop at the first hit
    }
    return m_closestHitFraction;
  }

  Vec3d origin, dir;
  double length;
  RayHitCollector* hits;
  bool anyHit = false;
};

class BulletWorld final : public CollisionWorld {
 public:
  BulletWorld() {
    btGImpactCollisionAlgorithm::registerAlgorithm(&dispatcher_);
    query_.getWorldTransform().setIdentity();
  }
  ~BulletWorld() override { query_.setCollisionShape(nullptr); }

  std::string_view backend() const override { return "bullet"; }
  std::string description() const override {
    const int v = btGetVersion();
    return "Bullet " + std::to_string(v / 100) + "." + std::to_string(v % 100) +
           " (btBvhTriangleMeshShape, GImpact, margins 0), " + (sizeof(btScalar) == sizeof(double) ? "double" : "float");
  }
  bool supports(WorldOp op) const override {
    if (op == WorldOp::MeshPlane) return false;
    return op <= WorldOp::MeshMesh;
  }
  WorldTolerance tolerance() const override { return kBulletTolerance; }

 protected:
  void onMeshAdded(MeshHandle h, const Mesh& mesh) override {
    meshes_[h.index] = std::make_unique<BulletMesh>(mesh.vertices(), mesh.triangles());
  }
  void onMeshRemoved(MeshHandle h) override { meshes_.erase(h.index); }

  Vec3d doClosestPoint(const Triangle& t, const Vec3& p) override {
    btVoronoiSimplexSolver solver;
    btSubSimplexClosestResult result;
    result.reset();
    solver.closestPtPointTriangle(toBt(p), toBt(t.a), toBt(t.b), toBt(t.c), result);
    return toD(result.m_closestPointOnSimplex);
  }
  bool doOverlaps(const Triangle& t, const Sphere& s) override { return meshSphere(*oneTriangleMesh(t), s); }
  bool doOverlaps(const Triangle& t, const Aabb& b) override { return meshAabb(*oneTriangleMesh(t), b); }
  bool doOverlaps(const Triangle& t, const Obb& b) override { return meshObb(*oneTriangleMesh(t), b); }
  bool doOverlaps(const Triangle& t, const Plane& p) override {
    btTriangleShape tri(toBt(t.a), toBt(t.b), toBt(t.c));
    tri.setMargin(0);
    const Vec3d n = p.normal.cast<double>();
    const double len = n.norm();
    const btVector3 unit = toBt(Vec3d(n / len));
    const btScalar d = btScalar(double(p.d) / len);
    btStaticPlaneShape below(unit, d), above(-unit, -d);
    return convexTouches(tri, btTransform::getIdentity(), below) &&
           convexTouches(tri, btTransform::getIdentity(), above);
  }
  bool doOverlaps(const Triangle& a, const Triangle& b) override { return meshTriangle(*oneTriangleMesh(b), a); }
  std::optional<WorldRayHit> doRaycast(const Ray& r, const Triangle& t) override {
    RayHitCollector hits(RayCollect::Closest);
    castRay(*oneTriangleMesh(t), r, hits, RayQueryOptions{});
    return hits.hit();
  }
  bool doIntersects(const Segment& s, const Triangle& t) override { return segmentHits(*oneTriangleMesh(t), s); }

  void doRaycast(MeshHandle m, const Ray& r, RayHitCollector& hits, const RayQueryOptions& options) override {
    castRay(mesh(m), r, hits, options);
  }
  bool doIntersects(MeshHandle m, const Segment& s) override { return segmentHits(mesh(m), s); }
  bool doOverlaps(MeshHandle m, const Sphere& s) override { return meshSphere(mesh(m), s); }
  bool doOverlaps(MeshHandle m, const Aabb& b) override { return meshAabb(mesh(m), b); }
  bool doOverlaps(MeshHandle m, const Obb& b) override { return meshObb(mesh(m), b); }
  bool doOverlaps(MeshHandle m, const Triangle& t) override { return meshTriangle(mesh(m), t); }
  bool doOverlaps(MeshHandle a, const Transform& ta, MeshHandle b, const Transform& tb) override {
    btCollisionObject oa, ob;
    oa.setCollisionShape(&mesh(a).gimpactShape());
    ob.setCollisionShape(&mesh(b).gimpactShape());
    oa.setWorldTransform(toBt(ta));
    ob.setWorldTransform(toBt(tb));
    world_.addCollisionObject(&oa);
    world_.addCollisionObject(&ob);
    bool touching = false;
    try {
      world_.performDiscreteCollisionDetection();
      for (int i = 0; i < dispatcher_.getNumManifolds() && !touching; ++i) {
        const btPersistentManifold* manifold = dispatcher_.getManifoldByIndexInternal(i);
        for (int j = 0; j < manifold->getNumContacts(); ++j)
          if (manifold->getContactPoint(j).getDistance() <= 0) touching = true;
      }
    } catch (...) {
      world_.removeCollisionObject(&ob);
      world_.removeCollisionObject(&oa);
      throw;
    }
    world_.removeCollisionObject(&ob);
    world_.removeCollisionObject(&oa);
    return touching;
  }

 private:
  BulletMesh& mesh(MeshHandle h) const { return *meshes_.at(h.index); }

  /// contactPairTest of a convex shape at `pose` against an object.
  bool touches(btCollisionShape& shape, const btTransform& pose, btCollisionObject& other) {
    query_.setCollisionShape(&shape);
    query_.setWorldTransform(pose);
    MinDistance cb;
    world_.contactPairTest(&query_, &other, cb);
    query_.setCollisionShape(nullptr);
    return cb.touching();
  }
  bool convexTouches(btCollisionShape& a, const btTransform& pose, btCollisionShape& b) {
    btCollisionObject other;
    other.setCollisionShape(&b);
    other.getWorldTransform().setIdentity();
    return touches(a, pose, other);
  }

  bool meshSphere(BulletMesh& m, const Sphere& s) {
    btSphereShape sphere(btScalar(s.radius));  // the whole sphere is its margin
    return touches(sphere, btTransform(btQuaternion::getIdentity(), toBt(s.center)), m.object);
  }
  bool meshAabb(BulletMesh& m, const Aabb& b) {
    btBoxShape box(toBt(b.half()));
    box.setMargin(0);  // keeps the full half extents
    return touches(box, btTransform(btQuaternion::getIdentity(), toBt(b.center())), m.object);
  }
  bool meshObb(BulletMesh& m, const Obb& b) {
    btBoxShape box(toBt(b.half));
    box.setMargin(0);
    // btMatrix3x3 takes rows; column i is box axis i. Left-handed axes (the same box) get their
    // third axis negated: Bullet's transforms are meant to be rotations.
    Mat3 a = b.axes;
    if (a.cast<double>().determinant() < 0) a.col(2) = -a.col(2);
    const btMatrix3x3 basis(btScalar(a(0, 0)), btScalar(a(0, 1)), btScalar(a(0, 2)), btScalar(a(1, 0)),
                            btScalar(a(1, 1)), btScalar(a(1, 2)), btScalar(a(2, 0)), btScalar(a(2, 1)),
                            btScalar(a(2, 2)));
    return touches(box, btTransform(basis, toBt(b.center)), m.object);
  }
  bool meshTriangle(BulletMesh& m, const Triangle& t) {
    btTriangleShape tri(toBt(t.a), toBt(t.b), toBt(t.c));
    tri.setMargin(0);
    return touches(tri, btTransform::getIdentity(), m.object);
  }

  /// rayTestSingle from the origin over min(maxDistance, a length past the mesh).
  void castRay(BulletMesh& m, const Ray& r, RayHitCollector& hits, const RayQueryOptions& options) {
    const Vec3d o = r.origin.cast<double>();
    const Vec3d u = r.dir.cast<double>().normalized();
    const double length = std::min(double(options.maxDistance), m.rayLength(o));
    const btVector3 from = toBt(o), to = toBt(Vec3d(o + length * u));
    CollectingRay cb(o, u, toD(to - from).norm(), &hits);
    if (options.cullBackFaces) cb.m_flags |= btTriangleRaycastCallback::kF_FilterBackfaces;
    rayTest(m, from, to, cb);
  }
  bool segmentHits(BulletMesh& m, const Segment& s) {
    const btVector3 from = toBt(s.start), to = toBt(s.end);
    CollectingRay cb(Vec3d::Zero(), Vec3d::Zero(), 0, nullptr);
    rayTest(m, from, to, cb);
    return cb.anyHit;
  }
  static void rayTest(BulletMesh& m, const btVector3& from, const btVector3& to, CollectingRay& cb) {
    const btTransform a(btQuaternion::getIdentity(), from), b(btQuaternion::getIdentity(), to);
    btCollisionWorld::rayTestSingle(a, b, &m.object, m.shape.get(), m.object.getWorldTransform(), cb);
  }

  btDefaultCollisionConfiguration configuration_;
  btCollisionDispatcher dispatcher_{&configuration_};
  btDbvtBroadphase broadphase_;
  btCollisionWorld world_{&dispatcher_, &broadphase_, &configuration_};
  btCollisionObject query_;
  std::map<std::uint32_t, std::unique_ptr<BulletMesh>> meshes_;
};

}  // namespace

std::unique_ptr<CollisionWorld> makeBulletWorld() { return std::make_unique<BulletWorld>(); }

}  // namespace crux::bullet_oracle
