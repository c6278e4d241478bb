// CPU vs CUDA ray tracing of S: the same model, camera rays and options through trace_rays and
// cuda::trace_rays. Both run the same trace_surface; they can differ only through compiler
// contraction (FMA) and math-library ulps. Those move a sheet hit by round-off and a smooth hit
// by at most the stopping distance, and they can flip the rare ray that grazes S or runs along
// ∂M; so hit/miss must agree on all but 0.1% of the rays, and where both hit, the kind, the
// triangle of a sheet hit, t (to round-off for sheets, to a few stopping distances for smooth
// pieces) and the normal must agree.
#include <cmath>
#include <string>

#include "gwnrt/cuda.h"
#include "render/camera.h"
#include "test_util.h"

namespace gwnrt {
namespace {

struct TraceCase {
  const char* mesh;
  TraceMode mode;
};

void PrintTo(const TraceCase& c, std::ostream* os) {
  *os << c.mesh << (c.mode == TraceMode::kSolidAngle ? ", solid angle" : ", gwn");
}

class CudaTrace : public ::testing::TestWithParam<TraceCase> {
 protected:
  void SetUp() override {
    std::string why;
    if (!cuda::device_available(&why)) GTEST_SKIP() << "CUDA tests skipped: " << why;
  }
};

TEST_P(CudaTrace, MatchesTheCpuBackend) {
  const GwnModel model = test::build_model(test::load_test_mesh(GetParam().mesh));
  cuda::DeviceModel device;
  ASSERT_TRUE(cuda::DeviceModel::upload(model, device).ok());
  const Aabb box = model.bounds();
  const float diag = glm::length(box.hi - box.lo);
  std::vector<Ray> rays;
  for (const float azimuth : {30.0f, 150.0f, 260.0f}) {
    const render::PinholeCamera camera = render::frame_box(box, 160, 120, azimuth, 20.0f);
    for (int y = 0; y < camera.height; ++y)
      for (int x = 0; x < camera.width; ++x) rays.push_back(camera.ray(x, y));
  }
  TraceOptions options;
  options.mode = GetParam().mode;
  std::vector<RayHit> cpu(rays.size()), gpu(rays.size());
  ASSERT_TRUE(trace_rays(model, rays, options, cpu).ok());
  const Status s = cuda::trace_rays(device, rays, options, gpu);
  ASSERT_TRUE(s.ok()) << s.message();

  const double eps = double(options.epsilon) * diag;
  size_t hit_disagree = 0, both_hit = 0, smooth = 0, turned = 0;
  double max_sheet_dt = 0, max_smooth_dt = 0, max_angle = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    EXPECT_FALSE(gpu[i].invalid);
    if (cpu[i].hit != gpu[i].hit) {
      ++hit_disagree;
      continue;
    }
    if (!cpu[i].hit) continue;
    ++both_hit;
    ASSERT_EQ(cpu[i].kind, gpu[i].kind) << "ray " << i;
    const double dt = std::abs(double(cpu[i].t) - double(gpu[i].t));  // unit directions
    // Along a ray that meets the surface at an angle (n · d = cos), a difference across it shows
    // as that over |cos| in t; grazing rays are left out.
    const double cosine = std::abs(double(glm::dot(cpu[i].normal, rays[i].direction)));
    if (cpu[i].kind == HitKind::kSheet) {
      EXPECT_EQ(cpu[i].triangle, gpu[i].triangle) << "ray " << i;
      // Round-off of one triangle crossing (the CPU with and without fused multiply-adds: up to
      // 5.6e-6 of the diagonal unscaled, at |cos| 0.008 to 0.06).
      if (cosine > 0.05) max_sheet_dt = std::max(max_sheet_dt, dt * cosine / diag);
    } else {
      // Both stopped within about ε|∇w| of the level in w, so within ε / |cos| in t.
      ++smooth;
      if (cosine > 0.05) max_smooth_dt = std::max(max_smooth_dt, dt * cosine / eps);
    }
    // The angle between unit normals from their chord (acos near 1 loses 7e-4 rad to rounding).
    const double angle = 2.0 * std::asin(std::min(1.0, 0.5 * double(glm::length(cpu[i].normal - gpu[i].normal))));
    max_angle = std::max(max_angle, angle);
    turned += angle > 1e-2;
  }
  std::printf(
      "[ %s ] %zu rays: %zu hit/miss disagreements, %zu both hit (%zu smooth); max |dt| times the cosine: "
      "sheets %.3g diag, smooth %.3g stopping distances; max normal angle %.3g rad (%zu beyond 1e-2)\n",
      GetParam().mesh, rays.size(), hit_disagree, both_hit, smooth, max_sheet_dt, max_smooth_dt, max_angle, turned);
  EXPECT_LE(hit_disagree, rays.size() / 1000);
  EXPECT_GT(both_hit, rays.size() / 50);  // the comparison says something
  EXPECT_LE(max_sheet_dt, 1e-6);          // float round-off of one crossing
  EXPECT_LE(max_smooth_dt, 4.0);
  // Normals to 1e-2 rad but for one ray in a thousand: a smooth normal is ∇w at the stopping
  // point, which turns fast near ∂M (bunny_holes in solid-angle mode: one ray of 57600 at 0.0129
  // rad with and without fused multiply-adds on the CPU).
  EXPECT_LE(turned, both_hit / 1000) << "max normal angle " << max_angle;
}

INSTANTIATE_TEST_SUITE_P(Meshes, CudaTrace,
                         ::testing::Values(TraceCase{"bunny.obj", TraceMode::kWindingNumber},
                                           TraceCase{"bunny_holes.obj", TraceMode::kWindingNumber},
                                           TraceCase{"teapot.obj", TraceMode::kWindingNumber},
                                           TraceCase{"bunny_holes.obj", TraceMode::kSolidAngle}));

}  // namespace
}  // namespace gwnrt
