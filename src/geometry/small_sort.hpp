// Sorting the few items a traversal orders per node or per leaf pair (geometry, mesh and scene
// layers).
#pragma once

namespace crux::detail {

/// Stable insertion sort of a[0, n) by `before` (a strict weak order: before(x, y) when x goes
/// first). For a few dozen items at most: no allocation, and none of std::sort's code for long
/// ranges (on a fixed eight-item array GCC warned of an index it never reaches).
template <class T, class Before>
void insertionSort(T* a, int n, Before before) {
  for (int i = 1; i < n; ++i) {
    const T x = a[i];
    int j = i;
    for (; j > 0 && before(x, a[j - 1]); --j) a[j] = a[j - 1];
    a[j] = x;
  }
}

}  // namespace crux::detail
