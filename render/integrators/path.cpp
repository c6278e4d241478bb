#include "render/integrators/path.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>

#include "apps/common/load_model.h"
#include "apps/common/program.h"
#include "apps/common/progress_bar.h"
#include "gwnrt/base/memory.h"
#include "render/image_output.h"
#include "render/render_program.h"
#include "render/tiles.h"

namespace gwnrt::render {
namespace {

uint64_t mix64(uint64_t x) {  // splitmix64's finaliser: decorrelates nearby seeds
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

float max_component(const Spectrum& s) { return std::max(s.x, std::max(s.y, s.z)); }
bool is_black(const Spectrum& s) { return !(s.x > 0.0f || s.y > 0.0f || s.z > 0.0f); }

float power_heuristic(float a, float b) {
  const float a2 = a * a, b2 = b * b;
  return a2 + b2 > 0.0f ? a2 / (a2 + b2) : 0.0f;
}

// Which lights next-event estimation picks from, each kind with equal probability.
struct LightChoice {
  bool environment = false, sun = false, area = false;
  int count() const { return int(environment) + int(sun) + int(area); }
  float probability() const { return count() > 0 ? 1.0f / float(count()) : 0.0f; }
};

LightChoice light_choice(const RenderScene& scene) {
  LightChoice c;
  c.environment = scene.environment_emits();
  c.sun = scene.sun().enabled();
  c.area = !scene.area_lights().empty();
  return c;
}

// Solid-angle density with which next-event estimation reaches point `x` (normal n) of an area
// light from `p`.
float area_light_pdf(const RenderScene& scene, const vec3& p, const vec3& x, const vec3& n) {
  const vec3 d = x - p;
  const float dist2 = glm::dot(d, d);
  const float cosine = std::abs(glm::dot(n, d)) / std::sqrt(dist2);
  if (!(cosine > 0.0f)) return 0.0f;
  return dist2 / (cosine * scene.area_lights().total_area);
}

struct LightSample {
  vec3 direction{0.0f};
  float distance = std::numeric_limits<float>::infinity();
  Spectrum radiance{0.0f};
  float pdf = 0.0f;  // solid angle, including the choice of the light
};

bool sample_light(const RenderScene& scene, const LightChoice& choice, const vec3& p, Sampler& sampler,
                  LightSample& out) {
  const int count = choice.count();
  if (count == 0) return false;
  int pick = std::min(int(sampler.next() * float(count)), count - 1);
  const float u0 = sampler.next(), u1 = sampler.next(), u2 = sampler.next();
  const float choose = choice.probability();
  // A distant light: a direction from its own sampler, the radiance it sends along it.
  auto distant = [&](const auto& light, auto radiance_toward) {
    float pdf;
    out.direction = light.sample(u0, u1, pdf);
    out.radiance = radiance_toward(out.direction);
    out.pdf = choose * pdf;
    return pdf > 0.0f;
  };
  if (choice.environment && pick-- == 0)
    return distant(scene.environment(), [&](const vec3& d) { return scene.environment().radiance(d); });
  if (choice.sun && pick-- == 0)
    return distant(scene.sun(), [&](const vec3& d) { return scene.sun().radiance_toward(d); });
  const AreaLights& lights = scene.area_lights();
  const size_t t = size_t(std::lower_bound(lights.cdf.begin(), lights.cdf.end(), u0) - lights.cdf.begin());
  const size_t tri = std::min(t, lights.emission.size() - 1);
  const vec3 a = lights.vertices[3 * tri], b = lights.vertices[3 * tri + 1], c = lights.vertices[3 * tri + 2];
  const float su = std::sqrt(u1);
  const vec3 x = (1.0f - su) * a + su * (1.0f - u2) * b + su * u2 * c;
  const vec3 n = glm::normalize(glm::cross(b - a, c - a));
  const vec3 d = x - p;
  out.distance = glm::length(d);
  if (!(out.distance > 0.0f)) return false;
  out.direction = d / out.distance;
  out.radiance = lights.emission[tri];
  out.pdf = choose * area_light_pdf(scene, p, x, n);
  return out.pdf > 0.0f;
}

}  // namespace

Sampler::Sampler(uint64_t seed, uint64_t pixel, uint64_t sample) {
  state_ = mix64(seed ^ mix64(pixel ^ mix64(sample)));
  increment_ = (mix64(pixel + 0x632BE59BD9B4E019ull) << 1u) | 1u;
}

float Sampler::next() {
  const uint64_t old = state_;
  state_ = old * 6364136223846793005ull + increment_;
  const uint32_t shifted = uint32_t(((old >> 18u) ^ old) >> 27u);
  const uint32_t rot = uint32_t(old >> 59u);
  const uint32_t r = (shifted >> rot) | (shifted << ((32u - rot) & 31u));
  return float(r >> 8) * (1.0f / 16777216.0f);  // 24 bits: exactly representable, < 1
}

Spectrum trace_path(const RenderScene& scene, const vec3& origin, const vec3& direction, int max_depth,
                    Sampler& sampler, SampleAovs* first) {
  const LightChoice choice = light_choice(scene);
  const float offset = 1e-4f * scene.scene_radius();
  Spectrum radiance(0.0f), throughput(1.0f);
  vec3 o = origin, d = direction;
  float bsdf_pdf_prev = 0.0f;
  bool specular = true;  // the camera ray, or one from a delta lobe: no light sampling competed
  vec3 p_prev = origin;
  for (int depth = 0; depth <= max_depth; ++depth) {
    SurfaceHit hit;
    if (!scene.intersect(o, d, offset * (depth == 0 ? 0.0f : 1.0f), std::numeric_limits<float>::infinity(), hit)) {
      // Escaped: the environment and the sun, weighted against next-event estimation.
      Spectrum l = scene.environment().radiance(d) *
                   (specular || !choice.environment
                        ? 1.0f
                        : power_heuristic(bsdf_pdf_prev, choice.probability() * scene.environment().pdf(d)));
      const Spectrum sun = scene.sun().radiance_toward(d);
      if (!is_black(sun))
        l += sun * (specular ? 1.0f : power_heuristic(bsdf_pdf_prev, choice.probability() * scene.sun().pdf(d)));
      radiance += throughput * l;
      break;
    }
    const Material& m = scene.materials()[size_t(hit.material)];
    if (first && depth == 0) {
      first->albedo = m.kind == MaterialKind::kEmissive ? m.emission : m.albedo;
      first->normal = hit.normal;
      first->depth = hit.t;
    }
    if (m.kind == MaterialKind::kEmissive) {
      float w = 1.0f;
      if (!specular && !hit.gwn && choice.area)
        w = power_heuristic(bsdf_pdf_prev,
                            choice.probability() * area_light_pdf(scene, p_prev, hit.position, hit.normal));
      radiance += throughput * m.emission * w;
      break;
    }
    // Shading frame: opaque surfaces are two-sided (the normal turned toward the viewer); a
    // dielectric keeps the outward normal, so that the side of the viewer says in or out.
    const vec3 wo_world = -d;
    vec3 n = hit.normal;
    if (m.kind != MaterialKind::kDielectric && glm::dot(n, wo_world) < 0.0f) n = -n;
    const Frame frame = Frame::from_normal(n);
    const vec3 wo = frame.to_local(wo_world);
    const vec3 above = hit.position + offset * (glm::dot(hit.normal, wo_world) >= 0.0f ? hit.normal : -hit.normal);

    if (!is_delta(m)) {
      LightSample ls;
      if (sample_light(scene, choice, hit.position, sampler, ls)) {
        const vec3 wi = frame.to_local(ls.direction);
        const Spectrum f = bsdf_eval(m, wo, wi);
        if (!is_black(f) && !is_black(ls.radiance)) {
          const float tmax =
              std::isinf(ls.distance) ? std::numeric_limits<float>::infinity() : ls.distance * (1.0f - 1e-4f);
          if (!scene.occluded(above, ls.direction, 0.0f, tmax)) {
            const float w = power_heuristic(ls.pdf, bsdf_pdf(m, wo, wi));
            radiance += throughput * f * std::abs(wi.z) * ls.radiance * (w / ls.pdf);
          }
        }
      }
    } else {
      sampler.next();  // keep the streams' layout independent of the material
      sampler.next();
      sampler.next();
      sampler.next();
    }

    BsdfSample bs;
    if (!bsdf_sample(m, wo, sampler.next(), sampler.next(), sampler.next(), bs)) break;
    throughput *= bs.weight;
    if (is_black(throughput) || !std::isfinite(throughput.x + throughput.y + throughput.z)) break;
    specular = bs.delta;
    bsdf_pdf_prev = bs.pdf;
    p_prev = hit.position;
    const vec3 wi_world = frame.to_world(bs.wi);
    // Leave on the side the new direction goes to (through for refraction).
    o = hit.position + offset * (glm::dot(hit.normal, wi_world) >= 0.0f ? hit.normal : -hit.normal);
    d = glm::normalize(wi_world);
    if (depth >= 3) {
      const float survive = std::min(0.95f, max_component(throughput));
      if (sampler.next() >= survive) break;
      throughput /= survive;
    }
  }
  return radiance;
}

PathRender render_paths(const RenderScene& scene, const RenderSettings& settings, std::atomic<std::size_t>* progress) {
  const render::PinholeCamera& cam = scene.desc().camera;
  std::vector<std::string> channels = {"R", "G", "B"};
  if (settings.aovs) channels.insert(channels.end(), {"albedo.R", "albedo.G", "albedo.B", "N.X", "N.Y", "N.Z", "Z"});
  PathRender out;
  out.image = Image(cam.width, cam.height, channels);
  const auto start = std::chrono::steady_clock::now();
  const TileGrid grid(cam.width, cam.height);
  parallel_for_tiles(grid, [&](const Tile& tile) {
    for (int y = tile.y0; y < tile.y1; ++y) {
      for (int x = tile.x0; x < tile.x1; ++x) {
        const uint64_t pixel = uint64_t(y) * uint64_t(cam.width) + uint64_t(x);
        Spectrum sum(0.0f);
        SampleAovs aov_sum;
        for (int s = 0; s < settings.spp; ++s) {
          Sampler sampler(settings.seed, pixel, uint64_t(s));
          const float u = sampler.next();  // in this order: x first, then y
          const float v = sampler.next();
          const Ray ray = cam.ray(x, y, u, v);
          SampleAovs first;
          const Spectrum l = trace_path(scene, ray.origin, ray.direction, settings.max_depth, sampler,
                                        settings.aovs ? &first : nullptr);
          if (std::isfinite(l.x + l.y + l.z)) sum += l;  // a NaN sample would poison the pixel: dropped
          aov_sum.albedo += first.albedo;
          aov_sum.normal += first.normal;
          aov_sum.depth += first.depth;
        }
        float* p = out.image.pixel(x, y);
        const float inv = 1.0f / float(settings.spp);
        p[0] = sum.x * inv;
        p[1] = sum.y * inv;
        p[2] = sum.z * inv;
        if (settings.aovs) {
          p[3] = aov_sum.albedo.x * inv;
          p[4] = aov_sum.albedo.y * inv;
          p[5] = aov_sum.albedo.z * inv;
          const vec3 n = glm::length(aov_sum.normal) > 0.0f ? glm::normalize(aov_sum.normal) : vec3(0.0f);
          p[6] = n.x;
          p[7] = n.y;
          p[8] = n.z;
          p[9] = aov_sum.depth * inv;
        }
      }
    }
    if (progress) progress->fetch_add(size_t(tile.pixel_count()), std::memory_order_relaxed);
  });
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  out.samples = uint64_t(cam.width) * uint64_t(cam.height) * uint64_t(settings.spp);
  return out;
}

int run_path_job(const PathJob& job, const std::string& description) {
  const apps::ThreadLimit thread_limit(job.threads);
  SceneDesc scene;
  const bool is_scene = std::filesystem::path(job.input).extension() == ".json";
  if (Status s = is_scene ? load_scene(job.input, scene) : default_scene(job.input, scene); !s.ok())
    return apps::fail(kProgram, s.message());
  if (job.set_width || !is_scene) scene.camera.width = job.width;
  if (job.set_height || !is_scene) scene.camera.height = job.height;
  if (job.spp > 0) scene.render.spp = job.spp;
  if (job.max_depth > 0) scene.render.max_depth = job.max_depth;
  if (job.seed >= 0) scene.render.seed = uint64_t(job.seed);
  scene.render.aovs = job.aovs;
  for (const LoadedMesh& m : scene.loaded_meshes) apps::print_load_warnings(kProgram, m.path, m.report, false);
  for (const std::string& w : scene.warnings) warn(w);
  // Not a warning, as for a mesh (print_load_warnings): said because it explains the figures.
  if (scene.origin != dvec3(0.0))
    std::fprintf(stderr, "%s: %s: far from the origin for its size: rendered relative to (%.17g, %.17g, %.17g)\n",
                 kProgram, job.input.c_str(), scene.origin.x, scene.origin.y, scene.origin.z);

  // The pixel buffers, checked against the memory available before anything is allocated: the
  // image (3 channels, 10 with AOVs), PNG's tone-mapped copy, and what
  // writing needs.
  const ImageFormat format = image_format_for(job.output).value_or(ImageFormat::kPng);
  const int channels = scene.render.aovs ? 10 : 3;
  const uint64_t bytes_per_pixel = 4 * uint64_t(channels) + (format == ImageFormat::kPng ? 4 * 3 : 0) +
                                   write_image_bytes_per_pixel(format, format == ImageFormat::kPng ? 3 : channels);
  if (Status s = check_memory(
          saturating_product(uint64_t(scene.camera.width) * uint64_t(scene.camera.height), bytes_per_pixel),
          "a " + std::to_string(scene.camera.width) + " x " + std::to_string(scene.camera.height) + " " +
              image_format_name(format) + " image" + (scene.render.aovs ? " with AOVs" : "") + " (" +
              std::to_string(bytes_per_pixel) + " bytes per pixel)");
      !s.ok())
    return apps::fail(kProgram, s.message());

  const auto t0 = std::chrono::steady_clock::now();
  RenderScene rs;
  if (Status s = rs.build(scene); !s.ok()) return apps::fail(kProgram, s.message());
  std::printf("%s: %s: %zu triangle meshes, %zu GWN objects; scene built in %.3f s\n", kProgram, job.input.c_str(),
              scene.meshes.size(), scene.gwn_objects.size(), apps::seconds_since(t0));
  std::fflush(stdout);

  const RenderSettings& settings = scene.render;
  std::atomic<size_t> progress{0};
  PathRender result;
  {
    apps::ProgressBar bar(progress, size_t(scene.camera.width) * size_t(scene.camera.height), "px");
    result = render_paths(rs, settings, &progress);
  }
  const double pixels = double(scene.camera.width) * double(scene.camera.height);
  std::printf("%s: %dx%d, %d spp in %.2f s on %s: %.3f us per sample per pixel (%s samples/s)\n", kProgram,
              scene.camera.width, scene.camera.height, settings.spp, result.seconds,
              count_of(thread_limit.workers(), "thread").c_str(), 1e6 * result.seconds / (pixels * settings.spp),
              apps::human_count(double(result.samples) / result.seconds).c_str());
  if (const uint64_t invalid = rs.invalid_rays()) {
    warn(count_of(invalid, "ray") + " with a non-finite or out-of-range origin or direction dropped (shown as misses)");
  }
  const bool png = format == ImageFormat::kPng;
  if (Status s = write_image(job.output, png ? tone_mapped(result.image) : result.image, description); !s.ok())
    return apps::fail(kProgram, s.message());
  std::printf("%s: wrote %s\n", kProgram, job.output.c_str());
  return 0;
}

}  // namespace gwnrt::render
