// The model on a GPU and the batches that run there, behind one interface so that the engine
// never asks whether the CUDA backend was built: cuda_device_copy.cpp implements it with the
// backend, no_device_copy.cpp (a build without it) says why there is no GPU.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "gwnrt/engine.h"

namespace gwnrt::detail {

class DeviceCopy {
 public:
  virtual ~DeviceCopy() = default;
  virtual const cuda::DeviceModel& model() const = 0;
  virtual Status evaluate_points(std::span<const vec3> points, const QueryRequest& request,
                                 std::span<PointResult> results, DeviceTimings* timings) const = 0;
  virtual Status evaluate_points_to_columns(std::span<const vec3> points, const QueryRequest& request,
                                            const PointColumns& columns, DeviceTimings* timings) const = 0;
  virtual Status trace_rays(std::span<const Ray> rays, const TraceOptions& options, std::span<RayHit> hits,
                            DeviceTimings* timings) const = 0;
  // `model` is the host model the copy was made from.
  virtual Status extract_surface(const GwnModel& model, const MeshingOptions& options, SurfaceMesh& out,
                                 MeshingStats* stats) const = 0;
};

bool device_backend_built();
bool device_usable(std::string* why);
uint64_t device_free_memory();
// The model's copy on the GPU, its parts built first. Fails without a usable GPU (device_usable's
// reason) before building any.
Status upload_device_copy(const GwnModel& model, std::unique_ptr<DeviceCopy>& out);

}  // namespace gwnrt::detail
