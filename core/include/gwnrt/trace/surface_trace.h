// Ray first-hit on S = ∂{w > w*} (docs/design.md §1, §3), and on level sets of Ω mod 4π (solid-angle
// mode). Host-and-device: the TBB driver, the renderer and the CUDA kernel all call trace_surface.
//
// Along a ray, w = (its band, an integer) + φ, φ = w mod 1. φ is continuous across M and
// harmonic off ∂M; it is evaluated on the cone C (ModelView::cone), whose size is that of ∂M.
// The ray is followed by two monotone walks, merged in t order:
//  - the crossings of M, exact and in order (ray.h): each moves w by ±1; one that moves w across
//    w* is a sheet hit;
//  - safe steps on φ (harnack.h: Harnack's with R = distance to ∂M, a Lipschitz step from the
//    Biot–Savart bound on |∇w|, and a second-order step near a level, whichever is longest;
//    phase.h evaluates what they need): every step is free of levels w* + k; where the march
//    converges on a level that w itself crosses at w*, it is a smooth hit; other levels
//    (w* ± 1, ...) are stepped across and move the band.
// A closed mesh has no ∂M, so no Harnack steps: the trace is one walk over its crossings.
#pragma once

#include "gwnrt/field/winding_number.h"
#include "gwnrt/geometry/model_view.h"
#include "gwnrt/geometry/ray.h"
#include "gwnrt/trace/harnack.h"
#include "gwnrt/trace/level_free_cells.h"
#include "gwnrt/trace/march_regions.h"
#include "gwnrt/trace/phase.h"
#include "gwnrt/trace/trace_types.h"

namespace gwnrt {

namespace detail {

// w_C at x: where the march starts, the integer part of w comes from it (sample_phase has only
// φ = w_C mod 1).
GWNRT_HD inline float cone_winding_number(const TriangleTreeView& cone, const vec3& x, const TraceOptions& o) {
  return o.exact ? float(winding_number_exact(cone, x).w) : winding_number_taylor<2, false, false>(cone, x, o.beta).w;
}

// Accept: bool(const RayHit&), asked about every candidate hit in increasing t; the trace ends
// at the first it accepts (an intersection filter turns candidates down).
template <class Accept>
class SurfaceTracer {
 public:
  GWNRT_HD SurfaceTracer(const ModelView& m, const Ray& ray, const TraceOptions& o, Accept accept)
      : m_(m), o_(o), accept_(accept) {
    if (untraceable_ray(ray)) {
      hit_.invalid = true;
      return;
    }
    const float len = float(glm::length(dvec3(ray.direction)));  // as untraceable_ray takes it
    len_ = len;
    dir_ = ray.direction / len;
    const vec3 extent = m.bounds.hi - m.bounds.lo;
    const float diagonal = glm::length(extent);
    // A ray from far away starts again on its line, across from the box's centre: t and the
    // points along the ray then step as finely as the mesh's coordinates do, where from 1e8 they
    // stepped by 8 and a unit tetrahedron was missed. Nearer rays are left as they are (a shift
    // would only move their rounding). The hit's t adds the shift back.
    const double ahead = glm::dot(dvec3(m.bounds.centre()) - dvec3(ray.origin), dvec3(dir_));
    vec3 origin = ray.origin;
    if (ahead > kFarRayDiagonals * double(diagonal)) {
      origin = vec3(dvec3(ray.origin) + ahead * dvec3(dir_));
      t_shift_ = ahead;
    }
    frame_ = make_ray_frame(origin, dir_);
    // In double: the shift is exact there, and rounded to float it moved a far ray's tnear or tfar
    // by up to half a float step of the distance (4 at 1e8), past a whole unit cube.
    t_near_ = float(double(ray.tnear) * double(len) - t_shift_);
    t_far_ = float(double(ray.tfar) * double(len) - t_shift_);
    sheets_ = o.mode == TraceMode::kWindingNumber;
    smooth_ = m.cone.triangle_count > 0;
    eps_ = o.epsilon * diagonal;
    phase_ = o.level - floorf(o.level);
    // No sheet and no smooth piece of w is at a level w never reaches (model_view.h); the
    // band's integer arithmetic below then also stays within an int.
    if (sheets_ && !level_within_reach(m, o.level)) sheets_ = smooth_ = false;
    // Not for the exact march: it is the reference the cells' proofs are tested against.
    free_cells_ = !o.exact && level_free_cells_apply(m.level_free, phase_);
  }

