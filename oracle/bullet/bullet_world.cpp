/// @file bullet_world.cpp  The "bullet" backend (see bullet_world.hpp): crux shapes converted to
/// Bullet collision shapes with zero margins, every answer straight from Bullet's collision
/// module.

#include "bullet/bullet_world.hpp"

#include "common/model_table.hpp"

#include <btBulletCollisionCommon.h>
#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <BulletCollision/NarrowPhaseCollision/btRaycastCallback.h>
#include <BulletCollision/NarrowPhaseCollision/btVoronoiSimplexSolver.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
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

  double rayLength(const Vec3d& o) const;
};

/// Length of a ray from o that certainly passes every point of the box [lo, hi]: twice the
/// distance to its farthest corner (1 when the box is the single point o).
double rayLength(const Vec3d& o, const Vec3d& lo, const Vec3d& hi) {
  double far2 = 0;
  for (int k = 0; k < 8; ++k) {
    const Vec3d c((k & 1) ? hi.x() : lo.x(), (k & 2) ? hi.y() : lo.y(), (k & 4) ? hi.z() : lo.z());
    far2 = std::max(far2, (c - o).squaredNorm());
  }
  return far2 > 0 ? 2 * std::sqrt(far2) : 1.0;
}

/// Length of a ray from o that certainly passes every point of the mesh (at the identity).
double BulletMesh::rayLength(const Vec3d& o) const { return bullet_oracle::rayLength(o, boundsMin, boundsMax); }

/// An object's world AABB as its shape computes it (btCollisionShape::getAabb at the object's
/// pose: the local box under |R|, plus the shape's margin, here 0), in double.
std::pair<Vec3d, Vec3d> worldAabb(const btCollisionObject& o) {
  btVector3 lo, hi;
  o.getCollisionShape()->getAabb(o.getWorldTransform(), lo, hi);
  return {toD(lo), toD(hi)};
}

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

/// Collects every point contactPairTest(objectA, objectB) reports, in crux's convention: A and B as
/// passed (Bullet may hand the pair over swapped), normal from B to A (Bullet's normal on B points
/// towards A: ptA = ptB + distance·normalOnB), depth = −distance; the triangle index for a mesh
/// object (index0/index1 of the wrapper that is the mesh).
struct ContactCollector : btCollisionWorld::ContactResultCallback {
  const btCollisionObject* objectA = nullptr;
  bool aIsMesh = false, bIsMesh = false;
  std::vector<WorldContact> contacts;
  btScalar addSingleResult(btManifoldPoint& cp, const btCollisionObjectWrapper* w0, int, int index0,
                           const btCollisionObjectWrapper*, int, int index1) override {
    const bool swapped = w0->getCollisionObject() != objectA;
    WorldContact c;
    const Vec3d p0 = toD(cp.getPositionWorldOnA()), p1 = toD(cp.getPositionWorldOnB());
    const Vec3d n = toD(cp.m_normalWorldOnB);
    c.pointA = swapped ? p1 : p0;
    c.pointB = swapped ? p0 : p1;
    c.normal = swapped ? Vec3d(-n) : n;
    c.depth = -double(cp.getDistance());
    const int indexA = swapped ? index1 : index0, indexB = swapped ? index0 : index1;
    if (aIsMesh && indexA >= 0) c.featureA = std::uint32_t(indexA);
    if (bIsMesh && indexB >= 0) c.featureB = std::uint32_t(indexB);
    contacts.push_back(c);
    return 0;
  }
};

/// A convex operand as a Bullet shape (margins 0; the sphere and capsule are all margin, i.e.
/// exact) and the pose placing it in the operand's frame.
struct BulletConvex {
  std::unique_ptr<btCollisionShape> shape;
  btTransform local = btTransform::getIdentity();
};

