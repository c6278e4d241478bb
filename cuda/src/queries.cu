// Batch queries on the GPU: one thread per point, each running the core's evaluate_point.
#include "gwnrt/sdf/point_query.h"
#include "map_on_device.cuh"

namespace gwnrt::cuda {
namespace {

struct EvaluatePoint {
  ModelView model;
  QueryRequest request;
  __device__ PointResult operator()(const vec3& x) const { return evaluate_point(model, x, request); }
};

}  // namespace

Status evaluate_points(const DeviceModel& model, std::span<const vec3> points, const QueryRequest& request,
                       std::span<PointResult> results, Stream stream, BatchTimings* timings) {
  const ModelView view = model.view();
  return map_batch_on_device(
      "evaluate_points", model, points, results, 128,
      [&] {
        if (Status s = validate_points(points); !s.ok()) return s;
        return validate_request(request, &view);
      },
      EvaluatePoint{view, request}, stream, timings);
}

}  // namespace gwnrt::cuda
