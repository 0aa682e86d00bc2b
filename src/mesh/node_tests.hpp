#pragma once
/// @file node_tests.hpp  Internal: conservative BVH node culling tests for the mesh queries.
///
/// A node test may say "maybe" for a box that the query shape misses (a little extra work) but
/// must never say "no" for a box that contains a triangle the exact per-triangle test accepts;
/// otherwise the BVH path would disagree with the brute-force path. The tests run in Real and
/// pad every comparison so that rounding can only enlarge what they accept:
///  - kNodeBoxPad: boxes are grown by this fraction of the query's coordinate scale (the
///    largest magnitude among the mesh bounds and the query shape), which dominates the
///    absolute rounding of differences of coordinates in Real, and also the error of the
///    geometry layer's double-precision decisions on non-integer inputs;
///  - kSlabRoundingPad: relative pad on ray slab parameters (the slab arithmetic has a relative
///    error of at most 2·γ(3) ≈ 3ε; Ize, "Robust BVH Ray Traversal", JCGT 2013);
///  - kRayPruneSlack: relative (and, times the scale, absolute) slack when a node is pruned
///    because its entry distance is beyond the best hit, covering the difference between the
///    geometry layer's rounded t and the exact one, so a triangle whose reported t ties or
///    beats the best hit is never pruned away.

#include <crux/geometry/shapes.hpp>
#include <crux/mesh/bvh.hpp>

#include "lanes.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>

