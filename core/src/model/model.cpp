#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <mutex>
#include <string>

#include "base/message.h"
#include "gwnrt/model/model.h"
#include "gwnrt/sdf/sheets.h"

namespace gwnrt {
namespace {

// The centroid values are needed only to tell |w_o − w*| from 1/2. A first pass at a coarse
// beta (max error about 0.01, at an eighth of the fine pass's time) decides almost every
// triangle; those within kSheetAmbiguity of the threshold, eight times that error, are evaluated
// again at the fine beta (docs/performance.md, the sheets).
constexpr float kSheetBetaCoarse = 1.5f;
constexpr float kSheetBetaFine = 4.0f;
constexpr float kSheetAmbiguity = 0.1f;
// The most segments the spanning surface may end up fanning from one apex (a boundary of many
// small scattered loops) for the sheets to be classified with it: past that it is C again.
constexpr size_t kMaxSingleApexSegments = 256;

constexpr const char* kEmptyModel = "GwnModel: empty (GwnModel::build makes one)";

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// SmoothRegion per group of loops (see model_view.h). Groups: the loops themselves, or, beyond
// kMaxSmoothRegions, runs of loops sorted along the axis where their centres spread most.
std::vector<SmoothRegion> group_smooth_regions(const Cone& cone, uint32_t loop_count) {
  std::vector<Aabb> box(loop_count);
  std::vector<double> area(loop_count, 0.0);
  for (size_t s = 0; s < cone.mesh.triangles.size(); ++s) {
    const uvec3 t = cone.mesh.triangles[s];
    const dvec3 p0(cone.mesh.positions[t[0]]), p1(cone.mesh.positions[t[1]]), p2(cone.mesh.positions[t[2]]);
    const uint32_t l = cone.loop_of_triangle[s];
    area[l] += 0.5 * glm::length(glm::cross(p1 - p0, p2 - p0));
    for (int k = 0; k < 3; ++k) box[l].extend(cone.mesh.positions[t[k]]);
  }
  std::vector<uint32_t> group(loop_count);
  uint32_t group_count = loop_count;
  if (loop_count > kMaxSmoothRegions) {
    Aabb centres;
    for (const Aabb& b : box) centres.extend(b.centre());
    const vec3 extent = centres.hi - centres.lo;
    const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
    std::vector<uint32_t> order(loop_count);
    for (uint32_t l = 0; l < loop_count; ++l) order[l] = l;
    std::sort(order.begin(), order.end(),
              [&](uint32_t a, uint32_t b) { return box[a].centre()[axis] < box[b].centre()[axis]; });
    for (uint32_t i = 0; i < loop_count; ++i) group[order[i]] = uint32_t(uint64_t(i) * kMaxSmoothRegions / loop_count);
    group_count = kMaxSmoothRegions;
  } else {
    for (uint32_t l = 0; l < loop_count; ++l) group[l] = l;
  }
  std::vector<SmoothRegion> regions(group_count);
  std::vector<double> group_area(group_count, 0.0);
  for (uint32_t l = 0; l < loop_count; ++l) {
    regions[group[l]].box.extend(box[l]);
    group_area[group[l]] += area[l];
  }
  // Shares λ_r proportional to sqrt(A_r): spread_r = A_r / λ_r = sqrt(A_r) · Σ sqrt(A). Rounded up
  // by 1% so that float round-off never shrinks the region.
  double root_sum = 0;
  for (double a : group_area) root_sum += std::sqrt(a);
  for (uint32_t r = 0; r < group_count; ++r) regions[r].spread = float(1.01 * std::sqrt(group_area[r]) * root_sum);
  return regions;
}

}  // namespace

std::string level_out_of_reach_message(uint32_t triangle_count, float level) {
  char text[48];  // %g: "100000" where the shortest round trip says "1e+05"
  std::snprintf(text, sizeof text, "%g", double(level));
  return cat("level ", std::string_view(text), " lies outside every value w takes on this mesh (|w| < ", triangle_count,
             "/2): S is empty");
}

struct GwnModel::Deferral {
  BuildOptions options;
  std::mutex mutex;
  std::atomic<uint32_t> built{0};  // ModelPart bits; set (release) once a part's members are written
};

GwnModel::GwnModel() = default;
GwnModel::~GwnModel() = default;
GwnModel::GwnModel(GwnModel&&) noexcept = default;
GwnModel& GwnModel::operator=(GwnModel&&) noexcept = default;

Status GwnModel::build(Mesh mesh, GwnModel& out, const BuildOptions& options) {
  return guard_status("GwnModel::build", [&] { return build_unguarded(std::move(mesh), out, options); });
}

Status GwnModel::build_unguarded(Mesh mesh, GwnModel& out, const BuildOptions& options) {
  if (options.max_leaf_triangles < 1 || options.max_leaf_triangles > kMaxLeafSize || options.max_leaf_segments < 1 ||
      options.max_leaf_segments > kMaxLeafSize)
    return {StatusCode::kInvalidArgument, "BuildOptions: max_leaf_triangles and max_leaf_segments must lie in [1, " +
                                              std::to_string(kMaxLeafSize) + "]"};
  if (uint32_t(options.sheet_method) >= kWindingMethodCount || options.sheet_method == WindingMethod::kBrute)
    return {StatusCode::kInvalidArgument,
            "BuildOptions: sheet_method must be auto, crossing or taylor (brute would sum n² terms)"};
  if (options.classify_sheets && !std::isfinite(options.sheet_level))
    return {StatusCode::kInvalidArgument, "BuildOptions: sheet level must be a finite number"};
  if (Status s = validate_mesh(mesh); !s.ok()) return s;
  if (Status s = check_mesh_scale(mesh); !s.ok()) return s;
  const auto t0 = std::chrono::steady_clock::now();
  GwnModel model;
  model.deferral_ = std::make_unique<Deferral>();
  model.deferral_->options = options;
  model.mesh_ = std::move(mesh);
  if (Status s = build_triangle_tree(model.mesh_, options.max_leaf_triangles, model.triangles_); !s.ok()) return s;
  // The tree leaves zero-area triangles out; with none left there is nothing to evaluate.
  if (model.triangles_.triangle_ids.empty())
    return {StatusCode::kInvalidMesh, "mesh: all " + std::to_string(model.mesh_.triangles.size()) +
                                          " triangles have zero area (nothing to evaluate)"};
  double area = 0;
  for (const uvec3& t : model.mesh_.triangles) {
    const dvec3 p0(model.mesh_.positions[t[0]]), p1(model.mesh_.positions[t[1]]), p2(model.mesh_.positions[t[2]]);
    area += 0.5 * glm::length(glm::cross(p1 - p0, p2 - p0));
    model.bounds_.extend(model.mesh_.positions[t[0]]);
    model.bounds_.extend(model.mesh_.positions[t[1]]);
    model.bounds_.extend(model.mesh_.positions[t[2]]);
  }
  // |w(x)| <= A / (4π d²) at distance d from the box, so beyond sqrt(A / 2π) no level w* + k
  // with |w*| <= 1/2 is reached; 1% more absorbs round-off.
  model.surface_margin_ = float(1.01 * std::sqrt(area / (2 * kPi)));
  model.timings_.tree_seconds = seconds_since(t0);
  model.deferral_->built.store(kPartTriangles, std::memory_order_release);
  if (!options.defer_parts) {
    if (Status s = model.prepare(kPartBoundary | kPartSheets); !s.ok()) return s;
  }
  out = std::move(model);
  return Status::Ok();
}

uint32_t GwnModel::built_parts() const { return deferral_ ? deferral_->built.load(std::memory_order_acquire) : 0; }

Status GwnModel::prepare(uint32_t parts) const {
  if ((built_parts() & parts) == parts) return Status::Ok();
  if (!deferral_) return {StatusCode::kInvalidArgument, kEmptyModel};
  return guard_status("GwnModel::prepare", [&] {
    std::lock_guard<std::mutex> lock(deferral_->mutex);
    if (parts & (kPartBoundary | kPartSheets | kPartLevelFreeCells)) {
      if (Status s = build_boundary(); !s.ok()) return s;
    }
    if (parts & kPartLevelFreeCells) {
      if (Status s = build_level_free_cells_locked(); !s.ok()) return s;
    }
    if ((parts & kPartSheets) && !(deferral_->built.load(std::memory_order_relaxed) & kPartSheets) &&
        deferral_->options.classify_sheets)
      return set_sheet_level_locked(deferral_->options.sheet_level);
    return Status::Ok();
  });
}

Status GwnModel::build_level_free_cells_locked() const {
  const float level = deferral_->options.sheet_level;
  const uint32_t built = deferral_->built.load(std::memory_order_relaxed);
  if ((built & kPartLevelFreeCells) && level_free_.params.phase == level - std::floor(level)) return Status::Ok();
  const auto t0 = std::chrono::steady_clock::now();
  LevelFreeCellGrid cells;  // into a local first: the view keeps the old cells until it is whole
  if (Status s = build_level_free_cells(view(), level, cells); !s.ok()) return s;
  level_free_ = std::move(cells);
  timings_.level_free_seconds = seconds_since(t0);
  deferral_->built.fetch_or(kPartLevelFreeCells, std::memory_order_release);
  return Status::Ok();
}

Status GwnModel::build_boundary() const {
  if (deferral_->built.load(std::memory_order_relaxed) & kPartBoundary) return Status::Ok();
  const auto t0 = std::chrono::steady_clock::now();
  const BuildOptions& options = deferral_->options;
  boundary_ = extract_boundary(mesh_);
  if (Status s = build_segment_tree(boundary_.endpoints, options.max_leaf_segments, boundary_tree_); !s.ok()) return s;
  if (Status s = build_ribbon_tree(boundary_.endpoints, options.max_leaf_segments, ribbon_tree_); !s.ok()) return s;
  uint32_t loop_count = 0;
  const std::vector<uint32_t> loop_of_segment = boundary_loops(boundary_, loop_count);
  const Cone cone = boundary_cone(boundary_, loop_of_segment, loop_count);
  if (Status s = build_triangle_tree(cone.mesh, options.max_leaf_triangles, cone_); !s.ok()) return s;
  add_corner_columns(cone_);
  cone_lengths_ = gwnrt::cone_boundary_lengths(cone_, cone.segment_triangles);
  cone_segments_ = gwnrt::cone_segments(cone_, cone.segment_triangles);
  smooth_regions_ = group_smooth_regions(cone, loop_count);
  ModelView v = view();  // the boundary's part is not marked built yet
  v.boundary = boundary_tree_.view();
  v.ribbons = ribbon_tree_.view();
  v.cone = cone_.view();
  crossing_work_ratio_ = sample_crossing_work_ratio(v);
  timings_.boundary_seconds = seconds_since(t0);
  deferral_->built.fetch_or(kPartBoundary, std::memory_order_release);
  return Status::Ok();
}

Status GwnModel::set_sheet_level(float level) {
  return guard_status("GwnModel::set_sheet_level", [&] {
    if (!deferral_) return Status{StatusCode::kInvalidArgument, kEmptyModel};
    std::lock_guard<std::mutex> lock(deferral_->mutex);
    if (Status s = build_boundary(); !s.ok()) return s;
    if (Status s = set_sheet_level_locked(level); !s.ok()) return s;
    // Kept for every later prepare and for requested_sheet_level (prepare only reads the options).
    deferral_->options.sheet_level = level;
    deferral_->options.classify_sheets = true;
    // Cells already built are proven for the old level's phase: again for the new one.
    if (deferral_->built.load(std::memory_order_relaxed) & kPartLevelFreeCells)
      if (Status s = build_level_free_cells_locked(); !s.ok()) return s;
    return Status::Ok();
  });
}

float GwnModel::requested_sheet_level() const {
  return deferral_ && deferral_->options.classify_sheets ? deferral_->options.sheet_level : __builtin_nanf("");
}

Status GwnModel::set_sheet_level_locked(float level) const {
  if (!std::isfinite(level)) return {StatusCode::kInvalidArgument, "sheet level must be a finite number"};
  const auto t0 = std::chrono::steady_clock::now();
  const BuildOptions& options = deferral_->options;
  if (other_winding_.empty()) {  // the first classification: how, and the values every level reads
    sheet_method_ = resolve_winding_method(view(), options.sheet_method);
    // A large ∂M (auto's crossing threshold) whose clusters are long, an open fan of slivers
    // around one vertex: the multipole opens every cluster at every centroid, and C, a fan over
    // ∂M, the same. By crossings with the spanning surface instead (its triangles near the part
    // of ∂M they span), exact and O(log² n) a centroid (docs/design.md §4).
    Mesh spanning_mesh;
    if (options.sheet_method == WindingMethod::kAuto && sheet_method_ == WindingMethod::kTaylor &&
        clusters_are_long(triangles_.view())) {
      SpanningSurface spanning = spanning_surface(boundary_);
      if (spanning.single_apex_segments <= kMaxSingleApexSegments) {
        spanning_mesh = std::move(spanning.mesh);
        sheet_method_ = WindingMethod::kCrossing;
      }
    }
    // Into locals first: a classification that fails half-way leaves none behind.
    std::vector<float> winding(mesh_.triangles.size(), std::numeric_limits<float>::quiet_NaN());
    std::vector<int8_t> jump(mesh_.triangles.size(), 0);
    if (sheet_method_ == WindingMethod::kCrossing) {  // exact, once for every level
      if (spanning_mesh.triangles.empty()) {
        other_triangles_winding_by_crossings(view(), view().cone, winding, jump);
      } else {
        TriangleTree spanning;
        if (Status s = build_triangle_tree(spanning_mesh, options.max_leaf_triangles, spanning); !s.ok()) return s;
        other_triangles_winding_by_crossings(view(), spanning.view(), winding, jump);
      }
    } else {  // the coarse pass over all triangles; the fine one below where a level needs it
      const size_t n = triangles_.triangle_ids.size();
      std::vector<uint32_t> leaves(n);
      for (uint32_t i = 0; i < n; ++i) leaves[i] = i;
      other_triangles_winding(triangles_, leaves, kSheetBetaCoarse, winding, jump);
      other_winding_refined_.assign(mesh_.triangles.size(), 0);
    }
    other_winding_ = std::move(winding);
    sheet_jump_ = std::move(jump);
  }
  if (sheet_method_ != WindingMethod::kCrossing) {
    std::vector<uint32_t> ambiguous;  // leaf order: a side within kSheetAmbiguity of the level
    for (uint32_t i = 0; i < triangles_.triangle_ids.size(); ++i) {
      const uint32_t t = triangles_.triangle_ids[i];
      const float half = 0.5f * float(std::abs(int(sheet_jump_[t])));
      if (!other_winding_refined_[t] && (fabsf(other_winding_[t] - half - level) < kSheetAmbiguity ||
                                         fabsf(other_winding_[t] + half - level) < kSheetAmbiguity)) {
        ambiguous.push_back(i);
        other_winding_refined_[t] = 1;
      }
    }
    other_triangles_winding(triangles_, ambiguous, kSheetBetaFine, other_winding_, sheet_jump_);
  }
  std::vector<uint8_t> is_sheet_flag(other_winding_.size(), 0);
  size_t sheet_count = 0;
  for (uint32_t t = 0; t < other_winding_.size(); ++t)
    if (is_sheet(other_winding_[t], level, sheet_jump_[t], sheet_side_tolerance())) {
      is_sheet_flag[t] = 1;
      ++sheet_count;
    }
  // Only distances are asked of the sheet tree: no moments. Most triangles sheets (a closed mesh
  // at w* = 1/2): the triangle tree filtered to them instead of a tree built again, at a
  // fraction of a build's cost.
  if (4 * sheet_count >= triangles_.triangle_ids.size()) {
    if (Status s = filter_triangle_tree(triangles_, is_sheet_flag, sheets_, TreeMoments::kWithout); !s.ok()) return s;
  } else {
    std::vector<uint32_t> sheets;
    sheets.reserve(sheet_count);
    for (uint32_t t = 0; t < other_winding_.size(); ++t)
      if (is_sheet_flag[t]) sheets.push_back(t);
    if (Status s =
            build_triangle_tree(mesh_, sheets, deferral_->options.max_leaf_triangles, sheets_, TreeMoments::kWithout);
        !s.ok())
      return s;
  }
  sheet_level_ = level;
  timings_.sheet_seconds = seconds_since(t0);
  deferral_->built.fetch_or(kPartSheets, std::memory_order_release);
  return Status::Ok();
}

ModelView GwnModel::view() const {
  const uint32_t built = built_parts();
  ModelView v;
  v.parts = built;
  v.triangles = triangle_view();
  v.bounds = bounds_;
  v.surface_margin = surface_margin_;
  if (built & kPartBoundary) {
    v.boundary = boundary_tree_.view();
    v.ribbons = ribbon_tree_.view();
    v.cone = cone_.view();
    v.cone_boundary_lengths = cone_lengths_.data();
    v.cone_segments = cone_segments_.data();
    v.smooth_regions = smooth_regions_.data();
    v.smooth_region_count = uint32_t(smooth_regions_.size());
    v.crossing_work_ratio = crossing_work_ratio_;
  }
  if (built & kPartSheets) {
    v.sheets = sheets_.view();
    v.sheet_level = sheet_level_;
  }
  if (built & kPartLevelFreeCells) v.level_free = level_free_.view();
  return v;
}

}  // namespace gwnrt
