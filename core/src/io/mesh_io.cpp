// load_mesh (gwnrt/io/mesh_io.h): the reader chosen by the extension, then validate_mesh.
#include "gwnrt/io/mesh_io.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <filesystem>
#include <limits>
#include <vector>

#include "gwnrt/geometry/mesh.h"
#include "gwnrt/geometry/weld.h"
#include "gwnrt/io/read_file.h"
#include "io/readers.h"
#include "io/text.h"

namespace gwnrt {
namespace {

// MeshLoadOptions::recentre: the origin for `world` (the positions in double, one per vertex), or
// zero when the mesh lies near enough the origin for its size.
dvec3 recentred_origin(const std::vector<dvec3>& world, const std::vector<uvec3>& triangles) {
  dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
  for (const uvec3& t : triangles)
    for (int k = 0; k < 3; ++k) {
      lo = glm::min(lo, world[t[k]]);
      hi = glm::max(hi, world[t[k]]);
    }
  // Also moved: a mesh beyond the coordinates a model serves (kMaxMeshCoordinate) though not far
  // for its size (2e7 across at 1e8), which moving may bring within them.
  return recentring_origin(lo, hi, double(kMaxMeshCoordinate));
}

Status load_mesh_unguarded(const std::string& path, Mesh& mesh, MeshLoadReport* report,
                           const MeshLoadOptions& options) {
  if (options.recentre && !report)
    return {StatusCode::kInvalidArgument,
            cat(path, ": MeshLoadOptions::recentre needs a MeshLoadReport to return the origin in")};
  const std::string ext = io::lower_extension(path);
  const bool is_obj = ext == ".obj", is_stl = ext == ".stl";
  if (!is_obj && !is_stl && ext != ".ply") {
    return {StatusCode::kInvalidArgument,
            cat(path, ": unsupported mesh file extension '", ext, "' (expected .obj, .ply or .stl)")};
  }
  if (!(options.weld_tolerance >= 0 && options.weld_tolerance <= kMaxWeldTolerance)) {
    return {StatusCode::kInvalidArgument, cat(path, ": weld tolerance ", options.weld_tolerance, " is not in [0, ",
                                              kMaxWeldTolerance, "] (a fraction of the box's diagonal)")};
  }
  std::string data;
  ReadLimits limits;
  // Lines are checked in a PLY's header and ASCII body, and in an ASCII STL.
  if (!is_obj) limits.text_end = is_stl ? io::stl_text_end : io::ply_text_end;
  if (Status s = read_file(path, data, limits); !s.ok()) return s;
  // A UTF-8 byte-order mark (some Windows editors write one) is not content: left in, it would
  // glue itself to the first keyword and the OBJ reader would skip that line.
  std::string_view content = data;
  if (content.substr(0, 3) == "\xEF\xBB\xBF") content.remove_prefix(3);

  Mesh m;
  MeshLoadReport rep;
  std::vector<dvec3> world;
  std::vector<dvec3>* const wide = options.recentre ? &world : nullptr;
  Status s = is_obj   ? io::read_obj(path, content, m, rep, wide)
             : is_stl ? io::read_stl(path, content, m, rep, wide)
                      : io::read_ply(path, content, m, rep, wide);
  if (!s.ok()) return s;
  if (!is_stl) rep.file_vertices = m.positions.size();
  if (s = validate_mesh(m, path); !s.ok()) return s;
  if (options.recentre) {
    rep.origin = recentred_origin(world, m.triangles);
    if (rep.origin != dvec3(0.0)) {
      for (size_t i = 0; i < world.size(); ++i) {
        const dvec3 moved = world[i] - rep.origin;
        m.positions[i] = vec3(moved);
        // Only a vertex no triangle uses, far from the rest, can leave float's range here.
        if (!(std::fabs(moved.x) <= FLT_MAX && std::fabs(moved.y) <= FLT_MAX && std::fabs(moved.z) <= FLT_MAX)) {
          return {StatusCode::kInvalidMesh,
                  cat(path, ": vertex ", i, " (counting from 0), at (", world[i].x, ", ", world[i].y, ", ", world[i].z,
                      "), is beyond float's range from the origin the mesh is recentred about (", rep.origin.x, ", ",
                      rep.origin.y, ", ", rep.origin.z, ")")};
        }
      }
    }
  }

  if (options.weld_tolerance > 0) {
    dvec3 lo(INFINITY), hi(-INFINITY);
    for (const uvec3& t : m.triangles)
      for (int k = 0; k < 3; ++k) {
        lo = glm::min(lo, dvec3(m.positions[t[k]]));
        hi = glm::max(hi, dvec3(m.positions[t[k]]));
      }
    rep.tolerance_welded = weld_within(m, options.weld_tolerance * glm::length(hi - lo));
  }
  if (options.summarize_weld) rep.weld = summarize_weld(m);
  rep.vertex_count = m.positions.size();
  rep.triangle_count = m.triangles.size();
  rep.uv_count = m.uvs.size();
  rep.has_colors = !m.colors.empty();
  for (const uvec3& t : m.triangles) {
    rep.degenerate_triangles += is_degenerate_triangle(m.positions[t.x], m.positions[t.y], m.positions[t.z]);
  }
  mesh = std::move(m);
  if (report) *report = std::move(rep);
  return Status::Ok();
}

}  // namespace

std::string recentred_note(const dvec3& origin) {
  if (origin == dvec3(0.0)) return "";
  return cat(" (coordinates relative to (", origin.x, ", ", origin.y, ", ", origin.z, "), the mesh being recentred)");
}

dvec3 recentring_origin(const dvec3& lo, const dvec3& hi, double max_coordinate) {
  const dvec3 far = glm::max(glm::abs(lo), glm::abs(hi));
  const double largest = std::max({far.x, far.y, far.z});
  const double diagonal = glm::length(hi - lo);
  if (!(largest > kRecentreCoordinatePerDiagonal * diagonal) && !(largest > max_coordinate)) return dvec3(0.0);
  const dvec3 centre = 0.5 * lo + 0.5 * hi;  // halves first: lo + hi may overflow
  if (diagonal == 0) return centre;          // one point: every triangle has zero area anyway
  const double step = std::exp2(std::floor(std::log2(diagonal)));
  return glm::round(centre / step) * step;
}

Status load_mesh(const std::string& path, Mesh& mesh, MeshLoadReport* report, const MeshLoadOptions& options) {
  return guard_status(path.c_str(), [&] { return load_mesh_unguarded(path, mesh, report, options); });
}

}  // namespace gwnrt
