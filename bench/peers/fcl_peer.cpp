#include "fcl_peer.hpp"

#include <fcl/config.h>
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/math/bv/OBBRSS.h>
#include <fcl/narrowphase/collision.h>

#include <vector>

namespace crux::bench {

namespace {

using Model = fcl::BVHModel<fcl::OBBRSSd>;

std::shared_ptr<Model> buildModel(const std::vector<fcl::Vector3d>& points, const std::vector<fcl::Triangle>& tris) {
  auto model = std::make_shared<Model>();
  model->beginModel(int(tris.size()), int(points.size()));
  model->addSubModel(points, tris);
  model->endModel();
  return model;
}

fcl::Transform3d poseTransform(const PoseQuery& p) {
  // Normalise in double: the float quaternion is unit only up to float rounding.
  const fcl::Quaterniond q =
      fcl::Quaterniond(double(p.rotation[0]), double(p.rotation[1]), double(p.rotation[2]), double(p.rotation[3]))
          .normalized();
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  tf.linear() = q.toRotationMatrix();
  tf.translation() = fcl::Vector3d(p.translation[0], p.translation[1], p.translation[2]);
  return tf;
}

bool collide(const fcl::CollisionGeometryd* a, const fcl::Transform3d& ta, const fcl::CollisionGeometryd* b,
             const fcl::Transform3d& tb) {
  const fcl::CollisionRequestd request(1, false);  // num_max_contacts 1, no contact details
  fcl::CollisionResultd result;
  fcl::collide(a, ta, b, tb, request, result);
  return result.isCollision();
}

}  // namespace

struct FclPeer::Impl {
  std::vector<fcl::Vector3d> points;
  std::vector<fcl::Triangle> triangles;
  std::shared_ptr<Model> model;
  std::vector<fcl::Vector3d> moved;  ///< scratch of refit()
};

FclPeer::FclPeer(const MeshArrays& mesh) : impl_(std::make_unique<Impl>()) {
  const std::size_t nv = mesh.vertexCount(), nt = mesh.triangleCount();
  impl_->points.reserve(nv);
  for (std::size_t i = 0; i < nv; ++i)
    impl_->points.emplace_back(mesh.positions[3 * i], mesh.positions[3 * i + 1], mesh.positions[3 * i + 2]);
  impl_->triangles.reserve(nt);
  for (std::size_t i = 0; i < nt; ++i)
    impl_->triangles.emplace_back(mesh.indices[3 * i], mesh.indices[3 * i + 1], mesh.indices[3 * i + 2]);
  impl_->model = buildModel(impl_->points, impl_->triangles);
}

FclPeer::~FclPeer() = default;

Seconds FclPeer::timeBuild() const {
  const Stopwatch watch;
  auto model = buildModel(impl_->points, impl_->triangles);
  const Seconds elapsed = watch.elapsed();
  return elapsed;
}

Seconds FclPeer::refit(const MeshArrays& moved) {
  std::vector<fcl::Vector3d>& v = impl_->moved;
  v.resize(moved.vertexCount());
  for (std::size_t i = 0; i < v.size(); ++i)
    v[i] = fcl::Vector3d(moved.positions[3 * i], moved.positions[3 * i + 1], moved.positions[3 * i + 2]);
  const Stopwatch watch;
  Model& m = *impl_->model;
  m.beginUpdateModel();
  m.updateSubModel(v);
  m.endUpdateModel(true, true);
  return watch.elapsed();
}

void FclPeer::sphereOverlaps(const SphereQuery* q, std::size_t n, std::uint8_t* out) const {
  const fcl::Transform3d identity = fcl::Transform3d::Identity();
  for (std::size_t i = 0; i < n; ++i) {
    const fcl::Sphered sphere(q[i].radius);
    fcl::Transform3d tf = fcl::Transform3d::Identity();
    tf.translation() = fcl::Vector3d(q[i].center[0], q[i].center[1], q[i].center[2]);
    out[i] = collide(impl_->model.get(), identity, &sphere, tf);
  }
}

void FclPeer::boxOverlaps(const BoxQuery* q, std::size_t n, std::uint8_t* out) const {
  const fcl::Transform3d identity = fcl::Transform3d::Identity();
  for (std::size_t i = 0; i < n; ++i) {
    const BoxQuery& b = q[i];
    const fcl::Boxd box(2.0 * b.half[0], 2.0 * b.half[1], 2.0 * b.half[2]);
    fcl::Transform3d tf = fcl::Transform3d::Identity();
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) tf.linear()(r, c) = b.axes[3 * c + r];
    tf.translation() = fcl::Vector3d(b.center[0], b.center[1], b.center[2]);
    out[i] = collide(impl_->model.get(), identity, &box, tf);
  }
}

void FclPeer::meshOverlaps(const PoseQuery* q, std::size_t n, std::uint8_t* out) const {
  const fcl::Transform3d identity = fcl::Transform3d::Identity();
  for (std::size_t i = 0; i < n; ++i)
    out[i] = collide(impl_->model.get(), identity, impl_->model.get(), poseTransform(q[i]));
}

std::size_t FclPeer::modelBytes() const {
  const Model& m = *impl_->model;
  return std::size_t(m.num_vertices) * sizeof(fcl::Vector3d) + std::size_t(m.num_tris) * sizeof(fcl::Triangle) +
         std::size_t(m.getNumBVs()) * sizeof(fcl::BVNode<fcl::OBBRSSd>) + std::size_t(m.num_tris) * sizeof(unsigned int);
}

std::string fclVersion() { return FCL_VERSION; }

}  // namespace crux::bench
