// The path tracer end to end, through Embree and the gwnrt plugin: furnace tests (diffuse and
// glass GWN spheres) and a diffuse sphere under an image environment, against closed forms;
// area lights and the sun on a floor; determinism across thread counts; the default scene.
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>
#include <tbb/global_control.h>

#include "render/integrators/path.h"
#include "render/render_scene.h"
#include "render/scene.h"
#include "test_util.h"

namespace gwnrt::render {
namespace {

// A diffuse sphere of albedo a as a GWN object inside a uniform environment of radiance E, no
// other light. The sphere is convex, so every ray leaving its surface escapes: the radiance it
// reflects toward the camera is exactly a·E (∫ (a/π) E cos = a·E), whatever the number of
// bounces; the background is E.
SceneDesc furnace(float albedo, float environment) {
  SceneDesc s;
  s.materials = {Material{MaterialKind::kDiffuse, Spectrum(albedo)}};
  s.material_names = {"white"};
  GwnObjectDesc sphere;
  sphere.source = "sphere";
  sphere.mesh = test::make_sphere(3);
  sphere.instances.push_back(glm::mat4(1.0f));
  s.gwn_objects.push_back(std::move(sphere));
  s.environment.radiance = Spectrum(environment);
  s.camera = render::look_at(vec3(0.0f, 0.0f, 4.0f), vec3(0.0f), vec3(0.0f, 1.0f, 0.0f), 40.0f, 40, 40);
  return s;
}

// The mean over the pixels `select` accepts (given the pixel's channels: R, G, B, then the
// AOVs) of their radiance (R+G+B)/3, and its standard error.
struct PixelMean {
  double mean = 0, stderr_ = 0;
  size_t pixels = 0;
};

template <class Select>
PixelMean pixel_mean(const PathRender& r, Select select) {
  PixelMean out;
  double sum = 0, sum2 = 0;
  for (int y = 0; y < r.image.height(); ++y)
    for (int x = 0; x < r.image.width(); ++x) {
      const float* p = r.image.pixel(x, y);
      if (!select(p)) continue;
      const double l = (double(p[0]) + p[1] + p[2]) / 3.0;
      sum += l;
      sum2 += l * l;
      ++out.pixels;
    }
  if (out.pixels == 0) return out;
  const double n = double(out.pixels);
  out.mean = sum / n;
  out.stderr_ = std::sqrt(std::max(0.0, sum2 / n - out.mean * out.mean) / n);
  return out;
}

struct FurnaceResult {
  PixelMean sphere;
  double background_min = 1e30, background_max = -1e30;
};

FurnaceResult render_furnace(float albedo, float environment, int spp) {
  const SceneDesc desc = furnace(albedo, environment);
  RenderScene scene;
  EXPECT_TRUE(scene.build(desc).ok());
  RenderSettings settings;
  settings.spp = spp;
  settings.max_depth = 8;
  settings.aovs = true;
  const PathRender r = render_paths(scene, settings);
  FurnaceResult out;
  // Every sample of the pixel on the sphere (depth averaged over samples equals a full hit's
  // only if all hit: compare with the pixel's own coverage through the albedo AOV).
  out.sphere = pixel_mean(r, [&](const float* p) { return std::abs(p[3] - albedo) < 1e-6f && p[9] > 0.0f; });
  for (int y = 0; y < desc.camera.height; ++y)
    for (int x = 0; x < desc.camera.width; ++x) {
      const float* p = r.image.pixel(x, y);
      for (int c = 0; c < 3; ++c) EXPECT_TRUE(std::isfinite(p[c]));
      if (p[3] == 0.0f && p[9] == 0.0f) {  // all background
        const double l = (double(p[0]) + p[1] + p[2]) / 3.0;
        out.background_min = std::min(out.background_min, l);
        out.background_max = std::max(out.background_max, l);
      }
    }
  return out;
}

TEST(PathTracer, FurnaceConvexGwnSphereReflectsAlbedoTimesEnvironment) {
  for (const float albedo : {0.5f, 0.8f, 1.0f}) {
    SCOPED_TRACE(albedo);
    const float environment = 1.0f;
    const FurnaceResult r = render_furnace(albedo, environment, 64);
    std::printf(
        "[ furnace albedo %.1f ] %zu sphere pixels: mean %.5f (expected %.5f, standard error %.2g); "
        "background in [%.6f, %.6f]\n",
        albedo, r.sphere.pixels, r.sphere.mean, double(albedo * environment), r.sphere.stderr_, r.background_min,
        r.background_max);
    ASSERT_GT(r.sphere.pixels, 400u);
    // Unbiased: the mean over ~700 pixels of 64 samples lies within 5 standard errors of a·E,
    // and within 1% whatever the noise estimate says (a bias would show as a constant offset).
    EXPECT_NEAR(r.sphere.mean, albedo * environment, std::max(5.0 * r.sphere.stderr_, 1e-3));
    EXPECT_NEAR(r.sphere.mean, albedo * environment, 0.01 * albedo * environment);
    // The background is the environment itself, exactly.
    EXPECT_FLOAT_EQ(float(r.background_min), environment);
    EXPECT_FLOAT_EQ(float(r.background_max), environment);
  }
}

// A smooth glass sphere (no absorption) in a uniform environment E is invisible: each path is
// reflected with probability F or refracted with 1 − F, and the radiance scalings of entering
// (1/η²) and leaving (η²) cancel, so every path that escapes carries E. A ray that enters the
// GWN object must then find S again from inside, with the outward normal telling the
// dielectric which side it is on: a lost exit, or a normal flipped for rays from inside, makes
// the sphere darker or brighter than the background.
// Only pixels seen at incidence below 53° (normal·view > 0.6) are measured: a faceted sphere
// seen at grazing incidence traps light by total internal reflection between facets (refraction
// near the critical angle, tilted by a facet), whispering-gallery paths that the depth cap cuts
// and Russian roulette makes heavy-tailed (found while writing this test: a ring of pixels 5%
// dark at 4096 samples, the same for Embree's triangles). Inside 53° the refracted ray meets
// the far side 10° short of the critical angle, more than facets of level 4 tilt it.
TEST(PathTracer, FurnaceGlassGwnSphereIsInvisible) {
  const float environment = 1.0f;
  SceneDesc s = furnace(1.0f, environment);
  s.gwn_objects[0].mesh = test::make_sphere(4);
  // The albedo does not tint a dielectric; 0.25 marks its pixels in the albedo AOV.
  s.materials[0] = Material{MaterialKind::kDielectric, Spectrum(0.25f), 0.0f, 1.5f, Spectrum(0.0f)};
  RenderScene scene;
  ASSERT_TRUE(scene.build(s).ok());
  RenderSettings settings;
  settings.spp = 64;
  settings.max_depth = 32;
  settings.aovs = true;
  // Not all samples on the glass (albedo AOV), or grazing (normal AOV's z toward the camera).
  const PixelMean glass = pixel_mean(render_paths(scene, settings),
                                     [](const float* p) { return std::abs(p[3] - 0.25f) <= 1e-6f && p[8] >= 0.6f; });
  ASSERT_GT(glass.pixels, 250u);
  std::printf("[ glass furnace ] %zu glass pixels: mean %.5f (expected %.5f, standard error %.2g)\n", glass.pixels,
              glass.mean, double(environment), glass.stderr_);
  EXPECT_NEAR(glass.mean, environment, std::max(5.0 * glass.stderr_, 1e-3));
  EXPECT_NEAR(glass.mean, environment, 0.01 * environment);
}

// A white diffuse GWN sphere under an image environment read from an EXR file through the
// scene (OpenImageIO, luminance importance sampling, MIS with the BSDF). The image holds the
// radiance L(ω) = c₀ + c·ω per channel, written through the documented lat-long mapping; a
// convex diffuse surface of albedo a with normal n then reflects exactly
// (a/π)∫_{n·ω>0} (c₀ + c·ω)(n·ω) dω = a (c₀ + (2/3) c·n), linear in n, so a pixel's averaged
// normal gives its expected value. The four quadrants of the sphere are checked apart: an
// image read upside down or mirrored, or a sampling pdf that does not match the image, moves
// one of them.
TEST(PathTracer, ImageEnvironmentLightsADiffuseSphereAsTheClosedFormSays) {
  const int w = 128, h = 64;
  const vec3 c0(1.0f, 1.0f, 1.0f);
  const glm::mat3 c(vec3(0.5f, 0.0f, 0.0f),   // column x: ∂L/∂ω_x per channel
                    vec3(0.8f, 0.8f, -0.6f),  // column y
                    vec3(0.0f, 0.3f, 0.2f));  // column z
  std::vector<float> pixels(size_t(w) * h * 3);
  for (int i = 0; i < h; ++i)
    for (int j = 0; j < w; ++j) {
      // The documented mapping (environment.h): θ = π v from +y, φ = 2π u − π, toward
      // (sin θ sin φ, cos θ, −sin θ cos φ).
      const double theta = kPi * (i + 0.5) / h, phi = 2.0 * kPi * (j + 0.5) / w - kPi;
      const vec3 omega(float(std::sin(theta) * std::sin(phi)), float(std::cos(theta)),
                       float(-std::sin(theta) * std::cos(phi)));
      const vec3 l = c0 + c * omega;
      for (int k = 0; k < 3; ++k) pixels[(size_t(i) * w + j) * 3 + k] = l[k];
    }
  const std::string path = std::string(::testing::TempDir()) + "/gwnrt_linear_sky.exr";
  {
    std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out) << OIIO::geterror();
    ASSERT_TRUE(out->open(path, OIIO::ImageSpec(w, h, 3, OIIO::TypeDesc::FLOAT))) << out->geterror();
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, pixels.data())) << out->geterror();
    ASSERT_TRUE(out->close()) << out->geterror();
  }
  const float albedo = 0.7f;
  SceneDesc s = furnace(albedo, 0.0f);
  s.gwn_objects[0].mesh = test::make_sphere(4);
  s.environment.file = path;
  RenderScene scene;
  ASSERT_TRUE(scene.build(s).ok());
  RenderSettings settings;
  settings.spp = 64;
  settings.aovs = true;
  const PathRender r = render_paths(scene, settings);
  // Per quadrant of the sphere as seen (by the signs of n_x and n_y) and channel:
  // Σ (rendered − expected), its square, and Σ expected.
  double diff[4][3] = {}, diff2[4][3] = {}, expected_sum[4][3] = {};
  size_t count[4] = {};
  for (int y = 0; y < s.camera.height; ++y)
    for (int x = 0; x < s.camera.width; ++x) {
      const float* p = r.image.pixel(x, y);
      if (std::abs(p[3] - albedo) > 1e-6f) continue;
      const vec3 normal(p[6], p[7], p[8]);
      const int quadrant = (normal.x > 0.0f ? 1 : 0) + (normal.y > 0.0f ? 2 : 0);
      const vec3 expected = albedo * (c0 + (2.0f / 3.0f) * (c * normal));
      for (int k = 0; k < 3; ++k) {
        const double d = double(p[k]) - expected[k];
        diff[quadrant][k] += d;
        diff2[quadrant][k] += d * d;
        expected_sum[quadrant][k] += expected[k];
      }
      ++count[quadrant];
    }
  static const char* const names[4] = {"lower left", "lower right", "upper left", "upper right"};
  for (int q = 0; q < 4; ++q) {
    SCOPED_TRACE(names[q]);
    ASSERT_GT(count[q], 100u);
    const double n = double(count[q]);
    for (int k = 0; k < 3; ++k) {
      const double bias = diff[q][k] / n, mean_expected = expected_sum[q][k] / n;
      const double stderr_ = std::sqrt(std::max(0.0, diff2[q][k] / n - bias * bias) / n);
      std::printf(
          "[ image environment ] %s, channel %d: %zu pixels, expected %.4f, rendered − expected %+.5f "
          "(standard error %.2g)\n",
          names[q], k, count[q], mean_expected, bias, stderr_);
      // The lat-long pixels are constant over ~2.8°: a piecewise-constant image of a linear L
      // reflects the same a(c₀ + (2/3)c·n) up to O(pixel²) ≈ 1e-3 (the pixel centres' errors
      // cancel to first order). So: within 5 standard errors plus that, and within 2%.
      EXPECT_NEAR(bias, 0.0, 5.0 * stderr_ + 2e-3 * mean_expected);
      EXPECT_LT(std::abs(bias), 0.02 * mean_expected);
    }
  }
}

