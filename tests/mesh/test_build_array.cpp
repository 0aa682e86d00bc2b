/// Tests of src/mesh/build_array.hpp: the BVH builder's arrays, mapped by the builder itself and
/// advised to use transparent huge pages from 2 MiB on.

#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <limits>
#include <new>
#include <sstream>
#include <string>

#include "mesh/build_array.hpp"
#include "support/sanitized.hpp"

namespace crux::detail {
namespace {

struct Item {
  std::uint32_t a = 7, b = 9;
};

TEST(BuildArray, AppendsAndValueInitialisesWithinItsCapacity) {
  BuildArray<Item> array(5);
  EXPECT_EQ(array.capacity(), 5u);
  EXPECT_EQ(array.size(), 0u);
  array.push_back({1, 2});
  array.resize(3);
  ASSERT_EQ(array.size(), 3u);
  EXPECT_EQ(array[0].a, 1u);
  EXPECT_EQ(array[2].a, 7u);  // value-initialised
  std::uint32_t sum = 0;
  for (const Item& i : array) sum += i.b;
  EXPECT_EQ(sum, 2u + 9u + 9u);
  BuildArray<Item> moved(std::move(array));
  EXPECT_EQ(moved.size(), 3u);
  EXPECT_EQ(array.data(), nullptr);  // NOLINT(bugprone-use-after-move): the moved-from state is empty
  moved.clear();
  EXPECT_EQ(moved.size(), 0u);
}

TEST(BuildArray, ResizeForOverwriteLeavesConstructionToTheCaller) {
  BuildArray<Item> array(4);
  array.resizeForOverwrite(4);
  ASSERT_EQ(array.size(), 4u);
  for (std::uint32_t i = 0; i < 4; ++i) new (array.data() + i) Item{i, 2 * i};
  EXPECT_EQ(array[3].a, 3u);
  EXPECT_EQ(array[3].b, 6u);
}

TEST(BuildArray, ACapacityWhoseBytesOverflowIsRefused) {
  const std::size_t tooMany = std::numeric_limits<std::size_t>::max() / sizeof(Item) + 1;
  EXPECT_THROW(BuildArray<Item>{tooMany}, std::bad_array_new_length);
}

TEST(BuildArray, ACapacityNoMemoryCanHoldThrowsBadAlloc) {
  // Its bytes fit std::size_t but rounding them up to whole huge pages would wrap.
  if (CRUX_TEST_SANITIZED) GTEST_SKIP() << "sanitizer allocators abort on such a request instead of throwing";
  volatile std::size_t most = std::numeric_limits<std::size_t>::max() / sizeof(Item);  // not folded: no size warning
  EXPECT_THROW(BuildArray<Item>{most}, std::bad_alloc);
}

TEST(BuildArray, SmallArraysUseTheHeapLargeOnesAMappingOfTheirOwn) {
  const BuildArray<std::uint64_t> small(1000);
  EXPECT_FALSE(small.mapped());
  BuildArray<std::uint64_t> large(kBuildHugePageBytes / sizeof(std::uint64_t) + 1);
#if defined(__linux__)
  ASSERT_TRUE(large.mapped());
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(large.data()) % kBuildHugePageBytes, 0u) << "not 2 MiB-aligned";
#endif
  large.resize(large.capacity());  // every byte is writable
  large[large.size() - 1] = 42;
  EXPECT_EQ(large[large.size() - 1], 42u);
}

#if defined(__linux__)
/// The transparent-huge-page mode in brackets in /sys/kernel/mm/transparent_hugepage/enabled
/// ("always", "madvise", "never"), or "" where the file is missing.
std::string thpMode() {
  std::ifstream in("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string line;
  std::getline(in, line);
  const auto open = line.find('['), close = line.find(']');
  return open == std::string::npos || close == std::string::npos ? "" : line.substr(open + 1, close - open - 1);
}

/// The "THPeligible:" value of the mapping that holds `address` in /proc/self/smaps (-1: none;
/// the kernel may merge the array's mapping with a neighbour of the same flags, so the mapping
/// is found by containment, not by its start).
int thpEligible(const void* address) {
  std::ifstream in("/proc/self/smaps");
  std::string line;
  bool inside = false;
  const auto at = reinterpret_cast<std::uintptr_t>(address);
  while (std::getline(in, line)) {
    std::uintptr_t from = 0, to = 0;
    char dash = 0;
    std::istringstream head(line);
    if (head >> std::hex >> from >> dash >> to && dash == '-') {
      inside = from <= at && at < to;
      continue;
    }
    if (inside && line.rfind("THPeligible:", 0) == 0) return std::stoi(line.substr(12));
  }
  return -1;
}

TEST(BuildArray, ALargeArrayIsEligibleForTransparentHugePages) {
  // The kernel's own account of the advice: a mapping advised MADV_HUGEPAGE is eligible in the
  // "madvise" and "always" modes. (Whether a huge page is then granted depends on free memory.)
  const std::string mode = thpMode();
  if (mode != "madvise" && mode != "always") GTEST_SKIP() << "transparent huge pages are '" << mode << "' here";
  BuildArray<std::uint64_t> large(4 * kBuildHugePageBytes / sizeof(std::uint64_t));
  ASSERT_TRUE(large.mapped());
  large.resize(large.capacity());
  const int eligible = thpEligible(large.data());
  if (eligible < 0) GTEST_SKIP() << "this kernel's smaps has no THPeligible field";
  EXPECT_EQ(eligible, 1);
}
#endif

}  // namespace
}  // namespace crux::detail
