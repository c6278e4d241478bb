// The mesher's driver, written once over a backend (the TBB one: core/src/meshing/
// host_backend.h; CUDA/CUB: cuda/src/mesh_backend.cuh): it sizes the arrays, runs the passes of
// meshing/dual_contouring.h over their items and compacts with exclusive scans. A backend
// provides Array<T> (resize, which need not keep the contents but zero-fills, data, size, move),
// parallel_for(n, fn[, grain, progress]), exclusive_scan(in, n, out) -> total (out may be in),
// to_host(array, i) for the few values the driver reads back, and move_out(array, std::vector&)
// for the output.
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
  Aabb box = march_region(m, level);
  box.extend(crossing_box(m));
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
  bool use_sheets = false;        // the scout's distance to S: to the sheets (exact classification) or to M
  bool settle_by_bounds = false;  // the scout drops blocks by the corners' bounds too (ScoutQuery)
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

namespace detail {

// The arrays of the sparse grid (sparse_grid.h) as the passes fill them; `view` points into them.
template <class Backend>
struct SparseGridArrays {
  template <class T>
  using Array = typename Backend::template Array<T>;
  Array<uint32_t> slot_of_block, block_of_slot, needed_from;
  Array<float> corner_value;
  Array<BlockWinding> block_winding;  // per slot, with the exact method and a cone
  Array<int8_t> corner_jumps;         // per item, with block_winding (CornerJumpsPass)
  // What a slot holds of those two, reserved with the slot and released when find_edges frees them.
  static constexpr uint64_t kBoundBytesPerSlot = sizeof(BlockWinding) + kBlockItems * sizeof(int8_t);
  Array<uint8_t> edge_mask;
  Array<uint16_t> edge_in_slot, vertex_in_slot;
  Array<uint32_t> slot_first_edge, slot_first_vertex;
  Array<uint32_t> cell_parts;
  SparseGridView view;
  uint64_t slots = 0;
};

// The crossing edges (corner item · 4 + axis) and their Hermite data.
template <class Backend>
struct EdgeArrays {
  typename Backend::template Array<uint64_t> edges;
  typename Backend::template Array<HermitePoint> hermite;
  uint64_t total = 0;
};

// Dual contouring's vertices: position, normal and the cell item each sits in.
template <class Backend>
struct VertexArrays {
  typename Backend::template Array<vec3> positions, normals;
  typename Backend::template Array<uint64_t> cell;
  uint64_t total = 0;
};

// 1. Scouting, coarse to fine: a block of 2^L·kBlockCells cells is split only when S may meet it.
// `kept`: the blocks of kBlockCells³ cells S may meet.
template <class Backend>
Status scout_blocks(Backend& backend, const MeshGrid& grid, const ScoutQuery& scout, MemoryBudget& budget,
                    typename Backend::template Array<GridCoord>& kept) {
  const int32_t corners_max = std::max({grid.cells[0], grid.cells[1], grid.cells[2]}) + 1;
  int level_top = 0;
  while ((int64_t(kBlockCells) << level_top) * 8 < corners_max) ++level_top;
  typename Backend::template Array<GridCoord> candidates;
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
    const auto inside = [=] GWNRT_PASS(const GridCoord& b) {
      return b.x * size <= grid.cells[0] && b.y * size <= grid.cells[1] && b.z * size <= grid.cells[2];
    };
    const auto box = [=] GWNRT_PASS(const GridCoord& b) {
      return Aabb{grid.corner_position({b.x * size, b.y * size, b.z * size}),
                  grid.corner_position({(b.x + 1) * size, (b.y + 1) * size, (b.z + 1) * size})};
    };
    uint64_t count = 0;
#if GWNRT_HOST_LANES && defined(__AVX__)
    if (level <= kScoutBoundLevel && scout.settle_by_bounds) {
      // kScoutBatch candidates at a time (the children of neighbouring kept blocks: consecutive
      // in the kept order), their centres' sums as batches.
      typename Backend::template Array<uint8_t> meets;
      meets.resize(candidates.size());
      uint8_t* m = meets.data();
      const uint64_t n = candidates.size();
      backend.parallel_for((n + kScoutBatch - 1) / kScoutBatch,
                           [=](uint64_t g) {
                             Aabb boxes[kScoutBatch];
                             bool out[kScoutBatch];
                             int count_in = 0;
                             uint64_t index[kScoutBatch];
                             for (uint64_t i = kScoutBatch * g; i < n && i < kScoutBatch * (g + 1); ++i) {
                               m[i] = 0;
                               if (!inside(c[i])) continue;
                               index[count_in] = i;
                               boxes[count_in++] = box(c[i]);
                             }
                             scout.may_meet_batch(boxes, count_in, out, level == 0);
                             for (int k = 0; k < count_in; ++k) m[index[k]] = out[k];
                           },
                           1);
      count = compact(
          backend, c, n, [=](uint64_t i) { return m[i] != 0; }, kept);
    } else
#endif
      count = compact(
          backend, c, candidates.size(),
          [=] GWNRT_PASS(uint64_t i) {
            if (!inside(c[i])) return false;
            const Aabb b = box(c[i]);
            return scout.may_meet(b.lo, b.hi, level <= kScoutBoundLevel, level == 0);
          },
          kept);
    if (Status s = budget.reserve(count * sizeof(GridCoord) * (level > 0 ? 9 : 1), "scouting"); !s.ok()) return s;
    budget.release(count * sizeof(GridCoord) * (level > 0 ? 9 : 1));
    if (level == 0) return Status::Ok();
    candidates.resize(count * 8);
    const GridCoord* src = kept.data();
    GridCoord* children = candidates.data();
    backend.parallel_for(count * 8, [=] GWNRT_PASS(uint64_t i) {
      const GridCoord b = src[i / 8];
      const int d = int(i % 8);
      children[i] = {2 * b.x + (d & 1), 2 * b.y + ((d >> 1) & 1), 2 * b.z + ((d >> 2) & 1)};
    });
  }
}

