// w over a whole box from a few evaluations (docs/design.md §11, corners): the sign of w − w* at
// many points of a box, settled by first-order estimates and bounds, where the box is far enough
// from the level. Host-and-device.
//
// Along the axis ray from x (fixed axis and direction), w(x) = ŵ(x) − J(x), J(x) the sum of M's
// jumps ahead of x and ŵ(x) = w_C(x) + the cone's jumps ahead (crossing_winding.h), which is also
// the sum of ∂M's ribbons swept opposite the ray (ribbon_winding.h, the batches). ŵ jumps only
// where the ray sweeps across ∂M (a crossing of M that moves from one triangle to its neighbour
// keeps its jump unless their edge is on ∂M); so where no segment of ∂M lies in the box swept
// along the ray to M's box, ŵ is continuous on the box, harmonic, with ∇ŵ = ∇w the Biot–Savart
// field of ∂M: |∇w(y)| <= K = (1/4π) Σ_segments length / distance(y, segment)², and |H_w| <= H
// likewise with 2/distance³. Hence for x and c in the box, ŵ(x) lies within ½·H·|x − c|² of
// ŵ(c) + ∇w(c)·(x − c) (and within K·|x − c| of ŵ(c)), and w(x) − w* has the sign of that
// estimate minus J(x) + w* wherever it clears the bound: one cone traversal for c, M's crossings
// (shared along columns) for each x.
#pragma once

#include "gwnrt/field/crossing_winding.h"

namespace gwnrt {

// Bounds on w's derivatives over a box, where ŵ is continuous on it (usable).
struct BoxFieldBounds {
  float gradient = 0;  // K: |∇w| <= K on the box
  float hessian = 0;   // |H_w| <= this on the box (operator norm)
  bool usable = false;
};

// ŵ and ∇w at one point of such a box: the centre of a first-order estimate.
struct TaylorPoint {
  vec3 gradient{0.0f};
  float w_hat = 0;
  GWNRT_HD bool finite() const {
    return is_finite(w_hat) && is_finite(gradient.x) && is_finite(gradient.y) && is_finite(gradient.z);
  }
};

// Work caps: segments tested one by one (a box beside a long stretch of ∂M is left to the
// corners' own evaluation rather than bounded at great cost), and the traversal stack.
inline constexpr int kMaxBoxBoundSegments = 256;

// Margin on ŵ(c) (held to 1e-5 by the cone's beta, crossing_winding.h) and on float round-off of
// the estimate: a point is settled only when its estimate clears the bound by this much.
inline constexpr float kBoxWindingMargin = 1e-3f;

// The centres' ∇w comes from the cone's clusters expanded beyond w's own beta, and is allowed this
// relative error plus the margin: where |∇w| is small the relative error grows (13% at beta 5 by
// the kuka kr150 STL's rim, 1e3 on the nearly closed kr10 even at 8), but the estimate reads the
// error times the distance from the centre, which stayed below 3.6e-5 at the half-diagonal of a
// block at 256³ on every real mesh at beta 5 as at 8 (80,000 points each; a floor of round-off),
// far within the 1e-3 margin. The derivatives' own beta (16) made the centres a third of the
// mesher's time on a scan, 8 a quarter (docs/performance.md).
inline constexpr float kTaylorPointBeta = kConeBeta;
inline constexpr float kTaylorGradientError = 2e-2f;
// A block's eighths (half its reach) take their centres at beta 4: there the errors of ŵ and ∇w
// times the eighth's half-diagonal stayed below 3.2e-5 on every real mesh and the bundled open
// ones at 16³ to 256³ (against beta 24; 1.6e-4 at 3), a thirtieth of the margin.
inline constexpr float kEighthPointBeta = 4.0f;

namespace detail {

GWNRT_HD inline float lane_box_gap2(const WideNode& node, int lane, const Aabb& box) {
  float d2 = 0.0f;
  for (int a = 0; a < 3; ++a) {
    const float gap = max_of(max_of(node.lo[a][lane] - box.hi[a], box.lo[a] - node.hi[a][lane]), 0.0f);
    d2 += gap * gap;
  }
  return d2;
}

GWNRT_HD inline float box_gap2(const vec3& lo, const vec3& hi, const Aabb& box) {
  float d2 = 0.0f;
  for (int a = 0; a < 3; ++a) {
    const float gap = max_of(max_of(lo[a] - box.hi[a], box.lo[a] - hi[a]), 0.0f);
    d2 += gap * gap;
  }
  return d2;
}

// BoundSums' boxes: eight to a vector where the host has them, else one by one.
#if GWNRT_HOST_LANES && defined(__AVX__)
using BoundLanes = f8;
#else
using BoundLanes = float;
#endif

// The sums of boundary_field_bounds for N boxes: Σ length / gap² and Σ length / gap³, a term
// (a box holding segments, and their length) added to each box's sums with its gap from that
// box (positive). A far cluster may take its expansion about its box's centre c instead, where
// smaller: with L = Σ (b − a) over its segments and ρ the half-diagonal of its box, ∇w's kernel G
// (norm 1/r²) differs from G at c by at most 2ρ/gap³ and its derivative by 6ρ/gap⁴ (the k-th
// derivative of 1/r has norm k!/r^(k+1); c is no nearer than the gap), so the terms are
// (|L| + 2·length·ρ/gap)/gap² and (|L| + 3·length·ρ/gap)/gap³: closed loops (L = 0) far away
// fall as 1/gap³ and 1/gap⁴.
template <int N, class V = BoundLanes>
struct BoundSums {
  static constexpr int kWidth = int(sizeof(V) / sizeof(float));
  static constexpr int kChunks = (N + kWidth - 1) / kWidth;
  V lo[3][kChunks], hi[3][kChunks], sum[kChunks], sum3[kChunks];
  uint32_t terms = 0;

