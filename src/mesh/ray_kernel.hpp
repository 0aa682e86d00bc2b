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
/// make exactly its decisions, only most misses are cheaper. Symmetrically, three products of
/// one strict sign beyond the bound prove that the line crosses the interior of a proper
/// triangle, and the mesh kernel then skips the exact edge tests (properRayTriangleCrossing,
/// geometry/ray_triangle.hpp). Four triangles are classified at once, one per SIMD lane.

#include <crux/geometry/shapes.hpp>
#include <crux/mesh/mesh.hpp>

#include "lanes.hpp"

#include <algorithm>
#include <cstdint>
#include <limits>

namespace crux::mesh_detail {

/// Margin of the filter in units of ε·(magnitude of the products): its own evaluation has at
/// most 7 roundings (γ₇ ≈ 3.5ε of Real); 64ε leaves a wide margin.
inline constexpr Real kRayFilterMargin = 64 * std::numeric_limits<Real>::epsilon();
/// The same margin for the geometry layer's evaluation of d·((a-o)×(b-o)) in Wide (about 5
/// roundings of Wide, relative to 2·M²·|d|₁ with M the largest |coordinate of v - o|).
inline constexpr Wide kWideFilterMargin = 64 * std::numeric_limits<Wide>::epsilon();

/// The filter for one ray, four triangles at a time (one lane each, independent: a triangle's
/// verdict does not depend on its lane or its neighbours).
class RayTriangleFilter {
 public:
  /// The filter of the ray's line, its products taken about the ray's origin.
  explicit RayTriangleFilter(const Ray& ray)
      : ox_(ray.origin.x()), oy_(ray.origin.y()), oz_(ray.origin.z()), dx_(ray.dir.x()), dy_(ray.dir.y()),
        dz_(ray.dir.z()), dNorm1_(ray.dir.cwiseAbs().sum()), dNormInf_(ray.dir.cwiseAbs().maxCoeff()) {}

  /// The same filter with its products taken about o' ≈ the point of the line nearest `anchor`
  /// (a point among the triangles to come, e.g. the mesh's box centre). An edge product is the
  /// same about every point of the line (d × d = 0), so only o''s distance from the line, δ,
  /// enters the bound; but the products' rounding then scales with the triangles' distance
  /// from o' instead of from the origin, which is what keeps a far origin (a scene ray mapped
  /// into a model) from leaving near-edge triangles undecided. o' = o + s·d is formed in Wide
  /// and rounded to Real: |δ|∞ <= 4ε_W(|o|∞ + |s||d|∞) + ε_R|o'|∞. Falls back to o when any
  /// of it is not finite.
  RayTriangleFilter(const Ray& ray, const Vec3& anchor) : RayTriangleFilter(ray) {
    const WVec3 o = wide(ray.origin), d = wide(ray.dir);
    const Wide dd = d.squaredNorm();
    if (!(dd > 0) || !std::isfinite(dd)) return;
    const Wide s = d.dot(wide(anchor) - o) / dd;
    if (!std::isfinite(s)) return;
    const Vec3 shifted = (o + s * d).template cast<Real>();
    if (!shifted.allFinite()) return;
    const Wide delta = 4 * std::numeric_limits<Wide>::epsilon() *
                           (o.cwiseAbs().maxCoeff() + std::abs(s) * d.cwiseAbs().maxCoeff()) +
                       Wide(std::numeric_limits<Real>::epsilon()) * Wide(shifted.cwiseAbs().maxCoeff());
    const Wide shift = (wide(shifted) - o).cwiseAbs().maxCoeff();  // |o' − o|∞
    if (!std::isfinite(delta) || !std::isfinite(shift)) return;
    ox_ = shifted.x(), oy_ = shifted.y(), oz_ = shifted.z();
    constexpr Wide up = 1 + Wide(kRayFilterMargin);  // rounding the bounds up to Real
    delta_ = Real(delta * up);
    shift_ = Real(shift * up);
  }

