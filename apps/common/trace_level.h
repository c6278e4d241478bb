// How the command-line programs name a traced surface: --mode gwn|solid-angle and --level, where
// the level is a value of w in gwn mode and an angle in radians in solid-angle mode.
#pragma once

#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>

#include "gwnrt/model/model.h"
#include "gwnrt/trace/surface_trace.h"

namespace gwnrt::apps {

// Sets options.mode and options.level. The tracer works in units of w in both modes: an angle Ω*
// is the level Ω*/(4π); the defaults (w = 1/2, Ω = 2π) are the same level.
inline void set_trace_surface(const std::string& mode, std::optional<double> level, TraceOptions& options) {
  const bool solid_angle = mode == "solid-angle";
  options.mode = solid_angle ? TraceMode::kSolidAngle : TraceMode::kWindingNumber;
  options.level = solid_angle ? float(level.value_or(2.0 * kPi) / (4.0 * kPi)) : float(level.value_or(0.5));
}

// A level w never reaches has no surface, and every ray then misses (model_view.h,
// level_within_reach): why, for a mesh of `triangle_count` triangles, or nothing when the level
// is within reach (or the mode is solid-angle, whose levels are angles).
inline std::optional<std::string> level_out_of_reach(uint32_t triangle_count, const TraceOptions& options) {
  if (options.mode != TraceMode::kWindingNumber || level_within_reach(triangle_count, options.level))
    return std::nullopt;
  return level_out_of_reach_message(triangle_count, options.level);
}

// Printed by the programs that trace, for the model they trace.
inline void warn_if_level_out_of_reach(const char* program, const ModelView& view, const TraceOptions& options) {
  if (const auto why = level_out_of_reach(view.triangles.triangle_count, options))
    std::fprintf(stderr, "%s: warning: %s\n", program, why->c_str());
}

}  // namespace gwnrt::apps
