// The path tracer end to end, through Embree and the gwnrt plugin: a furnace test against the
// closed form for a convex object in a uniform environment, determinism across thread counts,
// and the default scene.
#include <cmath>
#include <vector>

#include <tbb/global_control.h>

#include "../test_util.h"
#include "path_tracer.h"
#include "render_scene.h"
#include "scene.h"

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
  s.camera.eye = vec3(0.0f, 0.0f, 4.0f);
  s.camera.target = vec3(0.0f);
  s.camera.fov_degrees = 40.0f;
  s.camera.width = 40;
  s.camera.height = 40;
  return s;
}

struct FurnaceResult {
  double sphere_mean = 0, sphere_stderr = 0, background_min = 1e30, background_max = -1e30;
  size_t sphere_pixels = 0;
};

FurnaceResult render_furnace(float albedo, float environment, int spp) {
  const SceneDesc desc = furnace(albedo, environment);
  RenderScene scene;
  EXPECT_TRUE(scene.build(desc).ok());
  PathSettings settings;
  settings.spp = spp;
  settings.max_depth = 8;
  settings.aovs = true;
  const PathRender r = render_paths(scene, settings);
  FurnaceResult out;
  double sum = 0, sum2 = 0;
  for (int y = 0; y < desc.camera.height; ++y)
    for (int x = 0; x < desc.camera.width; ++x) {
      const float* p = r.image.pixel(x, y);
      for (int c = 0; c < 3; ++c) EXPECT_TRUE(std::isfinite(p[c]));
      const float depth = p[9];
      // Every sample of the pixel on the sphere (depth averaged over samples equals a full hit's
      // only if all hit: compare with the pixel's own coverage through the albedo AOV).
      const bool all_sphere = std::abs(p[3] - albedo) < 1e-6f && depth > 0.0f;
      const bool all_background = p[3] == 0.0f && depth == 0.0f;
      const double l = (double(p[0]) + p[1] + p[2]) / 3.0;
      if (all_sphere) {
        sum += l;
        sum2 += l * l;
        ++out.sphere_pixels;
      } else if (all_background) {
        out.background_min = std::min(out.background_min, l);
        out.background_max = std::max(out.background_max, l);
      }
    }
  const double n = double(out.sphere_pixels);
  out.sphere_mean = sum / n;
  out.sphere_stderr = std::sqrt(std::max(0.0, sum2 / n - out.sphere_mean * out.sphere_mean) / n);
  return out;
}

TEST(PathTracer, FurnaceConvexGwnSphereReflectsAlbedoTimesEnvironment) {
  for (const float albedo : {0.5f, 0.8f, 1.0f}) {
    SCOPED_TRACE(albedo);
    const float environment = 1.0f;
    const FurnaceResult r = render_furnace(albedo, environment, 64);
    std::printf("[ furnace albedo %.1f ] %zu sphere pixels: mean %.5f (expected %.5f, standard error %.2g); "
                "background in [%.6f, %.6f]\n",
                albedo, r.sphere_pixels, r.sphere_mean, double(albedo * environment), r.sphere_stderr,
                r.background_min, r.background_max);
    ASSERT_GT(r.sphere_pixels, 400u);
    // Unbiased: the mean over ~700 pixels of 64 samples lies within 5 standard errors of a·E,
    // and within 1% whatever the noise estimate says (a bias would show as a constant offset).
    EXPECT_NEAR(r.sphere_mean, albedo * environment, std::max(5.0 * r.sphere_stderr, 1e-3));
    EXPECT_NEAR(r.sphere_mean, albedo * environment, 0.01 * albedo * environment);
    // The background is the environment itself, exactly.
    EXPECT_FLOAT_EQ(float(r.background_min), environment);
    EXPECT_FLOAT_EQ(float(r.background_max), environment);
  }
}

// Mean radiance over the pixels that see `material` only (through the albedo AOV) of a render.
double mean_radiance_on(const PathRender& r, float albedo, size_t& pixels) {
  double sum = 0;
  pixels = 0;
  for (int y = 0; y < r.image.height(); ++y)
    for (int x = 0; x < r.image.width(); ++x) {
      const float* p = r.image.pixel(x, y);
      if (std::abs(p[3] - albedo) > 1e-6f) continue;
      sum += (double(p[0]) + p[1] + p[2]) / 3.0;
      ++pixels;
    }
  return pixels ? sum / double(pixels) : 0.0;
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
  s.camera.eye = vec3(0.0f, 0.5f, 0.0f);
  s.camera.target = vec3(0.3f, 0.0f, 0.2f);
  s.camera.fov_degrees = 30.0f;
  s.camera.width = s.camera.height = 24;
  RenderScene scene;
  ASSERT_TRUE(scene.build(s).ok());
  PathSettings settings;
  settings.spp = 64;
  settings.aovs = true;
  size_t pixels = 0;
  const double mean = mean_radiance_on(render_paths(scene, settings), albedo, pixels);
  std::printf("[ emissive ceiling ] %zu floor pixels: mean %.5f, expected %.5f\n", pixels, mean, double(albedo * emission));
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
  s.camera.eye = vec3(0.0f, 2.0f, 0.0f);
  s.camera.target = vec3(0.5f, 0.0f, 0.1f);
  s.camera.width = s.camera.height = 16;
  RenderScene scene;
  ASSERT_TRUE(scene.build(s).ok());
  PathSettings settings;
  settings.spp = 16;
  settings.aovs = true;
  size_t pixels = 0;
  const double mean = mean_radiance_on(render_paths(scene, settings), albedo, pixels);
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
  PathSettings settings;
  settings.spp = 2;
  settings.seed = seed;
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
  return render_paths(scene, settings);
}

TEST(PathTracer, SameSeedSameImageWhateverTheThreadCount) {
  const PathRender one = render_default_scene(1, 5), two = render_default_scene(2, 5), other = render_default_scene(2, 6);
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
      "gwn_objects": [{"file": ")" + mesh + R"(", "material": "a", "level": 0.4,
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