// 2. Slots: the active blocks and the neighbours (+x, +y, +z) whose corners their cells read; the
// block map's bytes were reserved before scouting.
template <class Backend>
Status assign_slots(Backend& backend, const MeshGrid& grid, const typename Backend::template Array<GridCoord>& kept,
                    MemoryBudget& budget, SparseGridArrays<Backend>& g) {
  using U32 = typename Backend::template Array<uint32_t>;
  const uint64_t block_count = grid.block_count();
  U32 needed_dense, is_slot;
  needed_dense.resize(block_count);
  g.slot_of_block.resize(block_count);
  {
    uint32_t* needed = needed_dense.data();
    const GridCoord* b = kept.data();
    backend.parallel_for(kept.size(), [=] GWNRT_PASS(uint64_t i) {
      for (int d = 0; d < 8; ++d) {
        const GridCoord t = cell_corner(b[i], d);
        if (t.x < grid.blocks[0] && t.y < grid.blocks[1] && t.z < grid.blocks[2])
          atomic_or(needed + grid.block_index(t.x, t.y, t.z), 1u << d);
      }
    });
  }
  is_slot.resize(block_count);
  {
    const uint32_t* needed = needed_dense.data();
    uint32_t* f = is_slot.data();
    backend.parallel_for(block_count, [=] GWNRT_PASS(uint64_t i) { f[i] = needed[i] != 0; });
  }
  const uint64_t slots = backend.exclusive_scan(is_slot.data(), block_count, g.slot_of_block.data());
  // Per item: the corner value, edge mask, cell parts, and the edges' and vertices' offsets in the
  // slot; per slot: its first edge and vertex, the block map's words, and the corners' bound (the
  // block winding and the corners' kept jumps).
  const uint64_t per_slot = uint64_t(kBlockItems) * (sizeof(float) + 1 + sizeof(uint32_t) + 2 * sizeof(uint16_t)) + 16 +
                            SparseGridArrays<Backend>::kBoundBytesPerSlot;
  if (Status s = budget.reserve(slots * per_slot, "the corners and cells of the blocks S may meet"); !s.ok()) return s;
  g.block_of_slot.resize(slots);
  g.needed_from.resize(slots);
  {
    const uint32_t *f = is_slot.data(), *needed = needed_dense.data();
    uint32_t *map = g.slot_of_block.data(), *bos = g.block_of_slot.data(), *nf = g.needed_from.data();
    backend.parallel_for(block_count, [=] GWNRT_PASS(uint64_t i) {
      if (f[i]) {
        bos[map[i]] = uint32_t(i);
        nf[map[i]] = needed[i];
      } else {
        map[i] = kEmptyLane;
      }
    });
  }
  g.slots = slots;
  g.view.grid = grid;
  g.view.slot_of_block = g.slot_of_block.data();
  g.view.block_of_slot = g.block_of_slot.data();
  g.view.needed_from = g.needed_from.data();
  return Status::Ok();
}