  GWNRT_HD RayHit run() {
    if (hit_.invalid || !(sheets_ || smooth_) || !(t_near_ <= t_far_)) return hit_;
    // Where the march is needed (see SmoothRegion), as sorted disjoint intervals.
    struct Interval {
      float a, b;
    } march[kMaxSmoothRegions];
    int march_count = 0;
    // Whether the march intervals are the smooth regions, on whose boundary |w_C| < δ still holds,
    // and whether the ray's own start lies inside one of them.
    bool proven_regions = false, origin_inside = false;
    if (smooth_) {
      proven_regions = level_distance(o_.level) > kMinLevelDistance;
      const uint32_t regions = march_box_count(m_, o_.level);
      for (uint32_t r = 0; r < regions; ++r) {
        const Aabb box = march_box(m_, o_.level, r);
        float a, b;
        clip_to_box(frame_, box, a, b);
        origin_inside = origin_inside || (a < t_near_ && t_near_ <= b);
        a = max_of(a, t_near_);
        b = min_of(b, t_far_);
        if (!(a <= b)) continue;
        int i = march_count++;  // insertion by start
        for (; i > 0 && march[i - 1].a > a; --i) march[i] = march[i - 1];
        march[i] = {a, b};
      }
      int merged = 0;
      for (int i = 0; i < march_count; ++i) {
        if (merged > 0 && march[i].a <= march[merged - 1].b) {
          march[merged - 1].b = max_of(march[merged - 1].b, march[i].b);
        } else {
          march[merged++] = march[i];
        }
      }
      march_count = merged;
    }
    float box0 = kInfinity, box1 = -kInfinity;
    if (sheets_) clip_to_box(frame_, crossing_box(m_), box0, box1);
    float t_start = sheets_ && box0 <= box1 ? box0 : kInfinity;
    t_end_ = sheets_ && box0 <= box1 ? box1 : -kInfinity;
    if (march_count > 0) {
      t_start = min_of(t_start, march[0].a);
      t_end_ = max_of(t_end_, march[march_count - 1].b);
    }
    t_start = max_of(t_start, t_near_);
    t_end_ = min_of(t_end_, t_far_);
    if (!(t_start <= t_end_)) return hit_;

    // march[0] starts at or after t_start; the start lies in a region exactly when they meet. A
    // ray from outside starts on a region's boundary, where the regions' bound still holds: w_C
    // needs evaluating only at a start strictly inside.
    const bool start_in_region =
        march_count > 0 && (march[0].a < t_start || (march[0].a == t_start && (origin_inside || !proven_regions)));
    float w_start = 0.0f;
    if (start_in_region) w_start = cone_winding_number(m_.cone, point(t_start), o_);
    if (sheets_) {
      // The integer part of w at the start: crossings of the closed M − C since the line entered
      // M's box (which holds C), where w = w_C.
      const int crossed = box0 < t_start
                              ? crossing_sum(m_.triangles.bvh, m_.triangles.vertices, frame_, box0, t_start) -
                                    crossing_sum(m_.cone.bvh, m_.cone.vertices, frame_, box0, t_start)
                              : 0;
      // Outside every region (and on their boundary) |w_C| < δ, so floor(w_C - w*) = -1 - floor(w*)
      // without evaluating it.
      band_ = start_in_region ? int(floorf(w_start + float(crossed) - o_.level)) : crossed - 1 - int(floorf(o_.level));
      have_next_ = next_crossing(m_.triangles.bvh, m_.triangles.vertices, frame_, t_start, kEmptyLane, t_end_, next_);
    }
    for (int k = 0; k < march_count; ++k) {
      const float a = max_of(march[k].a, t_start), b = min_of(march[k].b, t_end_);
      if (!(a <= b)) continue;
      if (sheets_ && walk_crossings_until(a)) return hit_;
      if (this->march(a, b)) return hit_;
    }
    if (sheets_) walk_crossings_until(t_end_);
    return hit_;
  }

 private:
  GWNRT_HD vec3 point(float t) const { return frame_.origin + t * dir_; }

