// Tests for the mesh writers: a cube with every per-vertex array, written as PLY and OBJ,
// indexed and as a soup, read back by the project's strict reader (positions and triangles,
// exactly), decoded byte by byte and number by number (every attribute), and read by Assimp,
// an independent reader; then the errors, each of which must name the file and the element.

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#if GWNRT_HAVE_ASSIMP
#include <assimp/scene.h>
#include <assimp/Importer.hpp>
#endif

#include "gwnrt/geometry/mesh.h"
#include "gwnrt/geometry/surface_mesh.h"
#include "gwnrt/io/mesh_io.h"
#include "gwnrt/io/mesh_writer.h"
#include "test_util.h"

namespace gwnrt {
namespace {

namespace fs = std::filesystem;

class MeshWriter : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::random_device rd;
    // ctest may run tests of several build trees at once; a random suffix keeps them apart.
    dir_ = fs::path(::testing::TempDir()) / (std::string("gwnrt_mesh_writer_") + info->test_suite_name() + "_" +
                                             info->name() + "_" + std::to_string(rd()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (dir_.empty()) return;  // skipped before SetUp made it
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

using test::read_bytes;

// A unit cube, moved and scaled so that its coordinates are not short decimals (the text
// writer must keep every digit), with every per-vertex array filled. Vertex i is the corner
// (i & 1, i >> 1 & 1, i >> 2 & 1); the triangles are counter-clockwise seen from outside.
SurfaceMesh cube() {
  SurfaceMesh m;
  for (uint32_t i = 0; i < 8; ++i) {
    const vec3 c(float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1));
    m.positions.push_back(c * (1.0f / 3.0f) + vec3(0.1f, -0.7f, 2.3f));
    m.normals.push_back(glm::normalize(c - vec3(0.5f)));
    m.colors.emplace_back(float(i) / 7.0f, 1.0f - float(i) / 9.0f, 0.3f, 0.9f);
    m.uvs.emplace_back(float(i) / 3.0f, float(i) / 7.0f);
    m.source_triangles.push_back(7 * i + 3);
    m.source_barycentrics.emplace_back(0.1f * float(i), 0.05f * float(i));
  }
  // Out of range and half-way: round(clamp(c) * 255) gives 255, 0, 128 (127.5 rounds up).
  m.colors[0] = {1.5f, -0.25f, 0.5f, 1.0f};
  m.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                 {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  return m;
}

SurfaceMesh positions_only(const SurfaceMesh& m) {
  SurfaceMesh p;
  p.positions = m.positions;
  p.triangles = m.triangles;
  return p;
}

uint8_t color_byte(float c) { return static_cast<uint8_t>(std::lround(std::clamp(c, 0.0f, 1.0f) * 255.0f)); }

// The mesh vertex behind output vertex j (a soup gives each triangle corner its own).
uint32_t source_vertex(const SurfaceMesh& m, bool soup, size_t j) { return soup ? m.triangles[j / 3][j % 3] : j; }

size_t output_vertex_count(const SurfaceMesh& m, bool soup) {
  return soup ? 3 * m.triangles.size() : m.positions.size();
}

uvec3 output_triangle(const SurfaceMesh& m, bool soup, size_t t) {
  if (!soup) return m.triangles[t];
  const auto b = static_cast<uint32_t>(3 * t);
  return {b, b + 1, b + 2};
}

// ---------------------------------------------------------------------------------------
// Read back by load_mesh: positions and triangles, exactly.

void expect_loads_back(const std::string& file, const SurfaceMesh& m, bool soup, const char* format) {
  Mesh back;
  MeshLoadReport report;
  const Status s = load_mesh(file, back, &report);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(report.format, format);
  ASSERT_EQ(back.positions.size(), output_vertex_count(m, soup));
  ASSERT_EQ(back.triangles.size(), m.triangles.size());
  for (size_t j = 0; j < back.positions.size(); ++j) {
    EXPECT_EQ(back.positions[j], m.positions[source_vertex(m, soup, j)]) << "vertex " << j;
  }
  for (size_t t = 0; t < back.triangles.size(); ++t) {
    EXPECT_EQ(back.triangles[t], output_triangle(m, soup, t)) << "triangle " << t;
  }
}

TEST_F(MeshWriter, PlyLoadsBackExactly) {
  const SurfaceMesh m = cube();
  for (const bool soup : {false, true}) {
    SCOPED_TRACE(soup ? "soup" : "indexed");
    const std::string file = path(soup ? "soup.ply" : "indexed.ply");
    const Status s = write_surface_mesh(file, m, {.soup = soup});
    ASSERT_TRUE(s.ok()) << s.message();
    expect_loads_back(file, m, soup, "ply-binary-le");
  }
}

TEST_F(MeshWriter, ObjLoadsBackExactly) {
  const SurfaceMesh m = cube();
  for (const bool soup : {false, true}) {
    SCOPED_TRACE(soup ? "soup" : "indexed");
    const std::string file = path(soup ? "soup.obj" : "indexed.obj");
    const Status s = write_surface_mesh(file, m, {.soup = soup});
    ASSERT_TRUE(s.ok()) << s.message();
    expect_loads_back(file, m, soup, "obj");
  }
}

TEST_F(MeshWriter, PositionsOnlyLoadBack) {
  const SurfaceMesh m = positions_only(cube());
  for (const char* name : {"bare.ply", "bare.obj"}) {
    SCOPED_TRACE(name);
    const Status s = write_surface_mesh(path(name), m);
    ASSERT_TRUE(s.ok()) << s.message();
    expect_loads_back(path(name), m, false, std::string_view(name).ends_with("ply") ? "ply-binary-le" : "obj");
  }
}

// ---------------------------------------------------------------------------------------
// The PLY bytes: the header as documented, then little-endian records of every array.

uint32_t le_u32(const std::string& b, size_t off) {
  uint32_t v = 0;
  for (int k = 3; k >= 0; --k) v = v << 8 | static_cast<uint8_t>(b[off + static_cast<size_t>(k)]);
  return v;
}

float le_f32(const std::string& b, size_t off) { return std::bit_cast<float>(le_u32(b, off)); }

TEST_F(MeshWriter, PlyHeaderAndRecords) {
  const SurfaceMesh m = cube();
  for (const bool soup : {false, true}) {
    SCOPED_TRACE(soup ? "soup" : "indexed");
    const std::string file = path("cube.ply");
    ASSERT_TRUE(write_surface_mesh(file, m, {.soup = soup}).ok());
    const std::string bytes = read_bytes(file);
    const size_t nv = output_vertex_count(m, soup);
    const std::string header = "ply\nformat binary_little_endian 1.0\ncomment written by gwnrt\nelement vertex " +
                               std::to_string(nv) +
                               "\nproperty float x\nproperty float y\nproperty float z\n"
                               "property float nx\nproperty float ny\nproperty float nz\n"
                               "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n"
                               "property float u\nproperty float v\n"
                               "property uint source_triangle\n"
                               "property float source_u\nproperty float source_v\n"
                               "element face 12\nproperty list uchar int vertex_indices\nend_header\n";
    ASSERT_EQ(bytes.substr(0, header.size()), header);
    constexpr size_t kVertexBytes = 12 + 12 + 4 + 8 + 4 + 8;
    constexpr size_t kFaceBytes = 1 + 12;
    ASSERT_EQ(bytes.size(), header.size() + nv * kVertexBytes + m.triangles.size() * kFaceBytes);

    for (size_t j = 0; j < nv; ++j) {
      SCOPED_TRACE("vertex " + std::to_string(j));
      const uint32_t i = source_vertex(m, soup, j);
      const size_t o = header.size() + j * kVertexBytes;
      for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(le_f32(bytes, o + 4 * k), m.positions[i][k]);
        EXPECT_EQ(le_f32(bytes, o + 12 + 4 * k), m.normals[i][k]);
      }
      for (int k = 0; k < 4; ++k) EXPECT_EQ(static_cast<uint8_t>(bytes[o + 24 + k]), color_byte(m.colors[i][k]));
      EXPECT_EQ(le_f32(bytes, o + 28), m.uvs[i].x);
      EXPECT_EQ(le_f32(bytes, o + 32), m.uvs[i].y);
      EXPECT_EQ(le_u32(bytes, o + 36), m.source_triangles[i]);
      EXPECT_EQ(le_f32(bytes, o + 40), m.source_barycentrics[i].x);
      EXPECT_EQ(le_f32(bytes, o + 44), m.source_barycentrics[i].y);
    }
    // The clamped and the half-way colour of vertex 0.
    if (!soup) {
      const size_t o = header.size() + 24;
      EXPECT_EQ(static_cast<uint8_t>(bytes[o]), 255);
      EXPECT_EQ(static_cast<uint8_t>(bytes[o + 1]), 0);
      EXPECT_EQ(static_cast<uint8_t>(bytes[o + 2]), 128);
      EXPECT_EQ(static_cast<uint8_t>(bytes[o + 3]), 255);
    }
    for (size_t t = 0; t < m.triangles.size(); ++t) {
      const size_t o = header.size() + nv * kVertexBytes + t * kFaceBytes;
      EXPECT_EQ(static_cast<uint8_t>(bytes[o]), 3);
      const uvec3 tri = output_triangle(m, soup, t);
      for (int k = 0; k < 3; ++k) EXPECT_EQ(le_u32(bytes, o + 1 + 4 * k), tri[k]) << "face " << t;
    }
  }
}

TEST_F(MeshWriter, PlyLeavesOutAbsentArrays) {
  SurfaceMesh m = positions_only(cube());
  m.uvs = cube().uvs;
  ASSERT_TRUE(write_surface_mesh(path("uv.ply"), m).ok());
  const std::string bytes = read_bytes(path("uv.ply"));
  const std::string header =
      "ply\nformat binary_little_endian 1.0\ncomment written by gwnrt\nelement vertex 8\n"
      "property float x\nproperty float y\nproperty float z\nproperty float u\nproperty float v\n"
      "element face 12\nproperty list uchar int vertex_indices\nend_header\n";
  ASSERT_EQ(bytes.substr(0, header.size()), header);
  EXPECT_EQ(bytes.size(), header.size() + 8 * 20 + 12 * 13);
}

// ---------------------------------------------------------------------------------------
// The OBJ text: every number reads back to the same float; faces in the form that fits.

struct ObjText {
  std::vector<std::vector<float>> v, vn, vt;
  std::vector<std::string> f;
  std::vector<std::string> comments;
};

ObjText parse_obj(const std::string& text) {
  ObjText o;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string kw;
    ls >> kw;
    if (kw == "#") {
      o.comments.push_back(line);
      continue;
    }
    if (kw == "f") {
      o.f.push_back(line);
      continue;
    }
    std::vector<float> nums;
    std::string tok;
    while (ls >> tok) {
      float x = 0;
      const auto [ptr, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), x);
      EXPECT_TRUE(ec == std::errc() && ptr == tok.data() + tok.size()) << "malformed number '" << tok << "'";
      nums.push_back(x);
    }
    (kw == "v" ? o.v : kw == "vn" ? o.vn : o.vt).push_back(nums);
    EXPECT_TRUE(kw == "v" || kw == "vn" || kw == "vt") << line;
  }
  return o;
}

TEST_F(MeshWriter, ObjNumbersRoundTrip) {
  const SurfaceMesh m = cube();
  for (const bool soup : {false, true}) {
    SCOPED_TRACE(soup ? "soup" : "indexed");
    ASSERT_TRUE(write_surface_mesh(path("cube.obj"), m, {.soup = soup}).ok());
    const ObjText o = parse_obj(read_bytes(path("cube.obj")));
    const size_t nv = output_vertex_count(m, soup);
    ASSERT_EQ(o.comments.size(), 1u);
    EXPECT_TRUE(o.comments[0].starts_with("# written by gwnrt")) << o.comments[0];
    ASSERT_EQ(o.v.size(), nv);
    ASSERT_EQ(o.vn.size(), nv);
    ASSERT_EQ(o.vt.size(), nv);
    ASSERT_EQ(o.f.size(), m.triangles.size());
    for (size_t j = 0; j < nv; ++j) {
      SCOPED_TRACE("vertex " + std::to_string(j));
      const uint32_t i = source_vertex(m, soup, j);
      ASSERT_EQ(o.v[j].size(), 6u);  // x y z r g b
      ASSERT_EQ(o.vn[j].size(), 3u);
      ASSERT_EQ(o.vt[j].size(), 2u);
      for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(o.v[j][k], m.positions[i][k]);
        EXPECT_EQ(o.v[j][3 + k], std::clamp(m.colors[i][k], 0.0f, 1.0f));
        EXPECT_EQ(o.vn[j][k], m.normals[i][k]);
      }
      EXPECT_EQ(o.vt[j][0], m.uvs[i].x);
      EXPECT_EQ(o.vt[j][1], m.uvs[i].y);
    }
    for (size_t t = 0; t < m.triangles.size(); ++t) {
      const uvec3 tri = output_triangle(m, soup, t) + 1u;
      std::string want = "f";
      for (int k = 0; k < 3; ++k) {
        const std::string i = std::to_string(tri[k]);
        want += " " + i + "/" + i + "/" + i;
      }
      EXPECT_EQ(o.f[t], want);
    }
  }
}

