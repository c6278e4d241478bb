// Unsigned distance to the mesh M (closest triangle, barycentrics) and distance to the
// boundary curve ∂M, by near-first traversal of the wide BVH. Host-and-device.
#pragma once

#include "gwnrt/geometry/bvh.h"

namespace gwnrt {

template <class T>
struct ClosestPoint {
  glm::vec<3, T> point;
  T u, v;  // point = (1 - u - v) p0 + u p1 + v p2   (segments: point = (1 - u) p0 + u p1, v = 0)
};

template <class T>
GWNRT_HD inline ClosestPoint<T> closest_point_on_segment(const glm::vec<3, T>& a, const glm::vec<3, T>& b,
                                                         const glm::vec<3, T>& x) {
  const glm::vec<3, T> ab = b - a;
  const T len2 = glm::dot(ab, ab);
  T t = len2 > 0 ? glm::dot(x - a, ab) / len2 : T(0);
  t = t < 0 ? T(0) : (t > 1 ? T(1) : t);
  return {a + t * ab, t, 0};
}

// Closest point of triangle (p0, p1, p2) to x, by the Voronoi region of x: vertex, edge or face.
// A zero-area triangle has no face region and its region tests degenerate (they can pick a
// wrong edge, or the face with a near-zero denominator), so it is treated as its three edges.
template <class T>
GWNRT_HD inline ClosestPoint<T> closest_point_on_triangle(const glm::vec<3, T>& p0, const glm::vec<3, T>& p1,
                                                          const glm::vec<3, T>& p2, const glm::vec<3, T>& x) {
  using V = glm::vec<3, T>;
  const V e1 = p1 - p0, e2 = p2 - p0, x0 = x - p0;
  const V normal = glm::cross(e1, e2);
  const T scale = glm::dot(e1, e1) * glm::dot(e2, e2);
  if (!(glm::dot(normal, normal) > T(1e-12) * scale)) {
    const ClosestPoint<T> c01 = closest_point_on_segment(p0, p1, x), c02 = closest_point_on_segment(p0, p2, x),
                          c12 = closest_point_on_segment(p1, p2, x);
    const T d01 = glm::dot(c01.point - x, c01.point - x), d02 = glm::dot(c02.point - x, c02.point - x),
            d12 = glm::dot(c12.point - x, c12.point - x);
    if (d01 <= d02 && d01 <= d12) return {c01.point, c01.u, 0};
    if (d02 <= d12) return {c02.point, 0, c02.u};
    return {c12.point, 1 - c12.u, c12.u};
  }
  const T d1 = glm::dot(e1, x0), d2 = glm::dot(e2, x0);
  if (d1 <= 0 && d2 <= 0) return {p0, 0, 0};
  const V x1 = x - p1;
  const T d3 = glm::dot(e1, x1), d4 = glm::dot(e2, x1);
  if (d3 >= 0 && d4 <= d3) return {p1, 1, 0};
  const T vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const T t = d1 - d3 > 0 ? d1 / (d1 - d3) : T(0);
    return {p0 + t * e1, t, 0};
  }
  const V x2 = x - p2;
  const T d5 = glm::dot(e1, x2), d6 = glm::dot(e2, x2);
  if (d6 >= 0 && d5 <= d6) return {p2, 0, 1};
  const T vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const T t = d2 - d6 > 0 ? d2 / (d2 - d6) : T(0);
    return {p0 + t * e2, 0, t};
  }
  const T va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const T denom = (d4 - d3) + (d5 - d6);
    const T t = denom > 0 ? (d4 - d3) / denom : T(0);
    return {p1 + t * (p2 - p1), 1 - t, t};
  }
  const T sum = va + vb + vc;
  if (!(sum > 0)) return {p0, 0, 0};  // unreachable for a proper triangle; guards NaN
  const T v = vb / sum, w = vc / sum;
  return {p0 + v * e1 + w * e2, v, w};
}

struct NearestPrimitive {
  float distance = kInfinity;       // +inf when the tree is empty
  uint32_t primitive = kEmptyLane;  // input index (triangle or boundary segment)
  float u = 0, v = 0;               // barycentrics of the closest point
  vec3 point{0.0f};
};

namespace detail {

GWNRT_HD GWNRT_FORCEINLINE float box_distance2(const WideNode& node, int lane, const vec3& x) {
  float d2 = 0;
  for (int a = 0; a < 3; ++a) {
    const float lo = node.lo[a][lane] - x[a], hi = x[a] - node.hi[a][lane];
    const float d = lo > 0 ? lo : (hi > 0 ? hi : 0.0f);
    d2 += d * d;
  }
  // Empty lanes have inverted boxes (lo > hi): never nearer than anything.
  return node.lo[0][lane] <= node.hi[0][lane] ? d2 : kInfinity;
}

// Near-first branch and bound over a wide BVH. `closest(i, x)` returns the ClosestPoint<float>
// of leaf-order primitive i; ids maps leaf order to the input index.
template <class ClosestFn>
GWNRT_HD NearestPrimitive nearest_primitive(const BvhView& bvh, const uint32_t* ids, const vec3& x, ClosestFn closest) {
  NearestPrimitive best;
  if (bvh.node_count == 0) return best;
  float best2 = kInfinity;
  NearFirstEntry stack[kTraversalStackSize];
  int sp = 0;
  stack[sp++] = {0, 0.0f};
  while (sp > 0) {
    const NearFirstEntry entry = stack[--sp];
    if (entry.key >= best2) continue;
    const WideNode& node = bvh.nodes[entry.node];
    NearFirstEntry inner[kBvhWidth];
    int inner_count = 0;
    for (int l = 0; l < kBvhWidth; ++l) {
      const float d2 = box_distance2(node, l, x);
      if (d2 >= best2) continue;
      if (node.count[l] == 0) {
        inner[inner_count++] = {node.child[l], d2};
        continue;
      }
      for (uint32_t i = node.child[l]; i < node.child[l] + node.count[l]; ++i) {
        const ClosestPoint<float> c = closest(i, x);
        const vec3 diff = c.point - x;
        const float dist2 = glm::dot(diff, diff);
        if (dist2 < best2) {
          best2 = dist2;
          best.primitive = ids[i];
          best.u = c.u;
          best.v = c.v;
          best.point = c.point;
        }
      }
    }
    push_near_first(stack, sp, inner, inner_count);
  }
  best.distance = best2 < kInfinity ? sqrtf(best2) : kInfinity;
  return best;
}

}  // namespace detail

GWNRT_HD inline NearestPrimitive unsigned_distance(const TriangleTreeView& tree, const vec3& x) {
  return detail::nearest_primitive(tree.bvh, tree.triangle_ids, x, [&](uint32_t i, const vec3& q) {
    return closest_point_on_triangle(tree.vertices[3 * i], tree.vertices[3 * i + 1], tree.vertices[3 * i + 2], q);
  });
}

// Distance to ∂M; +inf for a closed mesh (∂M empty).
GWNRT_HD inline NearestPrimitive boundary_distance(const SegmentTreeView& tree, const vec3& x) {
  return detail::nearest_primitive(tree.bvh, tree.segment_ids, x, [&](uint32_t i, const vec3& q) {
    return closest_point_on_segment(tree.endpoints[2 * i], tree.endpoints[2 * i + 1], q);
  });
}

}  // namespace gwnrt
