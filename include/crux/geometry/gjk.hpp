#pragma once
/// @file gjk.hpp  Distance, closest points, penetration depth and overlap of two convex shapes
/// under rigid transforms: GJK with the signed-volume subalgorithm, EPA when the cores overlap.
///
/// - GJK: Gilbert, Johnson, Keerthi, IEEE J. Robotics & Automation 1988, with the signed-volume
///   distance subalgorithm of Montanari, Petrinic, Barbieri, ACM TOG 36(3) 2017 (robust on
///   degenerate simplices), run on the polytope cores in double precision.
/// - EPA: the expanding polytope algorithm of van den Bergen (GDC 2001 / "Collision Detection in
///   Interactive 3D Environments" 2003), for the penetration depth of overlapping cores.
/// - Sphere/capsule pairs (point and segment cores) take the closed-form segment–segment closest
///   points (Ericson, RTCD 5.1.9) instead of GJK.
///
/// Sign and normal convention: `distance` > 0 is the separation, < 0 minus the penetration depth;
/// `normal` is the unit direction from B to A (moving A by -distance·normal makes the shapes
/// touch), and pointA - pointB = distance·normal. Queries never throw and never allocate; they
/// assume validated shapes (validate(...)) and unit rotations.
///
/// Poses: a rotation within kAxisAlignedRotationTolerance of one of the 24 axis-aligned rotations
/// (axis_aligned.hpp, the model and mesh layers' rule) is applied as its exact signed permutation,
/// so integer-grid shapes under quarter and half turns keep exact coordinates.

#include <crux/geometry/convex.hpp>

namespace crux {

/// How a distance query ended.
enum class GjkStatus : std::uint8_t {
  Separated,    ///< cores apart: distance from GJK (or closed form)
  Penetrating,  ///< cores overlap: depth from EPA
  Flat,         ///< cores overlap and their Minkowski difference is flat: core depth 0
  IterationCap  ///< an iteration cap was hit: best answer so far (never seen in the tests)
};

/// Result of distance(a, ta, b, tb). World coordinates.
struct DistanceResult {
  Real distance = 0;              ///< signed: separation (> 0) or -penetration depth
  Vec3 pointA = Vec3::Zero();     ///< closest (or deepest) point of A
  Vec3 pointB = Vec3::Zero();     ///< closest (or deepest) point of B
  Vec3 normal = Vec3::UnitZ();    ///< unit, from B to A
  int iterations = 0;             ///< GJK + EPA iterations
  GjkStatus status = GjkStatus::Separated;
};

/// Relative convergence tolerance of GJK and EPA: iteration stops when the lower and upper
/// bounds of the distance differ by at most kGjkRelativeTolerance × distance + kGjkScaleTolerance
/// × (size of the shapes and their offset). Both in double, whatever Real is.
inline constexpr double kGjkRelativeTolerance = 1e-12;
/// Absolute part of the GJK/EPA tolerance, relative to the problem's length scale (the shapes'
/// sizes plus the distance between their origins): 1000 ulps of double.
inline constexpr double kGjkScaleTolerance = 1000 * std::numeric_limits<double>::epsilon();
/// Iteration caps (a polytope pair converges in far fewer; the caps only guard against cycling).
inline constexpr int kGjkMaxIterations = 64;
inline constexpr int kEpaMaxIterations = 64;

/// Signed distance, closest points and normal of A (at pose ta) and B (at pose tb). Shapes or
/// poses that are not queryable (precondition.hpp) give distance NaN.
DistanceResult distance(const ConvexShape& a, const Transform& ta, const ConvexShape& b, const Transform& tb);

/// True when A and B share a point (touching counts), decided by GJK alone (no EPA): the cores'
/// distance minus the radii is <= kGjkScaleTolerance × the problem's length scale.
bool overlaps(const ConvexShape& a, const Transform& ta, const ConvexShape& b, const Transform& tb);

}  // namespace crux
