// gwnrt-query run as a subprocess: CSV layout, agreement with the library it wraps, and that bad
// input ends in a message and a non-zero exit rather than a crash or silently wrong rows.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli_util.h"
#include "gwnrt/io/mesh_io.h"
#include "gwnrt/query/batch.h"
#include "test_util.h"

namespace gwnrt {
namespace {

namespace fs = std::filesystem;
using test::quote;
using test::read_file;
using test::RunResult;
using test::temp_path;

std::string query_binary() { return test::program_binary("gwnrt-query"); }

std::string mesh_path() { return test::data_path("bunny_holes.obj"); }
std::string probe_points_path() { return test::data_path("bunny_probe_points.txt"); }

RunResult run_query(const std::string& binary, const std::string& args, const std::string& stdin_path = "") {
  return test::run_program(binary, args, stdin_path);
}

struct Csv {
  std::vector<std::string> header;
  std::vector<std::vector<float>> rows;
};

Csv parse_csv(const std::string& text) {
  Csv csv;
  std::istringstream in(text);
  std::string line;
  bool first = true;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::string cell;
    std::istringstream ls(line);
    while (std::getline(ls, cell, ',')) cells.push_back(cell);
    if (first) {
      csv.header = cells;
      first = false;
      continue;
    }
    std::vector<float> row;
    for (const std::string& c : cells) {
      char* end = nullptr;
      row.push_back(std::strtof(c.c_str(), &end));
      EXPECT_EQ(*end, '\0') << "bad CSV cell '" << c << "'";
    }
    csv.rows.push_back(row);
  }
  return csv;
}

// Same reading rules as the program (comments, blank lines), kept independent of its parser.
std::vector<vec3> load_points(const std::string& path) {
  std::ifstream in(path);
  std::vector<vec3> points;
  std::string line;
  while (std::getline(in, line)) {
    line = line.substr(0, line.find('#'));
    std::istringstream ls(line);
    vec3 p;
    if (ls >> p.x >> p.y >> p.z) points.push_back(p);
  }
  return points;
}

class QueryCliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    binary_ = query_binary();
    if (binary_.empty()) GTEST_SKIP() << "gwnrt-query not built next to the tests (expected <build>/bin/gwnrt-query)";
  }
  std::string binary_;
};

TEST_F(QueryCliTest, AllFieldsMatchLibraryInInputOrder) {
  const std::vector<vec3> points = load_points(probe_points_path());
  ASSERT_GE(points.size(), 150u);
  const RunResult r = run_query(
      binary_, quote(mesh_path()) + " --points " + quote(probe_points_path()) + " --fields w,grad,hess,udist,bdist");
  ASSERT_TRUE(r.exited);
  ASSERT_EQ(r.exit_code, 0) << r.err;

  const Csv csv = parse_csv(r.out);
  const std::vector<std::string> expected_header = {"x",   "y",   "z",   "w",   "gx",  "gy",    "gz",   "hxx",
                                                    "hxy", "hxz", "hyy", "hyz", "hzz", "udist", "bdist"};
  EXPECT_EQ(csv.header, expected_header);
  ASSERT_EQ(csv.rows.size(), points.size());

  GwnModel model = test::build_model(test::load_test_mesh("bunny_holes.obj"));
  QueryRequest request;
  request.fields = kFieldW | kFieldGradient | kFieldHessian | kFieldUnsignedDistance | kFieldBoundaryDistance;
  std::vector<PointResult> results(points.size());
  ASSERT_TRUE(evaluate_points(model, points, request, results).ok());

  for (size_t i = 0; i < points.size(); ++i) {
    const std::vector<float>& row = csv.rows[i];
    ASSERT_EQ(row.size(), expected_header.size()) << "row " << i;
    const PointResult& e = results[i];
    EXPECT_EQ(row[0], points[i].x) << "row " << i;
    EXPECT_EQ(row[1], points[i].y) << "row " << i;
    EXPECT_EQ(row[2], points[i].z) << "row " << i;
    // Shortest round-trip printing means the parsed values are bit-identical to the library's.
    EXPECT_EQ(row[3], e.w) << "row " << i;
    EXPECT_EQ(row[4], e.gradient.x) << "row " << i;
    EXPECT_EQ(row[5], e.gradient.y) << "row " << i;
    EXPECT_EQ(row[6], e.gradient.z) << "row " << i;
    EXPECT_EQ(row[7], e.hessian.xx) << "row " << i;
    EXPECT_EQ(row[8], e.hessian.xy) << "row " << i;
    EXPECT_EQ(row[9], e.hessian.xz) << "row " << i;
    EXPECT_EQ(row[10], e.hessian.yy) << "row " << i;
    EXPECT_EQ(row[11], e.hessian.yz) << "row " << i;
    EXPECT_EQ(row[12], e.hessian.zz) << "row " << i;
    EXPECT_EQ(row[13], e.unsigned_distance) << "row " << i;
    EXPECT_EQ(row[14], e.boundary_distance) << "row " << i;
  }
}

TEST_F(QueryCliTest, DefaultIsWOnlyAndOptionsChangeNothingButColumns) {
  const std::string base = quote(mesh_path()) + " --points " + quote(probe_points_path());
  const RunResult w = run_query(binary_, base);
  ASSERT_EQ(w.exit_code, 0) << w.err;
  EXPECT_EQ(w.out.substr(0, w.out.find('\n')), "x,y,z,w");

  const RunResult dist = run_query(binary_, base + " --fields bdist,udist --threads 1");
  ASSERT_EQ(dist.exit_code, 0) << dist.err;
  EXPECT_EQ(dist.out.substr(0, dist.out.find('\n')), "x,y,z,udist,bdist");

  // A single thread and a file output give the very same bytes.
  const std::string out_file = temp_path("o.csv");
  const RunResult to_file = run_query(binary_, base + " --threads 1 -o " + quote(out_file));
  ASSERT_EQ(to_file.exit_code, 0) << to_file.err;
  EXPECT_TRUE(to_file.out.empty());
  EXPECT_EQ(read_file(out_file), w.out);
  std::remove(out_file.c_str());
}

