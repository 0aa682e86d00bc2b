/// @file fcl_world.cpp  The "fcl" backend (see fcl_world.hpp): crux shapes converted to FCL
/// geometry, every answer straight from fcl::collide / fcl::distance.

#include "fcl/fcl_world.hpp"

#include "common/model_table.hpp"

#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/config.h>
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/geometry/shape/convex.h>
#include <fcl/geometry/shape/plane.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/math/bv/OBBRSS.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/continuous_collision.h>
#include <fcl/narrowphase/distance.h>

#include <algorithm>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace crux::fcl_oracle {
namespace {

using Model = fcl::BVHModel<fcl::OBBRSSd>;

fcl::Vector3d toFcl(const Vec3& v) { return v.cast<double>(); }

/// Builds a BVHModel; FCL reports failures by return codes, turned into exceptions here (the
/// world's edge reports them as BackendFailure).
std::shared_ptr<Model> buildModel(const std::vector<fcl::Vector3d>& points, const std::vector<fcl::Triangle>& tris) {
  auto model = std::make_shared<Model>();
  int code = model->beginModel(int(tris.size()), int(points.size()));
  if (code == fcl::BVH_OK) code = model->addSubModel(points, tris);
  if (code == fcl::BVH_OK) code = model->endModel();
  if (code != fcl::BVH_OK) throw std::runtime_error("BVHModel construction failed with code " + std::to_string(code));
  return model;
}

std::shared_ptr<Model> buildModel(const Mesh& mesh) {
  std::vector<fcl::Vector3d> points;
  points.reserve(mesh.vertexCount());
  for (const Vec3& v : mesh.vertices()) points.push_back(toFcl(v));
  std::vector<fcl::Triangle> tris;
  tris.reserve(mesh.triangleCount());
  for (const TriangleIndices& t : mesh.triangles()) tris.emplace_back(t[0], t[1], t[2]);
  return buildModel(points, tris);
}

/// The one-triangle model standing for a triangle of a primitive op.
std::shared_ptr<Model> buildModel(const Triangle& t) {
  return buildModel({toFcl(t.a), toFcl(t.b), toFcl(t.c)}, {fcl::Triangle(0, 1, 2)});
}

fcl::Transform3d translation(const Vec3& v) {
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  tf.translation() = toFcl(v);
  return tf;
}

/// A crux transform in double; the quaternion is normalised in double (it is unit only up to
/// Real's rounding).
fcl::Transform3d toFcl(const Transform& t) {
  const Eigen::Quaterniond q = t.rotation.cast<double>().normalized();
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  tf.linear() = q.toRotationMatrix();
  tf.translation() = toFcl(t.translation);
  return tf;
}

bool collide(const fcl::CollisionGeometryd& a, const fcl::Transform3d& ta, const fcl::CollisionGeometryd& b,
             const fcl::Transform3d& tb) {
  const fcl::CollisionRequestd request(1, false);  // one contact, no contact details
  fcl::CollisionResultd result;
  fcl::collide(&a, ta, &b, tb, request, result);
  return result.isCollision();
}

/// Collides a geometry placed in the world with a shape and its placement.
struct Placed {
  const fcl::CollisionGeometryd& geometry;
  fcl::Transform3d pose;
};

bool collide(const Placed& a, const Placed& b) { return collide(a.geometry, a.pose, b.geometry, b.pose); }

/// An AABB as an unrotated fcl box at its centre.
fcl::Boxd box(const Aabb& b) { return fcl::Boxd((b.max - b.min).cast<double>()); }
/// An OBB as a rotated fcl box: the pose's rotation columns are the box axes. Left-handed axes
/// (valid in crux: the box is the same point set) get their third axis negated, since FCL
/// converts poses to quaternions (libccd) and a reflection has none.
fcl::Boxd box(const Obb& b) { return fcl::Boxd(2.0 * b.half.cast<double>()); }
fcl::Transform3d pose(const Obb& b) {
  fcl::Transform3d tf = translation(b.center);
  tf.linear() = b.axes.cast<double>();
  if (tf.linear().determinant() < 0) tf.linear().col(2) = -tf.linear().col(2);
  return tf;
}
/// The plane dot(n, x) = d itself (fcl::Plane normalises n and d together).
fcl::Planed plane(const Plane& p) { return fcl::Planed(toFcl(p.normal), double(p.d)); }

const fcl::Transform3d& identity() {
  static const fcl::Transform3d id = fcl::Transform3d::Identity();
  return id;
}

/// A contacts/distance operand as FCL geometry at its world pose (meshes: the mesh's shared
/// BVHModel).
struct FclOperand {
  std::shared_ptr<const fcl::CollisionGeometryd> geometry;
  fcl::Transform3d pose;
};

/// A crux capsule (segment a–b ⊕ ball) as an fcl::Capsule (centred, along its local z) and the
/// pose putting it in the operand's frame.
FclOperand capsuleOperand(const Vec3& a, const Vec3& b, double radius) {
  const fcl::Vector3d pa = toFcl(a), pb = toFcl(b), axis = pb - pa;
  const double length = axis.norm();
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  tf.translation() = 0.5 * (pa + pb);
  if (length > 0) tf.linear() = Eigen::Quaterniond::FromTwoVectors(fcl::Vector3d::UnitZ(), axis).toRotationMatrix();
  return {std::make_shared<fcl::Capsuled>(radius, length), tf};
}

/// A crux hull as an fcl::Convex from its polygonal faces (ConvexHull::faces: counter-clockwise
/// loops); a point or segment hull (no faces) as a zero-radius sphere or capsule.
FclOperand hullOperand(const ConvexHull& h) {
  if (h.dimension() == 0) return {std::make_shared<fcl::Sphered>(0.0), translation(h.vertices()[0])};
  if (h.dimension() == 1) return capsuleOperand(h.vertices()[0], h.vertices()[1], 0.0);
  auto vertices = std::make_shared<std::vector<fcl::Vector3d>>();
  for (const Vec3& v : h.vertices()) vertices->push_back(toFcl(v));
  auto faces = std::make_shared<std::vector<int>>();
  for (const HullFace& f : h.faces()) {
    faces->push_back(int(f.count));
    for (std::uint32_t k = 0; k < f.count; ++k) faces->push_back(int(h.faceVertices()[f.first + k]));
  }
  return {std::make_shared<fcl::Convexd>(vertices, int(h.faces().size()), faces), identity()};
}

/// GJK/EPA stopping tolerance of FCL's distance requests (DistanceRequest::distance_tolerance)
/// for overlapping (and touching) pairs: FCL's default, 1e-6, which FCL's own signed-distance
/// tests ask for (test_fcl_signed_distance: penetrating sphere–sphere, sphere–capsule,
/// cylinder–box, box–box). A tighter 1e-12 drove libccd's EPA into its assertions
/// (isOutsidePolytopeFace) and endless loops on overlapping spheres and capsules, where the
/// default answers (docs/batch.md "Backends").
constexpr double kFclPenetrationTolerance = 1e-6;
/// The same tolerance for separated pairs: 1e-12. libccd's GJK reads the tolerance as a squared
/// length, so the default leaves distances up to ~sqrt(1e-6)·size off (a tetrahedron 0.02 from
/// a sphere of radius 0.01: 6.8e-6 long, beyond the fcl world's declared 1e-6; a hull–sphere
/// distance of 2: nearest points 7e-4 off); at 1e-12 both are at rounding level, and separated
/// pairs converge.
constexpr double kFclGjkTolerance = 1e-12;

/// fcl::distance with nearest points (world coordinates) and signed distance requested, at the
/// tolerance for the pair: kFclPenetrationTolerance when fcl::collide finds them overlapping,
/// else kFclGjkTolerance. A triangle mesh (BVHModel, also a triangle operand) against an
/// overlapping convex shape throws: FCL 0.7 answers that pair with a meaningless distance (0,
/// 8e-323) and nearest points it leaves partly uninitialised (a different answer per run).
fcl::DistanceResultd signedDistance(const FclOperand& a, const FclOperand& b) {
  const bool overlapping = collide(*a.geometry, a.pose, *b.geometry, b.pose);
  const bool meshA = a.geometry->getObjectType() == fcl::OT_BVH, meshB = b.geometry->getObjectType() == fcl::OT_BVH;
  if (overlapping && meshA != meshB)
    throw std::runtime_error(
        "FCL 0.7 has no signed distance for a triangle mesh against an overlapping shape (its answer is 0 with "
        "uninitialised nearest points)");
  fcl::DistanceRequestd request(true, true, 0.0, 0.0, overlapping ? kFclPenetrationTolerance : kFclGjkTolerance);
  fcl::DistanceResultd result;
  fcl::distance(a.geometry.get(), a.pose, b.geometry.get(), b.pose, request, result);
  return result;
}

/// A DistanceResult as the world reports it; triangles for the operands that are meshes.
WorldDistance toWorld(const fcl::DistanceResultd& r, bool aIsMesh, bool bIsMesh) {
  WorldDistance w;
  w.distance = r.min_distance;
  w.pointA = r.nearest_points[0];
  w.pointB = r.nearest_points[1];
  const Vec3d gap = w.pointA - w.pointB;
  if (gap.norm() > 0) w.normal = (r.min_distance < 0 ? -gap : gap).normalized();
  if (aIsMesh && r.b1 >= 0) w.triangleA = std::uint32_t(r.b1);
  if (bIsMesh && r.b2 >= 0) w.triangleB = std::uint32_t(r.b2);
  return w;
}

/// A model in FCL: a CollisionObjectd over its mesh's shared BVHModel at the model's world pose,
/// registered in the scene's broad phase. The object's user data points back here.
struct FclModel {
  ModelHandle handle;
  std::unique_ptr<fcl::CollisionObjectd> object;
};

const FclModel* modelOf(const fcl::CollisionObjectd* o) { return static_cast<const FclModel*>(o->getUserData()); }

/// Collides two placed objects with the same request as the mesh ops (one contact, no details).
bool collide(const fcl::CollisionObjectd* a, const fcl::CollisionObjectd* b) {
  const fcl::CollisionRequestd request(1, false);
  fcl::CollisionResultd result;
  fcl::collide(a, b, request, result);
  return result.isCollision();
}

/// scene_query's state through DynamicAABBTreeCollisionManager::collide(query, ...): every
/// model whose FCL AABB overlaps the query object's AABB reaches the callback.
struct SceneQueryData {
  bool boundsOnly = false;
  std::vector<ModelHandle> found;
};

/// scene_query callback: narrow phase fcl::collide(model, query); with boundsOnly, the query
/// shape against the model's FCL AABB as a Boxd instead.
bool sceneQueryCallback(fcl::CollisionObjectd* a, fcl::CollisionObjectd* b, void* data) {
  auto& d = *static_cast<SceneQueryData*>(data);
  const bool aIsModel = modelOf(a) != nullptr;
  const fcl::CollisionObjectd* model = aIsModel ? a : b;
  const fcl::CollisionObjectd* query = aIsModel ? b : a;
  bool hit = false;
  if (d.boundsOnly) {
    const fcl::AABBd& box = model->getAABB();
    const fcl::Boxd shape(box.max_ - box.min_);
    fcl::Transform3d pose = fcl::Transform3d::Identity();
    pose.translation() = box.center();
    hit = collide(shape, pose, *query->collisionGeometry(), query->getTransform());
  } else {
    hit = collide(model, query);
  }
  if (hit) d.found.push_back(modelOf(model)->handle);
  return false;  // never stop early: every model is wanted
}

/// scene_pairs callback (DynamicAABBTreeCollisionManager::collide(data, ...) hands over every
/// pair of models whose AABBs overlap): narrow phase fcl::collide on the two BVHModels.
bool scenePairsCallback(fcl::CollisionObjectd* a, fcl::CollisionObjectd* b, void* data) {
  if (collide(a, b))
    static_cast<std::vector<std::pair<ModelHandle, ModelHandle>>*>(data)->emplace_back(modelOf(a)->handle,
                                                                                       modelOf(b)->handle);
  return false;
}

class FclWorld final : public CollisionWorld {
 public:
  std::string_view backend() const override { return "fcl"; }
  std::string description() const override {
    return std::string("FCL ") + FCL_VERSION + " (BVHModel<OBBRSSd>, libccd GJK), double";
  }
  bool supports(WorldOp op) const override {
    switch (op) {
      case WorldOp::ClosestPointTriangle:
      case WorldOp::TriangleSphere:
      case WorldOp::TriangleAabb:
      case WorldOp::TriangleObb:
      case WorldOp::TrianglePlane:
      case WorldOp::TriangleTriangle:
      case WorldOp::Mesh:
      case WorldOp::LoadMesh:
      case WorldOp::MeshSphere:
      case WorldOp::MeshAabb:
      case WorldOp::MeshObb:
      case WorldOp::MeshPlane:
      case WorldOp::MeshTriangle:
      case WorldOp::MeshMesh:
      case WorldOp::AddModel:
      case WorldOp::SetTransform:
      case WorldOp::SetParent:
      case WorldOp::RemoveModel:
      case WorldOp::Children:
      case WorldOp::ModelSphere:
      case WorldOp::ModelAabb:
      case WorldOp::ModelObb:
      case WorldOp::ModelPlane:
      case WorldOp::ModelTriangle:
      case WorldOp::SceneQuery:
      case WorldOp::ScenePairs:
      case WorldOp::Distance:
      case WorldOp::MeshDistance:
      case WorldOp::ModelDistance:
      case WorldOp::Cast:  // convex pairs (FCL's conservative advancement against a BVHModel fails: doCast)
        return true;
      default:
        return false;
    }
  }
  WorldTolerance tolerance() const override { return kFclTolerance; }

