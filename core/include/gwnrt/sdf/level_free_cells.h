// Level-free cells (LevelFreeCells, model_view.h): a uniform grid over the march boxes of a level
// whose cells no level of φ = w mod 1 at the level's phase meets, for the tracer
// (trace/level_free_cells.h). Built on the host (core/src/sdf/level_free_cells.cpp).
#pragma once

#include <cstdint>
#include <vector>

#include "gwnrt/base/status.h"
#include "gwnrt/geometry/model_view.h"

namespace gwnrt {

// Cells along the longest side of the march boxes' union: at 64 the cells away from ∂M are a few
// Harnack steps across, and the grid (at most 64³ bytes) is built in tens of milliseconds on a
// scan with hundreds of holes (docs/performance.md, tracing).
inline constexpr uint32_t kLevelFreeCellsPerSide = 64;

// A block's bound must clear its half-diagonal by this factor: the cells' faces and corners are
// then inside the proven ball by far more than the round-off of a ray's exit from a cell.
inline constexpr float kLevelFreeSlack = 1.01f;

// The owner of the cells' flags; view() is what ModelView::level_free holds.
struct LevelFreeCellGrid {
  LevelFreeCells params;  // its `free` unset: view() points it at `free`
  std::vector<uint8_t> free;
  LevelFreeCells view() const {
    LevelFreeCells v = params;
    v.free = free.empty() ? nullptr : free.data();
    return v;
  }
};

// The cells for `level` of a model whose view holds the boundary (kPartBoundary): proven by
// level_set_distance_bound (sdf/signed_distance.h: the Harnack and Lipschitz balls of φ, the
// march boxes) at the centres of blocks of 8, 4, 2 and 1 cells, coarse to fine. Empty for a
// closed mesh (no levels off M), an empty region, or a grid too fine for float coordinates there.
Status build_level_free_cells(const ModelView& model, float level, LevelFreeCellGrid& out);

}  // namespace gwnrt