namespace crux::mesh_detail {

inline constexpr Real kEps = std::numeric_limits<Real>::epsilon();
/// Box growth in units of the query scale (64 ulps).
inline constexpr Real kNodeBoxPad = 64 * kEps;
/// Relative pad on ray slab parameters (8 ulps > 2·γ(3)).
inline constexpr Real kSlabRoundingPad = 8 * kEps;
/// Relative/absolute slack of the best-hit pruning (1024 ulps).
inline constexpr Real kRayPruneSlack = 1024 * kEps;
/// Added to |R_ij| in the OBB separating-axis test so near-parallel cross axes (whose rounded
/// direction may be garbage) can never separate (RTCD 4.4.1), 16 ulps.
inline constexpr Real kAxisPad = 16 * kEps;

/// Largest coordinate magnitude of a box.
inline Real maxAbs(const Aabb& b) { return std::max(b.min.cwiseAbs().maxCoeff(), b.max.cwiseAbs().maxCoeff()); }

/// 2^-⌊log2 m⌋ for a normal m > 0 whose result is normal too (read off the exponent bits; the
/// same value as ldexp(1, -ilogb(m))); 0 for any other m (zero, subnormal, inf, NaN, or a
/// result out of range), which the caller handles with ilogb and ldexp.
inline Real reciprocalPowerOfTwo(Real m) {
  using Bits = std::conditional_t<sizeof(Real) == 4, std::uint32_t, std::uint64_t>;
  constexpr int kMantissa = std::numeric_limits<Real>::digits - 1;
  constexpr Bits kExponentMask = (Bits(1) << (8 * sizeof(Real) - 1 - kMantissa)) - 1;
  constexpr Bits kBias = kExponentMask / 2;  // 127 or 1023
  Bits bits;
  std::memcpy(&bits, &m, sizeof bits);
  const Bits e = bits >> kMantissa;  // m > 0: no sign bit
  if (!(m > 0) || e < 1 || e > 2 * kBias - 1) return 0;
  const Bits r = (2 * kBias - e) << kMantissa;  // exponent bias − (e − bias)
  Real out;
  std::memcpy(&out, &r, sizeof out);
  return out;
}

/// A ray (or a segment as a ray with a distance limit) prepared for slab tests against boxes.
///
/// The direction is scaled by a power of two (exact) so its largest component lies in [1, 2):
/// slab parameters then neither overflow nor underflow for tiny or huge directions. A scaled
/// component that is zero gives ±inf inverses, and the resulting 0·inf = NaN (origin exactly on
/// a slab plane) is ignored by the NaN-dropping min/max below, which is the closed-slab answer;
/// a component that underflowed to a subnormal is treated as unbounded (NaN inverse). The
/// rounding pads are folded into the inverses (near planes ×(1-pad), far planes ×(1+pad)) and
/// distance limits are converted once into parameter limits, so a node test is 6 subtractions,
/// 6 multiplications and 6 comparisons.
class RayBoxTest {
 public:
  RayBoxTest(const Vec3& origin, const Vec3& dir, Real scale) {
    const Real m = dir.cwiseAbs().maxCoeff();
    // Scaling by 2^k is exact (unless a component underflows); one multiplier when 2^k is finite.
    // The three axes are set up together, one per lane (lane 3 unused).
    const Lanes raw = lanesOf(dir);
    Lanes d;
    if (const Real f = reciprocalPowerOfTwo(m); f != 0) {  // the usual case, from the exponent bits
      d = raw * f;
    } else {
      const int k = (m > 0 && std::isfinite(m)) ? -std::ilogb(m) : 0;
      if (k < std::numeric_limits<Real>::max_exponent) d = raw * std::ldexp(Real(1), k);
      else d = Lanes{std::ldexp(dir.x(), k), std::ldexp(dir.y(), k), std::ldexp(dir.z(), k), 0};
    }
    const Real pad = kNodeBoxPad * scale;
    const LaneBits negative = (LaneBits)d < 0;  // sign bits (−0 included: 1/−0 = −inf)
    Lanes inv = Real(1) / d;
    const Lanes nan = {std::numeric_limits<Real>::quiet_NaN(), std::numeric_limits<Real>::quiet_NaN(),
                       std::numeric_limits<Real>::quiet_NaN(), std::numeric_limits<Real>::quiet_NaN()};
    inv = lanesSelect((raw != 0) & (lanesAbs(d) < std::numeric_limits<Real>::min()), nan, inv);
    const Lanes invNear = inv * (1 - kSlabRoundingPad), invFar = inv * (1 + kSlabRoundingPad);
    const Lanes o = lanesOf(origin);
    const Lanes originNear = lanesSelect(negative, o - pad, o + pad);
    const Lanes originFar = lanesSelect(negative, o + pad, o - pad);
    const unsigned negativeAxes = laneMask(negative);
    for (int i = 0; i < 3; ++i) {
      const bool neg = negativeAxes >> i & 1u;
      // WideBvhNode's coordinate arrays: minX..minZ, maxX..maxZ, four Reals each
      nearOffset_[i] = 4 * (neg ? 3 + i : i);
      farOffset_[i] = 4 * (neg ? i : 3 + i);
      originNear_[i] = lanesBroadcast(originNear, i);
      originFar_[i] = lanesBroadcast(originFar, i);
      invNear_[i] = lanesBroadcast(invNear, i);
      invFar_[i] = lanesBroadcast(invFar, i);
    }
    const Vec3 scaled(d[0], d[1], d[2]);
    length_ = scaled.norm();
    // (a product instead of a division per parameterLimit; 2ε more pad covers the reciprocal's
    // and the product's roundings, so the limit stays at least the quotient's)
    limitFactor_ = (1 + kSlabRoundingPad + 2 * kEps) / length_;
    absSlack_ = kRayPruneSlack * scale;
  }

  /// The parameter limit for enter/keep that keeps every subtree which can hold a hit at world
  /// distance <= limit (inclusive, with the pruning slack). inf stays inf; a zero direction (a
  /// segment whose ends coincide) has no parameter scale and gets no limit.
  Real parameterLimit(Real limit) const {
    if (!(length_ > 0)) return std::numeric_limits<Real>::infinity();
    return (limit * (1 + kRayPruneSlack) + absSlack_) * limitFactor_;
  }

