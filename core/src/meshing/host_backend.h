// The mesher's CPU backend (meshing/mesh_pipeline.h): TBB's parallel_for and parallel_scan over
// std::vector arrays whose large blocks take huge pages and are reused while the backend lives
// (base/host_blocks.h).
#pragma once

#include <atomic>
#include <cstdint>
#include <utility>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_scan.h>

#include "gwnrt/base/host_blocks.h"

namespace gwnrt {

struct HostBackend {
  template <class T>
  using Array = std::vector<T, HostBlockAllocator<T>>;

  // fn(i) for i in [0, n), in chunks of at least `grain` items; `progress` counts finished items.
  template <class Fn>
  void parallel_for(uint64_t n, const Fn& fn, uint64_t grain = 1024, std::atomic<size_t>* progress = nullptr) const {
    if (n == 0) return;
    tbb::parallel_for(tbb::blocked_range<uint64_t>(0, n, grain), [&](const tbb::blocked_range<uint64_t>& r) {
      for (uint64_t i = r.begin(); i != r.end(); ++i) fn(i);
      if (progress) progress->fetch_add(r.size(), std::memory_order_relaxed);
    });
  }

  // out[i] = Σ in[0..i), returning the total (which may exceed 32 bits: the caller checks); out
  // may be in (each item is read before it is written, and a range is written once).
  uint64_t exclusive_scan(const uint32_t* in, uint64_t n, uint32_t* out) const {
    return tbb::parallel_scan(
        tbb::blocked_range<uint64_t>(0, n, 1 << 14), uint64_t(0),
        [&](const tbb::blocked_range<uint64_t>& r, uint64_t sum, bool final) {
          for (uint64_t i = r.begin(); i != r.end(); ++i) {
            const uint32_t item = in[i];
            if (final) out[i] = uint32_t(sum);
            sum += item;
          }
          return sum;
        },
        [](uint64_t a, uint64_t b) { return a + b; });
  }

  template <class T>
  const T& to_host(const Array<T>& a, uint64_t i) const {
    return a[i];
  }
  template <class T>
  void move_out(Array<T>& a, std::vector<T>& dst) const {
    dst.clear();
    dst.reserve(a.size());
    advise_huge_pages(dst.data(), a.size() * sizeof(T));
    dst.assign(a.begin(), a.end());
    a = Array<T>{};
  }

 private:
  HostBlockScope blocks_;
};

}  // namespace gwnrt
