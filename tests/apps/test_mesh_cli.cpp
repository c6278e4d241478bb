// gwnrt-mesh run as a subprocess: it writes the library's mesh, meshes a scan far from the origin
// where it lies, says where it ran, carries the input's UVs and colours, and refuses bad
// arguments and an output it cannot write.
#include <algorithm>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_util.h"
#include "gwnrt/io/mesh_io.h"
#include "gwnrt/meshing/extract_surface.h"
#include "gwnrt/meshing/mesh_comparison.h"
#include "mesh_files.h"
#include "meshing/meshing_fixtures.h"
#include "test_util.h"

namespace gwnrt {
namespace {

// gwnrt-mesh as a subprocess: it writes what the library gives, and refuses what it cannot do.
class MeshCliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    binary_ = test::program_binary("gwnrt-mesh");
    if (binary_.empty()) GTEST_SKIP() << "gwnrt-mesh not built next to the tests (expected <build>/bin/gwnrt-mesh)";
  }
  std::string binary_;
};

TEST_F(MeshCliTest, WritesTheLibrarysMesh) {
  const std::string out = test::temp_path("bunny_mesh.ply");
  const test::RunResult r = test::run_program(
      binary_, test::quote(test::data_path("bunny.obj")) + " -o " + test::quote(out) + " --resolution 40 -v");
  ASSERT_TRUE(r.exited && r.exit_code == 0) << r.err;
  EXPECT_NE(r.err.find("triangles"), std::string::npos) << r.err;
  Mesh read;
  ASSERT_TRUE(load_mesh(out, read).ok());
  const GwnModel model = test::build_model(test::load_test_mesh("bunny.obj"));
  SurfaceMesh lib;
  ASSERT_TRUE(extract_surface(model, options_at(40), lib).ok());
  ASSERT_EQ(read.positions.size(), lib.positions.size());
  ASSERT_EQ(read.triangles.size(), lib.triangles.size());
  for (size_t i = 0; i < lib.positions.size(); ++i) ASSERT_EQ(read.positions[i], lib.positions[i]);
}

// A georeferenced scan (the bunny moved to UTM metres, where float steps by 0.25): gwnrt-mesh meshes
// it about its own centre and writes it back where it lies, in double. The library's mesh of the
// bunny at the origin, moved there in double, is the reference: the two models differ by float
// rounding of coordinates about 10 across, as the CPU's and the GPU's results do, so the CUDA
// comparison's tolerances hold: vertices within 2e-3 cells, 90% within 1e-5 cells, a flat quad
// maybe split the other way (measured: worst 5.2e-5 cells, 99.5% within 1e-5, 2 quads resplit).
TEST_F(MeshCliTest, MeshesAScanFarFromTheOriginWhereItLies) {
  const dvec3 offset(512345.678, 4123456.789, 123.25);
  const Mesh near_mesh = test::load_test_mesh("bunny.obj");
  std::string text;
  for (const vec3& p : near_mesh.positions) {
    const dvec3 x = dvec3(p) + offset;
    text += "v " + test::num(x.x) + " " + test::num(x.y) + " " + test::num(x.z) + "\n";
  }
  for (const uvec3& t : near_mesh.triangles)
    text += "f " + std::to_string(t.x + 1) + " " + std::to_string(t.y + 1) + " " + std::to_string(t.z + 1) + "\n";
  const std::string in = test::temp_path("utm_bunny.obj"), out = test::temp_path("utm_bunny_mesh.ply");
  std::ofstream(in, std::ios::binary) << text;
  const test::RunResult r =
      test::run_program(binary_, test::quote(in) + " -o " + test::quote(out) + " --resolution 40 -v");
  ASSERT_TRUE(r.exited && r.exit_code == 0) << r.err;
  EXPECT_NE(r.err.find("far from the origin for its size: computed relative to ("), std::string::npos) << r.err;

  // Read back in double: the file's coordinates are origin + position.
  Mesh read;
  MeshLoadReport report;
  ASSERT_TRUE(load_mesh(out, read, &report, {.recentre = true}).ok());
  SurfaceMesh lib;
  MeshingStats stats;
  ASSERT_TRUE(extract_surface(test::build_model(near_mesh), options_at(40), lib, &stats).ok());
  ASSERT_EQ(read.positions.size(), lib.positions.size());
  const double cell = stats.cell_size;
  double worst = 0;
  size_t within = 0;
  for (size_t i = 0; i < lib.positions.size(); ++i) {
    const double d = glm::length(report.origin + dvec3(read.positions[i]) - (dvec3(lib.positions[i]) + offset));
    worst = std::max(worst, d);
    within += d <= 1e-5 * cell;
  }
  EXPECT_LT(worst, 2e-3 * cell) << "cell " << cell;
  EXPECT_GE(double(within), 0.9 * double(lib.positions.size()));
  const TriangleComparison c = compare_triangles(read.triangles, lib.triangles);
  EXPECT_TRUE(c.equal_up_to_splits()) << c.different << " of " << lib.triangles.size() << " triangles differ";
}

