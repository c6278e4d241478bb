// gwnrt-render: an offline path tracer on Embree whose scenes hold GWN objects (the surface
// S = ∂{w > level} of a mesh, through the gwnrt Embree plugin) beside ordinary triangle meshes.
//   gwnrt-render SCENE.json        renders a scene file (scene.h documents the format)
//   gwnrt-render MESH              renders the default scene: the mesh as a GWN object on a
//                                  ground plane under a sky and a sun
// Output: PNG (tone-mapped sRGB) or EXR (linear; --aovs adds albedo, normal, depth).
// --integrator first-hit keeps the first version: one Harnack-traced ray per pixel, shaded by
// normal or headlight, with its statistics image.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>
#include <tbb/global_control.h>

#include "camera.h"
#include "integrators/path.h"
#include "render_scene.h"
#include "scene.h"
#include "gwnrt/batch.h"
#include "gwnrt/geometry/mesh.h"
#include "gwnrt/geometry/model.h"
#include "image_output.h"
#include "load_model.h"
#include "integrators/first_hit.h"
#include "progress_bar.h"
#include "shading.h"
#include "trace_level.h"

namespace {

namespace fs = std::filesystem;
using gwnrt::render::ImageFormat;

constexpr const char* kProgram = "gwnrt-render";
// Far above any screen, far below where width·height·channels floats would overflow memory sizes.
constexpr int kMaxImageSide = 32768;

int fail(const std::string& message) {
  std::fprintf(stderr, "%s: %s\n", kProgram, message.c_str());
  return 1;
}

void warn(const std::string& message) { std::fprintf(stderr, "%s: warning: %s\n", kProgram, message.c_str()); }


// CLI11 reads "nan" and "inf" as numbers; none of the options here means anything with them.
std::optional<std::string> check_finite(const char* option, double value) {
  if (std::isfinite(value)) return std::nullopt;
  return std::string(option) + " must be a finite number";
}

// An output path's format, or why it cannot be written: checked before the mesh is loaded so a
// long render is never thrown away at the end.
std::optional<std::string> check_output_path(const char* option, const std::string& path, bool create_parent) {
  if (!gwnrt::render::image_format_for(path)) {
    return std::string(option) + " " + path + ": unknown image extension (supported: " +
           gwnrt::render::supported_image_extensions() + ")";
  }
  const fs::path parent = fs::path(path).parent_path();
  if (parent.empty()) return std::nullopt;
  std::error_code ec;
  if (create_parent) {
    fs::create_directories(parent, ec);
    if (ec) return std::string(option) + " " + path + ": cannot create directory " + parent.string() + ": " + ec.message();
  } else if (!fs::is_directory(parent, ec)) {
    return std::string(option) + " " + path + ": directory " + parent.string() + " does not exist";
  }
  return std::nullopt;
}

// "1 ray", "2 rays".
std::string count_of(uint64_t n, const char* noun) {
  return std::to_string(n) + " " + noun + (n == 1 ? "" : "s");
}

std::string command_line(int argc, char** argv) {
  std::string line;
  for (int i = 0; i < argc; ++i) line += (i ? " " : "") + std::string(argv[i]);
  return line;
}

struct PathOptions {
  std::string input, output;
  int width, height;
  bool set_width, set_height;
  int spp, max_depth;
  int64_t seed;
  bool aovs;
  int threads;
};

int run_path_tracer(PathOptions o, const std::string& description) {
  namespace render = gwnrt::render;
  if (o.spp < 0 || o.max_depth < 0) return fail("--spp and --max-depth must be at least 1");
  const bool default_output = o.output.empty();
  if (default_output) o.output = (fs::path("out") / fs::path(o.input).stem()).string() + ".png";
  if (auto why = check_output_path("-o", o.output, default_output)) return fail(*why);
  if (o.aovs && render::image_format_for(o.output) != ImageFormat::kExr) return fail("--aovs needs an .exr output");
  std::optional<tbb::global_control> thread_limit;
  if (o.threads > 0) thread_limit.emplace(tbb::global_control::max_allowed_parallelism, size_t(o.threads));
  const size_t thread_count = tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);

