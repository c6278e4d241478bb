// The passes of the mesher, each a per-item host-and-device function over trivially copyable
// views (the driver, meshing/mesh_pipeline.h, runs them over a backend) on the sparse grid of
// meshing/sparse_grid.h: scouting, corner values, edges and their Hermite data, cells and their
// vertices (where a cell's vertex is solved: CellVertexPass), quads, normals, and marching cubes.
#pragma once

#include <cstdint>

#include "gwnrt/base/atomics.h"
#include "gwnrt/field/box_winding.h"
#include "gwnrt/field/distance.h"
#include "gwnrt/field/evaluate_winding.h"
#include "gwnrt/field/ribbon_winding.h"
#include "gwnrt/geometry/exact_predicates.h"
#include "gwnrt/geometry/model_view.h"
#include "gwnrt/meshing/cell_topology.h"
#include "gwnrt/meshing/edge_hermite.h"
#include "gwnrt/meshing/qef.h"
#include "gwnrt/meshing/sparse_grid.h"
#include "gwnrt/sdf/signed_distance.h"

namespace gwnrt {

// ---------------------------------------------------------------------------------------------
// Scouting.

// Scouting keeps a block when the bound on the distance from its centre to S is at most its
// half-diagonal times this (float round-off of the bound's own terms is far below 1e-3).
inline constexpr float kScoutSlack = 1.001f;
// The scout levels (0: blocks of kBlockCells³) where the corners' first-order bounds may drop
// a block too: 8 and 16 cells (at 32 they settled too few to pay for themselves).
inline constexpr int kScoutBoundLevel = 1;

// The ray a block's first-order estimate of ŵ is taken along: the first of the six axis
// directions, nearest exit of M's box first, whose swept box holds no ∂M (its bounds usable),
// else the nearest exit's.
struct BlockRayChoice {
  int axis = 2;
  float sign = 1.0f;
  BoxFieldBounds bounds;
};
// boxes[0] is the block; with the bounds of boxes inside it too (boxes[1...]), from the same
// traversals (box_field_bounds): bounds[k] holds where the block's do.
template <int N>
GWNRT_HD inline BlockRayChoice choose_block_ray(const ModelView& model, const Aabb (&boxes)[N],
                                                BoxFieldBounds (&bounds)[N]) {
  const vec3 centre = boxes[0].centre();
  float exit[6];
  for (int d = 0; d < 6; ++d)
    exit[d] = d & 1 ? centre[d / 2] - model.bounds.lo[d / 2] : model.bounds.hi[d / 2] - centre[d / 2];
  int order[6] = {0, 1, 2, 3, 4, 5};
  for (int i = 1; i < 6; ++i)
    for (int j = i; j > 0 && exit[order[j]] < exit[order[j - 1]]; --j) {
      const int t = order[j];
      order[j] = order[j - 1];
      order[j - 1] = t;
    }
  BlockRayChoice out;
  for (int i = 0; i < 6; ++i) {
    const int axis = order[i] / 2;
    const float sign = order[i] & 1 ? -1.0f : 1.0f;
    BoxFieldBounds tried[N];
    box_field_bounds(model, boxes, axis, sign, tried);
    if (i == 0 || tried[0].usable) {
      out = {axis, sign, tried[0]};
      for (int k = 0; k < N; ++k) bounds[k] = tried[k];
    }
    if (tried[0].usable) break;
  }
  return out;
}

GWNRT_HD inline BlockRayChoice choose_block_ray(const ModelView& model, const Aabb& block) {
  const Aabb boxes[1] = {block};
  BoxFieldBounds bounds[1];
  return choose_block_ray(model, boxes, bounds);
}

// The jumps of `tree`'s triangles ahead of x along the ray (axis, sign).
GWNRT_HD inline int jumps_ahead(const TriangleTreeView& tree, const vec3& x, int axis, float sign) {
  const float u[1] = {x[(axis + 1) % 3]}, v[1] = {x[(axis + 2) % 3]}, along[1] = {x[axis]};
  int jumps[1][1];
  jumps_along_axis_lattice(tree, u, v, along, axis, sign, jumps);
  return jumps[0][0];
}

// Below this many points a batch is not worth its traversal of the ribbon tree for the points'
// box, and they are summed one by one. One: the ribbon tree's traversal for a single point costs
// less than the cone's crossing method (the scan's corners took a tenth less than at 4).
inline constexpr int kMinBatch = 1;

#if GWNRT_HOST_LANES && defined(__AVX__)
// taylor_point (at `beta`) at n <= N <= 64 points, each along its own ray (axis[k], sign[k]):
// those that share a ray from one batched traversal of the ribbon tree (ŵ: the ribbons swept
// opposite that ray, which is w plus M's jumps ahead; ∇w), the others and those the batch is
// unsure of one by one. ok[k]: taylor_point's result.
template <int N>
inline void taylor_points(const ModelView& model, const vec3* x, const int* axis, const float* sign, int n,
                          TaylorPoint* out, bool* ok, float beta = kTaylorPointBeta) {
  static_assert(N <= 64);
  uint64_t pending = n >= 64 ? ~uint64_t(0) : (uint64_t(1) << n) - 1u;
  while (pending != 0) {  // one batch for each ray among them
    const int first = __builtin_ctzll(pending);
    RibbonWindingBatch<N, true> batch;
    int in_batch[N];
    for (uint64_t rest = pending; rest != 0; rest &= rest - 1) {
      const int k = __builtin_ctzll(rest);
      if (axis[k] != axis[first] || sign[k] != sign[first]) continue;
      pending &= ~(uint64_t(1) << k);
      in_batch[batch.count] = k;
      batch.add(x[k]);
    }
    const bool batched = batch.count >= kMinBatch;
    if (batched) batch.evaluate(model.ribbons, beta, axis[first], sign[first]);
    for (int j = 0; j < batch.count; ++j) {
      const int k = in_batch[j];
      if (batched) {
        out[k].w_hat = batch.winding(j);
        out[k].gradient = batch.winding_gradient(j);
      }
      ok[k] = (batched && out[k].finite()) || taylor_point(model, x[k], axis[k], sign[k], out[k], beta);
    }
  }
}
#endif

// Blocks the scout takes at once (ScoutQuery::may_meet_batch): eight blocks' children.
inline constexpr int kScoutBatch = 64;
// A block's first-order centres (ScoutQuery, BlockWindingPass): its own and its eighths'.
inline constexpr int kBlockWindingPoints = 1 + 8;

// Whether S may meet the box [lo, hi]: a sheet meets it, or a lower bound on the distance from
// its centre to the level set is not above its half-diagonal. S lies on the sheets (or on M, when the sheets were
// classified for another level or inexactly) and on the level set of φ off M (level_set_distance_bound).
struct ScoutQuery {
  ModelView model;
  float level = 0.5f;
  float beta = 2.0f;
  bool use_sheets = false;
  // Blocks of the finest levels (by_bounds) that the level set's distance bound keeps are
  // dropped where the block's first-order estimate of ŵ (BlockWindingPass's) settles w − w* over
  // all of it: with the exact method and a cone, where the corners take the same bounds.
  bool settle_by_bounds = false;

  // With by_eighths (the finest level) a block its own estimate leaves unsettled may be settled
  // eighth by eighth (settled_by_bounds).
  GWNRT_HD bool may_meet(const vec3& lo, const vec3& hi, bool by_bounds = false, bool by_eighths = false) const {
    const Nearness n = nearness({lo, hi});
    if (n != Nearness::kLevelSet) return n == Nearness::kSheet;
    return !(by_bounds && settle_by_bounds && settled_by_bounds({lo, hi}, by_eighths));
  }

  // The distance tests alone: a sheet (or M) meeting the block, else S farther than the block's
  // half-diagonal from its centre, or only the level set's bound keeping it. With `sheets_only` the level set's bound
  // is not asked for (kLevelSet: it may keep the block).
  enum class Nearness { kFar, kSheet, kLevelSet };
  GWNRT_HD Nearness nearness(const Aabb& block, bool sheets_only = false) const {
    if (any_meets_box(use_sheets ? model.sheets : model.triangles, block)) return Nearness::kSheet;
    return sheets_only || level_set_keeps(block) ? Nearness::kLevelSet : Nearness::kFar;
  }
  // Whether the level set's distance bound from the block's centre is within its half-diagonal.
  GWNRT_HD bool level_set_keeps(const Aabb& block) const {
    const float radius = kScoutSlack * 0.5f * glm::length(block.hi - block.lo);
    return level_set_distance_bound(model, block.centre(), level, beta, radius) <= radius;
  }

  // No sheet within the block (the caller's distance), and ŵ's range over it holds no w* + n:
  // w = ŵ − J_M with J_M a whole number, so w ≠ w* off M, and on M S is sheets alone. With
  // by_eighths, where the block's estimate leaves some of it unsettled, each eighth is settled by
  // the block's estimate or by its own centre's (at kEighthPointBeta, with its own bounds), as
  // BlockWindingPass settles corners: half the blocks kept by a scan's rims held no vertex.
  GWNRT_HD bool settled_by_bounds(const Aabb& block, bool by_eighths = false) const {
    const BlockRayChoice ray = choose_block_ray(model, block);
    if (!ray.bounds.usable) return false;
    TaylorPoint p;
    if (!taylor_point(model, block.centre(), ray.axis, ray.sign, p)) return false;
    if (!taylor_may_leave_unsettled(p, ray.bounds, block.centre(), block, level)) return true;
    Aabb boxes[kBlockWindingPoints];
    BoxFieldBounds bounds[kBlockWindingPoints];
    block_and_eighths(block, boxes);
    uint32_t wanted;
    if (!by_eighths || !eighths_to_settle(p, ray, boxes, bounds, wanted)) return false;
    for (; wanted != 0; wanted &= wanted - 1) {
      const int i = 1 + lowest_set_bit(wanted);
      TaylorPoint q;
      if (!taylor_point(model, boxes[i].centre(), ray.axis, ray.sign, q, kEighthPointBeta) ||
          taylor_may_leave_unsettled(q, bounds[i], boxes[i].centre(), boxes[i], level))
        return false;
    }
    return true;
  }

