#include "render/integrators/first_hit.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "apps/common/device_choice.h"
#include "apps/common/load_model.h"
#include "apps/common/program.h"
#include "apps/common/progress_bar.h"
#include "apps/common/trace_level.h"
#include "gwnrt/base/memory.h"
#include "gwnrt/engine.h"
#include "gwnrt/model/model.h"
#include "gwnrt/query/validation.h"
#include "render/image_output.h"
#include "render/render_program.h"
#include "render/tiles.h"

#include "render/integrators/first_hit_cuda.h"

namespace gwnrt::render {

void FirstHitStats::add(const FirstHitSample& pixel, const TraceOptions& options) {
  const PixelTrace& t = pixel.trace;
  ++rays;
  steps += t.steps;
  crossings += t.crossings;
  max_steps = std::max(max_steps, t.steps);
  if (pixel.invalid) ++invalid;
  if (t.capped) {
    // RayHit says only that a cap ended the trace; which one is told by the count that reached it.
    if (t.steps >= options.max_steps)
      ++step_capped;
    else
      ++crossing_capped;
  }
  if (t.kind == HitKind::kSmooth) ++smooth_hits;
  if (t.kind == HitKind::kSheet) ++sheet_hits;
  if (pixel.facing_away) ++facing_away;
}

FirstHitStats& FirstHitStats::operator+=(const FirstHitStats& o) {
  rays += o.rays;
  steps += o.steps;
  crossings += o.crossings;
  sheet_hits += o.sheet_hits;
  smooth_hits += o.smooth_hits;
  step_capped += o.step_capped;
  crossing_capped += o.crossing_capped;
  invalid += o.invalid;
  facing_away += o.facing_away;
  max_steps = std::max(max_steps, o.max_steps);
  return *this;
}

FirstHitRender render_first_hit(const ModelView& model, const render::PinholeCamera& camera,
                                const FirstHitSettings& settings, std::atomic<std::size_t>* progress) {
  const int width = camera.width, height = camera.height;
  FirstHitRender out;
  out.colour = Image(width, height, {"R", "G", "B"});
  out.traces.resize(std::size_t(width) * std::size_t(height));

  const TileGrid grid(width, height);
  // One slot per tile, summed in tile order afterwards: the totals come out the same on every
  // run whatever the thread count, and no two tasks ever write the same counter.
  std::vector<FirstHitStats> tile_stats(std::size_t(grid.count()));

  const auto start = std::chrono::steady_clock::now();
  parallel_for_tiles(grid, [&](const Tile& tile) {
    FirstHitStats& stats = tile_stats[std::size_t(tile.index)];
    for (int y = tile.y0; y < tile.y1; ++y) {
      for (int x = tile.x0; x < tile.x1; ++x) {
        const FirstHitSample pixel = first_hit_pixel(model, camera, settings, x, y);
        out.colour.set_rgb(x, y, pixel.colour);
        out.traces[std::size_t(y) * std::size_t(width) + std::size_t(x)] = pixel.trace;
        stats.add(pixel, settings.trace);
      }
    }
    if (progress) progress->fetch_add(std::size_t(tile.pixel_count()), std::memory_order_relaxed);
  });
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  for (const FirstHitStats& s : tile_stats) out.stats += s;
  return out;
}

FirstHitRender first_hit_image(const std::vector<FirstHitSample>& pixels, const render::PinholeCamera& camera,
                               const FirstHitSettings& settings, double seconds) {
  FirstHitRender out;
  out.colour = Image(camera.width, camera.height, {"R", "G", "B"});
  out.traces.resize(pixels.size());
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      const FirstHitSample& p = pixels[std::size_t(y) * std::size_t(camera.width) + std::size_t(x)];
      out.colour.set_rgb(x, y, p.colour);
      out.traces[std::size_t(y) * std::size_t(camera.width) + std::size_t(x)] = p.trace;
      out.stats.add(p, settings.trace);
    }
  out.seconds = seconds;
  return out;
}

