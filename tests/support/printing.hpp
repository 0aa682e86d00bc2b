#pragma once
/// @file printing.hpp  Printers for failing-case messages: every number with 17 significant
/// digits, so a printed case reproduces exactly (test files add printers for their own shapes).

#include <Eigen/Core>

#include <sstream>
#include <string>

namespace crux::test_support {

/// x with 17 significant digits (round-trips a double).
inline std::string str(double x) {
  std::ostringstream os;
  os.precision(17);
  os << x;
  return os.str();
}

/// A 3-vector as "(x, y, z)", each coordinate as str(double).
template <class V>
std::string str(const Eigen::MatrixBase<V>& v) {
  return "(" + str(double(v.x())) + ", " + str(double(v.y())) + ", " + str(double(v.z())) + ")";
}

}  // namespace crux::test_support
