// Large host blocks on huge pages, reused while a HostBlockScope lives (base/host_blocks.h).
#include "gwnrt/base/host_blocks.h"

#include <algorithm>
#include <map>
#include <mutex>
#include <unordered_map>

#ifdef __linux__
#include <sys/mman.h>
#endif

namespace gwnrt {
namespace {

#ifdef __linux__
constexpr size_t kHugePage = size_t(2) << 20;

struct BlockCache {
  std::mutex mutex;
  int scopes = 0;
  std::multimap<size_t, uintptr_t> kept;         // size → start, free for reuse
  std::unordered_map<uintptr_t, size_t> in_use;  // start → mapped size
  size_t kept_bytes = 0;
};

BlockCache& cache() {
  static BlockCache* c = new BlockCache;  // never destroyed: blocks may be freed during exit
  return *c;
}

size_t mapped_size(size_t bytes) { return (bytes + kHugePage - 1) / kHugePage * kHugePage; }

void unmap(uintptr_t start, size_t size) { munmap(reinterpret_cast<void*>(start), size); }

// A fresh mapping of `size` bytes at a huge-page boundary: one page more is mapped and the
// unaligned head and tail unmapped.
uintptr_t map_block(size_t size) {
  void* p = mmap(nullptr, size + kHugePage, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (p == MAP_FAILED) throw std::bad_alloc();
  const uintptr_t start = reinterpret_cast<uintptr_t>(p), aligned = (start + kHugePage - 1) & ~(kHugePage - 1);
  if (aligned > start) unmap(start, aligned - start);
  unmap(aligned + size, start + kHugePage - aligned);  // the tail: at least a page
  madvise(reinterpret_cast<void*>(aligned), size, MADV_HUGEPAGE);
  return aligned;
}

void unmap_kept(BlockCache& c) {
  for (const auto& [size, start] : c.kept) unmap(start, size);
  c.kept.clear();
  c.kept_bytes = 0;
}
#endif

}  // namespace

void* allocate_host_block(size_t bytes, size_t alignment) {
#ifdef __linux__
  if (bytes >= kLargeHostBlock && alignment <= kHugePage) {
    if (bytes > SIZE_MAX - 2 * kHugePage) throw std::bad_alloc();  // rounded up, it would wrap
    const size_t size = mapped_size(bytes);
    BlockCache& c = cache();
    std::lock_guard<std::mutex> lock(c.mutex);
    uintptr_t start = 0;
    if (auto it = c.kept.lower_bound(size); it != c.kept.end()) {
      const auto [have, at] = *it;
      c.kept.erase(it);
      c.kept_bytes -= have;
      start = at;
      if (have > size) {  // the rest stays kept, a block of its own
        c.kept.emplace(have - size, at + size);
        c.kept_bytes += have - size;
      }
    } else {
      unmap_kept(c);
      start = map_block(size);
    }
    try {
      c.in_use.emplace(start, size);
    } catch (...) {
      unmap(start, size);
      throw;
    }
    return reinterpret_cast<void*>(start);
  }
#endif
  return ::operator new(bytes, std::align_val_t(alignment));
}

void free_host_block(void* block, size_t bytes, size_t alignment) noexcept {
  if (!block) return;
#ifdef __linux__
  if (bytes >= kLargeHostBlock && alignment <= kHugePage) {
    BlockCache& c = cache();
    std::lock_guard<std::mutex> lock(c.mutex);
    const uintptr_t start = reinterpret_cast<uintptr_t>(block);
    const auto it = c.in_use.find(start);
    const size_t size = it != c.in_use.end() ? it->second : mapped_size(bytes);
    if (it != c.in_use.end()) c.in_use.erase(it);
    try {
      if (c.scopes > 0) {
        c.kept.emplace(size, start);
        c.kept_bytes += size;
        return;
      }
    } catch (...) {  // no room to keep it: given back instead
    }
    unmap(start, size);
    return;
  }
#endif
  ::operator delete(block, bytes, std::align_val_t(alignment));
}

HostBlockScope::HostBlockScope() {
#ifdef __linux__
  BlockCache& c = cache();
  std::lock_guard<std::mutex> lock(c.mutex);
  ++c.scopes;
#endif
}

HostBlockScope::~HostBlockScope() {
#ifdef __linux__
  BlockCache& c = cache();
  std::lock_guard<std::mutex> lock(c.mutex);
  if (--c.scopes == 0) unmap_kept(c);
#endif
}

void advise_huge_pages(void* data, size_t bytes) noexcept {
#ifdef __linux__
  const uintptr_t start = reinterpret_cast<uintptr_t>(data);
  const uintptr_t first = (start + kHugePage - 1) & ~(kHugePage - 1), last = (start + bytes) & ~(kHugePage - 1);
  if (last > first) madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
#else
  (void)data;
  (void)bytes;
#endif
}

size_t kept_host_block_bytes() {
#ifdef __linux__
  BlockCache& c = cache();
  std::lock_guard<std::mutex> lock(c.mutex);
  return c.kept_bytes;
#else
  return 0;
#endif
}

}  // namespace gwnrt