  // A candidate hit for the caller's filter; true when it is accepted (the trace ends there),
  // false when the trace is to go on past it.
  GWNRT_HD bool offer(float t, HitKind kind, const vec3& normal, uint32_t triangle) {
    hit_.hit = true;
    hit_.kind = kind;
    hit_.t = float((double(t) + t_shift_) / double(len_));
    hit_.position = point(t);
    hit_.normal = normal;
    hit_.triangle = triangle;
    if (accept_(static_cast<const RayHit&>(hit_))) return true;
    hit_.hit = false;
    hit_.kind = HitKind::kNone;
    hit_.t = kInfinity;
    hit_.position = vec3(0.0f);
    hit_.normal = vec3(0.0f);
    hit_.triangle = kEmptyLane;
    return false;
  }

  // Applies the crossings with t <= t_limit in order; true when one of them is a sheet hit (or
  // the crossing cap ended the trace).
  GWNRT_HD bool walk_crossings_until(float t_limit) {
    while (have_next_ && next_.t <= t_limit) {
      if (++hit_.crossings > o_.max_crossings) {
        hit_.crossings = o_.max_crossings;
        hit_.capped = true;
        return true;
      }
      const int band = band_ + next_.jump;
      if ((band_ < 0) != (band < 0)) {
        const uint32_t i = next_.index;
        const vec3* v = m_.triangles.vertices + 3 * i;
        vec3 n = glm::cross(v[1] - v[0], v[2] - v[0]);
        n /= glm::length(n);
        // Entering {w > w*} the outside is behind the ray, leaving it the outside is ahead.
        const bool entering = band >= 0;
        if ((glm::dot(n, dir_) > 0.0f) == entering) n = -n;
        if (offer(next_.t, HitKind::kSheet, n, m_.triangles.triangle_ids[i])) return true;
      }
      band_ = band;
      have_next_ = next_crossing(m_.triangles.bvh, m_.triangles.vertices, frame_, next_.t, next_.index, t_end_, next_);
    }
    return false;
  }

  // One sample of the march: φ and what bounds the step from it (phase.h, harnack.h).
  struct MarchSample {
    vec3 x;
    PhaseSample phase;
    bool have_gradient = false;  // phase.gradient holds ∇w
    float phi = 0.0f, radius = 0.0f;
    LevelBracket levels;
    float gap_below = 0.0f, gap_above = 0.0f, gap = 0.0f;
    float ball = 0.0f;  // the radius free of levels about x
  };

  // What the march keeps of its previous sample (at t_prev): the step from it (rho_prev, and
  // certified when that was a safe step, not a jump), φ there and its bracket's lower level, a
  // level just jumped across on purpose (pending: +1 up, -1 down), and whether the next sample
  // needs ∇w.
  struct MarchMemory {
    float t_prev = 0.0f, rho_prev = 0.0f, phi_prev = 0.0f, below_prev = 0.0f;
    bool have_prev = false, certified = false, overstepped = false, gradient_wanted = false;
    int pending = 0;
  };

  enum class LevelStep { kNone, kJumped, kEnded };

  // Near ∂M the stopping test needs ∇w at almost every step; then it comes with φ.
  GWNRT_HD GWNRT_FORCEINLINE MarchSample sample_at(float t, bool gradient_wanted) const {
    MarchSample s;
    s.x = point(t);
    s.phase = sample_phase(m_, s.x, o_.beta, gradient_wanted, o_.exact);
    s.have_gradient = gradient_wanted;
    s.phi = s.phase.phi;
    s.radius = s.phase.boundary_distance;
    s.levels = bracket_levels(s.phi, phase_);
    s.gap_below = s.phi - s.levels.below;
    s.gap_above = s.levels.above - s.phi;
    s.gap = min_of(s.gap_below, s.gap_above);
    s.ball = level_free_radius(s.radius, s.phase.gradient_bound, s.phi, s.levels);
    return s;
  }

  GWNRT_HD GWNRT_FORCEINLINE void want_gradient(MarchSample& s) const {
    if (!s.have_gradient) s.phase = sample_phase(m_, s.x, o_.beta, true, o_.exact);
    s.have_gradient = true;
  }

