// gwnrt-render: an offline path tracer on Embree whose scenes hold GWN objects (the surface
// S = ∂{w > level} of a mesh, through the gwnrt Embree plugin) beside ordinary triangle meshes.
//   gwnrt-render SCENE.json        renders a scene file (scene.h documents the format)
//   gwnrt-render MESH              renders the default scene: the mesh as a GWN object on a
//                                  ground plane under a sky and a sun
// Output: PNG (tone-mapped sRGB) or EXR (linear; --aovs adds albedo, normal, depth).
// --integrator first-hit keeps the first version: one Harnack-traced ray per pixel, shaded by
// normal or headlight, with its statistics image.
#include <cmath>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <new>
#include <optional>
#include <string>
#include <system_error>
#include <utility>

#include <CLI/CLI.hpp>

#include "apps/common/cli_checks.h"
#include "apps/common/device_choice.h"
#include "apps/common/program.h"
#include "apps/common/trace_level.h"
#include "gwnrt/io/output_file.h"
#include "gwnrt/query/validation.h"
#include "render/image_output.h"
#include "render/integrators/first_hit.h"
#include "render/integrators/path.h"
#include "render/render_program.h"

namespace {

namespace fs = std::filesystem;
using gwnrt::render::ImageFormat;
using gwnrt::render::kProgram;

// Far above any screen, far below where width·height·channels floats would overflow memory sizes.
constexpr int kMaxImageSide = 32768;

int fail(const std::string& message) { return gwnrt::apps::fail(kProgram, message); }

// CLI11 reads "nan" and "inf" as numbers; none of the options here means anything with them.
std::optional<std::string> check_finite(const char* option, double value) {
  if (std::isfinite(value)) return std::nullopt;
  return std::string(option) + " must be a finite number";
}

// An output path's format, or why it cannot be written (tried by opening it for writing):
// checked before the mesh is loaded so a long render is never thrown away at the end.
std::optional<std::string> check_output_path(const char* option, const std::string& path, bool create_parent) {
  if (!gwnrt::render::image_format_for(path)) {
    return std::string(option) + " " + path +
           ": unknown image extension (supported: " + gwnrt::render::supported_image_extensions() + ")";
  }
  const fs::path parent = fs::path(path).parent_path();
  std::error_code ec;
  if (parent.empty()) {
    // The current directory.
  } else if (create_parent) {
    fs::create_directories(parent, ec);
    if (ec)
      return std::string(option) + " " + path + ": cannot create directory " + parent.string() + ": " + ec.message();
  } else if (!fs::is_directory(parent, ec)) {
    return std::string(option) + " " + path + ": directory " + parent.string() + " does not exist";
  }
  if (auto why = gwnrt::render::check_writable(path)) return std::string(option) + " " + *why;
  return std::nullopt;
}

// Resolves -o: `path` as given, or out/<input's stem>.png (out/ made if need be) when it was not;
// then why it cannot be written, if it cannot.
std::optional<std::string> resolve_output_path(std::string& path, const std::string& input) {
  const bool default_output = path.empty();
  if (default_output) path = (fs::path("out") / fs::path(input).stem()).string() + ".png";
  if (gwnrt::Status s = gwnrt::check_output_is_not_input(path, {input}); !s.ok()) return "-o: " + s.message();
  return check_output_path("-o", path, default_output);
}

// Runs a job: the jobs return Status-checked errors and check sizes before allocating, so an
// exception here is an allocation that failed anyway (Embree's build, a mesh's model) or a bug;
// it ends with a message and exit status 1 rather than in std::terminate.
template <class Job>
int guarded(Job job) {
  try {
    return job();
  } catch (const std::bad_alloc&) {
    return fail("out of memory");
  } catch (const std::exception& e) {
    return fail(std::string("internal error: ") + e.what());
  }
}

std::string command_line(int argc, char** argv) {
  std::string line;
  for (int i = 0; i < argc; ++i) line += (i ? " " : "") + std::string(argv[i]);
  return line;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Path-trace a scene whose GWN objects (the surface S = boundary of {w > level} of a mesh) sit "
      "beside ordinary triangle meshes in Embree, from a JSON scene file or, given a mesh, a default "
      "scene; to PNG (sRGB) or EXR (linear).",
      kProgram};

  std::string mesh_path;
  std::string output_path;
  std::string integrator = "path";
  int width = 800, height = 600;
  int spp = 0, max_depth = 0;
  int64_t seed = -1;
  bool aovs = false;
  std::string shading_name = "headlight";
  double azimuth = 30.0, elevation = 20.0, fov = 40.0;
  std::string mode_name = "gwn";
  std::optional<double> level;
  const gwnrt::TraceOptions defaults;
  double epsilon = defaults.epsilon;
  int64_t max_steps = defaults.max_steps;
  double beta = defaults.beta;
  int threads = 0;
  std::string stats_path;

