// gwnrt-consistency as a subprocess. Without a usable GPU (CI) it must exit 2
// with its reason; with --against cpu it runs its whole comparison, the CPU against itself, and
// every quantity must be there, identical, in the table and the JSON.
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_util.h"
#include "test_util.h"

namespace gwnrt {
namespace {

class ConsistencyCli : public ::testing::Test {
 protected:
  void SetUp() override {
    binary_ = test::program_binary("gwnrt-consistency");
    if (binary_.empty()) GTEST_SKIP() << "gwnrt-consistency not built next to the tests";
  }
  std::string binary_;
};

TEST_F(ConsistencyCli, ExitsTwoWithItsReasonWithoutAUsableGpu) {
  const test::RunResult r = test::run_program(binary_, "--count 1000 --resolution 16");
  ASSERT_TRUE(r.exited);
  if (r.exit_code != 2) GTEST_SKIP() << "a GPU is usable here: the comparison ran (exit " << r.exit_code << ")";
  EXPECT_NE(r.err.find("gwnrt-consistency: no usable GPU, nothing to compare: "), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

TEST_F(ConsistencyCli, AgainstItselfEveryQuantityAgrees) {
  const std::string json = test::temp_path("consistency.json");
  const test::RunResult r = test::run_program(
      binary_, "--against cpu --count 3000 --resolution 24 --image-width 64 --image-height 48 --threads 2 --mesh " +
                   test::quote(test::data_path("bunny_holes.obj")) + " --json " + test::quote(json));
  ASSERT_TRUE(r.exited);
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  EXPECT_NE(r.out.find("\nconsistent"), std::string::npos) << r.out;
  std::ifstream in(json);
  const nlohmann::json doc = nlohmann::json::parse(in);
  EXPECT_EQ(doc.at("against"), "cpu");
  std::set<std::string> quantities;
  for (const auto& row : doc.at("rows")) {
    quantities.insert(row.at("quantity").get<std::string>());
    EXPECT_TRUE(row.at("passes").get<bool>()) << row.dump();
    EXPECT_EQ(row.at("max_diff").get<double>(), 0.0) << row.dump();  // the same code on the same machine
    EXPECT_GT(row.at("items").get<size_t>(), 0u) << row.dump();
  }
  for (const char* q : {"w, taylor",
                        "w, crossing",
                        "w, brute",
                        "grad w, crossing",
                        "hessian w, taylor",
                        "unsigned distance",
                        "boundary distance",
                        "sdf",
                        "sdf1",
                        "sdf2",
                        "sheet distance",
                        "harnack bound",
                        "projection point",
                        "trace hit",
                        "trace t",
                        "trace normal",
                        "trace kind",
                        "mesh vertex count",
                        "mesh triangles",
                        "mesh vertex offset"})
    EXPECT_EQ(quantities.count(q), 1u) << q;
}

// A georeferenced mesh (a tetrahedron at UTM coordinates, which the build refuses where it lies)
// is compared recentred, as the other programs take it, on the given points (from standard
// input, which is read once and parsed again with the mesh's origin) and rays.
TEST_F(ConsistencyCli, FarOffMeshIsComparedRecentred) {
  const std::string mesh = test::temp_path("utm_consistency.obj"), points = test::temp_path("utm_points.txt"),
                    rays = test::temp_path("utm_rays.txt"), json = test::temp_path("utm_consistency.json");
  test::write_far_tetrahedron(mesh);
  std::ofstream(points) << "512345.878 4123456.989 123.45\n512345.928 4123457.039 123.5\n";
  std::ofstream(rays) << "512345.878 4123456.989 130 0 0 -1\n";
  const test::RunResult r = test::run_program(
      binary_,
      "--against cpu --resolution 8 --image-width 8 --image-height 6 --threads 2 --mesh " + test::quote(mesh) +
          " --points - --rays " + test::quote(rays) + " --json " + test::quote(json),
      points);
  ASSERT_TRUE(r.exited);
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  EXPECT_NE(r.err.find("far from the origin for its size: computed relative to ("), std::string::npos) << r.err;
  std::ifstream in(json);
  const nlohmann::json doc = nlohmann::json::parse(in);
  size_t w_items = 0, trace_items = 0;
  for (const auto& row : doc.at("rows")) {
    if (row.at("quantity") == "w, brute") w_items = row.at("items").get<size_t>();
    if (row.at("quantity") == "trace hit") trace_items = row.at("items").get<size_t>();
  }
  EXPECT_EQ(w_items, 2u);  // the given points, not a generated set
  EXPECT_EQ(trace_items, 1u);
  for (const std::string& f : {mesh, points, rays, json}) std::remove(f.c_str());
}

TEST_F(ConsistencyCli, BadInputIsNamed) {
  const test::RunResult mesh = test::run_program(binary_, "--against cpu --mesh /no/such/mesh.obj");
  ASSERT_TRUE(mesh.exited);
  EXPECT_EQ(mesh.exit_code, 3);  // an error: 1 says a quantity was beyond its tolerance
  EXPECT_NE(mesh.err.find("/no/such/mesh.obj"), std::string::npos) << mesh.err;
  const std::string points = test::temp_path("consistency_points.txt");
  {
    std::ofstream f(points);
    f << "0 0 0\n1 2\n";
  }
  const test::RunResult bad = test::run_program(binary_, "--against cpu --points " + test::quote(points));
  ASSERT_TRUE(bad.exited);
  EXPECT_EQ(bad.exit_code, 3);
  EXPECT_NE(bad.err.find(":2:"), std::string::npos) << bad.err;
  const test::RunResult option = test::run_program(binary_, "--against tpu");
  ASSERT_TRUE(option.exited);
  EXPECT_EQ(option.exit_code, 3);
}

}  // namespace
}  // namespace gwnrt
