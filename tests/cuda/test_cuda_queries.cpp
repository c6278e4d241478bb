// CPU vs CUDA: the same model, points and request through both backends. Both run the same
// evaluate_point; differences come only from compiler contraction (FMA) and math-library ulps,
// so the tolerances are a few float ulps scaled by each quantity's magnitude.
#include <cmath>
#include <string>

#include "gwnrt/cuda.h"
#include "../test_util.h"

namespace gwnrt {
namespace {

class CudaQueries : public ::testing::TestWithParam<const char*> {
 protected:
  void SetUp() override {
    std::string why;
    if (!cuda::device_available(&why)) GTEST_SKIP() << "CUDA tests skipped: " << why;
  }
};

TEST_P(CudaQueries, MatchTheCpuBackend) {
  const GwnModel model = test::build_model(test::load_test_mesh(GetParam()));
  cuda::DeviceModel device;
  ASSERT_TRUE(cuda::DeviceModel::upload(model, device).ok());
  const auto points = test::sample_points(test::mesh_bounds(model.mesh()), 20000, 3);
  const float diag = glm::length(test::mesh_bounds(model.mesh()).hi - test::mesh_bounds(model.mesh()).lo);
  for (int order = 0; order <= 2; ++order) {
    QueryRequest request;
    request.fields = kFieldW | kFieldGradient | kFieldHessian | kFieldUnsignedDistance | kFieldBoundaryDistance;
    request.taylor.order = order;
    std::vector<PointResult> cpu(points.size()), gpu(points.size());
    ASSERT_TRUE(evaluate_points(model, points, request, cpu).ok());
    const Status s = cuda::evaluate_points(device, points, request, gpu);
    ASSERT_TRUE(s.ok()) << s.message();
    double max_dw = 0, max_dg = 0, max_dd = 0;
    for (size_t i = 0; i < points.size(); ++i) {
      max_dw = std::max(max_dw, double(std::abs(cpu[i].w - gpu[i].w)));
      const float gscale = 1.0f + glm::length(cpu[i].gradient) * diag;
      max_dg = std::max(max_dg, double(glm::length(cpu[i].gradient - gpu[i].gradient) * diag / gscale));
      max_dd = std::max(max_dd, double(std::abs(cpu[i].unsigned_distance - gpu[i].unsigned_distance) / diag));
      if (std::isfinite(cpu[i].boundary_distance))
        max_dd = std::max(max_dd, double(std::abs(cpu[i].boundary_distance - gpu[i].boundary_distance) / diag));
      else
        EXPECT_FALSE(std::isfinite(gpu[i].boundary_distance));
    }
    RecordProperty("order" + std::to_string(order) + "_max_dw", std::to_string(max_dw));
    EXPECT_LT(max_dw, 1e-4) << "order " << order;
    EXPECT_LT(max_dg, 1e-3) << "order " << order;
    EXPECT_LT(max_dd, 1e-6) << "order " << order;
  }
}

INSTANTIATE_TEST_SUITE_P(Meshes, CudaQueries, ::testing::Values("bunny.obj", "bunny_holes.obj", "teapot.obj"));

TEST(CudaBackend, ReportsWhyNoDeviceIsUsable) {
  std::string why;
  if (cuda::device_available(&why)) GTEST_SKIP() << "a device is present";
  EXPECT_FALSE(why.empty());
  GwnModel model = test::build_model(test::make_cube());
  cuda::DeviceModel device;
  const Status s = cuda::DeviceModel::upload(model, device);
  EXPECT_FALSE(s.ok());
  EXPECT_EQ(s.code(), StatusCode::kUnavailable);
}

}  // namespace
}  // namespace gwnrt
