// The device copy on the CUDA backend (device_copy.h): a cuda::DeviceModel and gwnrt::cuda's
// batches over it.
#include <utility>

#include "device_copy.h"
#include "gwnrt/cuda.h"

namespace gwnrt::detail {
namespace {

void copy_timings(const cuda::BatchTimings& from, DeviceTimings* to) {
  if (to) *to = {from.upload, from.kernel, from.download};
}

class CudaDeviceCopy final : public DeviceCopy {
 public:
  cuda::DeviceModel device;

  const cuda::DeviceModel& model() const override { return device; }
  Status evaluate_points(std::span<const vec3> points, const QueryRequest& request, std::span<PointResult> results,
                         DeviceTimings* timings) const override {
    cuda::BatchTimings t;
    const Status s = cuda::evaluate_points(device, points, request, results, nullptr, &t);
    copy_timings(t, timings);
    return s;
  }
  Status evaluate_points_to_columns(std::span<const vec3> points, const QueryRequest& request,
                                    const PointColumns& columns, DeviceTimings* timings) const override {
    cuda::BatchTimings t;
    const Status s = cuda::evaluate_points_to_columns(device, points, request, columns, nullptr, &t);
    copy_timings(t, timings);
    return s;
  }
  Status trace_rays(std::span<const Ray> rays, const TraceOptions& options, std::span<RayHit> hits,
                    DeviceTimings* timings) const override {
    cuda::BatchTimings t;
    const Status s = cuda::trace_rays(device, rays, options, hits, nullptr, &t);
    copy_timings(t, timings);
    return s;
  }
  Status extract_surface(const GwnModel& model, const MeshingOptions& options, SurfaceMesh& out,
                         MeshingStats* stats) const override {
    return cuda::extract_surface(device, model, options, out, stats);
  }
};

}  // namespace

bool device_backend_built() { return true; }

bool device_usable(std::string* why) { return cuda::device_available(why); }

uint64_t device_free_memory() { return cuda::free_device_memory(); }

Status upload_device_copy(const GwnModel& model, std::unique_ptr<DeviceCopy>& out) {
  out.reset();
  auto copy = std::make_unique<CudaDeviceCopy>();
  if (Status s = cuda::DeviceModel::upload(model, copy->device); !s.ok()) return s;
  out = std::move(copy);
  return Status::Ok();
}

}  // namespace gwnrt::detail
