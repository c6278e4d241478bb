// Where the work runs, decided in one place: an Engine holds a GwnModel and runs its batches
// (points, rays, meshing) on the CPU (TBB) or on the GPU (the CUDA backend), uploading the model
// to the GPU once, on first need. The programs, the Python module and gwnrt-consistency all go
// through it; none of them asks whether the CUDA backend was built. Plain C++ header.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "gwnrt/meshing/extract_surface.h"
#include "gwnrt/model/model.h"
#include "gwnrt/query/batch.h"

namespace gwnrt {

namespace cuda {
class DeviceModel;
}
namespace detail {
class DeviceCopy;  // engine/src/device_copy.h
}

enum class Device : uint32_t {
  kCpu = 0,
  kCuda = 1,  // needs the CUDA backend built in and a usable GPU
  kAuto = 2,  // the GPU when kCuda would work, else the CPU
};

// "cpu", "cuda", "auto".
const char* device_name(Device device);
// The Device that device_name calls `name`; false for any other name.
bool device_named(std::string_view name, Device& device);

// Whether this build holds the CUDA backend.
bool cuda_backend_built();
// Whether batches can run on the GPU now: the backend built in and a usable device. `why`, when
// given, says what is missing otherwise.
bool cuda_usable(std::string* why = nullptr);

struct DeviceChoice {
  Device device = Device::kCpu;  // where the work runs: kCpu or kCuda
  std::string reason;            // why auto took the CPU (what the GPU lacks); empty otherwise
};
// `asked` resolved: the CPU; the GPU when usable, else kUnavailable saying why; auto: the GPU
// when usable, else the CPU with the reason.
Status choose_device(Device asked, DeviceChoice& out);

// The memory a batch on `device` may use now: what the host has available (kCpu) or the GPU's
// free memory (kCuda; 0 without one). kAuto is resolved as choose_device resolves it.
uint64_t available_memory_on(Device device);

// Where a GPU batch's time went, in seconds: inputs copied up, the kernel, results copied down.
struct DeviceTimings {
  double upload = 0, kernel = 0, download = 0;
};

class Engine {
 public:
  Engine();
  explicit Engine(GwnModel model);
  ~Engine();
  Engine(Engine&&) noexcept;
  Engine& operator=(Engine&&) noexcept;

  const GwnModel& model() const { return model_; }

  // GwnModel::set_sheet_level; the GPU's copy, if any, is made again for its next batch. As the
  // model's, not thread-safe with batches running on this engine.
  Status set_sheet_level(float level);

  // The model on the GPU, with every part built first (cuda::DeviceModel::upload builds them):
  // uploaded once (concurrent callers wait for one upload), kept until destruction or
  // set_sheet_level. Fails without a usable GPU, saying why, before any part is built.
  Status upload() const;
  // The GPU's copy for a caller's own kernels (gwnrt-render's first hit), uploaded as upload().
  Status device_model(const cuda::DeviceModel*& out) const;

  // The batches, on `device` (kAuto resolved per call by choose_device). On the CPU they are
  // gwnrt::evaluate_points, evaluate_points_to_columns, trace_rays and extract_surface (query/,
  // meshing/), which `progress` follows; on the GPU their gwnrt::cuda twins, which `timings`
  // follows (points and rays; left as they are on the CPU).
  Status evaluate_points(Device device, std::span<const vec3> points, const QueryRequest& request,
                         std::span<PointResult> results, std::atomic<size_t>* progress = nullptr,
                         DeviceTimings* timings = nullptr) const;
  Status evaluate_points_to_columns(Device device, std::span<const vec3> points, const QueryRequest& request,
                                    const PointColumns& columns, std::atomic<size_t>* progress = nullptr,
                                    DeviceTimings* timings = nullptr) const;
  Status trace_rays(Device device, std::span<const Ray> rays, const TraceOptions& options, std::span<RayHit> hits,
                    std::atomic<size_t>* progress = nullptr, DeviceTimings* timings = nullptr) const;
  Status extract_surface(Device device, const MeshingOptions& options, SurfaceMesh& out,
                         MeshingStats* stats = nullptr) const;

 private:
  struct Gpu;  // the mutex and the device copy, made on first need
  Status gpu_copy(const detail::DeviceCopy*& out) const;
  // `device` resolved (kAuto by choose_device); for the GPU its copy (null for the CPU).
  Status on_device(Device device, const detail::DeviceCopy*& copy) const;

  GwnModel model_;
  std::unique_ptr<Gpu> gpu_;
};

}  // namespace gwnrt