// `s` rendered with `spp` samples per pixel: the mean radiance over the pixels that see only the
// material of albedo `albedo` (through the albedo AOV), and how many they are (0 if `s` does not
// build).
double mean_radiance_on(const SceneDesc& s, int spp, float albedo, size_t& pixels) {
  pixels = 0;
  RenderScene scene;
  if (Status st = scene.build(s); !st.ok()) {
    ADD_FAILURE() << st.message();
    return 0.0;
  }
  RenderSettings settings;
  settings.spp = spp;
  settings.aovs = true;
  const PixelMean m =
      pixel_mean(render_paths(scene, settings), [&](const float* p) { return std::abs(p[3] - albedo) <= 1e-6f; });
  pixels = m.pixels;
  return m.mean;
}

// A square of side 2·h at height y, normal up (or down).
Mesh square(float h, float y, bool up) {
  Mesh m;
  m.positions = {{-h, y, -h}, {h, y, -h}, {h, y, h}, {-h, y, h}};
  m.triangles = up ? std::vector<uvec3>{{0, 2, 1}, {0, 3, 2}} : std::vector<uvec3>{{0, 1, 2}, {0, 2, 3}};
  return m;
}

// A white-ish diffuse floor (albedo a, y = 0) under an emissive ceiling (radiance L, y = 1,
// facing down), both squares of side 2000, nothing else: the floor's irradiance is π·L times
// the ceiling's form factor, 1 - O(height / side), so the floor shows a·L (to 1e-3). The light
// is reached by next-event estimation and by BSDF sampling, weighted by MIS: a wrong area pdf
// or MIS weight shows as a bias.
TEST(PathTracer, FloorUnderAnEmissiveCeilingReflectsAlbedoTimesRadiance) {
  const float albedo = 0.6f, emission = 2.0f;
  SceneDesc s;
  s.materials = {Material{MaterialKind::kDiffuse, Spectrum(albedo)},
                 Material{MaterialKind::kEmissive, Spectrum(0.0f), 0.0f, 1.5f, Spectrum(emission)}};
  s.material_names = {"floor", "ceiling"};
  MeshDesc floor, ceiling;
  floor.mesh = square(1000.0f, 0.0f, true);
  floor.material = 0;
  ceiling.mesh = square(1000.0f, 1.0f, false);
  ceiling.material = 1;
  s.meshes = {floor, ceiling};
  s.camera = render::look_at(vec3(0.0f, 0.5f, 0.0f), vec3(0.3f, 0.0f, 0.2f), vec3(0.0f, 1.0f, 0.0f), 30.0f, 24, 24);
  size_t pixels = 0;
  const double mean = mean_radiance_on(s, 64, albedo, pixels);
  std::printf("[ emissive ceiling ] %zu floor pixels: mean %.5f, expected %.5f\n", pixels, mean,
              double(albedo * emission));
  ASSERT_GT(pixels, 500u);
  EXPECT_NEAR(mean, albedo * emission, 0.01 * albedo * emission);
}