TEST_F(MeshWriter, ObjFaceFormsFollowWhatIsPresent) {
  const SurfaceMesh full = cube();
  struct Case {
    bool normals, uvs;
    const char* first_face;
  };
  for (const Case& c : {Case{false, false, "f 1 3 4"}, Case{true, false, "f 1//1 3//3 4//4"},
                        Case{true, true, "f 1/1/1 3/3/3 4/4/4"}, Case{false, true, "f 1/1 3/3 4/4"}}) {
    SCOPED_TRACE(c.first_face);
    SurfaceMesh m = positions_only(full);
    if (c.normals) m.normals = full.normals;
    if (c.uvs) m.uvs = full.uvs;
    ASSERT_TRUE(write_surface_mesh(path("forms.obj"), m).ok());
    const ObjText o = parse_obj(read_bytes(path("forms.obj")));
    ASSERT_EQ(o.f.size(), 12u);
    EXPECT_EQ(o.f[0], c.first_face);
    EXPECT_EQ(o.vn.size(), c.normals ? 8u : 0u);
    EXPECT_EQ(o.vt.size(), c.uvs ? 8u : 0u);
    ASSERT_EQ(o.v.size(), 8u);
    EXPECT_EQ(o.v[0].size(), 3u);  // no colours, no r g b
  }
}