 protected:
  void onMeshAdded(MeshHandle h, const Mesh& mesh) override { models_[h.index] = buildModel(mesh); }
  void onMeshRemoved(MeshHandle h) override { models_.erase(h.index); }

  Vec3d doClosestPoint(const Triangle& t, const Vec3& p) override {
    const auto tri = buildModel(t);
    const fcl::Sphered point(0.0);
    const fcl::DistanceRequestd request(true);  // nearest points, in world coordinates
    fcl::DistanceResultd result;
    fcl::distance(tri.get(), identity(), &point, translation(p), request, result);
    return result.nearest_points[0];
  }
  bool doOverlaps(const Triangle& t, const Sphere& s) override {
    const fcl::Sphered sphere(double(s.radius));
    return collide({*buildModel(t), identity()}, {sphere, translation(s.center)});
  }
  bool doOverlaps(const Triangle& t, const Aabb& b) override {
    const fcl::Boxd shape = box(b);
    return collide({*buildModel(t), identity()}, {shape, translation(b.center())});
  }
  bool doOverlaps(const Triangle& t, const Obb& b) override {
    const fcl::Boxd shape = box(b);
    return collide({*buildModel(t), identity()}, {shape, pose(b)});
  }
  bool doOverlaps(const Triangle& t, const Plane& p) override {
    const fcl::Planed shape = plane(p);
    return collide({*buildModel(t), identity()}, {shape, identity()});
  }
  bool doOverlaps(const Triangle& a, const Triangle& b) override {
    return collide({*buildModel(a), identity()}, {*buildModel(b), identity()});
  }

