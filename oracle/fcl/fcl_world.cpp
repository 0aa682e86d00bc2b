/// @file fcl_world.cpp  The "fcl" backend (see fcl_world.hpp): crux shapes converted to FCL
/// geometry, every answer straight from fcl::collide / fcl::distance.

#include "fcl/fcl_world.hpp"

#include <fcl/config.h>
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/plane.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/math/bv/OBBRSS.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/distance.h>

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

 private:
  const Model& model(MeshHandle h) const { return *models_.at(h.index); }

  std::map<std::uint32_t, std::shared_ptr<Model>> models_;
};

}  // namespace

std::unique_ptr<CollisionWorld> makeFclWorld() { return std::make_unique<FclWorld>(); }

}  // namespace crux::fcl_oracle
