// The batch drivers on the CPU: evaluate_point over many points and trace_surface over many
// rays, in parallel with TBB, results in input order (the CUDA backend's twins: gwnrt/cuda.h).
#pragma once

#include <atomic>
#include <span>

#include "gwnrt/model/model.h"
#include "gwnrt/query/point_columns.h"
#include "gwnrt/query/point_query.h"
#include "gwnrt/query/validation.h"
#include "gwnrt/trace/surface_trace.h"

namespace gwnrt {

// results.size() must equal points.size(). `progress`, when given, counts finished points
// (for a progress bar on another thread). Builds the model parts the request reads that are not
// yet (parts_read_by; GwnModel::prepare). Fails on a size mismatch, a point validate_points
// refuses, a bad order or a beta <= 0.
Status evaluate_points(const GwnModel& model, std::span<const vec3> points, const QueryRequest& request,
                       std::span<PointResult> results, std::atomic<size_t>* progress = nullptr);

// The same, each result written into the given columns (query/point_columns.h), which hold
// points.size() rows each: no PointResult array in between.
Status evaluate_points_to_columns(const GwnModel& model, std::span<const vec3> points, const QueryRequest& request,
                                  const PointColumns& columns, std::atomic<size_t>* progress = nullptr);

// hits.size() must equal rays.size(). Builds the model's boundary and cone if not yet. Invalid rays (non-finite, zero
// direction) are not an error of the batch: their hit has `invalid` set. Fails on a size mismatch or bad options.
Status trace_rays(const GwnModel& model, std::span<const Ray> rays, const TraceOptions& options, std::span<RayHit> hits,
                  std::atomic<size_t>* progress = nullptr);

}  // namespace gwnrt