// --device: cuda meshes on the GPU or, without one (or without the CUDA backend built
// in), fails saying why; auto says which it took and writes the CPU's mesh when it took the CPU.
TEST_F(MeshCliTest, DeviceCudaOrAutoSaysWhereItRan) {
  const std::string out = test::temp_path("device_mesh.ply");
  const std::string base = test::quote(test::data_path("bunny.obj")) + " -o " + test::quote(out) + " --resolution 24";
  const test::RunResult cuda = test::run_program(binary_, base + " --device cuda");
  ASSERT_TRUE(cuda.exited);
  if (cuda.exit_code != 0) {
    EXPECT_EQ(cuda.exit_code, 1);
    EXPECT_NE(cuda.err.find("--device cuda: "), std::string::npos) << cuda.err;
  }
  const test::RunResult automatic = test::run_program(binary_, base + " --device auto");
  ASSERT_TRUE(automatic.exited && automatic.exit_code == 0) << automatic.err;
  const bool took_cpu = automatic.err.find("--device auto: the CPU (") != std::string::npos;
  EXPECT_TRUE(took_cpu || automatic.err.find("--device auto: the GPU") != std::string::npos) << automatic.err;
  EXPECT_EQ(took_cpu, cuda.exit_code != 0) << "auto must take the GPU exactly when cuda works";
  Mesh read;
  ASSERT_TRUE(load_mesh(out, read).ok());
  const GwnModel model = test::build_model(test::load_test_mesh("bunny.obj"));
  SurfaceMesh lib;
  ASSERT_TRUE(extract_surface(model, options_at(24), lib).ok());
  ASSERT_EQ(read.triangles.size(), lib.triangles.size());
  if (took_cpu) {
    for (size_t i = 0; i < lib.positions.size(); ++i) ASSERT_EQ(read.positions[i], lib.positions[i]);
  }
}

