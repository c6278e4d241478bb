// Loading a mesh file and building its GwnModel, timed, and saying what loading skipped: the start
// of every command-line program.
#pragma once

#include <chrono>
#include <cstdio>
#include <string>
#include <utility>

#include "gwnrt/geometry/mesh.h"
#include "gwnrt/io/mesh_io.h"
#include "gwnrt/model/model.h"

namespace gwnrt::apps {

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct ModelLoad {
  MeshLoadReport report;
  double load_seconds = 0;
  double build_seconds = 0;
};

// Errors name the file (the loader's messages already do; a build failure gets it prefixed).
// Programs that read and write positions in the file's coordinates recentre far-off meshes
// (MeshLoadOptions::recentre; the origin is info.report.origin).
inline Status load_model(const std::string& path, GwnModel& model, ModelLoad& info, const BuildOptions& options = {},
                         const MeshLoadOptions& load_options = {}) {
  const auto t_load = std::chrono::steady_clock::now();
  Mesh mesh;
  if (Status s = load_mesh(path, mesh, &info.report, load_options); !s.ok()) return s;
  info.load_seconds = seconds_since(t_load);
  const auto t_build = std::chrono::steady_clock::now();
  if (Status s = GwnModel::build(std::move(mesh), model, options); !s.ok()) {
    // The build names coordinates as the model holds them: say how they relate to the file's.
    return {s.code(), path + ": " + s.message() + recentred_note(info.report.origin)};
  }
  info.build_seconds = seconds_since(t_build);
  return Status::Ok();
}

// What loading skipped that the user may not expect (MeshLoadReport::warnings: OBJ lines with an
// unknown statement), as "program: path: warning: ..." on stderr; said whether or not stderr is a
// terminal, because a skipped line may be a mistyped vertex. `positions_out`: whether the
// program reads and writes positions in the file's coordinates (not the renderer's images).
inline void print_load_warnings(const char* program, const std::string& path, const MeshLoadReport& report,
                                bool positions_out = true) {
  if (!report.warnings.empty())
    std::fprintf(stderr, "%s: %s: warning: %s\n", program, path.c_str(), report.warnings.c_str());
  // Not a warning: what was done to keep a far-off mesh's precision, said because timings and
  // the library's own messages (which name model coordinates) then differ from the file's.
  if (report.origin != dvec3(0.0))
    std::fprintf(stderr, "%s: %s: far from the origin for its size: computed relative to (%.17g, %.17g, %.17g)%s\n",
                 program, path.c_str(), report.origin.x, report.origin.y, report.origin.z,
                 positions_out ? "; positions are read and written in double" : "");
}

// What welding by position did (MeshLoadReport::weld), for -v: "5931 vertices welded from 35592
// corners; boundary: 182 edges in 34 loops (35592 by index)".
inline std::string weld_summary(const MeshLoadReport& report) {
  const WeldSummary& w = report.weld;
  using std::to_string;
  std::string s;
  if (report.file_vertices != report.vertex_count)  // an STL: corners merged as they were read
    s = to_string(report.vertex_count) + " vertices from " + to_string(report.file_vertices) + " corners, ";
  s += to_string(w.positions_used) + " positions for " + to_string(w.vertices_used) + " vertices used";
  if (report.tolerance_welded) s += " (" + to_string(report.tolerance_welded) + " moved by the weld tolerance)";
  s += "; boundary: " + to_string(w.boundary_by_position) + " edges";
  if (w.boundary_loops) s += " in " + to_string(w.boundary_loops) + (w.boundary_loops == 1 ? " loop" : " loops");
  if (w.boundary_by_index != w.boundary_by_position) s += " (" + to_string(w.boundary_by_index) + " by index)";
  return s;
}

inline void print_weld_summary(const char* program, const std::string& path, const MeshLoadReport& report) {
  std::fprintf(stderr, "%s: %s: welded by position: %s\n", program, path.c_str(), weld_summary(report).c_str());
}

}  // namespace gwnrt::apps
