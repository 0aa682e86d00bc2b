#pragma once
/// @file triangle_class.hpp  The one classification of a triangle's shape that every
/// narrow-phase routine uses (sphere, capsule, box and convex contacts, triangle–triangle
/// distance; closestPoint(Triangle) takes its thin line and decides degeneracy exactly): by its
/// doubled area |m| = |(b−a)×(c−a)| against its longest edge
/// squared L², i.e. by its smallest height h = |m|/L relative to L. The lines are drawn by
/// rounding, not by taste: a normal computed in double from m is tilted by about
/// 0.3·eps_double·L²/|m| (measured, worst of 2e5 random slivers).

#include <crux/math.hpp>

#include <limits>

namespace crux {

/// h <= this × L: the triangle is the segment or point it spans (within 1e-10 × L, far below
/// every tolerance of the narrow phase); it has no face (its computed normal would be tilted by
/// up to ~1e-6) and no normal axis.
inline constexpr double kTriangleDegenerateRelative = 1e-10;

/// h <= this × L (and not degenerate): a thin triangle. RTCD 5.1.5's region tests cancel on it
/// (products of a tiny edge with long ones), so its closest points come from its boundary and the
/// projection along its normal of the two shorter edges (closest_point_internal.hpp,
/// closestOnSliver), and its unit-normal plane rejects are skipped.
inline constexpr double kTriangleThinRelative = 1e-3;

/// Rounding budget, in ulps of Real × the pair's coordinate scale, within which a reference
/// feature of a contact manifold must place the points projected onto it (they are returned as
/// Real, whose own rounding is one ulp): used for thin faces (below) and near-parallel edges.
inline constexpr double kOnFeatureUlps = 8;

/// h >= this × L: the triangle may be a REFERENCE face of a contact manifold (or the named
/// feature against a shape without faces): its normal's tilt moves points projected onto it by
/// at most kOnFeatureUlps/2 Real ulps of L. Otherwise it is clipped as its supporting edge or
/// vertex (points used to land off such triangles). About 0.075 (a 1:13 triangle) in double
/// builds, about 1.4e-10 in float builds.
inline constexpr double kTriangleFaceRelative =
    0.3 * std::numeric_limits<double>::epsilon() /
    (0.5 * kOnFeatureUlps * double(std::numeric_limits<Real>::epsilon()));

/// The classes of one triangle (triangle_class.hpp's thresholds).
struct TriangleClass {
  bool degenerate = true;      ///< a segment or a point (kTriangleDegenerateRelative)
  bool thin = false;           ///< not degenerate, thinner than kTriangleThinRelative
  bool referenceFace = false;  ///< may be a manifold's reference face (kTriangleFaceRelative)
};

/// Whether a triangle of doubled area |(b−a)×(c−a)| and longest edge squared L² is no thicker
/// than kTriangleThinRelative (h <= kTriangleThinRelative × L, i.e. |m| <= k·L²), degenerate ones
/// included: the one thin line, for classifyTriangle and for closestPoint(Triangle) (which has
/// decided degeneracy exactly and sends every proper triangle under the line to its boundary).
inline bool belowThinLine(double doubledArea, double longestEdge2) {
  return doubledArea <= kTriangleThinRelative * longestEdge2;
}

/// Classifies a triangle from its doubled area |(b−a)×(c−a)| and its longest edge squared (both
/// computed in double by the caller). NaN input: degenerate.
inline TriangleClass classifyTriangle(double doubledArea, double longestEdge2) {
  TriangleClass c;
  c.degenerate = !(doubledArea > kTriangleDegenerateRelative * longestEdge2);
  c.thin = !c.degenerate && belowThinLine(doubledArea, longestEdge2);
  c.referenceFace = !c.degenerate && doubledArea >= kTriangleFaceRelative * longestEdge2;
  return c;
}

}  // namespace crux
