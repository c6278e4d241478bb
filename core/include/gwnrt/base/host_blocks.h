// Large host arrays on huge pages, their blocks reused while a run lasts (definitions:
// core/src/base/host_blocks.cpp). On a virtual machine a page fault costs microseconds, and the
// mesher's passes fill, free and refill hundreds of MiB: with 4 KiB pages and every large block
// unmapped when freed, faults and zeroing took up to half of its time (docs/performance.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <new>
#include <vector>

namespace gwnrt {

// From this size a block is mapped on its own, 2 MiB-aligned and advised to take huge pages.
inline constexpr size_t kLargeHostBlock = size_t(1) << 20;

// Throws std::bad_alloc (the callers' guard_status turns it into a Status).
void* allocate_host_block(size_t bytes, size_t alignment);
void free_host_block(void* block, size_t bytes, size_t alignment) noexcept;

// While one lives, large blocks freed are kept and handed out again (a larger one cut to size);
// an allocation none fits unmaps those kept first, so the memory mapped never exceeds the peak of
// what is in use. When the last scope ends, what is kept is unmapped.
class HostBlockScope {
 public:
  HostBlockScope();
  ~HostBlockScope();
  HostBlockScope(const HostBlockScope&) = delete;
  HostBlockScope& operator=(const HostBlockScope&) = delete;
};

// Advises the whole huge pages inside [data, data + bytes), not yet touched, to take huge pages:
// for a large std::vector reserved before it is filled (the mesher's output).
void advise_huge_pages(void* data, size_t bytes) noexcept;

// The mapped bytes kept for reuse now (tests).
size_t kept_host_block_bytes();

template <class T>
struct HostBlockAllocator {
  using value_type = T;
  HostBlockAllocator() = default;
  template <class U>
  HostBlockAllocator(const HostBlockAllocator<U>&) noexcept {}
  T* allocate(size_t n) {
    if (n > SIZE_MAX / sizeof(T)) throw std::bad_array_new_length();
    return static_cast<T*>(allocate_host_block(n * sizeof(T), alignof(T)));
  }
  void deallocate(T* p, size_t n) noexcept { free_host_block(p, n * sizeof(T), alignof(T)); }
  template <class U>
  bool operator==(const HostBlockAllocator<U>&) const noexcept {
    return true;
  }
};

// A std::vector on them (inside a HostBlockScope, its large blocks reused).
template <class T>
using HostVector = std::vector<T, HostBlockAllocator<T>>;

}  // namespace gwnrt
