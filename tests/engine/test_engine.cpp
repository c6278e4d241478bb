// The engine (gwnrt/engine.h): the device chosen as the build and the machine allow, and its
// batches on the CPU identical to the drivers they stand for; on a machine without a usable GPU,
// `cuda` refused with the reason and nothing run.
#include "gwnrt/engine.h"

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "gwnrt/base/memory.h"
#include "test_util.h"

namespace gwnrt {
namespace {

TEST(Engine, DeviceNamesRoundTrip) {
  for (Device d : {Device::kCpu, Device::kCuda, Device::kAuto}) {
    Device named = d == Device::kCpu ? Device::kAuto : Device::kCpu;
    ASSERT_TRUE(device_named(device_name(d), named)) << device_name(d);
    EXPECT_EQ(named, d);
  }
  Device untouched = Device::kCuda;
  for (const char* name : {"gpu", "CPU", "", "cuda "}) {
    EXPECT_FALSE(device_named(name, untouched)) << name;
    EXPECT_EQ(untouched, Device::kCuda);
  }
}

TEST(Engine, ChoosesTheDeviceTheMachineHas) {
  std::string why;
  const bool usable = cuda_usable(&why);
  if (!cuda_backend_built()) {
    EXPECT_FALSE(usable);
  }
  if (!usable) {
    EXPECT_FALSE(why.empty());
  }

  DeviceChoice cpu;
  ASSERT_TRUE(choose_device(Device::kCpu, cpu).ok());
  EXPECT_EQ(cpu.device, Device::kCpu);
  EXPECT_TRUE(cpu.reason.empty());

  DeviceChoice automatic;
  ASSERT_TRUE(choose_device(Device::kAuto, automatic).ok());
  EXPECT_EQ(automatic.device, usable ? Device::kCuda : Device::kCpu);
  EXPECT_EQ(automatic.reason, usable ? std::string() : why);

  DeviceChoice gpu;
  const Status s = choose_device(Device::kCuda, gpu);
  EXPECT_EQ(s.ok(), usable);
  if (!usable) {
    EXPECT_EQ(s.code(), StatusCode::kUnavailable);
    EXPECT_EQ(s.message(), why);
    EXPECT_EQ(gpu.device, Device::kCpu);
  }
}

// On the CPU every batch is the driver it stands for, bit for bit.
TEST(Engine, CpuBatchesAreTheDrivers) {
  const GwnModel reference = test::build_model(test::load_test_mesh("bunny_holes.obj"));
  const Engine engine(test::build_model(test::load_test_mesh("bunny_holes.obj")));
  const Aabb box = engine.model().bounds();
  const std::vector<vec3> points = test::sample_points(box, 2000, 7);

  QueryRequest request;
  request.fields = kFieldW | kFieldGradient | kFieldUnsignedDistance | kFieldSignedDistance;
  std::vector<PointResult> expected(points.size()), got(points.size());
  ASSERT_TRUE(evaluate_points(reference, points, request, expected).ok());
  ASSERT_TRUE(engine.evaluate_points(Device::kCpu, points, request, got).ok());
  for (size_t i = 0; i < points.size(); ++i) {
    EXPECT_EQ(got[i].w, expected[i].w) << i;
    EXPECT_EQ(got[i].gradient, expected[i].gradient) << i;
    EXPECT_EQ(got[i].unsigned_distance, expected[i].unsigned_distance) << i;
    EXPECT_EQ(got[i].sdf.distance, expected[i].sdf.distance) << i;
  }

  std::vector<float> w(points.size());
  PointColumns columns;
  columns.w = w.data();
  ASSERT_TRUE(engine.evaluate_points_to_columns(Device::kCpu, points, request, columns).ok());
  for (size_t i = 0; i < points.size(); ++i) EXPECT_EQ(w[i], expected[i].w) << i;

  std::vector<Ray> rays;
  for (size_t i = 0; i < 200; ++i) rays.push_back(Ray{box.hi + vec3(1.0f), points[i] - (box.hi + vec3(1.0f))});
  std::vector<RayHit> expected_hits(rays.size()), hits(rays.size());
  ASSERT_TRUE(trace_rays(reference, rays, TraceOptions{}, expected_hits).ok());
  ASSERT_TRUE(engine.trace_rays(Device::kCpu, rays, TraceOptions{}, hits).ok());
  for (size_t i = 0; i < rays.size(); ++i) {
    EXPECT_EQ(hits[i].hit, expected_hits[i].hit) << i;
    EXPECT_EQ(hits[i].t, expected_hits[i].t) << i;
  }

  MeshingOptions meshing;
  meshing.resolution = 24;
  SurfaceMesh expected_mesh, mesh;
  ASSERT_TRUE(extract_surface(reference, meshing, expected_mesh).ok());
  ASSERT_TRUE(engine.extract_surface(Device::kCpu, meshing, mesh).ok());
  ASSERT_EQ(mesh.positions.size(), expected_mesh.positions.size());
  ASSERT_EQ(mesh.triangles.size(), expected_mesh.triangles.size());
  EXPECT_EQ(std::memcmp(mesh.positions.data(), expected_mesh.positions.data(), mesh.positions.size() * sizeof(vec3)),
            0);
  EXPECT_EQ(available_memory_on(Device::kCpu) > 0, available_memory_bytes() > 0);
}

// Without a usable GPU, `cuda` is refused with the reason and the results are left alone; `auto`
// runs on the CPU.
TEST(Engine, CudaWithoutAGpuSaysWhy) {
  std::string why;
  if (cuda_usable(&why)) GTEST_SKIP() << "a GPU is usable here: tests/cuda compares it with the CPU";
  const Engine engine(test::build_model(test::load_test_mesh("bunny.obj")));
  const std::vector<vec3> points = {engine.model().bounds().centre()};
  std::vector<PointResult> results(1);
  results[0].w = -7.0f;
  const Status s = engine.evaluate_points(Device::kCuda, points, QueryRequest{}, results);
  EXPECT_EQ(s.code(), StatusCode::kUnavailable);
  EXPECT_EQ(s.message(), why);
  EXPECT_EQ(results[0].w, -7.0f);
  EXPECT_EQ(engine.upload().code(), StatusCode::kUnavailable);
  const cuda::DeviceModel* device = reinterpret_cast<const cuda::DeviceModel*>(&engine);
  EXPECT_FALSE(engine.device_model(device).ok());
  EXPECT_EQ(device, nullptr);
  EXPECT_EQ(available_memory_on(Device::kCuda), 0u);
  SurfaceMesh mesh;
  EXPECT_EQ(engine.extract_surface(Device::kCuda, MeshingOptions{}, mesh).code(), StatusCode::kUnavailable);

  std::vector<PointResult> on_cpu(1);
  ASSERT_TRUE(engine.evaluate_points(Device::kAuto, points, QueryRequest{}, results).ok());
  ASSERT_TRUE(engine.evaluate_points(Device::kCpu, points, QueryRequest{}, on_cpu).ok());
  EXPECT_EQ(results[0].w, on_cpu[0].w);
}

// set_sheet_level goes to the model (the sdf then reads the new level's sheets).
TEST(Engine, SetSheetLevelReachesTheModel) {
  Engine engine(test::build_model(test::load_test_mesh("bunny_holes.obj")));
  ASSERT_TRUE(engine.set_sheet_level(0.25f).ok());
  EXPECT_EQ(engine.model().sheet_level(), 0.25f);
  EXPECT_FALSE(engine.set_sheet_level(std::nanf("")).ok());
}

}  // namespace
}  // namespace gwnrt
