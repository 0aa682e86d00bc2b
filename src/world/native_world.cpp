/// @file native_world.cpp  The "native" backend: every hook forwards to the crux function of the
/// same op, so the world answers exactly what the direct API answers.

#include <crux/world/native_world.hpp>

#include <crux/geometry/closest_point.hpp>
#include <crux/geometry/overlap.hpp>
#include <crux/geometry/raycast.hpp>
#include <crux/mesh/mesh_query.hpp>

#include <string>

namespace crux {
namespace {

WorldRayHit toWorld(const RayHit& h) {
  WorldRayHit w;
  w.t = double(h.t);
  w.point = h.point.cast<double>();
  w.normal = h.normal.cast<double>();
  return w;
}

WorldRayHit toWorld(const MeshRayHit& h) {
  WorldRayHit w;
  w.t = double(h.t);
  w.point = h.point.cast<double>();
  w.normal = h.normal.cast<double>();
  w.triangle = h.triangle;
  return w;
}

class NativeWorld final : public CollisionWorld {
 public:
  std::string_view backend() const override { return "native"; }
  std::string description() const override {
    return std::string("crux (geometry and mesh layers), ") + (sizeof(Real) == sizeof(double) ? "double" : "float");
  }
  bool supports(WorldOp op) const override { return op <= WorldOp::MeshMesh; }
  WorldTolerance tolerance() const override { return kNativeTolerance; }

 protected:
  // The base class keeps the crux::Mesh, which carries its own BVH: nothing else to build.
  void onMeshAdded(MeshHandle, const Mesh&) override {}
  void onMeshRemoved(MeshHandle) override {}

  Vec3d doClosestPoint(const Triangle& t, const Vec3& p) override { return crux::closestPoint(t, p).cast<double>(); }
  bool doOverlaps(const Triangle& t, const Sphere& s) override { return crux::overlaps(t, s); }
  bool doOverlaps(const Triangle& t, const Aabb& b) override { return crux::overlaps(t, b); }
  bool doOverlaps(const Triangle& t, const Obb& b) override { return crux::overlaps(t, b); }
  bool doOverlaps(const Triangle& t, const Plane& p) override { return crux::overlaps(t, p); }
  bool doOverlaps(const Triangle& a, const Triangle& b) override { return crux::overlaps(a, b); }
  std::optional<WorldRayHit> doRaycast(const Ray& r, const Triangle& t) override {
    const std::optional<RayHit> h = crux::raycast(r, t);
    if (!h) return std::nullopt;
    return toWorld(*h);
  }
  bool doIntersects(const Segment& s, const Triangle& t) override { return crux::intersects(s, t); }

  void doRaycast(MeshHandle m, const Ray& r, RayHitCollector& hits, const RayQueryOptions& options) override {
    const Mesh& mesh = this->mesh(m);
    switch (hits.mode()) {
      case RayCollect::Closest:
        if (const auto h = raycastClosest(mesh, r, options)) hits.add(toWorld(*h));
        break;
      case RayCollect::Any:
        if (raycastAny(mesh, r, options)) hits.addAnonymousHit();
        break;
      case RayCollect::All:
        for (const MeshRayHit& h : raycastAll(mesh, r, options)) hits.add(toWorld(h));
        break;
    }
  }
  bool doIntersects(MeshHandle m, const Segment& s) override { return crux::intersects(mesh(m), s); }
  bool doOverlaps(MeshHandle m, const Sphere& s) override { return crux::overlaps(mesh(m), s); }
  bool doOverlaps(MeshHandle m, const Aabb& b) override { return crux::overlaps(mesh(m), b); }
  bool doOverlaps(MeshHandle m, const Obb& b) override { return crux::overlaps(mesh(m), b); }
  bool doOverlaps(MeshHandle m, const Plane& p) override { return crux::overlaps(mesh(m), p); }
  bool doOverlaps(MeshHandle m, const Triangle& t) override { return crux::overlaps(mesh(m), t); }
  bool doOverlaps(MeshHandle a, const Transform& ta, MeshHandle b, const Transform& tb) override {
    return crux::overlaps(mesh(a), ta, mesh(b), tb);
  }
};

}  // namespace

std::unique_ptr<CollisionWorld> makeNativeWorld() { return std::make_unique<NativeWorld>(); }

}  // namespace crux