// The sheets are classified only for the fields that read them (sdf,
// sheet_dist): the distance and w alone do not pay for them, and answer the same.
TEST_F(QueryCliTest, SheetsAreClassifiedOnlyForTheFieldsThatReadThem) {
  const std::string base = quote(mesh_path()) + " --points " + quote(probe_points_path()) + " -v --threads 1";
  const RunResult alone = run_query(binary_, base + " --fields udist,w");
  ASSERT_EQ(alone.exit_code, 0) << alone.err;
  EXPECT_NE(alone.err.find("sheets not classified"), std::string::npos) << alone.err;
  const RunResult with_sdf = run_query(binary_, base + " --fields udist,w,sheet_dist");
  ASSERT_EQ(with_sdf.exit_code, 0) << with_sdf.err;
  EXPECT_EQ(with_sdf.err.find("sheets not classified"), std::string::npos) << with_sdf.err;
  const Csv a = parse_csv(alone.out), b = parse_csv(with_sdf.out);
  ASSERT_EQ(a.rows.size(), b.rows.size());
  ASSERT_FALSE(a.rows.empty());
  for (size_t i = 0; i < a.rows.size(); ++i)
    for (size_t k = 0; k < a.header.size(); ++k) EXPECT_EQ(a.rows[i].at(k), b.rows[i].at(k)) << "row " << i;
  // The distance to M alone reads M's tree alone: neither the boundary nor its cone is built,
  // and the distances are those of the full build.
  const RunResult udist = run_query(binary_, base + " --fields udist");
  ASSERT_EQ(udist.exit_code, 0) << udist.err;
  EXPECT_NE(udist.err.find("boundary and cone not built"), std::string::npos) << udist.err;
  EXPECT_EQ(alone.err.find("boundary and cone not built"), std::string::npos) << alone.err;
  const Csv c = parse_csv(udist.out);
  ASSERT_EQ(c.rows.size(), b.rows.size());
  const size_t column = size_t(std::find(b.header.begin(), b.header.end(), "udist") - b.header.begin());
  ASSERT_LT(column, b.header.size());
  for (size_t i = 0; i < c.rows.size(); ++i) EXPECT_EQ(c.rows[i].back(), b.rows[i].at(column)) << "row " << i;
}

TEST_F(QueryCliTest, ClosedMeshPrintsInfiniteBoundaryDistance) {
  const std::string closed_mesh = test::data_path("bunny.obj");
  const RunResult r =
      run_query(binary_, quote(closed_mesh) + " --points " + quote(probe_points_path()) + " --fields bdist");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Csv csv = parse_csv(r.out);
  ASSERT_FALSE(csv.rows.empty());
  for (const auto& row : csv.rows) EXPECT_TRUE(std::isinf(row.at(3)));
  EXPECT_NE(r.out.find(",inf\n"), std::string::npos);
}

TEST_F(QueryCliTest, ExactAgreesWithTree) {
  const std::string base = quote(mesh_path()) + " --points " + quote(probe_points_path());
  const RunResult tree = run_query(binary_, base);
  const RunResult exact = run_query(binary_, base + " --exact");
  ASSERT_EQ(tree.exit_code, 0) << tree.err;
  ASSERT_EQ(exact.exit_code, 0) << exact.err;
  const Csv a = parse_csv(tree.out), b = parse_csv(exact.out);
  ASSERT_EQ(a.rows.size(), b.rows.size());
  ASSERT_FALSE(a.rows.empty());
  for (size_t i = 0; i < a.rows.size(); ++i) EXPECT_NEAR(a.rows[i].at(3), b.rows[i].at(3), 2e-3) << "row " << i;
}

TEST_F(QueryCliTest, MethodsAgreeAndCrossingIsExact) {
  // --method crossing against --method brute (the double reference): within the crossing
  // method's 1e-5 (the probe points are not within 1e-5 of the diagonal from the mesh); taylor
  // within the tree's 2e-3; auto (the default) is crossing on bunny_holes, and says so.
  const std::string base = quote(mesh_path()) + " --points " + quote(probe_points_path()) + " --verbose";
  const RunResult brute = run_query(binary_, base + " --method brute");
  const RunResult crossing = run_query(binary_, base + " --method crossing");
  const RunResult taylor = run_query(binary_, base + " --method taylor");
  const RunResult automatic = run_query(binary_, base);
  for (const RunResult* r : {&brute, &crossing, &taylor, &automatic}) ASSERT_EQ(r->exit_code, 0) << r->err;
  EXPECT_NE(automatic.err.find("w by crossing (--method auto)"), std::string::npos) << automatic.err;
  EXPECT_EQ(automatic.out, crossing.out);
  const Csv b = parse_csv(brute.out), c = parse_csv(crossing.out), t = parse_csv(taylor.out);
  ASSERT_EQ(b.rows.size(), c.rows.size());
  ASSERT_EQ(b.rows.size(), t.rows.size());
  ASSERT_FALSE(b.rows.empty());
  for (size_t i = 0; i < b.rows.size(); ++i) {
    EXPECT_NEAR(c.rows[i].at(3), b.rows[i].at(3), 1e-5) << "row " << i;
    EXPECT_NEAR(t.rows[i].at(3), b.rows[i].at(3), 2e-3) << "row " << i;
  }
  // --exact is --method brute, and the two may not be combined.
  const RunResult exact = run_query(binary_, base + " --exact");
  ASSERT_EQ(exact.exit_code, 0) << exact.err;
  EXPECT_EQ(exact.out, brute.out);
  for (const std::string& bad : {std::string(" --method exactly"), std::string(" --exact --method taylor")}) {
    const RunResult r = run_query(binary_, base + bad);
    EXPECT_NE(r.exit_code, 0) << bad;
    EXPECT_NE(r.err.find("--method"), std::string::npos) << bad << ": " << r.err;
    EXPECT_TRUE(r.out.empty()) << bad;
  }
}

