#pragma once
/// @file finite_lanes.hpp  Internal: the entry checks' finiteness test, four Reals at a time.
///
/// x − x is 0 for every finite x and NaN for ±inf and NaN, so the sum of those differences over
/// a block of numbers is 0 exactly when all of them are finite: one comparison for the block, no
/// branch per number. The numbers are read as the object's bytes (memcpy), four Reals per load,
/// the last load overlapping the one before; the object must hold only Reals, no padding.

#include <crux/geometry/shapes.hpp>

#include <cstring>
#include <type_traits>

// crux is built with GCC or Clang (README: requirements), so there is no scalar copy of the
// lane arithmetic to keep in step.
#if !defined(__GNUC__)
#error "crux needs GCC or Clang: src/geometry/finite_lanes.hpp uses their vector extension"
#endif

// Four doubles are 32 bytes, passed differently with and without AVX: the functions taking them
// are internal (inline, or in an anonymous namespace of the including file) and every file is
// built with the same flags, so GCC's ABI note does not apply. It is reported at the end of a
// translation unit, so it stays off for the rest of the including file (not popped).
#pragma GCC diagnostic ignored "-Wpsabi"

namespace crux::geometry_detail {

/// Four lanes of Real (the GCC/Clang vector extension): the one four-lane type of the entry
/// checks here and of the mesh layer's node tests (src/mesh/lanes.hpp).
using FiniteLanes = Real __attribute__((vector_size(4 * sizeof(Real))));

/// The lane sums of x − x over every Real of `obj` (an array of at least four Reals, no
/// padding): all lanes 0 when every number is finite, a NaN lane otherwise.
template <class T>
FiniteLanes finiteDifferences(const T& obj) {
  static_assert(sizeof(T) % sizeof(Real) == 0 && sizeof(T) >= 4 * sizeof(Real), "an array of at least four Reals");
  constexpr std::size_t kBlock = sizeof(FiniteLanes), kSize = sizeof(T);
  const char* bytes = reinterpret_cast<const char*>(&obj);
  FiniteLanes sum;
  std::memcpy(&sum, bytes, kBlock);
  sum -= sum;
  for (std::size_t at = kBlock; at < kSize; at += kBlock) {
    FiniteLanes x;
    std::memcpy(&x, bytes + (at + kBlock <= kSize ? at : kSize - kBlock), kBlock);
    sum += x - x;
  }
  return sum;
}

/// The differences of a pose's seven numbers (the rotation's four in one block, the
/// translation's three and a zero in another): the one finiteness rule of queryable(Transform) and
/// of the pair queries' entry check.
inline FiniteLanes poseDifferences(const Transform& pose) {
  const Vec3& t = pose.translation;
  const FiniteLanes translation = {t.x(), t.y(), t.z(), 0};
  return finiteDifferences(pose.rotation.coeffs()) + (translation - translation);
}

/// Whether every lane of a sum of differences is 0 (every number finite).
inline bool allZero(const FiniteLanes& sum) { return (sum[0] + sum[1]) + (sum[2] + sum[3]) == 0; }

/// The rule of a ray direction and a rotation beyond finiteness: not zero, i.e. a squared norm
/// > 0 in Wide. When Wide is wider than Real that is "some coefficient is not 0" (the square of
/// the smallest subnormal float, 2^-298, is a normal double), tested without the conversions.
template <class V>
bool nonZero(const V& v) {
  if constexpr (sizeof(Wide) > sizeof(Real)) return (v.array() != 0).any();
  else return v.template cast<Wide>().squaredNorm() > 0;
}

}  // namespace crux::geometry_detail