  render::SceneDesc scene;
  const bool is_scene = fs::path(o.input).extension() == ".json";
  if (gwnrt::Status s = is_scene ? render::load_scene(o.input, scene) : render::default_scene(o.input, scene); !s.ok())
    return fail(s.message());
  if (o.set_width || !is_scene) scene.camera.width = o.width;
  if (o.set_height || !is_scene) scene.camera.height = o.height;
  if (o.spp > 0) scene.render.spp = o.spp;
  if (o.max_depth > 0) scene.render.max_depth = o.max_depth;
  if (o.seed >= 0) scene.render.seed = uint64_t(o.seed);

  const auto t0 = std::chrono::steady_clock::now();
  render::RenderScene rs;
  if (gwnrt::Status s = rs.build(scene); !s.ok()) return fail(s.message());
  std::printf("%s: %s: %zu triangle meshes, %zu GWN objects; scene built in %.3f s\n", kProgram, o.input.c_str(),
              scene.meshes.size(), scene.gwn_objects.size(), gwnrt::examples::seconds_since(t0));
  std::fflush(stdout);

  render::PathSettings settings;
  settings.spp = scene.render.spp;
  settings.max_depth = scene.render.max_depth;
  settings.seed = scene.render.seed;
  settings.aovs = o.aovs;
  std::atomic<size_t> progress{0};
  render::PathRender result;
  {
    gwnrt::examples::ProgressBar bar(progress, size_t(scene.camera.width) * size_t(scene.camera.height), "px");
    result = render::render_paths(rs, settings, &progress);
  }
  const double pixels = double(scene.camera.width) * double(scene.camera.height);
  std::printf("%s: %dx%d, %d spp in %.2f s on %s: %.3f us per sample per pixel (%s samples/s)\n", kProgram,
              scene.camera.width, scene.camera.height, settings.spp, result.seconds,
              count_of(thread_count, "thread").c_str(), 1e6 * result.seconds / (pixels * settings.spp),
              gwnrt::examples::human_count(double(result.samples) / result.seconds).c_str());
  const bool png = render::image_format_for(o.output) == ImageFormat::kPng;
  if (gwnrt::Status s = render::write_image(o.output, png ? render::tone_mapped(result.image) : result.image, description);
      !s.ok())
    return fail(s.message());
  std::printf("%s: wrote %s\n", kProgram, o.output.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Path-trace a scene whose GWN objects (the surface S = boundary of {w > level} of a mesh) sit "
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

  app.add_option("input", mesh_path, "Scene file (.json) or triangle mesh (.obj or .ply)")->required();
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
  app.add_option("--fov", fov, "Vertical field of view, degrees in (0, 180)")
      ->type_name("DEG")
      ->capture_default_str();
  app.add_option("--mode", mode_name,
                 "gwn: S = boundary of {w > level}, sheets and smooth pieces; solid-angle: the level set "
                 "{Omega = level mod 4 pi}, smooth pieces only")
      ->capture_default_str()
      ->check(CLI::IsMember({"gwn", "solid-angle"}));
  app.add_option("--level", level,
                 "gwn mode: the value of w (default 0.5); solid-angle mode: an angle in radians (default 2 pi)")
      ->type_name("L");
  app.add_option("--eps", epsilon, "Harnack stopping distance, relative to the mesh's box diagonal")
      ->type_name("E")
      ->capture_default_str();
  app.add_option("--max-steps", max_steps, "Harnack steps per ray before it is given up (counted as capped)")
      ->type_name("N")
      ->capture_default_str();
  app.add_option("--beta", beta, "Accuracy of the multipole evaluation: expand a cluster beyond beta * radius")
      ->type_name("B")
      ->capture_default_str();
  app.add_option("--threads", threads, "CPU threads (default: all)")->type_name("N");
  app.add_option("--stats-image", stats_path,
                 "Also write a false-colour image of Harnack steps per pixel (.png, or .exr with the raw counts)")
      ->type_name("FILE");

  // Usage errors read like every other error of this program, and exit with 1 as they do.
  app.failure_message([](const CLI::App*, const CLI::Error& e) {
    return std::string(kProgram) + ": " + e.what() + "\nRun with --help for more information.\n";
  });
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 1;  // --help is a ParseError too, and succeeds
  }

