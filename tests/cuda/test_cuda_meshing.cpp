// The mesher on the CUDA backend against the TBB one: the same driver and passes
// (meshing/mesh_pipeline.h), so the same mesh up to float rounding: the same vertex and triangle
// counts and the same triangles, each vertex within 1e-5 of a cell of the CPU's (issue 17).
#include <cmath>
#include <string>

#include "../test_util.h"
#include "gwnrt/cuda.h"

namespace gwnrt {
namespace {

struct MeshCase {
  const char* mesh;
  uint32_t resolution;
  MeshingMethod method;
};

class CudaMeshing : public ::testing::TestWithParam<MeshCase> {
 protected:
  void SetUp() override {
    std::string why;
    if (!cuda::device_available(&why)) GTEST_SKIP() << "CUDA tests skipped: " << why;
  }
};

TEST_P(CudaMeshing, MatchesTheCpuBackend) {
  const MeshCase c = GetParam();
  const GwnModel model = test::build_model(test::load_test_mesh(c.mesh));
  cuda::DeviceModel device;
  ASSERT_TRUE(cuda::DeviceModel::upload(model, device).ok());
  MeshingOptions options;
  options.resolution = c.resolution;
  options.method = c.method;
  SurfaceMesh cpu, gpu;
  MeshingStats cpu_stats, gpu_stats;
  ASSERT_TRUE(extract_surface(model, options, cpu, &cpu_stats).ok());
  const Status s = cuda::extract_surface(device, model, options, gpu, &gpu_stats);
  ASSERT_TRUE(s.ok()) << s.message();
  ASSERT_GT(cpu.triangles.size(), 0u);
  EXPECT_EQ(gpu_stats.active_blocks, cpu_stats.active_blocks);
  EXPECT_EQ(gpu_stats.crossing_edges, cpu_stats.crossing_edges);
  EXPECT_EQ(gpu_stats.sheet_edges, cpu_stats.sheet_edges);
  ASSERT_EQ(gpu.positions.size(), cpu.positions.size());
  ASSERT_EQ(gpu.triangles.size(), cpu.triangles.size());
  const float tolerance = 1e-5f * cpu_stats.cell_size;
  float worst = 0;
  for (size_t i = 0; i < cpu.positions.size(); ++i)
    worst = std::max(worst, glm::length(gpu.positions[i] - cpu.positions[i]));
  EXPECT_LE(worst, tolerance) << "worst vertex offset " << worst / cpu_stats.cell_size << " cells";
  size_t same = 0;
  for (size_t t = 0; t < cpu.triangles.size(); ++t) same += gpu.triangles[t] == cpu.triangles[t];
  EXPECT_EQ(same, cpu.triangles.size());
  RecordProperty("worst_offset_cells", std::to_string(worst / cpu_stats.cell_size));
}

INSTANTIATE_TEST_SUITE_P(BundledMeshes, CudaMeshing,
                         ::testing::Values(MeshCase{"bunny.obj", 128, MeshingMethod::kDualContouring},
                                           MeshCase{"bunny_holes.obj", 128, MeshingMethod::kDualContouring},
                                           MeshCase{"bunny_holes.obj", 96, MeshingMethod::kMarchingCubes},
                                           MeshCase{"teapot.obj", 128, MeshingMethod::kDualContouring}),
                         [](const ::testing::TestParamInfo<MeshCase>& info) {
                           std::string name = info.param.mesh;
                           name = name.substr(0, name.find('.')) + "_" + std::to_string(info.param.resolution) +
                                  (info.param.method == MeshingMethod::kMarchingCubes ? "_mc" : "_dc");
                           return name;
                         });

// A model never uploaded, and a device copy of another model, are refused with a message.
TEST(CudaMeshingErrors, RefusesAMismatchedDeviceModel) {
  std::string why;
  if (!cuda::device_available(&why)) GTEST_SKIP() << "CUDA tests skipped: " << why;
  const GwnModel model = test::build_model(test::load_test_mesh("bunny_holes.obj"));
  const GwnModel other = test::build_model(test::load_test_mesh("teapot.obj"));
  SurfaceMesh out;
  cuda::DeviceModel empty;
  EXPECT_FALSE(cuda::extract_surface(empty, model, MeshingOptions{}, out).ok());
  cuda::DeviceModel device;
  ASSERT_TRUE(cuda::DeviceModel::upload(other, device).ok());
  const Status s = cuda::extract_surface(device, model, MeshingOptions{}, out);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("not an upload of this model"), std::string::npos) << s.message();
}

}  // namespace
}  // namespace gwnrt
