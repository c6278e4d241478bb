// gwnrt-mesh: a closed, oriented, manifold mesh of the GWN surface S = ∂{w > level} of any
// triangle mesh (holes capped, soups repaired), by sparse dual contouring, written as PLY or OBJ.
#include <sys/resource.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "apps/common/cli_checks.h"
#include "apps/common/device_choice.h"
#include "apps/common/load_model.h"
#include "apps/common/program.h"
#include "apps/common/progress_bar.h"
#include "gwnrt/base/memory.h"
#include "gwnrt/io/mesh_writer.h"
#include "gwnrt/meshing/attribute_transfer.h"
#include "gwnrt/meshing/extract_surface.h"
#include "gwnrt/meshing/mesh_quality.h"

namespace {

using gwnrt::Status;
using gwnrt::apps::fail;
using gwnrt::apps::seconds_since;

constexpr const char* kProgram = "gwnrt-mesh";

Status parse_attributes(const std::string& list, uint32_t& out) {
  out = 0;
  std::stringstream in(list);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (item.empty()) continue;
    const uint32_t attribute = gwnrt::mesh_attribute_named(item);
    if (attribute == 0)
      return {gwnrt::StatusCode::kInvalidArgument,
              "--attributes: unknown attribute '" + item + "' (" + gwnrt::kMeshAttributeNames + ")"};
    out |= attribute;
  }
  return Status::Ok();
}

// The process's peak resident memory, in bytes (Linux reports ru_maxrss in KiB).
uint64_t peak_memory_bytes() {
  rusage usage{};
  return getrusage(RUSAGE_SELF, &usage) == 0 ? uint64_t(usage.ru_maxrss) * 1024 : 0;
}

nlohmann::json report_json(const gwnrt::MeshingStats& stats, const gwnrt::MeshQualityReport& q, double mesh_seconds,
                           size_t vertices, size_t triangles) {
  const gwnrt::MeshTopology& t = q.topology;
  const gwnrt::SurfaceDistances& d = q.distances;
  const gwnrt::MeshingPassTimes& p = stats.seconds;
  nlohmann::json j;
  j["grid"] = {stats.grid[0], stats.grid[1], stats.grid[2]};
  j["cell_size"] = stats.cell_size;
  j["vertices"] = vertices;
  j["triangles"] = triangles;
  j["topology"] = {{"boundary_edges", t.boundary_edges},
                   {"non_manifold_edges", t.non_manifold_edges},
                   {"non_manifold_vertices", t.non_manifold_vertices},
                   {"inconsistent_edges", t.inconsistent_edges},
                   {"degenerate_triangles", t.degenerate_triangles},
                   {"components", t.components},
                   {"closed_manifold", t.closed_manifold()}};
  j["self_intersections"] = q.self_intersections;
  j["distances"] = {{"chamfer", d.chamfer},
                    {"hausdorff_to_surface", d.hausdorff_to_surface},
                    {"hausdorff_from_surface", d.hausdorff_from_surface},
                    {"mean_to_surface", d.mean_to_surface},
                    {"mean_from_surface", d.mean_from_surface},
                    {"normal_deviation_mean_deg", d.normal_deviation_mean_deg},
                    {"normal_deviation_max_deg", d.normal_deviation_max_deg},
                    {"surface_points", d.surface_points},
                    {"sheet_points", d.sheet_points},
                    {"output_samples", d.output_samples}};
  j["seconds"] = {{"total", mesh_seconds},  {"scout", p.scout},   {"corners", p.corners}, {"edges", p.edges},
                  {"vertices", p.vertices}, {"faces", p.faces},   {"repair", p.repair},   {"smoothing", p.smoothing},
                  {"output", p.output},     {"report", q.seconds}};
  j["report_seconds"] = {{"topology", q.seconds_topology},
                         {"self_intersections", q.seconds_self_intersections},
                         {"to_surface", d.seconds_to_surface},
                         {"from_surface", d.seconds_from_surface}};
  j["memory"] = {{"pipeline_bytes", stats.bytes}, {"peak_resident_bytes", peak_memory_bytes()}};
  j["edges"] = {{"crossing", stats.crossing_edges},
                {"sheet", stats.sheet_edges},
                {"smooth", stats.smooth_edges},
                {"fallback", stats.fallback_edges},
                {"capped", stats.capped_edges},
                {"open", stats.open_edges},
                {"rescouted_open", stats.rescouted_open_edges}};
  j["blocks"] = {{"active", stats.active_blocks}, {"evaluated", stats.evaluated_blocks}};
  j["multi_component_cells"] = stats.multi_component_cells;
  j["repair"] = {{"pairs_found", stats.self_intersections_repaired},
                 {"rounds", stats.repair_rounds},
                 {"vertex_moves", stats.repaired_vertex_moves},
                 {"pairs_left", stats.self_intersections_left}};
  return j;
}

