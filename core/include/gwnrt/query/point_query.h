// One point, every requested field: the single code path that the TBB batch driver and the
// CUDA kernel both call, so the two backends cannot drift apart. Host-and-device.
#pragma once

#include "gwnrt/field/distance.h"
#include "gwnrt/field/evaluate_winding.h"
#include "gwnrt/geometry/model_view.h"
#include "gwnrt/sdf/signed_distance.h"

namespace gwnrt {

enum QueryField : uint32_t {
  kFieldW = 1u << 0,
  kFieldGradient = 1u << 1,
  kFieldHessian = 1u << 2,
  kFieldUnsignedDistance = 1u << 3,
  kFieldBoundaryDistance = 1u << 4,
  kFieldSignedDistance = 1u << 5,  // sdf (with sdf1, sdf2, the sheet distance and the winning piece)
  kFieldPseudoDistance = 1u << 6,  // sdf1, sdf2 alone
  kFieldSheetDistance = 1u << 7,   // the distance to the sheet triangles alone
  kFieldProjection = 1u << 8,      // Newton projection onto the smooth pieces
  kFieldHarnackBound = 1u << 9,    // ρ(x) <= dist(x, S)
};

// The fields that read the model's sheets, which must have been classified for the request's level.
inline constexpr uint32_t kSheetFields = kFieldSignedDistance | kFieldSheetDistance;

struct QueryRequest {
  uint32_t fields = kFieldW;
  // How w, ∇w and H_w are evaluated, for every field that needs them (the pseudo-SDF, the sdf's
  // sign and smooth estimate, the Newton projection): field/evaluate_winding.h.
  WindingMethod method = WindingMethod::kAuto;
  TaylorOptions taylor;  // the tree's order and beta (method taylor; beta also for ρ's cone sum)
  float level = 0.5f;    // w*: S = ∂{w > w*}
  NewtonOptions newton;
};

// The model parts (ModelPart) evaluate_point reads for `request`: ∂M and its cone for every field
// but the distance to M and w by the tree or the brute force (auto chooses by the cone's size,
// the crossings read it, and so do ρ, the projection and the sdf), the sheets for kSheetFields.
inline uint32_t parts_read_by(const QueryRequest& request) {
  constexpr uint32_t kWindingFields = kFieldW | kFieldGradient | kFieldHessian | kFieldPseudoDistance;
  const bool winding_reads_cone = request.method != WindingMethod::kTaylor && request.method != WindingMethod::kBrute;
  const uint32_t without_cone = kFieldUnsignedDistance | (winding_reads_cone ? 0u : kWindingFields);
  uint32_t parts = kPartTriangles;
  if (request.fields & ~without_cone) parts |= kPartBoundary;
  if (request.fields & kSheetFields) parts |= kPartSheets;
  return parts;
}

struct PointResult {
  float w = 0;
  vec3 gradient{0.0f};
  sym3 hessian;
  float unsigned_distance = 0;
  uint32_t nearest_triangle = kEmptyLane;
  float bary_u = 0, bary_v = 0;  // of the closest point on nearest_triangle
  float boundary_distance = 0;   // +inf for a closed mesh
  uint32_t nearest_boundary_segment = kEmptyLane;
  SignedDistance sdf;  // distance, first_order, second_order, sheet distance
  SurfaceProjection projection;
  float harnack_bound = 0;
};

GWNRT_HD inline PointResult evaluate_point(const ModelView& model, const vec3& x, const QueryRequest& request) {
  PointResult r;
  const bool want_pseudo = request.fields & kFieldPseudoDistance;
  const bool want_gradient = want_pseudo || (request.fields & kFieldGradient);
  const bool want_hessian = want_pseudo || (request.fields & kFieldHessian);
  const bool want_sdf = request.fields & kFieldSignedDistance;
  const WindingOptions winding{resolve_point_method(model, request.method), request.taylor};
  // The brute-force sdf takes w, ∇w and H_w from one sum; otherwise sdf evaluates them itself,
  // only as far as it needs (mostly w alone), unless they are taken anyway.
  const bool full = want_hessian || (winding.method == WindingMethod::kBrute && want_sdf);
  const bool want_sample = full || (request.fields & (kFieldW | kFieldGradient));
  if (want_sample) {
    const WindingSample s = evaluate_winding(model, x, winding, want_gradient || full, full);
    r.w = s.w;
    r.gradient = s.gradient;
    r.hessian = s.hessian;
  }
  const WindingSample sample{r.w, r.gradient, r.hessian};
  if (want_sdf) {
    r.sdf = signed_distance(model, x, request.level, winding, full ? &sample : nullptr);  // also d₁, d₂
  } else {
    if (request.fields & kFieldSheetDistance) {
      const NearestPrimitive n = unsigned_distance(model.sheets, x);
      r.sdf.sheet_distance = n.distance;
      r.sdf.sheet_triangle = n.primitive;
    }
    if (want_pseudo) {
      r.sdf.first_order = pseudo_distance(r.w, r.gradient, request.level);
      r.sdf.second_order = curvature_corrected_distance(r.w, r.gradient, r.hessian, request.level);
    }
  }
  if (request.fields & kFieldProjection)
    r.projection = project_onto_surface(model, x, request.level, winding, request.newton);
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
  if (request.fields & kFieldHarnackBound) {
    const float mesh_distance = (request.fields & kFieldUnsignedDistance)
                                    ? r.unsigned_distance
                                    : unsigned_distance(model.triangles, x).distance;
    r.harnack_bound = harnack_lower_bound(model, x, request.level, request.taylor.beta, mesh_distance);
  }
  return r;
}

}  // namespace gwnrt
