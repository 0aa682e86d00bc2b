#pragma once
// Helpers shared by the tests of the `crux` command line (tests/apps/test_*.cpp).

#include "cli/batch.hpp"

#include <crux/math.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

namespace crux::cli::test {

/// Tolerance for computed (non-boolean) results on hand-checked cases whose coordinates are at
/// most ~10: a few ulps of Real at that magnitude.
inline constexpr double kResultTolerance = 16.0 * 10.0 * std::numeric_limits<Real>::epsilon();

/// The error message of an answer ("" when it has none).
inline std::string errorOf(const Answer& a) {
  const auto it = a.find("error");
  return it == a.end() ? std::string() : it->get<std::string>();
}

/// `v` is `[x, y, z]` within kResultTolerance.
inline ::testing::AssertionResult isPoint(const Answer& v, double x, double y, double z) {
  if (!v.is_array() || v.size() != 3) return ::testing::AssertionFailure() << "not a point: " << v.dump();
  const double want[3] = {x, y, z};
  for (std::size_t i = 0; i < 3; ++i) {
    if (!v[i].is_number() || std::fabs(v[i].get<double>() - want[i]) > kResultTolerance)
      return ::testing::AssertionFailure() << v.dump() << " != [" << x << ", " << y << ", " << z << "]";
  }
  return ::testing::AssertionSuccess();
}

inline std::vector<std::string> splitLines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

/// Path of the `crux` executable, built next to the test (CMAKE_RUNTIME_OUTPUT_DIRECTORY).
inline std::string cruxExecutable() {
  char self[4096];
  const ssize_t n = readlink("/proc/self/exe", self, sizeof(self) - 1);
  if (n <= 0) return "";
  std::string path(self, std::size_t(n));
  return path.substr(0, path.rfind('/') + 1) + "crux";
}

/// Runs a shell command; returns its exit status and standard output.
inline std::pair<int, std::string> run(const std::string& command) {
  std::string output;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return {-1, ""};
  char buffer[4096];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0;) output.append(buffer, n);
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

/// The whole text of a file ("" when it cannot be read).
inline std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

inline bool fileExists(const std::string& path) { return access(path.c_str(), F_OK) == 0; }

/// `s` quoted for a POSIX shell.
inline std::string shellQuoted(const std::string& s) {
  std::string q = "'";
  for (const char c : s) q += (c == '\'') ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

}  // namespace crux::cli::test