  bool doOverlaps(MeshHandle m, const Sphere& s) override {
    const fcl::Sphered sphere(double(s.radius));
    return collide({model(m), identity()}, {sphere, translation(s.center)});
  }
  bool doOverlaps(MeshHandle m, const Aabb& b) override {
    const fcl::Boxd shape = box(b);
    return collide({model(m), identity()}, {shape, translation(b.center())});
  }
  bool doOverlaps(MeshHandle m, const Obb& b) override {
    const fcl::Boxd shape = box(b);
    return collide({model(m), identity()}, {shape, pose(b)});
  }
  bool doOverlaps(MeshHandle m, const Plane& p) override {
    const fcl::Planed shape = plane(p);
    return collide({model(m), identity()}, {shape, identity()});
  }
  bool doOverlaps(MeshHandle m, const Triangle& t) override {
    return collide({model(m), identity()}, {*buildModel(t), identity()});
  }
  bool doOverlaps(MeshHandle a, const Transform& ta, MeshHandle b, const Transform& tb) override {
    return collide({model(a), toFcl(ta)}, {model(b), toFcl(tb)});
  }

  // ---- distances: fcl::distance with enable_nearest_points and enable_signed_distance --------
  // (docs/batch.md "Backends": FCL's sign convention for penetration and its bounds.)