  // Everything the user typed is checked before the mesh is loaded and built.
  if (width < 1 || width > kMaxImageSide || height < 1 || height > kMaxImageSide) {
    return fail("--width and --height must lie in [1, " + std::to_string(kMaxImageSide) + "], got " +
                std::to_string(width) + "x" + std::to_string(height));
  }
  for (const auto& [name, value] : {std::pair{"--azimuth", azimuth}, std::pair{"--elevation", elevation},
                                    std::pair{"--fov", fov}, std::pair{"--eps", epsilon}, std::pair{"--beta", beta}}) {
    if (auto why = check_finite(name, value)) return fail(*why);
  }
  if (level) {
    if (auto why = check_finite("--level", *level)) return fail(*why);
  }
  if (elevation < -90.0 || elevation > 90.0) return fail("--elevation must lie in [-90, 90] degrees");
  if (!(fov > 0.0 && fov < 180.0)) return fail("--fov must lie in (0, 180) degrees");
  if (max_steps < 1 || max_steps > int64_t(UINT32_MAX)) {
    return fail("--max-steps must lie in [1, " + std::to_string(UINT32_MAX) + "], got " + std::to_string(max_steps));
  }
  if (app.count("--threads") && threads < 1) return fail("--threads must be at least 1");

  if (integrator == "path") {
    PathOptions po{mesh_path, output_path, width, height, app.count("--width") > 0, app.count("--height") > 0,
                   spp, max_depth, seed, aovs, threads};
    return run_path_tracer(po, command_line(argc, argv));
  }
  if (fs::path(mesh_path).extension() == ".json") return fail("--integrator first-hit renders a mesh, not a scene file");

  gwnrt::TraceOptions trace = defaults;
  gwnrt::examples::set_trace_surface(mode_name, level, trace);
  const bool solid_angle = trace.mode == gwnrt::TraceMode::kSolidAngle;
  trace.epsilon = float(epsilon);
  trace.max_steps = uint32_t(max_steps);
  trace.beta = float(beta);
  if (gwnrt::Status s = gwnrt::validate_trace_options(trace); !s.ok()) return fail(s.message());

  const bool default_output = output_path.empty();
  if (default_output) output_path = (fs::path("out") / fs::path(mesh_path).stem()).string() + ".png";
  if (auto why = check_output_path("-o", output_path, default_output)) return fail(*why);
  if (!stats_path.empty()) {
    if (auto why = check_output_path("--stats-image", stats_path, false)) return fail(*why);
    std::error_code stats_ec, output_ec;
    const fs::path stats_file = fs::weakly_canonical(stats_path, stats_ec);
    const fs::path output_file = fs::weakly_canonical(output_path, output_ec);
    if (!stats_ec && !output_ec && stats_file == output_file) {
      return fail("--stats-image and the output are the same file: " + stats_path);
    }
  }