// ---------------------------------------------------------------------------------------
// The format: by extension, case-insensitive, or given.

TEST_F(MeshWriter, FormatFromExtensionOrOption) {
  const SurfaceMesh m = cube();
  ASSERT_TRUE(write_surface_mesh(path("upper.PLY"), m).ok());
  EXPECT_TRUE(read_bytes(path("upper.PLY")).starts_with("ply\nformat binary_little_endian 1.0\n"));
  ASSERT_TRUE(write_surface_mesh(path("mixed.Obj"), m).ok());
  EXPECT_TRUE(read_bytes(path("mixed.Obj")).starts_with("# written by gwnrt"));
  // A given format wins over the extension.
  ASSERT_TRUE(write_surface_mesh(path("given.txt"), m, {.format = MeshFileFormat::kObj}).ok());
  EXPECT_TRUE(read_bytes(path("given.txt")).starts_with("# written by gwnrt"));
  ASSERT_TRUE(write_surface_mesh(path("given.obj"), m, {.format = MeshFileFormat::kPly}).ok());
  EXPECT_TRUE(read_bytes(path("given.obj")).starts_with("ply\n"));
}

TEST_F(MeshWriter, EmptyMeshWritesEmptyElements) {
  const SurfaceMesh m;
  ASSERT_TRUE(write_surface_mesh(path("empty.ply"), m).ok());
  EXPECT_EQ(read_bytes(path("empty.ply")),
            "ply\nformat binary_little_endian 1.0\ncomment written by gwnrt\nelement vertex 0\n"
            "property float x\nproperty float y\nproperty float z\n"
            "element face 0\nproperty list uchar int vertex_indices\nend_header\n");
  ASSERT_TRUE(write_surface_mesh(path("empty.obj"), m, {.soup = true}).ok());
  EXPECT_EQ(read_bytes(path("empty.obj")), "# written by gwnrt: 0 vertices, 0 triangles\n");
}

