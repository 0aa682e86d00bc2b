/// @file model_cast.cpp  Casts against placed models: the mesh casts with the model's world pose.

#include <crux/model/model_cast.hpp>

namespace crux {

std::optional<MeshCastHit> castClosest(const PlacedMesh& m, const ConvexShape& shape, const Transform& shapePose,
                                       const Vec3& motion) {
  return castClosest(*m.mesh, m.world, shape, shapePose, motion);
}

std::optional<MeshCastHit> castClosest(const PlacedMesh& m, const ConvexShape& shape, const RigidMotion& motion) {
  return castClosest(*m.mesh, m.world, shape, motion);
}

bool castAny(const PlacedMesh& m, const ConvexShape& shape, const Transform& shapePose, const Vec3& motion) {
  return castAny(*m.mesh, m.world, shape, shapePose, motion);
}

bool castAny(const PlacedMesh& m, const ConvexShape& shape, const RigidMotion& motion) {
  return castAny(*m.mesh, m.world, shape, motion);
}

}  // namespace crux
