// What a Harnack step needs at a point, from one traversal of the cone C (ModelView::cone):
// φ = w mod 1, optionally ∇w, the distance to ∂M and an upper bound on |∇w|. Host-and-device.
//
// The cone's triangles are (apex, a, b), one for each segment a -> b of ∂M (and inner ones that
// carry none), so its tree is also a tree over ∂M: every near triangle gives its solid angle and
// its segment's share of the bound from the same vectors, and every far cluster its expansion and
// a bound for all of its segments at once.
//
// The bound: off ∂M, ∇w is the Biot–Savart field of ∂M (the gradient of a solid angle is the
// field of its boundary loop), so |∇w(x)| <= (1/4π) ∮ |dl| / |l - x|². Only ∂M enters, and the
// bound is tight beside an edge (within π/2 of the field of a straight wire), where Harnack's
// bound from the value of φ alone is loose by a factor of about 40. harnack.h turns it into a
// second safe step.
#pragma once

#include "gwnrt/field/distance.h"
#include "gwnrt/field/winding_number.h"
#include "gwnrt/geometry/model_view.h"

namespace gwnrt {

struct PhaseSample {
  float phi = 0.0f;                     // w mod 1, in [0, 1)
  vec3 gradient{0.0f};                  // ∇w, when asked for
  float boundary_distance = kInfinity;  // a lower bound on the distance to ∂M (exact near it)
  float gradient_bound = 0.0f;          // K >= (1/4π) ∮ |dl| / |l - x|² >= |∇w(x)|
};

// ∫ |dl| / |l - x|² over a segment of length L seen from x, bounded from above without
// trigonometry, from u, v (the endpoints relative to x): P = |u||v|, u·v and |u × v|². With Q =
// P + u·v and α the angle the segment subtends, the integral is exactly α L / |u × v|;
// α <= 2 tan(α/2) gives 2L/Q (tight for small α: far segments) and α <= π sin(α/2) gives
// πL / sqrt(2PQ) (within π/2 up to α = π: near ones). The first is the smaller while α <= 90°
// (Q >= P >= 8P/π²), so most segments cost one division. The minimum is at most 1.38 times
// the integral; +inf when x lies on the segment.
// V: float, or a lane vector (every lane takes both forms, then the one that applies).
template <class V>
GWNRT_HD GWNRT_FORCEINLINE V segment_inverse_square_integral(V p, V u_dot_v, V cross2, V length) {
  const V two = V{} + 2.0f;
  const V far = two * length / (p + u_dot_v);
  if constexpr (sizeof(V) == sizeof(float)) {
    if (u_dot_v >= 0.0f) return far;
  } else if (!lane_any(u_dot_v < V{})) {
    return far;  // every lane far: the near form's three divisions and root are most of a lane's cost
  }
  // Q without cancellation when α is near π (x beside the segment): P + u·v = |u×v|² / (P - u·v).
  const V q = cross2 / (p - u_dot_v);
  const V chord = two / q, arc = (V{} + float(kPi)) / lane_sqrt(two * p * q);
  const V near = lane_select(q > V{}, length * lane_select(arc < chord, arc, chord), V{} + kInfinity);
  return lane_select(u_dot_v >= V{}, far, near);
}

// The squared distance from x to a segment (endpoints at lengths l1, l2 from x, |u × v|² = cross2;
// `inside`: x projects inside it): the nearer endpoint, or the line. Without branches: which of
// the three is nearest varies from segment to segment.
template <class V, class M>
GWNRT_HD GWNRT_FORCEINLINE V segment_distance2(V l1, V l2, V cross2, V inverse_length2, M inside) {
  const V end2 = lane_select(l1 < l2, l1 * l1, l2 * l2);
  return lane_select(inside, cross2 * inverse_length2, end2);
}

namespace detail {

template <bool WantGradient>
struct PhaseSum {
  const TriangleTreeView& tree;
  const WideNodeLength* lengths;
  const ConeSegment* segments;
  const vec3& x;
  FieldAccumulator<float> far_field;
  HalfAngleSum near_half_angles;
  FanGradientSum near_gradient;
  float nearest2 = kInfinity;
  float integral = 0.0f;  // Σ ∫ |dl| / |l - x|², bounded

