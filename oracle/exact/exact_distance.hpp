#pragma once
/// @file exact_distance.hpp  Internal: exact signed distances, witnesses and contacts between
/// convex cores and mesh triangles with exact (rational) coordinates. Included only by
/// oracle/exact/*.cpp; the public entry points are in exact.hpp ("distances and contacts").
///
/// Method (every comparison and construction exact, Epeck; rounded to double once at the end):
/// every convex operand is a CORE point set plus a radius (sphere: centre; capsule: its two
/// points; box: 8 corners; triangle: 3 corners, degenerate or not; hull: its vertices), placed
/// by an ExactRigid. The signed distance of two operands is that of the origin to the Minkowski
/// difference C = conv(A − B) of their cores, minus rA + rB:
///  - C's affine dimension is found exactly (point / segment / polygon / solid);
///  - solid C: CGAL::convex_hull_3 of the pairwise differences; origin strictly outside a facet's
///    plane: the closest point of C is the nearest of the facets' exact closest points
///    (Voronoi-region case analysis of a point against a triangle, Ericson, Real-Time Collision
///    Detection 5.1.5, in rationals); otherwise the origin is inside and the core penetration
///    depth is the smallest facet-plane distance (squared: (n·v)²/|n|², exact), its projection
///    on that facet the witness (depth 0: the cores touch);
///  - flat C (polygon: CGAL::convex_hull_2 in the coordinate plane of the normal's largest
///    component, fanned into triangles; segment: its two extreme points; a point): the closest
///    point, 0 when the origin lies in it (the cores overlap with depth 0: "Flat").
/// The witness x ∈ C is a convex combination Σ λk (a_ik − b_jk) of hull vertices, so the points
/// Σ λk a_ik ∈ A and Σ λk b_jk ∈ B realise it exactly.

#include "exact/exact.hpp"
#include "exact/exact_kernel.hpp"
#include "exact/exact_rigid.hpp"

#include <crux/geometry/convex.hpp>
#include <crux/mesh/mesh.hpp>

#include <CGAL/Bbox_3.h>

#include <cstdint>
#include <optional>
#include <vector>

namespace crux::exact::detail {

/// A convex operand placed exactly: its core points and its radius (exact: a double).
struct ExactCore {
  std::vector<Point> points;
  double radius = 0;
  CGAL::Bbox_3 box;  ///< encloses the core points (interval boxes)
};

/// The core of a crux convex shape placed by `pose` (box corners computed exactly).
ExactCore coreOf(const ConvexShape& shape, const ExactRigid& pose);
/// The core of a (possibly degenerate) triangle with exact corners (radius 0).
ExactCore coreOf(const Point& a, const Point& b, const Point& c);

/// How the cores of a pair meet (exact.hpp): Separated: squared = squared core distance (> 0);
/// Penetrating: squared core depth (> 0); Touching, Flat: depth 0.
using CoreRelation = Relation;

/// Exact signed distance of two cores (radii not included) with its witness points.
struct CoreDistance {
  CoreRelation relation = CoreRelation::Separated;
  FT squared = 0;       ///< squared core distance (Separated) or squared core depth (else)
  Point pointA, pointB; ///< witnesses on the cores: pointA − pointB = the witness of C
  Vector normal = Vector(0, 0, 1);  ///< from B to A, not unit (Flat: oriented by the centroids)
};

/// The exact core distance of A and B (both non-empty).
CoreDistance coreDistance(const ExactCore& a, const ExactCore& b);

/// Whether x's signed core distance is smaller than y's (exact).
bool closer(const CoreDistance& x, const CoreDistance& y);

/// Whether the signed distance (core distance − rA − rB) is <= margin (>= 0), decided exactly.
bool withinMargin(const CoreDistance& d, double radiusA, double radiusB, double margin);

/// A distance answer rounded to double: distance = ±sqrt(squared) − rA − rB, points moved to
/// the rounded surfaces along the unit normal (pointA − pointB = distance·normal).
struct RoundedDistance {
  double distance = 0;
  Vec3d pointA = Vec3d::Zero(), pointB = Vec3d::Zero();
  Vec3d normal = Vec3d::UnitZ();
  CoreRelation relation = CoreRelation::Separated;
};
RoundedDistance rounded(const CoreDistance& d, double radiusA, double radiusB);

/// Rounds an exact point to double (each coordinate within one ulp).
Vec3d toVec3d(const Point& p);

/// A point common to two overlapping cores of at most 3 points each (triangles, segments,
/// points): for mesh–mesh distance 0. Precondition: they overlap.
Point commonPoint(const ExactCore& a, const ExactCore& b);

/// exact::meshDistance (exact.hpp) with the meshes placed by exact transforms (model_distance:
/// the models' exactly composed world transforms).
std::optional<ExactDistance> meshDistance(const Mesh& a, const ExactRigid& ta, const Mesh& b, const ExactRigid& tb,
                                          double maxDistance);

/// exact::cast (exact.hpp) of two placed cores, A translated by s·motion (exact_cast.cpp).
ExactCastResult castCores(const ExactCore& a, const Vec3& motion, const ExactCore& b);
/// Exact squared Euclidean gap between two (interval) boxes: a lower bound of the squared
/// distance of whatever they enclose.
FT squaredGap(const CGAL::Bbox_3& a, const CGAL::Bbox_3& b);

}  // namespace crux::exact::detail
