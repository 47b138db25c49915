#pragma once
// Private helper: a std::vector whose resize leaves new elements of trivial types uninitialised
// (default-initialised), for large arrays that a parallel loop fills completely. Zeroing them
// first would touch every fresh page from one thread; left alone, each page is first touched
// (and zeroed by the kernel) by the thread that fills it.
#include <memory>
#include <utility>
#include <vector>

namespace vpm::detail {

template <class T>
struct DefaultInitAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = DefaultInitAllocator<U>;
  };
  DefaultInitAllocator() = default;
  template <class U>
  DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}
  template <class U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

/// std::vector<T> whose resize(n) does not zero the new elements.
template <class T>
using UninitVector = std::vector<T, DefaultInitAllocator<T>>;

}  // namespace vpm::detail
