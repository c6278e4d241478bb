// How a primary hit (or miss) becomes a colour, and the false-colour ramp of the statistics
// image. Colours are linear light; the image writer encodes them for PNG. Everything here is
// GWNRT_HD and free of TBB and OpenImageIO, so a CUDA render path can shade the same way.
#pragma once

#include <cmath>

#include "gwnrt/base/hd.h"
#include "gwnrt/trace/surface_trace.h"

namespace gwnrt::render {

enum class ShadingMode {
  kNormal,     // the outward normal as a colour: 0.5·(n + 1)
  kHeadlight,  // diffuse from a light at the eye, sheet and smooth pieces tinted apart
};

// The inverse of the sRGB transfer curve. Colours that are specified as they should look on
// screen (normal colours, the false-colour ramp) go through it into the linear image, so that
// the PNG shows exactly the specified values and the EXR, viewed, looks the same as the PNG.
GWNRT_HD inline float srgb_decode(float encoded) {
  const float c = fminf(fmaxf(encoded, 0.0f), 1.0f);
  return c <= 0.04045f ? c / 12.92f : powf((c + 0.055f) / 1.055f, 2.4f);
}
GWNRT_HD inline vec3 srgb_decode(const vec3& c) { return vec3(srgb_decode(c.x), srgb_decode(c.y), srgb_decode(c.z)); }

// Sheet pieces (on the mesh) light grey; smooth pieces (caps over holes, the repaired surface of
// a soup) bluish, so that what the tracer filled in stands out from what the mesh already had.
inline constexpr float kSheetAlbedo[3] = {0.72f, 0.72f, 0.70f};
inline constexpr float kSmoothAlbedo[3] = {0.38f, 0.55f, 0.85f};
// Light that reaches surfaces seen edge-on, so silhouettes do not sink into the background.
inline constexpr float kAmbient = 0.12f;

// `v` runs from 0 at the top row to 1 at the bottom: a dark neutral grey, lighter at the top,
// darker than any lit surface.
GWNRT_HD inline vec3 background(float v) {
  const float top = 0.10f, bottom = 0.025f;
  return vec3(top + (bottom - top) * fminf(fmaxf(v, 0.0f), 1.0f));
}

// The colour of a hit seen along the unit direction `dir`.
GWNRT_HD inline vec3 shade_hit(const RayHit& hit, const vec3& dir, ShadingMode mode) {
  if (mode == ShadingMode::kNormal) return srgb_decode(0.5f * (hit.normal + vec3(1.0f)));
  const bool smooth = hit.kind == HitKind::kSmooth;
  const vec3 albedo = smooth ? vec3(kSmoothAlbedo[0], kSmoothAlbedo[1], kSmoothAlbedo[2])
                             : vec3(kSheetAlbedo[0], kSheetAlbedo[1], kSheetAlbedo[2]);
  // |n·(-d)|: the light sits at the eye, and a surface seen from its inner side (a camera inside
  // {w > level}, or solid-angle mode, where levels are crossed in both directions) is lit too.
  const float diffuse = fabsf(glm::dot(hit.normal, dir));
  return albedo * (kAmbient + (1.0f - kAmbient) * diffuse);
}

// The colour of a primary ray: its hit shaded, or the background.
GWNRT_HD inline vec3 shade_primary(const RayHit& hit, const vec3& dir, float v, ShadingMode mode) {
  return hit.hit ? shade_hit(hit, dir, mode) : background(v);
}

// A ramp for counts (s in [0, 1]): dark blue, blue, cyan, green, yellow, red. Linear colour.
GWNRT_HD inline vec3 false_colour(float s) {
  constexpr int kStops = 6;
  const float stops[kStops][3] = {{0.05f, 0.05f, 0.35f}, {0.10f, 0.30f, 0.95f}, {0.05f, 0.85f, 0.90f},
                                  {0.20f, 0.85f, 0.20f}, {0.98f, 0.90f, 0.15f}, {0.90f, 0.10f, 0.08f}};
  const float x = fminf(fmaxf(s, 0.0f), 1.0f) * float(kStops - 1);
  const int i = int(fminf(x, float(kStops - 2)));
  const float f = x - float(i);
  const vec3 a(stops[i][0], stops[i][1], stops[i][2]), b(stops[i + 1][0], stops[i + 1][1], stops[i + 1][2]);
  return srgb_decode(a + f * (b - a));
}

// Statistics-image colours for pixels without Harnack steps, and for capped rays.
inline constexpr float kStatsMissGrey = 0.0f;     // no steps, no hit
inline constexpr float kStatsNoStepGrey = 0.18f;  // a hit found by crossings alone (a sheet)
inline constexpr float kStatsCapped[3] = {1.0f, 0.0f, 1.0f};

}  // namespace gwnrt::render
