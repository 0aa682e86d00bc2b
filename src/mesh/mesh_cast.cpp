/// @file mesh_cast.cpp  Shape casts against a mesh (mesh_cast.hpp): the pair cast per triangle,
/// through the mesh's wide BVH (mesh_detail::walkOrdered) with the swept bounds' entry time as
/// the key. Linear casts first put each triangle of a leaf through the separating-axis bound of
/// the moving shape (detail::SweptSeparation, with the swept bounds' pad): a triangle the shape
/// cannot come within the pad of before the best t so far is skipped without running the
/// advancement, which leaves the answer unchanged (its hits are within the contact tolerance,
/// which the pad exceeds). Rigid casts skip this bound: their advancement may stop at its
/// iteration cap, short of the contact tolerance.

#include <crux/mesh/mesh_cast.hpp>
#include <crux/precondition.hpp>

#include "geometry/swept_separation.hpp"
#include "mesh_walk.hpp"
#include "node_tests.hpp"
#include "shape_bounds.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace crux {
namespace {

constexpr double kEpsReal = std::numeric_limits<Real>::epsilon();

/// A box moving by s·motion, s in [0, 1], in the mesh frame, grown by `pad` on every side.
class SweptBox {
 public:
  SweptBox(const Aabb& box, const Vec3& motion, double pad)
      : lo_(box.min.cast<double>().array() - pad), hi_(box.max.cast<double>().array() + pad),
        m_(motion.cast<double>()) {}

  /// Whether the moving box meets `node` at some s in [0, 1]; `key` receives the first such s
  /// (rounded down to Real).
  bool enter(const Aabb& node, Real& key) const {
    double s0 = 0, s1 = 1;
    for (int i = 0; i < 3; ++i) {
      const double nlo = double(node.min[i]), nhi = double(node.max[i]);
      // overlap on axis i at s: lo_i + s·m_i <= nhi and hi_i + s·m_i >= nlo
      if (m_[i] == 0) {
        if (lo_[i] > nhi || hi_[i] < nlo) return false;
        continue;
      }
      double a = (nlo - hi_[i]) / m_[i], b = (nhi - lo_[i]) / m_[i];
      if (a > b) std::swap(a, b);
      // the quotients' rounding (a few ulps of double) is far inside the pad
      s0 = std::max(s0, a);
      s1 = std::min(s1, b);
    }
    if (!(s0 <= s1)) return false;
    key = Real(s0);
    if (double(key) > s0) key = std::nextafter(key, Real(0));
    return true;
  }

 private:
  Eigen::Array3d lo_, hi_;
  Eigen::Vector3d m_;
};

/// Largest |coordinate| of a box.
double maxAbs(const Aabb& b) { return double(mesh_detail::maxAbs(b)); }

/// The search over the triangles shared by both paths; `castTriangle(triangle, options)` is the
/// pair cast of the shape against one triangle placed by the mesh pose.
template <class CastTriangle>
class Search {
 public:
  /// `cull`: the per-triangle separating-axis test of the linear casts (null: none).
  Search(const Mesh& mesh, const CastTriangle& castTriangle, const SweptBox& box,
         const detail::SweptSeparation* cull, bool stopAtFirst)
      : mesh_(mesh), castTriangle_(castTriangle), box_(box), cull_(cull), stopAtFirst_(stopAtFirst) {}

  // ---- the walk's visitor (mesh_detail::walkOrdered) ----
  bool entry(const Aabb& box, Real& key) const { return box_.enter(box, key) && keep(key); }
  /// A node entered at s may hold a triangle whose reported t (rounded down to Real, the entry
  /// being a lower bound of the double t) ties the best: kept up to an ulp past it.
  bool keep(Real key) const { return double(key) <= limit(); }
  /// The latest entry still kept (see keep); past 1 before the first hit.
  double limit() const { return found_ ? double(best_.cast.t) + 2 * kEpsReal : 2; }
  /// A triangle that the swept shape cannot come within the pad of before limit() is skipped:
  /// its cast could only miss or report a t past the best (swept_separation.hpp).
  bool leaf(std::uint32_t first, std::uint32_t count) {
    for (std::uint32_t k = first; k < first + count; ++k) {
      const Triangle tri = mesh_.slotTriangle(k);
      double entry;
      if (cull_ && !cull_->enter(tri, limit(), entry)) continue;
      if (!consider(tri, mesh_.bvh().primIndices[k])) return false;
    }
    return true;
  }

  /// Casts against one triangle; false stops the search (any-hit mode, after a hit).
  bool consider(const Triangle& tri, std::uint32_t index) {
    CastOptions options;
    if (found_) options.earlyOut = best_.cast.t;
    const CastResult r = castTriangle_(tri, options);
    if (!r.hit) return true;
    if (!found_ || r.t < best_.cast.t || (r.t == best_.cast.t && index < best_.triangle)) {
      best_.cast = r;
      best_.triangle = index;
      found_ = true;
    }
    return !stopAtFirst_;
  }

  std::optional<MeshCastHit> result() const {
    if (!found_) return std::nullopt;
    return best_;
  }

