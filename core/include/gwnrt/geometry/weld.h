// Which vertices are one (core/src/geometry/weld.cpp): files repeat a corner per facet (STL) or
// split vertices at UV and normal seams (OBJ, PLY), so topology (∂M, the cone, the sheets) goes by
// position, not by index. Exact welding moves nothing; welding within a tolerance snaps vertices
// together for files written with rounding (docs/design.md §13).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "gwnrt/geometry/mesh.h"

namespace gwnrt {

// For each vertex, the first vertex (lowest index) with bit-identical coordinates, -0 folded into
// +0: vertices with the same position share it.
std::vector<uint32_t> vertices_by_position(const std::vector<vec3>& positions);

// What welding by position changes in a mesh's topology.
struct WeldSummary {
  std::size_t vertices_used = 0;         // vertices the triangles refer to
  std::size_t positions_used = 0;        // distinct positions among them (the welded vertices)
  std::size_t boundary_by_index = 0;     // edges of ∂M when vertices are matched by index
  std::size_t boundary_by_position = 0;  // edges of ∂M after welding: what the model uses
  uint32_t boundary_loops = 0;           // its connected chains
};
WeldSummary summarize_weld(const Mesh& mesh);

// Moves every vertex within `distance` of another (chains of such pairs included) onto the position
// of the lowest-numbered vertex of its group, so that exact welding then makes them one. Triangles
// that lose an edge become degenerate (and contribute nothing). Returns how many vertices moved.
// Only vertices the triangles use take part.
std::size_t weld_within(Mesh& mesh, double distance);

}  // namespace gwnrt