  // For a block (boxes[0], its eighths after it: block_and_eighths) that the estimate p from its
  // centre along `ray` leaves unsettled: the eighths whose own centres must settle them (bit i for
  // boxes[1 + i]), their bounds along the ray in bounds[1...] (bounds[0] the ray's). False where
  // the block is kept without trying: the estimate itself crosses a level (S most likely meets
  // the block), or an eighth it leaves has no usable bounds.
  GWNRT_HD bool eighths_to_settle(const TaylorPoint& p, const BlockRayChoice& ray,
                                  const Aabb (&boxes)[kBlockWindingPoints],
                                  BoxFieldBounds (&bounds)[kBlockWindingPoints], uint32_t& wanted) const {
    const vec3 centre = boxes[0].centre();
    if (taylor_may_leave_unsettled(p, ray.bounds, centre, boxes[0], level, false)) return false;
    box_field_bounds(model, boxes, ray.axis, ray.sign, bounds);
    bounds[0] = ray.bounds;
    wanted = 0;
    for (int i = 1; i < kBlockWindingPoints; ++i) {
      if (!taylor_may_leave_unsettled(p, ray.bounds, centre, boxes[i], level)) continue;
      if (!bounds[i].usable) return false;
      wanted |= 1u << (i - 1);
    }
    return true;
  }

  // boxes[0] the block, boxes[1 + i] its eighth i (index x + 2y + 4z), split at its centre.
  GWNRT_HD static void block_and_eighths(const Aabb& block, Aabb (&boxes)[kBlockWindingPoints]) {
    const vec3 c = block.centre();
    boxes[0] = block;
    for (int i = 0; i < 8; ++i)
      for (int a = 0; a < 3; ++a) {
        const bool upper = (i >> a) & 1;
        boxes[1 + i].lo[a] = upper ? c[a] : block.lo[a];
        boxes[1 + i].hi[a] = upper ? block.hi[a] : c[a];
      }
  }

#if GWNRT_HOST_LANES && defined(__AVX__)
  // may_meet(·, ·, true) of up to 8 blocks (siblings, so near each other), their centres' sums
  // as batches (taylor_points). With `bounds_first` (the finest level, where the level set's
  // bound dropped 164 of the scan's 11,672 blocks and the first-order bounds 7,601) the bounds
  // are asked before the level set's distance, which only the blocks they leave take.
  // With `bounds_first` the eighths too (settled_by_bounds' by_eighths), their centres in
  // batches of 64 points. Up to kScoutBatch blocks: the children of eight neighbouring blocks,
  // whose centres share a traversal (a point cost 2.6 times as much in batches of eight).
  void may_meet_batch(const Aabb* blocks, int n, bool* out, bool bounds_first = false) const {
    vec3 centre[kScoutBatch]{};
    int axis[kScoutBatch]{}, pending[kScoutBatch]{}, count = 0;
    float sign[kScoutBatch]{};
    Aabb boxes[kScoutBatch][kBlockWindingPoints];
    BoxFieldBounds bounds[kScoutBatch][kBlockWindingPoints];
    for (int k = 0; k < n; ++k) {
      const Nearness near = nearness(blocks[k], bounds_first && settle_by_bounds);
      out[k] = near != Nearness::kFar;
      if (near != Nearness::kLevelSet || !settle_by_bounds) continue;
      const BlockRayChoice ray = choose_block_ray(model, blocks[k]);
      if (!ray.bounds.usable) {
        out[k] = !bounds_first || level_set_keeps(blocks[k]);
        continue;
      }
      block_and_eighths(blocks[k], boxes[count]);
      centre[count] = blocks[k].centre();
      axis[count] = ray.axis;
      sign[count] = ray.sign;
      bounds[count][0] = ray.bounds;
      pending[count++] = k;
    }
    TaylorPoint p[kScoutBatch];
    bool ok[kScoutBatch];
    taylor_points<kScoutBatch>(model, centre, axis, sign, count, p, ok);
    // Per pending block: kept, unless its estimate settles it whole or its eighths below do.
    bool keep[kScoutBatch];
    constexpr int kMids = 8 * kScoutBatch;
    vec3 mid_centre[kMids];
    int mid_axis[kMids], mid_of[kMids], mid_count = 0;
    float mid_sign[kMids];
    for (int j = 0; j < count; ++j) {
      keep[j] = !ok[j];
      if (keep[j] || !taylor_may_leave_unsettled(p[j], bounds[j][0], centre[j], boxes[j][0], level)) continue;
      uint32_t wanted;
      keep[j] =
          !bounds_first || !eighths_to_settle(p[j], {axis[j], sign[j], bounds[j][0]}, boxes[j], bounds[j], wanted);
      if (keep[j]) continue;
      for (; wanted != 0; wanted &= wanted - 1) {
        const int i = 1 + lowest_set_bit(wanted);
        mid_centre[mid_count] = boxes[j][i].centre();
        mid_axis[mid_count] = axis[j];
        mid_sign[mid_count] = sign[j];
        mid_of[mid_count++] = kBlockWindingPoints * j + i;
      }
    }
    for (int first = 0; first < mid_count; first += 64) {  // taylor_points takes 64 at most
      const int run = mid_count - first < 64 ? mid_count - first : 64;
      TaylorPoint mid[64];
      bool mid_ok[64];
      taylor_points<64>(model, mid_centre + first, mid_axis + first, mid_sign + first, run, mid, mid_ok,
                        kEighthPointBeta);
      for (int m = 0; m < run; ++m) {
        const int j = mid_of[first + m] / kBlockWindingPoints, i = mid_of[first + m] % kBlockWindingPoints;
        if (!mid_ok[m] || taylor_may_leave_unsettled(mid[m], bounds[j][i], mid_centre[first + m], boxes[j][i], level))
          keep[j] = true;
      }
    }
    for (int j = 0; j < count; ++j) out[pending[j]] = keep[j] && (!bounds_first || level_set_keeps(blocks[pending[j]]));
  }
#endif
};

// ---------------------------------------------------------------------------------------------
// Corner values.

// Whether corner `local` of a slot is read by some active block's cells: block b − d reads the
// corners of b whose coordinate is 0 along each axis set in d.
GWNRT_HD inline bool corner_needed(uint32_t needed_from, const GridCoord& local) {
  const uint32_t zero_axes = uint32_t(local.x == 0) | (uint32_t(local.y == 0) << 1) | (uint32_t(local.z == 0) << 2);
  for (uint32_t d = 0; d < 8; ++d)
    if (((needed_from >> d) & 1u) && (d & ~zero_axes) == 0) return true;
  return false;
}

// The corners need w exactly only where its sign is in doubt: a column is first evaluated with
// the ribbon tree's clusters expanded beyond kCornerScreenBeta radii, the corners within
// kCornerScreenMargin of the level again beyond kCornerRefineBeta, and only those within
// kCornerRefineMargin of it at the crossing method's own beta. The screen's error stayed below
// 1.7e-3 at beta 1.5 on every real and bundled open mesh at 256³ (the scan's rims; 5.2e-4 at 2),
// the refinement's within 1e-4 at 3 (edge_hermite.h): each margin is ten times or more its error,
// so off them the sign, which is all the mesh's topology reads, is the exact one. On a scan most
// corners in doubt are by its rim, where w at beta 5 costs three times w at 3 and the screen at
// 1.5 a fifth less than at 2 (docs/performance.md).
inline constexpr float kCornerScreenBeta = 1.5f;
inline constexpr float kCornerScreenMargin = 2e-2f;
inline constexpr float kCornerRefineBeta = kRootSearchConeBeta;
inline constexpr float kCornerRefineMargin = 2e-3f;

// w at a corner from M's jumps ahead of it, given its refined value: exact near the level.
GWNRT_HD inline float exact_corner_winding(const ModelView& m, const vec3& x, int axis, float sign, int mesh_jumps,
                                           float level, float refined) {
  return fabsf(refined - level) < kCornerRefineMargin ? winding_from_mesh_jumps(m, x, axis, sign, mesh_jumps) : refined;
}

// The same given its screened value: refined near the level, then exact nearer.
GWNRT_HD inline float refined_corner_winding(const ModelView& m, const vec3& x, int axis, float sign, int mesh_jumps,
                                             float level, float screened) {
  if (!(fabsf(screened - level) < kCornerScreenMargin)) return screened;
  return exact_corner_winding(m, x, axis, sign, mesh_jumps, level,
                              winding_from_mesh_jumps(m, x, axis, sign, mesh_jumps, kCornerRefineBeta));
}

// w at a corner from M's jumps ahead of it: screened, refined, then exact near the level.
GWNRT_HD inline float corner_winding_value(const ModelView& m, const vec3& x, int axis, float sign, int mesh_jumps,
                                           float level) {
  return refined_corner_winding(m, x, axis, sign, mesh_jumps, level,
                                winding_from_mesh_jumps(m, x, axis, sign, mesh_jumps, kCornerScreenBeta));
}

// The axis ray a block's corners take: the one by which its centre (corner 4, 4, 4 of the block)
// leaves M's box soonest.
struct BlockRay {
  int axis;
  float sign;
};
GWNRT_HD inline BlockRay block_ray(const MeshGrid& grid, const Aabb& bounds, const GridCoord& b) {
  const int32_t half = kBlockCells / 2;
  const vec3 centre =
      grid.corner_position({b.x * kBlockCells + half, b.y * kBlockCells + half, b.z * kBlockCells + half});
  const RayFrame exit = shortest_exit_axis_ray(bounds, centre);
  return {exit.kz, exit.sz > 0.0f ? 1.0f : -1.0f};
}

// Whether the cone sums of a slot's corners in doubt, eighths' centres and smooth roots go as
// batches (CornerBatchPass, BlockWindingPass, RootBatchPass, NormalBatchPass): where the host's
// lanes batch them (docs/performance.md: the scan); the device sums a point per thread.
#if GWNRT_HOST_LANES && defined(__AVX__)
inline constexpr bool kBatchedConeSums = true;
#else
inline constexpr bool kBatchedConeSums = false;
#endif

// Per slot, with the exact method and a cone (field/box_winding.h): bounds on ∇w and H_w and
// first-order centres at two scales: the block (8³ corners) and its eighths (4³: their own,
// tighter bounds) where the block's estimate may leave some of their corners unsettled or the
// block has no bounds (∂M in it). (A centre's ∇w costs about as much as the exact values of the
// eight corners of a 2³ eighth's eighth: such centres cost more than they saved.) The block's
// ray is the first of the six axis directions, nearest exit first, whose swept box holds no ∂M
// (else the nearest exit's). A corner takes the finer centre that holds it.
struct BlockWinding {
  BoxFieldBounds bounds[9];  // the block, its eighths (index x + 2y + 4z)
  uint32_t mid = 0;          // bit i: point[1 + i] computed
  bool block = false;        // point[0] computed
  int32_t axis = 2;
  float sign = 1.0f;
  TaylorPoint point[kBlockWindingPoints];
  GWNRT_HD bool any() const { return block || mid; }
};

// The box of the corners [first, first + count) of block b along each axis.
GWNRT_HD inline Aabb corner_box(const MeshGrid& grid, const GridCoord& b, const GridCoord& first, int count) {
  Aabb box;
  box.lo =
      grid.corner_position({b.x * kBlockCells + first.x, b.y * kBlockCells + first.y, b.z * kBlockCells + first.z});
  box.hi = grid.corner_position({b.x * kBlockCells + first.x + count - 1, b.y * kBlockCells + first.y + count - 1,
                                 b.z * kBlockCells + first.z + count - 1});
  return box;
}

// A first-order centre of a block (BlockWinding) and the bounds it is read with, which hold on
// the centre's own corners, [first, first + count) along each axis.
struct TaylorCentre {
  const TaylorPoint* point = nullptr;
  const BoxFieldBounds* bounds = nullptr;
  GridCoord first;
  int count = 0;
  GWNRT_HD vec3 centre(const MeshGrid& grid, const GridCoord& b) const {
    return corner_box(grid, b, first, count).centre();
  }
};

// The centres computed for corner `local` of a block, finer first: its eighth, the block.
GWNRT_HD inline int taylor_centres(const BlockWinding& w, const GridCoord& local, TaylorCentre (&out)[2]) {
  const int mid = local.x / 4 + 2 * (local.y / 4) + 4 * (local.z / 4);
  int n = 0;
  if ((w.mid >> mid) & 1u)
    out[n++] = {&w.point[1 + mid], &w.bounds[1 + mid], {local.x & ~3, local.y & ~3, local.z & ~3}, 4};
  if (w.block) out[n++] = {&w.point[0], &w.bounds[0], {0, 0, 0}, kBlockCells};
  return n;
}

struct BlockWindingPass {
  SparseGridView view;
  ModelView model;
  float level;
  BlockWinding* out;

