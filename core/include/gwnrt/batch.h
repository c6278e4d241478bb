// TBB batch drivers: evaluate_point over many points and trace_surface over many rays, in
// parallel, results in input order.
#pragma once

#include <atomic>
#include <cmath>
#include <span>

#include "gwnrt/geometry/model.h"
#include "gwnrt/sdf/point_columns.h"
#include "gwnrt/sdf/point_query.h"
#include "gwnrt/trace/surface_trace.h"

namespace gwnrt {

inline ModelView model_view(const GwnModel& model) { return model.view(); }

// results.size() must equal points.size(). `progress`, when given, counts finished points
// (for a progress bar on another thread). Builds the model parts the request reads that are not
// yet (parts_read_by; GwnModel::prepare). Fails on a size mismatch, a point validate_points
// refuses, a bad order or a beta <= 0.
Status evaluate_points(const GwnModel& model, std::span<const vec3> points, const QueryRequest& request,
                       std::span<PointResult> results, std::atomic<size_t>* progress = nullptr);

// The same, each result written into the given columns (sdf/point_columns.h), which hold
// points.size() rows each: no PointResult array in between.
Status evaluate_points_to_columns(const GwnModel& model, std::span<const vec3> points, const QueryRequest& request,
                                  const PointColumns& columns, std::atomic<size_t>* progress = nullptr);

// The query points the drivers serve: finite, every coordinate within +-kMaxQueryCoordinate
// (beyond, the squared distances to M overflow float: the distances came out NaN from 1e19 and
// the sdf negative; within it, measured on the limits of kMaxMeshCoordinate and
// kMinMeshExtent, w, the distances and the sdf are right). Names the first point that is not.
inline constexpr float kMaxQueryCoordinate = 1e18f;
// Whether `p` is such a point (NaN and inf are not).
inline bool query_point_served(const vec3& p) {
  return std::fabs(p.x) <= kMaxQueryCoordinate && std::fabs(p.y) <= kMaxQueryCoordinate &&
         std::fabs(p.z) <= kMaxQueryCoordinate;
}
Status validate_points(std::span<const vec3> points);

// Order, beta, level and Newton options; with `view`, also that it holds the parts the request
// reads and that sdf and sheet-distance requests ask for the level its sheets were classified for.
Status validate_request(const QueryRequest& request, const ModelView* view = nullptr);

// That `view` holds ∂M and its cone, which the tracer reads (a view without them would be traced
// as a closed mesh).
Status validate_trace_view(const ModelView& view);

// hits.size() must equal rays.size(). Builds the model's boundary and cone if not yet. Invalid rays (non-finite, zero
// direction) are not an error of the batch: their hit has `invalid` set. Fails on a size mismatch or bad options.
Status trace_rays(const GwnModel& model, std::span<const Ray> rays, const TraceOptions& options, std::span<RayHit> hits,
                  std::atomic<size_t>* progress = nullptr);

// Level finite, epsilon and beta finite and > 0, caps > 0.
Status validate_trace_options(const TraceOptions& options);

}  // namespace gwnrt
