// gwnrt-bench-mesh as a subprocess: the time per output triangle over the first mesh's, which
// its --real rows are read by, is the ratio of the rows' own figures; and it reads STL.
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_util.h"
#include "test_util.h"

namespace gwnrt {
namespace {

TEST(BenchMeshCli, PerTriangleCostIsOverTheFirstMeshs) {
  const std::string binary = test::program_binary("gwnrt-bench-mesh");
  if (binary.empty()) GTEST_SKIP() << "gwnrt-bench-mesh not built next to the tests";
  const std::string json = test::temp_path("bench_mesh.json");
  const test::RunResult r = test::run_program(
      binary, test::quote(test::data_path("bunny.obj")) + " " +
                  test::quote(test::data_path("realworld/motoman_motomini_visual_link_1_s.stl")) +
                  " --resolutions 16,24 --samples 64 --no-self-intersections --json " + test::quote(json));
  ASSERT_TRUE(r.exited && r.exit_code == 0) << r.err << r.out;
  std::ifstream in(json);
  const nlohmann::json doc = nlohmann::json::parse(in);
  const auto per_triangle = [](const nlohmann::json& row) {
    return row["seconds"].get<double>() / row["triangles"].get<double>();
  };
  int checked = 0;
  for (const nlohmann::json& row : doc["rows"]) {
    if (row["status"] != "ok" || row["triangles"].get<double>() == 0) continue;
    const nlohmann::json* first = nullptr;
    for (const nlohmann::json& f : doc["rows"])
      if (f["mesh"] == doc["rows"][0]["mesh"] && f["method"] == "gwnrt DC" && f["resolution"] == row["resolution"])
        first = &f;
    ASSERT_NE(first, nullptr);
    EXPECT_NEAR(row["per_triangle_over_first_mesh"].get<double>(), per_triangle(row) / per_triangle(*first),
                1e-9 * per_triangle(row) / per_triangle(*first))
        << row.dump();
    ++checked;
  }
  EXPECT_GE(checked, 8);  // DC and MC at two resolutions for both meshes
}

}  // namespace
}  // namespace gwnrt
