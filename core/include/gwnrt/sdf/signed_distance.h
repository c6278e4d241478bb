// Signed distance to S = ∂{w > w*} (docs/design.md §4), negative inside {w > w*}: the distance to the
// sheet triangles, the pseudo-SDF of the smooth pieces (first order and curvature-corrected),
// Newton projection onto the smooth pieces, and the Harnack lower bound that clamps them all.
// Host-and-device.
#pragma once

#include "gwnrt/field/distance.h"
#include "gwnrt/field/evaluate_winding.h"
#include "gwnrt/geometry/model_view.h"
#include "gwnrt/trace/harnack.h"
#include "gwnrt/trace/march_regions.h"
#include "gwnrt/trace/phase.h"

namespace gwnrt {

// Smooth pieces, first order: the Newton step onto the level along n = ∇w/|∇w|,
// d₁ = (w* − w)/|∇w|. It is the signed distance to first order: outside (w < w*) the level lies
// ahead along n, inside behind. ±inf where ∇w = 0 (a closed mesh away from its sheets), 0 on
// the level.
GWNRT_HD inline float pseudo_distance(float w, const vec3& gradient, float level) {
  const float gap = level - w;
  if (gap == 0.0f) return 0.0f;
  return gap / glm::length(gradient);  // gap / 0 = ±inf with the gap's sign
}

// Curvature-corrected, d₂: along the same line w(x + t n) = w + |∇w| t + ½ nᵀH n t² + O(t³).
// With κ = ∇wᵀ H ∇w / |∇w|³ the level is reached where ½κt² + t − d₁ = 0, at the root nearest 0,
//   t = 2 d₁ / (1 + sqrt(1 + 2κd₁)) = d₁ (1 − κ d₁ / 2 + O(d₁²)).
// So for this convention (negative inside, d₁ = (w* − w)/|∇w|) the correction is −κd₁²/2: where
// w curves up along n (κ > 0) the level comes sooner than the straight line says. (With the
// opposite convention, d₁ changes sign and so would the correction's sign relative to d₁.)
// The root form never changes the sign of d₁ and stays within 2|d₁|; where the quadratic has no
// root (1 + 2κd₁ < 0) the line's closest approach in the model, t = 2d₁, is taken.
// Checked where the answer is known: the open hemisphere's disk, tests/sdf/test_signed_distance.cpp.
GWNRT_HD inline float curvature_corrected_distance(float w, const vec3& gradient, const sym3& hessian, float level) {
  const float d1 = pseudo_distance(w, gradient, level);
  if (d1 == 0.0f || !(fabsf(d1) < kInfinity)) return d1;
  const float g2 = glm::dot(gradient, gradient);
  const vec3 hg = hessian.apply(gradient);
  const float kappa = glm::dot(gradient, hg) / (g2 * sqrtf(g2));
  const float disc = 1.0f + 2.0f * kappa * d1;
  const float t = 2.0f * d1 / (1.0f + sqrtf(fmaxf(disc, 0.0f)));
  return t == t ? t : d1;  // κ = NaN (overflow of g2³ᐟ²) keeps the first order
}

// Newton projection onto the smooth part of S: x ← x − (w − w*) ∇w / |∇w|².
struct NewtonOptions {
  uint32_t max_iterations = 32;
  float tolerance = 1e-4f;     // converged when |w − w*| <= tolerance
  float max_step = 0.1f;       // a step is at most this fraction of M's box diagonal ...
  float mesh_fraction = 0.9f;  // ... and at most this fraction of the distance to M
};

struct SurfaceProjection {
  vec3 point{0.0f};
  uint32_t iterations = 0;  // Newton steps taken
  bool converged = false;
  float residual = 0.0f;  // w − w* at `point`
};

// Each step is clipped to the ball around x that M does not enter (times mesh_fraction): w is
// smooth there, so Newton follows one branch of w and cannot jump across the model onto a
// level on the far side of a sheet (where w differs by a whole number). It reports
// non-convergence (a zero gradient, the iteration cap, a point that stalls against M or leaves
// the region where S can be) instead of returning a point off S as if it were on it; `point` is
// then the last iterate.
GWNRT_HD inline SurfaceProjection project_onto_surface(const ModelView& m, const vec3& start, float level,
                                                       const WindingOptions& winding, const NewtonOptions& options) {
  SurfaceProjection out;
  out.point = start;
  // A closed mesh has no smooth pieces (w is a whole number off M): nothing to project onto;
  // Newton would only follow the expansion's round-off gradient.
  if (m.cone.triangle_count == 0) {
    out.residual = evaluate_winding(m, start, winding).w - level;
    out.converged = fabsf(out.residual) <= options.tolerance;
    return out;
  }
  const float max_step = options.max_step * glm::length(m.bounds.hi - m.bounds.lo);
  // |w| < |w*| farther than surface_margin·sqrt(1/(2|w*|)) from M's box (surface_margin is where
  // |w| < 1/2): a point that leaves that box follows w toward 0 at infinity and will not come
  // back to the level (w* = 0: no such box).
  const float margin = m.surface_margin * max_of(1.0f, sqrtf(0.5f / fabsf(level)));
  const vec3 lo = m.bounds.lo - margin, hi = m.bounds.hi + margin;
  vec3 x = start;
  for (uint32_t it = 0;; ++it) {
    const WindingSample s = evaluate_winding(m, x, winding, true, false);
    out.point = x;
    out.iterations = it;
    out.residual = s.w - level;
    if (fabsf(out.residual) <= options.tolerance) {
      out.converged = true;
      return out;
    }
    const float g2 = glm::dot(s.gradient, s.gradient);
    if (it == options.max_iterations || !(g2 > 0.0f) || !(g2 < kInfinity)) return out;
    vec3 step = -out.residual / g2 * s.gradient;
    const float length = glm::length(step);
    const float limit = min_of(max_step, options.mesh_fraction * unsigned_distance(m.triangles, x).distance);
    if (!(limit > 0.0f)) return out;  // on M
    if (length > limit) step *= limit / length;
    x += step;
    if (!(x.x >= lo.x && x.y >= lo.y && x.z >= lo.z && x.x <= hi.x && x.y <= hi.y && x.z <= hi.z)) {
      out.iterations = it + 1;
      return out;
    }
  }
}

// A lower bound on the distance from x to the smooth pieces of S for level w*: they lie in the
// march boxes (surface_trace.h: where w_C can reach a level at all), so the distance to the
// nearest box; +inf when there are no smooth pieces (a closed mesh).
GWNRT_HD inline float smooth_piece_distance_bound(const ModelView& m, float level, const vec3& x) {
  float d2 = kInfinity;
  for (uint32_t r = 0; r < march_box_count(m, level); ++r) {
    const Aabb box = march_box(m, level, r);
    const vec3 outside = glm::max(glm::max(box.lo - x, x - box.hi), vec3(0.0f));
    d2 = min_of(d2, glm::dot(outside, outside));
  }
  return sqrtf(d2);
}

inline constexpr float kExactPhaseGap = 2e-3f;

// A lower bound on the distance from x to the smooth pieces of S: they lie on the level set
// {φ = w* mod 1}, which no point of the ball of radius level_free_radius (harnack.h: Harnack's
// bound for the lift of φ, harmonic on the ball since the ball avoids ∂M, and the Lipschitz bound
// from the Biot–Savart field) reaches, nor any point closer than the march boxes
// (smooth_piece_distance_bound). `known_bound` is a distance below which the answer is not
// needed: when the boxes are already that far, φ is not evaluated.
GWNRT_HD inline float level_set_distance_bound(const ModelView& m, const vec3& x, float level, float beta,
                                               float known_bound = 0.0f) {
  const float boxes = smooth_piece_distance_bound(m, level, x);
  // A closed mesh (no cone) has no smooth pieces: w is a whole number off M.
  if (m.cone.triangle_count == 0 || (boxes >= known_bound && known_bound > 0.0f)) return boxes;
  const float phase = level - floorf(level);
  PhaseSample p = sample_phase(m, x, beta, false);
  LevelBracket levels = bracket_levels(p.phi, phase);
  // The cone's expansion is off by up to a few 1e-4 in φ at beta = 2; within kExactPhaseGap of a
  // level the ball would be sized by that error, not by φ, and could reach past the level. There
  // φ is summed exactly, over the cone only (one triangle per boundary segment).
  if (min_of(p.phi - levels.below, levels.above - p.phi) < kExactPhaseGap) {
    p = sample_phase(m, x, beta, false, true);
    levels = bracket_levels(p.phi, phase);
  }
  return fmaxf(level_free_radius(p.boundary_distance, p.gradient_bound, p.phi, levels), boxes);
}

// A lower bound on the distance from x to S. S lies on M (sheets) or on the level set
// {φ = w* mod 1} off M (smooth pieces; φ = w mod 1 is continuous across M). The ball of radius
// dist(x, M) holds no point of M, the ball of radius level_set_distance_bound no point of the
// level set; the smaller holds no point of S: ρ(x) <= dist(x, S). For a closed mesh (no
// smooth pieces) ρ is the distance to M.
GWNRT_HD inline float harnack_lower_bound(const ModelView& m, const vec3& x, float level, float beta,
                                          float mesh_distance) {
  return min_of(level_set_distance_bound(m, x, level, beta, mesh_distance), mesh_distance);
}

// Which estimate gave the signed distance.
enum class DistancePiece : uint32_t {
  kSheet = 0,         // the distance to the sheet triangles
  kSmooth = 1,        // the curvature-corrected pseudo-SDF
  kHarnackBound = 2,  // both were below ρ(x): the lower bound itself
};

struct SignedDistance {
  float distance = kInfinity;  // sdf: negative inside {w > w*}
  // sdf1 = d₁ and sdf2 = d₂; NaN where signed_distance did not need them (no smooth piece of S
  // can be nearer than the sheets; d₂ also where |d₁| >= 2 × the sheet distance): ask for them
  // with kFieldPseudoDistance.
  float first_order = kInfinity;
  float second_order = kInfinity;
  float sheet_distance = kInfinity;  // unsigned, to the sheet triangles (+inf when there are none)
  uint32_t sheet_triangle = kEmptyLane;
  DistancePiece piece = DistancePiece::kSheet;
};

// sdf(x) = sign(w* − w) · max(ρ(x), min(distance to the sheets, |d₂|)).
//  - Where no smooth piece can be nearer than the nearest sheet (level_set_distance_bound, +inf
//    for a closed mesh) the sheet distance is the answer and only w is evaluated, for the sign.
//  - The smooth estimate competes only where |d₁| < 2 × the sheet distance: beyond, d₂ could win
//    only with κd₁ > 4, where the quadratic model's correction would exceed its first-order
//    term fourfold and it no longer describes w.
//  - ρ only matters when it exceeds the estimate; as ρ <= dist(x, M) <= the sheet distance, it
//    is read only where the smooth estimate wins and lies closer than M, its level-set part the
//    one the first test computed.
// `sample`, when given, holds w, ∇w and H_w at x (a caller that needs them anyway); otherwise
// they are evaluated here, only as far as needed: w alone, then ∇w, then H_w (a second
// traversal, where d₂ must compete: rare, as smooth pieces win only close to them). With
// `with_sign` false the distance is |sdf|, and where the sheet distance is the answer no w is
// evaluated at all (the mesh report's points on the output: on a CAD part's faces they lie on M
// to round-off, where w takes the tree's sum at the cone's beta).
GWNRT_HD inline SignedDistance signed_distance(const ModelView& m, const vec3& x, float level,
                                               const WindingOptions& winding, const WindingSample* sample = nullptr,
                                               bool with_sign = true) {
  SignedDistance out;
  const NearestPrimitive sheet = unsigned_distance(m.sheets, x);
  out.sheet_distance = sheet.distance;
  out.sheet_triangle = sheet.primitive;
  out.first_order = out.second_order = __builtin_nanf("");
  if (sample) {
    out.first_order = pseudo_distance(sample->w, sample->gradient, level);
    out.second_order = curvature_corrected_distance(sample->w, sample->gradient, sample->hessian, level);
  }
  const float level_set_bound = level_set_distance_bound(m, x, level, winding.taylor.beta, sheet.distance);
  if (level_set_bound >= sheet.distance) {
    // Whatever the caller already has, the answer here is the sheet distance.
    if (!with_sign) {
      out.distance = sheet.distance;
      return out;
    }
    const float w = sample ? sample->w : evaluate_winding(m, x, winding).w;
    out.distance = copysignf(sheet.distance, level - w);
    return out;
  }
  // w and ∇w first: d₁ decides whether d₂, and so H_w, is needed at all.
  WindingSample s = sample ? *sample : evaluate_winding(m, x, winding, true, false);
  if (!sample) out.first_order = pseudo_distance(s.w, s.gradient, level);
  float best = sheet.distance;
  if (fabsf(out.first_order) < 2.0f * sheet.distance) {
    if (!sample) {
      s = evaluate_winding(m, x, winding, true, true);
      out.second_order = curvature_corrected_distance(s.w, s.gradient, s.hessian, level);
    }
    const float smooth = fabsf(out.second_order);
    if (smooth < best) {
      best = smooth;
      out.piece = DistancePiece::kSmooth;
      const float mesh_distance = unsigned_distance(m.triangles, x).distance;
      if (best < mesh_distance) {
        // harnack_lower_bound's ρ, its level-set bound the one above (φ summed fully there, as
        // the sheet distance it was asked against is at least the mesh distance).
        const float rho = min_of(level_set_bound, mesh_distance);
        if (rho > best) {
          best = rho;
          out.piece = DistancePiece::kHarnackBound;
        }
      }
    }
  }
  out.distance = with_sign ? copysignf(best, level - s.w) : best;
  return out;
}

}  // namespace gwnrt
