// The programs never overwrite an input: an output that names one (the same path, a hard or a
// symbolic link) is refused before any work with exit status 1, naming both, and the input is
// left byte for byte; two outputs on one file are refused too; a run that writes replaces an
// existing output and leaves nothing beside it.
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <gtest/gtest.h>

#include "cli_util.h"
#include "mesh_files.h"
#include "test_util.h"

namespace gwnrt {
namespace {

namespace fs = std::filesystem;

class OutputsCli : public test::TempDirTest {
 protected:
  static std::string read(const std::string& p) {
    std::ifstream f(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  // Runs `program` with `args`; expects the refusal naming `output` and `input`, and `input`
  // unchanged.
  void expect_refused(const char* program, const std::string& args, const std::string& output,
                      const std::string& input) {
    const std::string binary = test::program_binary(program);
    if (binary.empty()) GTEST_SKIP() << program << " not built";
    const std::string before = read(input);
    const test::RunResult r = test::run_program(binary, args);
    ASSERT_TRUE(r.exited) << program << " " << args;
    EXPECT_EQ(r.exit_code, 1) << program << " " << args << ": " << r.err;
    EXPECT_NE(r.err.find(output + ": the output is the input " + input), std::string::npos) << r.err;
    EXPECT_EQ(read(input), before) << program << " " << args;
  }
};

TEST_F(OutputsCli, MeshRefusesToOverwriteItsInput) {
  const std::string mesh = path("in.obj");
  fs::copy_file(test::data_path("bunny.obj"), mesh);
  fs::create_hard_link(mesh, path("hard.obj"));
  fs::create_symlink(mesh, path("soft.obj"));
  for (const std::string& output : {mesh, path("hard.obj"), path("soft.obj")})
    expect_refused("gwnrt-mesh", test::quote(mesh) + " --resolution 16 -o " + test::quote(output), output, mesh);
  expect_refused("gwnrt-mesh",
                 test::quote(mesh) + " --resolution 16 -o " + test::quote(path("out.ply")) + " --report-json " +
                     test::quote(path("hard.obj")),
                 path("hard.obj"), mesh);
  // -o and --report-json on one file, before either exists.
  const std::string binary = test::program_binary("gwnrt-mesh");
  const test::RunResult both =
      test::run_program(binary, test::quote(mesh) + " --resolution 16 -o " + test::quote(path("same.ply")) +
                                    " --report-json " + test::quote(path("same.ply")));
  EXPECT_EQ(both.exit_code, 1) << both.err;
  EXPECT_NE(both.err.find("is also the --output output"), std::string::npos) << both.err;
  EXPECT_FALSE(fs::exists(path("same.ply")));
  // A run that writes replaces what was there, through a link, and leaves nothing beside it.
  const std::string out = path("out.ply");
  std::ofstream(out) << "old";
  fs::create_symlink(out, path("out_link.ply"));
  const test::RunResult ok =
      test::run_program(binary, test::quote(mesh) + " --resolution 16 -o " + test::quote(path("out_link.ply")) +
                                    " --report-json " + test::quote(path("report.json")));
  ASSERT_EQ(ok.exit_code, 0) << ok.err;
  EXPECT_TRUE(fs::is_symlink(path("out_link.ply")));
  EXPECT_EQ(read(out).rfind("ply\n", 0), 0u);
  EXPECT_EQ(read(path("report.json")).rfind("{", 0), 0u);
  size_t entries = 0;
  for (const auto& e : fs::directory_iterator(dir_)) entries += e.path().filename().string()[0] == '.';
  EXPECT_EQ(entries, 0u) << "a temporary file was left";
}

TEST_F(OutputsCli, QueryAndTraceRefuseToOverwriteTheirInputs) {
  const std::string mesh = path("in.obj"), points = path("points.txt"), rays = path("rays.txt");
  fs::copy_file(test::data_path("bunny.obj"), mesh);
  std::ofstream(points) << "0 0 0\n0.1 0.1 0.1\n";
  std::ofstream(rays) << "0 0 5 0 0 -1\n";
  fs::create_hard_link(points, path("points_link.txt"));
  expect_refused("gwnrt-query", test::quote(mesh) + " --points " + test::quote(points) + " -o " + test::quote(points),
                 points, points);
  expect_refused("gwnrt-query",
                 test::quote(mesh) + " --points " + test::quote(points) + " -o " + test::quote(path("points_link.txt")),
                 path("points_link.txt"), points);
  expect_refused("gwnrt-query", test::quote(mesh) + " --points " + test::quote(points) + " -o " + test::quote(mesh),
                 mesh, mesh);
  expect_refused("gwnrt-trace", test::quote(mesh) + " --rays " + test::quote(rays) + " -o " + test::quote(rays), rays,
                 rays);
  expect_refused("gwnrt-trace", test::quote(mesh) + " --rays " + test::quote(rays) + " -o " + test::quote(mesh), mesh,
                 mesh);
  // The same runs onto a new file write it.
  const std::string binary = test::program_binary("gwnrt-query");
  if (binary.empty()) GTEST_SKIP() << "gwnrt-query not built";
  const test::RunResult r = test::run_program(
      binary, test::quote(mesh) + " --points " + test::quote(points) + " -o " + test::quote(path("w.csv")));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(read(path("w.csv")).rfind("x,y,z,w\n", 0), 0u);
}

}  // namespace
}  // namespace gwnrt