  /// What the signs of the three edge products prove about the ray's line and a closed
  /// triangle: kMisses (two of opposite signs beyond the bound), kCrossesFront / kCrossesBack
  /// (all three of one strict sign beyond the bound: the line crosses the interior of a proper
  /// triangle, with d·n > 0 for kCrossesBack, n = (b − a) × (c − a), since d·n is their sum),
  /// or kUnknown.
  enum Verdict : std::uint8_t { kMisses, kCrossesFront, kCrossesBack, kUnknown };

  /// Four triangles' corners by coordinate, one triangle per lane.
  struct TriangleLanes {
    Lanes ax, ay, az, bx, by, bz, cx, cy, cz;
    /// Lanes from four triangles' corners (a lane may repeat another's triangle).
    static TriangleLanes gather(const Vec3* const (&a)[4], const Vec3* const (&b)[4], const Vec3* const (&c)[4]) {
      const auto lane = [](const Vec3* const (&v)[4], int k) {
        return Lanes{(*v[0])[k], (*v[1])[k], (*v[2])[k], (*v[3])[k]};
      };
      return {lane(a, 0), lane(a, 1), lane(a, 2), lane(b, 0), lane(b, 1), lane(b, 2), lane(c, 0), lane(c, 1), lane(c, 2)};
    }
  };

  /// The verdicts of four lanes as bit masks (bit j: lane j): kMisses, kCrossesBack and
  /// kCrossesFront; a lane in none of them is kUnknown.
  struct LaneVerdicts {
    unsigned misses, back, front;
    Verdict of(int j) const {
      return (misses >> j & 1u) ? kMisses : (back >> j & 1u) ? kCrossesBack : (front >> j & 1u) ? kCrossesFront : kUnknown;
    }
  };

  /// The verdicts of the four triangles of t.
  LaneVerdicts classify(const TriangleLanes& t) const {
    const Lanes &ax = t.ax, &ay = t.ay, &az = t.az, &bx = t.bx, &by = t.by, &bz = t.bz, &cx = t.cx, &cy = t.cy,
                &cz = t.cz;
    // e_ab = (b − a)·(d × (a − o)), and cyclically (the corners relative to the origin)
    const Lanes eab = edgeProduct(ax, ay, az, bx, by, bz);
    const Lanes ebc = edgeProduct(bx, by, bz, cx, cy, cz);
    const Lanes eca = edgeProduct(cx, cy, cz, ax, ay, az);
    const Lanes lo = lanesMin(eab, lanesMin(ebc, eca)), hi = lanesMax(eab, lanesMax(ebc, eca));
    // |error of ℓ·(d × u)| <= c·ε·|ℓ|₁·2·|d|∞·|u|∞ for each edge ℓ (bounded for all three at
    // once), and the same products' evaluation in Wide by the geometry layer, relative to
    // 2·M²·|d|₁ (M the largest |coordinate of v − o|); plus the smallest normal number, so that
    // an underflowed bound still covers the products' own underflow.
    const Lanes m = lanesMax(lanesMax(maxAbs3(ax - ox_, ay - oy_, az - oz_), maxAbs3(bx - ox_, by - oy_, bz - oz_)),
                             maxAbs3(cx - ox_, cy - oy_, cz - oz_));
    const Lanes edges = lanesMax(lanesMax(sumAbs3(bx - ax, by - ay, bz - az), sumAbs3(cx - bx, cy - by, cz - bz)),
                                 sumAbs3(ax - cx, ay - cy, az - cz));
    // About o' (see the anchored constructor): the products of the line through o' differ from
    // the true ones by at most |ℓ|₁·2·|d|∞·|δ|∞, and the geometry layer's |v − o| is at most
    // the |v − o'| above plus |o' − o|∞ (both 0 without an anchor).
    const Lanes own = kRayFilterMargin * 2 * edges * dNormInf_ * m + 2 * edges * dNormInf_ * delta_;
    const Lanes mo = (m + shift_) * (1 + kRayFilterMargin);
    const Lanes geometry = Real(kWideFilterMargin * 2) * mo * mo * dNorm1_;
    const Lanes bound = lanesMax(own, geometry) * (1 + kRayFilterMargin) + std::numeric_limits<Real>::min();
    return {laneMask((lo < -bound) & (hi > bound)), laneMask(lo > bound), laneMask(hi < -bound)};
  }

