// Meshing S = ∂{w > w*}: sparse, manifold dual contouring on a grid (docs/design.md §11).
// The output is closed by construction: its faces are dual to the grid edges whose corner
// signs differ, and the signs are exact wherever the winding method is.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>
#include <string_view>

#include "gwnrt/base/status.h"
#include "gwnrt/field/evaluate_winding.h"
#include "gwnrt/geometry/surface_mesh.h"
#include "gwnrt/model/model.h"

namespace gwnrt {

enum class MeshingMethod : uint32_t { kDualContouring = 0, kMarchingCubes = 1 };

// The methods' names where programs and bindings take them: "dc" and "mc".
inline const char* meshing_method_name(MeshingMethod method) {
  return method == MeshingMethod::kMarchingCubes ? "mc" : "dc";
}
inline bool meshing_method_named(std::string_view name, MeshingMethod& method) {
  for (MeshingMethod m : {MeshingMethod::kDualContouring, MeshingMethod::kMarchingCubes})
    if (name == meshing_method_name(m)) {
      method = m;
      return true;
    }
  return false;
}

enum MeshAttribute : uint32_t {
  kAttributeSource = 1u << 0,  // nearest source triangle + barycentrics
  kAttributeUv = 1u << 1,
  kAttributeColor = 1u << 2,
};

// The MeshAttribute called `name`, 0 for any other name: for the programs and bindings that take
// attributes by name (kMeshAttributeNames lists the names, for their messages).
inline constexpr const char* kMeshAttributeNames = "source, uv or color";
inline uint32_t mesh_attribute_named(std::string_view name) {
  if (name == "source") return kAttributeSource;
  if (name == "uv") return kAttributeUv;
  if (name == "color") return kAttributeColor;
  return 0;
}

struct MeshingOptions {
  // Cells along the longest side of the box that holds S, or (when > 0) the cell size itself.
  uint32_t resolution = 256;
  float cell_size = 0.0f;
  float level = 0.5f;  // w*
  MeshingMethod method = MeshingMethod::kDualContouring;
  // Vertex normals averaged with the neighbouring cells' within this angle (degrees); 0: off.
  float smooth_angle = 30.0f;
  bool soup = false;  // three vertices of its own per triangle
  uint32_t attributes = 0;
  WindingOptions winding;  // how w is evaluated at the corners (auto: exact where it wins)
  // With exact w and a boundary, corners far from the level take the sign of a first-order
  // estimate whose error is bounded (field/box_winding.h) rather than their own evaluation; off:
  // every corner evaluated (the reference the tests hold it to). The mesh's topology is the same;
  // smooth Hermite points may move within the root tolerance.
  bool settle_corners_by_bounds = true;
  // Pairs of output triangles that meet other than in a shared vertex or edge (by exact
  // predicates) are repaired by moving their vertices toward their cells' safe points (dual
  // contouring only; MeshingStats says what it did). Off: the vertices stay where the QEF put them.
  bool repair_self_intersections = true;
  // Refused (with what it would need) when the pipeline's arrays would exceed this many bytes.
  uint64_t memory_budget = uint64_t(8) << 30;
  // When given: work items done, and the items known so far (grown as each pass is sized).
  std::atomic<size_t>* progress = nullptr;
  std::atomic<size_t>* progress_total = nullptr;
};

struct MeshingPassTimes {
  double scout = 0, corners = 0, edges = 0, vertices = 0, faces = 0, repair = 0, smoothing = 0, output = 0;
  double total() const { return scout + corners + edges + vertices + faces + repair + smoothing + output; }
};

struct MeshingStats {
  uint32_t grid[3] = {0, 0, 0};  // cells per axis
  float cell_size = 0;
  float origin[3] = {0, 0, 0};  // the grid's lowest corner: cell (i, j, k) spans origin + cell_size · [i, i + 1] × ...
  uint64_t active_blocks = 0;   // blocks of kBlockCells³ cells that S may meet
  uint64_t evaluated_blocks = 0;  // with their corners' neighbours
  uint64_t corners = 0;           // corner values evaluated
  uint64_t crossing_edges = 0;    // sign-changing edges (one quad each)
  uint64_t sheet_edges = 0, smooth_edges = 0, fallback_edges = 0, capped_edges = 0;
  uint64_t multi_component_cells = 0;  // cells with two or more vertices
  uint64_t open_edges = 0;  // sign-changing edges whose four cells were not all active (0 unless a bound failed)
  // Open edges of a first meshing scouted by the sheets, after which S was meshed again scouted
  // by the distance to M (the sheets miss the parts of triangles that other triangles cut).
  uint64_t rescouted_open_edges = 0;
  uint64_t bytes = 0;  // the pipeline's largest arrays together, at their peak
  // The repair: intersecting pairs found before it, rounds run, vertex moves, and pairs left
  // after its last round (0 unless it ran out of rounds).
  uint64_t self_intersections_repaired = 0;
  uint32_t repair_rounds = 0;
  uint64_t repaired_vertex_moves = 0;
  uint64_t self_intersections_left = 0;
  MeshingPassTimes seconds;
  std::string message;  // e.g. why the mesh is empty
};

// Meshes S for the options. An empty S (no corner inside, or all inside) gives an empty mesh, a
// success and stats->message saying so. Fails on a resolution of 0, a cell size that is not
// finite and > 0, a grid beyond the memory budget (saying what it would need), a level that is
// not finite or 0 (S is then unbounded), a model built without sheets for another level.
Status extract_surface(const GwnModel& model, const MeshingOptions& options, SurfaceMesh& out,
                       MeshingStats* stats = nullptr);

}  // namespace gwnrt
