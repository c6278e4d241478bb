// Where S can be: the padded box of M that holds every crossing (and so every sheet), the boxes
// around the boundary loops that hold every smooth piece for a level, and their union, which
// the Embree bounds callback reports. Used by the tracer, the signed distance and the plugin.
#pragma once

#include <cfloat>

#include "gwnrt/base/hd.h"
#include "gwnrt/geometry/model_view.h"
#include "gwnrt/trace/trace_types.h"

namespace gwnrt {

// Below this distance between 0 and the nearest level (w* near a whole number) the smooth
// regions' bound is useless and the march covers M's box grown by ModelView::surface_margin.
inline constexpr float kMinLevelDistance = 1e-3f;

// Padding of M's box for the crossing walk, relative to its diagonal (plus an absolute floor for
// flat meshes): far above float round-off of the crossing and clip computations.
inline constexpr float kBoxPad = 1e-4f;

// How far past a level round-off may carry a safe step, in φ: far above float ulps of φ, far
// below the change of φ over the stopping distance.
inline constexpr float kPhaseRoundOff = 1e-5f;
inline constexpr float kBoxPadAbsolute = 1e-30f;

// δ: the distance from 0 to the nearest level w* + k (the levels repeat with period 1 in w).
GWNRT_HD inline float level_distance(float level) {
  const float phase = level - floorf(level);
  return min_of(phase, 1.0f - phase);
}

// Crossings live in M's box; it is padded because the crossing of a triangle lying in a face of
// the box is rounded differently from the box clip and may fall just outside it.
// The pad is also at least 4 float steps of the box's coordinates: far from the origin 1e-4 of
// the diagonal can be below one step, and the mesher's grid, centred on an unpadded box, would
// put its corners exactly on M's faces (zero-area triangles at every resolution).
GWNRT_HD inline Aabb crossing_box(const ModelView& m) {
  Aabb padded = m.bounds;
  const vec3 largest = glm::max(glm::abs(m.bounds.lo), glm::abs(m.bounds.hi));
  const float steps = 4.0f * FLT_EPSILON * max_of(largest.x, max_of(largest.y, largest.z));
  const vec3 pad(max_of(kBoxPad * glm::length(m.bounds.hi - m.bounds.lo) + kBoxPadAbsolute, steps));
  padded.lo -= pad;
  padded.hi += pad;
  return padded;
}

// Where the march may be needed for level w*: the smooth regions grown for δ = the distance from
// 0 to the nearest level (SmoothRegion), or, for levels at whole numbers, where that bound is
// useless, M's box grown by surface_margin. No smooth piece of S lies outside these boxes.
GWNRT_HD inline uint32_t march_box_count(const ModelView& m, float level) {
  if (m.cone.triangle_count == 0) return 0;
  if (!(level_distance(level) > kMinLevelDistance)) return 1u;
  return m.smooth_region_count < kMaxSmoothRegions ? m.smooth_region_count : kMaxSmoothRegions;
}

GWNRT_HD inline Aabb march_box(const ModelView& m, float level, uint32_t r) {
  const float delta = level_distance(level);
  Aabb box;
  float grow;
  if (delta > kMinLevelDistance) {
    box = m.smooth_regions[r].box;
    grow = sqrtf(m.smooth_regions[r].spread / (4.0f * float(kPi) * delta));
  } else {  // levels at whole numbers: only |w| <= A/(4π d²) of the whole mesh bounds them
    box = m.bounds;
    grow = m.surface_margin;
  }
  box.lo -= vec3(grow);
  box.hi += vec3(grow);
  return box;
}

// The union of the march boxes for level w*: every smooth piece of S. Empty (not valid()) when
// there are none (a closed mesh).
GWNRT_HD inline Aabb march_region(const ModelView& m, float level) {
  Aabb box;
  for (uint32_t r = 0; r < march_box_count(m, level); ++r) box.extend(march_box(m, level, r));
  return box;
}

// A box holding all of S for these options (what an Embree bounds callback reports): M's box for
// the sheets, the march boxes for the smooth pieces. Empty (not valid()) when S is.
GWNRT_HD inline Aabb surface_bounds(const ModelView& m, const TraceOptions& options) {
  Aabb box = march_region(m, options.level);
  if (options.mode == TraceMode::kWindingNumber) box.extend(crossing_box(m));
  return box;
}

}  // namespace gwnrt
