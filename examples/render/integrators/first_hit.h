// The first-hit renderer: one ray per pixel through the shared pinhole camera, traced on S by
// trace_surface and shaded directly (shading.h). It also keeps what each ray cost, for the
// summary line and the statistics image. The path tracer of a later issue shades differently
// but reuses the tiles, the statistics and the image writer.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "camera.h"
#include "gwnrt/geometry/model_view.h"
#include "gwnrt/trace/surface_trace.h"
#include "image.h"
#include "shading.h"

namespace gwnrt::render {

// What one primary ray cost and found.
struct PixelTrace {
  uint32_t steps = 0;      // Harnack evaluations
  uint32_t crossings = 0;  // triangle crossings walked
  HitKind kind = HitKind::kNone;
  bool capped = false;
};

struct RenderStats {
  uint64_t rays = 0;
  uint64_t steps = 0;
  uint64_t crossings = 0;
  uint64_t sheet_hits = 0;
  uint64_t smooth_hits = 0;
  uint64_t step_capped = 0;      // ended by TraceOptions::max_steps
  uint64_t crossing_capped = 0;  // ended by TraceOptions::max_crossings
  uint64_t invalid = 0;          // rejected by the tracer (a camera bug if ever nonzero)
  uint64_t facing_away = 0;      // hits whose outward normal points away from the eye
  uint32_t max_steps = 0;        // the most Harnack steps any one ray took

  void add(const RayHit& hit, const vec3& dir, const TraceOptions& options);
  RenderStats& operator+=(const RenderStats& other);
  double mean_steps() const { return rays ? double(steps) / double(rays) : 0.0; }
  double mean_crossings() const { return rays ? double(crossings) / double(rays) : 0.0; }
};

struct PrimaryRenderSettings {
  ShadingMode shading = ShadingMode::kHeadlight;
  TraceOptions trace;
};

struct PrimaryRender {
  Image colour;                     // linear RGB
  std::vector<PixelTrace> traces;   // row-major, one per pixel
  RenderStats stats;
  double seconds = 0;               // wall-clock time of the parallel tracing alone
};

// Renders camera.width × camera.height pixels. `progress`, when given, counts finished pixels.
// The trace options must have passed validate_trace_options.
PrimaryRender render_primary(const ModelView& model, const examples::PinholeCamera& camera,
                             const PrimaryRenderSettings& settings, std::atomic<std::size_t>* progress = nullptr);

// The steps-per-pixel image: log-scaled false colour from 1 step to `scale_max` steps (0: the
// largest count in the image), dark grey for hits that took no step, black for misses without
// steps, magenta for capped rays. Channels R, G, B, then the raw per-pixel counts "steps",
// "crossings", "kind" (0 miss, 1 sheet, 2 smooth) and "capped" (0/1), which only EXR keeps.
Image steps_image(const PrimaryRender& render, uint32_t scale_max = 0);

}  // namespace gwnrt::render