  GWNRT_HD void far(uint32_t node, int lane, const vec3& d) {
    add_cluster_far_field<2, WantGradient, false>(tree, node, lane, d, far_field);
    // Every point of the cluster is within its radius of the centre, and inside its box.
    const float ball = max_of(glm::length(d) - tree.expansion[node].radius[lane], 0.0f);
    const float d2 = max_of(ball * ball, box_distance2(tree.bvh.nodes[node], lane, x));
    if (lengths[node].length[lane] > 0.0f) {  // none below: inner triangles only
      integral += lengths[node].length[lane] / d2;
      nearest2 = min_of(nearest2, d2);
    }
  }

  GWNRT_HD float near_angle() const { return near_half_angles.angle(); }  // Σ atan2, modulo 2π

  // The segment a -> b of near triangle t (a and b at lengths l1 and l2 from x, with a·b = d12 and
  // |a × b|² = cross2 relative to x; `inside`: x projects inside it): its share of the bound, and
  // its distance (float is plenty for both). An inner triangle of a spanned loop carries none
  // (length 0).
  GWNRT_HD void add_segment(uint32_t t, double l1, double l2, double d12, float cross2, bool inside) {
    const ConeSegment segment = segments[t];
    if (!(segment.length > 0.0f)) return;
    integral += segment_inverse_square_integral(float(l1 * l2), float(d12), cross2, segment.length);
    const float dist2 = segment_distance2(float(l1), float(l2), cross2, segment.inverse_length2, inside);
    nearest2 = dist2 < nearest2 ? dist2 : nearest2;
  }

  // In double: the cone's inner edges (apex to boundary) are singular lines of each of their
  // two triangles' terms, which cancel; in float, the rounding of x relative to such an edge
  // leaves φ with errors of 1e-4 within 1e-3 of it, enough for a step to skip a level there.
  FanCorners corners;  // reuses the apex's and the shared vertex's lengths

  GWNRT_HD void near(uint32_t t, const vec3& apex, const vec3& a, const vec3& b) {
    const bool continues = corners.next(dvec3(x), apex, a, b);
    const dvec3 &g0 = corners.g0, &g1 = corners.g1, &g2 = corners.g2;
    const double l0 = corners.l0, l1 = corners.l1, l2 = corners.l2;
    const dvec3 c12 = glm::cross(g1, g2);
    const double d12 = glm::dot(g1, g2);
    const SolidAngleTangent<double> tangent = solid_angle_tangent(g0, g1, g2, l0, l1, l2, c12, d12);
    near_half_angles.add({float(tangent.numerator), float(tangent.denominator)});
    const dvec3 e = g2 - g1;
    add_segment(t, l1, l2, d12, float(glm::dot(c12, c12)), glm::dot(g1, e) < 0.0 && glm::dot(g2, e) > 0.0);
    // In double: the cone's long inner edges carry large Biot–Savart terms that cancel between
    // neighbours, and in float that cancellation bends normals above a flat cap by 1e-2.
    if constexpr (WantGradient) near_gradient.add(corners, continues);
  }
};

#if GWNRT_HOST_LANES
// PhaseSum on the host: a node's far lanes expanded together and their share of the bound taken
// as lanes (the far clusters' scalar expansion was most of a Harnack step on a scan, and of the
// mesh report's distances); the near triangles stay PhaseSum's.
template <bool WantGradient>
struct PhaseLanes : PhaseSum<WantGradient> {
  using Base = PhaseSum<WantGradient>;
  f4 far_omega{}, far_integral{}, far_nearest2 = splat<f4>(kInfinity);
  f4 far_gradient[3] = {};

  // A node's far lanes (f4), or a pair's (f8): their expansion and, as PhaseSum::far, their share
  // of the bound from the larger of the distances to the cluster's ball and to its box (box2).
  template <class V, class M, class Lanes>
  GWNRT_FORCEINLINE void add_far(Lanes lanes, M mask, V dx, V dy, V dz, V box2, V& omega, V (&gradient)[3], V& integral,
                                 V& nearest2) {
    const TriangleTreeView& tree = Base::tree;
    if constexpr (WantGradient)
      add_far_lanes_with_gradient<2>(tree, lanes, mask, dx, dy, dz, omega, gradient);
    else
      omega += lane_select(mask, expand_far_lanes<2>(tree, lanes, dx, dy, dz), V{});
    V ball = lane_sqrt(dx * dx + dy * dy + dz * dz) - lanes([&](uint32_t i) { return tree.expansion[i].radius; });
    ball = lane_select(ball > 0.0f, ball, V{});
    const V d2 = lane_select(ball * ball > box2, ball * ball, box2);
    const V length = lanes([&](uint32_t i) { return Base::lengths[i].length; });
    const auto counted = mask & (length > 0.0f);
    integral += lane_select(counted, length / d2, V{});
    nearest2 = lane_select(counted & (d2 < nearest2), d2, nearest2);
  }

