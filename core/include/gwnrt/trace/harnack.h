// How long a step may be: how far φ = w mod 1 can be followed before it may reach a level. Three
// bounds, each safe on its own: Harnack's (Gillespie, Yang, Botsch, Crane 2024, Eq. 7 and
// Algorithm 2), a Lipschitz bound from the Biot–Savart field of ∂M, and a second-order one near
// a level (docs/design.md §3). The march that takes these steps is SurfaceTracer
// (surface_trace.h); what a step needs at a point is phase.h. Host-and-device.
#pragma once

#include "gwnrt/base/hd.h"

namespace gwnrt {

// The largest step from a point where a harmonic function has value f, known to stay above c
// on the ball of radius `radius` around the point, that cannot reach the value `target`.
// Written as 2R|1 - a| / (a + 2 + sqrt(a² + 8a)), a = (f - c)/(target - c): the paper's
// (R/2)|a + 2 - sqrt(a² + 8a)| without its cancellation near a = 1 (the last steps before a hit).
GWNRT_HD inline float harnack_step(float radius, float f, float target, float c) {
  if (!(target > c)) return radius;  // the target lies below the bound: nowhere in the ball
  const float a = (f - c) / (target - c);
  return 2.0f * radius * fabsf(1.0f - a) / (a + 2.0f + sqrtf(a * (a + 8.0f)));
}

// Levels of an angle-valued function with period 1 (here φ = w mod 1 ∈ [0, 1)): the values
// phase + k, k integer, phase ∈ [0, 1). `below` <= φ < `above` = below + 1.
struct LevelBracket {
  float below, above;
};

GWNRT_HD inline LevelBracket bracket_levels(float phi, float phase) {
  const float below = phase + floorf(phi - phase);
  return {below, below + 1.0f};
}

// The lift of φ on a ball that avoids ∂M is harmonic; as in the paper's Algorithm 2 it is taken
// to stay above φ's own range shifted down by one period, c = -1 (-4π for Ω). The step is the
// smaller of the steps toward the levels just below and just above.
inline constexpr float kAngleLowerBound = -1.0f;

GWNRT_HD inline float angle_valued_step(float radius, float phi, const LevelBracket& levels) {
  return min_of(harnack_step(radius, phi, levels.below, kAngleLowerBound),
                harnack_step(radius, phi, levels.above, kAngleLowerBound));
}

// A bound on |∇φ| from the same ball: a positive harmonic u on a ball of radius R in 3D has
// |∇u(centre)| <= 3 u(centre) / R. The tracer evaluates the gradient for its stopping test only
// where this bound says the test could pass.
GWNRT_HD inline float harnack_gradient_bound(float radius, float phi) {
  return 3.0f * (phi - kAngleLowerBound) / radius;
}

// The second safe step, from a bound K on |∇φ| at the centre of the ball (phase.h).
// Every point of ∂M is at least R away, so on the segment [x, x + θR·d] the Biot–Savart bound
// grows at most to K / (1 - θ)²; φ cannot move by `gap` (its distance to the nearer level)
// while θR·K / (1 - θ)² < gap. The largest such θ, with p = RK / gap, is the root of
// θ / (1 - θ)² = 1/p, written without cancellation. Beside an edge, where Harnack steps shrink
// in proportion to the gap, this one covers about 60% of the way to the level at every step.
GWNRT_HD inline float gradient_bound_step(float radius, float gradient_bound, float gap) {
  const float p = radius * gradient_bound / gap;  // gap = 0 gives p = inf and no step
  return 2.0f * radius / (2.0f + p + sqrtf(p * (4.0f + p)));
}

// A ball around a point on which φ reaches none of the levels `levels`: the larger of the
// Harnack step and the Lipschitz step, each safe alone (fmaxf also drops the NaN of the second
// on ∂M itself). `radius` is the distance to ∂M, `gradient_bound` K >= |∇φ| at the centre.
GWNRT_HD inline float level_free_radius(float radius, float gradient_bound, float phi, const LevelBracket& levels) {
  const float gap = min_of(phi - levels.below, levels.above - phi);
  return fmaxf(angle_valued_step(radius, phi, levels), gradient_bound_step(radius, gradient_bound, gap));
}

// The third safe step, of second order, for the last steps onto a level (where the first-order
// steps above only shrink the gap by a constant factor each). Differentiating the Biot–Savart
// field once more gives |∂²φ/∂t²| <= (1/4π)∮ 2|dl| / |l - y|³ <= 2K(y)/R(y), so on the ball of
// radius θR around x the curvature is at most 2K / (R (1 - θ)³). With the previous sample Δ
// behind (inside that ball), the secant slope bounds φ'(x) to within curvature·Δ/2, and φ(x + s)
// to within a quadratic in s: the step it allows takes the gap down quadratically.
inline constexpr float kCurvatureBallFraction = 0.25f;  // θ: both Δ and the step stay within θR

GWNRT_HD inline float curvature_bound(float radius, float gradient_bound) {
  constexpr float shrink =
      (1.0f - kCurvatureBallFraction) * (1.0f - kCurvatureBallFraction) * (1.0f - kCurvatureBallFraction);
  return 2.0f * gradient_bound / (radius * shrink);
}

// The largest s >= 0 with slope·s + curvature·s²/2 <= gap (slope may be negative: moving away).
GWNRT_HD inline float curvature_bound_step(float gap, float slope, float curvature) {
  const float root = sqrtf(slope * slope + 2.0f * curvature * gap);
  return slope >= 0.0f ? 2.0f * gap / (slope + root) : (root - slope) / curvature;
}

// Over-stepping (the paper's §3.1.4): try this multiple of the safe step; the longer step is
// kept only when the safe balls of both of its ends cover it. The paper's 1.75 suits Harnack
// steps alone, which are far shorter than they need be; next to the Lipschitz and second-order
// steps it fails often enough to cost time (docs/performance.md, tracing).
inline constexpr float kOverstepFactor = 1.3f;
inline constexpr float kPaperOverstepFactor = 1.75f;  // for a tracer with Harnack steps only

}  // namespace gwnrt