  WorldDistance doDistance(const WorldOperand& a, const WorldOperand& b) override {
    const FclOperand oa = operand(a), ob = operand(b);
    const fcl::DistanceResultd r = signedDistance(oa, ob);
    // FCL 0.7's fcl::distance answers (shape, BVHModel) — here a convex shape against a triangle
    // operand — as (BVHModel, shape) and leaves its result in that order (DistanceResult's o1 is
    // then b's geometry; narrowphase/distance-inl.h swaps nothing back)
    if (r.o1 == ob.geometry.get() && r.o1 != oa.geometry.get()) return toWorld(r, b.isMesh(), a.isMesh()).reversed();
    return toWorld(r, a.isMesh(), b.isMesh());
  }
  std::optional<WorldDistance> doMeshDistance(MeshHandle a, const Transform& ta, MeshHandle b, const Transform& tb,
                                              double maxDistance) override {
    const fcl::DistanceResultd r = signedDistance({models_.at(a.index), toFcl(ta)}, {models_.at(b.index), toFcl(tb)});
    if (r.min_distance > maxDistance) return std::nullopt;  // FCL has no bound: filtered afterwards
    return toWorld(r, true, true);
  }
  std::optional<WorldDistance> doModelDistance(ModelHandle a, ModelHandle b, double maxDistance) override {
    const fcl::CollisionObjectd& oa = object(a, "a");
    const fcl::CollisionObjectd& ob = object(b, "b");
    const fcl::DistanceResultd r =
        signedDistance({oa.collisionGeometry(), oa.getTransform()}, {ob.collisionGeometry(), ob.getTransform()});
    if (r.min_distance > maxDistance) return std::nullopt;
    return toWorld(r, true, true);
  }

