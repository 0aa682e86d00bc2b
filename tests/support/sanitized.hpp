#pragma once
/// @file sanitized.hpp  CRUX_TEST_SANITIZED: 1 in a build under AddressSanitizer or
/// ThreadSanitizer (GCC's __SANITIZE_*__ or Clang's __has_feature), else 0. For tests whose
/// subject the sanitizers change (memory footprints) or make impractically slow.

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define CRUX_TEST_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define CRUX_TEST_SANITIZED 1
#endif
#endif
#ifndef CRUX_TEST_SANITIZED
#define CRUX_TEST_SANITIZED 0
#endif
