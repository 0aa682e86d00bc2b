#pragma once
/// @file invalid_input.hpp  The message of the crux::InvalidInput a call throws.

#include <crux/error.hpp>
#include <gtest/gtest.h>

#include <exception>
#include <functional>
#include <string>

namespace crux::test_support {

/// The message of the InvalidInput `f` throws; fails the test (and returns "") if it throws
/// nothing or another exception.
inline std::string invalidInputMessage(const std::function<void()>& f) {
  try {
    f();
  } catch (const InvalidInput& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "threw a non-InvalidInput exception: " << e.what();
    return {};
  }
  ADD_FAILURE() << "did not throw";
  return {};
}

}  // namespace crux::test_support
