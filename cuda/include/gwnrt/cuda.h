// The CUDA backend's host API: upload a GwnModel's flat arrays once, then evaluate batches of
// points on the GPU with the very same evaluate_point the CPU driver runs. Plain C++ header
// (no CUDA headers), so host programs include it freely.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "gwnrt/meshing/extract_surface.h"
#include "gwnrt/model/model.h"
#include "gwnrt/query/batch.h"
#include "gwnrt/query/point_columns.h"

struct CUstream_st;  // cudaStream_t is a CUstream_st*: streams pass without CUDA's headers

namespace gwnrt::cuda {

// A CUDA stream for the calls below (nullptr: the default stream).
using Stream = CUstream_st*;

// Where a batch's time went on the device, from CUDA events (seconds): its inputs copied up, the
// kernel, its results copied down (a PointResult is 116 bytes: for w alone the copy down can
// outlast the kernel; evaluate_points_to_columns copies only the columns asked for).
struct BatchTimings {
  double upload = 0, kernel = 0, download = 0;
};

// True when a CUDA device can be used; otherwise `why` says what is missing.
bool device_available(std::string* why = nullptr);

// The device memory free now, in bytes (0 without a usable device): a budget for the mesher.
uint64_t free_device_memory();

// The model's arrays in device memory, resident until destruction, with the scratch buffers the
// batches copy their inputs and results through: grown when a batch needs more, kept for the
// next (one batch at a time uses them: concurrent calls on one DeviceModel wait for each other).
// Move-only.
class DeviceModel {
 public:
  DeviceModel();
  ~DeviceModel();
  DeviceModel(DeviceModel&&) noexcept;
  DeviceModel& operator=(DeviceModel&&) noexcept;

  static Status upload(const GwnModel& model, DeviceModel& out);
  ModelView view() const;  // device pointers: pass to kernels only

 private:
  friend struct DeviceAccess;  // cuda/src/device_model.cuh: the batches' way to the buffers
  struct Buffers;
  std::unique_ptr<Buffers> buffers_;
};

// GPU counterpart of gwnrt::trace_rays (the same trace_surface per ray); hits in input order.
Status trace_rays(const DeviceModel& model, std::span<const Ray> rays, const TraceOptions& options,
                  std::span<RayHit> hits, Stream stream = nullptr, BatchTimings* timings = nullptr);

// GPU counterpart of gwnrt::evaluate_points; results in input order.
Status evaluate_points(const DeviceModel& model, std::span<const vec3> points, const QueryRequest& request,
                       std::span<PointResult> results, Stream stream = nullptr, BatchTimings* timings = nullptr);

// GPU counterpart of gwnrt::evaluate_points_to_columns: each point's result written on the device
// into the given columns only, which alone are copied down (w alone: 4 bytes a point, not a
// PointResult's 116). The columns are host memory of points.size() rows each.
Status evaluate_points_to_columns(const DeviceModel& model, std::span<const vec3> points, const QueryRequest& request,
                                  const PointColumns& columns, Stream stream = nullptr,
                                  BatchTimings* timings = nullptr);

// GPU counterpart of gwnrt::extract_surface: the same driver and passes on the CUDA backend
// (scans and compaction with CUB). `model` is the host model `device` was uploaded from (the
// grid, the attributes and the soup are made on the host from it).
Status extract_surface(const DeviceModel& device, const GwnModel& model, const MeshingOptions& options,
                       SurfaceMesh& out, MeshingStats* stats = nullptr, Stream stream = nullptr);

}  // namespace gwnrt::cuda