  // ---- casts: fcl::continuousCollide, conservative advancement (libccd GJK) ------------------

  /// cast: fcl::continuousCollide of two convex shapes (CCDC_CONSERVATIVE_ADVANCEMENT, GST_LIBCCD)
  /// under TranslationMotion (CCDM_TRANS) or, for a rigid motion, InterpMotion (CCDM_LINEAR:
  /// rotation at constant angular velocity about the shape's FCL origin, translation linear, as
  /// crux's slerp motion when that origin is the operand's). A triangle is cast as a one-face
  /// fcl::Convex (FCL has no advancement for TriangleP). FCL reports the time alone: no points,
  /// no normal. A mesh b throws: FCL 0.7's advancement against a BVHModel misses hits or crashes
  /// (docs/bench.md, "bench_cast").
  WorldCast doCast(const WorldOperand& a, const WorldMotion& motion, const WorldOperand& b, CastFind) override {
    if (b.isMesh())
      throw std::runtime_error(
          "FCL 0.7's conservative advancement against a triangle mesh misses hits (generic BV path) or crashes "
          "(OBBRSS path); the fcl world casts convex pairs only");
    const FclOperand oa = castOperand(a), ob = castOperand(b);
    const fcl::Transform3d local = toFcl(a.pose).inverse() * oa.pose;  // the shape in a's frame
    fcl::Transform3d end = oa.pose;
    if (motion.end) end = toFcl(*motion.end) * local;
    else end.translation() += motion.translation.cast<double>();
    fcl::ContinuousCollisionRequestd request;
    request.ccd_motion_type = motion.end ? fcl::CCDM_LINEAR : fcl::CCDM_TRANS;
    request.gjk_solver_type = fcl::GST_LIBCCD;
    request.ccd_solver_type = fcl::CCDC_CONSERVATIVE_ADVANCEMENT;
    fcl::ContinuousCollisionResultd result;
    fcl::continuousCollide(oa.geometry.get(), oa.pose, end, ob.geometry.get(), ob.pose, ob.pose, request, result);
    WorldCast w;
    if (!result.is_collide) return w;
    w.hit = true;
    w.t = result.time_of_contact;
    w.witnessKnown = false;
    w.startsOverlapping = result.time_of_contact == 0;
    return w;
  }

