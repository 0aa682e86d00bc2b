#pragma once
/// @file error.hpp  The one exception crux throws for bad input at its API edge.

#include <stdexcept>
#include <string>

namespace crux {

/// Thrown by validating constructors and `validate(...)` functions when an input cannot be
/// given a meaning: NaN/Inf coordinates, a zero direction, a negative radius, min > max, ...
/// The message names the offending field and value. Query functions themselves never throw;
/// they require validated inputs (their documented precondition).
class InvalidInput : public std::invalid_argument {
 public:
  explicit InvalidInput(const std::string& what) : std::invalid_argument(what) {}
};

}  // namespace crux
