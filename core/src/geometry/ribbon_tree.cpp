// The ribbon tree (ribbon_tree.h): each lane's loose ends and fan, computed from all the segments
// below it (a fan's apex differs from its children's, so its moments are not theirs combined).
#include "gwnrt/geometry/ribbon_tree.h"

#include <algorithm>
#include <cmath>
#include <tuple>

#include <tbb/parallel_for.h>

#include "geometry/raw_moments.h"

namespace gwnrt {
namespace {

bool position_less(const vec3& a, const vec3& b) { return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z); }

// ∂M's segments as closed trails, each segment starting where the last one ended (∂M has as many
// segments into each vertex as out of it): `order` lists them trail by trail, `trail` the trail
// of each listed one.
void closed_trails(std::span<const vec3> endpoints, std::vector<uint32_t>& order, std::vector<uint32_t>& trail) {
  const uint32_t n = uint32_t(endpoints.size() / 2);
  std::vector<uint32_t> by_start(n);
  for (uint32_t s = 0; s < n; ++s) by_start[s] = s;
  const auto start_less = [&](uint32_t a, uint32_t b) { return position_less(endpoints[2 * a], endpoints[2 * b]); };
  std::sort(by_start.begin(), by_start.end(), start_less);
  std::vector<uint8_t> used(n, 0);
  order.clear();
  trail.clear();
  uint32_t trails = 0;
  for (uint32_t first = 0; first < n; ++first) {
    if (used[first]) continue;
    for (uint32_t s = first; s != kEmptyLane;) {  // each step uses a segment: at most n steps in all
      used[s] = 1;
      order.push_back(s);
      trail.push_back(trails);
      const vec3& end = endpoints[2 * s + 1];
      auto it = std::lower_bound(by_start.begin(), by_start.end(), end,
                                 [&](uint32_t a, const vec3& p) { return position_less(endpoints[2 * a], p); });
      s = kEmptyLane;
      for (; it != by_start.end() && endpoints[2 * *it] == end; ++it)
        if (!used[*it]) {
          s = *it;
          break;
        }
    }
    ++trails;
  }
}

// The segments below a lane, in leaf order.
void collect_segments(const WideBvh& bvh, const WideNode& node, int lane, std::vector<uint32_t>& out) {
  if (node.count[lane] > 0) {
    for (uint32_t s = node.child[lane]; s < node.child[lane] + node.count[lane]; ++s) out.push_back(s);
    return;
  }
  const WideNode& child = bvh.nodes[node.child[lane]];
  for (int l = 0; l < kBvhWidth; ++l)
    if (child.child[l] != kEmptyLane) collect_segments(bvh, child, l, out);
}

// The loose ends of `segments` (endpoints at the same position are one vertex): every position
// whose multiplicity is not 0, in position order.
std::vector<LooseEnd> loose_ends_of(const std::vector<vec3>& endpoints, const std::vector<uint32_t>& segments) {
  std::vector<LooseEnd> ends;
  ends.reserve(2 * segments.size());
  for (const uint32_t s : segments) {
    ends.push_back({endpoints[2 * s], -1.0f});
    ends.push_back({endpoints[2 * s + 1], 1.0f});
  }
  std::sort(ends.begin(), ends.end(),
            [](const LooseEnd& a, const LooseEnd& b) { return position_less(a.position, b.position); });
  std::vector<LooseEnd> loose;
  for (size_t i = 0; i < ends.size();) {
    size_t j = i;
    float multiplicity = 0.0f;  // small whole numbers: exact in float
    for (; j < ends.size() && ends[j].position == ends[i].position; ++j) multiplicity += ends[j].multiplicity;
    if (multiplicity != 0.0f) loose.push_back({ends[i].position, multiplicity});
    i = j;
  }
  return loose;
}

// Lane `lane` of node `index`: its fan's moments about their area-weighted centroid, and its
// loose ends (all but the apex) appended to `ends` unless they are too many.
void build_lane(const RibbonTree& tree, uint32_t index, int lane, WideNodeFan& fan, WideNodeExpansion& ex,
                WideNodeOrder1& o1, WideNodeOrder2& o2, std::vector<LooseEnd>& ends) {
  const WideNode& node = tree.bvh.nodes[index];
  std::vector<uint32_t> segments;
  collect_segments(tree.bvh, node, lane, segments);
  const std::vector<LooseEnd> loose = loose_ends_of(tree.endpoints, segments);
  const vec3 apex = loose.empty() ? tree.endpoints[2 * segments.front()] : loose.front().position;
  for (int a = 0; a < 3; ++a) fan.apex[a][lane] = apex[a];
  if (loose.size() > kMaxLooseEnds + 1) {
    fan.first_end[lane] = 0;
    fan.end_count[lane] = kOpenFan;
  } else {
    fan.first_end[lane] = uint32_t(ends.size());
    fan.end_count[lane] = loose.empty() ? 0 : uint32_t(loose.size() - 1);
    if (!loose.empty()) ends.insert(ends.end(), loose.begin() + 1, loose.end());
  }
  const dvec3 z(apex);
  dvec3 weighted(0.0), plain(0.0);
  double area = 0;
  for (const uint32_t s : segments) {
    const dvec3 a(tree.endpoints[2 * s]), b(tree.endpoints[2 * s + 1]);
    const double t = 0.5 * glm::length(glm::cross(a - z, b - z));
    weighted += t * (z + a + b) / 3.0;
    plain += (z + a + b) / 3.0;
    area += t;
  }
  RawMoments m;
  m.centre = area > 0 ? weighted / area : plain / double(segments.size());
  for (const uint32_t s : segments) {
    const dvec3 p[3] = {z, dvec3(tree.endpoints[2 * s]), dvec3(tree.endpoints[2 * s + 1])};
    add_triangle_moments(p, m.centre, m);
  }
  // Every fan triangle lies in the lane's box (its corners are endpoints below the lane).
  m.radius = farthest_corner(node, lane, m.centre);
  store_lane_moments(m, lane, ex, o1, o2);
}

}  // namespace