// ---------------------------------------------------------------------------------------
// Errors: each a non-ok Status naming the file and the element; nothing is written.

void expect_error(const Status& s, StatusCode code, const std::string& file, const std::string& what) {
  EXPECT_FALSE(s.ok());
  EXPECT_EQ(s.code(), code) << s.message();
  EXPECT_NE(s.message().find(file), std::string::npos) << s.message();
  EXPECT_NE(s.message().find(what), std::string::npos) << "'" << what << "' not in: " << s.message();
}

TEST_F(MeshWriter, UnwritablePathFails) {
  const SurfaceMesh m = cube();
  const std::string missing = path("no_such_dir/cube.ply");
  expect_error(write_surface_mesh(missing, m), StatusCode::kIoError, missing, "cannot open");
  EXPECT_FALSE(fs::exists(missing));
  // A directory where the file should be.
  fs::create_directories(dir_ / "dir.obj");
  expect_error(write_surface_mesh(path("dir.obj"), m), StatusCode::kIoError, path("dir.obj"), "cannot open");
  EXPECT_TRUE(fs::is_directory(dir_ / "dir.obj"));
}

TEST_F(MeshWriter, WriteFailureIsReportedAndLeavesNoFile) {
  // /dev/full accepts the open and fails every write with ENOSPC: the failure must surface
  // (from fwrite or from fclose), and a device is not removed.
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full on this system";
  const Status s = write_surface_mesh("/dev/full", cube(), {.format = MeshFileFormat::kObj});
  expect_error(s, StatusCode::kIoError, "/dev/full", "write failed");
  EXPECT_TRUE(fs::exists("/dev/full"));
}