Image steps_image(const FirstHitRender& render, uint32_t scale_max) {
  const int width = render.colour.width(), height = render.colour.height();
  Image image(width, height, {"R", "G", "B", "steps", "crossings", "kind", "capped"});
  if (scale_max == 0) scale_max = render.stats.max_steps;
  // Step counts span orders of magnitude (a handful near most of a cap, thousands at its rim),
  // so the ramp is logarithmic: 1 step at its start, scale_max at its end.
  const float log_max = std::log2(float(std::max<uint32_t>(scale_max, 2)));
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const PixelTrace& t = render.traces[std::size_t(y) * std::size_t(width) + std::size_t(x)];
      vec3 colour;
      if (t.capped)
        colour = vec3(kStatsCapped[0], kStatsCapped[1], kStatsCapped[2]);
      else if (t.steps == 0)
        colour = vec3(t.kind == HitKind::kNone ? kStatsMissGrey : kStatsNoStepGrey);
      else
        colour = false_colour(std::log2(float(t.steps)) / log_max);
      float* p = image.pixel(x, y);
      p[0] = colour.x;
      p[1] = colour.y;
      p[2] = colour.z;
      p[3] = float(t.steps);
      p[4] = float(t.crossings);
      p[5] = float(static_cast<uint32_t>(t.kind));
      p[6] = t.capped ? 1.0f : 0.0f;
    }
  }
  return image;
}

