/// @file scene_cast.cpp  Casts against a scene (scene_cast.hpp): the broad phase's ray traversal
/// along the shape origin's path, the model casts per candidate.

#include <crux/scene/scene_cast.hpp>
#include <crux/precondition.hpp>

#include <algorithm>
#include <cmath>

namespace crux {
namespace {

/// Largest |coordinate| of a box.
double maxAbs(const Aabb& b) {
  return double(std::max(b.min.cwiseAbs().maxCoeff(), b.max.cwiseAbs().maxCoeff()));
}

/// A model cast and the rule picking the first hit (smallest t, then lowest model id).
template <class CastModel>
class Best {
 public:
  Best(const Scene& scene, const CastModel& castModel, bool stopAtFirst)
      : scene_(scene), castModel_(castModel), stopAtFirst_(stopAtFirst) {}
  /// Casts against one model; false: stop (any-hit mode, after a hit).
  bool consider(ModelId id) {
    const std::optional<MeshCastHit> h = castModel_(scene_.placed(id));
    if (h && (!best || h->cast.t < best->hit.cast.t || (h->cast.t == best->hit.cast.t && id < best->model)))
      best = SceneCastHit{id, *h};
    return !(stopAtFirst_ && best);
  }
  std::optional<SceneCastHit> best;

 private:
  const Scene& scene_;
  const CastModel& castModel_;
  bool stopAtFirst_;
};

/// Broad-phase candidates in the order of their boxes along the origin's path, pruned by the
/// best impact (its time × the path length, with the margin's slack).
template <class CastModel>
class PathCollector final : public RayProxyCollector {
 public:
  PathCollector(Best<CastModel>& best, Real pathLength, Real margin, Real slack)
      : best_(best), pathLength_(pathLength), slack_(slack) {
    boxMargin = margin;
  }
  bool add(ProxyId id, Real) override {
    const bool more = best_.consider(id);
    if (best_.best) maxT = best_.best->hit.cast.t * pathLength_ * (1 + slack_) + slack_ * boxMargin;
    return more;
  }

 private:
  Best<CastModel>& best_;
  Real pathLength_, slack_;
};

/// Runs a cast of a shape of size `size` whose origin goes from c0 to c1.
template <class CastModel>
std::optional<SceneCastHit> run(const Scene& scene, const CastModel& castModel, const Vec3& c0, const Vec3& c1,
                                double size, double angularReach, ScenePath path, bool stopAtFirst) {
  Best<CastModel> best(scene, castModel, stopAtFirst);
  const std::vector<ModelId> ids = scene.models().ids();
  if (path == ScenePath::BruteForce) {
    for (const ModelId id : ids)
      if (!best.consider(id)) break;
    return best.best;
  }
  // The margin: the shape's reach about its origin plus the casts' contact tolerance at the
  // largest scale a triangle pair of this scene can have (model boxes and mesh-local bounds),
  // plus 1000 ulps of Real of the coordinates for the slab test's rounding.
  double sceneScale = 0;
  for (const ModelId id : ids)
    sceneScale = std::max({sceneScale, maxAbs(scene.bounds(id)), maxAbs(scene.models().mesh(id)->bounds())});
  const double pathLength = (c1 - c0).cast<double>().norm();
  const double scale = size + angularReach + 2 * sceneScale * std::sqrt(3.0) + maxAbs(Aabb{c0, c0}) + pathLength;
  const double eps = double(std::numeric_limits<Real>::epsilon());
  const double margin = size + kCastRelativeTolerance * scale * (1 + 1e-6) + 1000 * eps * scale;
  const Vec3 dir = c1 - c0;
  Ray ray{c0, dir};
  if (!(pathLength > 0) || !(dir.cast<double>().squaredNorm() > 0)) {
    // no path: the boxes touching the ball the shape sweeps about its fixed origin
    for (const ProxyId id : queryIds(scene.broadPhase(), Sphere{c0, Real(margin)}))
      if (!best.consider(id)) break;
    return best.best;
  }
  PathCollector<CastModel> collector(best, Real(pathLength), Real(margin), Real(64 * eps));
  collector.maxT = Real(pathLength * (1 + 64 * eps) + 64 * eps * margin);
  scene.broadPhase().raycast(ray, collector);
  return best.best;
}

/// A linear cast: the path of the shape's origin, no rotation.
std::optional<SceneCastHit> runLinear(const Scene& scene, const ConvexShape& shape, const Transform& shapePose,
                                      const Vec3& motion, ScenePath path, bool stopAtFirst) {
  const auto castModel = [&](const PlacedMesh& m) { return castClosest(m, shape, shapePose, motion); };
  return run(scene, castModel, shapePose.translation, Vec3(shapePose.translation + motion), double(shape.size()), 0,
             path, stopAtFirst);
}

/// A rigid cast: the path of the shape's origin, and a rotation that moves its points by at most
/// π × its size.
std::optional<SceneCastHit> runRigid(const Scene& scene, const ConvexShape& shape, const RigidMotion& motion,
                                     ScenePath path, bool stopAtFirst) {
  const auto castModel = [&](const PlacedMesh& m) { return castClosest(m, shape, motion); };
  return run(scene, castModel, motion.start.translation, motion.end.translation, double(shape.size()),
             M_PI * double(shape.size()), path, stopAtFirst);
}

}  // namespace

std::optional<SceneCastHit> castClosest(const Scene& scene, const ConvexShape& shape, const Transform& shapePose,
                                        const Vec3& motion, ScenePath path) {
  if (!detail::entryPreconditions("castClosest(Scene, ConvexShape)", detail::rule::kCast, shape, shapePose, motion))
    return std::nullopt;
  return runLinear(scene, shape, shapePose, motion, path, false);
}

std::optional<SceneCastHit> castClosest(const Scene& scene, const ConvexShape& shape, const RigidMotion& motion,
                                        ScenePath path) {
  if (!detail::entryPreconditions("castClosest(Scene, ConvexShape, RigidMotion)", detail::rule::kCast, shape, motion))
    return std::nullopt;
  return runRigid(scene, shape, motion, path, false);
}

bool castAny(const Scene& scene, const ConvexShape& shape, const Transform& shapePose, const Vec3& motion,
             ScenePath path) {
  if (!detail::entryPreconditions("castAny(Scene, ConvexShape)", detail::rule::kCast, shape, shapePose, motion))
    return false;
  return runLinear(scene, shape, shapePose, motion, path, true).has_value();
}

bool castAny(const Scene& scene, const ConvexShape& shape, const RigidMotion& motion, ScenePath path) {
  if (!detail::entryPreconditions("castAny(Scene, ConvexShape, RigidMotion)", detail::rule::kCast, shape, motion))
    return false;
  return runRigid(scene, shape, motion, path, true).has_value();
}

}  // namespace crux
