#pragma once
/// @file bench_output.hpp  Small helpers every bench shares for its figures and its `--json`
/// output (hand-written JSON, so the benches need no JSON library).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace crux::bench {

/// `s` as a JSON string literal (quotes and backslashes escaped, control characters as \uXXXX).
inline std::string jsonString(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

/// `v` as a JSON number with 9 significant digits; null when not finite.
inline std::string jsonNumber(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

/// The median (mean of the middle two for an even count; 0 for none).
inline double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n == 0 ? 0 : (n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]));
}

}  // namespace crux::bench