  /// Whether the ray enters the padded box at a parameter <= sLimit; `key` receives the entry
  /// parameter (padded low), which orders siblings front to back.
  bool enter(const Aabb& b, Real sLimit, Real& key) const {
    Real lo = 0, hi = std::numeric_limits<Real>::max();  // lo = +inf (parallel miss) fails lo <= hi
    for (int i = 0; i < 3; ++i) {
      const bool nearIsMax = nearOffset_[i] > farOffset_[i];
      const Real nearPlane = nearIsMax ? b.max[i] : b.min[i];
      const Real farPlane = nearIsMax ? b.min[i] : b.max[i];
      const Real t0 = (nearPlane - originNear_[i][0]) * invNear_[i][0];  // (every lane holds the value)
      const Real t1 = (farPlane - originFar_[i][0]) * invFar_[i][0];
      lo = t0 > lo ? t0 : lo;  // NaN (0·inf) is dropped
      hi = t1 < hi ? t1 : hi;
    }
    key = lo;
    return lo <= hi && lo <= sLimit;
  }

  /// enter() for the four lane boxes of a wide node at once: bit i of the result is enter()'s
  /// answer for lane i's box (the same operations per lane), keys[i] its key. Unused lanes
  /// (empty boxes) are never entered.
  unsigned enter4(const WideBvhNode& node, Real sLimit, Real (&keys)[4]) const {
    static_assert(sizeof(WideBvhNode::minX) == sizeof(Lanes), "a coordinate array is one Lanes");
    const Real* coords = node.minX;  // minX, minY, minZ, maxX, maxY, maxZ: 4 Reals each
    constexpr Real kMax = std::numeric_limits<Real>::max();
    Lanes lo = {0, 0, 0, 0}, hi = {kMax, kMax, kMax, kMax};
    for (int i = 0; i < 3; ++i) {
      const Lanes t0 = (lanesLoad(coords + nearOffset_[i]) - originNear_[i]) * invNear_[i];
      const Lanes t1 = (lanesLoad(coords + farOffset_[i]) - originFar_[i]) * invFar_[i];
      lo = lanesMax(t0, lo);  // NaN (0·inf) is dropped
      hi = lanesMin(t1, hi);
    }
    std::memcpy(keys, &lo, sizeof keys);
    return laneMask((lo <= hi) & (lo <= sLimit));
  }

  /// Whether a subtree entered at parameter `key` can still matter under sLimit.
  static bool keep(Real key, Real sLimit) { return key <= sLimit; }