// UVs and colours from an OBJ (a cube, per-corner vt of six charts, v x y z r g b) to the PLY
// written: the library's transfer, and a clear refusal for a mesh without them.
TEST_F(MeshCliTest, CarriesTheInputsUvsAndColours) {
  const Mesh cube = test::make_cube();
  std::ostringstream obj;
  for (const vec3& p : cube.positions)
    obj << "v " << p.x << ' ' << p.y << ' ' << p.z << ' ' << 0.5 + 0.5 * p.x << " 0.25 " << 0.5 - 0.5 * p.z << '\n';
  for (size_t t = 0; t < cube.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) obj << "vt " << 0.1 * double(t / 2) + 0.01 * k << ' ' << 0.3 * k << '\n';
  for (size_t t = 0; t < cube.triangles.size(); ++t) {
    obj << 'f';
    for (int k = 0; k < 3; ++k) obj << ' ' << cube.triangles[t][k] + 1 << '/' << 3 * t + k + 1;
    obj << '\n';
  }
  const std::string in = test::temp_path("textured_cube.obj"), out = test::temp_path("textured_cube.ply");
  {
    std::ofstream f(in);
    f << obj.str();
  }
  const test::RunResult r = test::run_program(
      binary_, test::quote(in) + " -o " + test::quote(out) + " --resolution 16 --attributes uv,color -v");
  ASSERT_TRUE(r.exited && r.exit_code == 0) << r.err;
  EXPECT_NE(r.err.find("36 UVs, vertex colours"), std::string::npos) << r.err;
  Mesh source, read;
  ASSERT_TRUE(load_mesh(in, source).ok());
  ASSERT_TRUE(load_mesh(out, read).ok());
  MeshingOptions o = options_at(16);
  o.attributes = kAttributeUv | kAttributeColor;
  SurfaceMesh lib;
  ASSERT_TRUE(extract_surface(test::build_model(source), o, lib).ok());
  ASSERT_EQ(read.positions.size(), lib.positions.size());
  ASSERT_EQ(read.uvs.size(), lib.uvs.size());
  ASSERT_EQ(read.colors.size(), lib.colors.size());
  for (size_t i = 0; i < lib.positions.size(); ++i) {
    ASSERT_EQ(read.uvs[i], lib.uvs[i]) << "vertex " << i;
    for (int c = 0; c < 4; ++c) ASSERT_NEAR(read.colors[i][c], lib.colors[i][c], 0.5 / 255 + 1e-6) << "vertex " << i;
  }
  const test::RunResult refused = test::run_program(binary_, test::quote(test::data_path("bunny.obj")) + " -o " +
                                                                 test::quote(out) + " --resolution 16 --attributes uv");
  ASSERT_TRUE(refused.exited);
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.err.find("bunny.obj: meshing: UVs were asked for but the source mesh has no texture coordinates"),
            std::string::npos)
      << refused.err;
}

// A count or size that must be positive says so, not CLI11's range with a
// 300-digit bound; nan is refused too.
TEST_F(MeshCliTest, PositiveOptionsSayTheyMustBePositive) {
  for (const std::string args : {" --threads 0", " --threads -2", " --cell-size nan", " --cell-size 0"}) {
    const test::RunResult r = test::run_program(
        binary_, test::quote(test::data_path("bunny.obj")) + " -o " + test::quote(test::temp_path("p.ply")) + args);
    ASSERT_TRUE(r.exited) << args;
    EXPECT_NE(r.exit_code, 0) << args;
    const bool threads = args.find("--threads") != std::string::npos;
    EXPECT_NE(r.err.find(threads ? "[1, 1024]" : "> 0"), std::string::npos) << args << ": " << r.err;
    EXPECT_EQ(r.err.find("17976931"), std::string::npos) << args << ": " << r.err;
  }
}

TEST_F(MeshCliTest, RefusesBadArgumentsAndUnwritableOutput) {
  const std::string mesh = test::quote(test::data_path("bunny.obj"));
  for (const std::string args : {" --resolution 0", " --cell-size -1", " --resolution 40 --level 0",
                                 " --attributes nonsense", " --resolution 40 -o /nonexistent-dir/x.ply",
                                 " --resolution 40 -o out.xyz", " --weld-tolerance 0.5", " --weld-tolerance -1"}) {
    const std::string full =
        mesh + (args.find(" -o ") == std::string::npos ? " -o " + test::quote(test::temp_path("x.ply")) : "") + args;
    const test::RunResult r = test::run_program(binary_, full);
    ASSERT_TRUE(r.exited) << args;
    EXPECT_NE(r.exit_code, 0) << args;
    EXPECT_FALSE(r.err.empty()) << args;
  }
}

