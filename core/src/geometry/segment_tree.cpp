// The wide BVH over segments (segment_tree.h).
#include "gwnrt/geometry/segment_tree.h"

namespace gwnrt {

SegmentTreeView SegmentTree::view() const {
  return {bvh.view(),     endpoints.data(),  segment_ids.data(), uint32_t(segment_ids.size()),
          lengths.data(), net_lengths.data()};
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
  tree.lengths = lane_lengths(
      tree.bvh,
      [](const void* c, uint32_t s) {
        const vec3* e = static_cast<const vec3*>(c);
        return glm::length(dvec3(e[2 * s + 1]) - dvec3(e[2 * s]));
      },
      tree.endpoints.data());
  tree.net_lengths = lane_net_lengths(tree.bvh, tree.endpoints);
  out = std::move(tree);
  return Status::Ok();
}

}  // namespace gwnrt
