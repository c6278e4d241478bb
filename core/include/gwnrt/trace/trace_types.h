// What a ray trace is asked (TraceOptions) and what it answers (RayHit): the public types shared
// by the tracer, the batch driver, the CUDA backend and the Embree plugin.
#pragma once

#include <cmath>
#include <cstdint>

#include "gwnrt/base/hd.h"
#include "gwnrt/base/option_limits.h"
#include "gwnrt/geometry/bvh.h"
#include "gwnrt/geometry/ray.h"

namespace gwnrt {

enum class TraceMode : uint32_t {
  kWindingNumber = 0,  // S = ∂{w > level}: sheets and smooth pieces
  kSolidAngle = 1,     // {Ω ≡ 4π·level mod 4π}: smooth pieces only (the paper's nonplanar polygons)
};

struct TraceOptions {
  TraceMode mode = TraceMode::kWindingNumber;
  float level = 0.5f;         // w*; in solid-angle mode Ω*/(4π) (2π ↔ 0.5)
  float epsilon = 1e-5f;      // stopping distance, relative to the box diagonal of M
  uint32_t max_steps = 4096;  // Harnack evaluations per ray
  uint32_t max_crossings = 1u << 16;
  float beta = 2.0f;  // accuracy of the multipole evaluation of φ on the cone
  bool overstep = true;
  bool exact = false;  // φ by the double brute-force sum over the cone (reference, slow)
};

// The values validate_trace_options (query/validation.h) accepts, option by option: it checks with these,
// and a program checks its flags with them, so that a bad value is refused by the flag's name
// before anything is loaded (the library's own message cannot name a flag).
inline bool trace_level_valid(float level) { return std::isfinite(level); }
inline bool trace_epsilon_valid(float epsilon) { return epsilon > 0.0f && epsilon < 1.0f; }  // box diagonals
inline bool trace_beta_valid(float beta) { return beta_valid(beta); }
inline bool trace_cap_valid(uint32_t cap) { return cap >= 1; }  // max_steps, max_crossings

enum class HitKind : uint32_t { kNone = 0, kSheet = 1, kSmooth = 2 };

// The shortest ray direction traced: the smallest normal float (shorter ones, zero included,
// cannot be normalised and are refused).
inline constexpr float kMinDirectionLength = 1.17549435e-38f;

GWNRT_HD inline bool finite3(const vec3& v) { return is_finite(v.x) && is_finite(v.y) && is_finite(v.z); }

// Why the tracer cannot trace a ray (SurfaceTracer: its hit says invalid), or nullptr. A direction
// whose length in float is below the smallest normal float cannot be normalised (1e-44 gave
// t = inf for a hit): refused like a zero direction; |d| is taken in double, as |d|² under- and
// overflows float for finite d.
GWNRT_HD inline const char* untraceable_ray(const Ray& r) {
  if (!finite3(r.origin)) return "origin has a non-finite coordinate";
  if (!finite3(r.direction)) return "direction has a non-finite coordinate";
  const float length = float(glm::length(dvec3(r.direction)));
  if (!(length >= kMinDirectionLength)) return "direction is zero (or shorter than the smallest normal float)";
  if (!is_finite(length)) return "direction is longer than float's range";
  if (is_nan(r.tnear)) return "tnear is not a finite number";
  if (is_nan(r.tfar)) return "tfar is NaN";
  return nullptr;
}

// Why a ray is refused by a caller that refuses rather than flags (Python's trace, which says it
// with the ray's index), or nullptr: untraceable_ray's, and tnear infinite or above tfar, as the
// programs' ray files refuse them.
inline const char* ray_refusal(const Ray& r) {
  if (const char* why = untraceable_ray(r)) return why;
  if (!is_finite(r.tnear)) return "tnear is not a finite number";
  if (r.tnear > r.tfar) return "tnear exceeds tfar";
  return nullptr;
}

// A ray whose origin lies more than this many box diagonals before the box's centre is traced
// from its line's point across from the centre (SurfaceTracer): t steps there by 1.2e-7 of the
// distance, 8e-6 of the diagonal at this threshold.
inline constexpr double kFarRayDiagonals = 64.0;

struct RayHit {
  bool hit = false;
  bool capped = false;   // a step or crossing cap ended the trace (reported as a miss)
  bool invalid = false;  // rejected input: non-finite numbers, or a direction shorter than kMinDirectionLength
  HitKind kind = HitKind::kNone;
  float t = kInfinity;  // in units of the ray's own direction
  vec3 position{0.0f};
  vec3 normal{0.0f};               // unit, outward: from {w > w*} toward {w < w*}
  uint32_t triangle = kEmptyLane;  // input index, sheet hits
  uint32_t steps = 0;              // Harnack evaluations of φ
  uint32_t crossings = 0;          // triangle crossings walked
};

}  // namespace gwnrt
