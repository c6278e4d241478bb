// Sheet classification: which triangles are pieces of S for a level (computed in
// core/src/sdf/sheets.cpp; docs/design.md §4).
#pragma once

#include <cstdint>
#include <span>

#include "gwnrt/base/hd.h"
#include "gwnrt/geometry/model_view.h"
#include "gwnrt/geometry/triangle_tree.h"

namespace gwnrt {

// Sheet classification (docs/design.md §4). Across a triangle w jumps by its own ±1;
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
// The same, exactly, by crossings (field/crossing_winding.h) at every triangle of view.triangles:
// w at two points just off the centroid along the triangle's normal, either side of its stack,
// each from its own axis ray: their mean is w_o, their difference the stack's jump. `spanning` is
// the tree of a surface with boundary ∂M that stands in for the cone C (view.cone, or
// spanning_surface's when C is a fan the multipole must open at every centroid).
void other_triangles_winding_by_crossings(const ModelView& view, const TriangleTreeView& spanning, std::span<float> out,
                                          std::span<int8_t> jump);
// Whether the tree's clusters are long: a cluster's ball holds far more centroids than its
// triangles' area would suggest (a fan of slivers, every cluster of which reaches across it), so
// that the multipole opens O(n) clusters at each centroid.
bool clusters_are_long(const TriangleTreeView& tree);
// Sides within this of w* count as equal to it, for the multipole's w_o (that accurate near the
// threshold): then {w > w*} holds on the upper side only when it is really above, so a closed
// mesh is all sheets for w* = 0 and none for w* = 1, not a coin toss. Exact values (crossings)
// need no band: tolerance 0.
inline constexpr float kSheetSideTolerance = 1e-3f;
// The sides lo = w_o − |k|/2 and hi = w_o + |k|/2 straddle w*: lo <= w* < hi. False for NaN
// (zero-area triangles) and k = 0.
GWNRT_HD inline bool is_sheet(float other_winding, float level, int jump = 1, float tolerance = kSheetSideTolerance) {
  const float half = 0.5f * float(jump < 0 ? -jump : jump);
  const float at = level + tolerance;
  return jump != 0 && other_winding - half <= at && other_winding + half > at;
}

}  // namespace gwnrt
