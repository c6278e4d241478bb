// The one entry point for w (and ∇w, H_w) with a choice of method: exact by crossings and the
// cone (crossing_winding.h), the multipole tree (winding_number.h) or the double brute-force sum,
// and the rule by which `auto` chooses. Every query that needs w goes through here.
// Host-and-device.
#pragma once

#include <string_view>

#include "gwnrt/field/crossing_winding.h"
#include "gwnrt/field/winding_number.h"
#include "gwnrt/geometry/model_view.h"

namespace gwnrt {

enum class WindingMethod : uint32_t {
  kAuto = 0,      // crossing where it costs about as much as taylor or less (the rules below), else taylor
  kCrossing = 1,  // exact: signed crossings of M and C along a ray, plus the cone's field
  kTaylor = 2,    // the multipole tree at TaylorOptions' order and beta
  kBrute = 3,     // every triangle's exact term, summed in double (the reference)
};

inline constexpr uint32_t kWindingMethodCount = 4;

GWNRT_HD inline const char* winding_method_name(WindingMethod method) {
  switch (method) {
    case WindingMethod::kAuto:
      return "auto";
    case WindingMethod::kCrossing:
      return "crossing";
    case WindingMethod::kTaylor:
      return "taylor";
    default:
      return "brute";
  }
}

// The WindingMethod that winding_method_name calls `name`; false for any other name (for the
// programs and bindings that take the method by name).
inline bool winding_method_named(std::string_view name, WindingMethod& method) {
  for (uint32_t m = 0; m < kWindingMethodCount; ++m)
    if (name == winding_method_name(WindingMethod(m))) {
      method = WindingMethod(m);
      return true;
    }
  return false;
}

struct WindingOptions {
  WindingMethod method = WindingMethod::kAuto;
  TaylorOptions taylor;  // for kTaylor
};

// Two rules for `auto`. Fields that gain from exactness beyond one point's cost (the mesher, whose
// crossing path settles corners by box bounds; the sheets' classification) take the crossing
// method when ∂M has at most kCrossingConeRatio segments per triangle of M: a crossing query costs
// one ray through M's tree plus the cone's tree at kConeBeta (nearer cone triangles exactly, in
// double), a Taylor query one traversal of M's tree at beta, and that is about where the two cost
// the same on meshes whose loops are small and few (docs/performance.md). A soup whose every edge
// is on ∂M has three per triangle.
inline constexpr float kCrossingConeRatio = 0.1f;

GWNRT_HD inline WindingMethod resolve_winding_method(const ModelView& m, WindingMethod requested) {
  if (requested != WindingMethod::kAuto) return requested;
  return float(m.boundary.segment_count) <= kCrossingConeRatio * float(m.triangles.triangle_count)
             ? WindingMethod::kCrossing
             : WindingMethod::kTaylor;
}

// Point queries go by the work itself, sampled once per model (ModelView::crossing_work_ratio):
// a crossing query's cone triangles summed exactly and clusters expanded, over a Taylor query's
// (order 2, beta 2) clusters expanded and triangles summed, at a 7³ lattice over M's box grown by
// a fifth on each side. A unit of crossing work costs about 1.75 of Taylor's (its sums in double,
// plus M's walk), so the two take the same time at a work ratio of about 0.6, and up to there the
// exact one is taken: a scan with hundreds of holes around a long rim (2.9: Taylor, five times
// faster) is told from meshes whose loops are as few but small (0.23–0.36), which the ∂M-size rule
// above cannot tell apart (docs/performance.md).
inline constexpr float kCrossingWorkRatio = 0.6f;

GWNRT_HD inline WindingMethod resolve_point_method(const ModelView& m, WindingMethod requested) {
  if (requested != WindingMethod::kAuto) return requested;
  return m.crossing_work_ratio <= kCrossingWorkRatio ? WindingMethod::kCrossing : WindingMethod::kTaylor;
}

// The ratio resolve_point_method reads, sampled on `m` (its triangles, boundary and cone).
inline float sample_crossing_work_ratio(const ModelView& m) {
  if (m.cone.triangle_count == 0) return 0.0f;
  struct TaylorWork {
    uint64_t units = 0;
    void far(uint32_t, int, const vec3&) { ++units; }
    void near(uint32_t, const vec3&, const vec3&, const vec3&) { ++units; }
  } taylor;
  CrossingStats crossing;
  constexpr int kSide = 7;
  const vec3 extent = m.bounds.hi - m.bounds.lo;
  for (int i = 0; i < kSide; ++i)
    for (int j = 0; j < kSide; ++j)
      for (int k = 0; k < kSide; ++k) {
        const vec3 x = m.bounds.lo + extent * ((vec3(float(i), float(j), float(k)) + 0.5f) * (1.4f / kSide) - 0.2f);
        (void)winding_number_crossing<false, false>(m, x, kConeBeta, &crossing);
        visit_multipole(m.triangles, x, TaylorOptions{}.beta, taylor);
      }
  return float((double(crossing.cone_near) + double(crossing.cone_far)) / double(taylor.units > 0 ? taylor.units : 1));
}

// w (∇w, H_w when asked) by the options' method, `auto` resolved here (one comparison).
GWNRT_HD inline WindingSample evaluate_winding(const ModelView& m, const vec3& x, const WindingOptions& options,
                                               bool want_gradient = false, bool want_hessian = false) {
  switch (resolve_winding_method(m, options.method)) {
    case WindingMethod::kCrossing:
      return winding_number_crossing(m, x, want_gradient, want_hessian);
    case WindingMethod::kBrute: {
      const WindingSampleExact s = winding_number_exact(m.triangles, x, want_gradient, want_hessian);
      WindingSample out;
      out.w = float(s.w);
      out.gradient = vec3(s.gradient);
      out.hessian = {float(s.hessian.xx), float(s.hessian.xy), float(s.hessian.xz),
                     float(s.hessian.yy), float(s.hessian.yz), float(s.hessian.zz)};
      return out;
    }
    default:
      return winding_number(m.triangles, x, options.taylor, want_gradient, want_hessian);
  }
}

}  // namespace gwnrt
