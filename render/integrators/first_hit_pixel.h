// One pixel of the first-hit renderer, host and device: its camera ray traced onto S and shaded,
// and what the trace cost. The CPU's tiles (first_hit.cpp) and the GPU's kernel
// (first_hit_cuda.cu) both call first_hit_pixel, so the two images differ only by rounding. No
// OpenImageIO here: nvcc compiles it.
#pragma once

#include <cstdint>

#include "gwnrt/base/hd.h"
#include "gwnrt/geometry/model_view.h"
#include "gwnrt/trace/surface_trace.h"
#include "render/camera.h"
#include "render/shading.h"

namespace gwnrt::render {

// What one primary ray cost and found.
struct PixelTrace {
  uint32_t steps = 0;      // Harnack evaluations
  uint32_t crossings = 0;  // triangle crossings walked
  HitKind kind = HitKind::kNone;
  bool capped = false;
};

struct FirstHitSettings {
  ShadingMode shading = ShadingMode::kHeadlight;
  TraceOptions trace;
};

// A pixel: its linear colour, its trace, and what the statistics need beyond it.
struct FirstHitSample {
  vec3 colour{0.0f};
  PixelTrace trace;
  bool invalid = false;      // the tracer rejected the ray
  bool facing_away = false;  // a hit whose outward normal points away from the eye
};

GWNRT_HD inline FirstHitSample first_hit_pixel(const ModelView& model, const render::PinholeCamera& camera,
                                               const FirstHitSettings& settings, int x, int y) {
  const Ray ray = camera.ray(x, y);
  const RayHit hit = trace_surface(model, ray, settings.trace);
  FirstHitSample s;
  s.colour = shade_primary(hit, ray.direction, (float(y) + 0.5f) / float(camera.height), settings.shading);
  s.trace.steps = hit.steps;
  s.trace.crossings = hit.crossings;
  s.trace.kind = hit.hit ? hit.kind : HitKind::kNone;
  s.trace.capped = hit.capped;
  s.invalid = hit.invalid;
  s.facing_away = hit.hit && glm::dot(hit.normal, ray.direction) > 0.0f;
  return s;
}

}  // namespace gwnrt::render
