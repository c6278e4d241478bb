// CPU vs CUDA: the same model, points and request through both backends. Both run the same
// evaluate_point; differences come only from compiler contraction (FMA) and math-library ulps,
// so the tolerances are a few float ulps scaled by each quantity's magnitude.
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "gwnrt/cuda.h"
#include "test_util.h"

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

// The signed distance, Newton projection and Harnack bound. They are made of the quantities
// compared above, but divide by |∇w| and branch (which piece wins, whether Newton converged),
// so a few points near a tie may go either way: those are counted, not failed, up to 0.5%.
TEST_P(CudaQueries, SignedDistanceMatchesTheCpuBackend) {
  const GwnModel model = test::build_model(test::load_test_mesh(GetParam()));
  cuda::DeviceModel device;
  ASSERT_TRUE(cuda::DeviceModel::upload(model, device).ok());
  const auto points = test::sample_points(test::mesh_bounds(model.mesh()), 20000, 4);
  const float diag = glm::length(test::mesh_bounds(model.mesh()).hi - test::mesh_bounds(model.mesh()).lo);
  QueryRequest request;
  request.fields = kFieldSignedDistance | kFieldProjection | kFieldHarnackBound;
  std::vector<PointResult> cpu(points.size()), gpu(points.size());
  ASSERT_TRUE(evaluate_points(model, points, request, cpu).ok());
  const Status s = cuda::evaluate_points(device, points, request, gpu);
  ASSERT_TRUE(s.ok()) << s.message();
  size_t piece_differs = 0, convergence_differs = 0;
  double max_sdf = 0, max_projection = 0, max_bound = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const PointResult &c = cpu[i], &g = gpu[i];
    if (c.sdf.piece != g.sdf.piece) {
      ++piece_differs;
    } else {
      // Relative to the distance itself as well: far from S the smooth estimate is a ratio of
      // small numbers.
      max_sdf =
          std::max(max_sdf, double(std::abs(c.sdf.distance - g.sdf.distance)) / (diag + std::abs(c.sdf.distance)));
    }
    EXPECT_EQ(std::signbit(c.sdf.distance), std::signbit(g.sdf.distance)) << "point " << i;
    if (c.projection.converged != g.projection.converged) {
      ++convergence_differs;
    } else if (c.projection.converged) {
      max_projection = std::max(max_projection, double(glm::length(c.projection.point - g.projection.point)) / diag);
    }
    max_bound = std::max(max_bound, double(std::abs(c.harnack_bound - g.harnack_bound)) / (diag + c.harnack_bound));
  }
  std::printf(
      "[ %s ] sdf max rel. diff %.2g (pieces differ at %zu), projection %.2g (convergence differs at %zu), "
      "Harnack bound %.2g\n",
      GetParam(), max_sdf, piece_differs, max_projection, convergence_differs, max_bound);
  EXPECT_LE(piece_differs, points.size() / 200);
  EXPECT_LE(convergence_differs, points.size() / 200);
  EXPECT_LT(max_sdf, 1e-4);
  // Newton stops anywhere within the tolerance band |w − w*| <= 1e-4: the two may stop one
  // iteration apart, about 1e-4 / |∇w| from each other.
  EXPECT_LT(max_projection, 1e-3);
  EXPECT_LT(max_bound, 1e-4);
}

