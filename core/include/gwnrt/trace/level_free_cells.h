// The tracer's walk through level-free cells (LevelFreeCells, model_view.h; built by
// sdf/level_free_cells.h): a run of them is crossed in one step, where Harnack steps would be a
// fraction of the distance to ∂M each. Host-and-device.
#pragma once

#include "gwnrt/base/hd.h"
#include "gwnrt/geometry/model_view.h"

namespace gwnrt {

// Whether the cells were proven for the levels of this phase (w* mod 1).
GWNRT_HD inline bool level_free_cells_apply(const LevelFreeCells& cells, float phase) {
  return cells.free != nullptr && cells.phase == phase;
}

// The length of the segment x + s·dir, s >= 0 (dir a unit vector), that lies in the run of
// consecutive level-free cells starting with x's own: 0 when x is outside the grid or its cell
// is not free. No level of φ lies on it. Each cell's exit is computed afresh from x (no sum
// accumulates round-off), and the walk stops at the grid's edge: at most dims summed cells.
GWNRT_HD inline float level_free_run(const LevelFreeCells& cells, const vec3& x, const vec3& dir) {
  int index[3], step[3];
  for (int a = 0; a < 3; ++a) {
    const float u = (x[a] - cells.box.lo[a]) / cells.cell;
    if (!(u >= 0.0f && u < float(cells.dims[a]))) return 0.0f;
    index[a] = min_of(int(u), int(cells.dims[a]) - 1);
    step[a] = dir[a] > 0.0f ? 1 : (dir[a] < 0.0f ? -1 : 0);
  }
  // The ray's parameter where it leaves cell `index` across its face on axis a.
  const auto exit = [&](int a) {
    if (step[a] == 0) return kInfinity;
    const float face = cells.box.lo[a] + float(index[a] + (step[a] > 0 ? 1 : 0)) * cells.cell;
    return (face - x[a]) / dir[a];
  };
  float run = 0.0f;
  const int cap = int(cells.dims[0] + cells.dims[1] + cells.dims[2]);
  for (int n = 0; n < cap; ++n) {
    const uint32_t i = uint32_t(index[0]) + cells.dims[0] * (uint32_t(index[1]) + cells.dims[1] * uint32_t(index[2]));
    if (!cells.free[i]) break;
    const float e[3] = {exit(0), exit(1), exit(2)};
    const int a = e[0] <= e[1] ? (e[0] <= e[2] ? 0 : 2) : (e[1] <= e[2] ? 1 : 2);
    run = e[a];
    index[a] += step[a];
    if (index[a] < 0 || index[a] >= int(cells.dims[a])) break;
  }
  return max_of(run, 0.0f);
}

}  // namespace gwnrt