RibbonTreeView RibbonTree::view() const {
  RibbonTreeView v;
  v.fans.bvh = bvh.view();
  v.fans.expansion = expansion.data();
  v.fans.order1 = order1.data();
  v.fans.order2 = order2.data();
  v.fan_ends = fan_ends.data();
  v.loose_ends = loose_ends.data();
  v.endpoints = endpoints.data();
  v.segment_count = uint32_t(endpoints.size() / 2);
  return v;
}

Status build_ribbon_tree(std::span<const vec3> endpoints, uint32_t max_leaf_size, RibbonTree& out) {
  RibbonTree tree;
  std::vector<uint32_t> order, trail;
  closed_trails(endpoints, order, trail);
  std::vector<Aabb> bounds(order.size());
  for (size_t i = 0; i < order.size(); ++i) {
    bounds[i].extend(endpoints[2 * order[i]]);
    bounds[i].extend(endpoints[2 * order[i] + 1]);
  }
  if (Status s = build_wide_bvh(bounds, max_leaf_size, tree.bvh, trail); !s.ok()) return s;
  tree.endpoints.resize(2 * order.size());
  for (size_t i = 0; i < order.size(); ++i) {
    const uint32_t s = order[tree.bvh.primitive_order[i]];
    tree.endpoints[2 * i] = endpoints[2 * s];
    tree.endpoints[2 * i + 1] = endpoints[2 * s + 1];
  }
  const size_t n = tree.endpoints.empty() ? 0 : tree.bvh.nodes.size();
  tree.expansion.assign(n, WideNodeExpansion{});
  tree.order1.assign(n, WideNodeOrder1{});
  tree.order2.assign(n, WideNodeOrder2{});
  tree.fan_ends.assign(n, WideNodeFan{});
  std::vector<std::vector<LooseEnd>> node_ends(n);
  tbb::parallel_for(size_t(0), n, [&](size_t k) {
    const WideNode& node = tree.bvh.nodes[k];
    for (int l = 0; l < kBvhWidth; ++l) {
      if (node.child[l] == kEmptyLane) {
        // An empty lane is never far (NaN centre) and is skipped when near.
        for (int a = 0; a < 3; ++a) tree.expansion[k].centre[a][l] = NAN;
        tree.fan_ends[k].end_count[l] = kOpenFan;
        continue;
      }
      build_lane(tree, uint32_t(k), l, tree.fan_ends[k], tree.expansion[k], tree.order1[k], tree.order2[k],
                 node_ends[k]);
    }
  });
  // The nodes' loose ends as one array: first_end was relative to the node's own list.
  for (size_t k = 0; k < n; ++k) {
    const uint32_t base = uint32_t(tree.loose_ends.size());
    for (int l = 0; l < kBvhWidth; ++l)
      if (tree.fan_ends[k].end_count[l] != kOpenFan) tree.fan_ends[k].first_end[l] += base;
    tree.loose_ends.insert(tree.loose_ends.end(), node_ends[k].begin(), node_ends[k].end());
  }
  out = std::move(tree);
  return Status::Ok();
}

}  // namespace gwnrt
