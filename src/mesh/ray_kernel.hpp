#pragma once
/// @file ray_kernel.hpp  Internal: a fast float filter in front of the exact ray–triangle test.
///
/// The line {o + s·d} meets the closed triangle abc only if the three edge triple products
/// e_ab = d·((a-o)×(b-o)), e_bc, e_ca (Plücker coordinates; Woop, Benthin & Wald, JCGT 2013)
/// share a weak sign: two of them with strictly opposite signs prove a miss, for proper and
/// degenerate triangles alike. The filter evaluates them in Real as
/// e_ab = (b-a)·(d×(a-o)) (the same value: (a-o)×(b-o) = (a-o)×(b-a)), whose rounding error is
/// proportional to the edge length rather than to the distance from the origin, and reports
/// "certainly misses" only when the opposite signs exceed a forward error bound that covers
/// both its own rounding and the double-precision rounding of the geometry layer's evaluation.
/// So every ray that crux::raycast(Ray, Triangle) would hit still reaches it: the mesh queries
/// make exactly its decisions, only most misses are cheaper.

#include <crux/geometry/shapes.hpp>

#include <algorithm>
#include <limits>

namespace crux::mesh_detail {

/// Margin of the filter in units of ε·(magnitude of the products): its own evaluation has at
/// most 7 roundings (γ₇ ≈ 3.5ε of Real); 64ε leaves a wide margin.
inline constexpr Real kRayFilterMargin = 64 * std::numeric_limits<Real>::epsilon();
/// The same margin for the geometry layer's evaluation of d·((a-o)×(b-o)) in Wide (about 5
/// roundings of Wide, relative to 2·M²·|d|₁ with M the largest |coordinate of v - o|).
inline constexpr Wide kWideFilterMargin = 64 * std::numeric_limits<Wide>::epsilon();

class RayTriangleFilter {
 public:
  explicit RayTriangleFilter(const Ray& ray)
      : o_(ray.origin), d_(ray.dir), dNorm1_(ray.dir.cwiseAbs().sum()), dNormInf_(ray.dir.cwiseAbs().maxCoeff()) {}

  /// True only if the ray certainly misses the closed triangle t.
  bool certainlyMisses(const Triangle& t) const {
    const Vec3 a = t.a - o_, b = t.b - o_, c = t.c - o_;
    const Vec3 ab = t.b - t.a, bc = t.c - t.b, ca = t.a - t.c;
    const Real eab = ab.dot(d_.cross(a));
    const Real ebc = bc.dot(d_.cross(b));
    const Real eca = ca.dot(d_.cross(c));
    const Real lo = std::min(eab, std::min(ebc, eca));
    const Real hi = std::max(eab, std::max(ebc, eca));
    if (!(lo < 0 && hi > 0)) return false;
    // |error of ℓ·(d×u)| <= c·ε·|ℓ|₁·2·|d|∞·|u|∞ for each edge ℓ; bound all three at once.
    const Real m = std::max(a.cwiseAbs().maxCoeff(), std::max(b.cwiseAbs().maxCoeff(), c.cwiseAbs().maxCoeff()));
    const Real edges = std::max(ab.cwiseAbs().sum(), std::max(bc.cwiseAbs().sum(), ca.cwiseAbs().sum()));
    const Real own = kRayFilterMargin * 2 * edges * dNormInf_ * m;
    const Real geometry = Real(kWideFilterMargin * 2 * Wide(m) * Wide(m) * Wide(dNorm1_));
    const Real bound = std::max(own, geometry) * (1 + kRayFilterMargin);
    return lo < -bound && hi > bound;
  }

 private:
  Vec3 o_, d_;
  Real dNorm1_, dNormInf_;
};

}  // namespace crux::mesh_detail