  GWNRT_FORCEINLINE void far_lanes(uint32_t node, i4 mask, f4 dx, f4 dy, f4 dz) {
    float box2[kBvhWidth];
    box_distances2<true>(Base::tree.bvh.nodes[node], Base::x, box2);
    add_far([&](auto field) { return load4(field(node)); }, mask, dx, dy, dz, load4(box2), far_omega, far_gradient,
            far_integral, far_nearest2);
  }
#if defined(__AVX2__)
  // Two nodes' far lanes as one 8-wide vector (LaneTraversal::step_pair).
  f8 far_omega8{}, far_integral8{}, far_nearest2_8 = splat<f8>(kInfinity);
  f8 far_gradient8[3] = {};
  GWNRT_FORCEINLINE void far_lane_pair(uint32_t a, uint32_t b, i8 mask, f8 dx, f8 dy, f8 dz) {
    float box_a[kBvhWidth], box_b[kBvhWidth];
    box_distances2<true>(Base::tree.bvh.nodes[a], Base::x, box_a);
    box_distances2<true>(Base::tree.bvh.nodes[b], Base::x, box_b);
    add_far([&](auto field) { return load8(field(a), field(b)); }, mask, dx, dy, dz, load8(box_a, box_b), far_omega8,
            far_gradient8, far_integral8, far_nearest2_8);
  }
#endif
#if defined(__AVX__)
  UnwrappedAngleSumT<d4, l4> near_angles{};
  d4 near_integral{}, near_nearest2 = d4{} + kInfinity;

  // w alone: a leaf's near triangles four at a time in double, PhaseSum::near's terms (the near
  // triangles' sums were most of a query once the far lanes went together).
  GWNRT_FORCEINLINE void near_leaf(uint32_t first, uint32_t count) requires(!WantGradient) {
    for (uint32_t done = 0; done < count; done += 4) near_quad(first + done, count - done < 4 ? count - done : 4);
  }
  GWNRT_FORCEINLINE void near_quad(uint32_t first, uint32_t count) {
    d4 g[3][3];  // apex, a, b relative to x
    lane_triangle_corners(Base::tree, first, count, dvec3(Base::x), g);
    const LaneTangent<d4> tangent = lane_solid_angle_tangent(g[0], g[1], g[2]);
    const l4 used = l4{0, 1, 2, 3} < int64_t(count);
    const d4 zero{};
    // Unused lanes: the factor 0, which has no angle.
    near_angles.add(lane_select(used, tangent.numerator, zero), lane_select(used, tangent.denominator, zero));
    // The segments' shares of the bound and their distances as lanes (PhaseSum::add_segment's).
    const ConeSegment* segment = Base::segments + first;
    const uint32_t last = count - 1;
    const uint32_t m1 = last < 1 ? last : 1, m2 = last < 2 ? last : 2, m3 = last < 3 ? last : 3;
    const d4 length{segment[0].length, segment[m1].length, segment[m2].length, segment[m3].length};
    const d4 inverse_length2{segment[0].inverse_length2, segment[m1].inverse_length2, segment[m2].inverse_length2,
                             segment[m3].inverse_length2};
    const d4 &l1 = tangent.lb, &l2 = tangent.lc, &d12 = tangent.bc;
    // An inner triangle of a spanned loop carries none (length 0).
    const l4 counted = used & (length > zero);
    const d4 integral = segment_inverse_square_integral(l1 * l2, d12, tangent.cross2, length);
    near_integral += lane_select(counted, integral, zero);
    // e = b − a: a·e = d12 − l1², b·e = l2² − d12.
    const d4 dist2 =
        segment_distance2(l1, l2, tangent.cross2, inverse_length2, (d12 - l1 * l1 < zero) & (l2 * l2 - d12 > zero));
    near_nearest2 = lane_select(counted & (dist2 < near_nearest2), dist2, near_nearest2);
  }
  float near_angle() const {
    UnwrappedAngleSum lanes;
    add_lanes_to(near_angles, lanes);
    return float(atan2(lanes.im, lanes.re)) + Base::near_angle();
  }
#endif

