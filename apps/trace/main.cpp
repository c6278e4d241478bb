// gwnrt-trace: first hits of rays on the GWN surface S = ∂{w > level} of a triangle mesh (or on
// a level set of its solid angle), written as CSV in input order.
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "apps/common/cli_checks.h"
#include "apps/common/csv_writer.h"
#include "apps/common/device_choice.h"
#include "apps/common/load_model.h"
#include "apps/common/point_io.h"
#include "apps/common/program.h"
#include "apps/common/progress_bar.h"
#include "apps/common/trace_level.h"
#include "gwnrt/base/memory.h"
#include "gwnrt/geometry/mesh.h"
#include "gwnrt/model/model.h"
#include "gwnrt/query/batch.h"

namespace {

using gwnrt::Ray;
using gwnrt::RayHit;
using gwnrt::Status;
using gwnrt::StatusCode;
using gwnrt::vec3;
using gwnrt::apps::CsvWriter;
using gwnrt::apps::fail;
using gwnrt::apps::seconds_since;

constexpr const char* kProgram = "gwnrt-trace";

const char* kind_name(gwnrt::HitKind kind) {
  switch (kind) {
    case gwnrt::HitKind::kSheet:
      return "sheet";
    case gwnrt::HitKind::kSmooth:
      return "smooth";
    default:
      return "none";
  }
}

// The hit positions in the input's coordinates (about `origin`, MeshLoadReport::origin); t and the
// normals do not depend on where the mesh lies.
void write_csv(CsvWriter& csv, const std::vector<RayHit>& hits, const gwnrt::dvec3& origin) {
  for (const char* h : {"hit", "t", "px", "py", "pz", "nx", "ny", "nz", "kind", "tri", "steps", "crossings", "capped"})
    csv.field(h);
  csv.end_row();
  const float nan = std::nanf("");
  for (const RayHit& h : hits) {
    csv.field(h.hit ? 1u : 0u);
    csv.field(h.hit ? h.t : gwnrt::kInfinity);
    for (int a = 0; a < 3; ++a) csv.field(h.hit ? h.position[a] : nan, origin[a]);
    for (int a = 0; a < 3; ++a) csv.field(h.hit ? h.normal[a] : nan);
    csv.field(kind_name(h.kind));
    if (h.triangle == gwnrt::kEmptyLane) {
      csv.field("-1");
    } else {
      csv.field(unsigned(h.triangle));
    }
    csv.field(unsigned(h.steps));
    csv.field(unsigned(h.crossings));
    csv.field(h.capped ? 1u : 0u);
    csv.end_row();
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Trace rays against the generalized-winding-number surface S = boundary of {w > level} of a "
      "triangle mesh (OBJ/PLY), or against a level set of its solid angle, and write the first hits as CSV.",
      kProgram};

  std::string mesh_path, rays_path, output_path = "-", mode = "gwn", device = "cpu";
  std::optional<double> level;
  gwnrt::TraceOptions options;
  int threads = 0;
  bool verbose = false;

  double weld_tolerance = 0;
  app.add_option("mesh", mesh_path, "Triangle mesh (.obj, .ply or .stl)")->required();
  gwnrt::apps::add_weld_tolerance_option(app, weld_tolerance);
  app.add_option("--rays", rays_path, "Rays file, one 'ox oy oz dx dy dz [tnear tfar]' per line ('-' for stdin)")
      ->required();
  app.add_option("--mode", mode, "gwn: S = boundary of {w > level}; solid-angle: {Omega = level mod 4pi}")
      ->capture_default_str()
      ->check(CLI::IsMember({"gwn", "solid-angle"}));
  // The tracer's options are checked here, by their flags' names, with validate_trace_options'
  // limits (which it still applies below, naming no flag).
  app.add_option("--level", level,
                 "Target level: a value of w (gwn, default 0.5) or an angle in radians (solid-angle, "
                 "default 2pi)")
      ->check(gwnrt::apps::trace_level_number());
  app.add_option("--eps", options.epsilon, "Stopping distance, relative to the mesh's box diagonal")
      ->capture_default_str()
      ->check(gwnrt::apps::trace_epsilon_number());
  app.add_option("--max-steps", options.max_steps, "Harnack steps allowed per ray (capped rays are reported)")
      ->capture_default_str()
      ->check(gwnrt::apps::trace_cap_number());
  app.add_option("--max-crossings", options.max_crossings, "Triangle crossings allowed per ray")
      ->capture_default_str()
      ->check(gwnrt::apps::trace_cap_number());
  app.add_option("--beta", options.beta, "Accuracy of the multipole evaluation of w mod 1")
      ->capture_default_str()
      ->check(gwnrt::apps::beta_number());
  app.add_flag("--exact", options.exact, "Evaluate w mod 1 by the brute-force double sum (slow reference)");
  app.add_option("--device", device, gwnrt::apps::kDeviceHelp)
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "cpu", "cuda"}));
  app.add_option("--threads", threads, "CPU threads (default: all)")->check(gwnrt::apps::thread_count());
  app.add_option("-o,--output", output_path, "CSV output file ('-' for stdout)")->capture_default_str();
  app.add_flag("-v,--verbose", verbose,
               "Print the summary even when stderr is not a terminal, and what welding by position changed");
  if (const auto status = gwnrt::apps::parse_command_line(app, argc, argv)) return *status;
  if (const std::string clash = gwnrt::apps::first_output_clash({{"--output", output_path}}, {mesh_path, rays_path});
      !clash.empty())
    return fail(kProgram, clash);

  gwnrt::apps::set_trace_surface(mode, level, options);
  if (Status s = gwnrt::validate_trace_options(options); !s.ok()) return fail(kProgram, s.message());
  const bool chatty = verbose || ::isatty(2) == 1;

  gwnrt::Device where = gwnrt::Device::kCpu;
  if (Status s = gwnrt::apps::choose_device(kProgram, device, where); !s.ok()) return fail(kProgram, s.message());

  const gwnrt::apps::ThreadLimit thread_limit(threads);

  // Read and checked before the model is built (a mistyped line is not found after a long build),
  // in the file's coordinates; read again about the mesh's origin if it is recentred (below).
  std::vector<Ray> rays;
  std::string rays_text, rays_source;
  if (Status s = gwnrt::apps::read_text(rays_path, rays_text, rays_source); !s.ok()) return fail(kProgram, s.message());
  if (Status s = gwnrt::apps::parse_rays(rays_text, rays_source, rays); !s.ok()) return fail(kProgram, s.message());
  // Checked before the model is built and the hits allocated: with overcommit a size beyond memory would kill the
  // process later.
  if (Status s = gwnrt::check_memory(
          gwnrt::saturating_product(rays.size(), sizeof(RayHit)),
          gwnrt::source_name(rays_path) + ": the hits of its " + std::to_string(rays.size()) + " rays");
      !s.ok())
    return fail(kProgram, s.message());

  gwnrt::GwnModel model;
  gwnrt::apps::ModelLoad loaded;
  // A far-off mesh (a georeferenced scan) is traced about its own centre: the rays' origins are
  // moved by -origin, the hit positions written moved back.
  gwnrt::MeshLoadOptions load_options;
  load_options.recentre = true;
  load_options.weld_tolerance = weld_tolerance;
  load_options.summarize_weld = verbose;
  gwnrt::BuildOptions build_options;
  build_options.sheet_level = options.level;  // and so the tracer's level-free cells
  if (Status s = gwnrt::apps::load_model(mesh_path, model, loaded, build_options, load_options); !s.ok())
    return fail(kProgram, s.message());
  const gwnrt::dvec3 origin = loaded.report.origin;
  if (origin != gwnrt::dvec3(0.0)) {
    // From the text again: the origins' digits that float drops far from the mesh's origin.
    if (Status s = gwnrt::apps::parse_rays(rays_text, rays_source, rays, origin); !s.ok())
      return fail(kProgram, s.message());
  }
  std::string().swap(rays_text);
  gwnrt::apps::print_load_warnings(kProgram, mesh_path, loaded.report);
  if (verbose) gwnrt::apps::print_weld_summary(kProgram, mesh_path, loaded.report);
  gwnrt::apps::warn_if_level_out_of_reach(kProgram, model.view(), options);
  if (chatty)
    std::fprintf(stderr, "%s: %s: %zu triangles, %zu boundary segments%s; loaded and built in %.3f s\n", kProgram,
                 mesh_path.c_str(), model.mesh().triangles.size(), model.boundary().segment_count(),
                 model.boundary().segment_count() ? "" : " (closed: no Harnack steps)",
                 loaded.load_seconds + loaded.build_seconds);

  std::vector<RayHit> hits(rays.size());
  const auto t_trace = std::chrono::steady_clock::now();
  {
    const gwnrt::Engine engine(std::move(model));
    std::atomic<size_t> progress{0};
    std::optional<gwnrt::apps::ProgressBar> bar;  // the GPU's batch reports no progress
    if (where == gwnrt::Device::kCpu) bar.emplace(progress, rays.size(), "rays");
    const Status s = engine.trace_rays(where, rays, options, hits, &progress);
    bar.reset();
    if (!s.ok()) return fail(kProgram, s.message());
  }
  const double trace_seconds = seconds_since(t_trace);

  size_t hit_count = 0, capped = 0, steps = 0;
  for (const RayHit& h : hits) {
    hit_count += h.hit;
    capped += h.capped;
    steps += h.steps;
  }
  if (chatty)
    std::fprintf(stderr, "%s: %zu rays on %s in %.3f s (%.0f rays/s): %zu hits, %.1f Harnack steps per ray\n", kProgram,
                 rays.size(), gwnrt::device_name(where), trace_seconds,
                 trace_seconds > 0 ? double(rays.size()) / trace_seconds : 0.0, hit_count,
                 rays.empty() ? 0.0 : double(steps) / double(rays.size()));
  // Always said, terminal or not: a capped ray is a miss that may be wrong.
  if (capped)
    std::fprintf(stderr,
                 "%s: warning: %zu rays reached the step or crossing cap (column 'capped'); "
                 "raise --max-steps or --eps\n",
                 kProgram, capped);

  const auto csv_rows = [&](std::FILE* out) {
    CsvWriter csv(out);
    write_csv(csv, hits, origin);
    return csv.flush();
  };
  if (gwnrt::Status s = gwnrt::apps::write_output(output_path, csv_rows); !s.ok()) return fail(kProgram, s.message());
  return 0;
}
