#pragma once
/// @file fuzz_input.hpp  Helpers shared by the libFuzzer targets in tests/fuzz (docs/fuzzing.md):
/// a reader that turns the fuzzer's bytes into values, and the failure check.

#include <crux/math.hpp>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>

namespace crux::fuzz {

/// Reports a broken property and aborts: libFuzzer records the input as a crash, and the corpus
/// replay test (tests/fuzz/replay_main.cpp) fails.
[[noreturn]] inline void fail(const std::string& what) {
  std::fprintf(stderr, "fuzz property violated: %s\n", what.c_str());
  std::fflush(stderr);
  std::abort();
}

/// Consumes the fuzzer's bytes front to back; reads past the end give zeros.
class Input {
 public:
  Input(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

  std::size_t remaining() const { return size_ - pos_; }

  std::uint8_t byte() { return pos_ < size_ ? data_[pos_++] : 0; }

  /// A Real whose kind is chosen by one tag byte, so that every kind stays reachable for the
  /// mutator: small integers (the grid on which answers must be exact), raw bit patterns (NaN,
  /// Inf, denormals, anything), special values, and scaled integers up to 1e15 (the documented
  /// coordinate limit) and down to 1e-15.
  Real real() {
    const std::uint8_t tag = byte();
    switch (tag % 4) {
      case 0: return Real(int(byte() % 129) - 64);
      case 1: {
        Real r;
        unsigned char bytes[sizeof(Real)];
        for (unsigned char& b : bytes) b = byte();
        std::memcpy(&r, bytes, sizeof r);
        return r;
      }
      case 2: {
        using L = std::numeric_limits<Real>;
        const Real specials[] = {L::quiet_NaN(), L::infinity(), -L::infinity(), L::denorm_min(),
                                 -L::denorm_min(), L::min(), L::max(), L::lowest(), L::epsilon(),
                                 Real(-0.0), Real(1e15), Real(-1e15), Real(0.5), Real(1) / Real(3)};
        return specials[byte() % (sizeof specials / sizeof specials[0])];
      }
      default: {
        static const Real scales[] = {Real(1e-15), Real(1e-6), Real(1e-3), Real(1e3), Real(1e6), Real(1e15)};
        return Real(int(byte() % 129) - 64) * scales[byte() % 6];
      }
    }
  }

  Vec3 vec3() {
    const Real x = real(), y = real(), z = real();
    return Vec3(x, y, z);
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

}  // namespace crux::fuzz
