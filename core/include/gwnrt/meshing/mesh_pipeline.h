// The mesher's driver, written once over a backend (the TBB one: core/src/meshing/
// host_backend.h; CUDA/CUB: cuda/src/mesh_backend.cuh): it sizes the arrays, runs the passes of
// meshing/dual_contouring.h over their items and compacts with exclusive scans. A backend
// provides Array<T> (resize, which need not keep the contents but zero-fills, data, size, move),
// parallel_for(n, fn[, grain, progress]), exclusive_scan(in, n, out) -> total, to_host(array, i)
// for the few values the driver reads back, and move_out(array, std::vector&) for the output.
// Every function the driver hands to parallel_for is a GWNRT_HD functor or a GWNRT_PASS lambda
// (base/hd.h); it never touches host memory from inside one (the output is moved out whole).
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include "gwnrt/base/memory.h"
#include "gwnrt/meshing/dual_contouring.h"
#include "gwnrt/meshing/extract_surface.h"
#include "gwnrt/model/model.h"
#include "gwnrt/trace/march_regions.h"

namespace gwnrt {

namespace detail {

// The cell-size-independent part of the grid: the box that holds S (M's padded box for the
// sheets, the march boxes for the smooth pieces of this level).
inline Aabb surface_box(const ModelView& m, float level) {
  Aabb box = crossing_box(m);
  for (uint32_t r = 0; r < march_box_count(m, level); ++r) box.extend(march_box(m, level, r));
  return box;
}

class PassClock {
 public:
  double lap() {
    const auto now = std::chrono::steady_clock::now();
    const double s = std::chrono::duration<double>(now - last_).count();
    last_ = now;
    return s;
  }

 private:
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

// The bytes the driver's arrays hold at once, against MeshingOptions::memory_budget: reserve
// fails, naming the grid and what it was for, when the total would exceed it. (A class, not a
// lambda: nvcc refuses a function's local type in the template arguments of a function that
// holds extended lambdas, run_marching_cubes.)
class MemoryBudget {
 public:
  MemoryBudget(const MeshGrid& grid, uint64_t budget, MeshingStats& stats)
      : grid_(grid), budget_(budget), stats_(stats) {}
  Status reserve(uint64_t bytes, const char* what) {
    live_ += bytes;
    stats_.bytes = std::max(stats_.bytes, live_);
    if (live_ > budget_)
      return {StatusCode::kOutOfMemory, std::string("meshing at ") + std::to_string(grid_.cells[0]) + "x" +
                                            std::to_string(grid_.cells[1]) + "x" + std::to_string(grid_.cells[2]) +
                                            " cells needs at least " + memory_size_text(live_) + " (" + what +
                                            "), beyond the memory budget of " + memory_size_text(budget_)};
    return Status::Ok();
  }
  void release(uint64_t bytes) { live_ -= bytes; }