BulletConvex bulletConvex(const OperandShape& s) {
  BulletConvex out;
  if (const auto* sphere = std::get_if<Sphere>(&s)) {
    out.shape = std::make_unique<btSphereShape>(btScalar(sphere->radius));
    out.local.setOrigin(toBt(sphere->center));
  } else if (const auto* b = std::get_if<Obb>(&s)) {
    auto box = std::make_unique<btBoxShape>(toBt(b->half));
    box->setMargin(0);
    Mat3 a = b->axes;
    if (a.cast<double>().determinant() < 0) a.col(2) = -a.col(2);  // the same box, as a rotation
    out.local.setBasis(btMatrix3x3(btScalar(a(0, 0)), btScalar(a(0, 1)), btScalar(a(0, 2)), btScalar(a(1, 0)),
                                   btScalar(a(1, 1)), btScalar(a(1, 2)), btScalar(a(2, 0)), btScalar(a(2, 1)),
                                   btScalar(a(2, 2))));
    out.local.setOrigin(toBt(b->center));
    out.shape = std::move(box);
  } else if (const auto* c = std::get_if<Capsule>(&s)) {
    // btCapsuleShape: along its local y, centred, `height` between the sphere centres.
    const Vec3d a = c->a.cast<double>(), b2 = c->b.cast<double>(), axis = b2 - a;
    out.shape = std::make_unique<btCapsuleShape>(btScalar(c->radius), btScalar(axis.norm()));
    if (axis.norm() > 0) {
      const Eigen::Quaterniond q = Eigen::Quaterniond::FromTwoVectors(Vec3d::UnitY(), axis);
      out.local.setRotation(btQuaternion(btScalar(q.x()), btScalar(q.y()), btScalar(q.z()), btScalar(q.w())));
    }
    out.local.setOrigin(toBt(Vec3d(0.5 * (a + b2))));
  } else if (const auto* t = std::get_if<Triangle>(&s)) {
    auto tri = std::make_unique<btTriangleShape>(toBt(t->a), toBt(t->b), toBt(t->c));
    tri->setMargin(0);
    out.shape = std::move(tri);
  } else {
    auto hull = std::make_unique<btConvexHullShape>();
    for (const Vec3& v : std::get<ConvexHull>(s).vertices()) hull->addPoint(toBt(v), false);
    hull->recalcLocalAabb();
    hull->setMargin(0);
    out.shape = std::move(hull);
  }
  return out;
}

/// Feeds Bullet's ray hits to a RayHitCollector. Closest: returns the hit's fraction so Bullet
/// only looks for nearer ones; Any: returns 0 after the first hit; All: keeps the full segment.
struct CollectingRay : btCollisionWorld::RayResultCallback {
  CollectingRay(const Vec3d& origin, const Vec3d& unitDir, double length, RayHitCollector* hits)
      : origin(origin), dir(unitDir), length(length), hits(hits) {}