TEST_F(QueryCliTest, ReadsPointsFromStdin) {
  const RunResult from_file = run_query(binary_, quote(mesh_path()) + " --points " + quote(probe_points_path()));
  const RunResult from_stdin = run_query(binary_, quote(mesh_path()) + " --points -", probe_points_path());
  ASSERT_EQ(from_file.exit_code, 0) << from_file.err;
  ASSERT_EQ(from_stdin.exit_code, 0) << from_stdin.err;
  EXPECT_EQ(from_stdin.out, from_file.out);
}

TEST_F(QueryCliTest, BadArgumentsFailWithMessage) {
  const std::string base = quote(mesh_path()) + " --points " + quote(probe_points_path());
  struct Case {
    std::string args, expect_in_stderr;
  };
  const std::vector<Case> cases = {
      {base + " --order 3", "--order"},
      {base + " --beta -1", "beta"},
      {base + " --beta 0", "beta"},
      {base + " --beta 0.5", "--beta: must be a finite number >= 1"},  // inside a cluster's own ball
      {base + " --fields w,curl", "curl"},
      {base + " --device tpu", "--device"},
      {base + " --threads 0", "--threads"},
      {quote(mesh_path()), "--points"},
      {quote(test::data_path("no_such_mesh.obj")) + " --points " + quote(probe_points_path()), "no_such_mesh.obj"},
      {quote(mesh_path()) + " --points " + quote(test::data_path("no_such_points.txt")), "no_such_points.txt"},
  };
  for (const Case& c : cases) {
    const RunResult r = run_query(binary_, c.args);
    EXPECT_TRUE(r.exited) << c.args;
    EXPECT_NE(r.exit_code, 0) << c.args;
    EXPECT_NE(r.err.find(c.expect_in_stderr), std::string::npos) << c.args << "\nstderr: " << r.err;
    EXPECT_TRUE(r.out.empty()) << c.args;
  }
}

TEST_F(QueryCliTest, MalformedPointsNameTheLine) {
  struct Case {
    std::string text, where;
  };
  const std::vector<Case> cases = {
      {"# header\n0 0 0\n1 2\n", ":3:"}, {"0 0 0\n\n1 2 3 4\n", ":3:"}, {"1 2 x\n", ":1:"},
      {"0 0 0\n1 nan 0\n", ":2:"},       {"0 0 0\n1 1e99 0\n", ":2:"},
  };
  for (const Case& c : cases) {
    const std::string points = temp_path("bad_points.txt");
    std::ofstream(points) << c.text;
    const RunResult r = run_query(binary_, quote(mesh_path()) + " --points " + quote(points));
    EXPECT_TRUE(r.exited);
    EXPECT_EQ(r.exit_code, 1) << c.text;
    EXPECT_NE(r.err.find(points + c.where), std::string::npos) << "stderr: " << r.err;
    EXPECT_NE(r.err.find("gwnrt-query: "), std::string::npos) << r.err;
    EXPECT_TRUE(r.out.empty());
    std::remove(points.c_str());
  }
}

// A small open mesh (the upper half of a unit sphere, 8 rings of 32 segments, outward) written
// as OBJ: S is the shell (sheets) plus the flat disk that closes it (a smooth piece), so the
// points below reach every kind of signed-distance answer.
std::string write_hemisphere_obj() {
  const std::string path = temp_path("hemisphere.obj");
  std::ofstream out(path);
  constexpr int kRings = 8, kSegments = 32;
  out << "v 0 0 1\n";
  for (int i = 1; i <= kRings; ++i) {
    const double theta = 0.5 * kPi * i / kRings;
    const double r = i == kRings ? 1.0 : std::sin(theta), z = i == kRings ? 0.0 : std::cos(theta);
    for (int j = 0; j < kSegments; ++j) {
      const double phi = 2.0 * kPi * j / kSegments;
      out << "v " << float(r * std::cos(phi)) << " " << float(r * std::sin(phi)) << " " << float(z) << "\n";
    }
  }
  auto ring = [&](int i, int j) { return 2 + (i - 1) * kSegments + (j % kSegments); };  // OBJ: 1-based
  for (int j = 0; j < kSegments; ++j) out << "f 1 " << ring(1, j) << " " << ring(1, j + 1) << "\n";
  for (int i = 1; i < kRings; ++i)
    for (int j = 0; j < kSegments; ++j) {
      out << "f " << ring(i, j) << " " << ring(i + 1, j) << " " << ring(i + 1, j + 1) << "\n";
      out << "f " << ring(i, j) << " " << ring(i + 1, j + 1) << " " << ring(i, j + 1) << "\n";
    }
  return path;
}

float cell_float(const std::string& c) {
  char* end = nullptr;
  const float v = std::strtof(c.c_str(), &end);
  EXPECT_EQ(*end, '\0') << "bad CSV cell '" << c << "'";
  return v;
}

