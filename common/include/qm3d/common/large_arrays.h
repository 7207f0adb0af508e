// Arrays of millions of elements: not zeroed first by a serial pass when they are filled element
// by element anyway (in parallel); and, when QM3D_HUGE_PAGES=1 is in the environment, backed by
// transparent huge pages where the system offers them per region
// (/sys/kernel/mm/transparent_hugepage/enabled = madvise, the common default), so that hundreds
// of megabytes are faulted in 2 MiB at a time instead of 4 KiB. The advice is off by default:
// on virtual machines that hand free memory back to their host it makes every fault far slower
// (large_arrays.cpp).
#pragma once

#include <cstddef>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace qm3d {

/// madvise(MADV_HUGEPAGE) on the whole 2 MiB pages inside [data, data + bytes) when
/// QM3D_HUGE_PAGES=1; ignored below 4 MiB and wherever the system refuses (a hint only). Call it
/// before the memory is written.
void advise_huge_pages(const void* data, std::size_t bytes);

/// Reserves room for n elements in `v` and advises huge pages for it; call it before filling
/// (resize, assign) an empty vector.
template <typename T>
void reserve_with_huge_pages(std::vector<T>& v, std::size_t n) {
  if (n <= v.capacity()) return;
  v.reserve(n);
  advise_huge_pages(v.data(), n * sizeof(T));
}

/// std::allocator that advises huge pages for large blocks and default-initialises: resize(n)
/// leaves new elements of trivial types (double, std::array<double, 3>, ...) unwritten.
template <typename T>
struct LargeArrayAllocator : std::allocator<T> {
  using value_type = T;
  template <typename U>
  struct rebind {
    using other = LargeArrayAllocator<U>;
  };
  LargeArrayAllocator() = default;
  template <typename U>
  LargeArrayAllocator(const LargeArrayAllocator<U>&) noexcept {
  }  // NOLINT: converting, as std::allocator

  T* allocate(std::size_t n) {
    T* p = std::allocator<T>::allocate(n);
    advise_huge_pages(p, n * sizeof(T));
    return p;
  }
  template <typename U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible<U>::value) {
    ::new (static_cast<void*>(p)) U;  // default-initialisation: no zeroing
  }
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

template <typename T, typename U>
bool operator==(const LargeArrayAllocator<T>&, const LargeArrayAllocator<U>&) noexcept {
  return true;
}
template <typename T, typename U>
bool operator!=(const LargeArrayAllocator<T>&, const LargeArrayAllocator<U>&) noexcept {
  return false;
}

/// A vector for large arrays whose every element is written before it is read: resize(n) does
/// not initialise trivial elements (resize(n, value) does), memory comes in huge pages.
template <typename T>
using LargeArray = std::vector<T, LargeArrayAllocator<T>>;

}  // namespace qm3d
