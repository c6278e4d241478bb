// extract_surface on the CPU: the meshing driver over the TBB backend (gwnrt/meshing/extract_surface.h).
#include "gwnrt/meshing/extract_surface.h"

#include "gwnrt/meshing/mesh_pipeline.h"
#include "meshing/host_backend.h"

namespace gwnrt {
namespace {

Status extract_unguarded(const GwnModel& model, const MeshingOptions& options, SurfaceMesh& out, MeshingStats& stats) {
  MeshingPlan plan;
  if (Status s = plan_meshing(model, options, plan, out, stats); !s.ok() || plan.empty) return s;
  HostBackend backend;
  const ScoutQuery scout{plan.view, options.level, options.winding.taylor.beta, plan.use_sheets, plan.settle_by_bounds};
  if (Status s = run_dual_contouring(backend, plan.view, options, plan.grid, scout, out, stats); !s.ok()) {
    out = SurfaceMesh{};
    return s;
  }
  return finish_meshing(model, options, out);
}

}  // namespace

Status extract_surface(const GwnModel& model, const MeshingOptions& options, SurfaceMesh& out, MeshingStats* stats) {
  MeshingStats local;
  MeshingStats& s = stats ? *stats : local;
  s = MeshingStats{};
  return guard_status("extract_surface", [&] { return extract_unguarded(model, options, out, s); });
}

}  // namespace gwnrt