  GWNRT_HD void operator()(uint64_t slot) const {
    const GridCoord b = begin(slot);
    BlockWinding& w = out[slot];
    if (w.bounds[0].usable) w.block = taylor_point(model, block_box(b).centre(), w.axis, w.sign, w.point[0]);
    finish(slot, b);
  }

  GWNRT_HD Aabb block_box(const GridCoord& b) const { return corner_box(view.grid, b, {0, 0, 0}, kBlockCells); }

  // The slot's block, its BlockWinding cleared and its ray chosen.
  GWNRT_HD GridCoord begin(uint64_t slot) const {
    BlockWinding& w = out[slot];
    w = BlockWinding{};
    const GridCoord b = view.grid.block_of_index(view.block_of_slot[slot]);
    const Aabb block = block_box(b);
    choose_ray(b, block, w);
    return b;
  }

  // After the block's centre (w.block): the eighths whose centres are wanted, where the block's
  // estimate leaves corners unsettled (their bounds set), among those that hold a corner some
  // block reads (a neighbour's slot is read on its lower faces alone).
  GWNRT_HD uint32_t wanted_eighths(uint64_t slot, const GridCoord& b) const {
    BlockWinding& w = out[slot];
    const Aabb block = block_box(b);
    const vec3 centre = block.centre();
    if (w.block && !taylor_may_leave_unsettled(w.point[0], w.bounds[0], centre, block, level)) return 0;
    uint32_t wanted = 0;
    const uint32_t needed_from = view.needed_from[slot];
    for (int i = 0; i < 8; ++i) {
      // Eighth i holds a corner with local coordinate 0 along axis a only where bit a of i is 0;
      // block b − d reads the corners of b at 0 along each axis of d (corner_needed).
      bool read = false;
      for (uint32_t d = 0; d < 8; ++d) read = read || (((needed_from >> d) & 1u) && (d & uint32_t(i)) == 0);
      if (!read) continue;
      const Aabb mid = eighth_box(b, i);
      if (w.block && !taylor_may_leave_unsettled(w.point[0], w.bounds[0], centre, mid, level)) continue;
      if (!w.bounds[0].usable) w.bounds[1 + i] = box_field_bounds(model, mid, w.axis, w.sign);
      if (w.bounds[1 + i].usable) wanted |= 1u << i;
    }
    return wanted;
  }

  // Then those centres, one by one.
  GWNRT_HD void finish(uint64_t slot, const GridCoord& b) const {
    BlockWinding& w = out[slot];
    for (uint32_t wanted = wanted_eighths(slot, b); wanted != 0; wanted &= wanted - 1) {
      const int i = lowest_set_bit(wanted);
      if (taylor_point(model, eighth_box(b, i).centre(), w.axis, w.sign, w.point[1 + i], kEighthPointBeta))
        w.mid |= 1u << i;
    }
  }

  // The box of eighth i (index x + 2y + 4z) of block b's corners.
  GWNRT_HD Aabb eighth_box(const GridCoord& b, int i) const {
    return corner_box(view.grid, b, {4 * (i & 1), 4 * ((i >> 1) & 1), 4 * (i >> 2)}, 4);
  }

#if GWNRT_HOST_LANES && defined(__AVX__)
  // The blocks of a 2 × 2 × 2 group at once, by the group's first slot (the others do nothing):
  // their centres from one batched traversal of the ribbon tree for each ray among them
  // (taylor_points), then all the eighths' centres they want likewise (as many as 64 points, so
  // that the traversal and the local expansions serve many chunks), as taylor_point gives them.
  // Slots are in block order, so the group's first slot is its first block's.
  void group(uint64_t slot) const {
    const GridCoord b = view.grid.block_of_index(view.block_of_slot[slot]);
    const GridCoord g{b.x & ~1, b.y & ~1, b.z & ~1};
    uint64_t member[8];
    GridCoord member_block[8];
    int members = 0;
    for (int i = 0; i < 8; ++i) {
      const GridCoord m{g.x + (i & 1), g.y + ((i >> 1) & 1), g.z + (i >> 2)};
      if (m.x >= view.grid.blocks[0] || m.y >= view.grid.blocks[1] || m.z >= view.grid.blocks[2]) continue;
      const uint32_t s = view.slot_of_block[view.grid.block_index(m.x, m.y, m.z)];
      if (s == kEmptyLane) continue;
      if (members == 0 && s != slot) return;  // not the group's first
      member[members] = s;
      member_block[members++] = m;
    }
    vec3 centre[8]{};
    int axis[8]{}, wanted[8]{}, count = 0;
    float sign[8]{};
    for (int i = 0; i < members; ++i) {
      begin(member[i]);
      const BlockWinding& w = out[member[i]];
      if (!w.bounds[0].usable) continue;
      centre[count] = block_box(member_block[i]).centre();
      axis[count] = w.axis;
      sign[count] = w.sign;
      wanted[count++] = i;
    }
    TaylorPoint p[8];
    bool ok[8];
    taylor_points<8>(model, centre, axis, sign, count, p, ok);
    for (int j = 0; j < count; ++j) {
      BlockWinding& w = out[member[wanted[j]]];
      w.point[0] = p[j];
      w.block = ok[j];
    }
    vec3 mid_centre[64];
    int mid_axis[64], mid_of[64], mid_count = 0;
    float mid_sign[64];
    for (int i = 0; i < members; ++i) {
      const BlockWinding& w = out[member[i]];
      for (uint32_t rest = wanted_eighths(member[i], member_block[i]); rest != 0; rest &= rest - 1) {
        const int e = lowest_set_bit(rest);
        mid_centre[mid_count] = eighth_box(member_block[i], e).centre();
        mid_axis[mid_count] = w.axis;
        mid_sign[mid_count] = w.sign;
        mid_of[mid_count++] = 8 * i + e;
      }
    }
    TaylorPoint mid[64];
    bool mid_ok[64];
    taylor_points<64>(model, mid_centre, mid_axis, mid_sign, mid_count, mid, mid_ok, kEighthPointBeta);
    for (int j = 0; j < mid_count; ++j) {
      BlockWinding& w = out[member[mid_of[j] / 8]];
      w.point[1 + mid_of[j] % 8] = mid[j];
      if (mid_ok[j]) w.mid |= 1u << (mid_of[j] % 8);
    }
  }
#endif

  // The block's ray (choose_block_ray) and its bounds, and its eighths' where the block's are
  // usable (from the same traversal; else each eighth's own, in wanted_eighths).
  GWNRT_HD void choose_ray(const GridCoord& b, const Aabb& block, BlockWinding& w) const {
    Aabb boxes[kBlockWindingPoints];  // the block and its eighths, as w.bounds holds them
    boxes[0] = block;
    for (int i = 0; i < 8; ++i) boxes[1 + i] = eighth_box(b, i);
    BoxFieldBounds bounds[kBlockWindingPoints];
    const BlockRayChoice ray = choose_block_ray(model, boxes, bounds);
    if (ray.bounds.usable)
      for (int i = 0; i < 8; ++i) w.bounds[1 + i] = bounds[1 + i];
    w.axis = ray.axis;
    w.sign = ray.sign;
    w.bounds[0] = ray.bounds;
  }