// The same floor lit by the sun alone (black sky): radiance (a/π)·L_sun·Ω_sun·cos θ.
TEST(PathTracer, FloorUnderTheSunFollowsLambert) {
  const float albedo = 0.5f;
  SceneDesc s;
  s.materials = {Material{MaterialKind::kDiffuse, Spectrum(albedo)}};
  s.material_names = {"floor"};
  MeshDesc floor;
  floor.mesh = square(1000.0f, 0.0f, true);
  s.meshes = {floor};
  s.sun.direction = glm::normalize(vec3(0.3f, 0.8f, 0.2f));
  s.sun.radiance = Spectrum(1.0e4f);
  s.sun.angular_radius = 0.01f;
  s.camera = render::look_at(vec3(0.0f, 2.0f, 0.0f), vec3(0.5f, 0.0f, 0.1f), vec3(0.0f, 1.0f, 0.0f), 40.0f, 16, 16);
  size_t pixels = 0;
  const double mean = mean_radiance_on(s, 16, albedo, pixels);
  const double cone = 2.0 * kPi * (1.0 - std::cos(0.01));
  // The disc's own cosine spread is 1 ± 5e-5 across 0.01 rad: the centre cosine suffices.
  const double expected = albedo / kPi * 1.0e4 * cone * s.sun.direction.y;
  std::printf("[ sun ] %zu floor pixels: mean %.5f, expected %.5f\n", pixels, mean, expected);
  ASSERT_GT(pixels, 200u);
  EXPECT_NEAR(mean, expected, 0.01 * expected);
}