TEST_F(QueryCliTest, SignedDistanceFieldsMatchLibraryAtAnyLevel) {
  const std::string mesh = write_hemisphere_obj();
  const std::string points_file = temp_path("sdf_points.txt");
  // Above the disk's centre (smooth, inside), above the pole (sheet, outside), below the disk
  // (smooth, outside), inside the dome near the shell (sheet), beside the rim.
  const std::vector<vec3> points = {
      {0.1f, 0.2f, 0.05f}, {0.0f, 0.0f, 1.2f}, {0.3f, -0.2f, -0.1f}, {0.5f, 0.0f, 0.8f}, {1.1f, 0.0f, 0.02f}};
  {
    std::ofstream out(points_file);
    for (const vec3& p : points) out << p.x << " " << p.y << " " << p.z << "\n";
  }
  Mesh loaded;
  ASSERT_TRUE(load_mesh(mesh, loaded).ok());
  GwnModel model = test::build_model(loaded);

  const std::vector<std::string> expected_header = {
      "x",          "y",      "z",      "sdf",    "sdf_piece",  "sdf1",           "sdf2",
      "sheet_dist", "proj_x", "proj_y", "proj_z", "proj_iters", "proj_converged", "hbound"};
  for (const float level : {0.5f, 0.3f}) {
    std::string args =
        quote(mesh) + " --points " + quote(points_file) + " --fields sdf,sdf1,sdf2,sheet_dist,proj,hbound";
    if (level != 0.5f) args += " --level 0.3";
    const RunResult r = run_query(binary_, args);
    ASSERT_TRUE(r.exited);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    // Cells as text: sdf_piece is a word.
    const std::vector<std::vector<std::string>> rows = test::csv_rows(r.out);
    ASSERT_EQ(rows.size(), points.size() + 1);
    EXPECT_EQ(rows[0], expected_header);

    // The library, with the request the program makes: bit-identical (shortest round-trip
    // printing), the piece by name.
    ASSERT_TRUE(model.set_sheet_level(level).ok());
    QueryRequest request;
    request.fields =
        kFieldSignedDistance | kFieldPseudoDistance | kFieldSheetDistance | kFieldProjection | kFieldHarnackBound;
    request.level = level;
    std::vector<PointResult> e(points.size());
    ASSERT_TRUE(evaluate_points(model, points, request, e).ok());
    const char* piece_names[] = {"sheet", "smooth", "bound"};
    std::vector<std::string> pieces;
    for (size_t i = 0; i < points.size(); ++i) {
      const std::vector<std::string>& row = rows[i + 1];
      ASSERT_EQ(row.size(), expected_header.size()) << "row " << i;
      EXPECT_EQ(cell_float(row[0]), points[i].x);
      EXPECT_EQ(cell_float(row[3]), e[i].sdf.distance) << "row " << i << " level " << level;
      EXPECT_EQ(row[4], piece_names[unsigned(e[i].sdf.piece)]) << "row " << i;
      EXPECT_EQ(cell_float(row[5]), e[i].sdf.first_order) << "row " << i;
      EXPECT_EQ(cell_float(row[6]), e[i].sdf.second_order) << "row " << i;
      EXPECT_EQ(cell_float(row[7]), e[i].sdf.sheet_distance) << "row " << i;
      // Newton's iterates carry ∇w, whose sums g++ contracts into fused multiply-adds per inlined
      // copy: the program's and the test's copies may differ in the last bits (docs/design.md §7).
      for (int a = 0; a < 3; ++a)
        EXPECT_NEAR(cell_float(row[8 + a]), e[i].projection.point[a],
                    1e-6f * glm::length(model.bounds().hi - model.bounds().lo))
            << "row " << i;
      EXPECT_EQ(cell_float(row[11]), float(e[i].projection.iterations)) << "row " << i;
      EXPECT_EQ(row[12], e[i].projection.converged ? "1" : "0") << "row " << i;
      EXPECT_EQ(cell_float(row[13]), e[i].harnack_bound) << "row " << i;
      pieces.push_back(row[4]);
    }
    if (level == 0.5f) {
      // Independent of the library: above the disk's centre, sdf ≈ -z (the disk is S there); above
      // the pole, 0.2 outside the shell (the pole is a vertex at radius 1).
      EXPECT_NEAR(cell_float(rows[1][3]), -0.05f, 2e-3f);
      EXPECT_EQ(rows[1][4], "smooth");
      EXPECT_NEAR(cell_float(rows[2][3]), 0.2f, 1e-6f);
      EXPECT_EQ(rows[2][4], "sheet");
      EXPECT_EQ(rows[1][12], "1");  // Newton reaches the disk from just above it
      EXPECT_EQ(rows[2][12], "0");  // and cannot from above the shell
    }
  }
  std::remove(mesh.c_str());
  std::remove(points_file.c_str());
}

TEST_F(QueryCliTest, BadLevelIsRefused) {
  const std::string base = quote(mesh_path()) + " --points " + quote(probe_points_path()) + " --fields sdf";
  for (const std::string bad : {"nan", "inf", "-inf", "abc", "1e30", ""}) {
    const RunResult r = run_query(binary_, base + " --level " + quote(bad));
    EXPECT_TRUE(r.exited) << bad;
    EXPECT_NE(r.exit_code, 0) << "--level '" << bad << "'";
    EXPECT_NE(r.err.find("level"), std::string::npos) << "--level '" << bad << "': " << r.err;
    EXPECT_TRUE(r.out.empty()) << bad;
  }
}