  // w − w* at corner `local` (at x) from the finer centre that holds it, or NaN.
  GWNRT_HD static float estimate(const MeshGrid& grid, const GridCoord& b, const BlockWinding& w,
                                 const GridCoord& local, const vec3& x, int jumps, float level) {
    TaylorCentre c[2];
    const int n = taylor_centres(w, local, c);
    for (int i = 0; i < n; ++i) {
      const float f = taylor_estimate(*c[i].point, *c[i].bounds, jumps, x - c[i].centre(grid, b), level);
      if (f == f) return f;
    }
    return __builtin_nanf("");
  }
};

// The ray a slot's corners take and whether M's jumps along it give them (the exact method):
// the bound's ray where BlockWindingPass made one, else block_ray.
struct CornerRay {
  int axis = 2;
  float sign = 1.0f;
  bool exact = false;
  const BlockWinding* bound = nullptr;
};
GWNRT_HD inline CornerRay corner_ray(const SparseGridView& view, const ModelView& model, const WindingOptions& winding,
                                     const BlockWinding* block_winding, uint32_t slot) {
  CornerRay r;
  r.exact = resolve_winding_method(model, winding.method) == WindingMethod::kCrossing;
  if (!r.exact) return r;
  if (block_winding && block_winding[slot].any()) {
    r.bound = block_winding + slot;
    r.axis = r.bound->axis;
    r.sign = r.bound->sign;
    return r;
  }
  const BlockRay ray = block_ray(view.grid, model.bounds, view.grid.block_of_index(view.block_of_slot[slot]));
  r.axis = ray.axis;
  r.sign = ray.sign;
  return r;
}

// The corner of a slot's column (column = l[u] + kBlockCells · l[v]) that is k-th along its ray.
GWNRT_HD inline GridCoord column_corner(uint32_t column, int k, int axis, float sign) {
  const int32_t cu = int32_t(column % kBlockCells), cv = int32_t(column / kBlockCells);
  const int32_t ck = sign > 0.0f ? k : kBlockCells - 1 - k;
  // Built whole, not by l[axis] = ...: a store by a runtime index read back at once stalls.
  return axis == 0 ? GridCoord{ck, cu, cv} : (axis == 1 ? GridCoord{cv, ck, cu} : GridCoord{cu, cv, ck});
}

// The jumps of `tree`'s triangles ahead of each corner of block b along (axis, sign), for all its
// columns in one walk: jumps[column][k] for the corner column_corner(column, k, axis, sign).
GWNRT_HD inline void block_jumps(const TriangleTreeView& tree, const MeshGrid& grid, const GridCoord& b, int axis,
                                 float sign, int (&jumps)[kBlockCells * kBlockCells][kBlockCells]) {
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  float cu[kBlockCells], cv[kBlockCells], along[kBlockCells];
  for (int k = 0; k < kBlockCells; ++k) {
    // Corner (k, k, k): a corner's coordinate along an axis depends on its index along it alone.
    const vec3 diagonal = grid.corner_position({b.x * kBlockCells + k, b.y * kBlockCells + k, b.z * kBlockCells + k});
    cu[k] = diagonal[u];
    cv[k] = diagonal[v];
    along[sign > 0.0f ? k : kBlockCells - 1 - k] = diagonal[axis];
  }
  jumps_along_axis_lattice(tree, cu, cv, along, axis, sign, jumps);
}

// A corner whose cone sum CornerColumnPass left to CornerBatchPass: M's jumps ahead of it in the
// payload of a negative quiet NaN (nonzero: the default NaN of arithmetic is 0xffc00000).
inline constexpr int32_t kDeferredJumpsLimit = 1 << 21;
GWNRT_HD inline float deferred_corner(int mesh_jumps) {
  return bits_float(0xffc00000u | uint32_t(mesh_jumps + kDeferredJumpsLimit));
}
GWNRT_HD inline bool is_deferred_corner(float f, int& mesh_jumps) {
  const uint32_t bits = float_bits(f);
  mesh_jumps = int32_t(bits & 0x3fffffu) - kDeferredJumpsLimit;
  return (bits & 0xffc00000u) == 0xffc00000u && (bits & 0x3fffffu) != 0;
}

// A kept corner's jumps (CornerJumpsPass::corner_jumps) that did not fit its byte, or were taken
// along no bound's ray.
inline constexpr int8_t kUnknownJumps = INT8_MIN;

// Per slot, with the exact method: M's jumps ahead of each corner along the slot's ray, for all
// its columns in one walk (block_jumps), stored in the corner's value by its bits until
// CornerColumnPass reads them and writes the value over them.
struct CornerJumpsPass {
  SparseGridView view;
  ModelView model;
  WindingOptions winding;
  const BlockWinding* block_winding;  // per slot, or nullptr
  float* corner_value;
  // Per item, or nullptr: the jumps again along the bound's ray, for the edges' bounds
  // (HermitePass::edge_bound), where a walk per edge had cost a tenth of the edges' time on a scan.
  int8_t* corner_jumps = nullptr;

  GWNRT_HD void operator()(uint64_t slot) const {
    const CornerRay ray = corner_ray(view, model, winding, block_winding, uint32_t(slot));
    if (!ray.exact) return;
    const GridCoord b = view.grid.block_of_index(view.block_of_slot[slot]);
    int jumps[kBlockCells * kBlockCells][kBlockCells];
    block_jumps(model.triangles, view.grid, b, ray.axis, ray.sign, jumps);
    float* out = corner_value + slot * kBlockItems;
    int8_t* kept = corner_jumps ? corner_jumps + slot * kBlockItems : nullptr;
    for (uint32_t column = 0; column < kBlockCells * kBlockCells; ++column)
      for (int k = 0; k < kBlockCells; ++k) {
        const uint32_t local = local_index(column_corner(column, k, ray.axis, ray.sign));
        const int j = jumps[column][k];
        out[local] = bits_float(uint32_t(j));
        if (kept) kept[local] = ray.bound && j > INT8_MIN && j <= INT8_MAX ? int8_t(j) : kUnknownJumps;
      }
  }
};

// One column of a slot's corners (item = slot · kBlockCells² + column): w − w* where needed, NaN
// elsewhere. With the exact method M's crossings ahead of each corner are CornerJumpsPass's,
// along the block's ray (corner_ray): fewer crossings and nodes on the way than a fixed +z.
// Where the block's bound (BlockWindingPass) settles a corner's sign, its value is that
// estimate (the sign exact, the size within the bound); else the cone is summed, or with
// defer_cone_sums left to CornerBatchPass (deferred_corner).
struct CornerColumnPass {
  SparseGridView view;
  ModelView model;
  WindingOptions winding;
  float level;
  const BlockWinding* block_winding;  // per slot, or nullptr
  float* corner_value;
  bool defer_cone_sums = false;

  GWNRT_HD void operator()(uint64_t item) const {
    const uint32_t slot = uint32_t(item / (kBlockCells * kBlockCells));
    const uint32_t column = uint32_t(item % (kBlockCells * kBlockCells));
    const GridCoord b = view.grid.block_of_index(view.block_of_slot[slot]);
    const uint32_t needed_from = view.needed_from[slot];
    const CornerRay ray = corner_ray(view, model, winding, block_winding, slot);
    const BlockWinding* bound = ray.bound;
    const int axis = ray.axis;
    const float sign = ray.sign;
    GridCoord local[kBlockCells];
    bool needed[kBlockCells];
    for (int k = 0; k < kBlockCells; ++k) {
      const GridCoord l = column_corner(column, k, axis, sign);  // ascending along the ray
      local[k] = l;
      const GridCoord c{b.x * kBlockCells + l.x, b.y * kBlockCells + l.y, b.z * kBlockCells + l.z};
      needed[k] = c.x <= view.grid.cells[0] && c.y <= view.grid.cells[1] && c.z <= view.grid.cells[2] &&
                  corner_needed(needed_from, l);
    }
    float* out = corner_value + uint64_t(slot) * kBlockItems;
    const auto position = [&](const GridCoord& l) {
      return view.grid.corner_position({b.x * kBlockCells + l.x, b.y * kBlockCells + l.y, b.z * kBlockCells + l.z});
    };
    if (ray.exact) {
      vec3 points[kBlockCells];
      int jumps[kBlockCells];
      for (int k = 0; k < kBlockCells; ++k) {
        points[k] = position(local[k]);
        jumps[k] = int(float_bits(out[local_index(local[k])]));
      }
      for (int k = 0; k < kBlockCells; ++k) {
        float f = __builtin_nanf("");
        if (needed[k]) {
          if (model.cone.triangle_count == 0) {  // no cone: the crossings alone, exact
            f = -float(jumps[k]) - level;
          } else {
            if (bound) f = BlockWindingPass::estimate(view.grid, b, *bound, local[k], points[k], jumps[k], level);
            if (!(f == f)) {
              if (defer_cone_sums && jumps[k] > -kDeferredJumpsLimit && jumps[k] < kDeferredJumpsLimit)
                f = deferred_corner(jumps[k]);
              else
                f = corner_winding_value(model, points[k], axis, sign, jumps[k], level) - level;
            }
          }
        }
        out[local_index(local[k])] = f;
      }
      return;
    }
    for (int k = 0; k < kBlockCells; ++k)
      out[local_index(local[k])] =
          needed[k] ? evaluate_winding(model, position(local[k]), winding).w - level : __builtin_nanf("");
  }
};

// Per slot, after CornerColumnPass with defer_cone_sums: the corners it left (deferred_corner)
// screened together, their ribbons (swept opposite the slot's ray) from one traversal for all
// of them (RibbonWindingBatch, at kCornerScreenBeta) less M's jumps ahead, those within kCornerScreenMargin of the
// level refined as another batch, the exact sums nearer the level one by one (corner_winding_value's steps). A corner
// the batch is unsure of, or a slot with few, takes corner_winding_value.
struct CornerBatchPass {
  SparseGridView view;
  ModelView model;
  WindingOptions winding;
  float level;
  const BlockWinding* block_winding;  // per slot, or nullptr
  float* corner_value;

  GWNRT_HD void operator()(uint64_t slot) const {
    float* out = corner_value + slot * kBlockItems;
    uint16_t deferred[kBlockItems];
    int count = 0, mesh_jumps;
    for (uint32_t i = 0; i < kBlockItems; ++i)
      if (is_deferred_corner(out[i], mesh_jumps)) deferred[count++] = uint16_t(i);
    if (count == 0) return;
    const CornerRay ray = corner_ray(view, model, winding, block_winding, uint32_t(slot));
    const GridCoord b = view.grid.block_of_index(view.block_of_slot[slot]);
#if GWNRT_HOST_LANES && defined(__AVX__)
    if (count >= kMinBatch) {
      batch_sums(b, ray, deferred, count, out);
      return;
    }
#endif
    for (int j = 0; j < count; ++j) {
      const uint32_t i = deferred[j];
      is_deferred_corner(out[i], mesh_jumps);
      out[i] = corner_winding_value(model, position(b, i), ray.axis, ray.sign, mesh_jumps, level) - level;
    }
  }

