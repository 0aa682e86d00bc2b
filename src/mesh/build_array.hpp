#pragma once
/// @file build_array.hpp  Arrays for the BVH builder's large temporaries, in memory the builder
/// maps itself and advises to use transparent huge pages.
///
/// A build writes its temporaries (the primitives it partitions, the binary tree) once, into
/// fresh memory. The kernel maps fresh anonymous memory one 4 KiB page per fault, zeroing each;
/// on the virtual machines crux is measured on a fault costs ~10 µs, and a build of 10^6
/// triangles touched ~170 MB: a quarter of its time was the fault path (docs/bvh.md, "Build
/// time"). An array of at least kBuildHugePageBytes is therefore an anonymous mapping of its
/// own, 2 MiB-aligned and advised MADV_HUGEPAGE before its first touch, so a fault maps 2 MiB
/// (where transparent huge pages are enabled, `always` or `madvise`). This is Embree's rule too
/// (its os_malloc maps and advises the memory it owns and leaves the heap alone): advising heap
/// memory was measured to change how malloc reuses it, for crux and for every other user of the
/// heap in the process. Smaller arrays, other systems and a failed mapping use the heap.
///
/// Elements are constructed when appended (push_back), by resize(), or by the caller after
/// resizeForOverwrite(); the array never grows past the capacity it was made with, and a
/// capacity whose bytes overflow std::size_t throws std::bad_array_new_length.

#include <cassert>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <new>
#include <type_traits>
#include <utility>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace crux::detail {

/// Size from which a BuildArray is a mapping of its own: one transparent huge page (x86-64).
inline constexpr std::size_t kBuildHugePageBytes = std::size_t(2) << 20;

/// Memory for a BuildArray: `bytes` bytes aligned to `align`. Returns the memory and sets
/// `mapped` to the length of the mapping it is (0: heap memory).
inline void* allocateBuildMemory(std::size_t bytes, std::size_t align, std::size_t& mapped) {
  mapped = 0;
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  // (sizes within two huge pages of the largest std::size_t would wrap in the rounding below:
  // they go to operator new, which throws std::bad_alloc)
  if (bytes >= kBuildHugePageBytes && bytes <= std::numeric_limits<std::size_t>::max() - 2 * kBuildHugePageBytes &&
      align <= kBuildHugePageBytes) {
    const std::size_t length = (bytes + kBuildHugePageBytes - 1) / kBuildHugePageBytes * kBuildHugePageBytes;
    // over-map by one huge page, then unmap the unaligned head and the tail
    void* raw = ::mmap(nullptr, length + kBuildHugePageBytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (raw != MAP_FAILED) {
      const auto base = reinterpret_cast<std::uintptr_t>(raw);
      const std::uintptr_t aligned = (base + kBuildHugePageBytes - 1) & ~std::uintptr_t(kBuildHugePageBytes - 1);
      if (aligned > base) ::munmap(raw, aligned - base);
      const std::uintptr_t end = base + length + kBuildHugePageBytes;
      if (end > aligned + length) ::munmap(reinterpret_cast<void*>(aligned + length), end - (aligned + length));
      void* p = reinterpret_cast<void*>(aligned);
      ::madvise(p, length, MADV_HUGEPAGE);  // advice only: without it the mapping still works
      mapped = length;
      return p;
    }
  }
#endif
  return ::operator new(bytes, std::align_val_t(align));
}

/// Frees memory of allocateBuildMemory.
inline void freeBuildMemory(void* p, std::size_t align, std::size_t mapped) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  if (mapped != 0) {
    ::munmap(p, mapped);
    return;
  }
#endif
  ::operator delete(p, std::align_val_t(align));
}

/// An array of fixed capacity for the builder's temporaries (see the file comment).
template <class T>
class BuildArray {
  static_assert(std::is_trivially_destructible_v<T>, "BuildArray never runs destructors");

 public:
  BuildArray() = default;
  explicit BuildArray(std::size_t capacity) : capacity_(capacity) {
    if (capacity_ > std::numeric_limits<std::size_t>::max() / sizeof(T)) throw std::bad_array_new_length();
    if (capacity_ > 0) data_ = static_cast<T*>(allocateBuildMemory(capacity_ * sizeof(T), alignof(T), mapped_));
  }
  BuildArray(BuildArray&& o) noexcept { swap(o); }
  BuildArray& operator=(BuildArray&& o) noexcept {
    BuildArray(std::move(o)).swap(*this);
    return *this;
  }
  BuildArray(const BuildArray&) = delete;
  BuildArray& operator=(const BuildArray&) = delete;
  ~BuildArray() {
    if (data_) freeBuildMemory(data_, alignof(T), mapped_);
  }

  void push_back(const T& value) {
    assert(size_ < capacity_);
    new (data_ + size_++) T(value);
  }
  /// Grows to n elements (n <= capacity), value-initialising the new ones; or shrinks.
  void resize(std::size_t n) {
    assert(n <= capacity_);
    for (std::size_t i = size_; i < n; ++i) new (data_ + i) T();
    size_ = n;
  }
  /// Grows to n elements (n <= capacity) without constructing the new ones: the caller
  /// constructs every one of them (placement new) before reading it. Saves a pass of writes
  /// (and its page faults on the calling thread) where parallel tasks fill the array.
  void resizeForOverwrite(std::size_t n) {
    assert(n <= capacity_);
    size_ = n;
  }
  void clear() { size_ = 0; }

  std::size_t size() const { return size_; }
  std::size_t capacity() const { return capacity_; }
  /// Whether the array is a mapping of its own (advised to use huge pages).
  bool mapped() const { return mapped_ != 0; }
  T* data() { return data_; }
  const T* data() const { return data_; }
  T& operator[](std::size_t i) { return data_[i]; }
  const T& operator[](std::size_t i) const { return data_[i]; }
  T* begin() { return data_; }
  T* end() { return data_ + size_; }
  const T* begin() const { return data_; }
  const T* end() const { return data_ + size_; }

 private:
  void swap(BuildArray& o) noexcept {
    std::swap(data_, o.data_);
    std::swap(size_, o.size_);
    std::swap(capacity_, o.capacity_);
    std::swap(mapped_, o.mapped_);
  }

  T* data_ = nullptr;
  std::size_t size_ = 0, capacity_ = 0, mapped_ = 0;
};

}  // namespace crux::detail