TEST_F(QueryCliTest, CudaDeviceNeverCrashes) {
  const RunResult r =
      run_query(binary_, quote(mesh_path()) + " --points " + quote(probe_points_path()) + " --device cuda");
  // Built with CUDA on a machine with a GPU this succeeds; anywhere else it must explain why.
  ASSERT_TRUE(r.exited) << "gwnrt-query --device cuda was killed by a signal";
  if (r.exit_code != 0) {
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("cuda"), std::string::npos) << r.err;
  } else {
    EXPECT_EQ(parse_csv(r.out).rows.size(), load_points(probe_points_path()).size());
  }
}

// --device auto takes the GPU when --device cuda would work, else the CPU, saying which; on the
// CPU its output is the default's.
TEST_F(QueryCliTest, DeviceAutoSaysWhichItTook) {
  const std::string base = quote(mesh_path()) + " --points " + quote(probe_points_path()) + " --fields w,udist";
  const RunResult cpu = run_query(binary_, base);
  const RunResult cuda = run_query(binary_, base + " --device cuda");
  const RunResult automatic = run_query(binary_, base + " --device auto");
  ASSERT_EQ(cpu.exit_code, 0) << cpu.err;
  ASSERT_EQ(automatic.exit_code, 0) << automatic.err;
  const bool took_cpu = automatic.err.find("--device auto: the CPU (") != std::string::npos;
  EXPECT_TRUE(took_cpu || automatic.err.find("--device auto: the GPU") != std::string::npos) << automatic.err;
  EXPECT_EQ(took_cpu, cuda.exit_code != 0) << cuda.err;
  if (took_cpu) {
    EXPECT_EQ(automatic.out, cpu.out);
  }
}

// A points file that never ends a line (/dev/zero, as a file or on standard
// input) stopped the program only when memory ran out; now reading stops, naming the line.
TEST_F(QueryCliTest, PointStreamsThatNeverEndStopAtTheLineLimit) {
  // /dev/zero stops at its first byte, which is no text; a line of digits that never ends, at the
  // line limit.
  const std::string digits = temp_path("endless_digits.txt");
  std::ofstream(digits, std::ios::binary) << std::string((size_t(3) << 19), '1');
  const RunResult file = run_query(binary_, quote(mesh_path()) + " --points /dev/zero");
  const RunResult in = run_query(binary_, quote(mesh_path()) + " --points -", "/dev/zero");
  const RunResult long_line = run_query(binary_, quote(mesh_path()) + " --points -", digits);
  std::remove(digits.c_str());
  for (const RunResult* r : {&file, &in, &long_line}) {
    ASSERT_TRUE(r->exited);
    EXPECT_EQ(r->exit_code, 1);
    EXPECT_TRUE(r->out.empty());
  }
  EXPECT_NE(file.err.find("/dev/zero:1: binary content (byte 0x00): not a text file"), std::string::npos) << file.err;
  EXPECT_NE(in.err.find("<stdin>:1: binary content (byte 0x00)"), std::string::npos) << in.err;
  EXPECT_NE(long_line.err.find("<stdin>:1: line longer than 1.0 MiB"), std::string::npos) << long_line.err;
}

// A bad token is quoted short and printable in the message: it was copied whole, binary bytes and
// all (a megabyte of garbage made a megabyte of message).
TEST_F(QueryCliTest, BadTokensAreQuotedShortAndPrintable) {
  const std::string points = temp_path("garbage_points.txt");
  std::ofstream(points, std::ios::binary) << "0 0 0\n1 \x80\xff" << std::string(5000, 'z') << " 2\n";
  const RunResult r = run_query(binary_, quote(mesh_path()) + " --points " + quote(points));
  std::remove(points.c_str());
  ASSERT_TRUE(r.exited);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find(points + ":2: not a number: '??" + std::string(38, 'z') + "...'"), std::string::npos) << r.err;
  EXPECT_LT(r.err.size(), 300u);
  for (const char c : r.err) EXPECT_TRUE(c == '\n' || (static_cast<unsigned char>(c) >= 0x20 && c != 0x7f));
}

// Coordinates: beyond the query range refused naming the file and line (the library named only
// "point 1", counting from 0); below float's range read as 0 (1e-400 was "out of range" while
// 1e-50 read as 0, and the mesh readers read both as 0).
TEST_F(QueryCliTest, PointCoordinatesBeyondTheRangeAreNamedByLineAndTinyOnesAreZero) {
  const std::string far = temp_path("far_points.txt"), tiny = temp_path("tiny_points.txt");
  std::ofstream(far) << "0 0 0\n1e19 0 0\n";
  std::ofstream(tiny) << "1e-400 -1e-50 0\n";
  const RunResult refused = run_query(binary_, quote(mesh_path()) + " --points " + quote(far));
  const RunResult zero = run_query(binary_, quote(mesh_path()) + " --points " + quote(tiny) + " --fields w");
  std::remove(far.c_str());
  std::remove(tiny.c_str());
  ASSERT_TRUE(refused.exited && zero.exited);
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.err.find(far + ":2: coordinate beyond +-1e+18"), std::string::npos) << refused.err;
  EXPECT_EQ(zero.exit_code, 0) << zero.err;
  EXPECT_NE(zero.out.find("\n0,-0,0,"), std::string::npos) << zero.out;
}

