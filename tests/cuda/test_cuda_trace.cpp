// CPU vs CUDA ray tracing of S: the same model, camera rays and options through trace_rays and
// cuda::trace_rays. Both run the same trace_surface; they can differ only through compiler
// contraction (FMA) and math-library ulps. Those move a sheet hit by round-off and a smooth hit
// by at most the stopping distance, and they can flip the rare ray that grazes S or runs along
// ∂M; so hit/miss must agree on all but 0.1% of the rays, and where both hit, the kind, the
// triangle of a sheet hit, t (to round-off for sheets, to a few stopping distances for smooth
// pieces) and the normal must agree.
#include <cmath>
#include <string>

#include "../test_util.h"
#include "camera.h"
#include "gwnrt/cuda.h"

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
    const examples::PinholeCamera camera = examples::frame_box(box, 160, 120, azimuth, 20.0f);
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
  size_t hit_disagree = 0, both_hit = 0, smooth = 0;
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
    if (cpu[i].kind == HitKind::kSheet) {
      EXPECT_EQ(cpu[i].triangle, gpu[i].triangle) << "ray " << i;
      max_sheet_dt = std::max(max_sheet_dt, dt / diag);
    } else {
      // Both stopped within about ε|∇w| of the level in w, so within ε / |cos| in t along a ray
      // that meets the level at an angle (n · d = cos); grazing rays are left out.
      ++smooth;
      const double cosine = std::abs(double(glm::dot(cpu[i].normal, rays[i].direction)));
      if (cosine > 0.05) max_smooth_dt = std::max(max_smooth_dt, dt * cosine / eps);
    }
    const double cosine = std::clamp(double(glm::dot(cpu[i].normal, gpu[i].normal)), -1.0, 1.0);
    max_angle = std::max(max_angle, std::acos(cosine));
  }
  std::printf(
      "[ %s ] %zu rays: %zu hit/miss disagreements, %zu both hit (%zu smooth); max |dt|: sheets %.3g diag, "
      "smooth %.3g stopping distances (times the cosine); max normal angle %.3g rad\n",
      GetParam().mesh, rays.size(), hit_disagree, both_hit, smooth, max_sheet_dt, max_smooth_dt, max_angle);
  EXPECT_LE(hit_disagree, rays.size() / 1000);
  EXPECT_GT(both_hit, rays.size() / 50);  // the comparison says something
  EXPECT_LE(max_sheet_dt, 1e-6);          // float round-off of one crossing
  EXPECT_LE(max_smooth_dt, 4.0);
  EXPECT_LE(max_angle, 1e-2);
}

INSTANTIATE_TEST_SUITE_P(Meshes, CudaTrace,
                         ::testing::Values(TraceCase{"bunny.obj", TraceMode::kWindingNumber},
                                           TraceCase{"bunny_holes.obj", TraceMode::kWindingNumber},
                                           TraceCase{"teapot.obj", TraceMode::kWindingNumber},
                                           TraceCase{"bunny_holes.obj", TraceMode::kSolidAngle}));

}  // namespace
}  // namespace gwnrt
