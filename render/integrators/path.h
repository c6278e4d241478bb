// The path tracer: unidirectional, with next-event estimation toward the environment, the sun
// and emissive triangle meshes, combined with BSDF sampling by multiple importance sampling
// (power heuristic), and Russian roulette. Each pixel's random numbers come from a stream seeded
// by (seed, pixel, sample) alone, so an image depends on the seed, not on the thread count or
// the order in which tiles are rendered.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <string>

#include "render/image.h"
#include "render/render_scene.h"

namespace gwnrt::render {

// A small counter-based generator (PCG32) for one pixel sample's stream.
class Sampler {
 public:
  Sampler(uint64_t seed, uint64_t pixel, uint64_t sample);
  float next();  // uniform in [0, 1)

 private:
  uint64_t state_ = 0, increment_ = 1;
};

// What one camera sample found at its first hit (AOVs).
struct SampleAovs {
  Spectrum albedo{0.0f};
  vec3 normal{0.0f};
  float depth = 0.0f;  // 0 for a miss
};

// Radiance along one camera ray.
Spectrum trace_path(const RenderScene& scene, const vec3& origin, const vec3& direction, int max_depth,
                    Sampler& sampler, SampleAovs* first = nullptr);

struct PathRender {
  Image image;  // R, G, B (linear); with AOVs also albedo.R/G/B, N.X/Y/Z, Z
  double seconds = 0;
  uint64_t samples = 0;
};

// Renders the scene's camera (its pixels; samples, depth and seed from `settings`, not from the
// scene). `progress`, when given, counts finished pixels.
PathRender render_paths(const RenderScene& scene, const RenderSettings& settings,
                        std::atomic<std::size_t>* progress = nullptr);

// What `gwnrt-render` (the path integrator) was asked for, every option already checked: a scene
// file or a mesh (rendered in its default scene), and what overrides the scene's own settings.
struct PathJob {
  std::string input;              // .json: a scene file; else a mesh
  std::string output;             // the image (.png: tone-mapped; .exr: linear)
  int width = 800, height = 600;  // a mesh's image size; a scene's when set_*
  bool set_width = false, set_height = false;
  int spp = 0, max_depth = 0;  // 0: the scene's
  int64_t seed = -1;           // negative: the scene's
  bool aovs = false;           // EXR only
  int threads = 0;             // 0: all cores
};

// Loads (or makes) the scene, builds it in Embree, renders it with a progress bar, prints the time
// per sample per pixel and writes the image. Returns the exit status.
int run_path_job(const PathJob& job, const std::string& description);

}  // namespace gwnrt::render