// Whether w is summed over the cone (the exact method on a model with a boundary): what the
// corners' bounds and the batched sums apply to.
inline bool sums_cone(const ModelView& model, const MeshingOptions& options) {
  return model.cone.triangle_count > 0 &&
         resolve_winding_method(model, options.winding.method) == WindingMethod::kCrossing;
}

// 3. Corner values: w − w* at every corner an active block's cells read.
template <class Backend>
void evaluate_corners(Backend& backend, const ModelView& model, const MeshingOptions& options,
                      SparseGridArrays<Backend>& g) {
  g.corner_value.resize(g.slots * kBlockItems);
  const bool cone_sums = sums_cone(model, options);
  const BlockWinding* block_winding = nullptr;
  if (options.settle_corners_by_bounds && cone_sums) {
    g.block_winding.resize(g.slots);
    const BlockWindingPass pass{g.view, model, options.level, g.block_winding.data()};
#if GWNRT_HOST_LANES && defined(__AVX__)
    backend.parallel_for(g.slots, [=](uint64_t slot) { pass.group(slot); });
#else
    backend.parallel_for(g.slots, pass);
#endif
    block_winding = g.block_winding.data();
  }
  if (block_winding) g.corner_jumps.resize(g.slots * kBlockItems);
  if (resolve_winding_method(model, options.winding.method) == WindingMethod::kCrossing)
    backend.parallel_for(g.slots,
                         CornerJumpsPass{g.view, model, options.winding, block_winding, g.corner_value.data(),
                                         block_winding ? g.corner_jumps.data() : nullptr},
                         16);
  const uint64_t columns = g.slots * kBlockCells * kBlockCells;
  if (options.progress_total) options.progress_total->fetch_add(columns);
  const bool batched = kBatchedConeSums && cone_sums;
  backend.parallel_for(
      columns,
      CornerColumnPass{g.view, model, options.winding, options.level, block_winding, g.corner_value.data(), batched}, 4,
      options.progress);
  if constexpr (kBatchedConeSums)
    if (batched)
      backend.parallel_for(
          g.slots, CornerBatchPass{g.view, model, options.winding, options.level, block_winding, g.corner_value.data()},
          1);
  g.view.corner_value = g.corner_value.data();
}

