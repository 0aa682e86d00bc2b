// The 4-point manifold reduction of one pair's clipped points (contact.cpp,
// box_triangle_contact.cpp).
#pragma once

#include <crux/geometry/contact.hpp>

#include <algorithm>
#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace crux::contact_detail {

/// The 4-point manifold reduction of one pair's points (contact.cpp, box_triangle_contact.cpp;
/// the mesh's, over the points of many triangles, is mesh_contact.cpp's): of count > 4 points keep the deepest (smallest separation, the first of
/// equals), the one farthest from it, and the two of largest and smallest signed area about the
/// axis u with those two; when all lie on one side, the one of largest |area| and then the point
/// adding most area outside that triangle. `pos(p)` is point p's position (double) and `sep(p)`
/// its separation. The kept four move to the front, in that order; count becomes 4.
template <class Point, class Pos, class Sep>
void reduceToFour(Point* pts, int& count, const Eigen::Vector3d& u, const Pos& pos, const Sep& sep) {
  using V3 = Eigen::Vector3d;
  if (count <= ContactManifold::kMaxContactPoints) return;
  const auto P = [&](int i) -> V3 { return pos(pts[i]); };
  int sel[4] = {0, -1, -1, -1};
  for (int i = 1; i < count; ++i)
    if (sep(pts[i]) < sep(pts[sel[0]])) sel[0] = i;
  double best = -1;
  for (int i = 0; i < count; ++i)
    if (i != sel[0] && (P(i) - P(sel[0])).squaredNorm() > best) {
      best = (P(i) - P(sel[0])).squaredNorm();
      sel[1] = i;
    }
  const auto area = [&](int i) { return (P(sel[1]) - P(sel[0])).cross(P(i) - P(sel[0])).dot(u); };
  int hi = -1, lo = -1;
  for (int i = 0; i < count; ++i) {
    if (i == sel[0] || i == sel[1]) continue;
    if (hi < 0 || area(i) > area(hi)) hi = i;
    if (lo < 0 || area(i) < area(lo)) lo = i;
  }
  sel[2] = hi;
  sel[3] = lo;
  if (lo == hi || area(hi) <= 0 || area(lo) >= 0) {  // all on one side: the largest triangle + the best 4th
    sel[2] = std::abs(area(hi)) >= std::abs(area(lo)) ? hi : lo;
    sel[3] = -1;
    double bestGain = -1;
    for (int i = 0; i < count; ++i) {
      if (i == sel[0] || i == sel[1] || i == sel[2]) continue;
      double gain = 0;  // the largest |area| outside one of the triangle's edges
      for (int e = 0; e < 3; ++e) {
        const V3 a = P(sel[e]), b = P(sel[(e + 1) % 3]);
        gain = std::max(gain, std::abs((b - a).cross(P(i) - a).dot(u)));
      }
      if (gain > bestGain) {
        bestGain = gain;
        sel[3] = i;
      }
    }
  }
  Point kept[4];
  for (int k = 0; k < 4; ++k) kept[k] = pts[sel[k]];
  for (int k = 0; k < 4; ++k) pts[k] = kept[k];
  count = 4;
}


}  // namespace crux::contact_detail