  /// The verdict of one triangle (classify with one lane used).
  Verdict classify(const Triangle& t) const {
    const Vec3* const a[4] = {&t.a, &t.a, &t.a, &t.a};
    const Vec3* const b[4] = {&t.b, &t.b, &t.b, &t.b};
    const Vec3* const c[4] = {&t.c, &t.c, &t.c, &t.c};
    return classify(TriangleLanes::gather(a, b, c)).of(0);
  }

 private:
  /// (q − p)·(d × (p − o)) per lane, p and q two corners.
  Lanes edgeProduct(const Lanes& px, const Lanes& py, const Lanes& pz, const Lanes& qx, const Lanes& qy,
                    const Lanes& qz) const {
    const Lanes ux = px - ox_, uy = py - oy_, uz = pz - oz_;
    const Lanes cx = dy_ * uz - dz_ * uy, cy = dz_ * ux - dx_ * uz, cz = dx_ * uy - dy_ * ux;
    return ((qx - px) * cx + (qy - py) * cy) + (qz - pz) * cz;
  }
  static Lanes maxAbs3(const Lanes& x, const Lanes& y, const Lanes& z) {
    return lanesMax(lanesAbs(x), lanesMax(lanesAbs(y), lanesAbs(z)));
  }
  static Lanes sumAbs3(const Lanes& x, const Lanes& y, const Lanes& z) {
    return (lanesAbs(x) + lanesAbs(y)) + lanesAbs(z);
  }

  Real ox_, oy_, oz_, dx_, dy_, dz_;  // o (or o' with an anchor) and d
  Real dNorm1_, dNormInf_;
  Real delta_ = 0;  // |o' − (the line's point)|∞, rounded up (0: o' = o)
  Real shift_ = 0;  // |o' − o|∞, rounded up
};

/// The triangles of slots [first, first + count) of a mesh's BVH through the filter, four at a
/// time (the corners gathered from the slot indices straight into the lanes; a triangle's verdict
/// does not depend on its lane): f(k, triangle, verdict) for each slot k the filter does not
/// reject, in slot order. False from f stops it, and is returned.
template <class F>
bool filterSlots(const RayTriangleFilter& filter, const Mesh& mesh, std::uint32_t first, std::uint32_t count, F&& f) {
  const Vec3* vertices = mesh.vertices().data();
  for (std::uint32_t k0 = first, end = first + count; k0 < end; k0 += 4) {
    const int n = int(std::min<std::uint32_t>(4, end - k0));
    const Vec3* a[4];
    const Vec3* b[4];
    const Vec3* c[4];
    for (int j = 0; j < 4; ++j) {  // unused lanes repeat the first triangle
      const TriangleIndices& t = mesh.slotIndices(k0 + std::uint32_t(j < n ? j : 0));
      a[j] = vertices + t[0], b[j] = vertices + t[1], c[j] = vertices + t[2];
    }
    const RayTriangleFilter::LaneVerdicts verdicts = filter.classify(RayTriangleFilter::TriangleLanes::gather(a, b, c));
    for (unsigned todo = ~verdicts.misses & ((1u << n) - 1); todo != 0; todo &= todo - 1) {
      const int j = __builtin_ctz(todo);
      if (!f(k0 + std::uint32_t(j), Triangle{*a[j], *b[j], *c[j]}, verdicts.of(j))) return false;
    }
  }
  return true;
}

}  // namespace crux::mesh_detail
