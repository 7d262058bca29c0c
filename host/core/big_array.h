// The large arrays of a structure (nodes, references, packs): vectors whose
// resize() leaves new elements default-initialised (for these plain structs:
// untouched) instead of zero-filling them. The builders write every element
// anyway, so the threads that fill an array, not one serial resize, first
// touch its pages (at 10^7 primitives, a second of page faults otherwise).
//
// Transparent huge pages (madvise MADV_HUGEPAGE on these arrays) were
// measured and dropped: on the development machine (a VM) the pages came,
// trace times did not move, and the build at 10^7 triangles took 4.2 s
// instead of 3.0 (the kernel compacting memory for them).
#pragma once

#include <memory>
#include <type_traits>
#include <utility>
#include <vector>

namespace cr {

template <class T>
struct BigAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = BigAllocator<U>;
  };
  BigAllocator() = default;
  template <class U>
  BigAllocator(const BigAllocator<U>&) noexcept
  {
  }
  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>)
  {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... A>
  void construct(U* p, A&&... a)
  {
    ::new (static_cast<void*>(p)) U(std::forward<A>(a)...);
  }
};

template <class T>
using BigVector = std::vector<T, BigAllocator<T>>;

}  // namespace cr
