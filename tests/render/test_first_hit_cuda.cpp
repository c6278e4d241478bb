// First-hit rendering on the GPU against the CPU: the same per-pixel function
// (first_hit_pixel) in a kernel, so hit/miss must agree on at least 99.9% of the pixels, and
// where both hit, the kind. Skips without the CUDA backend or a usable GPU.
#include <string>

#include <gtest/gtest.h>

#include "gwnrt/engine.h"
#include "render/camera.h"
#include "render/integrators/first_hit.h"
#include "render/integrators/first_hit_cuda.h"
#include "test_util.h"

namespace gwnrt::render {
namespace {

TEST(FirstHitCuda, MatchesTheCpuImage) {
  std::string why;
  if (!cuda_usable(&why)) GTEST_SKIP() << "CUDA tests skipped: " << why;
  for (const char* mesh : {"bunny_holes.obj", "teapot.obj"}) {
    const Engine engine(test::build_model(test::load_test_mesh(mesh)));
    const GwnModel& model = engine.model();
    const cuda::DeviceModel* device = nullptr;
    ASSERT_TRUE(engine.device_model(device).ok());
    const render::PinholeCamera camera = render::frame_box(model.bounds(), 320, 240);
    FirstHitSettings settings;
    const FirstHitRender cpu = render_first_hit(model.view(), camera, settings);
    std::vector<FirstHitSample> pixels;
    double seconds = 0;
    const Status s = render_first_hit_cuda(*device, camera, settings, 2, pixels, seconds);
    ASSERT_TRUE(s.ok()) << s.message();
    ASSERT_EQ(pixels.size(), cpu.traces.size());
    size_t differ = 0, kind_differs = 0;
    for (size_t i = 0; i < pixels.size(); ++i) {
      const bool gpu_hit = pixels[i].trace.kind != HitKind::kNone, cpu_hit = cpu.traces[i].kind != HitKind::kNone;
      differ += gpu_hit != cpu_hit;
      kind_differs += gpu_hit && cpu_hit && pixels[i].trace.kind != cpu.traces[i].kind;
    }
    EXPECT_LE(differ, pixels.size() / 1000) << mesh;
    EXPECT_LE(kind_differs, pixels.size() / 1000) << mesh;
    std::printf("[ %s ] %zu pixels: hit/miss differs at %zu, kind at %zu; %.3f ms a frame\n", mesh, pixels.size(),
                differ, kind_differs, 1e3 * seconds);
  }
}

}  // namespace
}  // namespace gwnrt::render
