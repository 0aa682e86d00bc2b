#pragma once
/// @file triangle_colliders.hpp  Internal: the per-shape colliders of contacts(Mesh, ConvexShape),
/// one for each kind of convex shape against one candidate triangle of the mesh. Each has the same
/// members:
///   void collide(const CandidateTriangle&, InternalEdgeFilter&) const   its contacts with one
///       triangle (the per-shape rejects first), handed to the first stage (contact_stages.hpp);
///   const LocalShape& frame() const, bool mirrored() const   the shape in the frame it reports
///       points in, and whether that frame is left-handed against the mesh's;
///   void toMeshFrame(MeshContactManifold&) const   the reduced points back to the mesh frame;
///   bool touches(const Aabb&) const, [unsigned touches4(const WideBvhNode&) const],
///   bool leafTouches(const Triangle&) const   its BVH pruning (mesh_walk.hpp's visitor tests;
///       every one conservative: a triangle it rejects has no contact within the margin).
/// A new shape is one more collider and one more case in contacts()'s dispatch.

#include <crux/geometry/box_triangle_contact.hpp>
#include <crux/geometry/contact.hpp>
#include <crux/geometry/triangle_contact.hpp>
#include <crux/mesh/mesh_contact.hpp>

#include "geometry/unchecked.hpp"
#include "mesh/contact/contact_stages.hpp"
#include "mesh/contact/local_shape.hpp"
#include "mesh/node_tests.hpp"
#include "mesh/shape_bounds.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace crux::mesh_detail {

inline bool boxesOverlap(const Aabb& a, const Aabb& b) {
  return (a.min.array() <= b.max.array()).all() && (b.min.array() <= a.max.array()).all();
}

/// The query's reach in the mesh frame, shared by the colliders' BVH pruning: the shape's box
/// grown by `grow` (the margin and a rounding slack, boxSlack), and the rounded shapes' reach
/// from their core, (radius + grow) × (1 + 1000 ulps), squared.
struct QueryReach {
  Aabb box;
  Real grow = 0;
  Real reach2 = 0;
  QueryReach(const LocalShape& ls, Real margin) : box(ls.bounds()) {
    grow = margin + boxSlack(box);
    box.min.array() -= grow;
    box.max.array() += grow;
    const Real reach = (ls.radius + grow) * (1 + kMeshFeatureRelativeTolerance);
    reach2 = reach * reach;
  }
};

/// What the colliders that work in the mesh frame share: the shape there (frame(), never
/// mirrored), nothing to map back, the margin and the query's reach.
class MeshFrameCollider {
 public:
  MeshFrameCollider(const LocalShape& ls, Real margin) : ls_(ls), margin_(margin), reach_(ls, margin) {}
  const LocalShape& frame() const { return ls_; }
  bool mirrored() const { return false; }
  void toMeshFrame(MeshContactManifold&) const {}

 protected:
  const LocalShape& ls_;
  Real margin_;
  QueryReach reach_;
};

/// The sphere. Frame: the mesh frame. One point per triangle with its Voronoi region
/// (sphereTriangleContact, RTCD 5.1.5), handed on as InternalEdgeFilter::spherePoint. Prunes
/// nodes and triangles by the centre's distance to their boxes (RTCD 5.2.5), tighter than its
/// cube.
class SphereCollider : public MeshFrameCollider {
 public:
  using MeshFrameCollider::MeshFrameCollider;

  bool touches(const Aabb& bounds) const { return mesh_detail::boxSquaredDistance(bounds, ls_.p[0]) <= reach_.reach2; }
  unsigned touches4(const WideBvhNode& node) const {
    // (reach2 may be +inf for a huge sphere: unused lanes, whose keys are +inf too, are masked)
    return mesh_detail::laneMask((mesh_detail::boxSquaredDistances4(node, ls_.p[0]) <= reach_.reach2) &
                                 mesh_detail::usedLanes(node));
  }
  bool leafTouches(const Triangle& tri) const { return touches(bounds(tri)); }

  void collide(const CandidateTriangle& c, InternalEdgeFilter& out) const {
    SphereTriangleContact h;
    if (!unchecked::sphereTriangleContact(c.tri, ls_.p[0], ls_.radius, margin_, h)) return;
    MeshContactPoint p;
    p.pointA = h.pointA;
    p.pointB = h.pointB;
    p.normal = h.normal;
    p.separation = h.separation;
    p.triangle = c.index;
    p.featureB = featureId(FeatureKind::Vertex, 0);
    out.spherePoint(c, h, p);
  }
};

