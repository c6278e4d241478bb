// Batch queries on the GPU: one thread per point, each running the core's evaluate_point.
#include "device_buffer.h"
#include "gwnrt/cuda.h"
#include "gwnrt/point_query.h"

namespace gwnrt::cuda {
namespace {

__global__ void evaluate_points_kernel(ModelView model, const vec3* points, size_t count, QueryRequest request,
                                       PointResult* results) {
  const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
  if (i < count) results[i] = evaluate_point(model, points[i], request);
}

}  // namespace

Status evaluate_points(const DeviceModel& model, std::span<const vec3> points, const QueryRequest& request,
                       std::span<PointResult> results) {
  if (points.size() != results.size())
    return {StatusCode::kInvalidArgument, "evaluate_points: points and results differ in size"};
  if (Status s = validate_request(request); !s.ok()) return s;
  if (points.empty()) return Status::Ok();
  if (!model.view().triangles.bvh.nodes) return {StatusCode::kInvalidArgument, "evaluate_points: model not uploaded"};
  DeviceBuffer<vec3> d_points;
  DeviceBuffer<PointResult> d_results;
  if (Status s = d_points.upload(points.data(), points.size()); !s.ok()) return s;
  if (Status s = d_results.allocate(points.size()); !s.ok()) return s;
  const int block = 128;
  const unsigned grid = unsigned((points.size() + block - 1) / block);
  evaluate_points_kernel<<<grid, block>>>(model.view(), d_points.get(), points.size(), request, d_results.get());
  if (Status s = cuda_status(cudaGetLastError(), "kernel launch"); !s.ok()) return s;
  if (Status s = cuda_status(cudaDeviceSynchronize(), "kernel execution"); !s.ok()) return s;
  return d_results.download(results.data(), results.size());
}

}  // namespace gwnrt::cuda
