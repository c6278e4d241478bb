// Parallel top-down build of the 4-wide BVH. Median splits on centroids keep the tree balanced
// (depth <= log2 n), which is what multipole evaluation wants: compact clusters at every level.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_group.h>

#include "gwnrt/geometry/bvh.h"

namespace gwnrt {
namespace {

constexpr uint32_t kParallelGrain = 4096;  // smaller subtrees are built in the calling task

struct Range {
  uint32_t begin, end;
  uint32_t size() const { return end - begin; }
};

class Builder {
 public:
  Builder(std::span<const Aabb> bounds, uint32_t max_leaf, std::span<const uint32_t> groups, WideBvh& out)
      : bounds_(bounds), groups_(groups), max_leaf_(std::max<uint32_t>(1, max_leaf)), out_(out) {
    const size_t n = bounds.size();
    centroids_.resize(n);
    out_.primitive_order.resize(n);
    for (size_t i = 0; i < n; ++i) {
      centroids_[i] = bounds[i].centre();
      out_.primitive_order[i] = uint32_t(i);
    }
    out_.nodes.resize(std::max<size_t>(1, n));
    if (groups.empty()) return;
    // Each group's centroid: the mean of its primitives'.
    std::vector<dvec3> sum;
    std::vector<uint32_t> count;
    for (size_t i = 0; i < n; ++i) {
      if (groups[i] >= sum.size()) {
        sum.resize(groups[i] + 1, dvec3(0.0));
        count.resize(groups[i] + 1, 0);
      }
      sum[groups[i]] += dvec3(centroids_[i]);
      ++count[groups[i]];
    }
    group_centroids_.resize(sum.size());
    for (size_t g = 0; g < sum.size(); ++g)
      group_centroids_[g] = count[g] > 0 ? vec3(sum[g] / double(count[g])) : vec3(0.0f);
  }

  bool run() {
    next_node_ = 1;
    build(0, {0, uint32_t(bounds_.size())}, 1);
    out_.nodes.resize(next_node_.load());
    out_.depth = max_depth_.load();
    return !too_deep_.load();
  }

 private:
  Aabb centroid_bounds(Range r) const {
    auto reduce = [&](const tbb::blocked_range<uint32_t>& br, Aabb box) {
      for (uint32_t i = br.begin(); i != br.end(); ++i) box.extend(centroids_[out_.primitive_order[i]]);
      return box;
    };
    if (r.size() < kParallelGrain) return reduce(tbb::blocked_range<uint32_t>(r.begin, r.end), Aabb{});
    return tbb::parallel_reduce(tbb::blocked_range<uint32_t>(r.begin, r.end, kParallelGrain), Aabb{}, reduce,
                                [](Aabb a, const Aabb& b) {
                                  a.extend(b);
                                  return a;
                                });
  }

  // With groups: r ordered by its groups' centroids along their box's longest axis, each group's
  // primitives in their own order, and split at the group boundary nearest the median, or within
  // the one group r holds at its median.
  uint32_t group_split(Range r) {
    uint32_t* order = out_.primitive_order.data();
    Aabb box;
    for (uint32_t i = r.begin; i < r.end; ++i) box.extend(group_centroids_[groups_[order[i]]]);
    const vec3 extent = box.hi - box.lo;
    const int axis = extent.x >= extent.y ? (extent.x >= extent.z ? 0 : 2) : (extent.y >= extent.z ? 1 : 2);
    std::sort(order + r.begin, order + r.end, [&](uint32_t a, uint32_t b) {
      const float ka = group_centroids_[groups_[a]][axis], kb = group_centroids_[groups_[b]][axis];
      return ka != kb ? ka < kb : (groups_[a] != groups_[b] ? groups_[a] < groups_[b] : a < b);
    });
    const uint32_t mid = r.begin + r.size() / 2;
    const auto boundary = [&](uint32_t i) { return groups_[order[i - 1]] != groups_[order[i]]; };
    for (uint32_t step = 0; step < r.size(); ++step) {  // the nearest boundary, below first (mid > r.begin)
      if (step < mid - r.begin && boundary(mid - step)) return mid - step;
      if (mid + step < r.end && boundary(mid + step)) return mid + step;
    }
    return mid;  // one group
  }

  // Splits r at its median along the longest axis of its centroids' box.
  uint32_t median_split(Range r) {
    if (!groups_.empty()) return group_split(r);
    const Aabb box = centroid_bounds(r);
    const vec3 extent = box.hi - box.lo;
    const int axis = extent.x >= extent.y ? (extent.x >= extent.z ? 0 : 2) : (extent.y >= extent.z ? 1 : 2);
    const uint32_t mid = r.begin + r.size() / 2;
    uint32_t* order = out_.primitive_order.data();
    std::nth_element(order + r.begin, order + mid, order + r.end,
                     [&](uint32_t a, uint32_t b) { return centroids_[a][axis] < centroids_[b][axis]; });
    return mid;
  }

