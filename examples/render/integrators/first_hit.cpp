#include "integrators/first_hit.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "tiles.h"

namespace gwnrt::render {

void RenderStats::add(const RayHit& hit, const vec3& dir, const TraceOptions& options) {
  ++rays;
  steps += hit.steps;
  crossings += hit.crossings;
  max_steps = std::max(max_steps, hit.steps);
  if (hit.invalid) ++invalid;
  if (hit.capped) {
    // RayHit says only that a cap ended the trace; which one is told by the count that reached it.
    if (hit.steps >= options.max_steps) ++step_capped;
    else ++crossing_capped;
  }
  if (!hit.hit) return;
  if (hit.kind == HitKind::kSmooth) ++smooth_hits;
  else ++sheet_hits;
  if (glm::dot(hit.normal, dir) > 0.0f) ++facing_away;
}

RenderStats& RenderStats::operator+=(const RenderStats& o) {
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

PrimaryRender render_primary(const ModelView& model, const examples::PinholeCamera& camera,
                             const PrimaryRenderSettings& settings, std::atomic<std::size_t>* progress) {
  const int width = camera.width, height = camera.height;
  PrimaryRender out;
  out.colour = Image(width, height, {"R", "G", "B"});
  out.traces.resize(std::size_t(width) * std::size_t(height));

  const TileGrid grid(width, height);
  // One slot per tile, summed in tile order afterwards: the totals come out the same on every
  // run whatever the thread count, and no two tasks ever write the same counter.
  std::vector<RenderStats> tile_stats(std::size_t(grid.count()));

  const auto start = std::chrono::steady_clock::now();
  parallel_for_tiles(grid, [&](const Tile& tile) {
    RenderStats& stats = tile_stats[std::size_t(tile.index)];
    for (int y = tile.y0; y < tile.y1; ++y) {
      const float v = (float(y) + 0.5f) / float(height);
      for (int x = tile.x0; x < tile.x1; ++x) {
        const Ray ray = camera.ray(x, y);
        const RayHit hit = trace_surface(model, ray, settings.trace);
        out.colour.set_rgb(x, y, shade_primary(hit, ray.direction, v, settings.shading));
        PixelTrace& trace = out.traces[std::size_t(y) * std::size_t(width) + std::size_t(x)];
        trace.steps = hit.steps;
        trace.crossings = hit.crossings;
        trace.kind = hit.hit ? hit.kind : HitKind::kNone;
        trace.capped = hit.capped;
        stats.add(hit, ray.direction, settings.trace);
      }
    }
    if (progress) progress->fetch_add(std::size_t(tile.pixel_count()), std::memory_order_relaxed);
  });
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  for (const RenderStats& s : tile_stats) out.stats += s;
  return out;
}

Image steps_image(const PrimaryRender& render, uint32_t scale_max) {
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
      if (t.capped) colour = vec3(kStatsCapped[0], kStatsCapped[1], kStatsCapped[2]);
      else if (t.steps == 0) colour = vec3(t.kind == HitKind::kNone ? kStatsMissGrey : kStatsNoStepGrey);
      else colour = false_colour(std::log2(float(t.steps)) / log_max);
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

}  // namespace gwnrt::render