// The columns variant (the Python module's device path) runs the same evaluate_point on the same
// device as evaluate_points, only storing differently: every column must equal, bit for bit, what
// the CPU's store_point_result makes of the GPU's PointResults, over batches that grow the scratch.
TEST_P(CudaQueries, ColumnsHoldTheDevicesPointResults) {
  const GwnModel model = test::build_model(test::load_test_mesh(GetParam()));
  cuda::DeviceModel device;
  ASSERT_TRUE(cuda::DeviceModel::upload(model, device).ok());
  constexpr uint32_t kEveryField = kFieldW | kFieldGradient | kFieldHessian | kFieldUnsignedDistance |
                                   kFieldBoundaryDistance | kFieldSignedDistance | kFieldPseudoDistance |
                                   kFieldSheetDistance | kFieldProjection | kFieldHarnackBound;
  for (const uint32_t fields : {uint32_t(kFieldW), kEveryField}) {
    for (const size_t count : {size_t(20000), size_t(7), size_t(50000)}) {
      const auto points = test::sample_points(test::mesh_bounds(model.mesh()), count, uint32_t(count) + 5);
      QueryRequest request;
      request.fields = fields;
      std::vector<PointResult> results(count);
      ASSERT_TRUE(cuda::evaluate_points(device, points, request, results).ok());
      test::AllPointColumns expected(count, 0xAB), columns(count, 0xCD);
      for (size_t i = 0; i < count; ++i) store_point_result(expected.columns, i, results[i]);
      cuda::BatchTimings timings;
      const Status s = cuda::evaluate_points_to_columns(device, points, request, columns.columns, nullptr, &timings);
      ASSERT_TRUE(s.ok()) << s.message();
      EXPECT_GT(timings.kernel, 0.0);
      for (size_t k = 0; k < columns.bytes.size(); ++k)
        EXPECT_TRUE(columns.bytes[k] == expected.bytes[k]) << "column " << k << ", " << count << " points";
    }
  }
  // The same refusals as evaluate_points.
  std::vector<vec3> bad = test::sample_points(test::mesh_bounds(model.mesh()), 10, 1);
  bad[5].y = std::numeric_limits<float>::quiet_NaN();
  std::vector<float> w(bad.size());
  PointColumns just_w;
  just_w.w = w.data();
  const Status refused = cuda::evaluate_points_to_columns(device, bad, QueryRequest{}, just_w);
  EXPECT_FALSE(refused.ok());
  EXPECT_NE(refused.message().find("point 5"), std::string::npos) << refused.message();
}

INSTANTIATE_TEST_SUITE_P(Meshes, CudaQueries, ::testing::Values("bunny.obj", "bunny_holes.obj", "teapot.obj"));

// The scratch a DeviceModel keeps between batches: batches that grow, shrink
// and grow again past it give the CPU's w each time (a stale or short buffer would not).
TEST(CudaBackend, BatchesReuseAndGrowTheScratch) {
  std::string why;
  if (!cuda::device_available(&why)) GTEST_SKIP() << "CUDA tests skipped: " << why;
  const GwnModel model = test::build_model(test::load_test_mesh("bunny_holes.obj"));
  cuda::DeviceModel device;
  ASSERT_TRUE(cuda::DeviceModel::upload(model, device).ok());
  QueryRequest request;
  request.fields = kFieldW | kFieldUnsignedDistance;
  for (const size_t count : {size_t(1000), size_t(1), size_t(70000), size_t(10), size_t(200000), size_t(3)}) {
    const auto points = test::sample_points(test::mesh_bounds(model.mesh()), count, uint32_t(count));
    std::vector<PointResult> cpu(count), gpu(count);
    ASSERT_TRUE(evaluate_points(model, points, request, cpu).ok());
    cuda::BatchTimings timings;
    const Status s = cuda::evaluate_points(device, points, request, gpu, nullptr, &timings);
    ASSERT_TRUE(s.ok()) << s.message();
    EXPECT_GT(timings.kernel, 0.0);
    EXPECT_GT(timings.download, 0.0);
    for (size_t i = 0; i < count; ++i) {
      ASSERT_NEAR(gpu[i].w, cpu[i].w, 1e-4) << count << " points, point " << i;
      ASSERT_NEAR(gpu[i].unsigned_distance, cpu[i].unsigned_distance, 1e-6f * (1.0f + cpu[i].unsigned_distance))
          << count << " points, point " << i;
    }
  }
}

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