TEST_F(MeshWriter, UnknownExtensionIsRefused) {
  const SurfaceMesh m = cube();
  for (const char* name : {"cube.off", "cube", "cube.ply.gz"}) {
    SCOPED_TRACE(name);
    const std::string file = path(name);
    const Status s = write_surface_mesh(file, m);
    expect_error(s, StatusCode::kInvalidArgument, file, "extension");
    EXPECT_FALSE(fs::exists(file));
  }
  EXPECT_NE(write_surface_mesh(path("cube.off"), m).message().find("'.off'"), std::string::npos);
}

TEST_F(MeshWriter, IndexOutOfRangeNamesTheTriangle) {
  SurfaceMesh m = cube();
  m.triangles[5].y = 8;
  for (const char* name : {"bad.ply", "bad.obj"}) {
    const std::string file = path(name);
    expect_error(write_surface_mesh(file, m), StatusCode::kInvalidMesh, file, "triangle 5 refers to vertex 8");
    EXPECT_FALSE(fs::exists(file));
  }
}

TEST_F(MeshWriter, SizeMismatchNamesTheArray) {
  const SurfaceMesh good = cube();
  struct Case {
    const char* array;
    void (*shrink)(SurfaceMesh&);
  };
  for (const Case& c : {Case{"normals", [](SurfaceMesh& m) { m.normals.pop_back(); }},
                        Case{"colors", [](SurfaceMesh& m) { m.colors.push_back({}); }},
                        Case{"uvs", [](SurfaceMesh& m) { m.uvs.resize(3); }},
                        Case{"source_triangles", [](SurfaceMesh& m) { m.source_triangles.pop_back(); }},
                        Case{"source_barycentrics", [](SurfaceMesh& m) { m.source_barycentrics.resize(1); }}}) {
    SCOPED_TRACE(c.array);
    SurfaceMesh m = good;
    c.shrink(m);
    const std::string file = path("mismatch.ply");
    expect_error(write_surface_mesh(file, m, {.soup = true}), StatusCode::kInvalidMesh, file,
                 std::string(" ") + c.array + " for 8 positions");
    EXPECT_FALSE(fs::exists(file));
  }
}