  // φ continued from the previous sample: the nearest continuation, right for small changes; after
  // a safe step, which may change φ by almost a whole period, the one inside φ_prev's bracket
  // unless the nearest one is only round-off past its end.
  GWNRT_HD GWNRT_FORCEINLINE float continued_phi(const MarchMemory& mem, float phi) const {
    float d = phi - mem.phi_prev;
    d -= floorf(d + 0.5f);
    float lifted = mem.phi_prev + d;
    if (mem.certified) {
      const float over = max_of(mem.below_prev - lifted, lifted - (mem.below_prev + 1.0f));
      if (!(over >= 0.0f && over <= kPhaseRoundOff)) lifted = phi - floorf(phi - mem.below_prev);
    }
    return lifted;
  }

  // The levels crossed since the previous sample move the band; w* itself, crossed by round-off
  // (φ is within a few ulps of it), is a hit here. True when the trace ended.
  GWNRT_HD GWNRT_FORCEINLINE bool settle_crossed_levels(int crossed, int pending, float t, MarchSample& s) {
    if (crossed == 0) return false;
    const int step = crossed > 0 ? 1 : -1;
    if (step != pending && (!sheets_ || (band_ < 0) != (band_ + step < 0))) {
      want_gradient(s);
      const float gn = glm::length(s.phase.gradient);
      if (gn > 0.0f && offer(t, HitKind::kSmooth, -s.phase.gradient / gn, kEmptyLane)) return true;
    }
    band_ += step;
    return false;
  }

  // The safe step from s: its level-free ball, or the second-order step from the secant slope to
  // the previous sample and the curvature bound when longer (it looks ahead only, leaning on the
  // sample behind, so only after a safe step that crossed no level).
  GWNRT_HD GWNRT_FORCEINLINE float step_radius(const MarchMemory& mem, int crossed, float t, float lifted,
                                               const MarchSample& s) const {
    float rho = s.ball;
    const float delta = t - mem.t_prev;
    if (crossed == 0 && mem.have_prev && mem.certified && delta > 0.0f && delta <= kCurvatureBallFraction * s.radius) {
      const float slope = (lifted - mem.phi_prev) / delta;
      const float curvature = curvature_bound(s.radius, s.phase.gradient_bound);
      const float widen = 0.5f * curvature * delta;  // φ'(t) is the slope to within this
      const float ahead = min_of(curvature_bound_step(s.gap_above, slope + widen, curvature),
                                 curvature_bound_step(s.gap_below, widen - slope, curvature));
      rho = fmaxf(rho, min_of(ahead, kCurvatureBallFraction * s.radius));
    }
    return rho;
  }

  // Within eps of a level by ∇w: a smooth hit where w crosses w* there, else a jump across the
  // level (or on, moving away from it), checked on the far side. kNone when not that near.
  GWNRT_HD GWNRT_FORCEINLINE LevelStep step_across_level(float& t, float rho, MarchSample& s, MarchMemory& mem) {
    want_gradient(s);
    const vec3 g = s.phase.gradient;
    const float gn = glm::length(g);
    if (!(s.gap <= eps_ * gn)) return LevelStep::kNone;
    const bool at_above = s.gap_above <= s.gap_below;
    const float rate = glm::dot(g, dir_);  // dw/dt
    if (at_above ? rate > 0.0f : rate < 0.0f) {
      const int step = at_above ? 1 : -1;
      if ((!sheets_ || (band_ < 0) != (band_ + step < 0)) && offer(t, HitKind::kSmooth, -g / gn, kEmptyLane))
        return LevelStep::kEnded;
      // A level of w other than w* (or a hit the filter turned down): step across it and check
      // on the far side.
      mem.pending = step;
      t += min_of(2.0f * s.gap / fabsf(rate) + eps_, 10.0f * eps_);
    } else {
      t += fmaxf(rho, eps_);  // moving away from the level (or grazing it): no crossing
    }
    mem.t_prev = t;
    mem.rho_prev = 0.0f;
    mem.have_prev = true;  // a jump, not a safe step
    mem.certified = false;
    mem.phi_prev = s.phi;
    mem.below_prev = s.levels.below;
    return LevelStep::kJumped;
  }

