// GwnModel: a mesh together with everything the queries need (the multipole triangle tree,
// the boundary curve ∂M and its segment tree), built once on the CPU. Its views are what the
// host-and-device query functions and the CUDA backend consume.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "gwnrt/base/status.h"
#include "gwnrt/field/evaluate_winding.h"
#include "gwnrt/geometry/boundary.h"
#include "gwnrt/geometry/mesh.h"
#include "gwnrt/geometry/model_view.h"
#include "gwnrt/geometry/ribbon_tree.h"
#include "gwnrt/geometry/segment_tree.h"
#include "gwnrt/geometry/triangle_tree.h"
#include "gwnrt/sdf/level_free_cells.h"
#include "gwnrt/sdf/sheets.h"

namespace gwnrt {

// Leaves hold at most this many primitives (the traversals' per-leaf loops assume few).
inline constexpr uint32_t kMaxLeafSize = 64;

// Why a level w never reaches (level_within_reach is false) has no surface on a mesh of
// `triangle_count` triangles, in the words every program and the mesher use.
std::string level_out_of_reach_message(uint32_t triangle_count, float level);

struct BuildOptions {
  uint32_t max_leaf_triangles = 4;
  uint32_t max_leaf_segments = 4;
  // Classify the sheets for w* = sheet_level at build (set_sheet_level changes the level later):
  // w at every centroid. A model only traced (the Embree plugin) can skip it, and then refuses
  // the sdf and sheet-distance queries.
  bool classify_sheets = true;
  float sheet_level = 0.5f;
  // How the centroids' w is evaluated: crossing (exact; about a tree build's time), taylor (the
  // multipole tree, two passes, about ten tree builds; decided within kSheetSideTolerance), or
  // auto (resolve_winding_method). brute is refused (n² terms).
  WindingMethod sheet_method = WindingMethod::kAuto;
  // Build M's tree now and the other parts (the boundary and cone; the sheets, when
  // classify_sheets) on first need: GwnModel::prepare, which the batch drivers call with what a
  // request reads. A query of distances to M alone then never pays for them (about half a large
  // mesh's build). Off by default, so that build() reports every failure and a model's view() is
  // whole; gwnrt-query defers.
  bool defer_parts = false;
};

struct BuildTimings {
  double tree_seconds = 0;        // triangle BVH + moments, M's box and margin
  double boundary_seconds = 0;    // ∂M extraction + its tree + the cone (0 until built)
  double sheet_seconds = 0;       // w of the other triangles at every centroid + the sheet tree (0 until built)
  double level_free_seconds = 0;  // the level-free cells (0 until asked for: prepare(kPartLevelFreeCells))
};

class GwnModel {
 public:
  GwnModel();
  ~GwnModel();
  GwnModel(GwnModel&&) noexcept;
  GwnModel& operator=(GwnModel&&) noexcept;

  // Validates the mesh (finite coordinates, indices in range, not empty) and builds.
  static Status build(Mesh mesh, GwnModel& out, const BuildOptions& options = {});

  // Builds the ModelPart bits of `parts` not built yet (the sheets with the boundary they read;
  // not the sheets of a model built without classify_sheets, which validate_request then
  // refuses). Thread-safe and once: concurrent callers wait for one build, and a built part costs
  // an atomic load. The accessors below of the boundary, cone and sheets read what is built.
  Status prepare(uint32_t parts) const;
  uint32_t built_parts() const;

