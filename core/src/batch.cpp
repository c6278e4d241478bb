#include "gwnrt/batch.h"

#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace gwnrt {

Status validate_request(const QueryRequest& request) {
  if (request.taylor.order < 0 || request.taylor.order > 2)
    return {StatusCode::kInvalidArgument, "Taylor order must be 0, 1 or 2, got " + std::to_string(request.taylor.order)};
  if (!(request.taylor.beta > 0.0f) || !(request.taylor.beta < kInfinity))
    return {StatusCode::kInvalidArgument, "accuracy scale beta must be a finite number > 0"};
  return Status::Ok();
}

Status evaluate_points(const GwnModel& model, std::span<const vec3> points, const QueryRequest& request,
                       std::span<PointResult> results, std::atomic<size_t>* progress) {
  if (points.size() != results.size())
    return {StatusCode::kInvalidArgument, "evaluate_points: " + std::to_string(points.size()) + " points but " +
                                              std::to_string(results.size()) + " result slots"};
  if (Status s = validate_request(request); !s.ok()) return s;
  const ModelView view = model_view(model);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 256), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t i = range.begin(); i != range.end(); ++i) results[i] = evaluate_point(view, points[i], request);
    if (progress) progress->fetch_add(range.size(), std::memory_order_relaxed);
  });
  return Status::Ok();
}

}  // namespace gwnrt