 private:
  // Per axis, each value in all four lanes: the near and far planes' padded origin and inverse
  // direction; the offsets of the near and far coordinate arrays in a WideBvhNode.
  Lanes originNear_[3], originFar_[3], invNear_[3], invFar_[3];
  int nearOffset_[3], farOffset_[3];
  Real length_ = 1;
  Real limitFactor_ = 1 + kSlabRoundingPad;  // (1 + pad) / length_, rounded up (see the constructor)
  Real absSlack_ = 0;
};

/// The slab test of a ray from `origin` along `dir` against the boxes of a mesh of scale
/// `meshScale` (Mesh::scale()): its pads scale with the larger of the mesh's and the origin's
/// largest |coordinate|. Mesh rays and the point-in-volume parity ray take it.
inline RayBoxTest meshRayBoxTest(Real meshScale, const Vec3& origin, const Vec3& dir) {
  return RayBoxTest(origin, dir, std::max(meshScale, origin.cwiseAbs().maxCoeff()));
}

/// A node test on one box applied to each used lane of a wide node: bit i set when lane i's box
/// passes `test` (for the node tests that have no four-lane form).
template <class BoxTest>
unsigned eachLane(const WideBvhNode& node, const BoxTest& test) {
  unsigned bits = 0;
  for (int i = 0; i < 4; ++i)
    if (node.used(i) && test(node.laneBounds(i))) bits |= 1u << i;
  return bits;
}

/// The squared distance from p to a box, in Real: the per-axis gaps max(min − p, p − max, 0),
/// squared and summed in axis order (RTCD 5.1.3). boxSquaredDistances4 computes the same operations on
/// a wide node's four lane boxes, so its lane i equals this for lane i's box bit for bit (an
/// unused lane's empty box gives +inf).
inline Real boxSquaredDistance(const Aabb& b, const Vec3& p) {
  Real g[3];
  for (int i = 0; i < 3; ++i) g[i] = std::max(std::max(b.min[i] - p[i], p[i] - b.max[i]), Real(0));
  return (g[0] * g[0] + g[1] * g[1]) + g[2] * g[2];
}
/// Lanes of a wide node that hold a box (an unused lane's empty box has min > max): callers whose
/// limit may be +inf must mask with it, since an empty box's key is +inf too.
inline LaneBits usedLanes(const WideBvhNode& n) { return lanesLoad(n.minX) <= lanesLoad(n.maxX); }
inline Lanes boxSquaredDistances4(const WideBvhNode& n, const Vec3& p) {
  const Lanes zero{};
  auto gap = [&](const Real* lo, const Real* hi, Real x) {
    const Lanes px{x, x, x, x};
    return lanesMax(lanesMax(lanesLoad(lo) - px, px - lanesLoad(hi)), zero);
  };
  const Lanes gx = gap(n.minX, n.maxX, p.x()), gy = gap(n.minY, n.maxY, p.y()), gz = gap(n.minZ, n.maxZ, p.z());
  return (gx * gx + gy * gy) + gz * gz;
}

/// Sphere vs box grown by pad: squared distance from the centre <= (r + pad)², with a relative
/// pad on the rounded sum of squares.
inline bool sphereTouchesBox(const Vec3& c, Real r, const Aabb& b, Real pad) {
  Real d2 = 0;
  for (int i = 0; i < 3; ++i) {
    Real d = 0;
    if (c[i] < b.min[i] - pad) d = (b.min[i] - pad) - c[i];
    else if (c[i] > b.max[i] + pad) d = c[i] - (b.max[i] + pad);
    d2 += d * d;
  }
  const Real rr = r + pad;
  return d2 * (1 - kSlabRoundingPad) <= rr * rr;
}

/// Box vs box grown by pad (comparisons only).
inline bool boxTouchesBox(const Aabb& q, const Aabb& b, Real pad) {
  return (q.min.array() <= b.max.array() + pad).all() && (b.min.array() - pad <= q.max.array()).all();
}

/// Plane {n·x = d} vs box, |n·c - d| <= Σ h_i|n_i| plus pad·(|n|₁·scale + |d|).
inline bool planeTouchesBox(const Vec3& n, Real d, const Aabb& b, Real padFraction, Real scale) {
  const Vec3 c = b.center(), h = b.half();
  const Real s = n.dot(c) - d;
  const Real r = h.dot(n.cwiseAbs());
  return std::fabs(s) <= r + padFraction * (n.cwiseAbs().sum() * scale + std::fabs(d));
}

static_assert(sizeof(Aabb) == 6 * sizeof(Real), "Aabb is read as 6 contiguous Reals (min, then max)");

/// An OBB (orthonormal axes as columns) prepared for separating-axis tests against axis-aligned
/// boxes (RTCD 4.4.1 with the AABB as box A), restricted to the six face axes: the nine
/// edge–edge axes cost more than the few extra "maybe" answers they would remove, and skipping
/// axes keeps the test conservative. Comparisons are padded by an absolute pad; |R| by kAxisPad.
/// The six axes are tested at once, one lane per axis (lanes.hpp), in the scalar test's order
/// of operations (so the same answers).
class ObbBoxTest {
 public:
  ObbBoxTest(const Mat3& axes, Real pad) : pad2_(2 * pad) {
    const Mat3 absR = axes.cwiseAbs().array() + kAxisPad;
    absR_ = absR;
    for (int i = 0; i < 3; ++i) {
      rows_[i] = Lanes{axes(i, 0), axes(i, 1), axes(i, 2), 0};
      absRows_[i] = Lanes{absR(i, 0), absR(i, 1), absR(i, 2), 0};
    }
  }

