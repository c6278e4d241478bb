// ∂M and the small tree over it that serves distance-to-boundary (and, later, Harnack radii).
#include <algorithm>
#include <array>
#include <cstring>

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "gwnrt/model.h"

namespace gwnrt {
namespace {

// Welds vertices with bit-identical positions (after folding -0 into +0) so that half-edges
// cancel geometrically, not only by index: OBJ soups often repeat shared corners.
std::vector<uint32_t> weld_by_position(const std::vector<vec3>& positions) {
  const size_t n = positions.size();
  auto key = [&](uint32_t i) {
    std::array<uint32_t, 3> k;
    for (int a = 0; a < 3; ++a) {
      const float v = positions[i][a] + 0.0f;  // -0 + 0 = +0
      std::memcpy(&k[a], &v, sizeof v);
    }
    return k;
  };
  std::vector<uint32_t> order(n);
  for (size_t i = 0; i < n; ++i) order[i] = uint32_t(i);
  tbb::parallel_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    const auto ka = key(a), kb = key(b);
    return ka != kb ? ka < kb : a < b;
  });
  std::vector<uint32_t> canonical(n);
  for (size_t i = 0; i < n; ++i)
    canonical[order[i]] = (i > 0 && key(order[i]) == key(order[i - 1])) ? canonical[order[i - 1]] : order[i];
  return canonical;
}

}  // namespace

BoundaryCurve extract_boundary(const Mesh& mesh) {
  const std::vector<uint32_t> canonical = weld_by_position(mesh.positions);
  struct HalfEdge {
    uint64_t key;  // (min << 32) | max of the welded endpoints
    int32_t sign;  // +1 when the triangle walks min -> max
  };
  const size_t nt = mesh.triangles.size();
  std::vector<HalfEdge> half_edges(3 * nt, HalfEdge{~uint64_t(0), 0});
  tbb::parallel_for(size_t(0), nt, [&](size_t t) {
    const uvec3 tri = mesh.triangles[t];
    if (is_degenerate_triangle(mesh.positions[tri[0]], mesh.positions[tri[1]], mesh.positions[tri[2]])) return;
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = canonical[tri[k]], b = canonical[tri[(k + 1) % 3]];
      if (a == b) continue;
      half_edges[3 * t + k] = {(uint64_t(std::min(a, b)) << 32) | std::max(a, b), a < b ? 1 : -1};
    }
  });
  tbb::parallel_sort(half_edges.begin(), half_edges.end(),
                     [](const HalfEdge& x, const HalfEdge& y) { return x.key < y.key; });

  BoundaryCurve curve;
  for (size_t i = 0; i < half_edges.size();) {
    size_t j = i;
    int sum = 0;
    while (j < half_edges.size() && half_edges[j].key == half_edges[i].key) sum += half_edges[j++].sign;
    if (half_edges[i].sign != 0 && sum != 0) {
      const vec3 lo = mesh.positions[uint32_t(half_edges[i].key >> 32)];
      const vec3 hi = mesh.positions[uint32_t(half_edges[i].key & 0xFFFFFFFFu)];
      for (int m = 0; m < std::abs(sum); ++m) {
        curve.endpoints.push_back(sum > 0 ? lo : hi);
        curve.endpoints.push_back(sum > 0 ? hi : lo);
      }
    }
    i = j;
  }
  return curve;
}

Mesh boundary_cone(const BoundaryCurve& curve) {
  Mesh cone;
  const size_t n = curve.segment_count();
  if (n == 0) return cone;
  dvec3 sum(0.0);
  for (const vec3& p : curve.endpoints) sum += dvec3(p);
  cone.positions.reserve(2 * n + 1);
  cone.positions.push_back(vec3(sum / double(curve.endpoints.size())));
  cone.positions.insert(cone.positions.end(), curve.endpoints.begin(), curve.endpoints.end());
  cone.triangles.reserve(n);
  for (uint32_t s = 0; s < n; ++s) cone.triangles.push_back({0u, 1 + 2 * s, 2 + 2 * s});
  return cone;
}

SegmentTreeView SegmentTree::view() const {
  return {bvh.view(), endpoints.data(), segment_ids.data(), uint32_t(segment_ids.size())};
}

SegmentTree build_segment_tree(std::span<const vec3> endpoints, uint32_t max_leaf_size) {
  const size_t n = endpoints.size() / 2;
  std::vector<Aabb> bounds(n);
  for (size_t s = 0; s < n; ++s) {
    bounds[s].extend(endpoints[2 * s]);
    bounds[s].extend(endpoints[2 * s + 1]);
  }
  SegmentTree tree;
  tree.bvh = build_wide_bvh(bounds, max_leaf_size);
  tree.segment_ids = tree.bvh.primitive_order;
  tree.endpoints.resize(2 * n);
  for (size_t i = 0; i < n; ++i) {
    tree.endpoints[2 * i] = endpoints[2 * tree.segment_ids[i]];
    tree.endpoints[2 * i + 1] = endpoints[2 * tree.segment_ids[i] + 1];
  }
  return tree;
}

}  // namespace gwnrt