// 4. Edges: those whose corners straddle the level, listed, each with its Hermite point and
// normal, and the tally of how their crossings were found.
template <class Backend>
Status find_edges(Backend& backend, const ModelView& model, const MeshingOptions& options, MemoryBudget& budget,
                  SparseGridArrays<Backend>& g, EdgeArrays<Backend>& e, MeshingStats& stats) {
  const uint64_t items = g.slots * kBlockItems;
  g.edge_mask.resize(items);
  g.edge_in_slot.resize(items);
  g.slot_first_edge.resize(g.slots);
  backend.parallel_for(items, EdgeMaskPass{g.view, g.edge_mask.data()});
  backend.parallel_for(
      g.slots, SlotOffsetsPass<EdgesOfCorner>{{g.edge_mask.data()}, g.edge_in_slot.data(), g.slot_first_edge.data()});
  e.total = backend.exclusive_scan(g.slot_first_edge.data(), g.slots, g.slot_first_edge.data());
  if (e.total >= kEmptyLane / 2)
    return {StatusCode::kOutOfMemory, "meshing: " + std::to_string(e.total) + " crossing edges, beyond 2^31"};
  if (Status s = budget.reserve(e.total * (sizeof(uint64_t) + sizeof(HermitePoint) + 2 * sizeof(uvec3)), "the edges");
      !s.ok())
    return s;
  g.view.edge_mask = g.edge_mask.data();
  g.view.edge_in_slot = g.edge_in_slot.data();
  g.view.slot_first_edge = g.slot_first_edge.data();
  e.edges.resize(e.total);
  backend.parallel_for(items, EdgeListPass{g.view, e.edges.data()});
  e.hermite.resize(e.total);
  if (options.progress_total) options.progress_total->fetch_add(e.total);
  const bool batched = kBatchedConeSums && sums_cone(model, options);
  const BlockWinding* block_winding = g.block_winding.size() ? g.block_winding.data() : nullptr;
  const int8_t* corner_jumps = g.corner_jumps.size() ? g.corner_jumps.data() : nullptr;
  const HermitePass walks{g.view,        model,        options.winding, options.level,
                          block_winding, corner_jumps, e.edges.data(),  e.hermite.data(),
                          batched,       batched,      batched};
  backend.parallel_for(e.total, walks, 16, options.progress);
  if constexpr (kBatchedConeSums)
    if (batched) {
#if GWNRT_HOST_LANES && defined(__AVX__)
      backend.parallel_for(g.slots, WalkBatchPass{walks, e.total}, 1);
#endif
      backend.parallel_for(g.slots,
                           RootBatchPass{g.view, model, options.winding, options.level, block_winding, e.edges.data(),
                                         e.total, e.hermite.data()},
                           1);
      backend.parallel_for(g.slots, NormalBatchPass{model, options.winding, e.edges.data(), e.total, e.hermite.data()},
                           1);
    }
  // Read by the corners and edges alone: their blocks go to the passes after.
  g.block_winding = typename Backend::template Array<BlockWinding>{};
  g.corner_jumps = typename Backend::template Array<int8_t>{};
  budget.release(g.slots * SparseGridArrays<Backend>::kBoundBytesPerSlot);
  stats.crossing_edges = e.total;
  typename Backend::template Array<unsigned long long> tally;  // HermiteTally's counters, zeroed
  tally.resize(kHermiteTallies);
  backend.parallel_for((e.total + kHermiteTallyRun - 1) / kHermiteTallyRun,
                       HermiteTally{e.hermite.data(), e.total, tally.data()}, 16);
  stats.sheet_edges = backend.to_host(tally, kTallySheet);
  stats.smooth_edges = backend.to_host(tally, kTallySmooth);
  stats.fallback_edges = backend.to_host(tally, kTallyFallback);
  stats.capped_edges = backend.to_host(tally, kTallyCapped);
  return Status::Ok();
}

// 5. Cell vertices: the cells around the crossing edges, one vertex per surface component of
// each, placed by its QEF (CellVertexPass).
template <class Backend>
Status solve_cell_vertices(Backend& backend, MemoryBudget& budget, SparseGridArrays<Backend>& g,
                           const EdgeArrays<Backend>& e, VertexArrays<Backend>& v, MeshingStats& stats) {
  const uint64_t items = g.slots * kBlockItems;
  g.cell_parts.resize(items);  // zeroed
  g.vertex_in_slot.resize(items);
  g.slot_first_vertex.resize(g.slots);
  backend.parallel_for(e.total, CellMarkPass{g.view, e.edges.data(), g.cell_parts.data()});
  typename Backend::template Array<unsigned long long> multi;
  multi.resize(1);
  backend.parallel_for(items, CellPartsPass{g.view, g.cell_parts.data(), multi.data()});
  stats.multi_component_cells = backend.to_host(multi, 0);
  g.view.cell_parts = g.cell_parts.data();
  backend.parallel_for(g.slots,
                       SlotOffsetsPass<VerticesOfCell>{{g.view}, g.vertex_in_slot.data(), g.slot_first_vertex.data()});
  v.total = backend.exclusive_scan(g.slot_first_vertex.data(), g.slots, g.slot_first_vertex.data());
  if (Status s = budget.reserve(v.total * (2 * sizeof(vec3) + sizeof(uint64_t)), "the vertices"); !s.ok()) return s;
  g.view.vertex_in_slot = g.vertex_in_slot.data();
  g.view.slot_first_vertex = g.slot_first_vertex.data();
  v.positions.resize(v.total);
  v.normals.resize(v.total);
  v.cell.resize(v.total);
  backend.parallel_for(items,
                       CellVertexPass{g.view, e.hermite.data(), v.positions.data(), v.normals.data(), v.cell.data()});
  return Status::Ok();
}

