// A wide BVH over line segments (built in core/src/geometry/segment_tree.cpp): the tree over ∂M
// that serves the distance to the boundary.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "gwnrt/geometry/bvh.h"
#include "gwnrt/geometry/model_view.h"

namespace gwnrt {

struct SegmentTree {
  WideBvh bvh;
  std::vector<vec3> endpoints;              // 2 per segment, leaf order
  std::vector<uint32_t> segment_ids;        // leaf order -> segment index
  std::vector<WideNodeLength> lengths;      // per node: the length of ∂M below each lane (rounded up)
  std::vector<WideNodeLength> net_lengths;  // per node: |Σ (b − a)| below each lane (rounded up)
  SegmentTreeView view() const;
};

Status build_segment_tree(std::span<const vec3> endpoints, uint32_t max_leaf_size, SegmentTree& out);

}  // namespace gwnrt
