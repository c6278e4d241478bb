// Meshing S on the GPU: the CPU mesher's driver (meshing/mesh_pipeline.h) over the CUDA backend,
// around the same host-side plan (grid, options, parts) and finish (attributes, soup).
#include "gwnrt/cuda.h"
#include "gwnrt/meshing/mesh_pipeline.h"
#include "mesh_backend.cuh"

namespace gwnrt::cuda {

Status extract_surface(const DeviceModel& device, const GwnModel& model, const MeshingOptions& options,
                       SurfaceMesh& out, MeshingStats* stats, Stream stream) {
  MeshingStats local;
  MeshingStats& st = stats ? *stats : local;
  st = MeshingStats{};
  return guard_device("cuda::extract_surface", [&]() -> Status {
    MeshingPlan plan;
    if (Status s = plan_meshing(model, options, plan, out, st); !s.ok() || plan.empty) return s;
    const ModelView view = device.view();
    if (!view.triangles.bvh.nodes) return {StatusCode::kInvalidArgument, "cuda::extract_surface: model not uploaded"};
    // The same sheets as the host's plan (or none on either: a model built without them meshes
    // with the distance to M), NaN levels compared as equal.
    const bool same_sheets = (view.parts & kPartSheets) == (plan.view.parts & kPartSheets) &&
                             (view.sheet_level == plan.view.sheet_level ||
                              (view.sheet_level != view.sheet_level && plan.view.sheet_level != plan.view.sheet_level));
    if (view.triangles.triangle_count != plan.view.triangles.triangle_count || !same_sheets)
      return {StatusCode::kInvalidArgument,
              "cuda::extract_surface: the device model is not an upload of this model with its sheets "
              "(DeviceModel::upload after the last set_sheet_level)"};
    CudaBackend backend;
    backend.stream = stream;
    const ScoutQuery scout{view, options.level, options.winding.taylor.beta, plan.use_sheets, plan.settle_by_bounds};
    if (Status s = run_dual_contouring(backend, view, options, plan.grid, scout, out, st); !s.ok()) {
      out = SurfaceMesh{};
      return s;
    }
    return finish_meshing(model, options, out);
  });
}

}  // namespace gwnrt::cuda