  btScalar addSingleResult(btCollisionWorld::LocalRayResult& r, bool normalInWorldSpace) override {
    anyHit = true;
    if (hits) {
      WorldRayHit hit;
      hit.t = double(r.m_hitFraction) * length;
      hit.point = origin + hit.t * dir;
      // Bullet's concave-shape ray test hands the normal over in world space already (mesh
      // objects sit at the identity, models at their world pose); rotate it otherwise.
      const btVector3 nb = normalInWorldSpace ? r.m_hitNormalLocal
                                              : r.m_collisionObject->getWorldTransform().getBasis() * r.m_hitNormalLocal;
      const Vec3d n = toD(nb);
      hit.normal = n.norm() > 0 ? Vec3d(n / n.norm()) : Vec3d(-dir);
      hit.triangle = r.m_localShapeInfo ? std::uint32_t(r.m_localShapeInfo->m_triangleIndex) : 0;
      if (r.m_collisionObject && r.m_collisionObject->getUserIndex() >= 0)
        hit.model = ModelHandle{std::uint32_t(r.m_collisionObject->getUserIndex())};
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

/// Keeps the nearest hit of a convex sweep (Closest: returns its fraction, so Bullet only looks
/// for nearer ones; Any: returns 0 after the first). The point is on the hit object (Bullet
/// hands it over in world space), the normal from the hit object towards the cast shape.
struct NearestSweep : btCollisionWorld::ConvexResultCallback {
  explicit NearestSweep(CastFind find) : find(find) {}

  btScalar addSingleResult(btCollisionWorld::LocalConvexResult& r, bool normalInWorldSpace) override {
    hit = true;
    fraction = r.m_hitFraction;
    normal = normalInWorldSpace ? r.m_hitNormalLocal
                                : r.m_hitCollisionObject->getWorldTransform().getBasis() * r.m_hitNormalLocal;
    point = r.m_hitPointLocal;
    triangle = r.m_localShapeInfo ? std::optional<std::uint32_t>(std::uint32_t(r.m_localShapeInfo->m_triangleIndex))
                                  : std::nullopt;
    user = r.m_hitCollisionObject->getUserIndex();
    m_closestHitFraction = find == CastFind::Any ? btScalar(0) : r.m_hitFraction;
    return m_closestHitFraction;
  }

  CastFind find;
  bool hit = false;
  btScalar fraction = 1;
  btVector3 normal{0, 0, 1}, point{0, 0, 0};
  std::optional<std::uint32_t> triangle;
  int user = -1;
};

/// A btCollisionWorld with its own dispatcher (GImpact's algorithms registered) and a
/// btDbvtBroadphase, over a collision configuration (algorithm factories and memory pools)
/// shared by the world's spaces: building a btDefaultCollisionConfiguration fills pools of a
/// few MB, which dominated creating a world when each space had its own.
struct CollisionSpace {
  btCollisionDispatcher dispatcher;
  btDbvtBroadphase broadphase;
  btCollisionWorld world;
  explicit CollisionSpace(btCollisionConfiguration& configuration)
      : dispatcher(&configuration), world(&dispatcher, &broadphase, &configuration) {
    btGImpactCollisionAlgorithm::registerAlgorithm(&dispatcher);
  }
};

/// A model in Bullet: two btCollisionObjects at the model's world pose over its mesh's shared
/// shapes (the model keeps the BulletMesh alive if the mesh is removed later). `object` holds
/// the btBvhTriangleMeshShape and lives in the scene world (rays, contact tests against
/// convex query shapes: the same Bullet paths as the mesh ops); `pairObject` holds the
/// btGImpactMeshShape and lives in the pairs world, since Bullet has no algorithm for two
/// btBvhTriangleMeshShapes. Both carry the model handle as user index.
struct BulletModel {
  std::shared_ptr<BulletMesh> mesh;
  btCollisionObject object;
  btCollisionObject pairObject;
};

/// Smallest contact distance per object of a contactTest (the query touches an object when
/// one of its contacts has distance <= 0, as for contactPairTest).
struct PerObjectDistance : btCollisionWorld::ContactResultCallback {
  std::map<int, btScalar> minDistance;  ///< by user index (model handle)
  btScalar addSingleResult(btManifoldPoint& cp, const btCollisionObjectWrapper* a, int, int,
                           const btCollisionObjectWrapper* b, int, int) override {
    for (const btCollisionObjectWrapper* w : {a, b}) {
      const int id = w->getCollisionObject()->getUserIndex();
      if (id < 0) continue;  // the query object
      auto [it, fresh] = minDistance.emplace(id, cp.getDistance());
      if (!fresh) it->second = std::min(it->second, cp.getDistance());
    }
    return 0;
  }
};

/// The objects whose broad-phase proxies overlap a box (btDbvtBroadphase::aabbTest).
struct ProxyCollector : btBroadphaseAabbCallback {
  std::vector<const btCollisionObject*> objects;
  bool process(const btBroadphaseProxy* proxy) override {
    objects.push_back(static_cast<const btCollisionObject*>(proxy->m_clientObject));
    return true;
  }
};

class BulletWorld final : public CollisionWorld {
 public:
  BulletWorld() { query_.getWorldTransform().setIdentity(); }
  ~BulletWorld() override {
    query_.setCollisionShape(nullptr);
    // btCollisionWorld's destructor walks its objects: take the models out first.
    for (auto& [id, m] : models_) {
      scene_.world.removeCollisionObject(&m->object);
      pairs_.world.removeCollisionObject(&m->pairObject);
    }
  }

  std::string_view backend() const override { return "bullet"; }
  std::string description() const override {
    const int v = btGetVersion();
    return "Bullet " + std::to_string(v / 100) + "." + std::to_string(v % 100) +
           " (btBvhTriangleMeshShape, GImpact, margins 0), " + (sizeof(btScalar) == sizeof(double) ? "double" : "float");
  }
  bool supports(WorldOp op) const override {
    // No Bullet algorithm for a static plane against a static mesh: mesh_plane, model_plane.
    // Of the narrow-phase ops only contacts (contactPairTest): Bullet has no
    // closed-volume mode, and its distances are convex-only (btGjkPairDetector). Casts: its
    // convex sweeps (linear and rigid).
    if (op == WorldOp::Contacts || op == WorldOp::Cast || op == WorldOp::ModelCast || op == WorldOp::SceneCast)
      return true;
    return isContractOp(op) && op != WorldOp::MeshPlane && op != WorldOp::ModelPlane;
  }
  WorldTolerance tolerance() const override { return kBulletTolerance; }

 protected:
  void onMeshAdded(MeshHandle h, const Mesh& mesh) override {
    meshes_[h.index] = std::make_shared<BulletMesh>(mesh.vertices(), mesh.triangles());
  }
  void onMeshRemoved(MeshHandle h) override { meshes_.erase(h.index); }

  Vec3d doClosestPoint(const Triangle& t, const Vec3& p) override {
    btVoronoiSimplexSolver solver;
    btSubSimplexClosestResult result;
    result.reset();
    solver.closestPtPointTriangle(toBt(p), toBt(t.a), toBt(t.b), toBt(t.c), result);
    return toD(result.m_closestPointOnSimplex);
  }
  bool doOverlaps(const Triangle& t, const Sphere& s) override { return shapeTouches(s, oneTriangleMesh(t)->object); }
  bool doOverlaps(const Triangle& t, const Aabb& b) override { return shapeTouches(b, oneTriangleMesh(t)->object); }
  bool doOverlaps(const Triangle& t, const Obb& b) override { return shapeTouches(b, oneTriangleMesh(t)->object); }
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
  bool doOverlaps(MeshHandle m, const Sphere& s) override { return shapeTouches(s, mesh(m).object); }
  bool doOverlaps(MeshHandle m, const Aabb& b) override { return shapeTouches(b, mesh(m).object); }
  bool doOverlaps(MeshHandle m, const Obb& b) override { return shapeTouches(b, mesh(m).object); }
  bool doOverlaps(MeshHandle m, const Triangle& t) override { return meshTriangle(mesh(m), t); }
  bool doOverlaps(MeshHandle a, const Transform& ta, MeshHandle b, const Transform& tb) override {
    btCollisionObject oa, ob;
    oa.setCollisionShape(&mesh(a).gimpactShape());
    ob.setCollisionShape(&mesh(b).gimpactShape());
    oa.setWorldTransform(toBt(ta));
    ob.setWorldTransform(toBt(tb));
    meshMesh_.world.addCollisionObject(&oa);
    meshMesh_.world.addCollisionObject(&ob);
    bool touching = false;
    try {
      meshMesh_.world.performDiscreteCollisionDetection();
      for (int i = 0; i < meshMesh_.dispatcher.getNumManifolds() && !touching; ++i) {
        const btPersistentManifold* manifold = meshMesh_.dispatcher.getManifoldByIndexInternal(i);
        for (int j = 0; j < manifold->getNumContacts(); ++j)
          if (manifold->getContactPoint(j).getDistance() <= 0) touching = true;
      }
    } catch (...) {
      meshMesh_.world.removeCollisionObject(&ob);
      meshMesh_.world.removeCollisionObject(&oa);
      throw;
    }
    meshMesh_.world.removeCollisionObject(&ob);
    meshMesh_.world.removeCollisionObject(&oa);
    return touching;
  }

  // ---- models and the scene ----------------------------------------------------------------

  ModelHandle doAddModel(const std::string& name, MeshHandle mesh, const Transform& local,
                         std::optional<ModelHandle> parent) override {
    const ModelHandle h = table_.add(name, mesh, sharedMesh(mesh), local, parent);
    try {
      auto m = std::make_unique<BulletModel>();
      m->mesh = meshes_.at(mesh.index);
      m->object.setCollisionShape(m->mesh->shape.get());
      m->pairObject.setCollisionShape(&m->mesh->gimpactShape());
      m->object.setUserIndex(int(h.index));
      m->pairObject.setUserIndex(int(h.index));
      const btTransform pose = toBt(table_.world(h));
      m->object.setWorldTransform(pose);
      m->pairObject.setWorldTransform(pose);
      scene_.world.addCollisionObject(&m->object);
      pairs_.world.addCollisionObject(&m->pairObject);
      models_[h.index] = std::move(m);
    } catch (...) {
      table_.remove(h);
      throw;
    }
    return h;
  }
  void doRemoveModel(ModelHandle h) override {
    BulletModel& m = model(h);
    table_.remove(h);  // the children keep their world poses
    scene_.world.removeCollisionObject(&m.object);
    pairs_.world.removeCollisionObject(&m.pairObject);
    models_.erase(h.index);
  }
  void doSetTransform(ModelHandle h, const Transform& local) override { place(table_.setLocal(h, local)); }
  void doSetParent(ModelHandle h, std::optional<ModelHandle> parent) override {
    table_.setParent(h, parent);
    // World poses are kept; placing the subtree again keeps Bullet in step with the table.
    std::vector<ModelHandle> subtree = table_.descendants(h);
    subtree.push_back(h);
    place(subtree);
  }
  std::optional<ModelHandle> doFindModel(std::string_view name) override { return table_.find(name); }
  std::vector<std::string> doDescendants(ModelHandle h) override { return table_.descendantNames(h); }

  void doRaycast(ModelHandle h, const Ray& r, RayHitCollector& hits, const RayQueryOptions& options) override {
    btCollisionObject& o = model(h).object;
    const auto [lo, hi] = worldAabb(o);
    castRayWith(lo, hi, r, hits, options, [&](const btVector3& from, const btVector3& to, CollectingRay& cb) {
      rayTestObject(o, from, to, cb);
    });
  }
  bool doIntersects(ModelHandle h, const Segment& s) override {
    btCollisionObject& o = model(h).object;
    CollectingRay cb(Vec3d::Zero(), Vec3d::Zero(), 0, nullptr);
    rayTestObject(o, toBt(s.start), toBt(s.end), cb);
    return cb.anyHit;
  }
  bool doOverlaps(ModelHandle h, const Sphere& s) override { return shapeTouches(s, model(h).object); }
  bool doOverlaps(ModelHandle h, const Aabb& b) override { return shapeTouches(b, model(h).object); }
  bool doOverlaps(ModelHandle h, const Obb& b) override { return shapeTouches(b, model(h).object); }
  bool doOverlaps(ModelHandle h, const Triangle& t) override { return triangleTouches(model(h).object, t); }

  /// scene_ray: btCollisionWorld::rayTest over the scene world (broad phase: the Dbvt's ray
  /// walk) to a point past every model's bounds.
  void doSceneRaycast(const Ray& r, RayHitCollector& hits, const RayQueryOptions& options) override {
    if (models_.empty()) return;
    Vec3d lo = Vec3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (const auto& [id, m] : models_) {
      const auto [a, b] = worldAabb(m->object);
      lo = lo.cwiseMin(a);
      hi = hi.cwiseMax(b);
    }
    castRayWith(lo, hi, r, hits, options, [&](const btVector3& from, const btVector3& to, CollectingRay& cb) {
      scene_.world.rayTest(from, to, cb);
    });
  }
  /// scene_query: contactTest of the query shape against the scene world (its Dbvt finds the
  /// candidates); a model is found when one of its contacts has distance <= 0. boundsOnly: the
  /// Dbvt's candidates (aabbTest with the shape's box), each kept when the shape touches the
  /// model's own AABB (btCollisionShape::getAabb at its pose, without the broad phase's
  /// contact-threshold padding) as a btBoxShape, by contactPairTest.
  std::vector<std::string> doSceneQuery(const SceneQueryShape& shape, bool boundsOnly) override {
    std::vector<std::string> names;
    std::visit(
        [&](const auto& s) {
          withShape(s, [&](btCollisionShape& query, const btTransform& pose) {
            if (boundsOnly) {
              btVector3 qlo, qhi;
              query.getAabb(pose, qlo, qhi);
              ProxyCollector candidates;
              scene_.world.getBroadphase()->aabbTest(qlo, qhi, candidates);
              for (const btCollisionObject* o : candidates.objects) {
                const auto [lo, hi] = worldAabb(*o);
                btBoxShape box(toBt(Vec3d(0.5 * (hi - lo))));
                box.setMargin(0);
                btCollisionObject boxObject;
                boxObject.setCollisionShape(&box);
                boxObject.setWorldTransform(btTransform(btQuaternion::getIdentity(), toBt(Vec3d(0.5 * (lo + hi)))));
                if (touches(query, pose, boxObject)) names.push_back(table_.name(ModelHandle{std::uint32_t(o->getUserIndex())}));
              }
              return false;
            }
            query_.setCollisionShape(&query);
            query_.setWorldTransform(pose);
            PerObjectDistance cb;
            scene_.world.contactTest(&query_, cb);
            query_.setCollisionShape(nullptr);
            for (const auto& [id, d] : cb.minDistance)
              if (d <= 0) names.push_back(table_.name(ModelHandle{std::uint32_t(id)}));
            return false;
          });
        },
        shape);
    std::sort(names.begin(), names.end());
    names.erase(std::unique(names.begin(), names.end()), names.end());
    return names;
  }
  /// scene_pairs: performDiscreteCollisionDetection on the pairs world (GImpact objects, Dbvt
  /// broad phase); a pair counts when its manifolds hold a contact of distance <= 0 (as
  /// mesh_mesh does). GImpact clears a pair's manifold at every pass, so no stale contact is read.
  std::vector<std::pair<std::string, std::string>> doScenePairs() override {
    pairs_.world.performDiscreteCollisionDetection();
    std::set<std::pair<std::string, std::string>> found;
    for (int i = 0; i < pairs_.dispatcher.getNumManifolds(); ++i) {
      const btPersistentManifold* manifold = pairs_.dispatcher.getManifoldByIndexInternal(i);
      bool touching = false;
      for (int j = 0; j < manifold->getNumContacts() && !touching; ++j)
        touching = manifold->getContactPoint(j).getDistance() <= 0;
      if (!touching) continue;
      const int a = manifold->getBody0()->getUserIndex(), b = manifold->getBody1()->getUserIndex();
      if (a < 0 || b < 0 || a == b) continue;
      std::string na = table_.name(ModelHandle{std::uint32_t(a)}), nb = table_.name(ModelHandle{std::uint32_t(b)});
      if (nb < na) std::swap(na, nb);
      found.emplace(std::move(na), std::move(nb));
    }
    return {found.begin(), found.end()};
  }

  /// contacts: btCollisionWorld::contactPairTest of the two operands' objects (a mesh: its
  /// btBvhTriangleMeshShape, margin 0, at the operand's pose), every reported point with
  /// distance <= margin (m_closestDistanceThreshold = margin asks Bullet for the speculative
  /// ones). Bullet does not reduce: a convex shape across several triangles gets a point per
  /// triangle (crux keeps at most 4).
  std::vector<WorldContact> doContacts(const WorldOperand& a, const WorldOperand& b, double margin) override {
    BulletConvex ca, cb;
    btCollisionObject oa, ob;
    place(a, ca, oa);
    place(b, cb, ob);
    ContactCollector collector;
    collector.objectA = &oa;
    collector.aIsMesh = a.isMesh();
    collector.bIsMesh = b.isMesh();
    collector.m_closestDistanceThreshold = btScalar(margin);
    meshMesh_.world.contactPairTest(&oa, &ob, collector);
    std::vector<WorldContact> out;
    for (const WorldContact& c : collector.contacts)
      if (-c.depth <= margin) out.push_back(c);
    return out;
  }

  /// cast: btCollisionWorld::objectQuerySingle (convexSweepTest's per-object step:
  /// btContinuousConvexCollision for a convex b, btTriangleConvexcastCallback over the BVH for a
  /// mesh) from a's pose to its pose at t = 1, allowed penetration 0.
  WorldCast doCast(const WorldOperand& a, const WorldMotion& motion, const WorldOperand& b, CastFind find) override {
    BulletConvex cb;
    btCollisionObject ob;
    place(b, cb, ob);
    return sweepObject(a, motion, find, ob);
  }
  WorldCast doModelCast(const WorldOperand& a, const WorldMotion& motion, ModelHandle h, CastFind find) override {
    WorldCast w = sweepObject(a, motion, find, model(h).object);
    w.model = ModelHandle{};  // a model cast names no model (the caller gave it)
    return w;
  }
  /// scene_cast: btCollisionWorld::convexSweepTest over the scene world (its Dbvt culls by the
  /// swept box).
  WorldCast doSceneCast(const WorldOperand& a, const WorldMotion& motion, CastFind find) override {
    return sweep(a, motion, find, [&](const btConvexShape& shape, const btTransform& from, const btTransform& to,
                                      NearestSweep& result) { scene_.world.convexSweepTest(&shape, from, to, result, 0); });
  }

 private:
  BulletMesh& mesh(MeshHandle h) const { return *meshes_.at(h.index); }
  /// A model's objects; InvalidInput naming the field for an unknown handle.
  BulletModel& model(ModelHandle h) const {
    if (!table_.contains(h)) throw InvalidInput("model: unknown model handle " + std::to_string(h.index));
    return *models_.at(h.index);
  }

  /// An operand of contacts or a cast as a Bullet object at its world pose: a mesh's
  /// btBvhTriangleMeshShape, or bulletConvex(shape) (kept alive in `convex`) placed by its local
  /// pose.
  void place(const WorldOperand& o, BulletConvex& convex, btCollisionObject& object) const {
    const btTransform pose = toBt(o.pose);
    if (const auto* m = std::get_if<MeshHandle>(&o.shape)) {
      object.setCollisionShape(mesh(*m).shape.get());
      object.setWorldTransform(pose);
    } else {
      convex = bulletConvex(o.shape);
      object.setCollisionShape(convex.shape.get());
      object.setWorldTransform(pose * convex.local);
    }
  }
  /// sweep() against one object: btCollisionWorld::objectQuerySingle, allowed penetration 0.
  WorldCast sweepObject(const WorldOperand& a, const WorldMotion& motion, CastFind find, btCollisionObject& o) {
    return sweep(a, motion, find, [&](const btConvexShape& shape, const btTransform& from, const btTransform& to,
                                      NearestSweep& result) {
      btCollisionWorld::objectQuerySingle(&shape, from, to, &o, o.getCollisionShape(), o.getWorldTransform(), result, 0);
    });
  }
  /// Casts a's shape (bulletConvex) from its pose to its pose at t = 1 with test(shape, from,
  /// to, result) and reads the nearest hit: t = Bullet's hit fraction, both points at Bullet's
  /// hit point, the model by the hit object's user index. Bullet does not report an initial
  /// overlap: a hit at fraction 0 is taken as one, with depth 0.
  template <class Test>
  WorldCast sweep(const WorldOperand& a, const WorldMotion& motion, CastFind find, Test&& test) {
    const BulletConvex ca = bulletConvex(a.shape);
    const btTransform from = toBt(a.pose) * ca.local;
    btTransform to = from;
    if (motion.end) to = toBt(*motion.end) * ca.local;
    else to.setOrigin(from.getOrigin() + toBt(motion.translation));
    NearestSweep result(find);
    test(static_cast<const btConvexShape&>(*ca.shape), from, to, result);
    WorldCast w;
    if (!result.hit) return w;
    w.hit = true;
    w.t = double(result.fraction);
    w.pointA = w.pointB = toD(result.point);
    const Vec3d n = toD(result.normal);
    if (n.norm() > 0) w.normal = n / n.norm();
    w.startsOverlapping = result.fraction == 0;
    w.triangleB = result.triangle;
    if (result.user >= 0) w.model = ModelHandle{std::uint32_t(result.user)};
    return w;
  }

  /// Moves models' objects to their world poses (table_.world) and refreshes their
  /// broad-phase boxes in both worlds.
  void place(const std::vector<ModelHandle>& moved) {
    for (const ModelHandle h : moved) {
      BulletModel& m = model(h);
      const btTransform pose = toBt(table_.world(h));
      m.object.setWorldTransform(pose);
      m.pairObject.setWorldTransform(pose);
      scene_.world.updateSingleAabb(&m.object);
      pairs_.world.updateSingleAabb(&m.pairObject);
    }
  }

  /// contactPairTest of a convex shape at `pose` against an object.
  bool touches(btCollisionShape& shape, const btTransform& pose, btCollisionObject& other) {
    query_.setCollisionShape(&shape);
    query_.setWorldTransform(pose);
    MinDistance cb;
    meshMesh_.world.contactPairTest(&query_, &other, cb);
    query_.setCollisionShape(nullptr);
    return cb.touching();
  }
  bool convexTouches(btCollisionShape& a, const btTransform& pose, btCollisionShape& b) {
    btCollisionObject other;
    other.setCollisionShape(&b);
    other.getWorldTransform().setIdentity();
    return touches(a, pose, other);
  }

  /// Calls f(shape, pose) with the query shape as Bullet sees it: a btSphereShape (all margin),
  /// or a btBoxShape with margin 0 (keeping its full half extents) at the box's centre, turned
  /// by the OBB's axes (btMatrix3x3 takes rows; column i is box axis i). Left-handed axes (the
  /// same box) get their third axis negated: Bullet's transforms are meant to be rotations.
  template <class F>
  static bool withShape(const Sphere& s, F&& f) {
    btSphereShape sphere(btScalar(s.radius));
    return f(sphere, btTransform(btQuaternion::getIdentity(), toBt(s.center)));
  }
  template <class F>
  static bool withShape(const Aabb& b, F&& f) {
    btBoxShape box(toBt(b.half()));
    box.setMargin(0);
    return f(box, btTransform(btQuaternion::getIdentity(), toBt(b.center())));
  }
  template <class F>
  static bool withShape(const Obb& b, F&& f) {
    btBoxShape box(toBt(b.half));
    box.setMargin(0);
    Mat3 a = b.axes;
    if (a.cast<double>().determinant() < 0) a.col(2) = -a.col(2);
    const btMatrix3x3 basis(btScalar(a(0, 0)), btScalar(a(0, 1)), btScalar(a(0, 2)), btScalar(a(1, 0)),
                            btScalar(a(1, 1)), btScalar(a(1, 2)), btScalar(a(2, 0)), btScalar(a(2, 1)),
                            btScalar(a(2, 2)));
    return f(box, btTransform(basis, toBt(b.center)));
  }
  /// contactPairTest of a sphere or box against an object (a mesh at the identity or a model).
  template <class Shape>
  bool shapeTouches(const Shape& s, btCollisionObject& object) {
    return withShape(s, [&](btCollisionShape& shape, const btTransform& pose) { return touches(shape, pose, object); });
  }
  bool meshTriangle(BulletMesh& m, const Triangle& t) { return triangleTouches(m.object, t); }
  bool triangleTouches(btCollisionObject& object, const Triangle& t) {
    btTriangleShape tri(toBt(t.a), toBt(t.b), toBt(t.c));
    tri.setMargin(0);
    return touches(tri, btTransform::getIdentity(), object);
  }

  /// rayTestSingle from the origin over min(maxDistance, a length past the mesh).
  void castRay(BulletMesh& m, const Ray& r, RayHitCollector& hits, const RayQueryOptions& options) {
    castRayWith(m.boundsMin, m.boundsMax, r, hits, options,
                [&](const btVector3& from, const btVector3& to, CollectingRay& cb) { rayTest(m, from, to, cb); });
  }
  /// Casts from the origin over min(maxDistance, a length past the box [lo, hi]) with
  /// test(from, to, callback): rayTestSingle on one object, or the scene world's rayTest.
  template <class Test>
  static void castRayWith(const Vec3d& lo, const Vec3d& hi, const Ray& r, RayHitCollector& hits,
                      const RayQueryOptions& options, Test&& test) {
    const Vec3d o = r.origin.cast<double>();
    const Vec3d u = r.dir.cast<double>().normalized();
    const double length = std::min(double(options.maxDistance), rayLength(o, lo, hi));
    const btVector3 from = toBt(o), to = toBt(Vec3d(o + length * u));
    CollectingRay cb(o, u, toD(to - from).norm(), &hits);
    if (options.cullBackFaces) cb.m_flags |= btTriangleRaycastCallback::kF_FilterBackfaces;
    test(from, to, cb);
  }
  bool segmentHits(BulletMesh& m, const Segment& s) {
    const btVector3 from = toBt(s.start), to = toBt(s.end);
    CollectingRay cb(Vec3d::Zero(), Vec3d::Zero(), 0, nullptr);
    rayTest(m, from, to, cb);
    return cb.anyHit;
  }
  static void rayTest(BulletMesh& m, const btVector3& from, const btVector3& to, CollectingRay& cb) {
    rayTestObject(m.object, from, to, cb);
  }
  /// btCollisionWorld::rayTestSingle on one object at its world pose.
  static void rayTestObject(btCollisionObject& o, const btVector3& from, const btVector3& to,
                            CollectingRay& cb) {
    const btTransform a(btQuaternion::getIdentity(), from), b(btQuaternion::getIdentity(), to);
    btCollisionWorld::rayTestSingle(a, b, &o, o.getCollisionShape(), o.getWorldTransform(), cb);
  }

  btDefaultCollisionConfiguration configuration_;
  CollisionSpace meshMesh_{configuration_};  ///< mesh_mesh's private world, and contactPairTest's dispatcher
  CollisionSpace scene_{configuration_};     ///< models' btBvhTriangleMeshShape objects: rays, contact tests
  CollisionSpace pairs_{configuration_};     ///< models' btGImpactMeshShape objects: scene_pairs
  btCollisionObject query_;
  std::map<std::uint32_t, std::shared_ptr<BulletMesh>> meshes_;  ///< by mesh handle
  oracle::ModelTable table_;
  std::map<std::uint32_t, std::unique_ptr<BulletModel>> models_;  ///< by model handle
};

}  // namespace

std::unique_ptr<CollisionWorld> makeBulletWorld() { return std::make_unique<BulletWorld>(); }

}  // namespace crux::bullet_oracle