  GWNRT_HD vec3 position(const GridCoord& b, uint32_t i) const {
    const GridCoord l = local_coord(i);
    return view.grid.corner_position({b.x * kBlockCells + l.x, b.y * kBlockCells + l.y, b.z * kBlockCells + l.z});
  }

#if GWNRT_HOST_LANES && defined(__AVX__)
  // The deferred corners [deferred, deferred + count) of block b screened as one batch, those
  // within kCornerScreenMargin of the level refined as another, each finished one by one.
  void batch_sums(const GridCoord& b, const CornerRay& ray, const uint16_t* deferred, int count, float* out) const {
    RibbonWindingBatch<kBlockItems> batch;
    for (int j = 0; j < count; ++j) batch.add(position(b, deferred[j]));
    batch.evaluate(model.ribbons, kCornerScreenBeta, ray.axis, ray.sign);
    uint16_t near_level[kBlockItems];
    float near_value[kBlockItems];
    int near_count = 0, jumps;
    for (int j = 0; j < count; ++j) {
      const uint32_t i = deferred[j];
      is_deferred_corner(out[i], jumps);
      const float screened = batch.crossing_winding(j, jumps);
      if (!(screened == screened)) {
        out[i] = corner_winding_value(model, position(b, i), ray.axis, ray.sign, jumps, level) - level;
      } else if (fabsf(screened - level) < kCornerScreenMargin) {
        near_value[near_count] = screened;
        near_level[near_count++] = uint16_t(i);
      } else {
        out[i] = screened - level;
      }
    }
    const bool refine_in_batch = near_count >= kMinBatch;
    if (refine_in_batch) {
      batch.count = 0;
      for (int j = 0; j < near_count; ++j) batch.add(position(b, near_level[j]));
      batch.evaluate(model.ribbons, kCornerRefineBeta, ray.axis, ray.sign);
    }
    uint16_t nearer[kBlockItems];  // those within kCornerRefineMargin: the exact method's beta
    int nearer_jumps[kBlockItems], nearer_count = 0;
    for (int j = 0; j < near_count; ++j) {
      const uint32_t i = near_level[j];
      const vec3 x = position(b, i);
      is_deferred_corner(out[i], jumps);
      const float refined = refine_in_batch ? batch.crossing_winding(j, jumps) : __builtin_nanf("");
      if (refined == refined && fabsf(refined - level) < kCornerRefineMargin) {
        nearer_jumps[nearer_count] = jumps;
        nearer[nearer_count++] = uint16_t(i);
      }
      out[i] =
          (refined == refined ? refined
                              : refined_corner_winding(model, x, ray.axis, ray.sign, jumps, level, near_value[j])) -
          level;
    }
    // As exact_corner_winding, the batch at kConeBeta where it is sure.
    const bool exact_in_batch = nearer_count >= kMinBatch;
    if (exact_in_batch) {
      batch.count = 0;
      for (int j = 0; j < nearer_count; ++j) batch.add(position(b, nearer[j]));
      batch.evaluate(model.ribbons, kConeBeta, ray.axis, ray.sign);
    }
    for (int j = 0; j < nearer_count; ++j) {
      const uint32_t i = nearer[j];
      const float exact = exact_in_batch ? batch.crossing_winding(j, nearer_jumps[j]) : __builtin_nanf("");
      out[i] = (exact == exact ? exact
                               : winding_from_mesh_jumps(model, position(b, i), ray.axis, ray.sign, nearer_jumps[j])) -
               level;
    }
  }
#endif
};

GWNRT_HD inline bool is_inside(float f) { return f > 0.0f; }

// ---------------------------------------------------------------------------------------------
// Edges: each corner owns the three edges toward +x, +y, +z.

struct EdgeMaskPass {
  SparseGridView view;
  uint8_t* edge_mask;

  GWNRT_HD void operator()(uint64_t item) const {
    const float f = view.corner_value[item];
    uint32_t mask = 0;
    if (f == f) {
      const GridCoord local = local_coord(uint32_t(item % kBlockItems));
      for (int a = 0; a < 3; ++a) {
        const float g = view.next_corner_value(item, local, a);
        if (g == g && is_inside(f) != is_inside(g)) mask |= 1u << a;
      }
    }
    edge_mask[item] = uint8_t(mask);
  }
};

// Per slot: the running sum over its items of count(item) (its edges, its vertices) as offsets
// within the slot (in_slot), and the slot's total (slot_total, which an exclusive scan over the
// slots turns into their first indices).
template <class Count>
struct SlotOffsetsPass {
  Count count;
  uint16_t* in_slot;
  uint32_t* slot_total;
  GWNRT_HD void operator()(uint64_t slot) const {
    uint32_t sum = 0;
    for (uint64_t item = slot * kBlockItems; item < (slot + 1) * kBlockItems; ++item) {
      in_slot[item] = uint16_t(sum);
      sum += count(item);
    }
    slot_total[slot] = sum;
  }
};
struct EdgesOfCorner {
  const uint8_t* edge_mask;
  GWNRT_HD uint32_t operator()(uint64_t item) const { return uint32_t(bit_count(edge_mask[item])); }
};
struct VerticesOfCell {
  SparseGridView view;  // its cell_parts set
  GWNRT_HD uint32_t operator()(uint64_t item) const { return view.cell_vertex_count(item); }
};
static_assert(3 * kBlockItems <= 65535 && 4 * kBlockItems <= 65535, "a slot's offsets fit 16 bits");

// The edges listed: edge i = (corner item) · 4 + axis.
struct EdgeListPass {
  SparseGridView view;
  uint64_t* edges;
  GWNRT_HD void operator()(uint64_t item) const {
    uint32_t k = view.edge_offset(item);
    for (uint32_t mask = view.edge_mask[item]; mask != 0; mask &= mask - 1)
      edges[k++] = item * 4 + uint32_t(lowest_set_bit(mask));
  }
};

struct HermitePass {
  SparseGridView view;
  ModelView model;
  WindingOptions winding;
  float level;
  const BlockWinding* block_winding;  // per slot, or nullptr
  const int8_t* corner_jumps;         // per item (CornerJumpsPass), or nullptr
  const uint64_t* edges;
  HermitePoint* hermite;
  bool defer_normals = false;  // smooth roots' normals left to NormalBatchPass
  bool defer_roots = false;    // and their searches to RootBatchPass
  bool defer_values = false;   // and the values before crossings of M to WalkBatchPass

  GWNRT_HD void operator()(uint64_t i) const {
    const EdgeValues none{};
    hermite[i] = walk(i, defer_values ? &none : nullptr);
  }

  // Edge i's Hermite point, given the values before its crossings that its walk asked for.
  GWNRT_HD HermitePoint walk(uint64_t i, const EdgeValues* values) const {
    const uint64_t corner = edges[i] / 4;
    const int axis = int(edges[i] % 4);
    const GridCoord c = view.coord_of_item(corner);
    GridCoord n = c;
    ++n[axis];
    const vec3 p0 = view.grid.corner_position(c);
    EdgeBound bound;
    const bool bounded = block_winding && edge_bound(corner, axis, p0, bound);
    return edge_hermite(model, winding, level, p0, axis, view.grid.cell, view.corner_value[corner],
                        view.corner_value_at(n), bounded ? &bound : nullptr, defer_normals, defer_roots, values);
  }

  // The finer centre of the corner's block whose bounds' box holds the edge (both its ends), and
  // J at the corner along the block's ray.
  GWNRT_HD bool edge_bound(uint64_t corner, int axis, const vec3& p0, EdgeBound& out) const {
    const uint32_t slot = uint32_t(corner / kBlockItems);
    const BlockWinding& w = block_winding[slot];
    const GridCoord b = view.grid.block_of_index(view.block_of_slot[slot]);
    const GridCoord l = local_coord(uint32_t(corner % kBlockItems));
    TaylorCentre c[2];
    const int n = taylor_centres(w, l, c);
    int i = 0;
    while (i < n && l[axis] % c[i].count == c[i].count - 1) ++i;  // the edge leaves the bounds' box
    if (i == n) return false;
    out.point = *c[i].point;
    out.bounds = *c[i].bounds;
    out.centre = c[i].centre(view.grid, b);
    out.jumps = corner_jumps ? corner_jumps[corner] : kUnknownJumps;
    if (out.jumps == kUnknownJumps) {
      const vec3 points[1] = {p0};
      int jumps[1];
      mesh_jumps_along_axis(model, points, w.axis, w.sign, jumps);
      out.jumps = jumps[0];
    }
    return true;
  }
};

// The run [first, end) of the ascending edge list that holds the edges of slot `slot`.
GWNRT_HD inline void slot_edges(const uint64_t* edges, uint64_t edge_count, uint64_t slot, uint64_t& first,
                                uint64_t& end) {
  const uint64_t first_key = slot * kBlockItems * 4, end_key = (slot + 1) * kBlockItems * 4;
  uint64_t lo = 0, hi = edge_count;
  while (lo < hi) {
    const uint64_t mid = lo + (hi - lo) / 2;
    if (edges[mid] < first_key)
      lo = mid + 1;
    else
      hi = mid;
  }
  first = end = lo;
  while (end < edge_count && edges[end] < end_key) ++end;
}

// w − w* at x by crossings at kRootSearchConeBeta: what an edge's walk and root search take
// where a batch has no value.
GWNRT_HD inline float root_search_value(const ModelView& m, const vec3& x, float level) {
  return winding_number_crossing<false, false>(m, x, kRootSearchConeBeta).w - level;
}

#if GWNRT_HOST_LANES && defined(__AVX__)
// Per slot, after HermitePass with defer_values: the values its edges' walks stopped for (w − w*
// before a crossing of M, value_deferred) summed as one batch at kRootSearchConeBeta, as
// RootBatchPass sums its points, and the walks taken again with them, round after round until
// none stops (each walk stops at most kDeferredEdgeValues times, then sums alone).
struct WalkBatchPass {
  HermitePass walks;  // with defer_values
  uint64_t edge_count;

  void operator()(uint64_t slot) const {
    uint64_t first, end;
    slot_edges(walks.edges, edge_count, slot, first, end);
    const ModelView& model = walks.model;
    const CornerRay ray = corner_ray(walks.view, model, walks.winding, walks.block_winding, uint32_t(slot));
    HermitePoint* hermite = walks.hermite;
    RibbonWindingBatch<kBlockItems> batch;
    uint64_t index[kBlockItems];
    EdgeValues values[kBlockItems];
    for (uint64_t i = first; i < end;) {
      int count = 0;
      for (; i < end && count < int(kBlockItems); ++i)
        if (hermite[i].value_deferred) {
          values[count].count = 0;
          index[count++] = i;
        }
      int active[kBlockItems];
      for (int round = 0; round <= kDeferredEdgeValues; ++round) {
        batch.count = 0;
        for (int j = 0; j < count; ++j)
          if (hermite[index[j]].value_deferred) {
            active[batch.count] = j;
            batch.add(hermite[index[j]].point);
          }
        if (batch.count == 0) break;
        const bool batched = batch.count >= kMinBatch;
        if (batched) batch.evaluate(model.ribbons, kRootSearchConeBeta, ray.axis, ray.sign);
        for (int a = 0; a < batch.count; ++a) {
          const int j = active[a];
          const vec3 x = hermite[index[j]].point;
          const float w_hat = batched ? batch.winding(a) : __builtin_nanf("");
          values[j].value[values[j].count++] =
              w_hat == w_hat
                  ? batch.crossing_winding(a, jumps_ahead(model.triangles, x, ray.axis, ray.sign)) - walks.level
                  : root_search_value(model, x, walks.level);
          hermite[index[j]] = walks.walk(index[j], &values[j]);
        }
      }
    }
  }
};
#endif

// Per slot, after HermitePass with defer_roots: the searches of its edges' smooth roots
// (root_deferred) stepped together, each step's points as one batch of ribbon sums with ∇w at
// kRootSearchConeBeta (RibbonWindingBatch; M's jumps ahead along the slot's ray from each
// point's own walk), a point the batch is unsure of by winding_number_crossing as the search
// one by one takes it. ∂w along the edge is the search's slope (its next point Newton's), and ∇w
// at its last point the root's normal (kHermiteNormalBeta is the same beta): on the scan the
// normals' own batches had cost a quarter of the roots'. A root whose last value the batch was
// unsure of keeps its normal deferred (NormalBatchPass).
static_assert(kHermiteNormalBeta == kRootSearchConeBeta, "the roots' ∇w is their normals'");
struct RootBatchPass {
  SparseGridView view;
  ModelView model;
  WindingOptions winding;
  float level;
  const BlockWinding* block_winding;  // per slot, or nullptr
  const uint64_t* edges;              // ascending: a slot's edges are one run
  uint64_t edge_count;
  HermitePoint* hermite;

