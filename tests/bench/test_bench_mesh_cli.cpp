// gwnrt-bench-mesh as a subprocess: the time per output triangle over the first mesh's, which
// its --real rows are read by, is the ratio of the rows' own figures; it reads STL; and with
// --rounds each row's seconds are the median of its rounds.
#include <algorithm>
#include <fstream>
#include <string>
#include <vector>

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

TEST(BenchMeshCli, RoundsReportTheMedianOfEachMethodsTimes) {
  const std::string binary = test::program_binary("gwnrt-bench-mesh");
  if (binary.empty()) GTEST_SKIP() << "gwnrt-bench-mesh not built next to the tests";
  const std::string json = test::temp_path("bench_mesh_rounds.json");
  const test::RunResult r = test::run_program(binary, test::quote(test::data_path("bunny.obj")) +
                                                          " --resolutions 16 --samples 64 --no-self-intersections "
                                                          "--rounds 4 --json " +
                                                          test::quote(json));
  ASSERT_TRUE(r.exited && r.exit_code == 0) << r.err << r.out;
  EXPECT_NE(r.out.find("medians of 4 interleaved rounds"), std::string::npos) << r.out;
  std::ifstream in(json);
  const nlohmann::json doc = nlohmann::json::parse(in);
  EXPECT_EQ(doc["rounds"], 4);
  int checked = 0;
  for (const nlohmann::json& row : doc["rows"]) {
    if (row["status"] != "ok") continue;
    std::vector<double> t = row["round_seconds"].get<std::vector<double>>();
    ASSERT_EQ(t.size(), 4u) << row.dump();
    std::sort(t.begin(), t.end());
    EXPECT_DOUBLE_EQ(row["seconds"].get<double>(), 0.5 * (t[1] + t[2])) << row.dump();
    EXPECT_GT(t[0], 0.0);
    ++checked;
  }
  EXPECT_GE(checked, 2);  // DC and MC (and OpenVDB where it is built)

  const test::RunResult zero = test::run_program(binary, test::quote(test::data_path("bunny.obj")) + " --rounds 0");
  EXPECT_TRUE(zero.exited && zero.exit_code != 0);
  EXPECT_NE(zero.err.find("--rounds"), std::string::npos) << zero.err;
}

}  // namespace
}  // namespace gwnrt
