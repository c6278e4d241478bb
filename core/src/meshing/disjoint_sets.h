// Union-find over 32-bit ids, shared by the mesher's host code (the quality report's components,
// the attribute transfer's UV charts).
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace gwnrt {

// Union-find over 32-bit ids, by path halving; the smaller root wins so the result does not
// depend on the order of the unions.
class DisjointSets {
 public:
  explicit DisjointSets(size_t n) : parent_(n) {
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

}  // namespace gwnrt
