// The first-hit integrator: one ray per pixel through the shared pinhole camera, traced on S by
// trace_surface and shaded directly (shading.h), without Embree. It also keeps what each ray
// cost, for the summary line and the statistics image. `gwnrt-render --integrator first-hit`
// runs it on a mesh (run_first_hit_job).
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "gwnrt/geometry/model_view.h"
#include "gwnrt/trace/surface_trace.h"
#include "render/camera.h"
#include "render/image.h"
#include "render/integrators/first_hit_pixel.h"

namespace gwnrt::render {

struct FirstHitStats {
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

  void add(const FirstHitSample& pixel, const TraceOptions& options);
  FirstHitStats& operator+=(const FirstHitStats& other);
  double mean_steps() const { return rays ? double(steps) / double(rays) : 0.0; }
  double mean_crossings() const { return rays ? double(crossings) / double(rays) : 0.0; }
};

struct FirstHitRender {
  Image colour;                    // linear RGB
  std::vector<PixelTrace> traces;  // row-major, one per pixel
  FirstHitStats stats;
  double seconds = 0;  // wall-clock time of the parallel tracing alone
};

// Renders camera.width × camera.height pixels. `progress`, when given, counts finished pixels.
// The trace options must have passed validate_trace_options.
FirstHitRender render_first_hit(const ModelView& model, const render::PinholeCamera& camera,
                                const FirstHitSettings& settings, std::atomic<std::size_t>* progress = nullptr);

// The image, traces and statistics of pixels rendered elsewhere (the GPU), row-major.
FirstHitRender first_hit_image(const std::vector<FirstHitSample>& pixels, const render::PinholeCamera& camera,
                               const FirstHitSettings& settings, double seconds);

// The steps-per-pixel image: log-scaled false colour from 1 step to `scale_max` steps (0: the
// largest count in the image), dark grey for hits that took no step, black for misses without
// steps, magenta for capped rays. Channels R, G, B, then the raw per-pixel counts "steps",
// "crossings", "kind" (0 miss, 1 sheet, 2 smooth) and "capped" (0/1), which only EXR keeps.
Image steps_image(const FirstHitRender& render, uint32_t scale_max = 0);

// What `gwnrt-render --integrator first-hit` was asked for, every option already checked.
struct FirstHitJob {
  std::string mesh;         // the mesh file
  std::string output;       // the image (.png or .exr)
  std::string stats_image;  // empty: none
  int width = 800, height = 600;
  float azimuth = 30.0f, elevation = 20.0f, fov_degrees = 40.0f;  // frame_box's camera
  FirstHitSettings settings;                                      // trace options that passed validate_trace_options
  int threads = 0;                                                // 0: all cores
  std::string device = "cpu";                                     // cpu, cuda or auto (device_choice.h)
  int frames = 1;  // renders of the same image, for frames per second (the last is written)
};

// Loads and builds the mesh, renders it, prints the summary (rays/s, steps, hits, caps) and
// warnings, and writes the image and the statistics image. Returns the exit status.
int run_first_hit_job(const FirstHitJob& job, const std::string& description);

}  // namespace gwnrt::render
