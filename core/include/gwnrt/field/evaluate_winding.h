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
  kAuto = 0,      // crossing where the cone is small enough that it wins, else taylor
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

// `auto` takes the crossing method when ∂M has at most this many segments per triangle of M. A crossing query costs one
// ray through M's tree plus the cone's tree at kConeBeta (nearer cone triangles exactly, in double); a Taylor query one
// traversal of M's tree at beta. The threshold is about where the two cost the same (docs/performance.md), and there
// the exact one is taken. A soup whose every edge is on ∂M has three per triangle.
inline constexpr float kCrossingConeRatio = 0.1f;

GWNRT_HD inline WindingMethod resolve_winding_method(const ModelView& m, WindingMethod requested) {
  if (requested != WindingMethod::kAuto) return requested;
  return float(m.boundary.segment_count) <= kCrossingConeRatio * float(m.triangles.triangle_count)
             ? WindingMethod::kCrossing
             : WindingMethod::kTaylor;
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
