#pragma once
/// @file test_scale.hpp  Scaling of property-test case counts by the environment variable
/// CRUX_TEST_SCALE (a positive factor, default 1). The sanitizer stage of scripts/test sets it
/// below 1 so the heavy seeded property tests fit the CI budget under ASan/UBSan (docs/fuzzing.md);
/// the Release stages run the full counts.

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace crux::test {

/// The factor CRUX_TEST_SCALE, clamped to (0, 1000]. An unset, unparsable or non-positive value
/// means 1. For tests that scale something other than a count (a sample of data files).
inline double testScale() {
  const char* env = std::getenv("CRUX_TEST_SCALE");
  const double scale = env ? std::strtod(env, nullptr) : 1.0;
  if (!(scale > 0) || !std::isfinite(scale)) return 1.0;
  return std::min(scale, 1e3);
}

/// `cases` scaled by CRUX_TEST_SCALE, rounded, at least `minimum` (so hit-rate checks still see
/// enough cases; a `minimum` above `cases` is capped at `cases`, so a scale <= 1 never adds cases).
inline int scaledCases(int cases, int minimum = 1000) {
  return std::max(std::min(cases, minimum), int(std::lround(cases * testScale())));
}

}  // namespace crux::test