  const Mesh& mesh() const { return mesh_; }
  const TriangleTree& triangle_tree() const { return triangles_; }
  const BoundaryCurve& boundary() const { return boundary_; }
  const SegmentTree& boundary_tree() const { return boundary_tree_; }
  TriangleTreeView triangle_view() const {  // M's: mean_on_triangles
    TriangleTreeView v = triangles_.view();
    v.mean_on_triangles = true;
    return v;
  }
  SegmentTreeView boundary_view() const { return boundary_tree_.view(); }
  const TriangleTree& cone_tree() const { return cone_; }
  std::span<const WideNodeLength> cone_boundary_lengths() const { return cone_lengths_; }
  std::span<const ConeSegment> cone_segments() const { return cone_segments_; }
  std::span<const SmoothRegion> smooth_regions() const { return smooth_regions_; }
  const Aabb& bounds() const { return bounds_; }
  float surface_margin() const { return surface_margin_; }
  // Sheets: per input triangle the other triangles' w at its centroid (NaN for zero-area
  // triangles), and the tree over the triangles that are sheets for sheet_level() (NaN when
  // the sheets were not classified).
  std::span<const float> other_winding() const { return other_winding_; }
  std::span<const int8_t> sheet_jump() const { return sheet_jump_; }  // k per input triangle (is_sheet)
  // How other_winding() was evaluated (crossing or taylor), and the side tolerance is_sheet was
  // given for it (0 for the exact crossings).
  WindingMethod sheet_method() const { return sheet_method_; }
  float sheet_side_tolerance() const { return sheet_method_ == WindingMethod::kCrossing ? 0.0f : kSheetSideTolerance; }
  const TriangleTree& sheet_tree() const { return sheets_; }  // for distances: no moments
  // The tracer's level-free cells, for requested_sheet_level() (0.5 without sheets); empty
  // until prepare(kPartLevelFreeCells).
  const LevelFreeCellGrid& level_free_cells() const { return level_free_; }
  float sheet_level() const { return sheet_level_; }
  // The level the sheets are classified for, or will be on first need (a model built with
  // defer_parts, whose sheet_level() is NaN until then): BuildOptions::sheet_level, or the last
  // set_sheet_level's; NaN for a model without sheets. Safe beside prepare on other threads, not
  // beside set_sheet_level.
  float requested_sheet_level() const;
  // Classifies the sheets for another w* (evaluating w only at the centroids whose stored value
  // is too coarse to decide) and rebuilds the sheet tree; the first time, builds the boundary
  // if it is not. Not thread-safe with queries running on this model. Fails on a non-finite level.
  Status set_sheet_level(float level);
  // The built parts (view().parts says which; the others are empty).
  ModelView view() const;
  // Not to be read while another thread builds a part.
  const BuildTimings& timings() const { return timings_; }

 private:
  struct Deferral;  // what prepare needs: the options, the built bits, a mutex

  static Status build_unguarded(Mesh mesh, GwnModel& out, const BuildOptions& options);
  // Under deferral_->mutex: the boundary part (nothing when built), then a classification.
  Status build_boundary() const;
  Status set_sheet_level_locked(float level) const;
  // Under deferral_->mutex, with the boundary built: the level-free cells for options.sheet_level.
  Status build_level_free_cells_locked() const;

  Mesh mesh_;
  TriangleTree triangles_;
  Aabb bounds_;
  float surface_margin_ = 0;
  std::unique_ptr<Deferral> deferral_;
  // The parts built on first need (by const prepare, as a cache is): written only under
  // deferral_->mutex, read only once their bit is set.
  mutable BoundaryCurve boundary_;
  mutable SegmentTree boundary_tree_;
  mutable RibbonTree ribbon_tree_;
  mutable TriangleTree cone_;
  mutable std::vector<WideNodeLength> cone_lengths_;
  mutable std::vector<ConeSegment> cone_segments_;
  mutable std::vector<SmoothRegion> smooth_regions_;
  mutable float crossing_work_ratio_ = 0;
  mutable std::vector<float> other_winding_;
  mutable std::vector<int8_t> sheet_jump_;
  mutable std::vector<uint8_t> other_winding_refined_;  // per input triangle: evaluated at the fine beta
  mutable TriangleTree sheets_;
  mutable float sheet_level_ = __builtin_nanf("");
  mutable LevelFreeCellGrid level_free_;
  mutable WindingMethod sheet_method_ = WindingMethod::kAuto;  // resolved at the first classification
  mutable BuildTimings timings_;
};

}  // namespace gwnrt