  // The lanes folded into PhaseSum's sums.
  GWNRT_FORCEINLINE void fold() {
    Base::far_field.omega += lane_sum(far_omega);
    Base::integral += lane_sum(far_integral);
    for (int l = 0; l < 4; ++l) Base::nearest2 = min_of(Base::nearest2, far_nearest2[l]);
#if defined(__AVX2__)
    Base::far_field.omega += lane_sum(far_omega8);
    Base::integral += lane_sum(far_integral8);
    for (int l = 0; l < 8; ++l) Base::nearest2 = min_of(Base::nearest2, far_nearest2_8[l]);
    if constexpr (WantGradient)
      for (int k = 0; k < 3; ++k) Base::far_field.gradient[k] += lane_sum(far_gradient8[k]);
#endif
#if defined(__AVX__)
    if constexpr (!WantGradient) {
      Base::integral += float(near_integral[0] + near_integral[1] + near_integral[2] + near_integral[3]);
      for (int l = 0; l < 4; ++l) Base::nearest2 = min_of(Base::nearest2, float(near_nearest2[l]));
    }
#endif
    if constexpr (WantGradient)
      for (int k = 0; k < 3; ++k) Base::far_field.gradient[k] += lane_sum(far_gradient[k]);
  }
};
#endif

// Whether φ alone sums its near triangles in double (PhaseLanes::near_quad).
#if GWNRT_HOST_LANES && defined(__AVX__)
inline constexpr bool kPhaseNearInDouble = true;
#else
inline constexpr bool kPhaseNearInDouble = false;
#endif

template <bool WantGradient>
GWNRT_HD PhaseSample sample_phase(const ModelView& m, const vec3& x, float beta, bool exact) {
  // The exact reference reads every triangle as near: the bound from each segment alone.
#if GWNRT_HOST_LANES
  PhaseLanes<WantGradient> sum{{m.cone, m.cone_boundary_lengths, m.cone_segments, x, {}, {}, {}, kInfinity, 0.0f, {}}};
#if defined(__AVX__)
  if constexpr (!WantGradient) {
    // Every triangle near: one sweep over them in the tree's order, without the traversal (the
    // traversal was half of the report's distances from its output on a scan).
    if (exact)
      sum.near_leaf(0, m.cone.triangle_count);
    else
      visit_multipole(m.cone, x, beta, sum);
  } else
#endif
    visit_multipole(m.cone, x, exact ? kInfinity : beta, sum);
  sum.fold();
#else
  PhaseSum<WantGradient> sum{m.cone, m.cone_boundary_lengths, m.cone_segments, x, {}, {}, {}, kInfinity, 0.0f, {}};
  visit_multipole(m.cone, x, exact ? kInfinity : beta, sum);
#endif
  PhaseSample out;
  float w;
  if (exact && (WantGradient || !kPhaseNearInDouble)) {
    const WindingSampleExact s = winding_number_exact(m.cone, x, WantGradient);
    w = float(s.w - floor(s.w));
    out.gradient = vec3(s.gradient);
  } else {
    // Ω/4π, the near part as Σ atan2 / 2π taken modulo 1 all at once. Exact for φ alone on the
    // host: every triangle was near and summed in double (the reference's terms without an atan2
    // each, which were most of the mesh report's distances on a scan).
    w = sum.far_field.omega * kInv4Pi + sum.near_angle() * float(0.5 / kPi);
    out.gradient = (sum.far_field.gradient + vec3(sum.near_gradient.total())) * kInv4Pi;
  }
  out.phi = w - floorf(w);
  if (!(out.phi < 1.0f)) out.phi = 0.0f;  // w just below a whole number rounds up to it
  out.boundary_distance = sqrtf(sum.nearest2);
  // Rounded up past the float error of the sum (a relative 1e-6 for hundreds of terms).
  out.gradient_bound = sum.integral * kInv4Pi * (1.0f + 1e-5f);
  return out;
}

}  // namespace detail

GWNRT_HD inline PhaseSample sample_phase(const ModelView& m, const vec3& x, float beta, bool want_gradient,
                                         bool exact = false) {
  return want_gradient ? detail::sample_phase<true>(m, x, beta, exact) : detail::sample_phase<false>(m, x, beta, exact);
}

}  // namespace gwnrt