  GWNRT_HD explicit BoundSums(const Aabb (&boxes)[N]) {
    for (int c = 0; c < kChunks; ++c) {
      sum[c] = sum3[c] = V{};
      for (int a = 0; a < 3; ++a) {
        if constexpr (kWidth == 1) {
          lo[a][c] = boxes[c].lo[a];
          hi[a][c] = boxes[c].hi[a];
        } else {
          for (int l = 0; l < kWidth; ++l) {
            const Aabb& box = boxes[kWidth * c + l < N ? kWidth * c + l : N - 1];  // lanes past N repeat the last
            lo[a][c][l] = box.lo[a];
            hi[a][c][l] = box.hi[a];
          }
        }
      }
    }
  }
  GWNRT_HD GWNRT_FORCEINLINE V gap2(int c, const vec3& term_lo, const vec3& term_hi) const {
    V out{};
    for (int a = 0; a < 3; ++a) {
      const V below = term_lo[a] - hi[a][c], above = lo[a][c] - term_hi[a];
      const V larger = lane_select(below > above, below, above);
      const V gap = lane_select(larger > 0.0f, larger, V{});
      out += gap * gap;
    }
    return out;
  }
  GWNRT_HD GWNRT_FORCEINLINE void add(const vec3& term_lo, const vec3& term_hi, float length) {
    for (int c = 0; c < kChunks; ++c) {
      const V g2 = gap2(c, term_lo, term_hi);
      const V term = length / g2;
      sum[c] += term;
      sum3[c] += term / lane_sqrt(g2);
    }
    ++terms;
  }
  GWNRT_HD GWNRT_FORCEINLINE void add_cluster(const vec3& term_lo, const vec3& term_hi, float length, float net,
                                              float rho) {
    const V whole = V{} + length;
    for (int c = 0; c < kChunks; ++c) {
      const V inverse2 = 1.0f / gap2(c, term_lo, term_hi), inverse = lane_sqrt(inverse2);
      const V expanded = net + 2.0f * length * rho * inverse, expanded3 = net + 3.0f * length * rho * inverse;
      sum[c] += lane_select(expanded < whole, expanded, whole) * inverse2;
      sum3[c] += lane_select(expanded3 < whole, expanded3, whole) * inverse2 * inverse;
    }
    ++terms;
  }
  GWNRT_HD float gradient_sum(int k) const { return lane_of(sum[k / kWidth], k % kWidth); }
  GWNRT_HD float hessian_sum(int k) const { return lane_of(sum3[k / kWidth], k % kWidth); }
  GWNRT_HD static float lane_of(const V& v, int l) {
    if constexpr (kWidth == 1)
      return v;
    else
      return v[l];
  }
};

}  // namespace detail

// K = (1/4π) Σ length / gap² over ∂M's segments (gap: between the segment's box and the box) and
// the Hessian's (1/4π) Σ 2 length / gap³ (the kernel (y − l)/|y − l|³ of ∇w has a derivative of
// norm 2/|y − l|³) for boxes[0] and the boxes inside it at once, from one traversal: clusters
// taken whole when their gap from boxes[0] is at least their box's diagonal, each box's term
// with its own gap (no smaller), or its expansion where smaller (BoundSums); 0 for a closed
// mesh. The sums are in float, rounded up past their error (terms·2⁻²⁴ relative). False when a
// segment's box meets `swept` (which holds boxes[0]) or the caps are reached.
template <int N>
GWNRT_HD inline bool boundary_field_bounds(const SegmentTreeView& boundary, const Aabb (&boxes)[N], const Aabb& swept,
                                           float (&gradient_bound)[N], float (&hessian_bound)[N]) {
  for (int k = 0; k < N; ++k) gradient_bound[k] = hessian_bound[k] = 0.0f;
  if (boundary.segment_count == 0 || boundary.bvh.node_count == 0) return true;
  if (!boundary.lengths) return false;
  detail::BoundSums<N> sums(boxes);
  uint32_t stack[kTraversalStackSize];
  int sp = 0;
  stack[sp++] = 0;
  int segments_tested = 0;
  while (sp > 0) {
    const uint32_t index = stack[--sp];
    const WideNode& node = boundary.bvh.nodes[index];
    for (int lane = 0; lane < kBvhWidth; ++lane) {
      if (node.child[lane] == kEmptyLane) continue;
      if (!lane_meets_box(node, lane, swept)) {
        const float gap2 = detail::lane_box_gap2(node, lane, boxes[0]);
        float diagonal2 = 0.0f;
        for (int a = 0; a < 3; ++a) {
          const float e = node.hi[a][lane] - node.lo[a][lane];
          diagonal2 += e * e;
        }
        if (gap2 >= diagonal2 && gap2 > 0.0f) {
          const vec3 lane_lo(node.lo[0][lane], node.lo[1][lane], node.lo[2][lane]),
              lane_hi(node.hi[0][lane], node.hi[1][lane], node.hi[2][lane]);
          const float length = boundary.lengths[index].length[lane];
          if (boundary.net_lengths)  // ρ: the half-diagonal, rounded up
            sums.add_cluster(lane_lo, lane_hi, length, boundary.net_lengths[index].length[lane],
                             0.5f * sqrtf(diagonal2) * (1.0f + 0x1p-20f));
          else
            sums.add(lane_lo, lane_hi, length);
          continue;
        }
      }
      if (node.count[lane] == 0) {
        if (sp == kTraversalStackSize) return false;
        stack[sp++] = node.child[lane];
        continue;
      }
      for (uint32_t s = node.child[lane]; s < node.child[lane] + node.count[lane]; ++s) {
        if (++segments_tested > kMaxBoxBoundSegments) return false;
        const vec3 a = boundary.endpoints[2 * s], b = boundary.endpoints[2 * s + 1];
        const vec3 segment_lo = glm::min(a, b), segment_hi = glm::max(a, b);
        if (detail::box_gap2(segment_lo, segment_hi, swept) == 0.0f) return false;  // ∂M in the swept box
        sums.add(segment_lo, segment_hi, glm::length(b - a));
      }
    }
  }
  // Each term is off by a few roundings and the sum by one per term, all relative.
  const float round_up = 1.0f + float(sums.terms + 8) * 0x1p-23f;
  for (int k = 0; k < N; ++k) {
    gradient_bound[k] = sums.gradient_sum(k) * float(0.25 * kInvPi) * round_up;
    hessian_bound[k] = sums.hessian_sum(k) * float(0.5 * kInvPi) * round_up;
  }
  return true;
}

// The bounds over boxes[0] and the boxes inside it for rays along (axis, sign): the first box
// swept along that direction to M's box must hold no segment of ∂M (the others' swept boxes lie
// in its own).
template <int N>
GWNRT_HD inline void box_field_bounds(const ModelView& m, const Aabb (&boxes)[N], int axis, float sign,
                                      BoxFieldBounds (&out)[N]) {
  Aabb swept = boxes[0];
  if (sign > 0.0f)
    swept.hi[axis] = max_of(swept.hi[axis], m.bounds.hi[axis]);
  else
    swept.lo[axis] = min_of(swept.lo[axis], m.bounds.lo[axis]);
  float gradient[N], hessian[N];
  const bool usable = boundary_field_bounds(m.boundary, boxes, swept, gradient, hessian);
  for (int k = 0; k < N; ++k) {
    out[k].gradient = gradient[k];
    out[k].hessian = hessian[k];
    out[k].usable = usable && is_finite(gradient[k]) && is_finite(hessian[k]);
  }
}

GWNRT_HD inline BoxFieldBounds box_field_bounds(const ModelView& m, const Aabb& box, int axis, float sign) {
  const Aabb boxes[1] = {box};
  BoxFieldBounds out[1];
  box_field_bounds(m, boxes, axis, sign, out);
  return out[0];
}

// ŵ and ∇w at x along (axis, sign): one cone traversal at the derivatives' beta. False on the cone.
GWNRT_HD inline bool taylor_point(const ModelView& m, const vec3& x, int axis, float sign, TaylorPoint& out,
                                  float beta = kTaylorPointBeta) {
  if (m.cone.triangle_count == 0) {  // closed: ŵ = 0, ∇w = 0
    out = TaylorPoint{};
    return true;
  }
  vec3 direction(0.0f);
  direction[axis] = sign;
  const RayFrame frame = make_ray_frame(x, direction);  // the visitor keeps a reference
  typename detail::ConeCrossingVisitor<true, false>::type cone(m.cone, frame, x, beta, nullptr);
  cone.traverse();
  if (cone.on_cone) return false;
  out.w_hat = detail::crossing_winding(cone, 0);
  out.gradient = detail::cone_gradient(cone);
  return out.finite();
}

namespace detail {

// kBoxWindingMargin, grown with |ŵ(p)| for the float round-off of ŵ(p) − J.
GWNRT_HD inline float taylor_margin(const TaylorPoint& p) {
  return kBoxWindingMargin * (1.0f + 1e-3f * fabsf(p.w_hat));
}

// How far the first-order estimate from p may be from ŵ at `offset` from p: ½·|H|·r² (Taylor's
// remainder), ∇w(p)'s own error (kTaylorGradientError), and the margin.
GWNRT_HD inline float taylor_reach(const TaylorPoint& p, const BoxFieldBounds& b, float r) {
  return 0.5f * b.hessian * r * r + kTaylorGradientError * glm::length(p.gradient) * r + taylor_margin(p);
}

}  // namespace detail

// w − w* at x = p + offset, in the box the bounds hold on, or NaN where they do not settle its
// sign: `jumps` is J(x). First order, ŵ(p) + ∇w(p)·offset, within taylor_reach; else ŵ(p) alone,
// within K·|offset|.
GWNRT_HD inline float taylor_estimate(const TaylorPoint& p, const BoxFieldBounds& b, int jumps, const vec3& offset,
                                      float level) {
  const float r = glm::length(offset);
  const float constant = p.w_hat - float(jumps) - level;
  const float linear = constant + glm::dot(p.gradient, offset);
  if (fabsf(linear) > detail::taylor_reach(p, b, r)) return linear;
  return fabsf(constant) > b.gradient * r + detail::taylor_margin(p) ? constant : __builtin_nanf("");
}

// Whether the first-order estimate from p may leave some point of `box` unsettled: the range of
// ŵ(p) + ∇w(p)·(x − p) over the box, widened by the largest reach (unless `widened` is false: the
// estimate's own range), holds a level w* + n for some whole n (J is a whole number).
GWNRT_HD inline bool taylor_may_leave_unsettled(const TaylorPoint& p, const BoxFieldBounds& b, const vec3& centre,
                                                const Aabb& box, float level, bool widened = true) {
  float lo = p.w_hat, hi = p.w_hat, r2 = 0.0f;
  for (int a = 0; a < 3; ++a) {
    const float d0 = box.lo[a] - centre[a], d1 = box.hi[a] - centre[a];
    lo += min_of(p.gradient[a] * d0, p.gradient[a] * d1);
    hi += max_of(p.gradient[a] * d0, p.gradient[a] * d1);
    r2 += max_of(d0 * d0, d1 * d1);
  }
  const float reach = widened ? detail::taylor_reach(p, b, sqrtf(r2)) : 0.0f;
  // A level w* + n in [lo − reach, hi + reach]: floor(hi + reach − w*) >= ceil(lo − reach − w*).
  return floorf(hi + reach - level) >= ceilf(lo - reach - level);
}

// Whether ŵ(p) + ... settles w − w* to one sign, `positive` or not, on the whole segment [a, b]
// (with J constant on it): the first-order estimate minus its reach (linear minus convex: concave)
// at both ends, or the zeroth-order one at both ends; the one criterion at both ends, so that
// concavity carries it to every point between.
GWNRT_HD inline bool taylor_settles_segment(const TaylorPoint& p, const BoxFieldBounds& b, int jumps,
                                            const vec3& a_offset, const vec3& b_offset, float level, bool positive) {
  const float s = positive ? 1.0f : -1.0f;
  const float constant = p.w_hat - float(jumps) - level;
  const float ra = glm::length(a_offset), rb = glm::length(b_offset);
  const float la = constant + glm::dot(p.gradient, a_offset), lb = constant + glm::dot(p.gradient, b_offset);
  if (s * la > detail::taylor_reach(p, b, ra) && s * lb > detail::taylor_reach(p, b, rb)) return true;
  return s * constant > b.gradient * max_of(ra, rb) + detail::taylor_margin(p);
}

}  // namespace gwnrt
