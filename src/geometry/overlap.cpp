/// @file overlap.cpp  Boolean overlap of the non-triangle shape pairs (spheres, boxes, planes).
///
/// Each test is a comparison of division-free polynomials of the inputs evaluated in Wide, so
/// integer-grid inputs (|coordinates| <= 64, OBB axes signed unit vectors) get the exact answer
/// (see overlap.hpp and docs/geometry.md). Closed sets: every comparison accepts equality.

#include <algorithm>
#include <cmath>
#include <crux/geometry/overlap.hpp>

namespace crux {
namespace {

using WMat3 = Eigen::Matrix<Wide, 3, 3>;

/// An oriented box in Wide: centre, orthonormal axes (columns), half extents.
struct WideBox {
  WVec3 center;
  WMat3 axes;
  WVec3 half;
};

WideBox wideBox(const Obb& b) { return {wide(b.center), b.axes.cast<Wide>(), wide(b.half)}; }

/// The AABB as an oriented box; (min ± max)/2 are exact in Wide (halving is exact).
WideBox wideBox(const Aabb& b) {
  const WVec3 lo = wide(b.min), hi = wide(b.max);
  return {(lo + hi) * Wide(0.5), WMat3::Identity(), (hi - lo) * Wide(0.5)};
}

/// Separating-axis test of two oriented boxes (Gottschalk, Lin & Manocha, "OBBTree", SIGGRAPH
/// 1996; RTCD 4.4.1) over the 15 axes A_i, B_j and A_i × B_j. Unlike the book's code, the cross
/// axes are products of one axis of each box, and every projection is taken in world space onto
/// the unnormalised axis L: the boxes are separated on L iff |T·L| > Σ a_k|A_k·L| + Σ b_k|B_k·L|.
/// A cross axis with |L|² <= kParallelAxisTolerance·|A_i|²|B_j|² is skipped: for exactly
/// parallel edges it is the zero vector (separation then shows on a face axis), and for nearly
/// parallel ones its direction is rounding noise.
bool boxesOverlap(const WideBox& a, const WideBox& b) {
  const WVec3 t = b.center - a.center;
  // Radius of a box's projection onto L, given the dot products of its axes with L.
  const auto radius = [](const WVec3& half, const WVec3& dots) { return half.dot(dots.cwiseAbs()); };
  // Face axes of A: A_i. The projections of all six axes onto A_i are the entries of the
  // Gram matrix AᵀA and of R = AᵀB.
  const WMat3 gramA = a.axes.transpose() * a.axes;
  const WMat3 gramB = b.axes.transpose() * b.axes;
  const WMat3 r = a.axes.transpose() * b.axes;  // r(i, j) = A_i·B_j
  const WVec3 ta = a.axes.transpose() * t, tb = b.axes.transpose() * t;
  for (int i = 0; i < 3; ++i) {
    const Wide reach = radius(a.half, gramA.col(i)) + radius(b.half, r.row(i).transpose());
    if (std::abs(ta[i]) > reach) return false;
  }
  for (int j = 0; j < 3; ++j) {
    const Wide reach = radius(a.half, r.col(j)) + radius(b.half, gramB.col(j));
    if (std::abs(tb[j]) > reach) return false;
  }
  // Cross axes A_i × B_j. A_i·L = B_j·L = 0, so only the other two axes of each box reach.
  for (int i = 0; i < 3; ++i) {
    const WVec3 ai = a.axes.col(i);
    for (int j = 0; j < 3; ++j) {
      const WVec3 bj = b.axes.col(j);
      const WVec3 l = ai.cross(bj);
      if (l.squaredNorm() <= kParallelAxisTolerance * gramA(i, i) * gramB(j, j)) continue;
      const int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
      const Wide reach = a.half[i1] * std::abs(a.axes.col(i1).dot(l)) + a.half[i2] * std::abs(a.axes.col(i2).dot(l)) +
                         b.half[j1] * std::abs(b.axes.col(j1).dot(l)) + b.half[j2] * std::abs(b.axes.col(j2).dot(l));
      if (std::abs(t.dot(l)) > reach) return false;
    }
  }
  return true;
}

}  // namespace

bool overlaps(const Sphere& a, const Sphere& b) {
  const Wide r = Wide(a.radius) + Wide(b.radius);
  return (wide(a.center) - wide(b.center)).squaredNorm() <= r * r;
}

bool overlaps(const Sphere& s, const Aabb& b) {
  Wide d2 = 0;
  for (int i = 0; i < 3; ++i) {
    const Wide c = s.center[i];
    Wide excess = 0;
    if (c < b.min[i]) {
      excess = Wide(b.min[i]) - c;
    } else if (c > b.max[i]) {
      excess = c - Wide(b.max[i]);
    }
    d2 += excess * excess;
  }
  const Wide r = s.radius;
  return d2 <= r * r;
}

bool overlaps(const Sphere& s, const Obb& b) {
  const WVec3 d = wide(s.center) - wide(b.center);
  Wide d2 = 0;
  for (int i = 0; i < 3; ++i) {
    const Wide excess = std::abs(d.dot(wide(Vec3(b.axes.col(i))))) - Wide(b.half[i]);
    if (excess > 0) d2 += excess * excess;
  }
  const Wide r = s.radius;
  return d2 <= r * r;
}

bool overlaps(const Sphere& s, const Plane& p) {
  const WVec3 n = wide(p.normal);
  const Wide dist = n.dot(wide(s.center)) - Wide(p.d);  // |n| times the signed distance
  const Wide r = s.radius;
  return dist * dist <= r * r * n.squaredNorm();
}

bool overlaps(const Aabb& a, const Aabb& b) {
  return (a.min.array() <= b.max.array()).all() && (b.min.array() <= a.max.array()).all();
}

bool overlaps(const Aabb& a, const Obb& b) { return boxesOverlap(wideBox(a), wideBox(b)); }

bool overlaps(const Aabb& b, const Plane& p) {
  // n·x over the box spans [lo, hi], reached at the corners picked by the signs of n.
  Wide lo = 0, hi = 0;
  for (int i = 0; i < 3; ++i) {
    const Wide n = p.normal[i];
    const Wide atMin = n * Wide(b.min[i]), atMax = n * Wide(b.max[i]);
    lo += std::min(atMin, atMax);
    hi += std::max(atMin, atMax);
  }
  const Wide d = p.d;
  return lo <= d && d <= hi;
}

bool overlaps(const Obb& a, const Obb& b) { return boxesOverlap(wideBox(a), wideBox(b)); }

bool overlaps(const Obb& b, const Plane& p) {
  const WVec3 n = wide(p.normal);
  const Wide dist = n.dot(wide(b.center)) - Wide(p.d);
  Wide reach = 0;
  for (int i = 0; i < 3; ++i) reach += Wide(b.half[i]) * std::abs(n.dot(wide(Vec3(b.axes.col(i)))));
  return std::abs(dist) <= reach;
}

bool overlaps(const Plane& a, const Plane& b) {
  const WVec3 na = wide(a.normal), nb = wide(b.normal);
  if (na.cross(nb) != WVec3::Zero()) return true;  // not parallel: the planes meet in a line
  // Parallel (nb = k·na): coincident iff d_a·nb = d_b·na, compared without dividing by k.
  return Wide(a.d) * nb == Wide(b.d) * na;
}

}  // namespace crux
