// One point, every requested field: the single code path that the TBB batch driver and the
// CUDA kernel both call, so the two backends cannot drift apart. Host-and-device.
#pragma once

#include "gwnrt/distance.h"
#include "gwnrt/model_view.h"
#include "gwnrt/winding_number.h"

namespace gwnrt {

enum QueryField : uint32_t {
  kFieldW = 1u << 0,
  kFieldGradient = 1u << 1,
  kFieldHessian = 1u << 2,
  kFieldUnsignedDistance = 1u << 3,
  kFieldBoundaryDistance = 1u << 4,
};

struct QueryRequest {
  uint32_t fields = kFieldW;
  TaylorOptions taylor;
  bool exact = false;  // brute-force double sum instead of the tree (w, ∇w, H_w only)
};

struct PointResult {
  float w = 0;
  vec3 gradient{0.0f};
  sym3 hessian;
  float unsigned_distance = 0;
  uint32_t nearest_triangle = kEmptyLane;
  float bary_u = 0, bary_v = 0;          // of the closest point on nearest_triangle
  float boundary_distance = 0;           // +inf for a closed mesh
  uint32_t nearest_boundary_segment = kEmptyLane;
};

GWNRT_HD inline PointResult evaluate_point(const ModelView& model, const vec3& x, const QueryRequest& request) {
  PointResult r;
  const bool want_gradient = request.fields & kFieldGradient;
  const bool want_hessian = request.fields & kFieldHessian;
  if (request.fields & (kFieldW | kFieldGradient | kFieldHessian)) {
    if (request.exact) {
      const WindingSampleExact s = winding_number_exact(model.triangles, x, want_gradient, want_hessian);
      r.w = float(s.w);
      r.gradient = vec3(s.gradient);
      r.hessian = {float(s.hessian.xx), float(s.hessian.xy), float(s.hessian.xz),
                   float(s.hessian.yy), float(s.hessian.yz), float(s.hessian.zz)};
    } else {
      const WindingSample s = winding_number(model.triangles, x, request.taylor, want_gradient, want_hessian);
      r.w = s.w;
      r.gradient = s.gradient;
      r.hessian = s.hessian;
    }
  }
  if (request.fields & kFieldUnsignedDistance) {
    const NearestPrimitive n = unsigned_distance(model.triangles, x);
    r.unsigned_distance = n.distance;
    r.nearest_triangle = n.primitive;
    r.bary_u = n.u;
    r.bary_v = n.v;
  }
  if (request.fields & kFieldBoundaryDistance) {
    const NearestPrimitive n = boundary_distance(model.boundary, x);
    r.boundary_distance = n.distance;
    r.nearest_boundary_segment = n.primitive;
  }
  return r;
}

}  // namespace gwnrt