  // Harnack steps on φ over [t, t_end]; true when the trace ended (a hit, or a cap). Each step:
  // sample, go back if an over-step was not covered, walk the crossings up to here, settle the
  // levels crossed, then stop on, jump across or step safely toward the next level.
  GWNRT_HD bool march(float t, float t_end) {
    MarchMemory mem;
    mem.t_prev = t;
    for (;;) {
      if (hit_.steps >= o_.max_steps) {
        hit_.capped = true;
        return true;
      }
      ++hit_.steps;
      MarchSample s = sample_at(t, mem.gradient_wanted);
      if (mem.overstepped && t - mem.t_prev > mem.rho_prev + s.ball) {  // the long step was not covered
        t = mem.t_prev + mem.rho_prev;
        mem.overstepped = false;
        continue;
      }
      mem.overstepped = false;
      // No level lies in (t_prev, t): the crossings there come first.
      if (sheets_ && walk_crossings_until(t)) return true;
      const float lifted = mem.have_prev ? continued_phi(mem, s.phi) : s.phi;
      const int crossed = mem.have_prev ? int(floorf(lifted - phase_)) - int(floorf(mem.phi_prev - phase_)) : 0;
      if (settle_crossed_levels(crossed, mem.pending, t, s)) return true;
      mem.pending = 0;
      const float rho = step_radius(mem, crossed, t, lifted, s);
      mem.gradient_wanted = s.gap <= eps_ * min_of(s.phase.gradient_bound, harnack_gradient_bound(s.radius, s.phi));
      if (mem.gradient_wanted) {
        const LevelStep jump = step_across_level(t, rho, s, mem);
        if (jump == LevelStep::kEnded) return true;
        if (jump == LevelStep::kJumped) {
          if (t > t_end) return false;
          continue;
        }
      }
      if (t >= t_end) return false;
      float safe = fmaxf(rho, 0.5f * eps_);  // R -> 0 on ∂M itself: keep moving
      // Across the level-free cells ahead at once where they reach farther: as safe a step.
      const float cells = free_cells_ ? level_free_run(m_.level_free, s.x, dir_) : 0.0f;
      const bool across_cells = cells >= safe;  // safe > 0: a run of cells, then never over-stepped
      if (across_cells) safe = cells;
      if (t + safe >= t_end) return false;
      mem.t_prev = t;
      mem.rho_prev = safe;
      mem.have_prev = true;
      mem.certified = rho >= 0.5f * eps_ || across_cells;  // a safe step (over-stepping keeps it safe or goes back)
      mem.phi_prev = s.phi;
      mem.below_prev = s.levels.below;
      if (o_.overstep && !across_cells) {
        t = min_of(t + kOverstepFactor * safe, t_end);
        mem.overstepped = true;
      } else {
        t += safe;
      }
    }
  }

  const ModelView& m_;
  const TraceOptions& o_;
  Accept accept_;
  RayHit hit_;
  RayFrame frame_{};
  vec3 dir_{0.0f};
  float len_ = 1.0f, t_near_ = 0.0f, t_far_ = 0.0f, t_end_ = 0.0f, eps_ = 0.0f, phase_ = 0.5f;
  double t_shift_ = 0.0;  // where the ray's own origin lies, in t from the one traced from
  bool sheets_ = false, smooth_ = false, free_cells_ = false;
  int band_ = 0;  // floor(w - w*) just after the last event
  bool have_next_ = false;
  CrossingHit next_;
};

}  // namespace detail

namespace detail {
struct AcceptFirst {
  GWNRT_HD bool operator()(const RayHit&) const { return true; }
};
}  // namespace detail

// The first hit of the ray on S within [tnear, tfar].
GWNRT_HD inline RayHit trace_surface(const ModelView& model, const Ray& ray, const TraceOptions& options) {
  return detail::SurfaceTracer<detail::AcceptFirst>(model, ray, options, {}).run();
}

// The first hit that `accept` (bool(const RayHit&)) accepts: it is offered the hits in increasing
// t and the trace goes on past those it turns down (an intersection filter). A hit turned down
// is not reported; a miss means none was accepted.
template <class Accept>
GWNRT_HD RayHit trace_surface(const ModelView& model, const Ray& ray, const TraceOptions& options, Accept accept) {
  return detail::SurfaceTracer<Accept>(model, ray, options, accept).run();
}

}  // namespace gwnrt
