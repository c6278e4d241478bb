// The flat 4-wide BVH shared by the CPU and the GPU. A node holds, for each of its four
// lanes (children), the child's bounds and what the child is: an inner node, a leaf (a run
// of primitives in leaf order) or nothing. Expansion data (centre, radius, moments) lives in
// separate arrays per order so that a query touches only what its order needs.
// Views are trivially copyable and are what kernels receive; WideBvh owns the arrays.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "gwnrt/base/hd.h"
#include "gwnrt/base/status.h"

namespace gwnrt {

inline constexpr int kBvhWidth = 4;
inline constexpr uint32_t kEmptyLane = 0xFFFFFFFFu;
// A traversal holds at most (width - 1) entries per level plus one; the builder keeps trees
// far shallower than this (median splits halve the largest part at every level).
inline constexpr int kMaxBvhDepth = 40;
inline constexpr int kTraversalStackSize = (kBvhWidth - 1) * kMaxBvhDepth + 1;

// Lane i: count[i] == 0 and child[i] != kEmptyLane: inner node child[i];
//         count[i] > 0: leaf with primitives [child[i], child[i] + count[i]) in leaf order;
//         child[i] == kEmptyLane: unused.
struct alignas(16) WideNode {
  float lo[3][kBvhWidth];
  float hi[3][kBvhWidth];
  uint32_t child[kBvhWidth];
  uint32_t count[kBvhWidth];
};

// Per lane: expansion centre p̄, radius r (no point of the cluster is farther than r from p̄)
// and order-0 moment N.
struct alignas(16) WideNodeExpansion {
  float centre[3][kBvhWidth];
  float radius[kBvhWidth];
  float n[3][kBvhWidth];
};
struct alignas(16) WideNodeOrder1 {
  float s[6][kBvhWidth];
};
struct alignas(16) WideNodeOrder2 {
  float p[10][kBvhWidth];
  float e[3][kBvhWidth];
};

// Per lane: the total length of some curve below it (the cone's share of ∂M, ModelView), so that
// a whole far cluster's share of the tracer's Biot–Savart bound (phase.h) costs one division.
struct alignas(16) WideNodeLength {
  float length[kBvhWidth];
};

// Near-first traversal: a stack entry (a node and how near it is: entry distance along a ray, or
// squared distance to a point), and the push that sorts a node's inner children so that the
// nearest is popped next.
struct NearFirstEntry {
  uint32_t node;
  float key;
};

GWNRT_HD inline void push_near_first(NearFirstEntry* stack, int& sp, NearFirstEntry* children, int count) {
  for (int i = 1; i < count; ++i)  // descending keys: the farthest goes deepest
    for (int j = i; j > 0 && children[j].key > children[j - 1].key; --j) {
      const NearFirstEntry s = children[j];
      children[j] = children[j - 1];
      children[j - 1] = s;
    }
  for (int i = 0; i < count; ++i) stack[sp++] = children[i];
}

struct BvhView {
  const WideNode* nodes = nullptr;
  uint32_t node_count = 0;
};

// Triangles past the last in each of TriangleTreeView::corner_columns.
inline constexpr uint32_t kCornerColumnPadding = 4;

// The multipole tree over the mesh triangles.
struct TriangleTreeView {
  BvhView bvh;
  const WideNodeExpansion* expansion = nullptr;
  const WideNodeOrder1* order1 = nullptr;
  const WideNodeOrder2* order2 = nullptr;
  const vec3* vertices = nullptr;          // 3 per triangle, in leaf order
  const uint32_t* triangle_ids = nullptr;  // leaf order -> input triangle index
  uint32_t triangle_count = 0;
  // The vertices again by coordinate, where the tree has them (add_corner_columns; host only, the
  // device's view leaves them null): coordinate k of corner j of leaf-order triangle t at
  // corner_columns[(3j + k) · column_stride + t], each column padded with copies of the last
  // triangle, so that four triangles from any t load as one vector each.
  const float* corner_columns = nullptr;
  uint32_t column_stride = 0;
  // x on one of the triangles counts 0 for it (solid_angle.h, point_on_triangle): set for M's
  // tree, where w on M is the mean of its one-sided limits; not for the cone C, which is not part
  // of M and where the tracer needs the side its crossing count assumes (the mean would break the
  // band of a ray starting on a planar polygon's cone).
  bool mean_on_triangles = false;
};

// The tree over the boundary curve ∂M (segments a -> b, one per unit of multiplicity).
struct SegmentTreeView {
  BvhView bvh;
  const vec3* endpoints = nullptr;        // 2 per segment, in leaf order
  const uint32_t* segment_ids = nullptr;  // leaf order -> boundary segment index
  uint32_t segment_count = 0;
  const WideNodeLength* lengths = nullptr;  // per node, parallel to bvh.nodes
  // Per node: |Σ (b − a)| over the segments below each lane (rounded up), for the far field of a
  // cluster of closed loops (field/box_winding.h); may be null.
  const WideNodeLength* net_lengths = nullptr;
};

// Per lane of the ribbon tree (geometry/ribbon_tree.h, field/ribbon_winding.h): the apex z of the fan
// over the segments below (a loose end of them, or any endpoint when they close), and their other
// loose ends, RibbonTreeView::loose_ends[first_end, first_end + end_count), or end_count
// kOpenFan where they have more than kMaxLooseEnds (the lane is then never expanded).
inline constexpr uint32_t kMaxLooseEnds = 8;
inline constexpr uint32_t kOpenFan = 0xFFFFFFFFu;
struct alignas(16) WideNodeFan {
  float apex[3][kBvhWidth];
  uint32_t first_end[kBvhWidth];
  uint32_t end_count[kBvhWidth];
};
// A loose end v of a lane's segments: multiplicity = (segments ending at v) − (starting at v).
struct LooseEnd {
  vec3 position;
  float multiplicity;
};

// ∂M's segments clustered for the ribbons: the ribbon tree's BVH (closed trails kept whole) with,
// per lane, the fan's moments (a triangle cluster's: `fans`, whose vertices are unused) and its
// loose ends.
struct RibbonTreeView {
  TriangleTreeView fans;                  // bvh: the ribbon tree's; expansion, order1, order2: the fans'
  const WideNodeFan* fan_ends = nullptr;  // per node, parallel to fans.bvh.nodes
  const LooseEnd* loose_ends = nullptr;
  const vec3* endpoints = nullptr;  // 2 per segment, in the ribbon tree's leaf order
  uint32_t segment_count = 0;
};

struct Aabb {
  vec3 lo{3.4e38f};
  vec3 hi{-3.4e38f};
  GWNRT_HD void extend(const vec3& p) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  GWNRT_HD void extend(const Aabb& b) {
    lo = glm::min(lo, b.lo);
    hi = glm::max(hi, b.hi);
  }
  GWNRT_HD vec3 centre() const { return 0.5f * (lo + hi); }
  GWNRT_HD bool valid() const { return lo.x <= hi.x; }
  GWNRT_HD bool overlaps(const Aabb& b) const {  // the closed boxes share a point
    return lo.x <= b.hi.x && b.lo.x <= hi.x && lo.y <= b.hi.y && b.lo.y <= hi.y && lo.z <= b.hi.z && b.lo.z <= hi.z;
  }
};

// Whether a node's lane box and `box` (both closed) share a point.
GWNRT_HD inline bool lane_meets_box(const WideNode& node, int lane, const Aabb& box) {
  for (int a = 0; a < 3; ++a)
    if (node.lo[a][lane] > box.hi[a] || node.hi[a][lane] < box.lo[a]) return false;
  return true;
}

// Owning topology + bounds, built in parallel by median splits on primitive centroids.
struct WideBvh {
  std::vector<WideNode> nodes;
  std::vector<uint32_t> primitive_order;  // leaf order -> input primitive index
  uint32_t depth = 0;
  BvhView view() const { return {nodes.data(), uint32_t(nodes.size())}; }
};

// With `groups` (a group per primitive: chains, each given in its order), the splits keep groups
// whole while a range holds more than one, and cut one only into runs of consecutive primitives.
Status build_wide_bvh(std::span<const Aabb> primitive_bounds, uint32_t max_leaf_size, WideBvh& out,
                      std::span<const uint32_t> groups = {});

// Per node, the total of length_of(primitive in leaf order) below each lane: bottom-up in double
// (a long curve of short segments would lose its tail in float), each lane's float rounded up so
// that it still bounds the true total (the bounds it enters must not shrink).
std::vector<WideNodeLength> lane_lengths(const WideBvh& bvh, double (*length_of)(const void* context, uint32_t i),
                                         const void* context);

// Per node, |Σ (b − a)| over the segments (a, b) = (endpoints[2i], endpoints[2i + 1]), leaf order,
// below each lane: summed in double, each lane's float rounded up.
std::vector<WideNodeLength> lane_net_lengths(const WideBvh& bvh, std::span<const vec3> endpoints);

}  // namespace gwnrt
