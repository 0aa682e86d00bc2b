/// @file overlap.cpp  Boolean overlap of the non-triangle shape pairs (spheres, boxes, planes).
///
/// Each test is a comparison of division-free polynomials of the inputs. Sphere and plane pairs
/// read their signs through the exact judges (predicates.hpp: filter, then expansions), so they
/// are exact for any finite inputs; the box–box separating-axis test is evaluated in Wide, exact
/// for integer-grid inputs (|coordinates| <= 64, OBB axes signed unit vectors). See overlap.hpp
/// and docs/geometry.md. Closed sets: every comparison accepts equality.

#include "geometry/unchecked.hpp"

#include <algorithm>
#include <cmath>
#include <crux/geometry/overlap.hpp>
#include <crux/geometry/predicates.hpp>

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

bool unchecked::overlaps(const Sphere& a, const Sphere& b) {
  return robust::filtered([&](auto& judge) {
    using T = predicates::NumberOf<decltype(judge)>;
    const T r = T(Wide(a.radius)) + T(Wide(b.radius));
    return judge((robust::lift<T>(a.center) - robust::lift<T>(b.center)).squaredNorm() - r * r) <= 0;
  });
}

bool unchecked::overlaps(const Sphere& s, const Aabb& b) {
  return robust::filtered([&](auto& judge) {
    using T = predicates::NumberOf<decltype(judge)>;
    T d2 = T(Wide(0));
    for (int i = 0; i < 3; ++i) {
      const Real c = s.center[i];
      if (c < b.min[i]) {
        const T excess = T(Wide(b.min[i])) - T(Wide(c));
        d2 = d2 + excess * excess;
      } else if (c > b.max[i]) {
        const T excess = T(Wide(c)) - T(Wide(b.max[i]));
        d2 = d2 + excess * excess;
      }
    }
    const T r = T(Wide(s.radius));
    return judge(d2 - r * r) <= 0;
  });
}

bool unchecked::overlaps(const Sphere& s, const Obb& b) {
  // Distance in the box frame axesᵀ(c - center), the axes exactly as given.
  return robust::filtered([&](auto& judge) {
    using T = predicates::NumberOf<decltype(judge)>;
    const robust::V3<T> d = robust::lift<T>(s.center) - robust::lift<T>(b.center);
    T d2 = T(Wide(0));
    for (int i = 0; i < 3; ++i) {
      const T along = d.dot(robust::lift<T>(Vec3(b.axes.col(i))));
      const T excess = (judge(along) < 0 ? -along : along) - T(Wide(b.half[i]));
      if (judge(excess) > 0) d2 = d2 + excess * excess;
    }
    const T r = T(Wide(s.radius));
    return judge(d2 - r * r) <= 0;
  });
}

bool unchecked::overlaps(const Sphere& s, const Plane& p) {
  // (n·c - d)² <= r²|n|²: |n| times the signed distance against |n| times the radius.
  return robust::filtered([&](auto& judge) {
    using T = predicates::NumberOf<decltype(judge)>;
    const robust::V3<T> n = robust::lift<T>(p.normal);
    const T dist = n.dot(robust::lift<T>(s.center)) - T(Wide(p.d));
    const T r = T(Wide(s.radius));
    return judge(dist * dist - r * r * n.squaredNorm()) <= 0;
  });
}

bool unchecked::overlaps(const Aabb& a, const Aabb& b) {
  return (a.min.array() <= b.max.array()).all() && (b.min.array() <= a.max.array()).all();
}

bool unchecked::overlaps(const Aabb& a, const Obb& b) {
  return boxesOverlap(wideBox(a), wideBox(b));
}

bool unchecked::overlaps(const Aabb& b, const Plane& p) {
  // n·x over the box spans [lo, hi], reached at the corners picked by the signs of n.
  return robust::filtered([&](auto& judge) {
    using T = predicates::NumberOf<decltype(judge)>;
    T lo = T(Wide(0)), hi = T(Wide(0));
    for (int i = 0; i < 3; ++i) {
      const T n = T(Wide(p.normal[i]));
      const T atMin = n * T(Wide(b.min[i])), atMax = n * T(Wide(b.max[i]));
      const bool up = p.normal[i] >= 0;
      lo = lo + (up ? atMin : atMax);
      hi = hi + (up ? atMax : atMin);
    }
    const T d = T(Wide(p.d));
    return judge(lo - d) <= 0 && judge(hi - d) >= 0;
  });
}

bool unchecked::overlaps(const Obb& a, const Obb& b) {
  return boxesOverlap(wideBox(a), wideBox(b));
}

bool unchecked::overlaps(const Obb& b, const Plane& p) {
  return robust::filtered([&](auto& judge) {
    using T = predicates::NumberOf<decltype(judge)>;
    const robust::V3<T> n = robust::lift<T>(p.normal);
    const T dist = n.dot(robust::lift<T>(b.center)) - T(Wide(p.d));
    T reach = T(Wide(0));
    for (int i = 0; i < 3; ++i) {
      const T along = n.dot(robust::lift<T>(Vec3(b.axes.col(i))));
      reach = reach + T(Wide(b.half[i])) * (judge(along) < 0 ? -along : along);
    }
    return judge(dist - reach) <= 0 && judge(dist + reach) >= 0;
  });
}

bool unchecked::overlaps(const Plane& a, const Plane& b) {
  return robust::filtered([&](auto& judge) {
    using T = predicates::NumberOf<decltype(judge)>;
    const robust::V3<T> na = robust::lift<T>(a.normal), nb = robust::lift<T>(b.normal);
    if (!predicates::crossIsZero(judge, na, nb)) return true;  // not parallel: they meet in a line
    // Parallel (nb = k·na): coincident iff d_a·nb = d_b·na, compared without dividing by k.
    return predicates::nonzeroAxis(judge, T(Wide(a.d)) * nb - T(Wide(b.d)) * na) < 0;
  });
}

}  // namespace crux
