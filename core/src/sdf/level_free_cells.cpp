// Level-free cells: each block of the grid is proven free of φ's levels by one bound at its
// centre, or split into eighths down to single cells.

#include "gwnrt/sdf/level_free_cells.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "gwnrt/sdf/signed_distance.h"
#include "gwnrt/trace/march_regions.h"

namespace gwnrt {

namespace {

// The beta of φ's expansion in the bound, as the mesher's scout takes it (within kExactPhaseGap
// of a level the bound sums φ exactly).
constexpr float kLevelFreeBeta = 2.0f;
constexpr uint32_t kTopBlockCells = 8;

struct CellBlocks {
  const ModelView& model;
  float level;
  const LevelFreeCells& grid;
  uint8_t* free;

  // Cells [i, i + size)³ from (i, j, k), clipped to the grid.
  void prove(const uint32_t (&lo)[3], uint32_t size) const {
    uint32_t hi[3];
    for (int a = 0; a < 3; ++a) {
      if (lo[a] >= grid.dims[a]) return;
      hi[a] = std::min(lo[a] + size, grid.dims[a]);
    }
    Aabb box;
    for (int a = 0; a < 3; ++a) {
      box.lo[a] = grid.box.lo[a] + float(lo[a]) * grid.cell;
      box.hi[a] = grid.box.lo[a] + float(hi[a]) * grid.cell;
    }
    const float radius = 0.5f * glm::length(box.hi - box.lo);
    const float needed = kLevelFreeSlack * radius;
    if (level_set_distance_bound(model, box.centre(), level, kLevelFreeBeta, needed) >= needed) {
      for (uint32_t k = lo[2]; k < hi[2]; ++k)
        for (uint32_t j = lo[1]; j < hi[1]; ++j)
          for (uint32_t i = lo[0]; i < hi[0]; ++i) free[i + grid.dims[0] * (j + grid.dims[1] * k)] = 1;
      return;
    }
    if (size == 1) return;
    const uint32_t half = size / 2;
    for (uint32_t c = 0; c < 8; ++c) {
      const uint32_t child[3] = {lo[0] + (c & 1) * half, lo[1] + ((c >> 1) & 1) * half, lo[2] + (c >> 2) * half};
      prove(child, half);
    }
  }
};

}  // namespace

Status build_level_free_cells(const ModelView& model, float level, LevelFreeCellGrid& out) {
  out = LevelFreeCellGrid{};
  if (!std::isfinite(level)) return {StatusCode::kInvalidArgument, "build_level_free_cells: level is not finite"};
  if (!(model.parts & kPartBoundary) || model.cone.triangle_count == 0) return Status::Ok();
  const Aabb box = march_region(model, level);
  if (!box.valid()) return Status::Ok();
  const vec3 extent = box.hi - box.lo;
  const float longest = std::max({extent.x, extent.y, extent.z});
  const float cell = longest / float(kLevelFreeCellsPerSide);
  // A cell must stay far above the float steps of its coordinates, or a ray's exit from it could
  // be off by more than the slack covers: then no cells.
  const vec3 largest = glm::max(glm::abs(box.lo), glm::abs(box.hi));
  if (!(cell > 1e-4f * std::max({largest.x, largest.y, largest.z})) || !std::isfinite(cell)) return Status::Ok();
  LevelFreeCells& grid = out.params;
  grid.box = box;
  grid.cell = cell;
  for (int a = 0; a < 3; ++a)
    grid.dims[a] = std::clamp(uint32_t(std::ceil(extent[a] / cell)), 1u, kLevelFreeCellsPerSide);
  grid.phase = level - std::floor(level);
  // The last cell along each axis reaches the box's side (ceil, and the clamp at the longest).
  for (int a = 0; a < 3; ++a) grid.box.hi[a] = std::max(grid.box.hi[a], grid.box.lo[a] + float(grid.dims[a]) * cell);
  out.free.assign(size_t(grid.dims[0]) * grid.dims[1] * grid.dims[2], 0);
  uint32_t blocks[3];
  for (int a = 0; a < 3; ++a) blocks[a] = (grid.dims[a] + kTopBlockCells - 1) / kTopBlockCells;
  const CellBlocks prover{model, level, grid, out.free.data()};
  tbb::parallel_for(uint32_t(0), blocks[0] * blocks[1] * blocks[2], [&](uint32_t b) {
    const uint32_t lo[3] = {(b % blocks[0]) * kTopBlockCells, (b / blocks[0] % blocks[1]) * kTopBlockCells,
                            b / (blocks[0] * blocks[1]) * kTopBlockCells};
    prover.prove(lo, kTopBlockCells);
  });
  return Status::Ok();
}

}  // namespace gwnrt
