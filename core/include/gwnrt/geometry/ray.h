// Rays against the triangle BVH: a watertight ray–triangle crossing test whose ties (a ray
// exactly through an edge or a vertex) are broken by one fixed symbolic perturbation of the
// ray, and the two walks the tracer needs: the next crossing after a given one, in (t, index)
// order, and the signed count of crossings on an interval. Host-and-device.
//
// Why the perturbation: the tracer counts crossings to know the integer part of w, so a ray
// through an edge shared by two triangles must count it exactly once (and a ray through a
// vertex once per sheet through that vertex). The perturbed ray is a translate of the real
// one by (δ, δ²) in the plane orthogonal to it, δ → 0+; every triangle sees the same translate,
// so the counts are those of an honest ray and w stays consistent.
#pragma once

#include "gwnrt/base/lanes.h"
#include "gwnrt/geometry/bvh.h"

namespace gwnrt {

struct Ray {
  vec3 origin{0.0f};
  vec3 direction{0.0f, 0.0f, 1.0f};  // any nonzero length; t is measured in its units
  float tnear = 0.0f;
  float tfar = kInfinity;
};

// Per-ray constants of the watertight test (Woop, Benthin, Wald 2013): the axis most aligned
// with the direction becomes z, and a shear maps the direction onto it.
struct RayFrame {
  vec3 origin;
  vec3 inv_direction;  // for slab tests; zero components replaced by a huge finite value
  int kx, ky, kz;
  float sx, sy, sz;
};

GWNRT_HD inline RayFrame make_ray_frame(const vec3& origin, const vec3& direction) {
  RayFrame f;
  f.origin = origin;
  const vec3 ad = glm::abs(direction);
  f.kz = ad.x >= ad.y ? (ad.x >= ad.z ? 0 : 2) : (ad.y >= ad.z ? 1 : 2);
  f.kx = f.kz == 2 ? 0 : f.kz + 1;
  f.ky = f.kx == 2 ? 0 : f.kx + 1;
  if (direction[f.kz] < 0) {  // keep the projected winding
    const int k = f.kx;
    f.kx = f.ky;
    f.ky = k;
  }
  f.sx = direction[f.kx] / direction[f.kz];
  f.sy = direction[f.ky] / direction[f.kz];
  f.sz = 1.0f / direction[f.kz];
  for (int a = 0; a < 3; ++a) {
    // 1/0 = inf would give 0·inf = NaN for an origin on a slab plane; a huge finite value
    // gives the same answer everywhere else.
    const float d = direction[a];
    f.inv_direction[a] = d != 0.0f ? 1.0f / d : (d < 0.0f ? -1e30f : 1e30f);
  }
  return f;
}

namespace detail {

// The projected edge function Qx·Py − Qy·Px at the ray. The products of floats are exact in
// double, so the value for edge P→Q is exactly the negation of the value for Q→P whatever the
// compiler contracts.
// A template over the lane type (double, or the host's d4 of four triangles at once).
template <class D>
GWNRT_HD GWNRT_FORCEINLINE D edge_value_of(D px, D py, D qx, D qy) {
  return qx * py - qy * px;
}
GWNRT_HD GWNRT_FORCEINLINE double edge_value(float px, float py, float qx, float qy) {
  return edge_value_of<double>(px, py, qx, qy);
}

// Its sign at the perturbed ray: a zero value is decided by the perturbation, which keeps the
// antisymmetry.
GWNRT_HD GWNRT_FORCEINLINE int edge_sign(float px, float py, float qx, float qy, double value) {
  if (value != 0.0) return value > 0 ? 1 : -1;
  const float dy = qy - py;
  if (dy != 0.0f) return dy > 0 ? 1 : -1;
  const float dx = px - qx;
  return dx > 0 ? 1 : (dx < 0 ? -1 : 0);
}

}  // namespace detail

// Where the (perturbed) ray's line crosses triangle (p0, p1, p2): t along the frame's direction
// (any t, also negative), and the jump of w there: +1 when the line passes from the side the
// normal (p1-p0)×(p2-p0) points to onto the other side, -1 the other way. Edge-on and
// zero-area triangles are never crossed (they carry no jump of w).
// AxisAligned: the frame's ray runs along an axis (sx = sy = 0), and the shear, which would
// subtract exact zeros, is skipped: the same answers for less work.
template <bool AxisAligned = false>
GWNRT_HD GWNRT_FORCEINLINE bool triangle_crossing(const RayFrame& f, const vec3& p0, const vec3& p1, const vec3& p2,
                                                  float& t, int& jump) {
  const vec3 a = p0 - f.origin, b = p1 - f.origin, c = p2 - f.origin;
  const float sx = AxisAligned ? 0.0f : f.sx, sy = AxisAligned ? 0.0f : f.sy;
  const float ax = AxisAligned ? a[f.kx] : a[f.kx] - sx * a[f.kz], ay = AxisAligned ? a[f.ky] : a[f.ky] - sy * a[f.kz];
  const float bx = AxisAligned ? b[f.kx] : b[f.kx] - sx * b[f.kz], by = AxisAligned ? b[f.ky] : b[f.ky] - sy * b[f.kz];
  const float cx = AxisAligned ? c[f.kx] : c[f.kx] - sx * c[f.kz], cy = AxisAligned ? c[f.ky] : c[f.ky] - sy * c[f.kz];
  // Most triangles a ray is tested against are missed by a clear margin: the three signs are
  // combined without branches, and only an exact zero (the ray through an edge's line) takes
  // the symbolic tie-break.
  const double u = detail::edge_value(bx, by, cx, cy), v = detail::edge_value(cx, cy, ax, ay),
               w = detail::edge_value(ax, ay, bx, by);
  if ((u == 0.0) | (v == 0.0) | (w == 0.0)) {
    const int su = detail::edge_sign(bx, by, cx, cy, u);
    const int sv = detail::edge_sign(cx, cy, ax, ay, v);
    const int sw = detail::edge_sign(ax, ay, bx, by, w);
    if (su == 0 || su != sv || su != sw) return false;
  } else if (((u < 0.0) | (v < 0.0) | (w < 0.0)) & ((u > 0.0) | (v > 0.0) | (w > 0.0))) {
    return false;
  }
  const double det = u + v + w;
  if (det == 0.0) return false;
  const double tz = u * double(f.sz * a[f.kz]) + v * double(f.sz * b[f.kz]) + w * double(f.sz * c[f.kz]);
  t = float(tz / det);
  // det > 0: the triangle winds counter-clockwise seen from the origin looking along the ray,
  // so its normal faces the origin and the line goes from front to back.
  jump = det > 0 ? 1 : -1;
  return true;
}

// Slab test of the four lanes of a node against [t_lo, t_hi]: each lane's entry distance, or
// +inf on a miss. The exit is widened by a few ulps so that round-off never drops a triangle
// whose own test hits (the robust bound of pbrt's ray-box test). Written lane-parallel, without
// branches, so that the compiler can test the four lanes at once.
GWNRT_HD GWNRT_FORCEINLINE void lane_entries(const WideNode& node, const RayFrame& f, float t_lo, float t_hi,
                                             float entry[kBvhWidth]) {
  float t0[kBvhWidth], t1[kBvhWidth];
  for (int l = 0; l < kBvhWidth; ++l) {
    t0[l] = t_lo;
    t1[l] = t_hi;
  }
  for (int k = 0; k < 3; ++k) {
    for (int l = 0; l < kBvhWidth; ++l) {
      const float a = (node.lo[k][l] - f.origin[k]) * f.inv_direction[k];
      const float b = (node.hi[k][l] - f.origin[k]) * f.inv_direction[k];
      float near = a < b ? a : b, far = a < b ? b : a;
      near -= fabsf(near) * 4e-7f;
      far += fabsf(far) * 4e-7f;
      t0[l] = near > t0[l] ? near : t0[l];
      t1[l] = far < t1[l] ? far : t1[l];
    }
  }
  for (int l = 0; l < kBvhWidth; ++l) entry[l] = t0[l] <= t1[l] ? t0[l] : kInfinity;
}

// The same for a ray along a coordinate axis (a frame with sx = sy = 0): kx and ky compared, not
// divided (a lane whose kx or ky range misses the origin holds no triangle the ray crosses:
// axis_box_meets below), the slab along kz as above.
GWNRT_HD GWNRT_FORCEINLINE void axis_lane_entries(const WideNode& node, const RayFrame& f, float t_lo, float t_hi,
                                                  float entry[kBvhWidth]) {
  const float ox = f.origin[f.kx], oy = f.origin[f.ky], oz = f.origin[f.kz], inv = f.inv_direction[f.kz];
  for (int l = 0; l < kBvhWidth; ++l) {
    const float a = (node.lo[f.kz][l] - oz) * inv, b = (node.hi[f.kz][l] - oz) * inv;
    float near = a < b ? a : b, far = a < b ? b : a;
    near -= fabsf(near) * 4e-7f;
    far += fabsf(far) * 4e-7f;
    const float t0 = near > t_lo ? near : t_lo, t1 = far < t_hi ? far : t_hi;
    const bool in_xy =
        node.lo[f.kx][l] <= ox && ox <= node.hi[f.kx][l] && node.lo[f.ky][l] <= oy && oy <= node.hi[f.ky][l];
    entry[l] = in_xy && t0 <= t1 ? t0 : kInfinity;
  }
}

struct CrossingHit {
  float t = kInfinity;
  uint32_t index = kEmptyLane;  // leaf-order triangle index
  int jump = 0;
};

// The first crossing after (t_after, index_after) in lexicographic (t, leaf index) order, with
// t <= t_max; index_after = kEmptyLane means "from t_after on, inclusive". Visiting crossings
// one by one this way meets each exactly once, also several at the same t (stacked copies).
// AxisAligned: the ray runs along an axis, and the lanes and triangles take the axis tests,
// which give the same answers for less work.
template <bool AxisAligned = false>
GWNRT_HD inline bool next_crossing(const BvhView& bvh, const vec3* vertices, const RayFrame& f, float t_after,
                                   uint32_t index_after, float t_max, CrossingHit& out) {
  out = CrossingHit{};
  if (bvh.node_count == 0) return false;
  float best_t = t_max;
  bool found = false;
  NearFirstEntry stack[kTraversalStackSize];
  int sp = 0;
  stack[sp++] = {0, t_after};
  while (sp > 0) {
    const NearFirstEntry e = stack[--sp];
    if (e.key > best_t) continue;
    const WideNode& node = bvh.nodes[e.node];
    NearFirstEntry inner[kBvhWidth];
    int inner_count = 0;
    float entry[kBvhWidth];
    if constexpr (AxisAligned)
      axis_lane_entries(node, f, t_after, best_t, entry);
    else
      lane_entries(node, f, t_after, best_t, entry);
    for (int l = 0; l < kBvhWidth; ++l) {
      if (node.child[l] == kEmptyLane || entry[l] == kInfinity) continue;
      if (node.count[l] == 0) {
        inner[inner_count++] = {node.child[l], entry[l]};
        continue;
      }
      for (uint32_t i = node.child[l]; i < node.child[l] + node.count[l]; ++i) {
        float t;
        int jump;
        if (!triangle_crossing<AxisAligned>(f, vertices[3 * i], vertices[3 * i + 1], vertices[3 * i + 2], t, jump))
          continue;
        const bool after = t > t_after || (t == t_after && (index_after == kEmptyLane || i > index_after));
        const bool better = t < best_t || (t == best_t && (!found || i < out.index));
        if (after && better) {
          best_t = t;
          out = {t, i, jump};
          found = true;
        }
      }
    }
    push_near_first(stack, sp, inner, inner_count);
  }
  return found;
}

// Σ jumps of the crossings with t in [t_lo, t_hi).
GWNRT_HD inline int crossing_sum(const BvhView& bvh, const vec3* vertices, const RayFrame& f, float t_lo, float t_hi) {
  if (bvh.node_count == 0 || !(t_lo < t_hi)) return 0;
  int sum = 0;
  uint32_t stack[kTraversalStackSize];
  int sp = 0;
  stack[sp++] = 0;
  while (sp > 0) {
    const WideNode& node = bvh.nodes[stack[--sp]];
    float entry[kBvhWidth];
    lane_entries(node, f, t_lo, t_hi, entry);
    for (int l = 0; l < kBvhWidth; ++l) {
      if (node.child[l] == kEmptyLane || entry[l] == kInfinity) continue;
      if (node.count[l] == 0) {
        stack[sp++] = node.child[l];
        continue;
      }
      for (uint32_t i = node.child[l]; i < node.child[l] + node.count[l]; ++i) {
        float t;
        int jump;
        if (triangle_crossing(f, vertices[3 * i], vertices[3 * i + 1], vertices[3 * i + 2], t, jump) && t >= t_lo &&
            t < t_hi)
          sum += jump;
      }
    }
  }
  return sum;
}

// Rays along a coordinate axis (direction ±e_kz, a frame from make_ray_frame with sx = sy = 0):
// what the exact winding number (field/crossing_winding.h) casts from each point. A lane's box
// is met by the half-line t >= t_min exactly when the origin lies in the box's kx and ky ranges
// and the box reaches t_min along kz: compares only, no slab arithmetic. No padding is needed: a
// triangle whose vertices all lie on one side of the origin in x or y keeps those strict signs
// after rounding, so triangle_crossing misses it too; and a triangle entirely behind t_min gives
// a t that is a convex combination of values behind it.
// A template over the lane type: float for one lane, the host's f4 for a node's four (the
// result is then a lane mask).
namespace detail {
template <class V>
GWNRT_HD GWNRT_FORCEINLINE auto axis_box_meets(V lo_x, V hi_x, V lo_y, V hi_y, V lo_z, V hi_z, const RayFrame& f,
                                               float t_min) {
  const float ox = f.origin[f.kx], oy = f.origin[f.ky], oz = f.origin[f.kz];
  const auto in_xy = (lo_x <= ox) & (ox <= hi_x) & (lo_y <= oy) & (oy <= hi_y);
  const auto ahead = f.sz > 0.0f ? hi_z - oz >= t_min : oz - lo_z >= t_min;
  return in_xy & ahead;
}
}  // namespace detail

GWNRT_HD GWNRT_FORCEINLINE bool axis_ray_meets_lane(const WideNode& node, int lane, const RayFrame& f, float t_min) {
  return detail::axis_box_meets<float>(node.lo[f.kx][lane], node.hi[f.kx][lane], node.lo[f.ky][lane],
                                       node.hi[f.ky][lane], node.lo[f.kz][lane], node.hi[f.kz][lane], f, t_min);
}

// The same for the four lanes at once, as a bit mask. Empty lanes have inverted boxes and never
// pass. On the host as one f4 test: the compiler keeps the lane loop scalar (runtime axis
// indices), and on large meshes this test is the largest part of the walk.
GWNRT_HD GWNRT_FORCEINLINE uint32_t axis_ray_lane_mask(const WideNode& node, const RayFrame& f, float t_min) {
#if GWNRT_HOST_LANES
  return lane_bits(detail::axis_box_meets<f4>(load4(node.lo[f.kx]), load4(node.hi[f.kx]), load4(node.lo[f.ky]),
                                              load4(node.hi[f.ky]), load4(node.lo[f.kz]), load4(node.hi[f.kz]), f,
                                              t_min));
#else
  uint32_t mask = 0;
  for (int l = 0; l < kBvhWidth; ++l) mask |= uint32_t(axis_ray_meets_lane(node, l, f, t_min)) << l;
  return mask;
#endif
}

// The crossings of an axis ray with one leaf's triangles [first, first + count), t >= t_min, in
// index order. On the host with AVX, four triangles at a time: their edge values (exact in
// double, as in triangle_crossing) reject every triangle whose three values are nonzero and of
// mixed signs, which is exactly triangle_crossing's own early miss; every other one (a possible
// crossing, or an exact zero that needs the tie-break) goes through triangle_crossing itself,
// so the answers are its answers.
template <class Visitor>
GWNRT_HD GWNRT_FORCEINLINE void visit_axis_leaf(const vec3* vertices, uint32_t first, uint32_t count, const RayFrame& f,
                                                float t_min, Visitor& visit) {
#if GWNRT_HOST_LANES && defined(__AVX__)
  const float ox = f.origin[f.kx], oy = f.origin[f.ky];
  const int kx = f.kx, ky = f.ky;
  for (uint32_t base = first; base < first + count; base += 4) {
    const uint32_t n = first + count - base < 4 ? first + count - base : 4;
    f4 ax, ay, bx, by, cx, cy;
    for (uint32_t m = 0; m < 4; ++m) {
      const vec3* p = vertices + 3 * (base + (m < n ? m : 0));  // lanes past the leaf repeat its first
      ax[m] = p[0][kx] - ox;
      ay[m] = p[0][ky] - oy;
      bx[m] = p[1][kx] - ox;
      by[m] = p[1][ky] - oy;
      cx[m] = p[2][kx] - ox;
      cy[m] = p[2][ky] - oy;
    }
    const d4 dax = __builtin_convertvector(ax, d4), day = __builtin_convertvector(ay, d4);
    const d4 dbx = __builtin_convertvector(bx, d4), dby = __builtin_convertvector(by, d4);
    const d4 dcx = __builtin_convertvector(cx, d4), dcy = __builtin_convertvector(cy, d4);
    const d4 u = detail::edge_value_of(dbx, dby, dcx, dcy), v = detail::edge_value_of(dcx, dcy, dax, day),
             w = detail::edge_value_of(dax, day, dbx, dby);
    const d4 zero{};
    const l4 mixed = ((u < zero) | (v < zero) | (w < zero)) & ((u > zero) | (v > zero) | (w > zero));
    const l4 tie = (u == zero) | (v == zero) | (w == zero);
    uint32_t maybe = lane_bits64(tie | ~mixed) & ((1u << n) - 1u);
    for (; maybe != 0; maybe &= maybe - 1) {
      const uint32_t i = base + uint32_t(lowest_set_bit(maybe));
      float t;
      int jump;
      if (triangle_crossing<true>(f, vertices[3 * i], vertices[3 * i + 1], vertices[3 * i + 2], t, jump) && t >= t_min)
        visit(i, t, jump);
    }
  }
#else
  for (uint32_t i = first; i < first + count; ++i) {
    float t;
    int jump;
    if (triangle_crossing<true>(f, vertices[3 * i], vertices[3 * i + 1], vertices[3 * i + 2], t, jump) && t >= t_min)
      visit(i, t, jump);
  }
#endif
}

// A lane hook that keeps every lane (visit_axis_crossings' default).
struct KeepEveryLane {
  GWNRT_HD bool operator()(uint32_t, const WideNode&, int) const { return true; }
};

// Calls visit(leaf index, t, jump) for every crossing of the axis ray's line with t >= t_min
// (t_min <= 0 also reports crossings just behind the origin), in no particular order, over the
// subtree below `root` (0: the whole tree). lane_hook(node index, node, lane) is asked about
// every lane the ray meets (every leaf whose box holds the origin among them) before it is opened
// or its crossings visited; false leaves the lane out (a caller that knows more of its shape).
template <class Visitor, class LaneHook = KeepEveryLane>
GWNRT_HD inline void visit_axis_crossings(const BvhView& bvh, const vec3* vertices, const RayFrame& f, float t_min,
                                          Visitor&& visit, uint32_t root = 0, LaneHook&& lane_hook = {}) {
  if (bvh.node_count == 0) return;
  uint32_t stack[kTraversalStackSize];
  int sp = 0;
  stack[sp++] = root;
  while (sp > 0) {
    const uint32_t ni = stack[--sp];
    const WideNode& node = bvh.nodes[ni];
    for (uint32_t mask = axis_ray_lane_mask(node, f, t_min); mask != 0; mask &= mask - 1) {
      const int l = lowest_set_bit(mask);
      if (!lane_hook(ni, node, l)) continue;
      if (node.count[l] == 0) {
#if GWNRT_HOST_LANES
        // The walk is bound by node loads: start each child's load as soon as it is pushed.
        __builtin_prefetch(bvh.nodes + node.child[l]);
        __builtin_prefetch(reinterpret_cast<const char*>(bvh.nodes + node.child[l]) + 64);  // a node is 2 lines
#endif
        stack[sp++] = node.child[l];
        continue;
      }
      visit_axis_leaf(vertices, node.child[l], node.count[l], f, t_min, visit);
    }
  }
}

// A bundle of axis rays: frame f's direction, f's origin along kz for all of them, their origins
// along kx and ky anywhere in [lo, hi] (indexed by axis). visit_leaf(first, count) is called
// once for every leaf that any of them meets at t >= 0 by axis_ray_meets_lane (and maybe for a
// few others): each ray then tests its own triangles, and its crossings are the ones its own
// walk would find, for one walk instead of one a ray.
namespace detail {
template <class V>
GWNRT_HD GWNRT_FORCEINLINE auto axis_beam_box_meets(V lo_x, V hi_x, V lo_y, V hi_y, V lo_z, V hi_z, const RayFrame& f,
                                                    const vec3& lo, const vec3& hi) {
  const float oz = f.origin[f.kz];
  const auto in_xy = (lo_x <= hi[f.kx]) & (lo[f.kx] <= hi_x) & (lo_y <= hi[f.ky]) & (lo[f.ky] <= hi_y);
  const auto ahead = f.sz > 0.0f ? hi_z - oz >= 0.0f : oz - lo_z >= 0.0f;
  return in_xy & ahead;
}
}  // namespace detail

template <class LeafVisitor>
GWNRT_HD inline void visit_axis_beam_leaves(const BvhView& bvh, const RayFrame& f, const vec3& lo, const vec3& hi,
                                            LeafVisitor&& visit_leaf) {
  if (bvh.node_count == 0) return;
  uint32_t stack[kTraversalStackSize];
  int sp = 0;
  stack[sp++] = 0;
  while (sp > 0) {
    const WideNode& node = bvh.nodes[stack[--sp]];
#if GWNRT_HOST_LANES
    uint32_t mask = lane_bits(detail::axis_beam_box_meets<f4>(load4(node.lo[f.kx]), load4(node.hi[f.kx]),
                                                              load4(node.lo[f.ky]), load4(node.hi[f.ky]),
                                                              load4(node.lo[f.kz]), load4(node.hi[f.kz]), f, lo, hi));
#else
    uint32_t mask = 0;
    for (int l = 0; l < kBvhWidth; ++l)
      mask |=
          uint32_t(detail::axis_beam_box_meets<float>(node.lo[f.kx][l], node.hi[f.kx][l], node.lo[f.ky][l],
                                                      node.hi[f.ky][l], node.lo[f.kz][l], node.hi[f.kz][l], f, lo, hi))
          << l;
#endif
    for (; mask != 0; mask &= mask - 1) {
      const int l = lowest_set_bit(mask);
      if (node.count[l] == 0)
        stack[sp++] = node.child[l];
      else
        visit_leaf(node.child[l], node.count[l]);
    }
  }
}

// The axis ray that leaves `box` soonest from x, among the axes set in `axes` (bit k: axis k):
// toward the face nearest to x (outside the box, one that x is already beyond, so that the ray
// meets nothing in it).
GWNRT_HD inline RayFrame shortest_exit_axis_ray(const Aabb& box, const vec3& x, uint32_t axes = 7u) {
  int axis = 0;
  float sign = 1.0f, best = kInfinity;
  for (int k = 0; k < 3; ++k) {
    if (!((axes >> k) & 1u)) continue;
    const float up = box.hi[k] - x[k], down = x[k] - box.lo[k];
    if (up < best) {
      best = up;
      axis = k;
      sign = 1.0f;
    }
    if (down < best) {
      best = down;
      axis = k;
      sign = -1.0f;
    }
  }
  vec3 direction(0.0f);
  direction[axis] = sign;
  return make_ray_frame(x, direction);
}

// [t0, t1] of the line inside box b (t0 > t1: no overlap).
GWNRT_HD inline void clip_to_box(const RayFrame& f, const Aabb& b, float& t0, float& t1) {
  t0 = -kInfinity;
  t1 = kInfinity;
  for (int k = 0; k < 3; ++k) {
    float a = (b.lo[k] - f.origin[k]) * f.inv_direction[k];
    float c = (b.hi[k] - f.origin[k]) * f.inv_direction[k];
    if (a > c) {
      const float s = a;
      a = c;
      c = s;
    }
    t0 = a > t0 ? a : t0;
    t1 = c < t1 ? c : t1;
  }
}

}  // namespace gwnrt