  app.add_option("input", mesh_path, "Scene file (.json) or triangle mesh (.obj, .ply or .stl)")->required();
  app.add_option("--integrator", integrator,
                 "path: path tracing on Embree (scene file or default scene); first-hit: one traced ray per "
                 "pixel on the mesh's S, shaded directly")
      ->capture_default_str()
      ->check(CLI::IsMember({"path", "first-hit"}));
  app.add_option("--spp", spp, "Path tracing: samples per pixel (default: the scene's, 16 for a mesh)")->type_name("N");
  app.add_option("--max-depth", max_depth, "Path tracing: bounces per path (default: the scene's, 8)")->type_name("N");
  app.add_option("--seed", seed, "Path tracing: random seed (same seed, same image)")->type_name("S");
  app.add_flag("--aovs", aovs, "Path tracing: also write albedo, normal and depth channels (EXR only)");
  app.add_option("-o,--output", output_path, "Image to write, .png or .exr (default: out/<mesh stem>.png)")
      ->type_name("FILE");
  app.add_option("--width", width, "Image width in pixels (path tracing: overrides the scene's)")
      ->type_name("W")
      ->capture_default_str();
  app.add_option("--height", height, "Image height in pixels (path tracing: overrides the scene's)")
      ->type_name("H")
      ->capture_default_str();
  app.add_option("--shading", shading_name,
                 "normal: outward normal as colour; headlight: diffuse light from the eye, smooth pieces "
                 "(filled holes) bluish")
      ->capture_default_str()
      ->check(CLI::IsMember({"normal", "headlight"}));
  app.add_option("--azimuth", azimuth, "Camera direction about +y, degrees (0 looks along -z)")
      ->type_name("DEG")
      ->capture_default_str();
  app.add_option("--elevation", elevation, "Camera height above the horizon, degrees in [-90, 90]")
      ->type_name("DEG")
      ->capture_default_str();
  app.add_option("--fov", fov, "Vertical field of view, degrees in (0, 180)")->type_name("DEG")->capture_default_str();
  app.add_option("--mode", mode_name,
                 "gwn: S = boundary of {w > level}, sheets and smooth pieces; solid-angle: the level set "
                 "{Omega = level mod 4 pi}, smooth pieces only")
      ->capture_default_str()
      ->check(CLI::IsMember({"gwn", "solid-angle"}));
  // The tracer's options are checked by their flags' names, with validate_trace_options' limits
  // (which the first hit still applies below, naming no flag).
  app.add_option("--level", level,
                 "gwn mode: the value of w (default 0.5); solid-angle mode: an angle in radians (default 2 pi)")
      ->type_name("L")
      ->check(gwnrt::apps::trace_level_number());
  app.add_option("--eps", epsilon, "Harnack stopping distance, relative to the mesh's box diagonal")
      ->type_name("E")
      ->capture_default_str()
      ->check(gwnrt::apps::trace_epsilon_number());
  app.add_option("--max-steps", max_steps, "Harnack steps per ray before it is given up (counted as capped)")
      ->type_name("N")
      ->capture_default_str()
      ->check(gwnrt::apps::trace_cap_number());
  app.add_option("--beta", beta, "Accuracy of the multipole evaluation: expand a cluster beyond beta * radius")
      ->type_name("B")
      ->capture_default_str()
      ->check(gwnrt::apps::beta_number());
  app.add_option("--threads", threads, "CPU threads (default: all)")
      ->type_name("N")
      ->check(gwnrt::apps::thread_count());
  std::string device = "cpu";
  int64_t frames = 1;
  app.add_option("--device", device, std::string("First hit: ") + gwnrt::apps::kDeviceHelp)
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "cpu", "cuda"}));
  app.add_option("--frames", frames,
                 "First hit: render the image N times and print frames per second (the last is written)")
      ->type_name("N")
      ->capture_default_str();
  app.add_option("--stats-image", stats_path,
                 "Also write a false-colour image of Harnack steps per pixel (.png, or .exr with the raw counts)")
      ->type_name("FILE");

  // Usage errors read like every other error of this program, and exit with 1 as they do.
  app.failure_message([](const CLI::App*, const CLI::Error& e) {
    return std::string(kProgram) + ": " + e.what() + "\nRun with --help for more information.\n";
  });
  if (const auto status = gwnrt::apps::parse_command_line(app, argc, argv)) return *status;

  // Everything the user typed is checked before the mesh is loaded and built.
  if (width < 1 || width > kMaxImageSide || height < 1 || height > kMaxImageSide) {
    return fail("--width and --height must lie in [1, " + std::to_string(kMaxImageSide) + "], got " +
                std::to_string(width) + "x" + std::to_string(height));
  }
  for (const auto& [name, value] :
       {std::pair{"--azimuth", azimuth}, std::pair{"--elevation", elevation}, std::pair{"--fov", fov}}) {
    if (auto why = check_finite(name, value)) return fail(*why);
  }
  if (elevation < -90.0 || elevation > 90.0) return fail("--elevation must lie in [-90, 90] degrees");
  if (!(fov > 0.0 && fov < 180.0)) return fail("--fov must lie in (0, 180) degrees");

  const std::string description = command_line(argc, argv);
  if (integrator == "path") {
    // Scene files and the default scene bring their own camera and settings; what is given here
    // overrides them.
    // 0 and negative values are refused when given: leaving an option out is
    // how the scene's value is kept.
    // Within the ranges a scene file takes (kMaxSpp, kMaxPathDepth, kMaxSeed).
    const auto in_range = [&](const char* name, int64_t value, int64_t lo, int64_t hi) {
      return !app.count(name) || (value >= lo && value <= hi);
    };
    const auto refuse = [&](const char* name, int64_t lo, int64_t hi) {
      return fail(std::string(name) + " must lie in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                  "] (leave it out for the scene's)");
    };
    if (!in_range("--spp", spp, 1, gwnrt::render::kMaxSpp)) return refuse("--spp", 1, gwnrt::render::kMaxSpp);
    if (!in_range("--max-depth", max_depth, 1, gwnrt::render::kMaxPathDepth))
      return refuse("--max-depth", 1, gwnrt::render::kMaxPathDepth);
    if (!in_range("--seed", seed, 0, gwnrt::render::kMaxSeed)) return refuse("--seed", 0, gwnrt::render::kMaxSeed);
    // The first hit's own options would be silently ignored here (`--level 1e39` exited 0): a
    // scene file sets the surface per GWN object.
    for (const char* name : {"--shading", "--azimuth", "--elevation", "--fov", "--mode", "--level", "--eps",
                             "--max-steps", "--beta", "--stats-image", "--device", "--frames"})
      if (app.count(name))
        return fail(std::string(name) +
                    " is an option of --integrator first-hit (a scene file sets the surface and "
                    "camera of the path tracer)");
    gwnrt::render::PathJob job;
    job.input = mesh_path;
    job.output = output_path;
    if (auto why = resolve_output_path(job.output, mesh_path)) return fail(*why);
    if (aovs && gwnrt::render::image_format_for(job.output) != ImageFormat::kExr)
      return fail("--aovs needs an .exr output");
    job.width = width;
    job.height = height;
    job.set_width = app.count("--width") > 0;
    job.set_height = app.count("--height") > 0;
    job.spp = spp;
    job.max_depth = max_depth;
    job.seed = seed;
    job.aovs = aovs;
    job.threads = threads;
    return guarded([&] { return gwnrt::render::run_path_job(job, description); });
  }

  if (fs::path(mesh_path).extension() == ".json")
    return fail("--integrator first-hit renders a mesh, not a scene file");
  gwnrt::render::FirstHitJob job;
  job.mesh = mesh_path;
  gwnrt::TraceOptions& trace = job.settings.trace;
  trace = defaults;
  gwnrt::apps::set_trace_surface(mode_name, level, trace);
  trace.epsilon = float(epsilon);
  trace.max_steps = uint32_t(max_steps);
  trace.beta = float(beta);
  if (gwnrt::Status s = gwnrt::validate_trace_options(trace); !s.ok()) return fail(s.message());
  job.settings.shading =
      shading_name == "normal" ? gwnrt::render::ShadingMode::kNormal : gwnrt::render::ShadingMode::kHeadlight;

  job.output = output_path;
  if (auto why = resolve_output_path(job.output, mesh_path)) return fail(*why);
  if (!stats_path.empty()) {
    if (auto why = check_output_path("--stats-image", stats_path, false)) return fail(*why);
    std::error_code stats_ec, output_ec;
    const fs::path stats_file = fs::weakly_canonical(stats_path, stats_ec);
    const fs::path output_file = fs::weakly_canonical(job.output, output_ec);
    if (!stats_ec && !output_ec && stats_file == output_file) {
      return fail("--stats-image and the output are the same file: " + stats_path);
    }
  }
  job.stats_image = stats_path;
  job.width = width;
  job.height = height;
  job.azimuth = float(azimuth);
  job.elevation = float(elevation);
  job.fov_degrees = float(fov);
  job.threads = threads;
  if (frames < 1 || frames > 100000) return fail("--frames must lie in [1, 100000], got " + std::to_string(frames));
  job.frames = int(frames);
  job.device = device;
  return guarded([&] { return gwnrt::render::run_first_hit_job(job, description); });
}
