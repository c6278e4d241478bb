// Unsigned distance to the mesh M (closest triangle, barycentrics) and distance to the
// boundary curve ∂M, by near-first traversal of the wide BVH. Host-and-device.
#pragma once

#include "gwnrt/base/lanes.h"
#include "gwnrt/geometry/bvh.h"

namespace gwnrt {

template <class T>
struct ClosestPoint {
  glm::vec<3, T> point;
  T u, v;  // point = (1 - u - v) p0 + u p1 + v p2   (segments: point = (1 - u) p0 + u p1, v = 0)
};

// The nearest point to x of the segment from p to p + e, given xs = x − p: its parameter t in
// [0, 1] (a zero-length segment: 0) and the squared distance. Branch-free, for T = float, double
// or a lane vector (the edges of triangle_nearest, the boundary's segments).
template <class T>
GWNRT_HD GWNRT_FORCEINLINE T segment_nearest(const T (&xs)[3], const T (&e)[3], T& t) {
  const T zero{}, one = zero + 1.0f;
  const T ee = e[0] * e[0] + e[1] * e[1] + e[2] * e[2], de = e[0] * xs[0] + e[1] * xs[1] + e[2] * xs[2];
  t = lane_select(ee > zero, de / ee, zero);
  t = lane_select(t < zero, zero, lane_select(t > one, one, t));
  T d = zero;
  for (int a = 0; a < 3; ++a) {
    const T diff = t * e[a] - xs[a];
    d += diff * diff;
  }
  return d;
}

template <class T>
GWNRT_HD inline ClosestPoint<T> closest_point_on_segment(const glm::vec<3, T>& a, const glm::vec<3, T>& b,
                                                         const glm::vec<3, T>& x) {
  const T xs[3] = {x.x - a.x, x.y - a.y, x.z - a.z}, e[3] = {b.x - a.x, b.y - a.y, b.z - a.z};
  T t;
  (void)segment_nearest(xs, e, t);
  return {a + t * (b - a), t, 0};
}

// The nearest point of a triangle to x, branch-free, for one triangle (T = float or double) or
// one per lane (T = f4 on the host: a leaf's four at once). p[k][a]: corner k's coordinate a.
// Four candidates: the foot of x on the plane when it falls inside (barycentrics from the
// normal), and the nearest point of each edge; the nearest of them is the answer. No region
// tests (Ericson's): they rest on products of differences that float cannot resolve on a needle
// (corners 1e-5 of its length apart). A zero-area
// triangle has no foot inside (or its foot is a point of it anyway): its edges decide, as the
// brute force measures it. Ties go to the face, then edges p0p1, p0p2, p1p2. Returns the squared
// distance; u, v: barycentrics of the nearest point (point = (1 - u - v) p0 + u p1 + v p2).
template <class T>
GWNRT_HD GWNRT_FORCEINLINE T triangle_nearest(const T (&p)[3][3], const T (&x)[3], T& u, T& v) {
  T x0[3], x1[3], e1[3], e2[3], e3[3];
  for (int a = 0; a < 3; ++a) {
    x0[a] = x[a] - p[0][a];
    x1[a] = x[a] - p[1][a];
    e1[a] = p[1][a] - p[0][a];
    e2[a] = p[2][a] - p[0][a];
    e3[a] = p[2][a] - p[1][a];
  }
  const T zero{}, one = zero + 1.0f;
  const auto dot = [](const T(&a)[3], const T(&b)[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
  // Edges: t along each, and the squared distance to its point.
  T t1, t2, t3;
  const T d_ab = segment_nearest(x0, e1, t1), d_ac = segment_nearest(x0, e2, t2), d_bc = segment_nearest(x1, e3, t3);
  // The foot: u = n·(x0 × e2)/|n|², v = n·(e1 × x0)/|n|² (x's height over the plane drops out),
  // the distance to it x's height (x0·n)²/|n|². n by differences of products to an ulp or two of
  // itself: a sliver's plane from products that cancel to its width (a foot computed from u and v
  // errs across a sliver by several ulps of the coordinates). Where u and v are off
  // (by about an ulp of x0 across the triangle) the edge's candidate is as near.
  const T n[3] = {difference_of_products(e1[1], e2[2], e1[2], e2[1]),
                  difference_of_products(e1[2], e2[0], e1[0], e2[2]),
                  difference_of_products(e1[0], e2[1], e1[1], e2[0])};
  const T m2[3] = {e2[1] * n[2] - e2[2] * n[1], e2[2] * n[0] - e2[0] * n[2], e2[0] * n[1] - e2[1] * n[0]};
  const T m1[3] = {n[1] * e1[2] - n[2] * e1[1], n[2] * e1[0] - n[0] * e1[2], n[0] * e1[1] - n[1] * e1[0]};
  const T nn = dot(n, n), height = dot(x0, n);
  const T fu = lane_select(nn > zero, dot(x0, m2) / nn, -one), fv = lane_select(nn > zero, dot(x0, m1) / nn, -one);
  const auto inside = (fu >= zero) & (fv >= zero) & (fu + fv <= one);
  // height · (height / |n|²), not height² / |n|²: height² is the sixth power of the lengths,
  // which underflows float at the smallest served scales (a mesh 1e-8 across).
  T d_face = lane_select(nn > zero, height * (height / nn), zero);
  d_face = lane_select(inside, d_face, zero + kInfinity);
  // The nearest, in the order of the ties: BC, AC, AB over each other, the face over them all.
  T d = d_bc;
  u = one - t3;
  v = t3;
  auto nearer = d_ac <= d;
  d = lane_select(nearer, d_ac, d);
  u = lane_select(nearer, zero, u);
  v = lane_select(nearer, t2, v);
  nearer = d_ab <= d;
  d = lane_select(nearer, d_ab, d);
  u = lane_select(nearer, t1, u);
  v = lane_select(nearer, zero, v);
  nearer = d_face <= d;
  d = lane_select(nearer, d_face, d);
  u = lane_select(nearer, fu, u);
  v = lane_select(nearer, fv, v);
  return d;
}

template <class T>
GWNRT_HD GWNRT_FORCEINLINE T triangle_distance2(const T (&p)[3][3], const T (&x)[3]) {
  T u, v;
  return triangle_nearest(p, x, u, v);
}

// Closest point of triangle (p0, p1, p2) to x (triangle_nearest).
template <class T>
GWNRT_HD inline ClosestPoint<T> closest_point_on_triangle(const glm::vec<3, T>& p0, const glm::vec<3, T>& p1,
                                                          const glm::vec<3, T>& p2, const glm::vec<3, T>& x) {
  const T p[3][3] = {{p0.x, p0.y, p0.z}, {p1.x, p1.y, p1.z}, {p2.x, p2.y, p2.z}}, xs[3] = {x.x, x.y, x.z};
  T u, v;
  (void)triangle_nearest(p, xs, u, v);
  return {p0 + u * (p1 - p0) + v * (p2 - p0), u, v};
}

// Squared distance from x to a segment p[0] p[1], branch-free like triangle_distance2.
template <class T>
GWNRT_HD GWNRT_FORCEINLINE T segment_distance2(const T (&p)[2][3], const T (&x)[3]) {
  T xs[3], e[3], t;
  for (int a = 0; a < 3; ++a) {
    xs[a] = x[a] - p[0][a];
    e[a] = p[1][a] - p[0][a];
  }
  return segment_nearest(xs, e, t);
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

// Whether the host's four-wide path is taken (tests also run the scalar one, the device's).
inline constexpr bool kDistanceLanes = GWNRT_HOST_LANES != 0;

// The same for a node's four lanes at once.
template <bool Lanes = kDistanceLanes>
GWNRT_HD GWNRT_FORCEINLINE void box_distances2(const WideNode& node, const vec3& x, float (&out)[kBvhWidth]) {
#if GWNRT_HOST_LANES
  if constexpr (Lanes) {
    f4 d2{};
    for (int a = 0; a < 3; ++a) {
      const f4 lo = load4(node.lo[a]) - x[a], hi = splat<f4>(x[a]) - load4(node.hi[a]);
      const f4 d = lane_select(lo > 0.0f, lo, lane_select(hi > 0.0f, hi, f4{}));
      d2 += d * d;
    }
    d2 = lane_select(load4(node.lo[0]) <= load4(node.hi[0]), d2, splat<f4>(kInfinity));
    __builtin_memcpy(out, &d2, sizeof out);
    return;
  }
#endif
  for (int l = 0; l < kBvhWidth; ++l) out[l] = box_distance2(node, l, x);
}

// The primitives of a leaf [first, first + count) nearer than best2: on the host four at a time
// (lanes past the leaf repeat its last primitive and are not read back), else one by one, with
// the same formula; ties go to the first in leaf order either way.
template <bool Lanes, class Leaf>
GWNRT_HD GWNRT_FORCEINLINE void nearest_in_leaf(const Leaf& leaf, uint32_t first, uint32_t count, const vec3& x,
                                                float& best2, uint32_t& best) {
  constexpr int K = Leaf::kCorners;
  const float* c = &leaf.corners[0].x;
#if GWNRT_HOST_LANES
  if constexpr (Lanes) {
    const f4 xs[3] = {splat<f4>(x.x), splat<f4>(x.y), splat<f4>(x.z)};
    for (uint32_t base = first; base < first + count; base += 4) {
      const uint32_t left = first + count - base, used = left < 4 ? left : 4;
      const float* q[4];
      for (uint32_t l = 0; l < 4; ++l) q[l] = c + 3 * K * (base + (l < used ? l : used - 1));
      f4 p[K][3];
      for (int k = 0; k < K; ++k)
        for (int a = 0; a < 3; ++a) p[k][a] = f4{q[0][3 * k + a], q[1][3 * k + a], q[2][3 * k + a], q[3][3 * k + a]};
      const f4 d2 = leaf.distance2(p, xs);
      for (uint32_t l = 0; l < used; ++l)
        if (d2[l] < best2) {
          best2 = d2[l];
          best = base + l;
        }
    }
    return;
  }
#endif
  const float xs[3] = {x.x, x.y, x.z};
  for (uint32_t i = first; i < first + count; ++i) {
    float p[K][3];
    for (int k = 0; k < K; ++k)
      for (int a = 0; a < 3; ++a) p[k][a] = c[3 * (K * i + k) + a];
    const float d2 = leaf.distance2(p, xs);
    if (d2 < best2) {
      best2 = d2;
      best = i;
    }
  }
}

// Near-first branch and bound over a wide BVH: a node's four boxes at once, a leaf's primitives
// four at once (host), the nearest inner child popped next, and whatever is no nearer than the
// best so far left unopened. The closest point of the nearest primitive (leaf order; ids maps to
// the input index) is found last, once, by Leaf::closest.
template <class Leaf, bool Lanes = kDistanceLanes>
GWNRT_HD NearestPrimitive nearest_primitive(const BvhView& bvh, const uint32_t* ids, const vec3& x, const Leaf& leaf) {
  NearestPrimitive out;
  if (bvh.node_count == 0) return out;
  float best2 = kInfinity;
  uint32_t best = kEmptyLane;
  NearFirstEntry stack[kTraversalStackSize];
  int sp = 0;
  stack[sp++] = {0, 0.0f};
  while (sp > 0) {
    const NearFirstEntry entry = stack[--sp];
    if (entry.key >= best2) continue;
    const WideNode& node = bvh.nodes[entry.node];
    float d2[kBvhWidth];
    box_distances2<Lanes>(node, x, d2);
    NearFirstEntry inner[kBvhWidth];
    int inner_count = 0;
    for (int l = 0; l < kBvhWidth; ++l) {
      if (!(d2[l] < best2)) continue;
      if (node.count[l] == 0)
        inner[inner_count++] = {node.child[l], d2[l]};
      else
        nearest_in_leaf<Lanes>(leaf, node.child[l], node.count[l], x, best2, best);
    }
    push_near_first(stack, sp, inner, inner_count);
  }
  if (best == kEmptyLane) return out;
  const ClosestPoint<float> c = leaf.closest(best, x);
  out.distance = sqrtf(best2);
  out.primitive = ids[best];
  out.u = c.u;
  out.v = c.v;
  out.point = c.point;
  return out;
}

struct TriangleLeaves {
  static constexpr int kCorners = 3;
  const vec3* corners;  // 3 per triangle, leaf order
  template <class T>
  GWNRT_HD GWNRT_FORCEINLINE T distance2(const T (&p)[3][3], const T (&x)[3]) const {
    return triangle_distance2(p, x);
  }
  GWNRT_HD ClosestPoint<float> closest(uint32_t i, const vec3& x) const {
    return closest_point_on_triangle(corners[3 * i], corners[3 * i + 1], corners[3 * i + 2], x);
  }
};

struct SegmentLeaves {
  static constexpr int kCorners = 2;
  const vec3* corners;  // 2 per segment, leaf order
  template <class T>
  GWNRT_HD GWNRT_FORCEINLINE T distance2(const T (&p)[2][3], const T (&x)[3]) const {
    return segment_distance2(p, x);
  }
  GWNRT_HD ClosestPoint<float> closest(uint32_t i, const vec3& x) const {
    return closest_point_on_segment(corners[2 * i], corners[2 * i + 1], x);
  }
};

}  // namespace detail

GWNRT_HD inline NearestPrimitive unsigned_distance(const TriangleTreeView& tree, const vec3& x) {
  return detail::nearest_primitive(tree.bvh, tree.triangle_ids, x, detail::TriangleLeaves{tree.vertices});
}

namespace detail {

// Whether triangle (a, b, c) meets the box of centre `centre` and half-extents `half` (the
// separating axes: the box's three, the triangle's normal, the nine crosses of their edges); a
// degenerate triangle is separated by fewer axes, so it may be taken to meet a box it misses.
GWNRT_HD inline bool triangle_meets_box(const vec3& a, const vec3& b, const vec3& c, const vec3& centre,
                                        const vec3& half) {
  const vec3 v[3] = {a - centre, b - centre, c - centre};
  for (int k = 0; k < 3; ++k)
    if (min_of(min_of(v[0][k], v[1][k]), v[2][k]) > half[k] || max_of(max_of(v[0][k], v[1][k]), v[2][k]) < -half[k])
      return false;
  const vec3 edge[3] = {v[1] - v[0], v[2] - v[1], v[0] - v[2]};
  const auto separates = [&](const vec3& axis) {
    const float p0 = glm::dot(axis, v[0]), p1 = glm::dot(axis, v[1]), p2 = glm::dot(axis, v[2]);
    const float r = half.x * fabsf(axis.x) + half.y * fabsf(axis.y) + half.z * fabsf(axis.z);
    return min_of(min_of(p0, p1), p2) > r || max_of(max_of(p0, p1), p2) < -r;
  };
  if (separates(glm::cross(edge[0], edge[1]))) return false;
  for (int k = 0; k < 3; ++k)
    for (int e = 0; e < 3; ++e) {
      vec3 unit(0.0f);
      unit[k] = 1.0f;
      if (separates(glm::cross(unit, edge[e]))) return false;
    }
  return true;
}

}  // namespace detail

// Whether some triangle meets `box` grown by a thousandth of its size and float round-off of its
// coordinates (a box no triangle meets may still be reported met: a degenerate triangle near it).
// Nodes whose boxes miss it are not opened; the first triangle that meets it ends the search.
GWNRT_HD inline bool any_meets_box(const TriangleTreeView& tree, const Aabb& box) {
  if (tree.bvh.node_count == 0) return false;
  const vec3 centre = box.centre();
  const vec3 extent = box.hi - box.lo;
  const float round_off = 1e-6f * max_of(max_of(glm::length(box.lo), glm::length(box.hi)), glm::length(extent));
  const vec3 half = 0.5f * extent + (1e-3f * max_of(max_of(extent.x, extent.y), extent.z) + round_off);
  const Aabb grown{centre - half, centre + half};
  uint32_t stack[kTraversalStackSize];
  int sp = 0;
  stack[sp++] = 0;
  while (sp > 0) {
    const WideNode& node = tree.bvh.nodes[stack[--sp]];
    for (int lane = 0; lane < kBvhWidth; ++lane) {
      if (node.child[lane] == kEmptyLane) continue;
      if (!lane_meets_box(node, lane, grown)) continue;
      if (node.count[lane] == 0) {
        if (sp == kTraversalStackSize) return true;  // not reached (a node pops one, pushes four); kept
        stack[sp++] = node.child[lane];
        continue;
      }
      for (uint32_t t = node.child[lane]; t < node.child[lane] + node.count[lane]; ++t)
        if (detail::triangle_meets_box(tree.vertices[3 * t], tree.vertices[3 * t + 1], tree.vertices[3 * t + 2], centre,
                                       half))
          return true;
    }
  }
  return false;
}

// Distance to ∂M; +inf for a closed mesh (∂M empty).
GWNRT_HD inline NearestPrimitive boundary_distance(const SegmentTreeView& tree, const vec3& x) {
  return detail::nearest_primitive(tree.bvh, tree.segment_ids, x, detail::SegmentLeaves{tree.endpoints});
}

}  // namespace gwnrt
