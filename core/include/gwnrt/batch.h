// TBB batch drivers: evaluate_point over many points, in parallel, results in input order.
#pragma once

#include <atomic>
#include <span>

#include "gwnrt/model.h"
#include "gwnrt/point_query.h"

namespace gwnrt {

inline ModelView model_view(const GwnModel& model) { return {model.triangle_view(), model.boundary_view()}; }

// results.size() must equal points.size(). `progress`, when given, counts finished points
// (for a progress bar on another thread). Fails on a size mismatch, a bad order or a beta <= 0.
Status evaluate_points(const GwnModel& model, std::span<const vec3> points, const QueryRequest& request,
                       std::span<PointResult> results, std::atomic<size_t>* progress = nullptr);

Status validate_request(const QueryRequest& request);

}  // namespace gwnrt
