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

GWNRT_HD inline bool finite3(const vec3& v) { return is_finite(v.x) && is_finite(v.y) && is_finite(v.z); }

// Accept: bool(const RayHit&), asked about every candidate hit in increasing t; the trace ends
// at the first it accepts (an intersection filter turns candidates down).
template <class Accept>
class SurfaceTracer {
 public:
  GWNRT_HD SurfaceTracer(const ModelView& m, const Ray& ray, const TraceOptions& o, Accept accept)
      : m_(m), o_(o), accept_(accept) {
    const float len = float(glm::length(dvec3(ray.direction)));  // in float, |d|² under/overflows for finite d
    // A direction whose length is below the smallest normal float cannot be normalised (1e-44
    // gave t = inf for a hit): refused like a zero direction.
    if (!finite3(ray.origin) || !finite3(ray.direction) || !(len >= kMinDirectionLength) || !is_finite(len) ||
        is_nan(ray.tnear) || is_nan(ray.tfar)) {
      hit_.invalid = true;
      return;
    }
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

  // Harnack steps on φ over [t, t_end]; true when the trace ended (a hit, or a cap).
  GWNRT_HD bool march(float t, float t_end) {
    float t_prev = t, rho_prev = 0.0f;
    bool overstepped = false, gradient_wanted = false;
    // The previous sample (at t_prev), and whether the step from it was safe. φ is continued from
    // it to find the levels crossed since: none after a safe step, except when round-off carried
    // the step a few ulps past the level it stopped short of (found here, not lost); the level
    // after a deliberate jump across it (pending: +1 up, -1 down, already handled).
    bool have_prev = false, certified = false;
    float phi_prev = 0.0f, below_prev = 0.0f;
    int pending = 0;
    for (;;) {
      if (hit_.steps >= o_.max_steps) {
        hit_.capped = true;
        return true;
      }
      ++hit_.steps;
      const vec3 x = point(t);
      // Near ∂M the stopping test needs ∇w at almost every step; then it comes with φ.
      PhaseSample sample = sample_phase(m_, x, o_.beta, gradient_wanted, o_.exact);
      bool have_gradient = gradient_wanted;
      const float phi = sample.phi, radius = sample.boundary_distance;
      const LevelBracket levels = bracket_levels(phi, phase_);
      const float gap_below = phi - levels.below, gap_above = levels.above - phi;
      const float gap = min_of(gap_below, gap_above);
      const float ball = level_free_radius(radius, sample.gradient_bound, phi, levels);
      if (overstepped && t - t_prev > rho_prev + ball) {  // the long step was not covered
        t = t_prev + rho_prev;
        overstepped = false;
        continue;
      }
      overstepped = false;
      // No level lies in (t_prev, t): the crossings there come first.
      if (sheets_ && walk_crossings_until(t)) return true;
      int crossed = 0;
      float lifted = phi;  // φ continued from φ_prev
      if (have_prev) {
        float d = phi - phi_prev;
        d -= floorf(d + 0.5f);
        lifted = phi_prev + d;  // the nearest continuation: right for small changes
        if (certified) {
          // A safe step may change φ by almost a whole period: then the continuation is the one
          // inside φ_prev's bracket, unless the nearest one is only round-off past its end.
          const float over = max_of(below_prev - lifted, lifted - (below_prev + 1.0f));
          if (!(over >= 0.0f && over <= kPhaseRoundOff)) lifted = phi - floorf(phi - below_prev);
        }
        crossed = int(floorf(lifted - phase_)) - int(floorf(phi_prev - phase_));
      }
      if (crossed != 0) {
        const int step = crossed > 0 ? 1 : -1;
        if (step != pending && (!sheets_ || (band_ < 0) != (band_ + step < 0))) {
          // w* itself, crossed by round-off: the hit is here (φ is within a few ulps of it).
          if (!have_gradient) sample = sample_phase(m_, x, o_.beta, true, o_.exact);
          have_gradient = true;
          const float gn = glm::length(sample.gradient);
          if (gn > 0.0f && offer(t, HitKind::kSmooth, -sample.gradient / gn, kEmptyLane)) return true;
        }
        band_ += step;
      }
      pending = 0;
      // The second-order step looks ahead only (it leans on the sample behind).
      float rho = ball;
      const float delta = t - t_prev;
      if (crossed == 0 && have_prev && certified && delta > 0.0f && delta <= kCurvatureBallFraction * radius) {
        const float slope = (lifted - phi_prev) / delta;
        const float curvature = curvature_bound(radius, sample.gradient_bound);
        const float widen = 0.5f * curvature * delta;  // φ'(t) is the slope to within this
        const float ahead = min_of(curvature_bound_step(gap_above, slope + widen, curvature),
                                   curvature_bound_step(gap_below, widen - slope, curvature));
        rho = fmaxf(rho, min_of(ahead, kCurvatureBallFraction * radius));
      }
      gradient_wanted = gap <= eps_ * min_of(sample.gradient_bound, harnack_gradient_bound(radius, phi));
      if (gradient_wanted) {
        if (!have_gradient) sample = sample_phase(m_, x, o_.beta, true, o_.exact);
        const vec3 g = sample.gradient;
        const float gn = glm::length(g);
        if (gap <= eps_ * gn) {
          const bool at_above = gap_above <= gap_below;
          const float rate = glm::dot(g, dir_);  // dw/dt
          if (at_above ? rate > 0.0f : rate < 0.0f) {
            const int step = at_above ? 1 : -1;
            if ((!sheets_ || (band_ < 0) != (band_ + step < 0)) && offer(t, HitKind::kSmooth, -g / gn, kEmptyLane))
              return true;
            // A level of w other than w* (or a hit the filter turned down): step across it and
            // check on the far side.
            pending = step;
            t += min_of(2.0f * gap / fabsf(rate) + eps_, 10.0f * eps_);
          } else {
            t += fmaxf(rho, eps_);  // moving away from the level (or grazing it): no crossing
          }
          t_prev = t;
          rho_prev = 0.0f;
          have_prev = true;  // a jump, not a safe step
          certified = false;
          phi_prev = phi;
          below_prev = levels.below;
          if (t > t_end) return false;
          continue;
        }
      }
      if (t >= t_end) return false;
      const float safe = fmaxf(rho, 0.5f * eps_);  // R -> 0 on ∂M itself: keep moving
      if (t + safe >= t_end) return false;
      t_prev = t;
      rho_prev = safe;
      have_prev = true;
      certified = rho >= 0.5f * eps_;  // a safe step (over-stepping keeps it safe or goes back)
      phi_prev = phi;
      below_prev = levels.below;
      if (o_.overstep) {
        t = min_of(t + kOverstepFactor * safe, t_end);
        overstepped = true;
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
  bool sheets_ = false, smooth_ = false;
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