TEST_F(MeshWriter, NonFiniteValuesNameTheVertex) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  SurfaceMesh m = cube();
  m.positions[4].y = nan;
  expect_error(write_surface_mesh(path("nan.obj"), m), StatusCode::kInvalidMesh, path("nan.obj"),
               "vertex 4 has a non-finite position");
  m = cube();
  m.normals[6].z = -inf;
  expect_error(write_surface_mesh(path("inf.ply"), m), StatusCode::kInvalidMesh, path("inf.ply"),
               "vertex 6 has a non-finite normal");
  EXPECT_FALSE(fs::exists(path("nan.obj")));
  EXPECT_FALSE(fs::exists(path("inf.ply")));
}

TEST_F(MeshWriter, InvalidMeshLeavesAnExistingFileAlone) {
  const std::string file = path("keep.ply");
  ASSERT_TRUE(write_surface_mesh(file, cube()).ok());
  const std::string before = read_bytes(file);
  SurfaceMesh bad = cube();
  bad.triangles[0].x = 100;
  EXPECT_FALSE(write_surface_mesh(file, bad).ok());
  EXPECT_EQ(read_bytes(file), before);
}

// ---------------------------------------------------------------------------------------
// MeshWriteOptions::origin: positions in the input's coordinates, in double.

double le_f64(const std::string& b, size_t off) {
  return std::bit_cast<double>(uint64_t(le_u32(b, off + 4)) << 32 | le_u32(b, off));
}

// A recentred scan's origin (UTM metres): float steps by 0.25 there, double by 9.3e-10.
const dvec3 kScanOrigin(512344.0, 4123464.0, 120.0);

TEST_F(MeshWriter, OriginIsAddedInDoubleToPlyPositions) {
  const SurfaceMesh m = cube();
  for (const bool soup : {false, true}) {
    SCOPED_TRACE(soup ? "soup" : "indexed");
    ASSERT_TRUE(write_surface_mesh(path("far.ply"), m, {.soup = soup, .origin = kScanOrigin}).ok());
    const std::string b = read_bytes(path("far.ply"));
    const std::string xyz = "property double x\nproperty double y\nproperty double z\nproperty float nx\n";
    EXPECT_NE(b.find(xyz), std::string::npos);
    const size_t body = b.find("end_header\n") + 11;
    // x y z as doubles, then normals, colours, uvs, source triangle and barycentrics as before.
    const size_t record = 3 * 8 + 3 * 4 + 4 + 2 * 4 + 4 + 2 * 4;
    for (size_t j = 0; j < output_vertex_count(m, soup); ++j) {
      const uint32_t i = source_vertex(m, soup, j);
      for (int k = 0; k < 3; ++k)
        EXPECT_EQ(le_f64(b, body + j * record + 8 * k), kScanOrigin[k] + double(m.positions[i][k])) << j;
      EXPECT_EQ(le_f32(b, body + j * record + 24), m.normals[i].x) << j;
    }
    // Read back recentred, the positions come back where they were written to float's resolution
    // of the cube's size, not of 4e6.
    Mesh back;
    MeshLoadReport r;
    ASSERT_TRUE(load_mesh(path("far.ply"), back, &r, {.recentre = true}).ok());
    ASSERT_NE(r.origin, dvec3(0.0));
    for (size_t j = 0; j < back.positions.size(); ++j)
      EXPECT_LT(glm::length(r.origin + dvec3(back.positions[j]) -
                            (kScanOrigin + dvec3(m.positions[source_vertex(m, soup, j)]))),
                1e-6)
          << j;
  }
}