/// The capsule. Frame: the mesh frame. Up to two points per triangle (capsuleTriangleContacts,
/// segment–triangle closest points and reference clipping). Prunes nodes by its box and by its
/// segment's distance to the node box's circumscribed sphere (its box is loose when it is
/// tilted), triangles by its box.
class CapsuleCollider : public MeshFrameCollider {
 public:
  using MeshFrameCollider::MeshFrameCollider;

  bool touches(const Aabb& bounds) const {
    if (!boxesOverlap(bounds, reach_.box)) return false;
    const Vec3 &centre = ls_.p[0], &end = ls_.p[1];
    const Vec3 c = Real(0.5) * (bounds.min + bounds.max);
    const Real e = Real(0.5) * (bounds.max - bounds.min).norm() * (1 + 4 * std::numeric_limits<Real>::epsilon());
    const Vec3 ab = end - centre;
    const Real l2 = ab.squaredNorm();
    const Real t = l2 > 0 ? std::clamp(ab.dot(c - centre) / l2, Real(0), Real(1)) : Real(0);
    const Real lim = std::sqrt(reach_.reach2) + e;
    return (centre + t * ab - c).squaredNorm() <= lim * lim;
  }
  bool leafTouches(const Triangle& tri) const { return boxesOverlap(bounds(tri), reach_.box); }

  void collide(const CandidateTriangle& c, InternalEdgeFilter& out) const {
    ContactManifold m;
    if (unchecked::capsuleTriangleContacts(c.tri, ls_.p[0], ls_.p[1], ls_.radius, margin_, m)) out.manifold(c, c.tri, m);
  }
};

/// The box. Frame: the box's own (centre 0, identity axes; left-handed when the box's axes are,
/// mirrored()): each triangle is mapped there (double, rounded once), meets the box's face axes
/// (cheap), then the SAT routine (boxTriangleContacts); its points are filtered, merged and
/// reduced there and only the reduced ones mapped back (toMeshFrame). Prunes nodes by the
/// OBB–AABB SAT's six face axes (its axis-aligned box is loose when it is rotated), padded by the
/// margin and a rounding slack; its triangles meet the box's faces in collide().
class BoxCollider {
 public:
  BoxCollider(const LocalShape& ls, Real margin)
      : ls_(ls),
        margin_(margin),
        inItsFrame_(Obb{Vec3::Zero(), ls.half, Mat3::Identity()}),
        frame_(inItsFrame_, LocalShape::OwnFrame{}),
        reach_(ls.half.cast<double>().array() + double(margin) + ls.boxSlack),
        obb_(ls.axes, QueryReach(ls, margin).grow + kMeshFeatureRelativeTolerance * (ls.p[0].norm() + ls.half.norm())),
        placed_(obb_.place(ls.p[0], ls.half)) {}
  BoxCollider(const BoxCollider&) = delete;
  BoxCollider& operator=(const BoxCollider&) = delete;

  const LocalShape& frame() const { return frame_; }
  bool mirrored() const { return ls_.boxMirrored; }

  /// The reduced points from the box frame to the mesh frame (rounded once).
  void toMeshFrame(MeshContactManifold& out) const {
    const Eigen::Matrix3d R = ls_.boxToLocal.transpose();
    for (int i = 0; i < out.count; ++i) {
      MeshContactPoint& p = out.points[i];
      p.normal = (R * p.normal.cast<double>()).cast<Real>();
      p.pointA = (R * p.pointA.cast<double>() + ls_.boxCentre).cast<Real>();
      p.pointB = (R * p.pointB.cast<double>() + ls_.boxCentre).cast<Real>();
    }
  }

  bool touches(const Aabb& bounds) const { return obb_.touches(placed_, bounds); }
  /// touches on four boxes at once (per box the same answer).
  unsigned touches4(const WideBvhNode& node) const { return obb_.touches4(placed_, node); }
  bool leafTouches(const Triangle&) const { return true; }