PathRender render_default_scene(int threads, uint64_t seed) {
  SceneDesc desc;
  EXPECT_TRUE(default_scene(test::data_path("bunny_holes.obj"), desc).ok());
  desc.camera.width = 48;
  desc.camera.height = 32;
  RenderScene scene;
  EXPECT_TRUE(scene.build(desc).ok());
  RenderSettings settings;
  settings.spp = 2;
  settings.seed = seed;
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
  return render_paths(scene, settings);
}

TEST(PathTracer, SameSeedSameImageWhateverTheThreadCount) {
  const PathRender one = render_default_scene(1, 5), two = render_default_scene(2, 5),
                   other = render_default_scene(2, 6);
  ASSERT_EQ(one.image.data().size(), two.image.data().size());
  EXPECT_EQ(one.image.data(), two.image.data());  // bit for bit
  EXPECT_NE(one.image.data(), other.image.data());
}

TEST(PathTracer, DefaultSceneIsNotBlank) {
  const PathRender r = render_default_scene(2, 1);
  const Image& im = r.image;
  float lo = 1e30f, hi = -1e30f;
  for (float v : im.data()) {
    ASSERT_TRUE(std::isfinite(v));
    ASSERT_GE(v, 0.0f);
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  EXPECT_LT(lo, 0.5f * hi);
  // The object stands in the middle of the frame, the sky fills the top row: they differ.
  const float* centre = im.pixel(im.width() / 2, im.height() / 2);
  const float* sky = im.pixel(im.width() / 2, 0);
  EXPECT_GT(std::abs(centre[0] - sky[0]) + std::abs(centre[2] - sky[2]), 0.05f);
}

TEST(SceneFile, BadFilesAreRefusedWithTheirPlace) {
  const std::string dir = std::string(::testing::TempDir());
  auto write = [&](const std::string& name, const std::string& text) {
    const std::string path = dir + "/" + name;
    FILE* f = std::fopen(path.c_str(), "w");
    std::fputs(text.c_str(), f);
    std::fclose(f);
    return path;
  };
  SceneDesc s;
  Status st = load_scene(dir + "/does_not_exist.json", s);
  EXPECT_FALSE(st.ok());
  EXPECT_NE(st.message().find("does_not_exist.json"), std::string::npos);
  st = load_scene(write("broken.json", "{ \"camera\": "), s);
  EXPECT_FALSE(st.ok());
  EXPECT_NE(st.message().find("not valid JSON"), std::string::npos);
  st = load_scene(write("badmat.json", R"({"materials": {"m": {"type": "plastic"}}})"), s);
  EXPECT_FALSE(st.ok());
  EXPECT_NE(st.message().find("/materials/m/type"), std::string::npos) << st.message();
  st = load_scene(write("badref.json", R"({"meshes": [{"plane": 2, "material": "nope"}]})"), s);
  EXPECT_FALSE(st.ok());
  EXPECT_NE(st.message().find("/meshes/0/material"), std::string::npos) << st.message();
  st = load_scene(write("badfov.json", R"({"camera": {"fov": 200}})"), s);
  EXPECT_FALSE(st.ok());
  EXPECT_NE(st.message().find("/camera/fov"), std::string::npos) << st.message();
  st = load_scene(write("nomesh.json", R"({"gwn_objects": [{"file": "missing.obj"}]})"), s);
  EXPECT_FALSE(st.ok());
  EXPECT_NE(st.message().find("missing.obj"), std::string::npos) << st.message();
  // And a good one: relative paths resolve next to the file.
  const std::string mesh = test::data_path("bunny_holes.obj");
  st = load_scene(write("good.json", R"({"materials": {"a": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
      "gwn_objects": [{"file": ")" + mesh +
                                         R"(", "material": "a", "level": 0.4,
                       "instances": [{"translate": [1, 2, 3]}, {"scale": 2}]}],
      "sun": {"direction": [0, 1, 0], "radiance": [1, 1, 1]}})"),
                  s);
  ASSERT_TRUE(st.ok()) << st.message();
  ASSERT_EQ(s.gwn_objects.size(), 1u);
  EXPECT_EQ(s.gwn_objects[0].instances.size(), 2u);
  EXPECT_FLOAT_EQ(s.gwn_objects[0].options.level, 0.4f);
  EXPECT_FLOAT_EQ(s.gwn_objects[0].instances[0][3][1], 2.0f);
}

}  // namespace
}  // namespace gwnrt::render
