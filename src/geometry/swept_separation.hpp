#pragma once
/// @file swept_separation.hpp  Internal: separating axes of a convex shape under a linear motion
/// against a triangle, the per-triangle cull of the mesh casts (mesh_cast.cpp) before the
/// advancement (cast.hpp).
///
/// On any axis a, the shape translated by s·m (s in [0, 1]) and the triangle can be within a
/// distance p of each other only while their projections on a are within p·|a|: an interval of
/// s (the projections move by s·(m·a)). The intersection of these intervals over a set of axes
/// holds every s at which the shapes are within p, so its start is a lower bound of the time at
/// which the advancement, whose hits are within its contact tolerance δ <= p, can report a hit,
/// and an empty intersection means it reports none. (A cast stopped by kCastMaxIterations is the
/// exception: linear casts converge in a few steps, or about log2(1/kCastRelativeTolerance)/2 for
/// rounded shapes meeting tangentially, far from the cap; rigid casts may reach it, so the mesh
/// casts use this bound for linear motions only.) Any axis gives a valid bound (rounded axes
/// included: both projections use the same rounded vector); the axes below make it tight:
///   - the triangle's normal and its three in-plane edge normals (n × e_i);
///   - the shape's face normals (box: its three axes; a triangle: its normal);
///   - the cross products of the triangle's edges with the shape's edge directions (box: its
///     three axes; capsule: its segment; triangle: its edges).
/// For a box or a triangle these include every face normal of the Minkowski difference, so the
/// bound is the exact time of impact up to the pad (the separating-axis test of the swept
/// polytopes; Eberly, "Intersection of objects with linear and angular velocities using oriented
/// bounding boxes", 2008; Gottschalk et al. OBBTree, SIGGRAPH 1996, for the 15 box axes).
/// Spheres, capsules and hulls get a prism-like bound (hull edges are not enumerated).

#include "geometry/gjk_internal.hpp"

namespace crux::detail {

/// A convex shape placed in double, moving by s·motion, against triangles in the same frame.
class SweptSeparation {
 public:
  /// `pad`: the distance below which shapes count as touching (the caller's contact tolerance
  /// plus its rounding slack), absolute.
  SweptSeparation(const ConvexShape& shape, const Transform& pose, const Vec3& motion, double pad);

  /// Whether the moving shape comes within the pad of triangle (a, b, c) at some s in [0, 1];
  /// `entry` receives a lower bound of the first such s (in double). Stops testing axes once the
  /// entry passes `after` (then returns false): the caller has no use for later entries.
  bool enter(const Triangle& tri, double after, double& entry) const;

 private:
  /// Projection [lo, hi] of the shape at s = 0 on axis a (radius included).
  void project(const V3& a, double& lo, double& hi) const;

  Placed shape_;
  V3 m_;
  double pad_;
  int faceCount_ = 0, edgeCount_ = 0;
  V3 faces_[3], edges_[3];  // face normals and edge directions of the core
  V3 hullCentre_ = V3::Zero(), hullHalf_ = V3::Zero();  // hull: its box in its frame, placed
  double hullBall_ = 0;  // hull: radius of the ball about hullCentre_ holding it
};

}  // namespace crux::detail
