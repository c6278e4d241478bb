// Batch queries on the GPU: one thread per point, each running the core's evaluate_point.
#include <vector>

#include "gwnrt/query/point_columns.h"
#include "gwnrt/query/point_query.h"
#include "map_on_device.cuh"

namespace gwnrt::cuda {
namespace {

// Both kernels below call this one compiled function, so that the columns hold bit for bit what
// a PointResult batch gives: inlined into each, nvcc could contract their multiply-adds
// differently after inlining. The call is small against a query's traversal.
__device__ __noinline__ PointResult evaluate_on_device(const ModelView& model, const vec3& x,
                                                       const QueryRequest& request) {
  return evaluate_point(model, x, request);
}

struct EvaluatePoint {
  ModelView model;
  QueryRequest request;
  __device__ PointResult operator()(const vec3& x) const { return evaluate_on_device(model, x, request); }
};

// The columns variant's per-point work: the PointResult stays in registers, only the given
// columns are written (store_point_result, the CPU's own).
struct EvaluatePointToColumns {
  ModelView model;
  QueryRequest request;
  PointColumns columns;  // device pointers
  __device__ void operator()(size_t i, const vec3& x) const {
    store_point_result(columns, i, evaluate_on_device(model, x, request));
  }
};

// Where each given column lies in the result scratch: one after another, each at a multiple of
// 256 bytes (cudaMalloc's alignment, so any element type is aligned).
struct ColumnLayout {
  struct Given {
    void* host;
    size_t offset, bytes;
  };
  std::vector<Given> given;
  std::vector<size_t> offsets;  // of every column, in for_each_point_column's order
  size_t bytes = 0;             // the scratch they need

  ColumnLayout(PointColumns columns, size_t rows) {
    for_each_point_column(columns, [&](auto* column, size_t values) {
      offsets.push_back(bytes);
      if (!column) return;
      const size_t size = rows * values * sizeof(*column);
      given.push_back({column, bytes, size});
      bytes += (size + 255) / 256 * 256;
    });
  }
  // `host`'s columns re-pointed into the scratch at `base` (null ones stay null).
  PointColumns on_device(PointColumns host, void* base) const {
    size_t k = 0;
    for_each_point_column(host, [&](auto*& column, size_t) {
      using T = std::remove_reference_t<decltype(*column)>;
      if (column) column = reinterpret_cast<T*>(static_cast<unsigned char*>(base) + offsets[k]);
      ++k;
    });
    return host;
  }
  // The copies of the given columns down from the scratch at `base`, queued on `stream`.
  Status copy_down(const void* base, cudaStream_t stream) const {
    for (const Given& g : given)
      if (Status s = copy_to_host(g.host, static_cast<const unsigned char*>(base) + g.offset, g.bytes, stream); !s.ok())
        return s;
    return Status::Ok();
  }
};

Status validate_query(std::span<const vec3> points, const QueryRequest& request, const ModelView& view) {
  if (Status s = validate_points(points); !s.ok()) return s;
  return validate_request(request, &view);
}

}  // namespace

Status evaluate_points(const DeviceModel& model, std::span<const vec3> points, const QueryRequest& request,
                       std::span<PointResult> results, Stream stream, BatchTimings* timings) {
  const ModelView view = model.view();
  return map_batch_on_device(
      "evaluate_points", model, points, results, 128, [&] { return validate_query(points, request, view); },
      EvaluatePoint{view, request}, stream, timings);
}

Status evaluate_points_to_columns(const DeviceModel& model, std::span<const vec3> points, const QueryRequest& request,
                                  const PointColumns& columns, Stream stream, BatchTimings* timings) {
  const ModelView view = model.view();
  return batch_on_device(
      "evaluate_points_to_columns", model, points.size(), [&] { return validate_query(points, request, view); },
      [&](DeviceAccess::Buffers& buffers) {
        const ColumnLayout layout(columns, points.size());
        return run_on_device(
            buffers, points, layout.bytes, 128,
            [&](void* scratch) {
              return EvaluatePointToColumns{view, request, layout.on_device(columns, scratch)};
            },
            [&](const void* scratch) { return layout.copy_down(scratch, stream); }, stream, timings);
      });
}

}  // namespace gwnrt::cuda
