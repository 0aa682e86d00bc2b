// The 4-point manifold reductions: reduceToFour for one pair's clipped points (contact.cpp,
// box_triangle_contact.cpp) and reduceMerged for the merged points of many triangles
// (mesh_contact.cpp).
#pragma once

#include <crux/geometry/contact.hpp>

#include <algorithm>
#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace crux::contact_detail {

/// The 4-point manifold reduction of one pair's points (contact.cpp, box_triangle_contact.cpp;
/// reduceMerged below is the mesh's, over the points of many triangles): of count > 4 points keep the deepest (smallest separation, the first of
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

/// The 4-point reduction of a mesh manifold (mesh_contact.cpp), over the points of many triangles
/// that its merge stage has already merged within `tol`: the deepest (smallest separation; ties
/// by the lower `triangle`), then the farthest from it, then the point of largest |area| with
/// those two about the deepest point's normal, then the one adding most area outside that
/// triangle; it stops early when the next point adds nothing (no farther than tol, or no area
/// beyond tol × the first pair's distance: coincident or collinear within the merge tolerance).
/// `buf[i]` (i < n) is a Point, which has pointA and normal (vectors), separation and triangle.
/// The kept points are written to out in that order; returns their count (0 to 4).
template <class Points, class Point>
int reduceMerged(const Points& buf, int n, double tol, Point* out) {
  int count = 0;
  if (n == 0) return count;
  int sel[4] = {0, -1, -1, -1};
  for (int i = 1; i < n; ++i)
    if (buf[i].separation < buf[sel[0]].separation ||
        (buf[i].separation == buf[sel[0]].separation && buf[i].triangle < buf[sel[0]].triangle))
      sel[0] = i;
  out[count++] = buf[sel[0]];
  auto P = [&](int i) { return buf[i].pointA.template cast<double>(); };
  const Eigen::Vector3d u = buf[sel[0]].normal.template cast<double>();
  double best = tol * tol;
  for (int i = 0; i < n; ++i)
    if ((P(i) - P(sel[0])).squaredNorm() > best) {
      best = (P(i) - P(sel[0])).squaredNorm();
      sel[1] = i;
    }
  if (sel[1] < 0) return count;
  out[count++] = buf[sel[1]];
  const double areaTol = tol * (P(sel[1]) - P(sel[0])).norm();
  auto area = [&](int i) { return (P(sel[1]) - P(sel[0])).cross(P(i) - P(sel[0])).dot(u); };
  double a2 = areaTol;
  for (int i = 0; i < n; ++i)
    if (std::abs(area(i)) > a2) {
      a2 = std::abs(area(i));
      sel[2] = i;
    }
  if (sel[2] < 0) return count;
  out[count++] = buf[sel[2]];
  const double orient = area(sel[2]) > 0 ? 1 : -1;
  double g3 = areaTol;
  for (int i = 0; i < n; ++i) {
    double gain = 0;  // area outside the triangle's edges
    for (int e = 0; e < 3; ++e) {
      const Eigen::Vector3d a = P(sel[e]), b = P(sel[(e + 1) % 3]);
      gain = std::max(gain, -orient * (b - a).cross(P(i) - a).dot(u));
    }
    if (gain > g3) {
      g3 = gain;
      sel[3] = i;
    }
  }
  if (sel[3] >= 0) out[count++] = buf[sel[3]];
  return count;
}

}  // namespace crux::contact_detail
