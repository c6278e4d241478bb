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
GWNRT_HD inline float segment_inverse_square_integral(float p, float u_dot_v, float cross2, float length) {
  if (u_dot_v >= 0.0f) return 2.0f * length / (p + u_dot_v);
  // Q without cancellation when α is near π (x beside the segment): P + u·v = |u×v|² / (P - u·v).
  const float q = cross2 / (p - u_dot_v);
  if (!(q > 0.0f)) return kInfinity;
  return length * min_of(2.0f / q, float(kPi) / sqrtf(2.0f * p * q));
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
    // The segment a -> b: its share of the bound, and its distance (float is plenty for both).
    // An inner triangle of a spanned loop carries none (length 0).
    const ConeSegment segment = segments[t];
    if (segment.length > 0.0f) {
      const dvec3 e = g2 - g1;
      const float c2 = float(glm::dot(c12, c12));
      integral += segment_inverse_square_integral(float(l1 * l2), float(d12), c2, segment.length);
      // Without branches (which of the three is nearest varies from segment to segment): the
      // nearer endpoint, or the line when x projects inside the segment.
      const bool inside = glm::dot(g1, e) < 0.0 && glm::dot(g2, e) > 0.0;
      const float end2 = float(l1 < l2 ? l1 * l1 : l2 * l2);
      const float dist2 = inside ? c2 * segment.inverse_length2 : end2;
      nearest2 = dist2 < nearest2 ? dist2 : nearest2;
    }
    // In double: the cone's long inner edges carry large Biot–Savart terms that cancel between
    // neighbours, and in float that cancellation bends normals above a flat cap by 1e-2.
    if constexpr (WantGradient) near_gradient.add(corners, continues);
  }
};

template <bool WantGradient>
GWNRT_HD PhaseSample sample_phase(const ModelView& m, const vec3& x, float beta, bool exact) {
  // The exact reference reads every triangle as near: the bound from each segment alone.
  PhaseSum<WantGradient> sum{m.cone, m.cone_boundary_lengths, m.cone_segments, x, {}, {}, {}, kInfinity, 0.0f, {}};
  visit_multipole(m.cone, x, exact ? kInfinity : beta, sum);
  PhaseSample out;
  float w;
  if (exact) {
    const WindingSampleExact s = winding_number_exact(m.cone, x, WantGradient);
    w = float(s.w - floor(s.w));
    out.gradient = vec3(s.gradient);
  } else {
    // Ω/4π, the near part as Σ atan2 / 2π taken modulo 1 all at once.
    w = sum.far_field.omega * kInv4Pi + sum.near_half_angles.angle() * float(0.5 / kPi);
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
