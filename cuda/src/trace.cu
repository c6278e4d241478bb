// Ray tracing on the GPU: one thread per ray, each running the core's trace_surface.
#include "gwnrt/query/batch.h"
#include "gwnrt/trace/surface_trace.h"
#include "map_on_device.cuh"

namespace gwnrt::cuda {
namespace {

struct TraceRay {
  ModelView model;
  TraceOptions options;
  __device__ RayHit operator()(const Ray& ray) const { return trace_surface(model, ray, options); }
};

}  // namespace

Status trace_rays(const DeviceModel& model, std::span<const Ray> rays, const TraceOptions& options,
                  std::span<RayHit> hits, Stream stream, BatchTimings* timings) {
  // Smaller blocks than for points: rays diverge in cost and hold a larger stack.
  const ModelView view = model.view();
  return map_batch_on_device(
      "trace_rays", model, rays, hits, 64,
      [&] {
        if (Status s = validate_trace_options(options); !s.ok()) return s;
        return validate_trace_view(view);
      },
      TraceRay{view, options}, stream, timings);
}

}  // namespace gwnrt::cuda