int run_first_hit_job(const FirstHitJob& job, const std::string& description) {
  const apps::ThreadLimit thread_limit(job.threads);
  const TraceOptions& trace = job.settings.trace;
  const bool solid_angle = trace.mode == TraceMode::kSolidAngle;

  // The pixel buffers, checked against the memory available before the mesh is even loaded:
  // the colour image, the per-pixel traces, the statistics image when asked
  // for, and what writing each needs.
  const auto format_of = [](const std::string& path) { return image_format_for(path).value_or(ImageFormat::kPng); };
  uint64_t bytes_per_pixel = 4 * 3 + sizeof(PixelTrace) + write_image_bytes_per_pixel(format_of(job.output), 3);
  if (!job.stats_image.empty()) bytes_per_pixel += 4 * 7 + write_image_bytes_per_pixel(format_of(job.stats_image), 7);
  if (Status s = check_memory(saturating_product(uint64_t(job.width) * uint64_t(job.height), bytes_per_pixel),
                              "a " + std::to_string(job.width) + " x " + std::to_string(job.height) +
                                  " first-hit image" + (job.stats_image.empty() ? "" : " and its statistics image") +
                                  " (" + std::to_string(bytes_per_pixel) + " bytes per pixel)");
      !s.ok())
    return apps::fail(kProgram, s.message());

  Device where = Device::kCpu;
  if (Status s = apps::choose_device(kProgram, job.device, where); !s.ok()) return apps::fail(kProgram, s.message());

  GwnModel model;
  apps::ModelLoad loaded;
  // Recentred when far off: the camera frames the model's box, and the image holds no positions,
  // so a georeferenced scan renders as it would at the origin.
  if (Status s = apps::load_model(job.mesh, model, loaded, {}, MeshLoadOptions{.recentre = true}); !s.ok())
    return apps::fail(kProgram, s.message());
  apps::print_load_warnings(kProgram, job.mesh, loaded.report, false);
  // The tracer's level-free cells are made for the level the model's sheets are classified at.
  if (!(model.requested_sheet_level() == trace.level))
    if (Status s = model.set_sheet_level(trace.level); !s.ok()) return apps::fail(kProgram, s.message());
  if (Status s = model.prepare(kPartLevelFreeCells); !s.ok()) return apps::fail(kProgram, s.message());
  apps::warn_if_level_out_of_reach(kProgram, model.view(), trace);
  const size_t boundary_segments = model.boundary().segment_count();
  std::printf("%s: %s: %zu triangles, %zu boundary segments%s; loaded in %.3f s, built in %.3f s\n", kProgram,
              job.mesh.c_str(), loaded.report.triangle_count, boundary_segments, boundary_segments ? "" : " (closed)",
              loaded.load_seconds, loaded.build_seconds);
  std::fflush(stdout);
  if (solid_angle && boundary_segments == 0) {
    // Off a closed mesh Ω is a whole multiple of 4π: there is no level set to see.
    warn("the mesh is closed: in solid-angle mode there is nothing to render");
  }

  const render::PinholeCamera camera =
      render::frame_box(model.bounds(), job.width, job.height, job.azimuth, job.elevation, job.fov_degrees);
  // The framing is in float: a mesh too large for it (its box's squared diagonal overflows)
  // would give every ray a non-finite origin.
  const auto finite = [](const vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); };
  if (!finite(camera.eye) || !finite(camera.forward) || !finite(camera.right) || !finite(camera.up))
    return apps::fail(kProgram, job.mesh + ": the mesh is too large to frame with a camera in float");
  FirstHitRender render;
  std::string where_text = count_of(thread_limit.workers(), "thread");
  if (where == Device::kCuda) {
    const Engine engine(std::move(model));
    const cuda::DeviceModel* device_model = nullptr;
    if (Status s = engine.device_model(device_model); !s.ok())
      return apps::fail(kProgram, job.mesh + ": " + s.message());
    std::vector<FirstHitSample> pixels;
    if (Status s = render_first_hit_cuda(*device_model, camera, job.settings, job.frames, pixels, render.seconds);
        !s.ok())
      return apps::fail(kProgram, job.mesh + ": " + s.message());
    render = first_hit_image(pixels, camera, job.settings, render.seconds);
    where_text = "the GPU";
  } else {
    std::atomic<size_t> progress{0};
    apps::ProgressBar bar(progress, size_t(job.width) * size_t(job.height) * size_t(job.frames), "px");
    double seconds = 0;
    for (int f = 0; f < job.frames; ++f) {
      render = render_first_hit(model.view(), camera, job.settings, &progress);
      seconds += render.seconds;
    }
    render.seconds = seconds / job.frames;
  }

  const FirstHitStats& stats = render.stats;
  const double rays_per_second = render.seconds > 0 ? double(stats.rays) / render.seconds : 0.0;
  if (job.frames > 1)
    std::printf("%s: %d frames, %.4g frames/s (%.3f ms a frame%s)\n", kProgram, job.frames,
                render.seconds > 0 ? 1.0 / render.seconds : 0.0, 1e3 * render.seconds,
                where == Device::kCuda ? ", its pixels copied to the host; the upload not counted" : "");
  std::printf(
      "%s: %dx%d in %.3f s on %s: %s rays/s, %.2f steps/ray (max %u), %.2f crossings/ray; "
      "hits: %llu sheet, %llu smooth, %llu missed; %llu capped\n",
      kProgram, job.width, job.height, render.seconds, where_text.c_str(), apps::human_count(rays_per_second).c_str(),
      stats.mean_steps(), stats.max_steps, stats.mean_crossings(), (unsigned long long)stats.sheet_hits,
      (unsigned long long)stats.smooth_hits, (unsigned long long)(stats.rays - stats.sheet_hits - stats.smooth_hits),
      (unsigned long long)(stats.step_capped + stats.crossing_capped));
  std::fflush(stdout);
  if (stats.step_capped) {
    warn(count_of(stats.step_capped, "ray") + " hit the step cap (--max-steps " + std::to_string(trace.max_steps) +
         "), shown as background");
  }
  if (stats.crossing_capped) {
    warn(count_of(stats.crossing_capped, "ray") + " hit the crossing cap (" + std::to_string(trace.max_crossings) +
         " crossings), shown as background");
  }
  if (stats.invalid) warn(count_of(stats.invalid, "ray") + " rejected by the tracer as invalid");
  // With the eye outside {w > level} (far from the mesh w is near 0), every first hit enters the
  // region, so its outward normal faces the eye. Solid-angle levels are crossed both ways.
  if (!solid_angle && trace.level > 0.0f && stats.facing_away) {
    warn(count_of(stats.facing_away, "hit") + " with an outward normal facing away from the camera");
  }

  if (Status s = write_image(job.output, render.colour, description); !s.ok()) return apps::fail(kProgram, s.message());
  std::printf("%s: wrote %s\n", kProgram, job.output.c_str());
  if (!job.stats_image.empty()) {
    const Image steps = steps_image(render);
    if (Status s = write_image(job.stats_image, steps, description); !s.ok()) return apps::fail(kProgram, s.message());
    if (stats.max_steps == 0) {
      std::printf("%s: wrote %s (no ray took a Harnack step: grey is a hit, black a miss)\n", kProgram,
                  job.stats_image.c_str());
    } else {
      std::printf(
          "%s: wrote %s (Harnack steps per pixel, log scale from dark blue = 1 to red = %u; grey: a hit "
          "without steps; black: a miss without steps; magenta: capped)\n",
          kProgram, job.stats_image.c_str(), std::max(stats.max_steps, 2u));
    }
  }
  return 0;
}

}  // namespace gwnrt::render
