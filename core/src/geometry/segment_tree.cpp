// The wide BVH over segments (segment_tree.h).
#include "gwnrt/geometry/segment_tree.h"

#include <cmath>

namespace gwnrt {

SegmentTreeView SegmentTree::view() const {
  return {bvh.view(), endpoints.data(), segment_ids.data(), uint32_t(segment_ids.size()), lengths.data()};
}

Status build_segment_tree(std::span<const vec3> endpoints, uint32_t max_leaf_size, SegmentTree& out) {
  const size_t n = endpoints.size() / 2;
  std::vector<Aabb> bounds(n);
  for (size_t s = 0; s < n; ++s) {
    bounds[s].extend(endpoints[2 * s]);
    bounds[s].extend(endpoints[2 * s + 1]);
  }
  SegmentTree tree;
  if (Status s = build_wide_bvh(bounds, max_leaf_size, tree.bvh); !s.ok()) return s;
  tree.segment_ids = tree.bvh.primitive_order;
  tree.endpoints.resize(2 * n);
  for (size_t i = 0; i < n; ++i) {
    tree.endpoints[2 * i] = endpoints[2 * tree.segment_ids[i]];
    tree.endpoints[2 * i + 1] = endpoints[2 * tree.segment_ids[i] + 1];
  }
  // Bottom-up, in double (a long curve of short segments would lose its tail in float), and
  // rounded up so that the float total still bounds the true one.
  tree.lengths.assign(tree.bvh.nodes.size(), WideNodeLength{});
  auto node_length = [&](auto& self, uint32_t index) -> double {
    const WideNode& node = tree.bvh.nodes[index];
    double total = 0;
    for (int l = 0; l < kBvhWidth; ++l) {
      double lane = 0;
      if (node.count[l] > 0) {
        for (uint32_t s = node.child[l]; s < node.child[l] + node.count[l]; ++s)
          lane += glm::length(dvec3(tree.endpoints[2 * s + 1]) - dvec3(tree.endpoints[2 * s]));
      } else if (node.child[l] != kEmptyLane) {
        lane = self(self, node.child[l]);
      }
      tree.lengths[index].length[l] = lane > 0 ? std::nextafter(float(lane), kInfinity) : 0.0f;
      total += lane;
    }
    return total;
  };
  if (!tree.bvh.nodes.empty()) node_length(node_length, 0);
  out = std::move(tree);
  return Status::Ok();
}

}  // namespace gwnrt
