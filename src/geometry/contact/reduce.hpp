// The 4-point manifold reduction, one rule for every manifold: a pair's clipped points
// (contact.cpp, box_triangle_contact.cpp) and a mesh's merged points (mesh/contact/contact_stages.hpp).
#pragma once

#include <crux/geometry/contact.hpp>

#include <algorithm>
#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace crux::contact_detail {

/// The 4-point manifold reduction (Gregorius, "Robust Contact Creation for Physics Simulations",
/// GDC 2015: deepest, farthest, largest triangle, largest quadrilateral). Of the n points of
/// `pts` (indexable, pts[i] for i < n) select, in this order:
///   1. the deepest: smallest `sep(p)`; ties by the lower `key(p)` (a mesh's triangle index; a
///      constant for one pair), then the first;
///   2. the farthest from it, when farther than `tol`;
///   3. the point of largest |area| with those two about the axis `axis(deepest)` (a unit vector),
///      when above tol × the first two's distance;
///   4. the point adding most area outside that triangle's edges, above the same bound.
/// It stops early when the next point adds nothing: coincident or collinear within `tol` (>= 0;
/// 0 keeps every point that adds any area). `pos(p)` is the position (Eigen::Vector3d). Among
/// equals the first wins at every step. Writes the indices to `sel` and returns their count
/// (0 for n = 0, else 1 to 4).
template <class Points, class Pos, class Sep, class Key, class Axis>
int selectFour(const Points& pts, int n, double tol, const Pos& pos, const Sep& sep, const Key& key, const Axis& axis,
               int sel[4]) {
  using V3 = Eigen::Vector3d;
  if (n <= 0) return 0;
  sel[0] = 0;
  for (int i = 1; i < n; ++i)
    if (sep(pts[i]) < sep(pts[sel[0]]) || (sep(pts[i]) == sep(pts[sel[0]]) && key(pts[i]) < key(pts[sel[0]])))
      sel[0] = i;
  const auto P = [&](int i) -> V3 { return pos(pts[i]); };
  const V3 p0 = P(sel[0]);
  double best = tol * tol;
  sel[1] = -1;
  for (int i = 0; i < n; ++i)
    if ((P(i) - p0).squaredNorm() > best) {
      best = (P(i) - p0).squaredNorm();
      sel[1] = i;
    }
  if (sel[1] < 0) return 1;
  const V3 u = axis(pts[sel[0]]);
  const V3 e01 = P(sel[1]) - p0;
  const double areaTol = tol * e01.norm();
  const auto area = [&](int i) { return e01.cross(P(i) - p0).dot(u); };
  double a2 = areaTol;
  sel[2] = -1;
  for (int i = 0; i < n; ++i)
    if (std::abs(area(i)) > a2) {
      a2 = std::abs(area(i));
      sel[2] = i;
    }
  if (sel[2] < 0) return 2;
  const double orient = area(sel[2]) > 0 ? 1 : -1;
  const V3 corner[3] = {p0, P(sel[1]), P(sel[2])};
  double g3 = areaTol;
  sel[3] = -1;
  for (int i = 0; i < n; ++i) {
    double gain = 0;  // the area outside the triangle's edges
    for (int e = 0; e < 3; ++e) {
      const V3& a = corner[e];
      gain = std::max(gain, -orient * (corner[(e + 1) % 3] - a).cross(P(i) - a).dot(u));
    }
    if (gain > g3) {
      g3 = gain;
      sel[3] = i;
    }
  }
  return sel[3] < 0 ? 3 : 4;
}

/// A pair's manifold reduced in place (selectFour with one axis `u` and no key): unchanged when it
/// has at most ContactManifold::kMaxContactPoints points; else the selected points move to the
/// front, in selectFour's order, and count becomes their number.
template <class Point, class Pos, class Sep>
void reduceToFour(Point* pts, int& count, const Eigen::Vector3d& u, double tol, const Pos& pos, const Sep& sep) {
  if (count <= ContactManifold::kMaxContactPoints) return;
  int sel[4];
  const int kept = selectFour(
      pts, count, tol, pos, sep, [](const Point&) { return 0; }, [&](const Point&) { return u; }, sel);
  Point keep[4];
  for (int k = 0; k < kept; ++k) keep[k] = pts[sel[k]];
  for (int k = 0; k < kept; ++k) pts[k] = keep[k];
  count = kept;
}

}  // namespace crux::contact_detail
