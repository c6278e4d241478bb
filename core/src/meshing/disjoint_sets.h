// Union-find over 32-bit ids, shared by the mesher's host code (the quality report's components
// and fans, the attribute transfer's UV charts).
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "gwnrt/base/host_blocks.h"

namespace gwnrt {

// Union-find over 32-bit ids, by path halving; the smaller root wins so the result does not
// depend on the order of the unions.
class DisjointSets {
 public:
  explicit DisjointSets(size_t n) { reset(n); }
  // n singletons again, keeping the storage (many small sets in a row: a vertex's corners).
  void reset(size_t n) {
    parent_.resize(n);
    for (size_t i = 0; i < n; ++i) parent_[i] = uint32_t(i);
  }
  uint32_t find(uint32_t x) {
    while (parent_[x] != x) {
      parent_[x] = parent_[parent_[x]];
      x = parent_[x];
    }
    return x;
  }
  void unite(uint32_t a, uint32_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return;
    if (a < b) std::swap(a, b);
    parent_[a] = b;
  }

 private:
  std::vector<uint32_t> parent_;
};

// The same for unions from many threads at once: a root is linked under a smaller one by
// compare-and-swap (so no cycle can form and the sets do not depend on the threads' order), and
// finds halve paths by compare-and-swap too, which only ever points an id at an ancestor.
class ConcurrentDisjointSets {
 public:
  explicit ConcurrentDisjointSets(size_t n) : parent_(n) {
    for (size_t i = 0; i < n; ++i) parent_[i] = uint32_t(i);
  }
  uint32_t find(uint32_t x) {
    for (;;) {
      uint32_t p = at(x).load(std::memory_order_relaxed);
      if (p == x) return x;
      const uint32_t g = at(p).load(std::memory_order_relaxed);
      if (g == p) return p;
      at(x).compare_exchange_weak(p, g, std::memory_order_relaxed);
      x = g;
    }
  }
  void unite(uint32_t a, uint32_t b) {
    for (;;) {  // each failed swap means another thread linked the root first
      a = find(a);
      b = find(b);
      if (a == b) return;
      if (a < b) std::swap(a, b);
      uint32_t root = a;
      if (at(a).compare_exchange_strong(root, b, std::memory_order_relaxed)) return;
    }
  }

 private:
  std::atomic_ref<uint32_t> at(uint32_t x) { return std::atomic_ref<uint32_t>(parent_[x]); }
  HostVector<uint32_t> parent_;
};

}  // namespace gwnrt
