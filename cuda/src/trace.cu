// Ray tracing on the GPU: one thread per ray, each running the core's trace_surface.
#include "device_buffer.h"
#include "gwnrt/batch.h"
#include "gwnrt/cuda.h"
#include "gwnrt/surface_trace.h"

namespace gwnrt::cuda {
namespace {

__global__ void trace_rays_kernel(ModelView model, const Ray* rays, size_t count, TraceOptions options, RayHit* hits) {
  const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
  if (i < count) hits[i] = trace_surface(model, rays[i], options);
}

}  // namespace

Status trace_rays(const DeviceModel& model, std::span<const Ray> rays, const TraceOptions& options,
                  std::span<RayHit> hits) {
  if (rays.size() != hits.size()) return {StatusCode::kInvalidArgument, "trace_rays: rays and hits differ in size"};
  if (Status s = validate_trace_options(options); !s.ok()) return s;
  if (rays.empty()) return Status::Ok();
  if (!model.view().triangles.bvh.nodes) return {StatusCode::kInvalidArgument, "trace_rays: model not uploaded"};
  DeviceBuffer<Ray> d_rays;
  DeviceBuffer<RayHit> d_hits;
  if (Status s = d_rays.upload(rays.data(), rays.size()); !s.ok()) return s;
  if (Status s = d_hits.allocate(rays.size()); !s.ok()) return s;
  const int block = 64;
  const unsigned grid = unsigned((rays.size() + block - 1) / block);
  trace_rays_kernel<<<grid, block>>>(model.view(), d_rays.get(), rays.size(), options, d_hits.get());
  if (Status s = cuda_status(cudaGetLastError(), "kernel launch"); !s.ok()) return s;
  if (Status s = cuda_status(cudaDeviceSynchronize(), "kernel execution"); !s.ok()) return s;
  return d_hits.download(hits.data(), hits.size());
}

}  // namespace gwnrt::cuda