void print_report(const nlohmann::json& j) {
  const auto& t = j["topology"];
  const auto& d = j["distances"];
  const auto& s = j["seconds"];
  std::printf("vertices %llu, triangles %llu, components %llu\n", (unsigned long long)j["vertices"],
              (unsigned long long)j["triangles"], (unsigned long long)t["components"]);
  std::printf(
      "closed manifold: %s (boundary edges %llu, non-manifold edges %llu, non-manifold vertices %llu, "
      "inconsistent edges %llu, degenerate triangles %llu)\n",
      bool(t["closed_manifold"]) ? "yes" : "no", (unsigned long long)t["boundary_edges"],
      (unsigned long long)t["non_manifold_edges"], (unsigned long long)t["non_manifold_vertices"],
      (unsigned long long)t["inconsistent_edges"], (unsigned long long)t["degenerate_triangles"]);
  std::printf("self-intersections: %llu triangle pairs\n", (unsigned long long)j["self_intersections"]);
  std::printf("distance to S: chamfer %.6g, hausdorff output->S %.6g, S->output %.6g (cell %.6g)\n",
              double(d["chamfer"]), double(d["hausdorff_to_surface"]), double(d["hausdorff_from_surface"]),
              double(j["cell_size"]));
  std::printf("normal deviation from S: mean %.3f deg, max %.3f deg\n", double(d["normal_deviation_mean_deg"]),
              double(d["normal_deviation_max_deg"]));
  std::printf(
      "seconds: total %.3f (scout %.3f, corners %.3f, edges %.3f, vertices %.3f, faces %.3f, repair %.3f, "
      "smoothing %.3f, output %.3f); report %.3f\n",
      double(s["total"]), double(s["scout"]), double(s["corners"]), double(s["edges"]), double(s["vertices"]),
      double(s["faces"]), double(s["repair"]), double(s["smoothing"]), double(s["output"]), double(s["report"]));
  std::printf("memory: pipeline arrays %s, process peak %s\n",
              gwnrt::memory_size_text(uint64_t(j["memory"]["pipeline_bytes"])).c_str(),
              gwnrt::memory_size_text(uint64_t(j["memory"]["peak_resident_bytes"])).c_str());
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Mesh the generalized-winding-number surface S = boundary of {w > level} of a triangle mesh (OBJ/PLY): "
      "a closed, oriented, manifold mesh whatever the input (holes capped, soups repaired), written as binary "
      "PLY or OBJ.",
      kProgram};
  std::string mesh_path, output_path, method = "dc", attributes, device = "cpu";
  gwnrt::MeshingOptions options;
  std::optional<uint32_t> resolution;
  std::optional<float> cell_size;
  int threads = 0;
  bool verbose = false, report = false;
  std::string report_json_path;
  double weld_tolerance = 0;
  app.add_option("mesh", mesh_path, "Triangle mesh (.obj, .ply or .stl)")->required();
  gwnrt::apps::add_weld_tolerance_option(app, weld_tolerance);
  app.add_option("-o,--output", output_path, "Output mesh (.ply, .obj or .stl)")->required();
  auto* res = app.add_option(
      "--resolution", resolution,
      "Cells along the longest side of the mesh's box (default " + std::to_string(options.resolution) + ")");
  app.add_option("--cell-size", cell_size, "Cell size in the mesh's units (instead of --resolution)")->excludes(res);
  app.add_option("--method", method, "dc: dual contouring; mc: marching cubes")
      ->capture_default_str()
      ->check(CLI::IsMember({"dc", "mc"}));
  app.add_option("--level", options.level, "The level w* of S = boundary of {w > w*}")->capture_default_str();
  app.add_option("--smooth-angle", options.smooth_angle,
                 "Average vertex normals with neighbours within this angle in degrees (0: off)")
      ->capture_default_str();
  app.add_flag("--soup", options.soup, "Write a triangle soup (three vertices of its own per triangle)");
  bool no_repair = false;
  app.add_flag("--no-repair", no_repair,
               "Leave the vertices where dual contouring puts them: skip the exact search for intersecting "
               "triangles and their repair (faster; the output may then intersect itself)");
  app.add_option("--attributes", attributes, "Per-vertex attributes to carry from the input: source,uv,color");
  app.add_option("--threads", threads, "CPU threads (default: all)")->check(gwnrt::apps::thread_count());
  app.add_option("--device", device, gwnrt::apps::kDeviceHelp)
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "cpu", "cuda"}));
  app.add_flag("--report", report,
               "Print a quality report: topology, self-intersections, distances to S (from samples that follow "
               "the output's size), time per pass, memory");
  app.add_option("--report-json", report_json_path, "Write the quality report as JSON to this file");
  app.add_flag("-v,--verbose", verbose,
               "Print the summary even when stderr is not a terminal, and what welding by position changed");
  if (const auto status = gwnrt::apps::parse_command_line(app, argc, argv)) return *status;
  const bool chatty = verbose || ::isatty(2) == 1;

  if (const std::string clash = gwnrt::apps::first_output_clash(
          {{"--output", output_path}, {"--report-json", report_json_path}}, {mesh_path});
      !clash.empty())
    return fail(kProgram, clash);
  if (resolution) options.resolution = *resolution;
  if (cell_size) options.cell_size = *cell_size;
  options.repair_self_intersections = !no_repair;
  if (cell_size && !(*cell_size > 0.0f)) return fail(kProgram, "--cell-size must be a number > 0");
  if (resolution && *resolution == 0) return fail(kProgram, "--resolution must be at least 1");
  (void)gwnrt::meshing_method_named(method, options.method);  // --method's check took only these names
  if (Status s = parse_attributes(attributes, options.attributes); !s.ok()) return fail(kProgram, s.message());
  gwnrt::Device where = gwnrt::Device::kCpu;
  if (Status s = gwnrt::apps::choose_device(kProgram, device, where); !s.ok()) return fail(kProgram, s.message());
  // The mesher refuses a grid beyond its budget, saying what it would need; a budget beyond the
  // memory available would let the kernel kill the process instead, or on the GPU
  // fail an allocation half-way.
  const uint64_t available = gwnrt::available_memory_on(where);
  const bool budget_is_available_memory = available < options.memory_budget;
  if (budget_is_available_memory) options.memory_budget = available;
  const gwnrt::apps::ThreadLimit thread_limit(threads);

  gwnrt::GwnModel model;
  gwnrt::apps::ModelLoad loaded;
  // A far-off scan is meshed about its own centre and written back where it was.
  gwnrt::MeshLoadOptions load_options;
  load_options.recentre = true;
  load_options.weld_tolerance = weld_tolerance;
  load_options.summarize_weld = verbose;
  // The sheets for the level meshed: the scout's exact bound and --report both read them (at 0.5
  // alone, --report at any other level had failed after writing the mesh). A level the mesher
  // refuses keeps the default, and the mesher says why.
  gwnrt::BuildOptions build_options;
  if (std::isfinite(options.level) && options.level != 0.0f) build_options.sheet_level = options.level;
  if (Status s = gwnrt::apps::load_model(mesh_path, model, loaded, build_options, load_options); !s.ok())
    return fail(kProgram, s.message());
  if (chatty)
    std::fprintf(stderr, "%s: %s: %zu triangles, %zu boundary segments%s%s; loaded and built in %.3f s\n", kProgram,
                 mesh_path.c_str(), model.mesh().triangles.size(), model.boundary().segment_count(),
                 loaded.report.uv_count ? (", " + std::to_string(loaded.report.uv_count) + " UVs").c_str() : "",
                 loaded.report.has_colors ? ", vertex colours" : "", loaded.load_seconds + loaded.build_seconds);
  if (Status a = gwnrt::check_attributes(model.mesh(), options.attributes); !a.ok())
    return fail(kProgram, mesh_path + ": " + a.message());
  gwnrt::apps::print_load_warnings(kProgram, mesh_path, loaded.report);
  if (verbose) gwnrt::apps::print_weld_summary(kProgram, mesh_path, loaded.report);
  if (!loaded.report.attributes_dropped.empty())
    std::fprintf(stderr, "%s: %s: note: %s\n", kProgram, mesh_path.c_str(), loaded.report.attributes_dropped.c_str());

  gwnrt::SurfaceMesh out;
  gwnrt::MeshingStats stats;
  std::atomic<size_t> done{0}, total{0};
  options.progress = &done;
  options.progress_total = &total;
  Status s;
  double upload_seconds = 0;
  auto t0 = std::chrono::steady_clock::now();
  const gwnrt::Engine engine(std::move(model));
  if (where == gwnrt::Device::kCuda) {
    // Timed apart: the mesher's time is after the upload (the sheets are classified before it).
    s = engine.upload();
    upload_seconds = seconds_since(t0);
    t0 = std::chrono::steady_clock::now();
    if (s.ok()) s = engine.extract_surface(where, options, out, &stats);
  } else {
    gwnrt::apps::ProgressBar bar(done, total, "items");
    s = engine.extract_surface(where, options, out, &stats);
  }
  if (!s.ok() && s.code() == gwnrt::StatusCode::kOutOfMemory && budget_is_available_memory)
    return fail(kProgram, s.message() + " (the memory available now)");
  if (!s.ok()) return fail(kProgram, s.message());
  const double mesh_seconds = seconds_since(t0);
  if (!stats.message.empty()) std::fprintf(stderr, "%s: %s\n", kProgram, stats.message.c_str());
  const auto t_write = std::chrono::steady_clock::now();
  gwnrt::MeshWriteOptions write_options;
  write_options.origin = loaded.report.origin;
  if (Status w = gwnrt::write_surface_mesh(output_path, out, write_options); !w.ok())
    return fail(kProgram, w.message());
  if (chatty)
    std::fprintf(stderr,
                 "%s: %.3f s on the %s (+ %s%.3f s to write): %ux%ux%u cells of %g, %llu active "
                 "blocks, %zu vertices, %zu triangles\n",
                 kProgram, mesh_seconds, where == gwnrt::Device::kCuda ? "GPU" : "CPU",
                 where == gwnrt::Device::kCuda ? (std::to_string(upload_seconds) + " s to upload, ").c_str() : "",
                 seconds_since(t_write), stats.grid[0], stats.grid[1], stats.grid[2], double(stats.cell_size),
                 (unsigned long long)stats.active_blocks, out.positions.size(), out.triangles.size());
  if (verbose) {
    const gwnrt::MeshingPassTimes& t = stats.seconds;
    std::fprintf(stderr,
                 "%s: passes (s): scout %.3f, corners %.3f (%llu blocks), edges %.3f (%llu: %llu sheet, %llu smooth), "
                 "vertices %.3f, faces %.3f, repair %.3f (%llu intersecting pairs, %llu vertex moves), smoothing %.3f, "
                 "output %.3f; %s at the peak\n",
                 kProgram, t.scout, t.corners, (unsigned long long)stats.evaluated_blocks, t.edges,
                 (unsigned long long)stats.crossing_edges, (unsigned long long)stats.sheet_edges,
                 (unsigned long long)stats.smooth_edges, t.vertices, t.faces, t.repair,
                 (unsigned long long)stats.self_intersections_repaired, (unsigned long long)stats.repaired_vertex_moves,
                 t.smoothing, t.output, gwnrt::memory_size_text(stats.bytes).c_str());
  }
  if (report || !report_json_path.empty()) {
    gwnrt::MeshQualityReport quality;
    gwnrt::SurfaceDistanceOptions distance_options = gwnrt::samples_for_output(out.triangles.size());
    distance_options.level = options.level;
    // A soup's corners, and the copies a UV seam splits off, are welded by position: the
    // topology is the surface's, not the texture's.
    const bool weld = options.soup || !out.uvs.empty();
    if (Status q = gwnrt::mesh_quality_report(engine.model(), out, distance_options, quality, weld); !q.ok())
      return fail(kProgram, "--report: " + q.message());
    const nlohmann::json j = report_json(stats, quality, mesh_seconds, out.positions.size(), out.triangles.size());
    if (report) print_report(j);
    if (!report_json_path.empty()) {
      if (Status w = gwnrt::apps::write_text_file(report_json_path, j.dump(2) + "\n"); !w.ok())
        return fail(kProgram, w.message());
    }
  }
  if (stats.open_edges)
    std::fprintf(stderr, "%s: warning: %llu crossing edges lacked a cell (the output has holes there)\n", kProgram,
                 (unsigned long long)stats.open_edges);
  if (stats.self_intersections_left)
    std::fprintf(stderr, "%s: warning: %llu pairs of triangles still intersect after the repair's last round\n",
                 kProgram, (unsigned long long)stats.self_intersections_left);
  if (stats.capped_edges)
    std::fprintf(stderr, "%s: warning: %llu edges reached the crossing or root-step cap\n", kProgram,
                 (unsigned long long)stats.capped_edges);
  return 0;
}