// 6. Faces: two triangles per crossing edge (QuadPass); an edge missing a cell gives empty ones.
template <class Backend>
void make_faces(Backend& backend, const SparseGridArrays<Backend>& g, const EdgeArrays<Backend>& e,
                const VertexArrays<Backend>& v, typename Backend::template Array<uvec3>& triangles) {
  triangles.resize(2 * e.total);
  backend.parallel_for(e.total,
                       QuadPass{g.view, e.edges.data(), e.hermite.data(), v.positions.data(), triangles.data()});
}

// 6b. Repair: the pairs of triangles that meet other than in a shared vertex or edge found
// exactly, cell by cell, and their vertices moved toward their safe points, the cells around the
// moved ones tested again, for at most kRepairRounds rounds (dual_contouring.h).
template <class Backend>
Status repair_self_intersections(Backend& backend, const MeshingOptions& options, MemoryBudget& budget,
                                 const SparseGridArrays<Backend>& g, VertexArrays<Backend>& v,
                                 const typename Backend::template Array<uvec3>& triangles, MeshingStats& stats) {
  if (!options.repair_self_intersections) return Status::Ok();
  const uint64_t items = g.slots * kBlockItems;
  const uint64_t flag_bytes = (v.total + dirty_words(items)) * sizeof(uint32_t);
  if (Status s = budget.reserve(flag_bytes, "the repair's flags"); !s.ok()) return s;
  typename Backend::template Array<uint32_t> flag, dirty;
  flag.resize(v.total);                                        // zeroed
  typename Backend::template Array<unsigned long long> moves;  // VertexRepairPass's count, zeroed
  moves.resize(1);
  for (int round = 0;; ++round) {
    typename Backend::template Array<unsigned long long> pairs;
    pairs.resize(1);
    backend.parallel_for(v.total,
                         SelfIntersectionPass{g.view, v.cell.data(), triangles.data(), v.positions.data(),
                                              round == 0 ? nullptr : dirty.data(), flag.data(), pairs.data()},
                         64);
    const unsigned long long found = backend.to_host(pairs, 0);
    if (round == 0) stats.self_intersections_repaired = found;
    stats.self_intersections_left = found;
    if (found == 0 || round == kRepairRounds) break;
    typename Backend::template Array<uint32_t> fresh;
    fresh.resize(dirty_words(items));  // zeroed
    dirty = std::move(fresh);
    backend.parallel_for(v.total, VertexRepairPass{g.view, v.cell.data(), v.positions.data(), flag.data(), dirty.data(),
                                                   round >= kRepairSnapRound, moves.data()});
    stats.repair_rounds = uint32_t(round + 1);
  }
  stats.repaired_vertex_moves = backend.to_host(moves, 0);
  budget.release(flag_bytes);
  return Status::Ok();
}

// 7. Normals: averaged with the neighbouring vertices within options.smooth_angle (none at 0).
template <class Backend>
void smooth_normals(Backend& backend, const MeshingOptions& options, const SparseGridArrays<Backend>& g,
                    VertexArrays<Backend>& v) {
  if (!(options.smooth_angle > 0.0f)) return;
  typename Backend::template Array<vec3> smoothed;
  smoothed.resize(v.total);
  backend.parallel_for(v.total, SmoothNormalsPass{g.view, v.cell.data(), v.normals.data(), smoothed.data(),
                                                  cosf(options.smooth_angle * kDegree)});
  v.normals = std::move(smoothed);
}

// 8. Output: the vertices moved out, the triangles without the empty ones (indexed).
template <class Backend>
void write_indexed_mesh(Backend& backend, VertexArrays<Backend>& v,
                        const typename Backend::template Array<uvec3>& triangles, SurfaceMesh& out,
                        MeshingStats& stats) {
  backend.move_out(v.positions, out.positions);
  backend.move_out(v.normals, out.normals);
  const uvec3* t = triangles.data();
  const uint64_t n = triangles.size();
  typename Backend::template Array<uvec3> kept_triangles;
  const uint64_t face_total = compact(
      backend, t, n, [=] GWNRT_PASS(uint64_t i) { return t[i].x != kEmptyLane; }, kept_triangles);
  backend.move_out(kept_triangles, out.triangles);
  stats.open_edges = (n - face_total) / 2;
}