  Aabb build(uint32_t node_index, Range range, uint32_t depth) {
    uint32_t prev = max_depth_.load();
    while (depth > prev && !max_depth_.compare_exchange_weak(prev, depth)) {
    }
    // Median splits halve every range, so depth <= log2(n) + 1 <= 33 for 32-bit counts; deeper
    // would overflow the traversal stacks, so it is refused rather than built.
    if (depth > uint32_t(kMaxBvhDepth)) {
      too_deep_ = true;
      return {};
    }

    // Split the largest part until there are four or none can be split.
    Range parts[kBvhWidth];
    int part_count = 1;
    parts[0] = range;
    while (part_count < kBvhWidth) {
      int largest = -1;
      for (int i = 0; i < part_count; ++i)
        if (parts[i].size() > max_leaf_ && (largest < 0 || parts[i].size() > parts[largest].size())) largest = i;
      if (largest < 0) break;
      const uint32_t mid = median_split(parts[largest]);
      for (int i = part_count; i > largest + 1; --i) parts[i] = parts[i - 1];
      parts[largest + 1] = {mid, parts[largest].end};
      parts[largest].end = mid;
      ++part_count;
    }

    WideNode node{};
    Aabb lane_bounds[kBvhWidth];
    tbb::task_group tasks;
    for (int i = 0; i < kBvhWidth; ++i) {
      node.child[i] = kEmptyLane;
      node.count[i] = 0;
      if (i >= part_count) continue;
      const Range part = parts[i];
      if (part.size() <= max_leaf_) {
        node.child[i] = part.begin;
        node.count[i] = part.size();
        for (uint32_t k = part.begin; k < part.end; ++k) lane_bounds[i].extend(bounds_[out_.primitive_order[k]]);
      } else {
        const uint32_t child = next_node_.fetch_add(1);
        node.child[i] = child;
        if (part.size() >= kParallelGrain)
          tasks.run([this, child, part, depth, &lane_bounds, i] { lane_bounds[i] = build(child, part, depth + 1); });
        else
          lane_bounds[i] = build(child, part, depth + 1);
      }
    }
    tasks.wait();

    Aabb total;
    for (int i = 0; i < kBvhWidth; ++i) {
      // Empty lanes get an inverted box so that box tests reject them.
      for (int a = 0; a < 3; ++a) {
        node.lo[a][i] = lane_bounds[i].lo[a];
        node.hi[a][i] = lane_bounds[i].hi[a];
      }
      if (i < part_count) total.extend(lane_bounds[i]);
    }
    out_.nodes[node_index] = node;
    return total;
  }

  std::span<const Aabb> bounds_;
  std::span<const uint32_t> groups_;
  std::vector<vec3> group_centroids_;
  uint32_t max_leaf_;
  WideBvh& out_;
  std::vector<vec3> centroids_;
  std::atomic<uint32_t> next_node_{1};
  std::atomic<uint32_t> max_depth_{0};
  std::atomic<bool> too_deep_{false};
};

}  // namespace

Status build_wide_bvh(std::span<const Aabb> primitive_bounds, uint32_t max_leaf_size, WideBvh& out,
                      std::span<const uint32_t> groups) {
  WideBvh bvh;
  if (!groups.empty() && groups.size() != primitive_bounds.size())
    return {StatusCode::kInvalidArgument, "BVH build: " + std::to_string(groups.size()) + " groups for " +
                                              std::to_string(primitive_bounds.size()) + " primitives"};
  if (primitive_bounds.size() > size_t(std::numeric_limits<uint32_t>::max()))
    return {StatusCode::kInvalidArgument, "BVH build: more than 2^32 - 1 primitives"};
  if (!primitive_bounds.empty() && !Builder(primitive_bounds, max_leaf_size, groups, bvh).run())
    return {StatusCode::kInternal, "BVH build: deeper than kMaxBvhDepth (" + std::to_string(kMaxBvhDepth) + ")"};
  out = std::move(bvh);
  return Status::Ok();
}

namespace {

// Per node, for each lane, the norm of the total of value_of(primitive in leaf order) below it:
// bottom-up in double, each lane's float rounded up.
template <class Total, class ValueOf, class Norm>
std::vector<WideNodeLength> lane_totals(const WideBvh& bvh, ValueOf value_of, Norm norm) {
  std::vector<WideNodeLength> out(bvh.nodes.size(), WideNodeLength{});
  auto node_total = [&](auto& self, uint32_t index) -> Total {
    const WideNode& node = bvh.nodes[index];
    Total total{};
    for (int l = 0; l < kBvhWidth; ++l) {
      Total lane{};
      if (node.count[l] > 0) {
        for (uint32_t i = node.child[l]; i < node.child[l] + node.count[l]; ++i) lane += value_of(i);
      } else if (node.child[l] != kEmptyLane) {
        lane = self(self, node.child[l]);
      }
      const double size = norm(lane);
      out[index].length[l] = size > 0 ? std::nextafter(float(size), kInfinity) : 0.0f;
      total += lane;
    }
    return total;
  };
  if (!bvh.nodes.empty()) node_total(node_total, 0);
  return out;
}

}  // namespace

std::vector<WideNodeLength> lane_lengths(const WideBvh& bvh, double (*length_of)(const void* context, uint32_t i),
                                         const void* context) {
  return lane_totals<double>(
      bvh, [&](uint32_t i) { return length_of(context, i); }, [](double x) { return x; });
}

std::vector<WideNodeLength> lane_net_lengths(const WideBvh& bvh, std::span<const vec3> endpoints) {
  return lane_totals<dvec3>(
      bvh, [&](uint32_t i) { return dvec3(endpoints[2 * i + 1]) - dvec3(endpoints[2 * i]); },
      [](const dvec3& v) { return glm::length(v); });
}

}  // namespace gwnrt
