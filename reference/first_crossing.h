// The first point of a level set of w along a ray, by the brute-force w of brute_force_winding.h:
// the ray sampled densely, the first sign change of (w - level) refined by bisection. w jumps by
// ±1 across a triangle, so the bisection converges either to a smooth crossing of the level or
// to a triangle whose jump straddles it; both lie on S = ∂{w > level}. In solid-angle mode w is
// lifted continuously across the ±1 jumps first, so only smooth crossings of φ = w mod 1 count.
// The reference for gwnrt's tracer on meshes with holes (tests/trace/test_surface_trace_open.cpp, the plugin tests).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "gwnrt/geometry/ray.h"
#include "reference/brute_force_winding.h"

namespace gwnrt::reference {

enum class ReferenceMode { kWindingNumber, kSolidAngle };

// w sampled along a ray: s is the distance along the unit direction.
struct ReferenceProfile {
  dvec3 origin, direction;  // direction unit
  double length = 1;        // |ray.direction|: t = s / length
  std::vector<double> s, w;
  dvec3 point(double si) const { return origin + si * direction; }
};

// The ray from s0 to s1 (distances along the unit direction), sampled at `samples` + 1 evenly
// spaced points.
inline ReferenceProfile reference_profile_between(const ReferenceMesh& r, const Ray& ray, double s0, double s1,
                                                  int samples) {
  ReferenceProfile p;
  p.origin = dvec3(ray.origin);
  p.length = glm::length(dvec3(ray.direction));
  p.direction = dvec3(ray.direction) / p.length;
  if (!(s0 < s1)) return p;
  p.s.resize(samples + 1);
  p.w.resize(samples + 1);
  for (int i = 0; i <= samples; ++i) {
    p.s[i] = s0 + (s1 - s0) * double(i) / samples;
    p.w[i] = reference_w(r, p.point(p.s[i]));
  }
  return p;
}

// [s0, s1] of the ray (from tnear on) inside `box`; s0 > s1 when it misses.
inline void clip_ray_to_box(const Ray& ray, const Aabb& box, double& s0, double& s1) {
  const dvec3 o(ray.origin);
  const double length = glm::length(dvec3(ray.direction));
  const dvec3 d = dvec3(ray.direction) / length;
  s0 = std::max(0.0, double(ray.tnear) * length);
  s1 = double(ray.tfar) * length;
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0) {
      if (o[k] < box.lo[k] || o[k] > box.hi[k]) s1 = -1;
      continue;
    }
    double a = (box.lo[k] - o[k]) / d[k], b = (box.hi[k] - o[k]) / d[k];
    if (a > b) std::swap(a, b);
    s0 = std::max(s0, a);
    s1 = std::min(s1, b);
  }
}

// The part of the ray inside `box`, sampled at `samples` + 1 evenly spaced points (none when
// the ray misses the box).
inline ReferenceProfile reference_profile(const ReferenceMesh& r, const Ray& ray, const Aabb& box, int samples) {
  double s0, s1;
  clip_ray_to_box(ray, box, s0, s1);
  return reference_profile_between(r, ray, s0, s1, samples);
}

struct ReferenceCrossing {
  bool hit = false;
  double s = std::numeric_limits<double>::infinity();  // along the unit direction
  double t = std::numeric_limits<double>::infinity();  // in units of the ray's direction
  bool sheet = false;   // a triangle whose ±1 jump straddles the level (winding-number mode)
  dvec3 gradient{0.0};  // ∇w at the crossing (smooth crossings)
  double rate = 0;      // |dw/ds| there: how fast the ray crosses the level (infinite for sheets)
};

namespace detail {
// The change of w from a to b with whole jumps removed (solid-angle mode): right while the
// smooth change over the interval stays below 1/2.
inline double wrapped_change(double a, double b) {
  const double d = b - a;
  return d - std::floor(d + 0.5);
}
}  // namespace detail

// First crossing of `level` along a sampled profile, refined by bisection to double precision.
// Winding-number mode: the first sign change of w - level (a smooth crossing or a triangle whose
// jump straddles the level). Solid-angle mode: w is lifted continuously across the ±1 jumps and
// the first copy level + k that the lift meets counts.
inline ReferenceCrossing reference_crossing(const ReferenceMesh& r, const ReferenceProfile& p, double level,
                                            ReferenceMode mode = ReferenceMode::kWindingNumber) {
  ReferenceCrossing out;
  const bool lifted = mode == ReferenceMode::kSolidAngle;
  double lift = p.w.empty() ? 0.0 : p.w[0];
  for (size_t i = 0; i + 1 < p.s.size(); ++i) {
    const double next = lifted ? lift + detail::wrapped_change(p.w[i], p.w[i + 1]) : p.w[i + 1];
    double target = level;
    if (lifted) target += next >= lift ? std::floor(lift - level) + 1 : std::ceil(lift - level) - 1;
    double ga = lift - target, gb = next - target;
    lift = next;
    if (ga != 0 && (ga > 0) == (gb > 0)) continue;
    double a = p.s[i], b = p.s[i + 1], wa = p.w[i], lift_a = ga + target;
    for (int it = 0; it < 200; ++it) {
      const double m = 0.5 * (a + b);
      if (m <= a || m >= b) break;
      const double wm = reference_w(r, p.point(m));
      const double lift_m = lifted ? lift_a + detail::wrapped_change(wa, wm) : wm;
      const double gm = lift_m - target;
      if (gm != 0 && (gm > 0) == (ga > 0)) {
        a = m;
        ga = gm;
        wa = wm;
        lift_a = lift_m;
      } else {
        b = m;
        gb = gm;
      }
    }
    out.hit = true;
    out.s = 0.5 * (a + b);
    out.t = out.s / p.length;
    out.sheet = !lifted && std::fabs(gb - ga) > 0.5;  // a whole jump of w, not a smooth change
    if (out.sheet) {
      out.rate = std::numeric_limits<double>::infinity();
    } else {
      out.gradient = reference_gradient(r, p.point(out.s));
      out.rate = std::fabs(glm::dot(out.gradient, p.direction));
    }
    return out;
  }
  return out;
}

// The whole reference in one call: the first point of S = ∂{w > level} (solid-angle mode: of
// {w ≡ level mod 1}, smooth crossings only) along `ray` inside `box`, or none.
inline ReferenceCrossing reference_first_crossing(const ReferenceMesh& r, const Ray& ray, double level, const Aabb& box,
                                                  int samples, ReferenceMode mode = ReferenceMode::kWindingNumber) {
  return reference_crossing(r, reference_profile(r, ray, box, samples), level, mode);
}

}  // namespace gwnrt::reference