// A level w never reaches has no S (|w| < n/2 for n triangles): the fields that read the level
// are answered (the sdf infinite) with a warning, as gwnrt-trace and gwnrt-mesh give; w alone
// reads no level and is not warned about.
TEST_F(QueryCliTest, UnreachableLevelIsWarnedAboutForTheFieldsThatReadIt) {
  const std::string base = quote(mesh_path()) + " --points " + quote(probe_points_path());
  const RunResult sdf = run_query(binary_, base + " --fields sdf --level 1e5");
  const RunResult w = run_query(binary_, base + " --fields w --level 1e5");
  const RunResult reachable = run_query(binary_, base + " --fields sdf --level 0.5");
  ASSERT_TRUE(sdf.exited && w.exited && reachable.exited);
  EXPECT_EQ(sdf.exit_code, 0);
  EXPECT_NE(sdf.err.find("warning: level 100000 lies outside every value w takes"), std::string::npos) << sdf.err;
  EXPECT_EQ(w.err.find("warning"), std::string::npos) << w.err;
  EXPECT_EQ(reachable.err.find("warning"), std::string::npos) << reachable.err;
}

// The same for a mesh: /dev/zero under a mesh file's name stops at its first byte, no text.
TEST_F(QueryCliTest, MeshStreamThatNeverEndsStopsAtItsFirstByte) {
  const std::string zero = temp_path("zero.obj");
  fs::create_symlink("/dev/zero", zero);
  const RunResult r = run_query(binary_, quote(zero) + " --points " + quote(probe_points_path()));
  fs::remove(zero);
  ASSERT_TRUE(r.exited);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find(zero + ":1: binary content (byte 0x00): not a text file"), std::string::npos) << r.err;
}

// An OBJ statement nobody knows is a warning (said whether or not stderr is a
// terminal: it may be a mistyped vertex), and the query still runs.
TEST_F(QueryCliTest, UnknownObjStatementsAreWarnedAbout) {
  const std::string mesh = temp_path("unknown.obj");
  std::ofstream(mesh) << "v 0 0 0\nv 1 0 0\nvv 0 1 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
  const RunResult r = run_query(binary_, quote(mesh) + " --points " + quote(probe_points_path()));
  std::remove(mesh.c_str());
  ASSERT_TRUE(r.exited);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("gwnrt-query: " + mesh + ": warning: 1 line with an unknown statement"), std::string::npos)
      << r.err;
}

// Georeferenced input (MeshLoadOptions::recentre): bunny_holes.obj and its probe points moved to
// UTM-like coordinates, where float steps by 0.25 to 0.5 (y = 4e6) and GwnModel::build refused
// the mesh. The program computes about the mesh's own centre (the origin) and writes positions
// back in the input's coordinates.
using test::kUtm;

struct FarCopy {
  std::string mesh, points;
  ~FarCopy() {
    std::remove(mesh.c_str());
    std::remove(points.c_str());
  }
};

// The moved mesh and probe points, written with 17 significant digits.
void write_far_copy(FarCopy& copy) {
  copy.mesh = temp_path("utm_bunny.obj");
  copy.points = temp_path("utm_points.txt");
  test::write_translated(mesh_path(), copy.mesh, kUtm, true);
  test::write_translated(probe_points_path(), copy.points, kUtm, false);
}

constexpr const char* kFarFields = "all,sdf,sdf1,sdf2,sheet_dist,proj,hbound";

// The same answers as about the origin, to the float rounding of the inputs: each run rounds the
// mesh's corners and the points, in its own model coordinates (within s = |p| + 16 of its
// origin: the bunny lies within 10 of (0, 0, 0) and within 16 of the recentred origin), to
// delta = 2^-24 s, and the origin is not the translation, so the two models differ by that
// rounding (they are not bit-identical copies). Then, with slack for each run's own rounding:
// - positions (x y z, proj_*) are the untranslated ones + the translation: the points to 2
//   delta (each run's rounding of the same point); the Newton projection to 1e-4 of its walk
//   (its steps (w - w*) grad w / |grad w|^2 divide w's rounding, 2e-7 here, by |grad w|, down
//   to 1e-3 on the far points: 1.3e-4 on a walk of 9.6) + 16 delta;
// - distances (udist, bdist, sdf, sheet_dist, hbound), 1-Lipschitz in the point and in each
//   corner: 16 delta (observed: under 0.14 of it);
// - w: the crossing method's 1e-5 for each run (MethodsAgreeAndCrossingIsExact) + 16 delta
//   |grad w|; the gradient: 1e-5 relative + 16 delta |H|; the Hessian 1e-3 relative (+ 1e-5);
//   sdf1 and sdf2, ratios of w and its derivatives: 1e-4 relative + 16 delta;
// - the sdf's piece, the Newton iterations and whether they converged: equal.
// Observed, the largest ratio of a difference to its tolerance is 0.13 (bdist of a far point).
TEST_F(QueryCliTest, FarOffMeshAnswersAsTheSameMeshAtTheOrigin) {
  FarCopy far;
  write_far_copy(far);
  const RunResult near_run =
      run_query(binary_, quote(mesh_path()) + " --points " + quote(probe_points_path()) + " --fields " + kFarFields);
  const RunResult far_run =
      run_query(binary_, quote(far.mesh) + " --points " + quote(far.points) + " --fields " + kFarFields);
  ASSERT_TRUE(near_run.exited && far_run.exited);
  ASSERT_EQ(near_run.exit_code, 0) << near_run.err;
  ASSERT_EQ(far_run.exit_code, 0) << far_run.err;
  const auto a = test::csv_rows(near_run.out), b = test::csv_rows(far_run.out);
  ASSERT_EQ(a.size(), load_points(probe_points_path()).size() + 1);
  ASSERT_EQ(b.size(), a.size());
  ASSERT_EQ(b[0], a[0]);
  std::map<std::string, size_t> col;
  for (size_t j = 0; j < a[0].size(); ++j) col[a[0][j]] = j;

  for (size_t i = 1; i < a.size(); ++i) {
    ASSERT_EQ(a[i].size(), a[0].size());
    ASSERT_EQ(b[i].size(), a[0].size());
    const auto near = [&](const char* c) { return test::cell_double(a[i][col.at(c)]); };
    const auto far = [&](const char* c) { return test::cell_double(b[i][col.at(c)]); };
    const dvec3 p(near("x"), near("y"), near("z"));
    const double delta = std::ldexp(std::max({std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)}) + 16.0, -24);
    const double grad = glm::length(dvec3(near("gx"), near("gy"), near("gz")));
    double hess = 0;
    for (const char* h : {"hxx", "hxy", "hxz", "hyy", "hyz", "hzz"}) hess = std::max(hess, std::fabs(near(h)));
    const double travel = glm::distance(dvec3(near("proj_x"), near("proj_y"), near("proj_z")), p);
    const auto expect_close = [&](const char* c, double tolerance) {
      if (std::isinf(near(c)) && far(c) == near(c)) return;
      EXPECT_LE(std::fabs(far(c) - near(c)), tolerance)
          << c << ", row " << i << ": " << b[i][col.at(c)] << " vs " << a[i][col.at(c)];
    };
    const auto expect_moved = [&](const char* c, int axis, double tolerance) {
      EXPECT_LE(std::fabs(far(c) - (near(c) + kUtm[axis])), tolerance)
          << c << ", row " << i << ": " << b[i][col.at(c)] << " vs " << a[i][col.at(c)] << " + " << kUtm[axis];
    };
    for (int k = 0; k < 3; ++k) {
      expect_moved(std::array{"x", "y", "z"}[k], k, 2 * delta);
      expect_moved(std::array{"proj_x", "proj_y", "proj_z"}[k], k, 1e-4 * (1 + travel) + 16 * delta);
    }
    for (const char* c : {"udist", "bdist", "sdf", "sheet_dist", "hbound"}) expect_close(c, 16 * delta);
    expect_close("w", 2e-5 + 16 * delta * grad);
    for (const char* c : {"gx", "gy", "gz"}) expect_close(c, 1e-5 * grad + 16 * delta * hess);
    for (const char* c : {"hxx", "hxy", "hxz", "hyy", "hyz", "hzz"}) expect_close(c, 1e-3 * hess + 1e-5);
    for (const char* c : {"sdf1", "sdf2"}) expect_close(c, 1e-4 * std::fabs(near(c)) + 16 * delta);
    for (const char* c : {"sdf_piece", "proj_iters", "proj_converged"})
      EXPECT_EQ(b[i][col.at(c)], a[i][col.at(c)]) << c << ", row " << i;
  }
}