TEST_F(MeshWriter, OriginIsAddedInDoubleToObjPositions) {
  const SurfaceMesh m = cube();
  ASSERT_TRUE(write_surface_mesh(path("far.obj"), m, {.origin = kScanOrigin}).ok());
  std::istringstream in(read_bytes(path("far.obj")));
  std::string line;
  size_t j = 0;
  while (std::getline(in, line)) {
    if (!line.starts_with("v ")) continue;
    std::istringstream ls(line.substr(2));
    std::string tok;
    for (int k = 0; k < 6 && ls >> tok; ++k) {
      double x = 0;
      const auto [ptr, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), x);
      ASSERT_TRUE(ec == std::errc() && ptr == tok.data() + tok.size()) << tok;
      if (k < 3) {
        EXPECT_EQ(x, kScanOrigin[k] + double(m.positions[j][k])) << "vertex " << j;
      } else {
        EXPECT_EQ(float(x), std::clamp(m.colors[j][k - 3], 0.0f, 1.0f)) << "vertex " << j;  // colours as before
      }
    }
    ++j;
  }
  EXPECT_EQ(j, m.positions.size());
}

TEST_F(MeshWriter, ZeroOriginWritesFloatsAndABadOneIsRefused) {
  const SurfaceMesh m = cube();
  for (const char* name : {"a.ply", "a.obj"}) {
    SCOPED_TRACE(name);
    ASSERT_TRUE(write_surface_mesh(path(name), m).ok());
    const std::string plain = read_bytes(path(name));
    ASSERT_TRUE(write_surface_mesh(path(name), m, {.origin = dvec3(0.0)}).ok());
    EXPECT_EQ(read_bytes(path(name)), plain);
  }
  const std::string file = path("nan_origin.ply");
  expect_error(write_surface_mesh(file, m, {.origin = {1.0, std::nan(""), 0.0}}), StatusCode::kInvalidArgument, file,
               "origin");
  EXPECT_FALSE(fs::exists(file));
}

// ---------------------------------------------------------------------------------------
// Assimp, an independent reader: counts, positions, normals, texture coordinates, colours.

#if GWNRT_HAVE_ASSIMP

// Assimp's float parser (fast_atof) is not correctly rounded: text it reads can come back an
// ulp or so away, where our reader (from_chars) is exact.
constexpr float kTextTolerance = 1e-6f;

void expect_near3(const aiVector3D& got, const vec3& want, float tol, const std::string& what) {
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(got[static_cast<unsigned>(k)], want[k], tol * std::max(1.0f, std::abs(want[k]))) << what;
  }
}

