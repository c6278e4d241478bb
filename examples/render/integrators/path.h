// The path tracer: unidirectional, with next-event estimation toward the environment, the sun
// and emissive triangle meshes, combined with BSDF sampling by multiple importance sampling
// (power heuristic), and Russian roulette. Each pixel's random numbers come from a stream seeded
// by (seed, pixel, sample) alone, so an image depends on the seed, not on the thread count or
// the order in which tiles are rendered.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>

#include "image.h"
#include "render_scene.h"

namespace gwnrt::render {

// A small counter-based generator (PCG32) for one pixel sample's stream.
class Sampler {
 public:
  Sampler(uint64_t seed, uint64_t pixel, uint64_t sample);
  float next();  // uniform in [0, 1)

 private:
  uint64_t state_ = 0, increment_ = 1;
};

struct PathSettings {
  int spp = 16;
  int max_depth = 8;
  uint64_t seed = 1;
  bool aovs = false;  // also albedo, normal and depth of the first hit
};

// What one camera sample found at its first hit (AOVs).
struct FirstHit {
  Spectrum albedo{0.0f};
  vec3 normal{0.0f};
  float depth = 0.0f;  // 0 for a miss
};

// Radiance along one camera ray.
Spectrum trace_path(const RenderScene& scene, const vec3& origin, const vec3& direction, int max_depth,
                    Sampler& sampler, FirstHit* first = nullptr);

struct PathRender {
  Image image;  // R, G, B (linear); with AOVs also albedo.R/G/B, N.X/Y/Z, Z
  double seconds = 0;
  uint64_t samples = 0;
};

// Renders the scene's camera. `progress`, when given, counts finished pixels.
PathRender render_paths(const RenderScene& scene, const PathSettings& settings,
                        std::atomic<std::size_t>* progress = nullptr);

}  // namespace gwnrt::render