// Exactly the library's answers on the recentred mesh (load_mesh with recentre, the points moved
// by -origin in double and rounded to float): the positions as expect_position_reads_back says,
// the other columns to the bit as ever. A point read from the input is written back as it was given (the probe
// points' 5 decimals + the translation's 3: fewer digits than their floats resolve).
TEST_F(QueryCliTest, FarOffPositionsAreWrittenInTheInputsCoordinates) {
  FarCopy far;
  far.mesh = temp_path("utm_bunny.obj");
  far.points = temp_path("utm_points.txt");
  test::write_translated(mesh_path(), far.mesh, kUtm, true);
  std::vector<dvec3> given;
  {
    std::ofstream out(far.points);
    for (const vec3& q : load_points(probe_points_path())) {
      char line[96];
      std::snprintf(line, sizeof line, "%.5f %.5f %.5f\n", double(q.x) + kUtm[0], double(q.y) + kUtm[1],
                    double(q.z) + kUtm[2]);
      out << line;
      std::istringstream ls(line);
      dvec3 g;
      ls >> g.x >> g.y >> g.z;
      given.push_back(g);
    }
  }
  const RunResult r =
      run_query(binary_, quote(far.mesh) + " --points " + quote(far.points) + " --fields " + kFarFields);
  ASSERT_TRUE(r.exited);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rows = test::csv_rows(r.out);
  ASSERT_EQ(rows.size(), given.size() + 1);

  Mesh mesh;
  MeshLoadReport report;
  MeshLoadOptions options;
  options.recentre = true;
  ASSERT_TRUE(load_mesh(far.mesh, mesh, &report, options).ok());
  const dvec3 origin = report.origin;
  ASSERT_NE(origin, dvec3(0.0));
  {
    // The mesh is one GwnModel::build refuses where it lies.
    Mesh as_is;
    ASSERT_TRUE(load_mesh(far.mesh, as_is).ok());
    GwnModel refused;
    const Status s = GwnModel::build(std::move(as_is), refused);
    EXPECT_NE(s.message().find("translate the mesh near the origin"), std::string::npos) << s.message();
  }
  const GwnModel model = test::build_model(std::move(mesh));
  std::vector<vec3> points;
  for (const dvec3& g : given) points.push_back(vec3(g - origin));
  QueryRequest request;
  request.fields = kFieldW | kFieldGradient | kFieldHessian | kFieldUnsignedDistance | kFieldBoundaryDistance |
                   kFieldSignedDistance | kFieldPseudoDistance | kFieldSheetDistance | kFieldProjection |
                   kFieldHarnackBound;
  std::vector<PointResult> e(points.size());
  ASSERT_TRUE(evaluate_points(model, points, request, e).ok());

  std::map<std::string, size_t> col;
  for (size_t j = 0; j < rows[0].size(); ++j) col[rows[0][j]] = j;
  for (size_t i = 0; i < points.size(); ++i) {
    const std::vector<std::string>& row = rows[i + 1];
    ASSERT_EQ(row.size(), rows[0].size());
    const auto cell = [&](const char* c) { return test::cell_double(row[col.at(c)]); };
    for (int k = 0; k < 3; ++k) {
      const char* xyz = std::array{"x", "y", "z"}[k];
      EXPECT_EQ(cell(xyz), given[i][k]) << "row " << i << ": " << row[col.at(xyz)];
      test::expect_position_reads_back(row[col.at(xyz)], origin[k], points[i][k]);
      test::expect_position_reads_back(row[col.at(std::array{"proj_x", "proj_y", "proj_z"}[k])], origin[k],
                                       e[i].projection.point[k]);
    }
    EXPECT_EQ(float(cell("w")), e[i].w) << "row " << i;
    EXPECT_EQ(float(cell("gy")), e[i].gradient.y) << "row " << i;
    EXPECT_EQ(float(cell("hxz")), e[i].hessian.xz) << "row " << i;
    EXPECT_EQ(float(cell("udist")), e[i].unsigned_distance) << "row " << i;
    EXPECT_EQ(float(cell("bdist")), e[i].boundary_distance) << "row " << i;
    EXPECT_EQ(float(cell("sdf")), e[i].sdf.distance) << "row " << i;
    EXPECT_EQ(float(cell("sdf1")), e[i].sdf.first_order) << "row " << i;
    EXPECT_EQ(float(cell("hbound")), e[i].harnack_bound) << "row " << i;
    EXPECT_EQ(cell("proj_iters"), double(e[i].projection.iterations)) << "row " << i;
  }
}

