// The engine (gwnrt/engine.h): the device chosen, the GPU's copy made once, each batch sent to
// the CPU's driver or the GPU's.
#include "gwnrt/engine.h"

#include <mutex>
#include <utility>

#include "device_copy.h"
#include "gwnrt/base/memory.h"

namespace gwnrt {

const char* device_name(Device device) {
  switch (device) {
    case Device::kCpu:
      return "cpu";
    case Device::kCuda:
      return "cuda";
    default:
      return "auto";
  }
}

bool device_named(std::string_view name, Device& device) {
  for (Device d : {Device::kCpu, Device::kCuda, Device::kAuto})
    if (name == device_name(d)) {
      device = d;
      return true;
    }
  return false;
}

bool cuda_backend_built() { return detail::device_backend_built(); }

bool cuda_usable(std::string* why) { return detail::device_usable(why); }

Status choose_device(Device asked, DeviceChoice& out) {
  out = DeviceChoice{};
  if (asked == Device::kCpu) return Status::Ok();
  std::string why;
  const bool usable = cuda_usable(&why);
  if (asked == Device::kCuda && !usable) return {StatusCode::kUnavailable, why};
  if (usable)
    out.device = Device::kCuda;
  else
    out.reason = why;
  return Status::Ok();
}

struct Engine::Gpu {
  std::mutex mutex;
  std::unique_ptr<detail::DeviceCopy> copy;
};

Engine::Engine() : gpu_(std::make_unique<Gpu>()) {}
Engine::Engine(GwnModel model) : model_(std::move(model)), gpu_(std::make_unique<Gpu>()) {}
Engine::~Engine() = default;
Engine::Engine(Engine&&) noexcept = default;
Engine& Engine::operator=(Engine&&) noexcept = default;

Status Engine::set_sheet_level(float level) {
  if (Status s = model_.set_sheet_level(level); !s.ok()) return s;
  std::lock_guard<std::mutex> lock(gpu_->mutex);
  gpu_->copy.reset();
  return Status::Ok();
}

Status Engine::gpu_copy(const detail::DeviceCopy*& out) const {
  out = nullptr;
  return guard_status("Engine::upload", [&] {
    std::lock_guard<std::mutex> lock(gpu_->mutex);
    if (!gpu_->copy) {
      if (Status s = detail::upload_device_copy(model_, gpu_->copy); !s.ok()) return s;
    }
    out = gpu_->copy.get();
    return Status::Ok();
  });
}

Status Engine::upload() const {
  const detail::DeviceCopy* copy = nullptr;
  return gpu_copy(copy);
}

Status Engine::device_model(const cuda::DeviceModel*& out) const {
  out = nullptr;
  const detail::DeviceCopy* copy = nullptr;
  if (Status s = gpu_copy(copy); !s.ok()) return s;
  out = &copy->model();
  return Status::Ok();
}

uint64_t available_memory_on(Device device) {
  DeviceChoice chosen;
  if (!choose_device(device, chosen).ok()) return 0;
  return chosen.device == Device::kCuda ? detail::device_free_memory() : available_memory_bytes();
}

Status Engine::on_device(Device device, const detail::DeviceCopy*& copy) const {
  copy = nullptr;
  if (device == Device::kCpu) return Status::Ok();
  if (device == Device::kAuto) {
    DeviceChoice chosen;
    if (Status s = choose_device(device, chosen); !s.ok() || chosen.device == Device::kCpu) return s;
  }
  // kCuda: the upload refuses a missing GPU with choose_device's reason; once made, the copy is
  // used without asking the driver again.
  return gpu_copy(copy);
}

Status Engine::evaluate_points(Device device, std::span<const vec3> points, const QueryRequest& request,
                               std::span<PointResult> results, std::atomic<size_t>* progress,
                               DeviceTimings* timings) const {
  const detail::DeviceCopy* copy = nullptr;
  if (Status s = on_device(device, copy); !s.ok()) return s;
  if (copy) return copy->evaluate_points(points, request, results, timings);
  return gwnrt::evaluate_points(model_, points, request, results, progress);
}

Status Engine::evaluate_points_to_columns(Device device, std::span<const vec3> points, const QueryRequest& request,
                                          const PointColumns& columns, std::atomic<size_t>* progress,
                                          DeviceTimings* timings) const {
  const detail::DeviceCopy* copy = nullptr;
  if (Status s = on_device(device, copy); !s.ok()) return s;
  if (copy) return copy->evaluate_points_to_columns(points, request, columns, timings);
  return gwnrt::evaluate_points_to_columns(model_, points, request, columns, progress);
}

Status Engine::trace_rays(Device device, std::span<const Ray> rays, const TraceOptions& options, std::span<RayHit> hits,
                          std::atomic<size_t>* progress, DeviceTimings* timings) const {
  const detail::DeviceCopy* copy = nullptr;
  if (Status s = on_device(device, copy); !s.ok()) return s;
  if (copy) return copy->trace_rays(rays, options, hits, timings);
  return gwnrt::trace_rays(model_, rays, options, hits, progress);
}

Status Engine::extract_surface(Device device, const MeshingOptions& options, SurfaceMesh& out,
                               MeshingStats* stats) const {
  const detail::DeviceCopy* copy = nullptr;
  if (Status s = on_device(device, copy); !s.ok()) return s;
  if (copy) return copy->extract_surface(model_, options, out, stats);
  return gwnrt::extract_surface(model_, options, out, stats);
}

}  // namespace gwnrt