  std::optional<tbb::global_control> thread_limit;
  if (threads > 0) thread_limit.emplace(tbb::global_control::max_allowed_parallelism, size_t(threads));
  const size_t thread_count = tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);

  gwnrt::GwnModel model;
  gwnrt::examples::ModelLoad loaded;
  if (gwnrt::Status s = gwnrt::examples::load_model(mesh_path, model, loaded); !s.ok()) return fail(s.message());
  const double load_seconds = loaded.load_seconds, build_seconds = loaded.build_seconds;
  const size_t boundary_segments = model.boundary().segment_count();
  std::printf("%s: %s: %zu triangles, %zu boundary segments%s; loaded in %.3f s, built in %.3f s\n", kProgram,
              mesh_path.c_str(), loaded.report.triangle_count, boundary_segments, boundary_segments ? "" : " (closed)",
              load_seconds, build_seconds);
  std::fflush(stdout);
  if (solid_angle && boundary_segments == 0) {
    // Off a closed mesh Ω is a whole multiple of 4π: there is no level set to see.
    warn("the mesh is closed: in solid-angle mode there is nothing to render");
  }

  const gwnrt::examples::PinholeCamera camera =
      gwnrt::examples::frame_box(model.bounds(), width, height, float(azimuth), float(elevation), float(fov));
  gwnrt::render::PrimaryRenderSettings settings;
  settings.shading = shading_name == "normal" ? gwnrt::render::ShadingMode::kNormal
                                              : gwnrt::render::ShadingMode::kHeadlight;
  settings.trace = trace;

  std::atomic<size_t> progress{0};
  gwnrt::render::PrimaryRender render;
  {
    gwnrt::examples::ProgressBar bar(progress, size_t(width) * size_t(height), "px");
    render = gwnrt::render::render_primary(gwnrt::model_view(model), camera, settings, &progress);
  }

  const gwnrt::render::RenderStats& stats = render.stats;
  const double rays_per_second = render.seconds > 0 ? double(stats.rays) / render.seconds : 0.0;
  std::printf("%s: %dx%d in %.3f s on %s: %s rays/s, %.2f steps/ray (max %u), %.2f crossings/ray; "
              "hits: %llu sheet, %llu smooth, %llu missed; %llu capped\n",
              kProgram, width, height, render.seconds, count_of(thread_count, "thread").c_str(), gwnrt::examples::human_count(rays_per_second).c_str(),
              stats.mean_steps(), stats.max_steps, stats.mean_crossings(),
              (unsigned long long)stats.sheet_hits, (unsigned long long)stats.smooth_hits,
              (unsigned long long)(stats.rays - stats.sheet_hits - stats.smooth_hits),
              (unsigned long long)(stats.step_capped + stats.crossing_capped));
  std::fflush(stdout);
  if (stats.step_capped) {
    warn(count_of(stats.step_capped, "ray") + " hit the step cap (--max-steps " + std::to_string(trace.max_steps) +
         "), shown as background");
  }
  if (stats.crossing_capped) {
    warn(count_of(stats.crossing_capped, "ray") + " hit the crossing cap (" +
         std::to_string(trace.max_crossings) + " crossings), shown as background");
  }
  if (stats.invalid) warn(count_of(stats.invalid, "ray") + " rejected by the tracer as invalid");
  // With the eye outside {w > level} (far from the mesh w is near 0), every first hit enters the
  // region, so its outward normal faces the eye. Solid-angle levels are crossed both ways.
  if (!solid_angle && trace.level > 0.0f && stats.facing_away) {
    warn(count_of(stats.facing_away, "hit") + " with an outward normal facing away from the camera");
  }

  const std::string description = command_line(argc, argv);
  if (gwnrt::Status s = gwnrt::render::write_image(output_path, render.colour, description); !s.ok()) {
    return fail(s.message());
  }
  std::printf("%s: wrote %s\n", kProgram, output_path.c_str());
  if (!stats_path.empty()) {
    const gwnrt::render::Image steps = gwnrt::render::steps_image(render);
    if (gwnrt::Status s = gwnrt::render::write_image(stats_path, steps, description); !s.ok()) return fail(s.message());
    if (stats.max_steps == 0) {
      std::printf("%s: wrote %s (no ray took a Harnack step: grey is a hit, black a miss)\n", kProgram,
                  stats_path.c_str());
    } else {
      std::printf("%s: wrote %s (Harnack steps per pixel, log scale from dark blue = 1 to red = %u; grey: a hit "
                  "without steps; black: a miss without steps; magenta: capped)\n",
                  kProgram, stats_path.c_str(), std::max(stats.max_steps, 2u));
    }
  }
  return 0;
}