  void collide(const CandidateTriangle& c, InternalEdgeFilter& out) const {
    const Triangle& tri = c.tri;
    const Eigen::Matrix3d& Rt = ls_.boxToLocal;
    const Eigen::Vector3d a = Rt * (tri.a.cast<double>() - ls_.boxCentre);
    const Eigen::Vector3d b = Rt * (tri.b.cast<double>() - ls_.boxCentre);
    const Eigen::Vector3d cc = Rt * (tri.c.cast<double>() - ls_.boxCentre);
    // the triangle beyond a face of the box by more than the margin
    const Eigen::Vector3d lo = a.cwiseMin(b).cwiseMin(cc), hi = a.cwiseMax(b).cwiseMax(cc);
    // one branch on the six comparisons (as six, each was mispredicted now and then)
    const bool beyond = int(lo.x() > reach_.x()) | int(lo.y() > reach_.y()) | int(lo.z() > reach_.z()) |
                        int(hi.x() < -reach_.x()) | int(hi.y() < -reach_.y()) | int(hi.z() < -reach_.z());
    if (beyond) return;
    // (no plane reject here: the routine's SAT tests the triangle's normal itself; that
    // prefilter rejected ~1% of the triangles the face axes leave on bunny00 and cost more)
    const Triangle tb{a.cast<Real>(), b.cast<Real>(), cc.cast<Real>()};
    // left uninitialised (boxTriangleContacts sets the normal, the count and the points it
    // reports; the filter reads no more): its default values were ~20 stores per call
    union Uninitialised {
      Uninitialised() {}
      ContactManifold m;
    } u;
    if (!unchecked::boxTriangleContacts(ls_.half, tb, margin_, u.m)) return;
    out.manifold(c, tb, u.m);
  }

 private:
  const LocalShape& ls_;
  Real margin_;
  ConvexShape inItsFrame_;  // the box centred at the origin with identity axes
  LocalShape frame_;        // it, in its own frame (support and projection there are exact)
  /// Half extents + margin + rounding slack (1000 ulps of Real × scale, LocalShape::boxSlack), in
  /// double: the face-axis reject of collide().
  Eigen::Vector3d reach_;
  ObbBoxTest obb_;
  ObbBoxTest::Placed placed_;
};

/// Any other convex shape (hull, triangle, cylinder, …). Frame: the mesh frame. The triangle's
/// plane first (a conservative reject), then the generic contact routine (contacts(ConvexShape,
/// …): GJK/EPA and reference clipping) with the shape at its relative pose; a triangle shape
/// under an axis-aligned rotation, mapped exactly, at the identity. Prunes nodes and triangles by
/// the shape's box.
class ConvexCollider : public MeshFrameCollider {
 public:
  using MeshFrameCollider::MeshFrameCollider;

  bool touches(const Aabb& bounds) const { return boxesOverlap(bounds, reach_.box); }
  bool leafTouches(const Triangle& tri) const { return boxesOverlap(bounds(tri), reach_.box); }

  void collide(const CandidateTriangle& c, InternalEdgeFilter& out) const {
    const Triangle& tri = c.tri;
    if (planeSeparates(tri)) return;
    ContactManifold m;
    const bool touching = ls_.aligned && ls_.shape.kind == ConvexKind::Triangle
                              ? contacts(ConvexShape(tri), Transform::identity(), ConvexShape(ls_.mappedTriangle),
                                         Transform::identity(), margin_, m)
                              : contacts(ConvexShape(tri), Transform::identity(), ls_.shape, ls_.rel, margin_, m);
    if (touching) out.manifold(c, tri, m);
  }

 private:
  /// Cheap conservative reject: the triangle's plane separates it from the shape by more than
  /// the margin (plus rounding slack), so the contact routine reports nothing.
  bool planeSeparates(const Triangle& tri) const {
    const Vec3 nl = (tri.b - tri.a).cross(tri.c - tri.a);
    const Real len = nl.norm();
    if (!(len > 0)) return false;
    const Vec3 face = nl / len;
    Real lo = 0, hi = 0;
    ls_.project(face, lo, hi);
    const Real base = face.dot(tri.a);
    const Real slack = kMeshFeatureRelativeTolerance *
                       (tri.a.cwiseAbs().maxCoeff() + ls_.rel.translation.cwiseAbs().maxCoeff() + ls_.shape.size() +
                        (tri.b - tri.a).norm() + (tri.c - tri.a).norm());
    return lo - base > margin_ + slack || base - hi > margin_ + slack;
  }
};

}  // namespace crux::mesh_detail
