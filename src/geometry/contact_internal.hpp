// Rules shared by the generic contact clipping (contact.cpp) and the closed-form triangle
// contacts (triangle_contact.cpp), which must classify triangle features and merge coincident
// points identically.
#pragma once

#include <crux/geometry/contact.hpp>
#include <crux/math.hpp>

#include <limits>

namespace crux::contact_detail {

/// Rounding budget, in ulps of Real × the pair's coordinate scale, within which a reference
/// feature must place the points projected onto it (they are returned as Real, whose own
/// rounding is one ulp): used for sliver triangles and near-parallel edge pairs.
inline constexpr double kOnFeatureUlps = 8;

/// A triangle's unit normal computed in double from (b−a)×(c−a) is tilted by about
/// 0.3·eps_double·L²/|(b−a)×(c−a)| (L its longest edge; measured, worst of 2e5 random slivers),
/// which moves points projected onto its plane by that × L. A triangle is used as a REFERENCE
/// face (or named as the feature against a shape without faces) only when this stays within
/// kOnFeatureUlps/2 Real ulps of L, i.e. when |(b−a)×(c−a)| >= kSliverAreaRatio·L²; a sliver is
/// clipped as its supporting edge or vertex instead (issue 6: points landed off sliver
/// triangles). About 0.075 (a 1:13 triangle) in double builds, about 4e-9 in float builds.
inline constexpr double kSliverAreaRatio =
    0.3 * std::numeric_limits<double>::epsilon() / (0.5 * kOnFeatureUlps * double(std::numeric_limits<Real>::epsilon()));

/// Removes the points of pts[0, count) that coincide with another on both bodies (pointA and
/// pointB within `tol` of it), keeping the deepest (smallest separation) of each such group, so
/// that an engine never gets two constraints at one place. Order is otherwise kept.
inline void removeCoincident(ContactPoint* pts, int& count, double tol) {
  int k = 0;
  for (int i = 0; i < count; ++i) {
    int same = -1;
    for (int j = 0; j < k && same < 0; ++j)
      if ((pts[i].pointA - pts[j].pointA).template cast<double>().norm() <= tol &&
          (pts[i].pointB - pts[j].pointB).template cast<double>().norm() <= tol)
        same = j;
    if (same < 0) pts[k++] = pts[i];
    else if (pts[i].separation < pts[same].separation) pts[same] = pts[i];
  }
  count = k;
}

}  // namespace crux::contact_detail
