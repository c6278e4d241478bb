// GwnModel: a mesh together with everything the queries need (the multipole triangle tree,
// the boundary curve ∂M and its segment tree), built once on the CPU. Its views are what the
// host-and-device query functions and the CUDA backend consume.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "gwnrt/bvh.h"
#include "gwnrt/mesh.h"
#include "gwnrt/model_view.h"
#include "gwnrt/status.h"

namespace gwnrt {

struct TriangleTree {
  WideBvh bvh;
  std::vector<WideNodeExpansion> expansion;
  std::vector<WideNodeOrder1> order1;
  std::vector<WideNodeOrder2> order2;
  std::vector<vec3> vertices;          // 3 per triangle, leaf order
  std::vector<uint32_t> triangle_ids;  // leaf order -> input triangle
  TriangleTreeView view() const;
};

struct SegmentTree {
  WideBvh bvh;
  std::vector<vec3> endpoints;        // 2 per segment, leaf order
  std::vector<uint32_t> segment_ids;  // leaf order -> segment index
  SegmentTreeView view() const;
};

// ∂M: the edges whose oriented half-edges do not cancel. Vertices are matched by position
// (bit-identical coordinates), so a soup that repeats shared vertices still cancels; zero-area
// triangles are left out (they contribute nothing to w). An edge a->b whose half-edges sum to
// k != 0 appears |k| times, oriented by the sign of k.
struct BoundaryCurve {
  std::vector<vec3> endpoints;  // 2 per segment: a, b
  std::size_t segment_count() const { return endpoints.size() / 2; }
};
BoundaryCurve extract_boundary(const Mesh& mesh);

// Connected components of ∂M (loops, or any closed chains): the loop index of each segment.
std::vector<uint32_t> boundary_loops(const BoundaryCurve& curve, uint32_t& loop_count);

// The cone C over ∂M (see ModelView::cone): one triangle (z_l, a, b) per segment a→b, z_l the
// mean of its loop's endpoints; a and b are the very same floats as the curve's (so crossings
// of M and C agree on shared edges).
Mesh boundary_cone(const BoundaryCurve& curve, std::span<const uint32_t> loop_of_segment, uint32_t loop_count);

// Per cone triangle (leaf order), the segment of ∂M it carries (its edge 1 -> 2); per lane of
// the cone's tree, the length of ∂M below it.
std::vector<ConeSegment> cone_segments(const TriangleTree& cone);
std::vector<WideNodeLength> cone_boundary_lengths(const TriangleTree& cone);

TriangleTree build_triangle_tree(const Mesh& mesh, uint32_t max_leaf_size);
// The tree over the triangles `selection` of the mesh (input indices, none of zero area); its
// triangle_ids are those input indices.
TriangleTree build_triangle_tree(const Mesh& mesh, std::span<const uint32_t> selection, uint32_t max_leaf_size);

// Sheet classification (DESIGN §1, signed distance). Across a triangle w jumps by its own ±1;
// the other triangles' w, w_o, is continuous there, so the two sides carry w_o ± 1/2 and the
// triangle is a piece of S = ∂{w > w*} when they straddle w*. (Equivalently, the side the normal
// points to, w_o − 1/2, lies in (w* − 1, w*).) A stack of k coincident triangles (net count of
// their orientations, a soup that repeats a face) makes w jump by k: the sides are w_o ± k/2,
// with w_o the rest of the mesh, and k = 0 is no jump at all. w_o is taken at the centroid,
// once per triangle.
// This evaluates w_o and k at the centroids of the leaf-order triangles `leaves` of `tree`, into
// out[input index] and jump[input index].
void other_triangles_winding(const TriangleTree& tree, std::span<const uint32_t> leaves, float beta,
                             std::span<float> out, std::span<int8_t> jump);
// Sides within this of w* count as equal to it (the stored w_o is that accurate near the
// threshold): then {w > w*} holds on the upper side only when it is really above, so a closed
// mesh is all sheets for w* = 0 and none for w* = 1, not a coin toss.
inline constexpr float kSheetSideTolerance = 1e-3f;
// The sides lo = w_o − |k|/2 and hi = w_o + |k|/2 straddle w*: lo <= w* < hi. False for NaN
// (zero-area triangles) and k = 0.
GWNRT_HD inline bool is_sheet(float other_winding, float level, int jump = 1) {
  const float half = 0.5f * float(jump < 0 ? -jump : jump);
  const float at = level + kSheetSideTolerance;
  return jump != 0 && other_winding - half <= at && other_winding + half > at;
}
SegmentTree build_segment_tree(std::span<const vec3> endpoints, uint32_t max_leaf_size);

struct BuildOptions {
  uint32_t max_leaf_triangles = 4;
  uint32_t max_leaf_segments = 4;
  // Classify the sheets for w* = sheet_level at build (set_sheet_level changes the level later).
  // It costs about what ten tree builds do (a w evaluation at every centroid; 2 s for 871k
  // triangles on 2 cores): a model only traced (the Embree plugin) can skip it, and then
  // refuses the sdf and sheet-distance queries.
  bool classify_sheets = true;
  float sheet_level = 0.5f;
};

struct BuildTimings {
  double tree_seconds = 0;      // triangle BVH + moments
  double boundary_seconds = 0;  // ∂M extraction + its tree
  double sheet_seconds = 0;     // w of the other triangles at every centroid + the sheet tree
};

class GwnModel {
 public:
  // Validates the mesh (finite coordinates, indices in range, not empty) and builds.
  static Status build(Mesh mesh, GwnModel& out, const BuildOptions& options = {});

  const Mesh& mesh() const { return mesh_; }
  const TriangleTree& triangle_tree() const { return triangles_; }
  const BoundaryCurve& boundary() const { return boundary_; }
  const SegmentTree& boundary_tree() const { return boundary_tree_; }
  TriangleTreeView triangle_view() const { return triangles_.view(); }
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
  const TriangleTree& sheet_tree() const { return sheets_; }
  float sheet_level() const { return sheet_level_; }
  // Classifies the sheets for another w* (evaluating w only at the centroids whose stored value
  // is too coarse to decide) and rebuilds the sheet tree. Not thread-safe with queries running
  // on this model. Fails on a non-finite level.
  Status set_sheet_level(float level);
  ModelView view() const;
  const BuildTimings& timings() const { return timings_; }

 private:
  Mesh mesh_;
  TriangleTree triangles_;
  BoundaryCurve boundary_;
  SegmentTree boundary_tree_;
  TriangleTree cone_;
  std::vector<WideNodeLength> cone_lengths_;
  std::vector<ConeSegment> cone_segments_;
  std::vector<SmoothRegion> smooth_regions_;
  Aabb bounds_;
  float surface_margin_ = 0;
  std::vector<float> other_winding_;
  std::vector<int8_t> sheet_jump_;
  std::vector<uint8_t> other_winding_refined_;  // per input triangle: evaluated at the fine beta
  TriangleTree sheets_;
  float sheet_level_ = __builtin_nanf("");
  uint32_t max_leaf_triangles_ = 4;
  BuildTimings timings_;
};

}  // namespace gwnrt