  // Edge i's start and direction.
  struct Line {
    vec3 p0, direction{0.0f};
    GWNRT_HD vec3 at(float t) const { return p0 + t * direction; }
  };
  GWNRT_HD Line line(uint64_t i) const {
    Line l;
    l.p0 = view.grid.corner_position(view.coord_of_item(edges[i] / 4));
    l.direction[int(edges[i] % 4)] = 1.0f;
    return l;
  }

  GWNRT_HD void operator()(uint64_t slot) const {
    uint64_t first, end;
    slot_edges(edges, edge_count, slot, first, end);
#if GWNRT_HOST_LANES && defined(__AVX__)
    const CornerRay ray = corner_ray(view, model, winding, block_winding, uint32_t(slot));
    RibbonWindingBatch<kBlockItems, true> batch;
    uint64_t index[kBlockItems];
    IllinoisBracket bracket[kBlockItems];
    vec3 gradient[kBlockItems];  // ∇w at each bracket's last point, or NaN
    for (uint64_t i = first; i < end;) {
      int count = 0;
      for (; i < end && count < int(kBlockItems); ++i)
        if (hermite[i].root_deferred) {
          bracket[count] = edge_bracket(i);
          gradient[count] = vec3(__builtin_nanf(""));
          index[count++] = i;
        }
      int active[kBlockItems];
      vec3 point[kBlockItems];
      for (int step = 0; step <= kMaxRootSteps; ++step) {  // each bracket takes at most kMaxRootSteps
        batch.count = 0;
        for (int j = 0; j < count; ++j)
          if (bracket[j].active()) {
            active[batch.count] = j;
            point[batch.count] = line(index[j]).at(bracket[j].next());
            batch.add(point[batch.count]);
          }
        if (batch.count == 0) break;
        const bool batched = batch.count >= kMinBatch;
        if (batched) batch.evaluate(model.ribbons, kRootSearchConeBeta, ray.axis, ray.sign);
        for (int a = 0; a < batch.count; ++a) {
          const int j = active[a];
          const vec3& x = point[a];
          // The jumps' walks only where the batch has a value.
          const float w_hat = batched ? batch.winding(a) : __builtin_nanf("");
          gradient[j] = w_hat == w_hat ? batch.winding_gradient(a) : vec3(__builtin_nanf(""));
          if (w_hat == w_hat)
            bracket[j].take(batch.crossing_winding(a, jumps_ahead(model.triangles, x, ray.axis, ray.sign)) - level,
                            gradient[j][int(edges[index[j]] % 4)]);
          else
            bracket[j].take(root_search_value(model, x, level));
        }
      }
      for (int j = 0; j < count; ++j) {
        finish(index[j], bracket[j]);
        // The normal from ∇w at the search's last point, within kRootTolerance of the edge from
        // the root.
        if (gradient[j].x == gradient[j].x) {
          HermitePoint& p = hermite[index[j]];
          p.normal = smooth_normal(gradient[j], p.normal);
          p.normal_deferred = false;
        }
      }
    }
#else
    for (uint64_t i = first; i < end; ++i) {
      if (!hermite[i].root_deferred) continue;
      const Line l = line(i);
      IllinoisBracket b = edge_bracket(i);
      while (b.active()) b.take(root_search_value(model, l.at(b.next()), level));
      finish(i, b);
    }
#endif
  }

  // Edge i's bracket; on a whole edge (no crossing of M on it), with its first point from the
  // corner values along its line (interpolated_root_guess).
  GWNRT_HD IllinoisBracket edge_bracket(uint64_t i) const {
    const float h = view.grid.cell;
    IllinoisBracket b = deferred_bracket(hermite[i], h);
    if (b.ta != 0.0f || b.tb != h) return b;
    const int axis = int(edges[i] % 4);
    GridCoord before = view.coord_of_item(edges[i] / 4), after = before;
    --before[axis];
    after[axis] += 2;
    float slope;
    const float guess =
        interpolated_root_guess(view.corner_value_at(before), b.fa, b.fb, view.corner_value_at(after), slope);
    if (guess == guess) {
      b.first_guess = h * guess;
      b.slope = slope / h;
    }
    return b;
  }

  // The root of edge i's finished search, its normal deferred.
  GWNRT_HD void finish(uint64_t i, const IllinoisBracket& b) const {
    const Line l = line(i);
    hermite[i] = smooth_root_point(model, winding, l.p0, l.direction, b, true);
  }
};

// Per slot, after RootBatchPass: the normals of its edges' smooth roots still deferred
// (normal_deferred) from one batched traversal of the ribbon tree for all of them (∇w, the
// Biot–Savart sum over ∂M: RibbonWindingBatch); a root the batch is unsure of takes smooth_root_gradient.
struct NormalBatchPass {
  ModelView model;
  WindingOptions winding;
  const uint64_t* edges;  // ascending: a slot's edges are one run
  uint64_t edge_count;
  HermitePoint* hermite;

  GWNRT_HD void operator()(uint64_t slot) const {
    uint64_t lo, end;
    slot_edges(edges, edge_count, slot, lo, end);
#if GWNRT_HOST_LANES && defined(__AVX__)
    RibbonWindingBatch<kBlockItems, true> batch;
    uint64_t index[kBlockItems];
    for (uint64_t i = lo; i < end;) {
      batch.count = 0;
      for (; i < end && batch.count < int(kBlockItems); ++i)
        if (hermite[i].normal_deferred) {
          index[batch.count] = i;
          batch.add(hermite[i].point);
        }
      if (batch.count < kMinBatch) {
        for (int j = 0; j < batch.count; ++j) finish(hermite[index[j]], vec3(__builtin_nanf("")));
        continue;
      }
      batch.evaluate(model.ribbons, kHermiteNormalBeta, -1, 1.0f);
      for (int j = 0; j < batch.count; ++j) finish(hermite[index[j]], batch.winding_gradient(j));
    }
#else
    for (uint64_t i = lo; i < end; ++i)
      if (hermite[i].normal_deferred) finish(hermite[i], vec3(__builtin_nanf("")));
#endif
  }

  // The normal from ∇w, or from smooth_root_gradient where it is NaN.
  GWNRT_HD void finish(HermitePoint& p, vec3 gradient) const {
    if (!(gradient.x == gradient.x)) gradient = smooth_root_gradient(model, winding, p.point);
    p.normal = smooth_normal(gradient, p.normal);
    p.normal_deferred = false;
  }
};

// How the edges' crossings were found, counted for MeshingStats: on the device the driver reads
// back four counters, not every edge.
enum HermiteTallyIndex : uint32_t { kTallySheet, kTallySmooth, kTallyFallback, kTallyCapped, kHermiteTallies };

// Item: a run of kHermiteTallyRun edges, counted locally and added once (four atomics a run, not
// two an edge, which contend on one cache line).
inline constexpr uint64_t kHermiteTallyRun = 256;

struct HermiteTally {
  const HermitePoint* hermite;
  uint64_t edge_count;
  unsigned long long* tally;  // kHermiteTallies counters, zeroed

  GWNRT_HD void operator()(uint64_t run) const {
    unsigned long long local[kHermiteTallies] = {0, 0, 0, 0};
    const uint64_t run_end = (run + 1) * kHermiteTallyRun;
    const uint64_t end = run_end < edge_count ? run_end : edge_count;
    for (uint64_t i = run * kHermiteTallyRun; i < end; ++i) {
      const HermitePoint& h = hermite[i];
      ++local[h.kind == HermiteKind::kSheet    ? kTallySheet
              : h.kind == HermiteKind::kSmooth ? kTallySmooth
                                               : kTallyFallback];
      local[kTallyCapped] += h.capped;
    }
    for (uint32_t k = 0; k < kHermiteTallies; ++k)
      if (local[k]) atomic_add(tally + k, local[k]);
  }
};

// The index of the edge along `axis` from corner c (one with a sign change), or kEmptyLane.
GWNRT_HD inline uint32_t edge_index(const SparseGridView& view, const GridCoord& c, int axis) {
  const uint64_t item = view.item_of(c, 1);
  if (item == ~uint64_t(0)) return kEmptyLane;
  const uint32_t mask = view.edge_mask[item];
  if (!((mask >> axis) & 1u)) return kEmptyLane;
  return view.edge_offset(item) + uint32_t(bit_count(mask & ((1u << axis) - 1u)));
}

// The index of edge e (cell_topology.h's numbering) of `cell`, or kEmptyLane.
GWNRT_HD inline uint32_t cell_edge_index(const SparseGridView& view, const GridCoord& cell, int e) {
  return edge_index(view, cell_corner(cell, edge_corner(e)), edge_axis(e));
}

// ---------------------------------------------------------------------------------------------
// Cells.

// The inside mask of a cell (bit k: corner k inside), or -1 when a corner was not evaluated.
GWNRT_HD inline int cell_inside_mask(const SparseGridView& view, uint64_t item, const GridCoord& cell) {
  float f[kCellCorners];
  view.cell_corner_values(item, cell, f);
  uint32_t mask = 0;
  for (int k = 0; k < kCellCorners; ++k) {
    if (f[k] != f[k]) return -1;
    mask |= uint32_t(is_inside(f[k])) << k;
  }
  return int(mask);
}

// The inside mask of any cell in a block with a slot, -1 beyond the grid or where a corner is not
// evaluated.
GWNRT_HD inline int inside_mask_at(const SparseGridView& view, const GridCoord& cell) {
  const uint64_t item = view.item_of(cell, 0);
  return item == ~uint64_t(0) ? -1 : cell_inside_mask(view, item, cell);
}

// The faces of a cell whose pairing is flipped (visit_face_segments): those with a tunnel through
// them in both this cell and the cell across (tunnel_through_face).
GWNRT_HD inline uint32_t flipped_faces(const SparseGridView& view, const GridCoord& cell, uint32_t inside) {
  uint32_t flipped = 0;
  for (int face = 0; face < 6; ++face) {
    if (!tunnel_through_face(inside, face)) continue;
    GridCoord other = cell;
    other[face >> 1] += (face & 1) ? 1 : -1;
    const int mask = inside_mask_at(view, other);
    if (mask >= 0 && tunnel_through_face(uint32_t(mask), face ^ 1)) flipped |= 1u << face;
  }
  return flipped;
}

// The cells around each crossing edge, marked (cell_parts = 1) so that the count reads the
// corners of those cells only: few of the slots' cells have a crossing edge, and reading every
// cell's corners would be a noticeable share of the mesher's time.
struct CellMarkPass {
  SparseGridView view;
  const uint64_t* edges;
  uint32_t* cell_parts;
  GWNRT_HD void operator()(uint64_t i) const {
    const int a = int(edges[i] % 4), b = (a + 1) % 3, c = (a + 2) % 3;
    const GridCoord g = view.coord_of_item(edges[i] / 4);
    for (int k = 0; k < 4; ++k) {
      GridCoord cell = g;
      cell[b] -= k & 1;
      cell[c] -= k >> 1;
      const uint64_t item = view.item_of(cell, 0);
      if (item != ~uint64_t(0)) atomic_or(cell_parts + item, 1u);
    }
  }
};

// The surface components of each marked cell of an active slot (packed: its vertices, one each).
struct CellPartsPass {
  SparseGridView view;
  uint32_t* cell_parts;
  unsigned long long* multi_component_cells;
  GWNRT_HD void operator()(uint64_t item) const {
    uint32_t parts = 0;
    if (cell_parts[item] != 0 && view.slot_active(uint32_t(item / kBlockItems))) {
      const GridCoord cell = view.coord_of_item(item);
      const bool in_grid = cell.x < view.grid.cells[0] && cell.y < view.grid.cells[1] && cell.z < view.grid.cells[2];
      const int mask = in_grid ? cell_inside_mask(view, item, cell) : -1;
      if (mask > 0 && mask < 255)
        parts = packed_cell_components(uint32_t(mask), flipped_faces(view, cell, uint32_t(mask)));
    }
    cell_parts[item] = parts;
    if (packed_count(parts) > 1) atomic_add(multi_component_cells, 1);
  }
};

// p clamped into the open cell: each coordinate strictly between the cell's corner positions
// (where the grid's floats leave room between them).
GWNRT_HD inline vec3 strictly_inside_cell(const MeshGrid& grid, const GridCoord& cell, vec3 p) {
  const vec3 lo = grid.corner_position(cell), hi = grid.corner_position({cell.x + 1, cell.y + 1, cell.z + 1});
  for (int a = 0; a < 3; ++a) {
    const float first = nextafterf(lo[a], hi[a]), last = nextafterf(hi[a], lo[a]);
    if (first <= last) p[a] = fminf(fmaxf(p[a], first), last);
  }
  return p;
}

// Each component's vertex: the QEF of its edges' Hermite data in cell units (well conditioned
// whatever the model's scale), solved and clamped to the cell; its normal the mean of theirs.
struct CellVertexPass {
  SparseGridView view;
  const HermitePoint* hermite;
  vec3* positions;
  vec3* normals;
  uint64_t* vertex_cell;  // the cell item of each vertex (for the smoothing)