  /// An OBB with these axes placed at `center` with half extents `half`, prepared for touches():
  /// doubled centre and half extents (exact), and its world box grown by the pad; each vector
  /// is followed by one more Real, so touches() reads them as four lanes.
  struct Placed {
    Vec3 center2, half2, lo, hi;
    Real end = 0;  // hi's fourth lane
  };
  Placed place(const Vec3& center, const Vec3& half) const {
    const Vec3 ext = absR_ * half + Vec3::Constant(pad2_ / 2);
    return {2 * center, 2 * half, center - ext, center + ext};
  }

  /// Does the placed OBB touch box b (grown by the pad)?
  bool touches(const Placed& o, const Aabb& b) const {
    const Real* box = b.min.data();
    const Lanes mn = lanesLoad(box);  // min, max.x
    const Lanes tail = lanesLoad(box + 2);  // min.z, max
    const Lanes mx = Lanes{tail[1], tail[2], tail[3], tail[3]};
    // Box A's face axes: the OBB's world box against b (comparisons only).
    const LaneBits outside = (lanesLoad(o.lo.data()) > mx) | (lanesLoad(o.hi.data()) < mn);
    // The OBB's face axes u_j (lane j): |t·u_j| > Σ_i h_i |R_ij| + e_j, all doubled (2t, 2h, 2e).
    const Lanes t2 = lanesLoad(o.center2.data()) - (mn + mx);
    const Lanes h2 = mx - mn;
    const Lanes dot = (t2[0] * rows_[0] + t2[1] * rows_[1]) + t2[2] * rows_[2];
    const Lanes reach = (((h2[0] * absRows_[0] + h2[1] * absRows_[1]) + h2[2] * absRows_[2]) + lanesLoad(o.half2.data())) + pad2_;
    return !anyOf3(outside | (lanesAbs(dot) > reach));
  }

  /// touches() for the four lane boxes of a wide node at once (one lane per box, bit i of the
  /// result: lane i's box touches), in the same order of operations per box, so each bit is
  /// touches()' answer for that box. Unused lanes (empty boxes) are rejected.
  unsigned touches4(const Placed& o, const WideBvhNode& node) const {
    const Lanes mnX = lanesLoad(node.minX), mnY = lanesLoad(node.minY), mnZ = lanesLoad(node.minZ);
    const Lanes mxX = lanesLoad(node.maxX), mxY = lanesLoad(node.maxY), mxZ = lanesLoad(node.maxZ);
    // Box A's face axes: the OBB's world box against each box
    LaneBits outside = (o.lo.x() > mxX) | (o.hi.x() < mnX);
    outside |= (o.lo.y() > mxY) | (o.hi.y() < mnY);
    outside |= (o.lo.z() > mxZ) | (o.hi.z() < mnZ);
    const Lanes tx = o.center2.x() - (mnX + mxX), ty = o.center2.y() - (mnY + mxY), tz = o.center2.z() - (mnZ + mxZ);
    const Lanes hx = mxX - mnX, hy = mxY - mnY, hz = mxZ - mnZ;
    for (int j = 0; j < 3; ++j) {  // the OBB's face axis u_j
      const Lanes dot = (tx * rows_[0][j] + ty * rows_[1][j]) + tz * rows_[2][j];
      const Lanes reach = (((hx * absRows_[0][j] + hy * absRows_[1][j]) + hz * absRows_[2][j]) + o.half2[j]) + pad2_;
      outside |= lanesAbs(dot) > reach;
    }
    return ~laneMask(outside) & 15u;
  }

 private:
  Lanes rows_[3], absRows_[3];  // row i of the axes (lane j: R_ij), and of |R| + kAxisPad
  Mat3 absR_;
  Real pad2_;
};

}  // namespace crux::mesh_detail
