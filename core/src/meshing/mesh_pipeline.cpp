// What both backends' meshing runs around the driver: the options checked, the grid planned, the
// attributes transferred and the soup split (gwnrt/meshing/mesh_pipeline.h).
#include "gwnrt/meshing/mesh_pipeline.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "base/message.h"
#include "gwnrt/base/option_limits.h"
#include "gwnrt/meshing/attribute_transfer.h"
#include "meshing/host_backend.h"

namespace gwnrt {
namespace {

// Cells per axis at most: grid coordinates stay far inside int32, and a corner's float position
// still resolves a cell (2^21 cells of a box span 21 of float's 24 bits).
constexpr int32_t kMaxGridCells = 1 << 21;

Status validate_options(const MeshingOptions& o) {
  if (o.cell_size != 0.0f && !(o.cell_size > 0.0f && std::isfinite(o.cell_size)))
    return {StatusCode::kInvalidArgument, "meshing: the cell size must be a finite number > 0"};
  if (o.cell_size == 0.0f && o.resolution == 0)
    return {StatusCode::kInvalidArgument, "meshing: the resolution must be at least 1 cell"};
  if (!std::isfinite(o.level)) return {StatusCode::kInvalidArgument, "meshing: the level w* must be a finite number"};
  if (o.level == 0.0f)
    return {StatusCode::kInvalidArgument,
            "meshing: level 0 gives no bounded surface (w tends to 0 far from the mesh, on either side)"};
  if (!(o.smooth_angle >= 0.0f && o.smooth_angle <= 180.0f))
    return {StatusCode::kInvalidArgument, "meshing: the smoothing angle must lie in [0, 180] degrees"};
  if (o.method != MeshingMethod::kDualContouring && o.method != MeshingMethod::kMarchingCubes)
    return {StatusCode::kInvalidArgument, "meshing: the method must be dual contouring or marching cubes"};
  if (uint32_t(o.winding.method) >= kWindingMethodCount)
    return {StatusCode::kInvalidArgument, "meshing: unknown winding method"};
  if (o.winding.taylor.order < 0 || o.winding.taylor.order > 2)
    return {StatusCode::kInvalidArgument, "meshing: Taylor order must be 0, 1 or 2"};
  if (!beta_valid(o.winding.taylor.beta))
    return {StatusCode::kInvalidArgument, "meshing: " + beta_refusal(o.winding.taylor.beta)};
  if (o.attributes & ~uint32_t(kAttributeSource | kAttributeUv | kAttributeColor))
    return {StatusCode::kInvalidArgument, "meshing: unknown attribute flags (source, uv and color exist)"};
  return Status::Ok();
}

// The grid: cells of the requested size (or the longest side of M's box over the resolution:
// the box that holds every sheet, and for a closed mesh all of S), covering the box that holds
// S with one cell to spare on every side, so that the outermost corners lie off S and the
// output closes.
Status make_grid(const ModelView& view, const MeshingOptions& o, MeshGrid& grid) {
  const Aabb sheets = crossing_box(view);
  const Aabb box = detail::surface_box(view, o.level);
  const vec3 mesh_extent = sheets.hi - sheets.lo;
  const float longest = std::max({mesh_extent.x, mesh_extent.y, mesh_extent.z});
  const float cell = o.cell_size > 0.0f ? o.cell_size : longest / float(o.resolution);
  if (!(cell > 0.0f) || !std::isfinite(cell))
    return {StatusCode::kInvalidArgument, "meshing: the mesh's box has no extent to divide into cells"};
  const vec3 extent = box.hi - box.lo;
  for (int a = 0; a < 3; ++a) {
    const double cells = std::ceil(double(extent[a]) / double(cell)) + 2.0;
    if (!(cells <= double(kMaxGridCells)))
      return {StatusCode::kInvalidArgument, "meshing: " + std::to_string(uint64_t(std::min(cells, 1e18))) +
                                                " cells along an axis, beyond the " + std::to_string(kMaxGridCells) +
                                                " the grid allows (a smaller resolution or a larger cell size)"};
    grid.cells[a] = int32_t(cells);
    grid.blocks[a] = (grid.cells[a] + 1 + kBlockCells - 1) / kBlockCells;
  }
  grid.cell = cell;
  const vec3 span = cell * vec3(float(grid.cells[0]), float(grid.cells[1]), float(grid.cells[2]));
  grid.origin = box.centre() - 0.5f * span;
  return Status::Ok();
}

}  // namespace

Status plan_meshing(const GwnModel& model, const MeshingOptions& options, MeshingPlan& plan, SurfaceMesh& out,
                    MeshingStats& stats) {
  out = SurfaceMesh{};
  plan = MeshingPlan{};
  if (Status s = validate_options(options); !s.ok()) return s;
  if (Status s = check_attributes(model.mesh(), options.attributes); !s.ok()) return s;
  if (Status s = model.prepare(kPartBoundary | kPartSheets); !s.ok()) return s;
  plan.view = model.view();
  if (!level_within_reach(plan.view, options.level)) {
    stats.message = level_out_of_reach_message(plan.view.triangles.triangle_count, options.level) + " (an empty mesh)";
    plan.empty = true;
    return Status::Ok();
  }
  if (Status s = make_grid(plan.view, options, plan.grid); !s.ok()) return s;
  for (int a = 0; a < 3; ++a) {
    stats.grid[a] = uint32_t(plan.grid.cells[a]);
    stats.origin[a] = plan.grid.origin[a];
  }
  stats.cell_size = plan.grid.cell;
  // The sheets bound the distance to S only when classified for this level and exactly (the
  // multipole's classification decides within a tolerance); otherwise the distance to M does.
  plan.use_sheets = plan.view.sheet_level == options.level && model.sheet_side_tolerance() == 0.0f;
  plan.settle_by_bounds = options.settle_corners_by_bounds && detail::sums_cone(plan.view, options);
  return Status::Ok();
}

Status finish_meshing(const GwnModel& model, const MeshingOptions& options, SurfaceMesh& out) {
  if (Status s = transfer_attributes(model.mesh(), model.triangle_view(), options.attributes, out); !s.ok()) {
    out = SurfaceMesh{};
    return s;
  }
  if (options.soup) {
    // Three vertices of its own per triangle, each a copy of the indexed corner's.
    const HostBackend backend;
    const uint64_t t = out.triangles.size();
    for_each_vertex_array(out, [&](auto& a) {
      if (a.empty()) return;
      std::remove_cvref_t<decltype(a)> corners(3 * t);
      backend.parallel_for(t, [&](uint64_t f) {
        for (int k = 0; k < 3; ++k) corners[3 * f + k] = a[out.triangles[f][k]];
      });
      a = std::move(corners);
    });
    backend.parallel_for(
        t, [&](uint64_t f) { out.triangles[f] = uvec3(uint32_t(3 * f), uint32_t(3 * f + 1), uint32_t(3 * f + 2)); });
  }
  return Status::Ok();
}

}  // namespace gwnrt