  GWNRT_HD void operator()(uint64_t item) const {
    const uint32_t count = view.cell_vertex_count(item);
    if (count == 0) return;
    const GridCoord cell = view.coord_of_item(item);
    const uint32_t parts = view.cell_parts[item];
    const vec3 lo = view.grid.corner_position(cell);
    const double inv_cell = 1.0 / double(view.grid.cell);
    Qef qef[4];
    dvec3 box_lo[4] = {dvec3(1.0), dvec3(1.0), dvec3(1.0), dvec3(1.0)},
          box_hi[4] = {dvec3(0.0), dvec3(0.0), dvec3(0.0), dvec3(0.0)};
    for (int e = 0; e < kCellEdges; ++e) {
      const uint32_t k = cell_edge_index(view, cell, e);
      if (k == kEmptyLane) continue;
      const HermitePoint& h = hermite[k];
      const int c = packed_component(parts, e);
      const dvec3 q = (dvec3(h.point) - dvec3(lo)) * inv_cell;
      qef[c].add(q, dvec3(h.normal));
      box_lo[c] = glm::min(box_lo[c], q);
      box_hi[c] = glm::max(box_hi[c], q);
    }
    const uint32_t first = view.cell_vertex_offset(item);
    for (uint32_t p = 0; p < count; ++p) {
      // Kept in the cell itself. A sharp edge passing just outside a cell whose grid edges both
      // its faces cross has its QEF minimum outside the cell, and the clamped vertex lies off the
      // edge; letting such vertices out of the cell makes the output intersect itself. A cell
      // with two or more components (two sheets, a thin part) keeps each vertex in the box of its
      // own component's Hermite points: clamped to the cell, the components' vertices can fall
      // onto the same cell edge and their triangles overlap. Single components keep the whole
      // cell: a cube's corner lies outside its crossings' box. (docs/performance.md, meshing.)
      const dvec3 x = count > 1 ? solve_qef(qef[p], box_lo[p], box_hi[p]) : solve_qef(qef[p], dvec3(0.0), dvec3(1.0));
      positions[first + p] = strictly_inside_cell(view.grid, cell, lo + vec3(x) * view.grid.cell);
      const dvec3 n = qef[p].normal_sum;
      const double length = glm::length(n);
      normals[first + p] = length > 0 ? vec3(n / length) : vec3(0.0f, 0.0f, 1.0f);
      vertex_cell[first + p] = item;
    }
  }
};

// The vertex of the component holding the edge along `axis` from corner c in `cell`, or
// kEmptyLane when the cell has none (not active).
GWNRT_HD inline uint32_t edge_vertex(const SparseGridView& view, const GridCoord& cell, const GridCoord& c, int axis) {
  const uint64_t item = view.item_of(cell, 0);
  if (item == ~uint64_t(0)) return kEmptyLane;
  const uint32_t parts = view.cell_parts[item];
  if (parts == 0) return kEmptyLane;
  const int corner = (c.x - cell.x) | ((c.y - cell.y) << 1) | ((c.z - cell.z) << 2);
  return view.cell_vertex_offset(item) + uint32_t(packed_component(parts, corner_edge(corner, axis)));
}

// One quad per sign-changing edge, from the four cells around it, ordered so that its normal
// (right-handed) points out of {w > w*}, split into two triangles along the diagonal whose
// triangles bend less against each other. An edge missing a cell gives two empty triangles
// (kEmptyLane), removed afterwards.
// How far from the edge's Hermite point the triangle (p, q, r) crosses the line of the edge
// (through g along axis a), or +inf when it does not cross it.
GWNRT_HD inline float crossing_offset(const vec3& p, const vec3& q, const vec3& r, const vec3& g, int a, float target) {
  const int b = (a + 1) % 3, c = (a + 2) % 3;
  const float d = (q[b] - p[b]) * (r[c] - p[c]) - (r[b] - p[b]) * (q[c] - p[c]);
  if (d == 0.0f) return kInfinity;
  const float u = ((g[b] - p[b]) * (r[c] - p[c]) - (r[b] - p[b]) * (g[c] - p[c])) / d;
  const float v = ((q[b] - p[b]) * (g[c] - p[c]) - (g[b] - p[b]) * (q[c] - p[c])) / d;
  if (!(u >= 0.0f && v >= 0.0f && u + v <= 1.0f)) return kInfinity;
  return fabsf(p[a] + u * (q[a] - p[a]) + v * (r[a] - p[a]) - target);
}

struct QuadPass {
  SparseGridView view;
  const uint64_t* edges;
  const HermitePoint* hermite;
  const vec3* positions;
  uvec3* triangles;

  GWNRT_HD void operator()(uint64_t i) const {
    const uint64_t corner = edges[i] / 4;
    const int a = int(edges[i] % 4), b = (a + 1) % 3, c = (a + 2) % 3;
    const GridCoord g = view.coord_of_item(corner);
    // Around the edge counter-clockwise seen from +a: cells at (b, c) offsets (-1,-1), (0,-1),
    // (0,0), (-1,0), since e_b × e_c = e_a.
    const int db[4] = {-1, 0, 0, -1}, dc[4] = {-1, -1, 0, 0};
    uint32_t v[4];
    for (int k = 0; k < 4; ++k) {
      GridCoord cell = g;
      cell[b] += db[k];
      cell[c] += dc[k];
      v[k] = edge_vertex(view, cell, g, a);
      if (v[k] == kEmptyLane) {
        triangles[2 * i] = triangles[2 * i + 1] = uvec3(kEmptyLane);
        return;
      }
    }
    if (!is_inside(view.corner_value[corner])) {  // outside at the lower end: the normal is -a
      const uint32_t s = v[1];
      v[1] = v[3];
      v[3] = s;
    }
    const vec3 p0 = positions[v[0]], p1 = positions[v[1]], p2 = positions[v[2]], p3 = positions[v[3]];
    const auto unit = [](const vec3& n) {
      const float l = glm::length(n);
      return l > 0.0f ? n / l : vec3(0.0f);
    };
    // Diagonal 0-2: triangles (0,1,2), (0,2,3); diagonal 1-3: (0,1,3), (1,2,3). The quad is dual
    // to the edge, and S crosses the edge at its Hermite point: the split that crosses the edge
    // nearer that point is taken. Along a sharp feature this keeps the fold on the feature (two
    // of the four vertices lie on it), where the flatter split would cut it off by up to half a
    // cell.
    const vec3 origin = view.grid.corner_position(g);
    const float target = hermite[i].point[a];
    const float off02 =
        fminf(crossing_offset(p0, p1, p2, origin, a, target), crossing_offset(p0, p2, p3, origin, a, target));
    const float off13 =
        fminf(crossing_offset(p0, p1, p3, origin, a, target), crossing_offset(p1, p2, p3, origin, a, target));
    const float bend02 = glm::dot(unit(glm::cross(p1 - p0, p2 - p0)), unit(glm::cross(p2 - p0, p3 - p0)));
    const float bend13 = glm::dot(unit(glm::cross(p1 - p0, p3 - p0)), unit(glm::cross(p2 - p1, p3 - p1)));
    // A split whose triangles face against the edge's outward direction, or against each other,
    // folds the surface over itself: the other one is taken whatever the Hermite point says.
    vec3 outward(0.0f);
    outward[a] = is_inside(view.corner_value[corner]) ? 1.0f : -1.0f;
    const auto faces_out = [&](const vec3& x, const vec3& y, const vec3& z) {
      return glm::dot(glm::cross(y - x, z - x), outward) > 0.0f;
    };
    const bool sound02 = bend02 > 0.0f && faces_out(p0, p1, p2) && faces_out(p0, p2, p3);
    const bool sound13 = bend13 > 0.0f && faces_out(p0, p1, p3) && faces_out(p1, p2, p3);
    const bool split02 = sound02 != sound13 ? sound02 : (off02 != off13 ? off02 < off13 : bend02 >= bend13);
    if (split02) {
      triangles[2 * i] = {v[0], v[1], v[2]};
      triangles[2 * i + 1] = {v[0], v[2], v[3]};
    } else {
      triangles[2 * i] = {v[0], v[1], v[3]};
      triangles[2 * i + 1] = {v[1], v[2], v[3]};
    }
  }
};

// ---------------------------------------------------------------------------------------------
// Repair of intersecting triangles.
//
// Every vertex lies strictly inside its cell (strictly_inside_cell), so a triangle of the quad of
// edge E lies in the interior of the box of the four cells around E, and two triangles that meet
// share a cell of both their edges' four. Each pair is tested, exactly, in the lowest such cell
// (SelfIntersectionPass); the vertices of the pairs that meet other than in a shared vertex or
// edge move toward their component's safe point (VertexRepairPass) and the cells around them are
// tested again, for at most kRepairRounds rounds.

// The lowest of the four cells around the edge along `axis` from corner c.
GWNRT_HD inline GridCoord edge_lowest_cell(GridCoord c, int axis) {
  --c[(axis + 1) % 3];
  --c[(axis + 2) % 3];
  return c;
}

// The cell a pair of triangles is tested in: the lowest cell around both their edges (whose
// lowest cells are a and b, the two edges being edges of one cell).
GWNRT_HD inline GridCoord pair_cell(const GridCoord& a, const GridCoord& b) {
  return {a.x > b.x ? a.x : b.x, a.y > b.y ? a.y : b.y, a.z > b.z ? a.z : b.z};
}

inline constexpr int kRepairRounds = 6;
// Rounds before this one move a vertex half way to its safe point; from it on, onto it.
inline constexpr int kRepairSnapRound = 2;

// The repair's dirty cells: a bit per item, 32 to a word (dirty_words of them).
GWNRT_HD constexpr uint64_t dirty_words(uint64_t items) { return (items + 31) / 32; }
GWNRT_HD inline bool is_dirty(const uint32_t* dirty, uint64_t item) { return (dirty[item / 32] >> (item % 32)) & 1u; }
GWNRT_HD inline void mark_dirty(uint32_t* dirty, uint64_t item) { atomic_or(dirty + item / 32, 1u << (item % 32)); }

// Per cell with vertices (run over the vertices: the cell's first vertex does it) whose `dirty`
// flag is set (every such cell when dirty is null): the pairs of triangles of its edges' quads
// tested in it that meet; their vertices get `flag` 1, the count goes to pairs[0].
struct SelfIntersectionPass {
  SparseGridView view;
  const uint64_t* vertex_cell;
  const uvec3* triangles;  // two per edge (kEmptyLane: none)
  const vec3* positions;
  const uint32_t* dirty;
  uint32_t* flag;
  unsigned long long* pairs;