  // ---- models and the scene ----------------------------------------------------------------

  ModelHandle doAddModel(const std::string& name, MeshHandle mesh, const Transform& local,
                         std::optional<ModelHandle> parent) override {
    const ModelHandle h = table_.add(name, mesh, sharedMesh(mesh), local, parent);
    try {
      auto entry = std::make_unique<FclModel>();
      entry->handle = h;
      // The model keeps the mesh's BVHModel alive (shared_ptr) if the mesh is removed later.
      entry->object = std::make_unique<fcl::CollisionObjectd>(models_.at(mesh.index), toFcl(table_.world(h)));
      entry->object->setUserData(entry.get());
      manager_.registerObject(entry->object.get());
      objects_[h.index] = std::move(entry);
    } catch (...) {
      table_.remove(h);
      throw;
    }
    return h;
  }
  void doRemoveModel(ModelHandle m) override {
    table_.remove(m);  // validates m; the children keep their world poses, so no FCL update
    manager_.unregisterObject(objects_.at(m.index)->object.get());  // m is known: table_.remove passed
    objects_.erase(m.index);
  }
  void doSetTransform(ModelHandle m, const Transform& local) override { place(table_.setLocal(m, local)); }
  void doSetParent(ModelHandle m, std::optional<ModelHandle> parent) override {
    table_.setParent(m, parent);
    // World poses are kept; placing the subtree again keeps FCL in step with the table anyway.
    std::vector<ModelHandle> subtree = table_.descendants(m);
    subtree.push_back(m);
    place(subtree);
  }
  std::optional<ModelHandle> doFindModel(std::string_view name) override { return table_.find(name); }
  std::vector<std::string> doDescendants(ModelHandle m) override { return table_.descendantNames(m); }

  bool doOverlaps(ModelHandle m, const Sphere& s) override {
    const fcl::Sphered sphere(double(s.radius));
    return collide(placed(m), {sphere, translation(s.center)});
  }
  bool doOverlaps(ModelHandle m, const Aabb& b) override {
    const fcl::Boxd shape = box(b);
    return collide(placed(m), {shape, translation(b.center())});
  }
  bool doOverlaps(ModelHandle m, const Obb& b) override {
    const fcl::Boxd shape = box(b);
    return collide(placed(m), {shape, pose(b)});
  }
  bool doOverlaps(ModelHandle m, const Plane& p) override {
    const fcl::Planed shape = plane(p);
    return collide(placed(m), {shape, identity()});
  }
  bool doOverlaps(ModelHandle m, const Triangle& t) override {
    return collide(placed(m), {*buildModel(t), identity()});
  }

  std::vector<std::string> doSceneQuery(const SceneQueryShape& shape, bool boundsOnly) override {
    std::shared_ptr<fcl::CollisionGeometryd> geometry;
    fcl::Transform3d where = identity();
    if (const auto* s = std::get_if<Sphere>(&shape)) {
      geometry = std::make_shared<fcl::Sphered>(double(s->radius));
      where = translation(s->center);
    } else if (const auto* b = std::get_if<Aabb>(&shape)) {
      geometry = std::make_shared<fcl::Boxd>(box(*b));
      where = translation(b->center());
    } else {
      const Obb& o = std::get<Obb>(shape);
      geometry = std::make_shared<fcl::Boxd>(box(o));
      where = pose(o);
    }
    fcl::CollisionObjectd query(geometry, where);  // user data null: not a model
    SceneQueryData data;
    data.boundsOnly = boundsOnly;
    manager_.collide(&query, &data, sceneQueryCallback);
    std::vector<std::string> names;
    for (const ModelHandle h : data.found) names.push_back(table_.name(h));
    std::sort(names.begin(), names.end());
    names.erase(std::unique(names.begin(), names.end()), names.end());
    return names;
  }
  std::vector<std::pair<std::string, std::string>> doScenePairs() override {
    std::vector<std::pair<ModelHandle, ModelHandle>> found;
    manager_.collide(&found, scenePairsCallback);
    std::vector<std::pair<std::string, std::string>> pairs;
    for (const auto& [a, b] : found) {
      std::string na = table_.name(a), nb = table_.name(b);
      if (nb < na) std::swap(na, nb);
      pairs.emplace_back(std::move(na), std::move(nb));
    }
    std::sort(pairs.begin(), pairs.end());
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
    return pairs;
  }

