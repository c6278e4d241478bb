// Everything a query or a ray needs from a GwnModel, as trivially copyable views: what the
// host-and-device functions take and what the CUDA backend fills with device pointers.
#pragma once

#include "gwnrt/geometry/bvh.h"

namespace gwnrt {

// Where the smooth pieces of S can be. For a group of boundary loops whose cone triangles lie in
// `box` with total area A_r, |w_C(y)| <= Σ_r A_r / (4π d_r²), d_r = distance from y to box r
// (each triangle's solid angle is at most its area over distance squared). A level w* + k is
// reached only where |w_C| >= δ = distance from 0 to the nearest level, so at least one group
// has A_r / d_r² >= 4πδ·λ_r for shares λ_r summing to 1: d_r <= sqrt(spread_r / (4πδ)) with
// spread_r = A_r / λ_r. Outside those grown boxes no level is crossed and the tracer needs no
// Harnack step at all.
struct SmoothRegion {
  Aabb box;
  float spread = 0;
};

// The segment of ∂M that a cone triangle (apex, a, b) carries, a -> b: its length and
// 1 / length², kept so that the tracer's bound (phase.h) spends no square root or division on them.
struct ConeSegment {
  float length = 0;
  float inverse_length2 = 0;
};

inline constexpr uint32_t kMaxSmoothRegions = 16;  // loops are grouped beyond this

// Cells of a uniform grid that no level of φ = w mod 1 at `phase` meets (phase w* mod 1: the
// levels w* + k for every whole k), each proven so when built (sdf/level_free_cells.h): the
// tracer crosses a run of them in one step instead of Harnack steps sized by the distance to ∂M.
// Empty (no cells) when not built or useless (a closed mesh has no levels off M).
struct LevelFreeCells {
  Aabb box;  // the grid's box: cell (i, j, k) spans box.lo + cell · [i, i + 1] × ...
  float cell = 0;
  uint32_t dims[3] = {0, 0, 0};
  float phase = __builtin_nanf("");  // in [0, 1); NaN when empty
  const uint8_t* free = nullptr;     // per cell, i + dims[0] · (j + dims[1] · k): 1 where no level meets it
};

// The parts of a GwnModel, built by GwnModel::build at once or, with BuildOptions::defer_parts,
// on first need (GwnModel::prepare). A ModelView says which it holds: the others are empty views,
// which the queries would read as a closed mesh without sheets, so the drivers check.
enum ModelPart : uint32_t {
  kPartTriangles = 1u << 0,  // M's multipole tree, its box and margin: always built
  kPartBoundary = 1u << 1,   // ∂M and its tree, the cone C over ∂M and its tree, the smooth regions
  kPartSheets = 1u << 2,     // the sheet classification and the sheet tree (reads the boundary's)
  // The level-free cells for the sheet level's phase (reads the boundary): only on request, never
  // by build() alone, since only the tracer reads them.
  kPartLevelFreeCells = 1u << 3,
};

struct ModelView {
  TriangleTreeView triangles;  // M
  SegmentTreeView boundary;    // ∂M
  // ∂M's segments clustered for the ribbons' exact w (field/ribbon_winding.h), over `boundary`'s
  // BVH. Host only: the device's view leaves it empty.
  RibbonTreeView ribbons;
  // The cone C over ∂M (boundary_cone): a triangle (z, a, b) for each boundary segment a→b, z its
  // loop's mean or its group's in a spanned loop, and the spanned loops' inner triangles. M − C
  // is closed, so w − w_C is an integer off M ∪ C and w mod 1 = w_C mod 1 (docs/design.md §3):
  // the tracer's Harnack steps evaluate C, not M. Empty when ∂M is.
  TriangleTreeView cone;
  // Per node of the cone's tree: the length of ∂M below each lane (the segments its triangles
  // carry, as their edges 1 -> 2), for the tracer's bound on |∇w| (phase.h).
  const WideNodeLength* cone_boundary_lengths = nullptr;
  const ConeSegment* cone_segments = nullptr;  // per cone triangle, in leaf order (length 0: inner)
  // The sheet triangles of M for the level sheet_level (sdf/sheets.h, is_sheet): the distance to
  // the sheet pieces of S is the distance to them.
  TriangleTreeView sheets;
  float sheet_level = __builtin_nanf("");  // NaN: not classified (the tree is empty)
  const SmoothRegion* smooth_regions = nullptr;
  uint32_t smooth_region_count = 0;
  // A crossing query's work over a Taylor query's, sampled when the boundary is built
  // (field/evaluate_winding.h, sample_crossing_work_ratio); 0 for a closed mesh.
  float crossing_work_ratio = 0;
  Aabb bounds;               // of M
  float surface_margin = 0;  // S lies inside `bounds` grown by this: |w| < 1/2 beyond (docs/design.md §5)
  LevelFreeCells level_free;
  uint32_t parts = 0;  // ModelPart bits: what the view holds
};

// Whether w can reach `level` anywhere: w sums one solid angle in (-2π, 2π) over 4π per triangle,
// so |w| < n/2 for n triangles, and ∂{w > level} is empty for |level| >= n/2. The tracer and the
// mesher give no surface for such a level (a huge level would overflow the tracer's integer band);
// the programs say why. `triangle_count` may also count zero-area triangles (a mesh's own count,
// before the model leaves them out of its tree): they add nothing to w, so the bound holds, if less
// tight.
GWNRT_HD inline bool level_within_reach(uint32_t triangle_count, float level) {
  return fabsf(level) < 0.5f * float(triangle_count);
}
GWNRT_HD inline bool level_within_reach(const ModelView& m, float level) {
  return level_within_reach(m.triangles.triangle_count, level);
}

}  // namespace gwnrt