// One meshing of S with this scout: the steps above in order.
template <class Backend>
Status contour(Backend& backend, const ModelView& model, const MeshingOptions& options, const MeshGrid& grid,
               const ScoutQuery& scout, SurfaceMesh& out, MeshingStats& stats) {
  detail::PassClock clock;
  detail::MemoryBudget budget(grid, options.memory_budget, stats);
  // The block map (needed_dense, is_slot and slot_of_block) has three words a block of the grid,
  // known now: a grid whose map alone is beyond the budget is refused before scouting.
  if (Status s = budget.reserve(grid.block_count() * 3 * sizeof(uint32_t), "the block map"); !s.ok()) return s;

  typename Backend::template Array<GridCoord> kept;
  if (Status s = detail::scout_blocks(backend, grid, scout, budget, kept); !s.ok()) return s;
  stats.active_blocks = kept.size();
  stats.seconds.scout = clock.lap();
  if (kept.size() == 0) {
    stats.message = "S does not meet the grid: no point has w above the level (an empty mesh)";
    return Status::Ok();
  }
  detail::SparseGridArrays<Backend> g;
  if (Status s = detail::assign_slots(backend, grid, kept, budget, g); !s.ok()) return s;
  stats.evaluated_blocks = g.slots;

  detail::evaluate_corners(backend, model, options, g);
  stats.seconds.corners = clock.lap();

  stats.corners = 0;
  detail::EdgeArrays<Backend> e;
  if (Status s = detail::find_edges(backend, model, options, budget, g, e, stats); !s.ok()) return s;
  stats.seconds.edges = clock.lap();
  if (e.total == 0) {
    stats.message = "S does not cross the grid: every corner is on one side of the level (an empty mesh)";
    return Status::Ok();
  }
  if (options.method == MeshingMethod::kMarchingCubes)
    return run_marching_cubes(backend, g.view, e.total, e.hermite, budget, clock, out, stats);

  detail::VertexArrays<Backend> v;
  if (Status s = detail::solve_cell_vertices(backend, budget, g, e, v, stats); !s.ok()) return s;
  stats.seconds.vertices = clock.lap();
  typename Backend::template Array<uvec3> triangles;
  detail::make_faces(backend, g, e, v, triangles);
  stats.seconds.faces = clock.lap();
  if (Status s = detail::repair_self_intersections(backend, options, budget, g, v, triangles, stats); !s.ok()) return s;
  stats.seconds.repair = clock.lap();
  detail::smooth_normals(backend, options, g, v);
  stats.seconds.smoothing = clock.lap();
  detail::write_indexed_mesh(backend, v, triangles, out, stats);
  stats.seconds.output = clock.lap();
  return Status::Ok();
}

}  // namespace detail

// Dual contouring of S on `grid` (its cells and blocks set, its arrays not yet). `scout` decides
// which blocks S may meet. Fills out (positions, normals, triangles; indexed) and stats. Marching
// cubes (options.method) shares the steps up to the edges. Scouting by the sheets trusts each
// triangle's classification at its centroid, but a triangle that other triangles cut (the
// intersecting parts of an assembly) can carry S on one side of the cut and not the other; when
// an edge S crosses is then left without its cells, S is meshed again with the scout bounded by
// the distance to M, which holds everywhere (MeshingStats::rescouted_open_edges).
template <class Backend>
Status run_dual_contouring(Backend& backend, const ModelView& model, const MeshingOptions& options,
                           const MeshGrid& grid, const ScoutQuery& scout, SurfaceMesh& out, MeshingStats& stats) {
  const MeshingStats planned = stats;
  const Status first = detail::contour(backend, model, options, grid, scout, out, stats);
  if (!first.ok() || stats.open_edges == 0 || !scout.use_sheets) return first;
  const uint64_t open = stats.open_edges;
  const double first_seconds = stats.seconds.total();
  ScoutQuery by_mesh = scout;
  by_mesh.use_sheets = false;
  stats = planned;
  out = SurfaceMesh{};
  const Status again = detail::contour(backend, model, options, grid, by_mesh, out, stats);
  stats.rescouted_open_edges = open;
  stats.seconds.scout += first_seconds;  // the first meshing is part of the cost
  return again;
}

}  // namespace gwnrt