 private:
  const Mesh& mesh_;
  const CastTriangle& castTriangle_;
  const SweptBox& box_;
  const detail::SweptSeparation* cull_;
  bool stopAtFirst_;
  bool found_ = false;
  MeshCastHit best_;
};

template <class CastTriangle>
std::optional<MeshCastHit> run(const Mesh& mesh, const CastTriangle& castTriangle, const SweptBox& box,
                               const detail::SweptSeparation* cull, QueryPath path, bool stopAtFirst) {
  Search<CastTriangle> search(mesh, castTriangle, box, cull, stopAtFirst);
  if (path == QueryPath::BruteForce) {
    for (std::uint32_t i = 0, n = std::uint32_t(mesh.triangleCount()); i < n; ++i)
      if (!search.consider(mesh.triangle(i), i)) break;
  } else {
    mesh_detail::walkOrdered(mesh, search);
  }
  return search.result();
}

/// Pad of the swept box: the cast's contact tolerance at the largest scale any triangle can
/// give (a triangle's size is at most √3 × the mesh's largest |coordinate|), since a reported
/// impact leaves the shapes up to that far apart, plus the rounding of the boxes (1000 ulps of
/// Real × the coordinates' magnitude, as mesh distance's boxSlack).
double sweptPad(const Mesh& mesh, const Aabb& box, const Vec3& motion, double pairScale) {
  const double meshSize = std::sqrt(3.0) * maxAbs(mesh.bounds());
  const double tolerance = kCastRelativeTolerance * (pairScale + meshSize) * (1 + 1e-6);
  const double magnitude = maxAbs(mesh.bounds()) + maxAbs(box) + double(motion.cwiseAbs().maxCoeff()) +
                           double((box.max - box.min).maxCoeff());
  return tolerance + double(kMeshFeatureRelativeTolerance) * magnitude;
}

std::optional<MeshCastHit> linearCast(const Mesh& mesh, const Transform& meshPose, const ConvexShape& shape,
                                      const Transform& shapePose, const Vec3& motion, QueryPath path,
                                      bool stopAtFirst) {
  const Transform rel = meshPose.inverse() * shapePose;
  const Aabb sb = mesh_detail::shapeBoundsIn(shape, rel);
  const Vec3 localMotion = meshPose.rotation.conjugate() * motion;
  const double scale = double(shape.size()) +
                       (shapePose.translation - meshPose.translation).cast<double>().norm() +
                       motion.cast<double>().norm();
  const double pad = sweptPad(mesh, sb, localMotion, scale);
  const SweptBox box(sb, localMotion, pad);
  const detail::SweptSeparation cull(shape, rel, localMotion, pad);
  const auto castTriangle = [&](const Triangle& tri, const CastOptions& o) {
    return cast(shape, shapePose, motion, ConvexShape(tri), meshPose, o);
  };
  return run(mesh, castTriangle, box, &cull, path, stopAtFirst);
}

std::optional<MeshCastHit> rigidCast(const Mesh& mesh, const Transform& meshPose, const ConvexShape& shape,
                                     const RigidMotion& motion, QueryPath path, bool stopAtFirst) {
  // The shape stays within its size r of its moving origin, which goes linearly from c0 to c1.
  const Transform inv = meshPose.inverse();
  const Vec3 c0 = inv.apply(motion.start.translation), c1 = inv.apply(motion.end.translation);
  const Real r = shape.size();
  const Aabb sb{c0.array() - r, c0.array() + r};
  const double scale = double(r) + (motion.start.translation - meshPose.translation).cast<double>().norm() +
                       (motion.end.translation - motion.start.translation).cast<double>().norm() + M_PI * double(r);
  const SweptBox box(sb, c1 - c0, sweptPad(mesh, sb, c1 - c0, scale));
  const auto castTriangle = [&](const Triangle& tri, const CastOptions& o) {
    return cast(shape, motion, ConvexShape(tri), meshPose, o);
  };
  return run(mesh, castTriangle, box, nullptr, path, stopAtFirst);
}

}  // namespace

std::optional<MeshCastHit> castClosest(const Mesh& mesh, const Transform& meshPose, const ConvexShape& shape,
                                       const Transform& shapePose, const Vec3& motion, QueryPath path) {
  if (!detail::entryPreconditions("castClosest(Mesh, ConvexShape)", detail::rule::kCast, meshPose, shape, shapePose, motion))
    return std::nullopt;
  return linearCast(mesh, meshPose, shape, shapePose, motion, path, false);
}

std::optional<MeshCastHit> castClosest(const Mesh& mesh, const Transform& meshPose, const ConvexShape& shape,
                                       const RigidMotion& motion, QueryPath path) {
  if (!detail::entryPreconditions("castClosest(Mesh, ConvexShape, RigidMotion)", detail::rule::kCast, meshPose, shape, motion))
    return std::nullopt;
  return rigidCast(mesh, meshPose, shape, motion, path, false);
}

bool castAny(const Mesh& mesh, const Transform& meshPose, const ConvexShape& shape, const Transform& shapePose,
             const Vec3& motion, QueryPath path) {
  if (!detail::entryPreconditions("castAny(Mesh, ConvexShape)", detail::rule::kCast, meshPose, shape, shapePose, motion)) return false;
  return linearCast(mesh, meshPose, shape, shapePose, motion, path, true).has_value();
}

bool castAny(const Mesh& mesh, const Transform& meshPose, const ConvexShape& shape, const RigidMotion& motion,
             QueryPath path) {
  if (!detail::entryPreconditions("castAny(Mesh, ConvexShape, RigidMotion)", detail::rule::kCast, meshPose, shape, motion))
    return false;
  return rigidCast(mesh, meshPose, shape, motion, path, true).has_value();
}

}  // namespace crux
