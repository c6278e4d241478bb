// The boundary curve ∂M, its loops, and the cone C over it (built in
// core/src/geometry/boundary.cpp; docs/design.md §3).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "gwnrt/geometry/mesh.h"
#include "gwnrt/geometry/model_view.h"
#include "gwnrt/geometry/triangle_tree.h"

namespace gwnrt {

// ∂M: the edges whose oriented half-edges do not cancel. Vertices are matched by position
// (bit-identical coordinates), so a soup that repeats shared vertices still cancels; zero-area
// triangles are left out (they contribute nothing to w). An edge a->b whose half-edges sum to
// k != 0 appears |k| times, oriented by the sign of k.
struct BoundaryCurve {
  std::vector<vec3> endpoints;  // 2 per segment: a, b
  std::size_t segment_count() const { return endpoints.size() / 2; }
};
BoundaryCurve extract_boundary(const Mesh& mesh);
// The same with vertices matched by `vertex_of` (one id per vertex; equal ids are one vertex):
// extract_boundary(mesh) is this with vertices_by_position (geometry/weld.h), the identity matches
// them by index.
BoundaryCurve extract_boundary(const Mesh& mesh, std::span<const uint32_t> vertex_of);

// Connected components of ∂M (loops, or any closed chains): the loop index of each segment.
std::vector<uint32_t> boundary_loops(const BoundaryCurve& curve, uint32_t& loop_count);

// The cone C over ∂M (see ModelView::cone): one triangle (z_l, a, b) per segment a→b, z_l the
// mean of its loop's endpoints; a and b are the very same floats as the curve's (so crossings
// of M and C agree on shared edges).
Mesh boundary_cone(const BoundaryCurve& curve, std::span<const uint32_t> loop_of_segment, uint32_t loop_count);

// A surface S with ∂S = ∂M whose triangles stay near the part of ∂M they span, where the cone's
// reach from one apex across the whole loop: the segments are cut into compact groups of up to
// kSpanningGroup (median splits of their midpoints); each group is fanned from its mean, which
// leaves as its boundary the group's segments plus spokes from the mean to the group's loose ends;
// those spokes, reversed, are a closed curve of a quarter the segments or fewer along a smooth
// ∂M, spanned the same way, level by level. Used to classify the sheets of a fan whose cone is
// itself a fan (sheets.h): a point sees O(log n) of S's clusters where it sees all of C's.
inline constexpr std::size_t kSpanningGroup = 8;
struct SpanningSurface {
  Mesh mesh;  // a soup: three positions a triangle; zero-area triangles (a mean on its segment's line) kept
  // Segments fanned from one apex at the end because a level's spokes stopped shrinking (a
  // boundary of many small scattered loops, as in a soup): S is then no better than C there.
  std::size_t single_apex_segments = 0;
};
SpanningSurface spanning_surface(const BoundaryCurve& curve);

// Per cone triangle (leaf order), the segment of ∂M it carries (its edge 1 -> 2); per lane of
// the cone's tree, the length of ∂M below it.
std::vector<ConeSegment> cone_segments(const TriangleTree& cone);
std::vector<WideNodeLength> cone_boundary_lengths(const TriangleTree& cone);

}  // namespace gwnrt
