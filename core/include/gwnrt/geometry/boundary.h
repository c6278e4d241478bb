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

// The cone C over ∂M (see ModelView::cone): a surface with boundary ∂M, built loop by loop: a fan
// from the loop's mean, or for a loop of more than kFannedLoopSegments segments that is mostly a
// curve (at most a quarter of its segments start where another does) its spanning surface
// (below), whose triangles stay near the part of the loop they span: a long loop's fan is of
// slivers that every query near the loop has to open (a scan's rim: docs/performance.md). The
// branching curves of soups and flipped faces stay fans: spanned, their spokes criss-cross and the
// expansion's error at kConeBeta grew past 1e-5. Each
// segment a -> b is carried by one triangle (z, a, b) of non-zero area, a and b the very same floats
// as the curve's (so crossings of M and C agree on shared edges): the first segment_triangles
// triangles; the others are inner (their edges are spokes between the fans' apexes).
inline constexpr std::size_t kFannedLoopSegments = 64;
struct Cone {
  Mesh mesh;                               // a soup: three positions a triangle
  std::vector<uint32_t> loop_of_triangle;  // the loop each triangle spans
  size_t segment_triangles = 0;
};
Cone boundary_cone(const BoundaryCurve& curve, std::span<const uint32_t> loop_of_segment, uint32_t loop_count);

// A surface S with ∂S = ∂M whose triangles stay near the part of ∂M they span, where a fan from
// one apex reaches across the whole curve: the segments are cut into compact groups of up to
// kSpanningGroup (median splits of their midpoints); each group is fanned from its mean (moved off
// its segments' lines), which leaves as its boundary the group's segments plus spokes from the
// mean to the group's loose ends; those spokes, reversed, are a closed curve of a quarter the
// segments or fewer along a smooth ∂M, spanned the same way, level by level. Its first
// segment_count() triangles are the first level's, (mean, a, b) per segment a -> b. Each loop of C
// is one (above); over the whole of ∂M it classifies the sheets of a fan mesh (sheets.h), where a
// point sees O(log n) of S's clusters and all of a fan's.
inline constexpr std::size_t kSpanningGroup = 8;
struct SpanningSurface {
  Mesh mesh;  // a soup: three positions a triangle; zero-area triangles (segments on one line) kept
  // Segments fanned from one apex at the end because a level's spokes stopped shrinking (a
  // boundary of many small scattered loops, as in a soup): S is then no better than C there.
  std::size_t single_apex_segments = 0;
};
SpanningSurface spanning_surface(const BoundaryCurve& curve);

// Per cone triangle (leaf order), the segment of ∂M it carries (its edge 1 -> 2; zero length for
// an inner triangle, input index segment_triangles or more); per lane of the cone's tree, the
// length of ∂M below it.
std::vector<ConeSegment> cone_segments(const TriangleTree& cone, size_t segment_triangles);
std::vector<WideNodeLength> cone_boundary_lengths(const TriangleTree& cone, size_t segment_triangles);

}  // namespace gwnrt
