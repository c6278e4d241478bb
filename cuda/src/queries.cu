// Batch queries on the GPU: one thread per point, each running the core's evaluate_point.
#include "map_on_device.cuh"
#include "gwnrt/cuda.h"
#include "gwnrt/sdf/point_query.h"

namespace gwnrt::cuda {
namespace {

struct EvaluatePoint {
  ModelView model;
  QueryRequest request;
  __device__ PointResult operator()(const vec3& x) const { return evaluate_point(model, x, request); }
};

}  // namespace

Status evaluate_points(const DeviceModel& model, std::span<const vec3> points, const QueryRequest& request,
                       std::span<PointResult> results) {
  if (points.size() != results.size())
    return {StatusCode::kInvalidArgument, "evaluate_points: points and results differ in size"};
  const ModelView view = model.view();
  if (Status s = validate_request(request, &view); !s.ok()) return s;
  if (points.empty()) return Status::Ok();
  if (!model.view().triangles.bvh.nodes) return {StatusCode::kInvalidArgument, "evaluate_points: model not uploaded"};
  return map_on_device(points, results, 128, EvaluatePoint{model.view(), request});
}

}  // namespace gwnrt::cuda
