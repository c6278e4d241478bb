// A static k-d tree over points, k nearest neighbours: the accuracy study's smooth reference
// finds the nearest of its points on S with it. Implicit: the median of each range is its node.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <numeric>
#include <vector>

#include "gwnrt/base/hd.h"

namespace gwnrt::reference {

class KdTree {
 public:
  static constexpr size_t kMaxK = 16;

  explicit KdTree(const std::vector<dvec3>& points) : points_(points), index_(points.size()), axis_(points.size()) {
    std::iota(index_.begin(), index_.end(), 0u);
    build(0, index_.size());
  }

  // The k nearest (k <= kMaxK, fewer when there are fewer points), nearest first.
  size_t nearest(const dvec3& x, size_t k, uint32_t* ids, double* d2) const {
    Heap heap{ids, d2, std::min(k, kMaxK), 0};
    search(0, index_.size(), x, heap);
    return heap.size;
  }

 private:
  struct Heap {  // a sorted array: k is small
    uint32_t* ids;
    double* d2;
    size_t k, size;
    double bound() const { return size < k ? kInfinity : d2[size - 1]; }
    void offer(uint32_t id, double d) {
      if (d >= bound()) return;
      size_t i = size < k ? size++ : size - 1;
      for (; i > 0 && d2[i - 1] > d; --i) {
        d2[i] = d2[i - 1];
        ids[i] = ids[i - 1];
      }
      d2[i] = d;
      ids[i] = id;
    }
  };

  void build(size_t lo, size_t hi) {
    if (hi - lo <= 1) return;
    dvec3 a(kInfinity), b(-kInfinity);
    for (size_t i = lo; i < hi; ++i) {
      a = glm::min(a, points_[index_[i]]);
      b = glm::max(b, points_[index_[i]]);
    }
    const dvec3 e = b - a;
    const int axis = e.x >= e.y && e.x >= e.z ? 0 : (e.y >= e.z ? 1 : 2);
    const size_t mid = (lo + hi) / 2;
    std::nth_element(index_.begin() + lo, index_.begin() + mid, index_.begin() + hi,
                     [&](uint32_t i, uint32_t j) { return points_[i][axis] < points_[j][axis]; });
    axis_[mid] = uint8_t(axis);
    build(lo, mid);
    build(mid + 1, hi);
  }

  void search(size_t lo, size_t hi, const dvec3& x, Heap& heap) const {
    if (lo >= hi) return;
    const size_t mid = (lo + hi) / 2;
    const dvec3& p = points_[index_[mid]];
    const dvec3 d = p - x;
    heap.offer(index_[mid], glm::dot(d, d));
    if (hi - lo == 1) return;
    const double diff = x[axis_[mid]] - p[axis_[mid]];
    const bool left_first = diff < 0;
    search(left_first ? lo : mid + 1, left_first ? mid : hi, x, heap);
    if (diff * diff < heap.bound()) search(left_first ? mid + 1 : lo, left_first ? hi : mid, x, heap);
  }

  const std::vector<dvec3>& points_;
  std::vector<uint32_t> index_;
  std::vector<uint8_t> axis_;
};

}  // namespace gwnrt::reference