 private:
  const MeshGrid& grid_;
  uint64_t budget_;
  MeshingStats& stats_;
  uint64_t live_ = 0;
};

// out = the items i of in[0, n) for which keep(i) holds, in order: the backend interface's
// compaction (flags, an exclusive scan, a scatter), written once over parallel_for and
// exclusive_scan. Returns how many were kept.
template <class Backend, class T, class Keep, class Out>
uint64_t compact(Backend& backend, const T* in, uint64_t n, Keep keep, Out& out) {
  typename Backend::template Array<uint32_t> flag, offset;
  flag.resize(n);
  offset.resize(n);
  uint32_t* f = flag.data();
  backend.parallel_for(n, [=] GWNRT_PASS(uint64_t i) { f[i] = keep(i) ? 1u : 0u; });
  const uint64_t total = backend.exclusive_scan(f, n, offset.data());
  out.resize(total);
  if (total == 0) return 0;
  const uint32_t* o = offset.data();
  T* dst = out.data();
  backend.parallel_for(n, [=] GWNRT_PASS(uint64_t i) {
    if (f[i]) dst[o[i]] = in[i];
  });
  return total;
}

}  // namespace detail

// What extract_surface does around the driver, shared with the CUDA backend's entry point
// (gwnrt/cuda.h): plan_meshing checks the options and attributes, builds the model's parts and
// sizes the grid; `empty` (with Ok) when S is empty for the level (stats.message says why, out
// stays empty). finish_meshing transfers the attributes and makes the soup, on the host. Both in
// core/src/meshing/extract_surface.cpp.
struct MeshingPlan {
  ModelView view;  // the host's
  MeshGrid grid;
  bool use_sheets = false;  // the scout's distance to S: to the sheets (exact classification) or to M
  bool empty = false;
};
Status plan_meshing(const GwnModel& model, const MeshingOptions& options, MeshingPlan& plan, SurfaceMesh& out,
                    MeshingStats& stats);
Status finish_meshing(const GwnModel& model, const MeshingOptions& options, SurfaceMesh& out);

// Marching cubes after the shared passes (corners, edges, Hermite data): the edges' points are
// the vertices, each cell's loops its polygons.
template <class Backend, class Array>
Status run_marching_cubes(Backend& backend, const SparseGridView& view, uint64_t edge_total, const Array& hermite,
                          detail::MemoryBudget& budget, detail::PassClock& clock, SurfaceMesh& out,
                          MeshingStats& stats) {
  using U32 = typename Backend::template Array<uint32_t>;
  const uint64_t items = stats.evaluated_blocks * kBlockItems;
  U32 count, offset;
  count.resize(items);
  offset.resize(items);
  backend.parallel_for(items, MarchingCountPass{view, count.data()});
  const uint64_t face_total = backend.exclusive_scan(count.data(), items, offset.data());
  if (Status s = budget.reserve(face_total * 2 * sizeof(uvec3), "the triangles"); !s.ok()) return s;
  typename Backend::template Array<uvec3> triangles;
  triangles.resize(face_total);
  backend.parallel_for(items, MarchingFacePass{view, count.data(), offset.data(), triangles.data()});
  stats.seconds.faces = clock.lap();
  {
    typename Backend::template Array<vec3> positions, normals;
    positions.resize(edge_total);
    normals.resize(edge_total);
    const HermitePoint* h = hermite.data();
    vec3 *p = positions.data(), *n = normals.data();
    backend.parallel_for(edge_total, [=] GWNRT_PASS(uint64_t i) {
      p[i] = h[i].point;
      n[i] = h[i].normal;
    });
    backend.move_out(positions, out.positions);
    backend.move_out(normals, out.normals);
  }
  // Faces with an edge not listed (a cell missing: a failed bound) are dropped, as in DC.
  const uvec3* t = triangles.data();
  typename Backend::template Array<uvec3> kept_triangles;
  const uint64_t kept = detail::compact(
      backend, t, face_total, [=] GWNRT_PASS(uint64_t i) { return t[i].x != kEmptyLane; }, kept_triangles);
  backend.move_out(kept_triangles, out.triangles);
  stats.open_edges = face_total - kept;
  stats.seconds.output = clock.lap();
  return Status::Ok();
}

// Dual contouring of S on `grid` (its cells and blocks set, its arrays not yet). `scout` decides
// which blocks S may meet. Fills out (positions, normals, triangles; indexed) and stats.
template <class Backend>
Status run_dual_contouring(Backend& backend, const ModelView& model, const MeshingOptions& options,
                           const MeshGrid& grid, const ScoutQuery& scout, SurfaceMesh& out, MeshingStats& stats) {
  using U32 = typename Backend::template Array<uint32_t>;
  detail::PassClock clock;
  detail::MemoryBudget budget(grid, options.memory_budget, stats);
  // The block map (step 2: needed_dense, is_slot and slot_of_block) has three words a block of
  // the grid, known now: a grid whose map alone is beyond the budget is refused before scouting,
  // which at --resolution 100000 ran past a minute and 3 GB before the refusal.
  const uint64_t block_count = grid.block_count();
  if (Status s = budget.reserve(block_count * 3 * sizeof(uint32_t), "the block map"); !s.ok()) return s;

  // 1. Scouting, coarse to fine: a block of 2^L·kBlockCells cells is split only when S may meet it.
  const int32_t corners_max = std::max({grid.cells[0], grid.cells[1], grid.cells[2]}) + 1;
  int level_top = 0;
  while ((int64_t(kBlockCells) << level_top) * 8 < corners_max) ++level_top;
  typename Backend::template Array<GridCoord> candidates, kept;
  {
    const int32_t size = kBlockCells << level_top;
    const int32_t n[3] = {(grid.cells[0] + size) / size, (grid.cells[1] + size) / size, (grid.cells[2] + size) / size};
    candidates.resize(uint64_t(n[0]) * n[1] * n[2]);
    GridCoord* c = candidates.data();
    backend.parallel_for(candidates.size(), [=] GWNRT_PASS(uint64_t i) {
      c[i] = {int32_t(i % n[0]), int32_t((i / n[0]) % n[1]), int32_t(i / (uint64_t(n[0]) * n[1]))};
    });
  }
  for (int level = level_top;; --level) {
    const int32_t size = kBlockCells << level;
    const GridCoord* c = candidates.data();
    const uint64_t count = detail::compact(
        backend, c, candidates.size(),
        [=] GWNRT_PASS(uint64_t i) {
          const GridCoord b = c[i];
          if (!(b.x * size <= grid.cells[0] && b.y * size <= grid.cells[1] && b.z * size <= grid.cells[2]))
            return false;
          const vec3 lo = grid.corner_position({b.x * size, b.y * size, b.z * size});
          const vec3 hi = grid.corner_position({(b.x + 1) * size, (b.y + 1) * size, (b.z + 1) * size});
          return scout.may_meet(lo, hi);
        },
        kept);
    if (Status s = budget.reserve(count * sizeof(GridCoord) * (level > 0 ? 9 : 1), "scouting"); !s.ok()) return s;
    budget.release(count * sizeof(GridCoord) * (level > 0 ? 9 : 1));
    if (level == 0) break;
    candidates.resize(count * 8);
    const GridCoord* src = kept.data();
    GridCoord* children = candidates.data();
    backend.parallel_for(count * 8, [=] GWNRT_PASS(uint64_t i) {
      const GridCoord b = src[i / 8];
      const int d = int(i % 8);
      children[i] = {2 * b.x + (d & 1), 2 * b.y + ((d >> 1) & 1), 2 * b.z + ((d >> 2) & 1)};
    });
  }
  stats.active_blocks = kept.size();
  stats.seconds.scout = clock.lap();
  if (kept.size() == 0) {
    stats.message = "S does not meet the grid: no point has w above the level (an empty mesh)";
    return Status::Ok();
  }

  // 2. Slots: the active blocks and the neighbours (+x, +y, +z) whose corners their cells read
  // (the block map's bytes reserved above).
  U32 needed_dense, slot_of_block;
  needed_dense.resize(block_count);
  slot_of_block.resize(block_count);
  {
    uint32_t* needed = needed_dense.data();
    const GridCoord* b = kept.data();
    backend.parallel_for(kept.size(), [=] GWNRT_PASS(uint64_t i) {
      for (int d = 0; d < 8; ++d) {
        const GridCoord t{b[i].x + (d & 1), b[i].y + ((d >> 1) & 1), b[i].z + ((d >> 2) & 1)};
        if (t.x < grid.blocks[0] && t.y < grid.blocks[1] && t.z < grid.blocks[2])
          atomic_or(needed + grid.block_index(t.x, t.y, t.z), 1u << d);
      }
    });
  }
  U32 is_slot;
  is_slot.resize(block_count);
  {
    const uint32_t* needed = needed_dense.data();
    uint32_t* f = is_slot.data();
    backend.parallel_for(block_count, [=] GWNRT_PASS(uint64_t i) { f[i] = needed[i] != 0; });
  }
  const uint64_t slots = backend.exclusive_scan(is_slot.data(), block_count, slot_of_block.data());
  // Per item: the corner value, edge mask, count and offset, the cell parts, count and offset.
  const uint64_t per_slot = uint64_t(kBlockItems) * (sizeof(float) + 1 + 5 * sizeof(uint32_t)) + 8;
  if (Status s = budget.reserve(slots * per_slot, "the corners and cells of the blocks S may meet"); !s.ok()) return s;
  U32 block_of_slot, needed_from;
  block_of_slot.resize(slots);
  needed_from.resize(slots);
  {
    const uint32_t *f = is_slot.data(), *needed = needed_dense.data();
    uint32_t *map = slot_of_block.data(), *bos = block_of_slot.data(), *nf = needed_from.data();
    backend.parallel_for(block_count, [=] GWNRT_PASS(uint64_t i) {
      if (f[i]) {
        bos[map[i]] = uint32_t(i);
        nf[map[i]] = needed[i];
      } else {
        map[i] = kEmptyLane;
      }
    });
  }
  stats.evaluated_blocks = slots;

  SparseGridView view;
  view.grid = grid;
  view.slot_of_block = slot_of_block.data();
  view.block_of_slot = block_of_slot.data();
  view.needed_from = needed_from.data();

  // 3. Corner values.
  typename Backend::template Array<float> corner_value;
  corner_value.resize(slots * kBlockItems);
  if (options.progress_total) options.progress_total->fetch_add(slots * kBlockCells * kBlockCells);
  backend.parallel_for(slots * kBlockCells * kBlockCells,
                       CornerColumnPass{view, model, options.winding, options.level, corner_value.data()}, 4,
                       options.progress);
  view.corner_value = corner_value.data();
  stats.seconds.corners = clock.lap();

  // 4. Edges and their Hermite data.
  typename Backend::template Array<uint8_t> edge_mask;
  U32 edge_count, edge_offset;
  edge_mask.resize(slots * kBlockItems);
  edge_count.resize(slots * kBlockItems);
  edge_offset.resize(slots * kBlockItems);
  backend.parallel_for(slots * kBlockItems, EdgeCountPass{view, edge_mask.data(), edge_count.data()});
  const uint64_t edge_total = backend.exclusive_scan(edge_count.data(), edge_count.size(), edge_offset.data());
  if (edge_total >= kEmptyLane / 2)
    return {StatusCode::kOutOfMemory, "meshing: " + std::to_string(edge_total) + " crossing edges, beyond 2^31"};
  if (Status s =
          budget.reserve(edge_total * (sizeof(uint64_t) + sizeof(HermitePoint) + 2 * sizeof(uvec3)), "the edges");
      !s.ok())
    return s;
  view.edge_mask = edge_mask.data();
  view.edge_offset = edge_offset.data();
  stats.corners = 0;
  typename Backend::template Array<uint64_t> edges;
  edges.resize(edge_total);
  backend.parallel_for(slots * kBlockItems, EdgeListPass{view, edges.data()});
  typename Backend::template Array<HermitePoint> hermite;
  hermite.resize(edge_total);
  if (options.progress_total) options.progress_total->fetch_add(edge_total);
  backend.parallel_for(edge_total,
                       HermitePass{view, model, options.winding, options.level, edges.data(), hermite.data()}, 16,
                       options.progress);
  stats.crossing_edges = edge_total;
  {
    typename Backend::template Array<unsigned long long> tally;  // HermiteTally's counters, zeroed
    tally.resize(kHermiteTallies);
    backend.parallel_for((edge_total + kHermiteTallyRun - 1) / kHermiteTallyRun,
                         HermiteTally{hermite.data(), edge_total, tally.data()}, 16);
    stats.sheet_edges = backend.to_host(tally, kTallySheet);
    stats.smooth_edges = backend.to_host(tally, kTallySmooth);
    stats.fallback_edges = backend.to_host(tally, kTallyFallback);
    stats.capped_edges = backend.to_host(tally, kTallyCapped);
  }
  stats.seconds.edges = clock.lap();
  if (edge_total == 0) {
    stats.message = "S does not cross the grid: every corner is on one side of the level (an empty mesh)";
    return Status::Ok();
  }

  if (options.method == MeshingMethod::kMarchingCubes)
    return run_marching_cubes(backend, view, edge_total, hermite, budget, clock, out, stats);

  // 5. Cells: one vertex per component.
  U32 cell_parts, cell_count, cell_offset;
  cell_parts.resize(slots * kBlockItems);  // zeroed
  cell_count.resize(slots * kBlockItems);
  cell_offset.resize(slots * kBlockItems);
  backend.parallel_for(edge_total, CellMarkPass{view, edges.data(), cell_parts.data()});
  typename Backend::template Array<unsigned long long> multi;
  multi.resize(1);
  backend.parallel_for(slots * kBlockItems, CellCountPass{view, cell_parts.data(), cell_count.data(), multi.data()});
  stats.multi_component_cells = backend.to_host(multi, 0);
  view.cell_parts = cell_parts.data();
  const uint64_t vertex_total = backend.exclusive_scan(cell_count.data(), cell_count.size(), cell_offset.data());
  if (Status s = budget.reserve(vertex_total * (2 * sizeof(vec3) + sizeof(uint64_t)), "the vertices"); !s.ok())
    return s;
  view.cell_vertex_count = cell_count.data();
  view.cell_vertex_offset = cell_offset.data();
  typename Backend::template Array<vec3> positions, normals;
  typename Backend::template Array<uint64_t> vertex_cell;
  positions.resize(vertex_total);
  normals.resize(vertex_total);
  vertex_cell.resize(vertex_total);
  backend.parallel_for(slots * kBlockItems,
                       CellVertexPass{view, hermite.data(), positions.data(), normals.data(), vertex_cell.data()});
  stats.seconds.vertices = clock.lap();

  // 6. Faces: two triangles per crossing edge; edges missing a cell are dropped.
  typename Backend::template Array<uvec3> triangles;
  triangles.resize(2 * edge_total);
  backend.parallel_for(edge_total, QuadPass{view, edges.data(), hermite.data(), positions.data(), triangles.data()});
  stats.seconds.faces = clock.lap();

  // 7. Normals.
  if (options.smooth_angle > 0.0f) {
    typename Backend::template Array<vec3> smoothed;
    smoothed.resize(vertex_total);
    backend.parallel_for(vertex_total, SmoothNormalsPass{view, vertex_cell.data(), normals.data(), smoothed.data(),
                                                         cosf(options.smooth_angle * kDegree)});
    normals = std::move(smoothed);
  }
  stats.seconds.smoothing = clock.lap();

  // 8. Output (indexed).
  backend.move_out(positions, out.positions);
  backend.move_out(normals, out.normals);
  const uvec3* t = triangles.data();
  typename Backend::template Array<uvec3> kept_triangles;
  const uint64_t face_total = detail::compact(
      backend, t, 2 * edge_total, [=] GWNRT_PASS(uint64_t i) { return t[i].x != kEmptyLane; }, kept_triangles);
  backend.move_out(kept_triangles, out.triangles);
  stats.open_edges = (2 * edge_total - face_total) / 2;
  stats.seconds.output = clock.lap();
  return Status::Ok();
}

}  // namespace gwnrt