  GWNRT_HD void operator()(uint64_t vertex) const {
    const uint64_t item = vertex_cell[vertex];
    if (vertex != view.cell_vertex_offset(item) || (dirty && !is_dirty(dirty, item))) return;
    const GridCoord cell = view.coord_of_item(item);
    constexpr int kMax = 2 * kCellEdges;
    uint32_t id[kMax];
    GridCoord low[kMax];
    exact::Triangle tri[kMax];
    exact::PlaneFilter plane[kMax];
    Aabb box[kMax];
    int n = 0;
    for (int e = 0; e < kCellEdges; ++e) {
      const int axis = edge_axis(e);
      const GridCoord c = cell_corner(cell, edge_corner(e));
      const uint32_t k = edge_index(view, c, axis);
      if (k == kEmptyLane) continue;
      for (uint32_t t = 2 * k; t < 2 * k + 2; ++t) {
        const uvec3 v = triangles[t];
        if (v.x == kEmptyLane) continue;
        id[n] = t;
        low[n] = edge_lowest_cell(c, axis);
        for (int j = 0; j < 3; ++j) tri[n][j] = positions[v[j]];
        box[n] = {glm::min(tri[n][0], glm::min(tri[n][1], tri[n][2])),
                  glm::max(tri[n][0], glm::max(tri[n][1], tri[n][2]))};
        plane[n].set(tri[n]);
        // A zero-area triangle meets nothing by the pair test's rule.
        if (plane[n].certainly_nonzero_area() || !exact::collinear(tri[n][0], tri[n][1], tri[n][2])) ++n;
      }
    }
    unsigned long long found = 0;
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j) {
        const GridCoord at = pair_cell(low[i], low[j]);
        if (at.x != cell.x || at.y != cell.y || at.z != cell.z) continue;
        if (!box[i].overlaps(box[j])) continue;
        // Shared vertices by index (the filter stays safe for distinct vertices that coincide).
        if (exact::apart_beyond_shared(tri[i], plane[i], tri[j], plane[j], triangles[id[i]], triangles[id[j]]) ||
            !exact::triangles_of_nonzero_area_intersect(tri[i], tri[j]))
          continue;
        ++found;
        for (const uint32_t t : {id[i], id[j]})
          for (int k = 0; k < 3; ++k) atomic_or(flag + triangles[t][k], 1u);
      }
    if (found) atomic_add(pairs, found);
  }
};

// A vertex's safe point: the mean of the midpoints of its component's edges in the cell (that
// of surface nets, away from the cell's faces), strictly inside the cell.
GWNRT_HD inline vec3 component_safe_point(const SparseGridView& view, const GridCoord& cell, uint32_t parts,
                                          int component) {
  vec3 sum(0.0f);
  int count = 0;
  for (int e = 0; e < kCellEdges; ++e) {
    const int corner = edge_corner(e), axis = edge_axis(e);
    if (cell_edge_index(view, cell, e) == kEmptyLane || packed_component(parts, e) != component) continue;
    vec3 mid(float(corner & 1), float((corner >> 1) & 1), float((corner >> 2) & 1));
    mid[axis] = 0.5f;
    sum += mid;
    ++count;
  }
  const vec3 local = count > 0 ? sum / float(count) : vec3(0.5f);
  return strictly_inside_cell(view.grid, cell, view.grid.corner_position(cell) + local * view.grid.cell);
}

// Per flagged vertex: moved half way to its safe point (onto it when `snap`), its flag cleared,
// the cells around it (whose tests read its triangles) marked dirty, the move counted.
struct VertexRepairPass {
  SparseGridView view;
  const uint64_t* vertex_cell;
  vec3* positions;
  uint32_t* flag;
  uint32_t* dirty;
  bool snap;
  unsigned long long* moves;

  GWNRT_HD void operator()(uint64_t v) const {
    if (!flag[v]) return;
    flag[v] = 0;
    const uint64_t item = vertex_cell[v];
    const GridCoord cell = view.coord_of_item(item);
    const int component = int(v - view.cell_vertex_offset(item));
    const vec3 safe = component_safe_point(view, cell, view.cell_parts[item], component);
    const vec3 p = snap ? safe : strictly_inside_cell(view.grid, cell, 0.5f * (positions[v] + safe));
    if (p == positions[v]) return;
    positions[v] = p;
    atomic_add(moves, 1ull);
    for (int d = 0; d < 27; ++d) {
      const uint64_t near = view.item_of({cell.x + d % 3 - 1, cell.y + (d / 3) % 3 - 1, cell.z + d / 9 - 1}, 0);
      if (near != ~uint64_t(0)) mark_dirty(dirty, near);
    }
  }
};

// Angle-gated normal smoothing: a vertex's normal averaged with those of the vertices in its
// cell and the six face-neighbouring cells that lie within the angle of it (cos_angle).
struct SmoothNormalsPass {
  SparseGridView view;
  const uint64_t* vertex_cell;
  const vec3* normals_in;
  vec3* normals_out;
  float cos_angle;

  GWNRT_HD void operator()(uint64_t v) const {
    const vec3 n0 = normals_in[v];
    vec3 sum = n0;
    const GridCoord cell = view.coord_of_item(vertex_cell[v]);
    for (int k = 0; k < 6; ++k) {
      GridCoord nb = cell;
      nb[k >> 1] += (k & 1) ? 1 : -1;
      const uint64_t item = view.item_of(nb, 0);
      if (item == ~uint64_t(0)) continue;
      const uint32_t first = view.cell_vertex_offset(item), count = view.cell_vertex_count(item);
      for (uint32_t j = first; j < first + count; ++j)
        if (glm::dot(normals_in[j], n0) >= cos_angle) sum += normals_in[j];
    }
    const float length = glm::length(sum);
    normals_out[v] = length > 0.0f ? sum / length : n0;
  }
};

// ---------------------------------------------------------------------------------------------
// Marching cubes on the same corners and edge points: a vertex per crossing edge (its Hermite
// point and normal), per cell a fan of triangles over each loop of cell_loops (whose ambiguous
// faces are split by cell_components' rule, so the two cells sharing a face agree).

GWNRT_HD inline uint32_t cell_loop_triangles(const CellLoops& loops) {
  uint32_t n = 0;
  for (int l = 0; l < loops.count; ++l) n += uint32_t(loops.length[l] - 2);
  return n;
}

struct MarchingCountPass {
  SparseGridView view;
  uint32_t* cell_triangles;
  GWNRT_HD void operator()(uint64_t item) const {
    uint32_t n = 0;
    if (view.slot_active(uint32_t(item / kBlockItems))) {
      const GridCoord cell = view.coord_of_item(item);
      const bool in_grid = cell.x < view.grid.cells[0] && cell.y < view.grid.cells[1] && cell.z < view.grid.cells[2];
      const int mask = in_grid ? cell_inside_mask(view, item, cell) : -1;
      if (mask > 0 && mask < 255) n = cell_loop_triangles(cell_loops_of(uint32_t(mask)));
    }
    cell_triangles[item] = n;
  }
};

struct MarchingFacePass {
  SparseGridView view;
  const uint32_t* cell_triangles;
  const uint32_t* cell_triangle_offset;
  uvec3* triangles;
  GWNRT_HD void operator()(uint64_t item) const {
    if (cell_triangles[item] == 0) return;
    const GridCoord cell = view.coord_of_item(item);
    const CellLoops loops = cell_loops_of(uint32_t(cell_inside_mask(view, item, cell)));
    uint32_t out = cell_triangle_offset[item];
    int first = 0;
    for (int l = 0; l < loops.count; ++l) {
      uint32_t v[kCellEdges];
      bool complete = true;
      for (int k = 0; k < loops.length[l]; ++k) {
        v[k] = cell_edge_index(view, cell, loops.edge[first + k]);
        complete = complete && v[k] != kEmptyLane;
      }
      for (int k = 1; k + 1 < loops.length[l]; ++k)
        triangles[out++] = complete ? uvec3(v[0], v[k], v[k + 1]) : uvec3(kEmptyLane);
      first += loops.length[l];
    }
  }
};

}  // namespace gwnrt