void expect_assimp_reads(const std::string& file, const SurfaceMesh& m, bool soup, bool ply) {
  Assimp::Importer importer;
  // No post-processing (flags 0): in particular no joining of identical vertices, which
  // would merge a soup's corners back together.
  const aiScene* scene = importer.ReadFile(file, 0);
  ASSERT_NE(scene, nullptr) << importer.GetErrorString();
  ASSERT_EQ(scene->mNumMeshes, 1u);
  const aiMesh* am = scene->mMeshes[0];
  ASSERT_EQ(am->mNumFaces, m.triangles.size());
  // Assimp's OBJ importer gives every face corner a vertex of its own; its PLY importer keeps
  // the file's vertices.
  const size_t want_vertices = ply ? output_vertex_count(m, soup) : 3 * m.triangles.size();
  ASSERT_EQ(am->mNumVertices, want_vertices);
  ASSERT_TRUE(am->HasNormals());
  ASSERT_TRUE(am->HasTextureCoords(0));
  ASSERT_TRUE(am->HasVertexColors(0));
  const float tol = ply ? 0.0f : kTextTolerance;

  for (unsigned f = 0; f < am->mNumFaces; ++f) {
    const aiFace& face = am->mFaces[f];
    ASSERT_EQ(face.mNumIndices, 3u) << "face " << f;
    const uvec3 out_tri = output_triangle(m, soup, f);
    for (unsigned k = 0; k < 3; ++k) {
      const unsigned a = face.mIndices[k];
      ASSERT_LT(a, am->mNumVertices);
      if (ply) {
        EXPECT_EQ(a, out_tri[static_cast<int>(k)]) << "face " << f;
      }
      const uint32_t i = m.triangles[f][static_cast<int>(k)];  // the mesh vertex at this corner
      const std::string what = "face " + std::to_string(f) + " corner " + std::to_string(k);
      expect_near3(am->mVertices[a], m.positions[i], tol, what + " position");
      expect_near3(am->mNormals[a], m.normals[i], tol, what + " normal");
      EXPECT_NEAR(am->mTextureCoords[0][a].x, m.uvs[i].x, tol) << what << " u";
      EXPECT_NEAR(am->mTextureCoords[0][a].y, m.uvs[i].y, tol) << what << " v";
      const aiColor4D& c = am->mColors[0][a];
      if (ply) {
        // Bytes, which Assimp scales to [0, 1].
        EXPECT_FLOAT_EQ(c.r, color_byte(m.colors[i].x) / 255.0f) << what << " red";
        EXPECT_FLOAT_EQ(c.g, color_byte(m.colors[i].y) / 255.0f) << what << " green";
        EXPECT_FLOAT_EQ(c.b, color_byte(m.colors[i].z) / 255.0f) << what << " blue";
        EXPECT_FLOAT_EQ(c.a, color_byte(m.colors[i].w) / 255.0f) << what << " alpha";
      } else {
        EXPECT_NEAR(c.r, std::clamp(m.colors[i].x, 0.0f, 1.0f), tol) << what << " red";
        EXPECT_NEAR(c.g, std::clamp(m.colors[i].y, 0.0f, 1.0f), tol) << what << " green";
        EXPECT_NEAR(c.b, std::clamp(m.colors[i].z, 0.0f, 1.0f), tol) << what << " blue";
      }
    }
  }
}

#endif  // GWNRT_HAVE_ASSIMP

class MeshWriterAssimp : public MeshWriter {
 protected:
  void SetUp() override {
#if !GWNRT_HAVE_ASSIMP
    GTEST_SKIP() << "Assimp was not found at configure time (Debian: libassimp-dev); the independent-reader "
                    "checks are skipped";
#else
    MeshWriter::SetUp();
#endif
  }
};

TEST_F(MeshWriterAssimp, ReadsPly) {
#if GWNRT_HAVE_ASSIMP
  const SurfaceMesh m = cube();
  for (const bool soup : {false, true}) {
    SCOPED_TRACE(soup ? "soup" : "indexed");
    const std::string file = path(soup ? "soup.ply" : "indexed.ply");
    ASSERT_TRUE(write_surface_mesh(file, m, {.soup = soup}).ok());
    expect_assimp_reads(file, m, soup, true);
  }
#endif
}

TEST_F(MeshWriterAssimp, ReadsObj) {
#if GWNRT_HAVE_ASSIMP
  const SurfaceMesh m = cube();
  for (const bool soup : {false, true}) {
    SCOPED_TRACE(soup ? "soup" : "indexed");
    const std::string file = path(soup ? "soup.obj" : "indexed.obj");
    ASSERT_TRUE(write_surface_mesh(file, m, {.soup = soup}).ok());
    expect_assimp_reads(file, m, soup, false);
  }
#endif
}

}  // namespace
}  // namespace gwnrt