// A far-off mesh GwnModel::build refused ("translate the mesh near the origin": a unit
// tetrahedron at UTM-like coordinates, its box 4e-7 of its largest coordinate) is answered: w and
// the signed distance to its faces, as about the origin.
TEST_F(QueryCliTest, MeshThatWasRefusedAsFarOffIsAnswered) {
  const std::string mesh = temp_path("utm_tet.obj"), points = temp_path("utm_tet_points.txt");
  test::write_far_tetrahedron(mesh);
  {
    // Inside, 0.2 from the faces x = 0, y = 0 and z = 0; outside, 2 in front of the face x = 0.
    std::ofstream p(points);
    p << "512345.878 4123456.989 123.45\n512343.678 4123457.039 123.5\n";
  }
  const RunResult r = run_query(binary_, quote(mesh) + " --points " + quote(points) + " --fields w,sdf");
  std::remove(mesh.c_str());
  std::remove(points.c_str());
  ASSERT_TRUE(r.exited);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rows = test::csv_rows(r.out);
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0], (std::vector<std::string>{"x", "y", "z", "w", "sdf", "sdf_piece"}));
  ASSERT_EQ(rows[1].size(), 6u);
  ASSERT_EQ(rows[2].size(), 6u);
  // The points as given; w and the sdf as about the origin, to float's rounding there (6e-8).
  EXPECT_EQ(rows[1][0] + " " + rows[1][1] + " " + rows[1][2], "512345.878 4123456.989 123.45");
  EXPECT_EQ(rows[2][0] + " " + rows[2][1] + " " + rows[2][2], "512343.678 4123457.039 123.5");
  EXPECT_NEAR(test::cell_double(rows[1][3]), 1.0, 1e-5);
  EXPECT_NEAR(test::cell_double(rows[2][3]), 0.0, 1e-5);
  EXPECT_NEAR(test::cell_double(rows[1][4]), -0.2, 1e-5);
  EXPECT_NEAR(test::cell_double(rows[2][4]), 2.0, 1e-5);
  EXPECT_EQ(rows[1][5], "sheet");
  EXPECT_EQ(rows[2][5], "sheet");
}

// A recentred mesh the build still refuses (its three vertices coincide, 5e6 out): the build's
// message names model coordinates, so the origin they are relative to is said with it.
TEST_F(QueryCliTest, RefusalOfARecentredMeshSaysTheOrigin) {
  const std::string mesh = temp_path("utm_point.obj"), points = temp_path("utm_point_points.txt");
  std::ofstream(mesh) << "v 5000000.5 1 1\nv 5000000.5 1 1\nv 5000000.5 1 1\nf 1 2 3\n";
  std::ofstream(points) << "0 0 0\n";
  const RunResult r = run_query(binary_, quote(mesh) + " --points " + quote(points));
  std::remove(mesh.c_str());
  std::remove(points.c_str());
  ASSERT_TRUE(r.exited);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find(mesh + ": "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("(coordinates relative to (5000000.5, 1, 1), the mesh being recentred)"), std::string::npos)
      << r.err;
}

TEST(ScaleCli, QueryRefusesAnUnservedMeshNamingIt) {
  // gwnrt-query used to print w = -nan, udist = inf at 1e30 and exited 0.
  const std::string binary = test::program_binary("gwnrt-query");
  if (binary.empty()) GTEST_SKIP() << "gwnrt-query not built next to the tests";
  const std::string mesh = test::temp_path("huge_tet") + ".obj", points = test::temp_path("huge_points") + ".txt";
  {
    std::ofstream m(mesh);
    m << "v 0 0 0\nv 1e30 0 0\nv 0 1e30 0\nv 0 0 1e30\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
    std::ofstream p(points);
    p << "2e29 2e29 2e29\n";
  }
  const test::RunResult run = test::run_program(binary, test::quote(mesh) + " --points " + test::quote(points));
  EXPECT_TRUE(run.exited);
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.err.find("scale the mesh down"), std::string::npos) << run.err;
  EXPECT_EQ(run.out.find("nan"), std::string::npos) << run.out;
}

}  // namespace
}  // namespace gwnrt