// An STL soup in, an STL out: the soup's corners are welded (the summary says so), and the STL
// written holds the library's mesh of the same triangles read from an OBJ, facet for facet.
TEST_F(MeshCliTest, MeshesAnStlSoupIntoAnStl) {
  const std::string stl = test::data_path("realworld/kuka_kr10r1100sixx_visual_base_link.stl");
  const std::string out = test::temp_path("kuka_mesh.stl");
  const test::RunResult r =
      test::run_program(binary_, test::quote(stl) + " -o " + test::quote(out) + " --resolution 48 -v");
  ASSERT_TRUE(r.exited && r.exit_code == 0) << r.err;
  EXPECT_NE(r.err.find("5969 vertices from 35592 corners"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("boundary: 182 edges in 34 loops"), std::string::npos) << r.err;
  Mesh written, source;
  ASSERT_TRUE(load_mesh(out, written).ok());
  ASSERT_TRUE(load_mesh(stl, source).ok());
  const GwnModel model = test::build_model(std::move(source));
  SurfaceMesh lib;
  ASSERT_TRUE(extract_surface(model, options_at(48), lib).ok());
  ASSERT_EQ(written.triangles.size(), lib.triangles.size());
  for (size_t t = 0; t < lib.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k)
      ASSERT_EQ(written.positions[written.triangles[t][k]], lib.positions[lib.triangles[t][k]]) << "triangle " << t;

  // The tolerance weld closes its cracks: no boundary left.
  const test::RunResult welded = test::run_program(
      binary_, test::quote(stl) + " -o " + test::quote(out) + " --resolution 16 -v --weld-tolerance 1e-6");
  ASSERT_TRUE(welded.exited && welded.exit_code == 0) << welded.err;
  EXPECT_NE(welded.err.find("moved by the weld tolerance); boundary: 0 edges"), std::string::npos) << welded.err;
  const test::RunResult refused =
      test::run_program(binary_, test::quote(stl) + " -o " + test::quote(out) + " --weld-tolerance 0.5");
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.err.find("--weld-tolerance"), std::string::npos) << refused.err;
}

// The repair, as the report and -v see it: the output of a CAD part at 64³ has no intersecting
// triangles, the unrepaired one (--no-repair) has the pairs the repair said it found.
TEST_F(MeshCliTest, RepairsIntersectingTrianglesUnlessAskedNotTo) {
  const std::string stl = test::quote(test::data_path("realworld/motoman_motomini_visual_link_1_s.stl"));
  const std::string out = test::quote(test::temp_path("motoman_mesh.ply"));
  const auto run = [&](const std::string& extra) {
    const std::string json = test::temp_path("motoman_report.json");
    const test::RunResult r =
        test::run_program(binary_, stl + " -o " + out + " --resolution 64 --report-json " + test::quote(json) + extra);
    EXPECT_TRUE(r.exited && r.exit_code == 0) << r.err;
    std::ifstream in(json);
    return nlohmann::json::parse(in, nullptr, false);
  };
  const nlohmann::json repaired = run(""), raw = run(" --no-repair");
  ASSERT_FALSE(repaired.is_discarded() || raw.is_discarded());
  EXPECT_EQ(repaired["self_intersections"], 0u);
  EXPECT_GT(uint64_t(repaired["repair"]["pairs_found"]), 0u);
  EXPECT_GT(uint64_t(repaired["repair"]["vertex_moves"]), 0u);
  EXPECT_EQ(repaired["repair"]["pairs_left"], 0u);
  EXPECT_EQ(raw["self_intersections"], repaired["repair"]["pairs_found"]);
  EXPECT_EQ(raw["repair"]["rounds"], 0u);
  EXPECT_EQ(raw["triangles"], repaired["triangles"]);
}

// --report at a level other than 1/2: the sheets are classified for the level meshed (it had
// exited 1 after writing the mesh, "the model's sheets were classified for level 0.5"). On the
// bunny with holes the distances from S's samples to the output stay within a cell, as at 1/2.
TEST_F(MeshCliTest, ReportsAtAnyLevel) {
  for (const char* level : {"0.3", "0.5", "0.8"}) {
    const std::string json = test::temp_path("level_report.json");
    const test::RunResult r = test::run_program(
        binary_, test::quote(test::data_path("bunny_holes.obj")) + " -o " + test::quote(test::temp_path("l.ply")) +
                     " --resolution 32 --level " + level + " --report-json " + test::quote(json));
    ASSERT_TRUE(r.exited && r.exit_code == 0) << level << ": " << r.err;
    std::ifstream in(json);
    const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
    ASSERT_FALSE(j.is_discarded()) << level;
    EXPECT_EQ(j["self_intersections"], 0u) << level;
    EXPECT_GT(uint64_t(j["distances"]["surface_points"]), 100u) << level;
    EXPECT_LT(double(j["distances"]["hausdorff_from_surface"]), double(j["cell_size"])) << level;
  }
}

}  // namespace
}  // namespace gwnrt