 private:
  const Model& model(MeshHandle h) const { return *models_.at(h.index); }

  /// An operand as FCL geometry in the world: convex shapes are placed by the operand's pose
  /// composed with the shape's own placement (box centre and axes, capsule axis).
  FclOperand operand(const WorldOperand& o) const {
    const fcl::Transform3d where = toFcl(o.pose);
    if (const auto* m = std::get_if<MeshHandle>(&o.shape)) return {models_.at(m->index), where};
    FclOperand local;
    if (const auto* s = std::get_if<Sphere>(&o.shape)) {
      local = {std::make_shared<fcl::Sphered>(double(s->radius)), translation(s->center)};
    } else if (const auto* b = std::get_if<Obb>(&o.shape)) {
      local = {std::make_shared<fcl::Boxd>(box(*b)), pose(*b)};
    } else if (const auto* c = std::get_if<Capsule>(&o.shape)) {
      local = capsuleOperand(c->a, c->b, double(c->radius));
    } else if (const auto* t = std::get_if<Triangle>(&o.shape)) {
      local = {buildModel(*t), identity()};
    } else {
      local = hullOperand(std::get<ConvexHull>(o.shape));
    }
    return {local.geometry, where * local.pose};
  }

  /// A cast operand: as operand(), but a triangle as the convex hull of its corners.
  FclOperand castOperand(const WorldOperand& o) const {
    if (const auto* t = std::get_if<Triangle>(&o.shape)) {
      const FclOperand hull = hullOperand(ConvexHull::build({t->a, t->b, t->c}));
      return {hull.geometry, toFcl(o.pose) * hull.pose};
    }
    return operand(o);
  }

  /// The model's FCL object; InvalidInput naming the field for an unknown handle.
  fcl::CollisionObjectd& object(ModelHandle m, const char* field = "model") const {
    if (!table_.contains(m)) throw InvalidInput(std::string(field) + ": unknown model handle " + std::to_string(m.index));
    return *objects_.at(m.index)->object;
  }
  /// The model's geometry at its world pose.
  Placed placed(ModelHandle m) const {
    const fcl::CollisionObjectd& o = object(m);
    return {*o.collisionGeometry(), o.getTransform()};
  }
  /// Moves models' FCL objects to their world poses (table_.world, rotation normalised in
  /// double), recomputes their AABBs and updates the broad phase once.
  void place(const std::vector<ModelHandle>& moved) {
    std::vector<fcl::CollisionObjectd*> objects;
    objects.reserve(moved.size());
    for (const ModelHandle h : moved) {
      fcl::CollisionObjectd* o = &object(h);
      o->setTransform(toFcl(table_.world(h)));
      o->computeAABB();
      objects.push_back(o);
    }
    manager_.update(objects);
  }

  std::map<std::uint32_t, std::shared_ptr<Model>> models_;  ///< by mesh handle
  oracle::ModelTable table_;
  std::map<std::uint32_t, std::unique_ptr<FclModel>> objects_;  ///< by model handle
  fcl::DynamicAABBTreeCollisionManagerd manager_;
};

}  // namespace

std::unique_ptr<CollisionWorld> makeFclWorld() { return std::make_unique<FclWorld>(); }

}  // namespace crux::fcl_oracle
