#pragma once
/// @file test_scale.hpp  Scaling of property-test case counts by the environment variable
/// CRUX_TEST_SCALE (a positive factor, default 1). The sanitizer stage of scripts/test sets it
/// below 1 so the heavy seeded property tests fit the CI budget under ASan/UBSan (docs/fuzzing.md);
/// the Release stages run the full counts.

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace crux::test {

/// `cases` scaled by CRUX_TEST_SCALE, rounded, at least `minimum` (so hit-rate checks still see
/// enough cases). An unset, unparsable or non-positive CRUX_TEST_SCALE means 1.
inline int scaledCases(int cases, int minimum = 1000) {
  const char* env = std::getenv("CRUX_TEST_SCALE");
  double scale = env ? std::strtod(env, nullptr) : 1.0;
  if (!(scale > 0) || !std::isfinite(scale)) scale = 1.0;
  return std::max(std::min(cases, minimum), int(std::lround(cases * std::min(scale, 1e3))));
}

}  // namespace crux::test
