#pragma once
/// @file lanes.hpp  Internal: four lanes of Real (the GCC/Clang vector extension; SSE on x86-64
/// in either precision) and the per-lane helpers the mesh layer's vectorised node tests share
/// (mesh_distance.cpp's oriented box pairs, mesh_contact.cpp's box-vs-node test).

#include <crux/geometry/shapes.hpp>

#include "geometry/finite_lanes.hpp"  // the four-lane type (and GCC's AVX ABI note turned off)

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>

namespace crux::mesh_detail {

/// Four lanes of Real (the geometry layer's type).
using Lanes = geometry_detail::FiniteLanes;
using LaneInt = std::conditional_t<sizeof(Real) == 4, std::int32_t, std::int64_t>;
/// Four lanes of integers as wide as Real (comparison results: all ones or all zeros).
using LaneBits = LaneInt __attribute__((vector_size(4 * sizeof(Real))));

/// |x| per lane, exactly (clears the sign bits).
inline Lanes lanesAbs(const Lanes& x) { return (Lanes)((LaneBits)x & std::numeric_limits<LaneInt>::max()); }

/// Correctly rounded square root per lane (as std::sqrt).
inline Lanes lanesSqrt(const Lanes& x) {
#if defined(__SSE2__) && !CRUX_DOUBLE_PRECISION_ENABLED
  return (Lanes)_mm_sqrt_ps((__m128)x);
#elif defined(__SSE2__)
  __m128d half[2];
  std::memcpy(half, &x, sizeof half);
  half[0] = _mm_sqrt_pd(half[0]), half[1] = _mm_sqrt_pd(half[1]);
  Lanes r;
  std::memcpy(&r, half, sizeof half);
  return r;
#else
  return Lanes{std::sqrt(x[0]), std::sqrt(x[1]), std::sqrt(x[2]), std::sqrt(x[3])};
#endif
}

/// mask ? x : y per lane (mask lanes all ones or all zeros, as comparisons give).
inline Lanes lanesSelect(const LaneBits& mask, const Lanes& x, const Lanes& y) {
  return (Lanes)((mask & (LaneBits)x) | (~mask & (LaneBits)y));
}

/// a > b ? a : b per lane (so a NaN in a gives b: SSE's max operand order).
inline Lanes lanesMax(const Lanes& a, const Lanes& b) {
#if defined(__SSE2__) && !CRUX_DOUBLE_PRECISION_ENABLED
  return (Lanes)_mm_max_ps((__m128)a, (__m128)b);
#elif defined(__SSE2__)
  __m128d x[2], y[2];
  std::memcpy(x, &a, sizeof x);
  std::memcpy(y, &b, sizeof y);
  x[0] = _mm_max_pd(x[0], y[0]), x[1] = _mm_max_pd(x[1], y[1]);
  Lanes r;
  std::memcpy(&r, x, sizeof x);
  return r;
#else
  return lanesSelect(a > b, a, b);
#endif
}

/// a < b ? a : b per lane (a NaN in a gives b).
inline Lanes lanesMin(const Lanes& a, const Lanes& b) {
#if defined(__SSE2__) && !CRUX_DOUBLE_PRECISION_ENABLED
  return (Lanes)_mm_min_ps((__m128)a, (__m128)b);
#elif defined(__SSE2__)
  __m128d x[2], y[2];
  std::memcpy(x, &a, sizeof x);
  std::memcpy(y, &b, sizeof y);
  x[0] = _mm_min_pd(x[0], y[0]), x[1] = _mm_min_pd(x[1], y[1]);
  Lanes r;
  std::memcpy(&r, x, sizeof x);
  return r;
#else
  return lanesSelect(a < b, a, b);
#endif
}

/// Lane i of x in all four lanes.
inline Lanes lanesBroadcast(const Lanes& x, int i) { return Lanes{x[i], x[i], x[i], x[i]}; }

/// x in all four lanes.
inline Lanes lanesSplat(Real x) { return Lanes{x, x, x, x}; }

/// (v.x, v.y, v.z, 0): a point or vector as lanes, one coordinate per lane.
inline Lanes lanesOf(const Vec3& v) { return Lanes{v.x(), v.y(), v.z(), 0}; }

/// The sign bits of a comparison result's four lanes, lane i as bit i.
inline unsigned laneMask(const LaneBits& m) {
#if defined(__SSE2__) && !CRUX_DOUBLE_PRECISION_ENABLED
  __m128 v;
  std::memcpy(&v, &m, sizeof v);
  return unsigned(_mm_movemask_ps(v));
#elif defined(__SSE2__)
  __m128d half[2];
  std::memcpy(half, &m, sizeof half);
  return unsigned(_mm_movemask_pd(half[0]) | _mm_movemask_pd(half[1]) << 2);
#else
  return unsigned(m[0] & 1) | unsigned(m[1] & 1) << 1 | unsigned(m[2] & 1) << 2 | unsigned(m[3] & 1) << 3;
#endif
}

/// Whether any of lanes 0..2 of a comparison result is set; lane 3 is ignored.
inline bool anyOf3(const LaneBits& m) { return (laneMask(m) & 7u) != 0; }

/// Four Reals from memory (no alignment needed).
inline Lanes lanesLoad(const Real* p) {
  Lanes r;
  std::memcpy(&r, p, sizeof r);
  return r;
}

}  // namespace crux::mesh_detail
