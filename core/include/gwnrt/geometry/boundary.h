// The boundary curve ∂M, its loops, and the cone C over it (built in
// core/src/build/boundary.cpp; docs/design.md §3).
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

}  // namespace gwnrt
