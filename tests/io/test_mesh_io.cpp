// Tests for the strict OBJ/PLY readers: real files, the same mesh in every supported
// encoding, and a table of broken inputs that must fail with a message naming the problem.

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "gwnrt/base/memory.h"
#include "gwnrt/geometry/mesh.h"
#include "gwnrt/io/mesh_io.h"
#include "gwnrt/io/mesh_writer.h"
#include "gwnrt/io/read_file.h"
#include "gwnrt/model/model.h"
#include "gwnrt/query/batch.h"
#include "mesh_files.h"
#include "test_util.h"

namespace gwnrt {
namespace {

namespace fs = std::filesystem;

using test::data_path;
using test::kSmallObj;
using test::num;
using test::PlyBody;
using test::PlyTypes;
using test::Small;
using test::small_ply;

// Each test's files in a directory of its own (test::TempDirTest).
class TempFiles : public test::TempDirTest {};

void expect_mesh(const Mesh& m, const std::vector<vec3>& pos, const std::vector<uvec3>& tris) {
  ASSERT_EQ(m.positions.size(), pos.size());
  for (size_t i = 0; i < pos.size(); ++i) EXPECT_EQ(m.positions[i], pos[i]) << "vertex " << i;
  ASSERT_EQ(m.triangles.size(), tris.size());
  for (size_t i = 0; i < tris.size(); ++i) EXPECT_EQ(m.triangles[i], tris[i]) << "triangle " << i;
}

// Every directed edge has exactly one opposite twin.
bool is_closed_manifold(const Mesh& m) {
  std::set<std::pair<uint32_t, uint32_t>> edges;
  for (const uvec3& t : m.triangles) {
    for (int k = 0; k < 3; ++k) {
      if (!edges.insert({t[k], t[(k + 1) % 3]}).second) return false;
    }
  }
  for (const auto& [a, b] : edges) {
    if (!edges.count({b, a})) return false;
  }
  return true;
}

// ---------------------------------------------------------------------------------------
// Real files

TEST(MeshIoData, Bunny) {
  Mesh m;
  MeshLoadReport r;
  const Status s = load_mesh(data_path("bunny.obj"), m, &r);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(r.format, "obj");
  EXPECT_EQ(r.vertex_count, 1839u);
  EXPECT_EQ(r.triangle_count, 3674u);
  EXPECT_EQ(m.triangles.size(), 3674u);
  EXPECT_EQ(m.positions.size(), 1839u);
  EXPECT_EQ(r.polygons_fanned, 0u);
  EXPECT_TRUE(is_closed_manifold(m));
}

TEST(MeshIoData, BunnyWithHoles) {
  Mesh m;
  MeshLoadReport r;
  const Status s = load_mesh(data_path("bunny_holes.obj"), m, &r);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(r.triangle_count, 3524u);
  EXPECT_FALSE(is_closed_manifold(m));
}

TEST(MeshIoData, Teapot) {
  Mesh m;
  MeshLoadReport r;
  const Status s = load_mesh(data_path("teapot.obj"), m, &r);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(r.triangle_count, 992u);
  EXPECT_EQ(r.vertex_count, 792u);
}

TEST(MeshIoData, DragonPlyAscii) {
  Mesh m;
  MeshLoadReport r;
  const Status s = load_mesh(data_path("dragon_vrip_res4.ply"), m, &r);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(r.format, "ply-ascii");
  EXPECT_EQ(r.vertex_count, 5205u);
  EXPECT_EQ(r.triangle_count, 11102u);
  EXPECT_EQ(r.polygons_fanned, 0u);
  EXPECT_EQ(m.positions[0], vec3(0.0317083f, 0.0557939f, -0.049836f));
}

// The dragon re-encoded as binary PLY (both byte orders) and OBJ reads back bit for bit.
TEST_F(TempFiles, DragonRoundTrips) {
  Mesh ref;
  ASSERT_TRUE(load_mesh(data_path("dragon_vrip_res4.ply"), ref).ok());
  for (const char* format : {"binary_little_endian", "binary_big_endian"}) {
    std::string text = std::string("ply\nformat ") + format + " 1.0\nelement vertex " +
                       std::to_string(ref.positions.size()) +
                       "\nproperty float x\nproperty float y\nproperty float z\n" + "element face " +
                       std::to_string(ref.triangles.size()) + "\nproperty list uchar uint vertex_indices\nend_header\n";
    PlyBody b(format);
    for (const vec3& p : ref.positions) {
      for (int k = 0; k < 3; ++k) b.put("float", p[k]);
    }
    for (const uvec3& t : ref.triangles) {
      b.put("uchar", 3);
      for (int k = 0; k < 3; ++k) b.put("uint", t[k]);
    }
    Mesh m;
    MeshLoadReport r;
    const Status s = load_mesh(write(std::string(format) + ".ply", text + b.bytes()), m, &r);
    ASSERT_TRUE(s.ok()) << s.message();
    EXPECT_EQ(r.format, format == std::string("binary_little_endian") ? "ply-binary-le" : "ply-binary-be");
    expect_mesh(m, ref.positions, ref.triangles);
  }
  std::string obj;
  for (const vec3& p : ref.positions) obj += "v " + num(p.x) + " " + num(p.y) + " " + num(p.z) + "\n";
  for (const uvec3& t : ref.triangles) {
    obj += "f " + std::to_string(t.x + 1) + " " + std::to_string(t.y + 1) + " " + std::to_string(t.z + 1) + "\n";
  }
  Mesh m;
  const Status s = load_mesh(write("dragon.obj", obj), m);
  ASSERT_TRUE(s.ok()) << s.message();
  expect_mesh(m, ref.positions, ref.triangles);
}

// ---------------------------------------------------------------------------------------
// One mesh, every encoding

TEST_F(TempFiles, SmallObj) {
  const Small ref;
  Mesh m;
  MeshLoadReport r;
  const Status s = load_mesh(write("small.obj", kSmallObj), m, &r);
  ASSERT_TRUE(s.ok()) << s.message();
  expect_mesh(m, ref.positions, ref.triangles);
  EXPECT_EQ(r.format, "obj");
  EXPECT_EQ(r.vertex_count, 7u);
  EXPECT_EQ(r.triangle_count, 7u);
  EXPECT_EQ(r.polygons_fanned, 2u);
  EXPECT_EQ(r.degenerate_triangles, 0u);
}

TEST_F(TempFiles, ExtensionIsCaseInsensitive) {
  Mesh m;
  EXPECT_TRUE(load_mesh(write("SMALL.OBJ", kSmallObj), m).ok());
  EXPECT_TRUE(load_mesh(write("SMALL.Ply", small_ply("ascii", Small().positions)), m).ok());
}

TEST_F(TempFiles, SmallPlyAllEncodings) {
  const Small ref;
  const std::vector<std::pair<std::string, std::string>> formats = {
      {"ascii", "ply-ascii"}, {"binary_little_endian", "ply-binary-le"}, {"binary_big_endian", "ply-binary-be"}};
  std::vector<PlyTypes> variants(6);
  variants[1].xyz = "double";
  variants[1].count = "int";
  variants[1].index = "uint";
  variants[2].xyz = "float32";
  variants[2].count = "uint8";
  variants[2].index = "int32";
  variants[2].list_name = "vertex_index";
  variants[3].xyz = "float64";
  variants[3].count = "ushort";
  variants[3].index = "ushort";
  variants[4].count = "char";
  variants[4].index = "uchar";
  variants[4].eol = "\r\n";
  variants[5].count = "uint16";
  variants[5].index = "int16";
  int n = 0;
  for (const auto& [format, name] : formats) {
    for (const PlyTypes& t : variants) {
      SCOPED_TRACE(format + " xyz=" + t.xyz + " count=" + t.count + " index=" + t.index +
                   " eol=" + std::to_string(t.eol.size()));
      Mesh m;
      MeshLoadReport r;
      const Status s =
          load_mesh(write("small" + std::to_string(n++) + ".ply", small_ply(format, ref.positions, t)), m, &r);
      ASSERT_TRUE(s.ok()) << s.message();
      expect_mesh(m, ref.positions, ref.triangles);
      EXPECT_EQ(r.format, name);
      EXPECT_EQ(r.vertex_count, 7u);
      EXPECT_EQ(r.triangle_count, 7u);
      EXPECT_EQ(r.polygons_fanned, 2u);
      EXPECT_EQ(r.degenerate_triangles, 0u);
    }
  }
}

TEST_F(TempFiles, PlyIntegerCoordinates) {
  const Small ref;
  std::vector<vec3> pos;
  for (const vec3& p : ref.positions) pos.push_back(p * 4.0f);  // all integers
  int n = 0;
  for (const char* format : {"ascii", "binary_little_endian", "binary_big_endian"}) {
    for (const char* type : {"char", "short", "int", "int16"}) {
      SCOPED_TRACE(std::string(format) + " " + type);
      PlyTypes t;
      t.xyz = type;
      Mesh m;
      const Status s = load_mesh(write("int" + std::to_string(n++) + ".ply", small_ply(format, pos, t)), m);
      ASSERT_TRUE(s.ok()) << s.message();
      expect_mesh(m, pos, ref.triangles);
    }
  }
}

// ---------------------------------------------------------------------------------------
// Recentring far-off meshes (MeshLoadOptions::recentre)

// A georeferenced site: UTM easting and northing in metres, the small mesh a few metres across.
const dvec3 kUtmOffset(512345.678, 4123456.789, 123.25);

std::vector<dvec3> small_at(const dvec3& offset) {
  std::vector<dvec3> world;
  for (const vec3& p : Small().positions) world.push_back(dvec3(p) + offset);
  return world;
}

std::string obj_text(const std::vector<dvec3>& world, const std::vector<std::vector<uint32_t>>& faces) {
  std::string text;
  for (const dvec3& p : world) text += "v " + num(p.x) + " " + num(p.y) + " " + num(p.z) + "\n";
  for (const auto& f : faces) {
    text += "f";
    for (uint32_t v : f) {
      text += ' ';
      text += std::to_string(v + 1);
    }
    text += "\n";
  }
  return text;
}

Status load_recentred(const std::string& path, Mesh& m, MeshLoadReport& r) {
  MeshLoadOptions o;
  o.recentre = true;
  return load_mesh(path, m, &r, o);
}

TEST_F(TempFiles, RecentreKeepsAFarMeshsShapeInEveryEncoding) {
  const std::vector<dvec3> world = small_at(kUtmOffset);
  const Small ref;
  std::vector<std::pair<std::string, std::string>> files = {{"small.obj", obj_text(world, ref.faces)}};
  for (const char* format : {"ascii", "binary_little_endian", "binary_big_endian"}) {
    PlyTypes t;
    t.xyz = "double";
    files.emplace_back(std::string("small_") + format + ".ply", small_ply(format, world, t));
  }
  // Float properties in ASCII whose text has the digits a float would lose (as programs that
  // declare float but print doubles write them; binary float cannot hold them).
  PlyTypes as_double;
  as_double.xyz = "double";
  std::string float_declared = small_ply("ascii", world, as_double);
  for (const char* axis : {"x", "y", "z"}) {
    const std::string declared = std::string("property double ") + axis + "\n";
    float_declared.replace(float_declared.find(declared), declared.size(),
                           std::string("property float ") + axis + "\n");
  }
  files.emplace_back("small_ascii_float.ply", float_declared);
  for (const auto& [name, text] : files) {
    SCOPED_TRACE(name);
    Mesh m;
    MeshLoadReport r;
    const Status s = load_recentred(write(name, text), m, r);
    ASSERT_TRUE(s.ok()) << s.message();
    ASSERT_EQ(m.positions.size(), world.size());
    expect_mesh(m, m.positions, ref.triangles);
    // The origin: within half a step of the box centre, on a multiple of the step (the largest
    // power of 2 not above the diagonal: 4 for this box, 7.0 across).
    dvec3 lo(world[0]), hi(world[0]);
    for (const dvec3& p : world) lo = glm::min(lo, p), hi = glm::max(hi, p);
    const double step = std::exp2(std::floor(std::log2(glm::length(hi - lo))));
    EXPECT_EQ(step, 4.0);
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(std::fmod(r.origin[k], step), 0.0) << k;
      EXPECT_LE(std::fabs(r.origin[k] - 0.5 * (lo[k] + hi[k])), 0.5 * step) << k;
    }
    // Each position is the file's minus the origin, rounded once to float: the shape keeps float's
    // resolution of the mesh's size (an ulp of 4 is 4.8e-7), where a plain load keeps that of
    // 4e6 (0.25).
    for (size_t i = 0; i < world.size(); ++i) {
      EXPECT_EQ(m.positions[i], vec3(world[i] - r.origin)) << "vertex " << i;
      EXPECT_LE(glm::length(dvec3(m.positions[i]) + r.origin - world[i]), 1e-6) << "vertex " << i;
    }
    Mesh plain;
    ASSERT_TRUE(load_mesh(write("plain_" + name, text), plain).ok());
    double plain_error = 0;
    for (size_t i = 0; i < world.size(); ++i)
      plain_error = std::max(plain_error, glm::length(dvec3(plain.positions[i]) - world[i]));
    EXPECT_GT(plain_error, 0.01) << "a plain load should lose the shape: the check above would prove nothing";
  }
}

TEST_F(TempFiles, RecentreLeavesMeshesNearTheOriginAsAPlainLoadReadsThem) {
  const Small ref;
  PlyTypes t;
  t.xyz = "double";
  // About the origin, and off it by less than 16 diagonals: not far enough to move (the box is 7.0 across).
  for (const dvec3 offset : {dvec3(0.0), dvec3(10.0, -3.0, 7.0), dvec3(0.0, 0.0, -100.0)}) {
    for (const auto& [name, text] :
         {std::pair<std::string, std::string>{"near.obj", obj_text(small_at(offset), ref.faces)},
          {"near.ply", small_ply("binary_little_endian", small_at(offset), t)}}) {
      SCOPED_TRACE(name + " offset z " + std::to_string(offset.z));
      const std::string path = write(name, text);
      Mesh plain, m;
      MeshLoadReport r;
      ASSERT_TRUE(load_mesh(path, plain).ok());
      ASSERT_TRUE(load_recentred(path, m, r).ok());
      EXPECT_EQ(r.origin, dvec3(0.0));
      expect_mesh(m, plain.positions, plain.triangles);
    }
  }
  Mesh bunny, plain;
  MeshLoadReport r;
  ASSERT_TRUE(load_recentred(data_path("bunny.obj"), bunny, r).ok());
  ASSERT_TRUE(load_mesh(data_path("bunny.obj"), plain).ok());
  EXPECT_EQ(r.origin, dvec3(0.0));
  expect_mesh(bunny, plain.positions, plain.triangles);
}

TEST_F(TempFiles, RecentreThresholdIsSixteenDiagonals) {
  const Small ref;
  dvec3 lo(kInfinity), hi(-kInfinity);
  for (const dvec3& p : small_at(dvec3(0.0))) lo = glm::min(lo, p), hi = glm::max(hi, p);
  const double diagonal = glm::length(hi - lo);
  // The largest coordinate lies hi.x past the offset along x.
  for (const double factor : {15.9, 16.1}) {
    const double offset = factor * diagonal - hi.x;
    Mesh m;
    MeshLoadReport r;
    ASSERT_TRUE(load_recentred(write("t.obj", obj_text(small_at({offset, 0, 0}), ref.faces)), m, r).ok());
    EXPECT_EQ(r.origin != dvec3(0.0), factor > kRecentreCoordinatePerDiagonal) << factor;
  }
  // Near for its size (3.5 diagonals) but beyond the coordinates a model serves: moved, it is
  // served (a plain load is refused by the build).
  const std::string big = write("big.obj",
                                "v 1e8 0 0\nv 1.2e8 0 0\nv 1e8 2e7 0\nv 1e8 0 2e7\n"
                                "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  Mesh m, plain;
  MeshLoadReport r;
  ASSERT_TRUE(load_recentred(big, m, r).ok());
  EXPECT_NE(r.origin, dvec3(0.0));
  GwnModel model;
  EXPECT_TRUE(GwnModel::build(std::move(m), model).ok());
  ASSERT_TRUE(load_mesh(big, plain).ok());
  EXPECT_FALSE(GwnModel::build(std::move(plain), model).ok());
}

TEST_F(TempFiles, RecentreNeedsAReportAndKeepsTheChecks) {
  const std::string path = write("far.obj", obj_text(small_at(kUtmOffset), Small().faces));
  Mesh m;
  MeshLoadOptions o;
  o.recentre = true;
  const Status s = load_mesh(path, m, nullptr, o);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("needs a MeshLoadReport"), std::string::npos) << s.message();
  EXPECT_TRUE(m.positions.empty());
  // The readers' checks come first, with the same messages.
  MeshLoadReport r;
  const Status bad = load_mesh(write("bad.obj", "v 1e6 2e6 nan\nv 0 0 0\nv 1 0 0\nf 1 2 3\n"), m, &r, o);
  EXPECT_EQ(bad.code(), StatusCode::kInvalidMesh);
  EXPECT_NE(bad.message().find("bad.obj:1: vertex 1 has a non-finite coordinate"), std::string::npos) << bad.message();
  // An unused vertex far beyond the rest is only referenced by nothing: the origin follows the
  // triangles, and the vertex is kept (here it still fits a float).
  std::string text = obj_text(small_at(kUtmOffset), Small().faces) + "v 3e38 0 0\n";
  ASSERT_TRUE(load_mesh(write("unused.obj", text), m, &r, o).ok());
  EXPECT_LT(std::fabs(r.origin.x - kUtmOffset.x), 8.0);
  // Moved by a triangle at -1e38, an unused vertex at 3.4e38 leaves float's range: said so, with
  // the file's coordinates, not as a non-finite coordinate the file does not hold.
  const Status beyond =
      load_mesh(write("beyond.obj", "v -1e38 0 0\nv -1e38 1e31 0\nv -1e38 0 1e31\nv 3.4e38 0 0\nf 1 2 3\n"), m, &r, o);
  EXPECT_EQ(beyond.code(), StatusCode::kInvalidMesh);
  EXPECT_NE(
      beyond.message().find("beyond.obj: vertex 3 (counting from 0), at (3.4e+38, 0, 0), is beyond float's range"),
      std::string::npos)
      << beyond.message();
}

// Stand-in for a georeferenced scan: bunny_holes moved to UTM coordinates. A plain load is refused
// by GwnModel::build (too small for where it lies); recentred, it answers as at the origin.
TEST_F(TempFiles, RecentredFarMeshAnswersAsTheMeshAtTheOrigin) {
  Mesh near_mesh;
  ASSERT_TRUE(load_mesh(data_path("bunny_holes.obj"), near_mesh).ok());
  std::vector<dvec3> world;
  for (const vec3& p : near_mesh.positions) world.push_back(dvec3(p) + kUtmOffset);
  std::string text;
  for (const dvec3& p : world) text += "v " + num(p.x) + " " + num(p.y) + " " + num(p.z) + "\n";
  for (const uvec3& t : near_mesh.triangles)
    text += "f " + std::to_string(t.x + 1) + " " + std::to_string(t.y + 1) + " " + std::to_string(t.z + 1) + "\n";
  const std::string path = write("utm_bunny.obj", text);

  Mesh plain;
  ASSERT_TRUE(load_mesh(path, plain).ok());
  GwnModel refused;
  const Status s = GwnModel::build(std::move(plain), refused);
  EXPECT_NE(s.message().find("translate the mesh near the origin"), std::string::npos) << s.message();

  Mesh far_mesh;
  MeshLoadReport r;
  ASSERT_TRUE(load_recentred(path, far_mesh, r).ok());
  ASSERT_NE(r.origin, dvec3(0.0));
  const GwnModel far_model = test::build_model(std::move(far_mesh));
  const GwnModel near_model = test::build_model(near_mesh);

  // The same world points asked of both: about the origin, and about the origin of the far one.
  test::Random rng(7);
  Aabb box = near_model.bounds();
  const vec3 pad = 0.2f * (box.hi - box.lo);
  box.lo -= pad, box.hi += pad;
  std::vector<vec3> near_points, far_points;
  for (int i = 0; i < 2000; ++i) {
    const vec3 p = rng.in_box(box);
    near_points.push_back(p);
    far_points.push_back(vec3(dvec3(p) + kUtmOffset - r.origin));
  }
  QueryRequest request;
  request.fields = kFieldW | kFieldUnsignedDistance;
  request.method = WindingMethod::kCrossing;
  std::vector<PointResult> near_results(near_points.size()), far_results(far_points.size());
  ASSERT_TRUE(evaluate_points(near_model, near_points, request, near_results).ok());
  ASSERT_TRUE(evaluate_points(far_model, far_points, request, far_results).ok());
  // The two meshes and point sets differ by float rounding of coordinates about 10 across (up to
  // 4.8e-7), which moves w by about that over the distance to M. Points within 1e-2 of M are left
  // out (w is steep there). Measured: |dw| <= 1.8e-7, |d udist| <= 1.2e-6 (the box is 22 across).
  const float diag = glm::length(box.hi - box.lo);
  int compared = 0;
  for (size_t i = 0; i < near_points.size(); ++i) {
    EXPECT_NEAR(far_results[i].unsigned_distance, near_results[i].unsigned_distance, 1e-6f * diag) << i;
    if (near_results[i].unsigned_distance < 1e-2f) continue;
    ++compared;
    EXPECT_NEAR(far_results[i].w, near_results[i].w, 1e-5f) << "point " << i;
  }
  EXPECT_GT(compared, 1900);
}

// ---------------------------------------------------------------------------------------
// Degenerate triangles

TEST_F(TempFiles, DegenerateTrianglesAreKeptAndCounted) {
  const char* obj =
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nv 1 0 0\n"
      "f 1 2 3\n"   // proper
      "f 1 1 2\n"   // repeated index
      "f 1 2 4\n"   // collinear
      "f 2 5 3\n";  // two distinct vertices at the same place
  Mesh m;
  MeshLoadReport r;
  const Status s = load_mesh(write("degenerate.obj", obj), m, &r);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(r.triangle_count, 4u);
  EXPECT_EQ(m.triangles.size(), 4u);
  EXPECT_EQ(r.degenerate_triangles, 3u);

  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 1 1\n2 2 2\n3 0 1 2\n4 0 1 2 1\n";
  const Status s2 = load_mesh(write("degenerate.ply", ply), m, &r);
  ASSERT_TRUE(s2.ok()) << s2.message();
  EXPECT_EQ(r.triangle_count, 3u);
  EXPECT_EQ(r.degenerate_triangles, 3u);
  EXPECT_EQ(r.polygons_fanned, 1u);
}

TEST(MeshIoDegenerate, ExactTest) {
  EXPECT_FALSE(is_degenerate_triangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}));
  EXPECT_TRUE(is_degenerate_triangle({0, 0, 0}, {1, 2, 3}, {2, 4, 6}));
  EXPECT_TRUE(is_degenerate_triangle({1, 2, 3}, {1, 2, 3}, {4, 5, 7}));
  EXPECT_TRUE(is_degenerate_triangle({1, 2, 3}, {1, 2, 3}, {1, 2, 3}));
  // The product of the edges underflows in float but not in double.
  EXPECT_FALSE(is_degenerate_triangle({0, 0, 0}, {1e-30f, 0, 0}, {0, 1e-30f, 0}));
  // Nearly but not exactly collinear.
  EXPECT_FALSE(is_degenerate_triangle({0, 0, 0}, {1, 1, 1}, {2, 2, std::nextafter(2.0f, 3.0f)}));
}

// ---------------------------------------------------------------------------------------
// validate_mesh

Mesh tetrahedron() {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return m;
}

TEST(MeshIoValidate, InMemory) {
  EXPECT_TRUE(validate_mesh(tetrahedron()).ok());

  Mesh m = tetrahedron();
  m.positions[1] = {std::numeric_limits<float>::quiet_NaN(), 0, 1};
  Status s = validate_mesh(m, "src");
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
  EXPECT_EQ(s.message(), "src: vertex 1 has a non-finite coordinate (nan, 0, 1)");

  m = tetrahedron();
  m.positions[3].z = -std::numeric_limits<float>::infinity();
  s = validate_mesh(m);
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
  EXPECT_EQ(s.message(),
            "mesh: vertex 3 has a non-finite coordinate (0, 0, -inf): infinite, or beyond float's range (+-3.4e38)");

  m = tetrahedron();
  m.triangles[2] = {0, 7, 2};
  s = validate_mesh(m, "src");
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
  EXPECT_EQ(s.message(), "src: triangle 2 refers to vertex 7 but there are 4 vertices");

  m = tetrahedron();
  m.triangles.clear();
  s = validate_mesh(m, "src");
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
  EXPECT_EQ(s.message(), "src: the mesh has no triangles");

  s = validate_mesh(Mesh{}, "src");
  EXPECT_FALSE(s.ok());

  // Degenerate triangles are valid.
  m = tetrahedron();
  m.triangles.push_back({1, 1, 2});
  EXPECT_TRUE(validate_mesh(m).ok());
}

// ---------------------------------------------------------------------------------------
// Broken inputs

struct BadCase {
  std::string name;  // file name, extension chooses the reader
  std::string content;
  StatusCode code;
  std::vector<std::string> fragments;  // each must appear in the message
};

const std::string kTri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";  // lines 1-3

// Nine lines; counts are text so that a test can declare counts no real file could hold.
std::string ply_header(std::string_view format, const std::string& nv, const std::string& nf,
                       std::string_view index_type = "int") {
  return "ply\nformat " + std::string(format) + " 1.0\nelement vertex " + nv +
         "\nproperty float x\nproperty float y\nproperty float z\nelement face " + nf + "\nproperty list uchar " +
         std::string(index_type) + " vertex_indices\nend_header\n";
}

std::string ply_header(std::string_view format, int nv, int nf, std::string_view index_type = "int") {
  return ply_header(format, std::to_string(nv), std::to_string(nf), index_type);
}
const std::string kQuadVerts = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n";  // lines 10-13 after ply_header

std::string binary_ply(std::string_view format, const std::vector<vec3>& pos,
                       const std::vector<std::vector<int>>& faces) {
  PlyBody b(format);
  for (const vec3& p : pos) {
    for (int k = 0; k < 3; ++k) b.put("float", p[k]);
  }
  for (const auto& f : faces) {
    b.put("uchar", static_cast<double>(f.size()));
    for (int v : f) b.put("int", v);
  }
  return ply_header(format, static_cast<int>(pos.size()), static_cast<int>(faces.size())) + b.bytes();
}

std::vector<BadCase> bad_cases() {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<vec3> quad = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  const std::string good_bin = binary_ply("binary_little_endian", quad, {{0, 1, 2}, {0, 2, 3}});
  const auto P = StatusCode::kParseError;
  const auto M = StatusCode::kInvalidMesh;
  return {
      // OBJ syntax
      {"obj_bad_number.obj", "v 0 0 0\nv 1 0 0\nv 1 zz 0\nf 1 2 3\n", P, {":3:", "malformed number 'zz'"}},
      {"obj_trailing_junk.obj", "v 0 0 0\nv 1 0 0\nv 1 1.0x 0\nf 1 2 3\n", P, {":3:", "'1.0x'"}},
      {"obj_missing_coord.obj", kTri + "v 1 2\nf 1 2 3\n", P, {":4:", "vertex has 2 coordinates"}},
      {"obj_bad_extra_component.obj", kTri + "v 1 2 3 red\nf 1 2 3\n", P, {":4:", "'red'"}},
      {"obj_bad_corner.obj", kTri + "f 1/2/3/4 2 3\n", P, {":4:", "malformed face corner '1/2/3/4'"}},
      {"obj_bad_corner_text.obj", kTri + "f 1 2x 3\n", P, {":4:", "malformed face corner '2x'"}},
      {"obj_bad_corner_slash.obj", kTri + "f 1 2/ 3\n", P, {":4:", "'2/'"}},
      {"obj_bad_corner_texture.obj", kTri + "f 1 2/a 3\n", P, {":4:", "'2/a'"}},
      // OBJ content
      {"obj_index_zero.obj", kTri + "f 0 1 2\n", M, {":4:", "vertex index 0 is invalid"}},
      // OBJ texture coordinates and colours
      {"obj_vt_bad_number.obj", kTri + "vt 0 x\nf 1/1 2/1 3/1\n", P, {":4:", "malformed number 'x' in texture"}},
      {"obj_vt_too_many.obj", kTri + "vt 0 1 2 3\nf 1/1 2/1 3/1\n", P, {":4:", "texture coordinate has 4 numbers"}},
      {"obj_vt_empty.obj", kTri + "vt\nf 1 2 3\n", P, {":4:", "has 0 numbers"}},
      {"obj_vt_nan.obj", kTri + "vt nan 0\nf 1/1 2/1 3/1\n", M, {":4:", "texture coordinate 1 is not finite"}},
      {"obj_vt_index_range.obj",
       kTri + "vt 0 0\nf 1/1 2/9 3/1\n",
       M,
       {":5:", "texture index 9 is out of range", "1 texture"}},
      {"obj_vt_relative_range.obj", kTri + "vt 0 0\nf 1/-2 2/1 3/1\n", M, {":5:", "relative texture index -2"}},
      {"obj_vt_index_zero.obj", kTri + "vt 0 0\nf 1/0 2/1 3/1\n", M, {":5:", "'1/0' is out of range"}},
      {"obj_vt_mixed_corners.obj",
       kTri + "vt 0 0\nf 1/1 2 3/1\n",
       M,
       {":5:", "texture indices for 2 of its 3 corners"}},
      {"obj_colour_nan.obj", "v 0 0 0 1 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", M, {":1:", "non-finite colour"}},
      {"obj_binary.obj", kTri + std::string("f 1 2 3\n\x01\x02garbage\n"), P, {":5:", "binary content (byte 0x01)"}},
      {"obj_nul.obj", kTri + std::string("v 1 1\0 1\nf 1 2 3\n", 17), P, {":4:", "byte 0x00"}},
      // PLY attributes
      {"ply_red_list.ply",
       "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty list "
       "uchar uchar red\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0 1 5\n1 0 0 1 5\n0 1 "
       "0 1 5\n3 0 1 2\n",
       P,
       {"'red' is a list"}},
      {"ply_texcoord_length.ply",
       "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face "
       "2\nproperty list uchar int vertex_indices\nproperty list uchar float texcoord\nend_header\n0 0 0\n1 0 0\n0 1 "
       "0\n3 0 1 2 6 0 0 1 0 0 1\n3 0 2 1 4 0 0 1 0\n",
       M,
       {"face 1 has 4 texcoord values", "needs 6"}},
      {"obj_index_too_big.obj", kTri + "f 1 2 4\n", M, {":4:", "vertex index 4 is out of range", "3 vertices"}},
      {"obj_index_later_too_big.obj", kTri + "f 1 2 3\nf 1 2 9\nf 1 2 3\n", M, {":5:", "index 9 is out of range"}},
      {"obj_index_huge.obj", kTri + "f 1 2 99999999999999999999999\n", M, {":4:", "out of range"}},
      {"obj_index_negative.obj", kTri + "f -1 -2 -4\n", M, {":4:", "relative vertex index -4 is out of range"}},
      {"obj_index_negative_early.obj", "v 0 0 0\nf -1 -2 -3\nv 1 0 0\nv 0 1 0\n", M, {":2:", "-2", "out of range"}},
      {"obj_nan.obj",
       "v 0 0 0\nv nan 0 1\nv 0 1 0\nf 1 2 3\n",
       M,
       {":2:", "vertex 2 has a non-finite coordinate (nan, 0, 1)"}},
      {"obj_inf.obj", kTri + "v 0 -inf 0\nf 1 2 3\n", M, {":4:", "vertex 4", "non-finite", "-inf"}},
      {"obj_overflow.obj", kTri + "v 1e999 0 0\nf 1 2 3\n", M, {":4:", "non-finite", "inf"}},
      {"obj_beyond_float.obj", kTri + "v 3.5e38 0 0\nf 1 2 3\n", M, {":4:", "infinite, or beyond float's range"}},
      {"obj_two_corners.obj", kTri + "f 1 2\n", M, {":4:", "face has 2 corners"}},
      {"obj_no_corners.obj", kTri + "f\n", M, {":4:", "face has 0 corners"}},
      {"obj_empty.obj", "", M, {"the mesh has no triangles"}},
      {"obj_comments_only.obj", "# nothing\n\n   \n", M, {"the mesh has no triangles"}},
      {"obj_vertices_only.obj", kTri, M, {"the mesh has no triangles"}},

      // PLY header
      {"ply_bad_magic.ply",
       "plx\n" + ply_header("ascii", 4, 1).substr(4) + kQuadVerts + "3 0 1 2\n",
       P,
       {"not a PLY file"}},
      {"ply_magic_case.ply",
       "PLY\n" + ply_header("ascii", 4, 1).substr(4) + kQuadVerts + "3 0 1 2\n",
       P,
       {"not a PLY file"}},
      {"ply_header_only_no_end.ply",
       "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n",
       P,
       {"no end_header"}},
      {"ply_missing_end_header.ply",
       "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 1\nproperty list uchar int vertex_indices\n" +
           kQuadVerts + "3 0 1 2\n",
       P,
       {":9:", "missing end_header"}},
      {"ply_bad_format.ply",
       "ply\nformat binary_middle_endian 1.0\nend_header\n",
       P,
       {":2:", "unsupported PLY format 'binary_middle_endian'"}},
      {"ply_bad_version.ply", "ply\nformat ascii 2.0\nend_header\n", P, {":2:", "version '2.0'"}},
      {"ply_short_format.ply", "ply\nformat ascii\nend_header\n", P, {":2:", "malformed format line"}},
      {"ply_missing_format.ply", "ply\nelement vertex 0\nend_header\n", P, {":2:", "format"}},
      {"ply_no_format_at_all.ply", "ply\ncomment hi\nend_header\n", P, {"no 'format' line"}},
      {"ply_unknown_type.ply",
       "ply\nformat ascii 1.0\nelement vertex 1\nproperty flot x\nend_header\n",
       P,
       {":4:", "unknown property type 'flot'"}},
      {"ply_bad_count.ply",
       "ply\nformat ascii 1.0\nelement vertex -1\nend_header\n",
       P,
       {":3:", "malformed element count '-1'"}},
      {"ply_missing_z.ply",
       "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nelement face 1\n"
       "property list uchar int vertex_indices\nend_header\n0 0\n1 0\n0 1\n3 0 1 2\n",
       P,
       {"the vertex element has no 'z' property"}},
      {"ply_no_vertex_element.ply", "ply\nformat ascii 1.0\nend_header\n", P, {"no 'vertex' element"}},
      {"ply_no_face_list.ply",
       "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 1\nproperty list uchar int corners\nend_header\n0 0 0\n3 0 0 0\n",
       P,
       {"no 'vertex_indices' list"}},
      {"ply_float_index.ply",
       ply_header("ascii", 4, 1, "float") + kQuadVerts + "3 0 1 2\n",
       P,
       {"non-integer index type 'float'"}},
      {"ply_float_count.ply",
       "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 1\nproperty list float int vertex_indices\nend_header\n0 0 0\n3 0 0 0\n",
       P,
       {":8:", "list count type 'float' is not an integer type"}},
      {"ply_too_many_vertices.ply", ply_header("binary_little_endian", "99999999999", "0"), M, {"too many vertices"}},

      // PLY ascii data
      {"ply_truncated_ascii_vertices.ply", ply_header("ascii", 4, 1) + "0 0 0\n1 0 0\n", P, {"truncated", "vertex"}},
      {"ply_truncated_ascii_vertices_long.ply",
       ply_header("ascii", 4, 1) + "0.000000 0.000000 0.000000\n1.000000 0.000000 0.000000\n",
       P,
       {":11:", "truncated", "vertex 2 of 4"}},
      {"ply_truncated_ascii_faces.ply", ply_header("ascii", 4, 2) + kQuadVerts + "3 0 1 2\n", P, {"truncated", "face"}},
      {"ply_truncated_ascii_face_list.ply",
       ply_header("ascii", 4, 2) + kQuadVerts + "3 0 1 2\n3 0 2     ",
       P,
       {":15:", "truncated", "face 1 of 2"}},
      {"ply_ascii_bad_number.ply",
       ply_header("ascii", 4, 1) + "0 0 0\n1 zz 0\n1 1 0\n0 1 0\n3 0 1 2\n",
       P,
       {":11:", "invalid float value 'zz' in vertex 1, property 'y'"}},
      {"ply_ascii_float_as_index.ply",
       ply_header("ascii", 4, 1) + kQuadVerts + "3 0 1.5 2\n",
       P,
       {":14:", "invalid int value '1.5' in face 0"}},
      {"ply_ascii_uchar_overflow.ply",
       ply_header("ascii", 4, 1) + kQuadVerts + "300 0 1 2\n",
       P,
       {":14:", "invalid uchar value '300'"}},
      {"ply_ascii_trailing_data.ply",
       ply_header("ascii", 4, 1) + kQuadVerts + "3 0 1 2 3\n",
       P,
       {":14:", "unexpected data '3'"}},
      {"ply_out_of_range.ply",
       ply_header("ascii", 4, 2) + kQuadVerts + "3 0 1 2\n3 0 1 9\n",
       M,
       {":15:", "face 1 refers to vertex 9 but there are 4 vertices"}},
      {"ply_negative_index.ply",
       ply_header("ascii", 4, 1) + kQuadVerts + "3 0 -1 2\n",
       M,
       {"face 0 refers to vertex -1 but there are 4 vertices"}},
      {"ply_two_corners.ply",
       ply_header("ascii", 4, 1) + kQuadVerts + "2 0 1\n",
       M,
       {"face 0 has 2 corners, needs at least 3"}},
      {"ply_ascii_nan.ply",
       ply_header("ascii", 4, 1) + "0 0 0\n1 0 nan\n1 1 0\n0 1 0\n3 0 1 2\n",
       M,
       {"vertex 1 has a non-finite coordinate (1, 0, nan)"}},
      {"ply_no_faces.ply", ply_header("ascii", 4, 0) + kQuadVerts, M, {"the mesh has no triangles"}},

      // PLY binary data
      {"ply_truncated_binary.ply", good_bin.substr(0, good_bin.size() - 5), P, {"truncated", "face 1 of 2"}},
      {"ply_truncated_binary_vertices.ply", good_bin.substr(0, good_bin.size() - 40), P, {"truncated", "vertex"}},
      {"ply_binary_nan.ply",
       binary_ply("binary_little_endian", {{0, 0, 0}, {1, 0, 0}, {0, nan, 0}}, {{0, 1, 2}}),
       M,
       {"vertex 2 has a non-finite coordinate (0, nan, 0)"}},
      {"ply_binary_be_inf.ply",
       binary_ply("binary_big_endian", {{0, 0, 0}, {1, 0, 0}, {0, 0, std::numeric_limits<float>::infinity()}},
                  {{0, 1, 2}}),
       M,
       {"vertex 2 has a non-finite coordinate (0, 0, inf)"}},
      {"ply_binary_out_of_range.ply",
       binary_ply("binary_big_endian", quad, {{0, 1, 2}, {0, 2, 3}, {3, 4, 0}}),
       M,
       {"face 2 refers to vertex 4 but there are 4 vertices"}},
      {"ply_binary_negative.ply",
       binary_ply("binary_little_endian", quad, {{0, 1, 2}, {0, -7, 3}}),
       M,
       {"face 1 refers to vertex -7"}},
      {"ply_binary_forged_count.ply",
       ply_header("binary_little_endian", "4000000000", "1") + "\x01\x02\x03",
       P,
       {"truncated", "4000000000 vertex elements"}},
  };
}

TEST_F(TempFiles, BadInputsFailWithUsefulMessages) {
  for (const BadCase& c : bad_cases()) {
    SCOPED_TRACE(c.name);
    const std::string path = write(c.name, c.content);
    Mesh m;
    m.positions = {{7, 7, 7}};
    MeshLoadReport r;
    r.format = "untouched";
    const Status s = load_mesh(path, m, &r);
    ASSERT_FALSE(s.ok());
    EXPECT_EQ(s.code(), c.code) << s.message();
    EXPECT_EQ(s.message().rfind(path, 0), 0u) << "message should start with the path: " << s.message();
    for (const std::string& f : c.fragments) EXPECT_NE(s.message().find(f), std::string::npos) << s.message();
    // A failed load leaves its outputs alone.
    EXPECT_EQ(m.positions.size(), 1u);
    EXPECT_TRUE(m.triangles.empty());
    EXPECT_EQ(r.format, "untouched");
  }
}

TEST_F(TempFiles, FileProblems) {
  Mesh m;
  const std::string missing = (dir_ / "does_not_exist.obj").string();
  Status s = load_mesh(missing, m);
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_NE(s.message().find(missing), std::string::npos) << s.message();

  s = load_mesh(write("mesh.stl", "solid x\nendsolid x\n"), m);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("'.stl'"), std::string::npos) << s.message();

  s = load_mesh(write("no_extension", kSmallObj), m);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);

  fs::create_directories(dir_ / "folder.obj");
  s = load_mesh((dir_ / "folder.obj").string(), m);
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_NE(s.message().find("directory"), std::string::npos) << s.message();
}

std::string random_bytes(size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::string s(n, '\0');
  for (char& c : s) c = static_cast<char>(rng() & 0xff);
  return s;
}

TEST_F(TempFiles, RandomBytesFail) {
  for (unsigned seed = 1; seed <= 4; ++seed) {
    for (const char* ext : {".ply", ".obj"}) {
      Mesh m;
      const Status s = load_mesh(write("random" + std::to_string(seed) + ext, random_bytes(4096, seed)), m);
      EXPECT_FALSE(s.ok()) << ext;
    }
    // Past a valid header, the bytes are data: they must be read safely too.
    const std::string header = ply_header("binary_little_endian", 100, 100);
    Mesh m;
    const Status s =
        load_mesh(write("random_body" + std::to_string(seed) + ".ply", header + random_bytes(1000, seed)), m);
    EXPECT_FALSE(s.ok());
  }
}

// Every proper prefix of a binary file is truncated; prefixes and corrupted bytes of text
// files may or may not parse, but nothing may crash (checked under the sanitizers).
TEST_F(TempFiles, PrefixesAndCorruptionNeverCrash) {
  const Small ref;
  const std::string bin_le = small_ply("binary_little_endian", ref.positions);
  const std::string bin_be = small_ply("binary_big_endian", ref.positions);
  const std::string ascii = small_ply("ascii", ref.positions);
  const std::string obj = kSmallObj;
  for (const std::string* file : {&bin_le, &bin_be}) {
    for (size_t n = 0; n < file->size(); ++n) {
      Mesh m;
      EXPECT_FALSE(load_mesh(write("prefix.ply", file->substr(0, n)), m).ok()) << n;
    }
  }
  for (size_t n = 0; n < ascii.size(); ++n) {
    Mesh m;
    (void)load_mesh(write("prefix.ply", ascii.substr(0, n)), m);
  }
  for (size_t n = 0; n < obj.size(); ++n) {
    Mesh m;
    (void)load_mesh(write("prefix.obj", obj.substr(0, n)), m);
  }
  std::mt19937 rng(7);
  for (const std::string* file : {&bin_le, &ascii, &obj}) {
    const char* name = file == &obj ? "corrupt.obj" : "corrupt.ply";
    for (int trial = 0; trial < 300; ++trial) {
      std::string bad = *file;
      for (int k = 0; k < 3; ++k) bad[rng() % bad.size()] = static_cast<char>(rng() & 0xff);
      Mesh m;
      MeshLoadReport r;
      const Status s = load_mesh(write(name, bad), m, &r);
      if (s.ok()) {
        EXPECT_TRUE(validate_mesh(m).ok());
        EXPECT_EQ(r.triangle_count, m.triangles.size());
      }
    }
  }
}

// ---------------------------------------------------------------------------------------
// Texture coordinates and vertex colours.

TEST_F(TempFiles, ObjKeepsTextureCoordinatesAndColours) {
  // A quad (fanned) with absolute vt indices, then a triangle with relative ones and a normal index.
  const std::string obj =
      "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 1 1 0 0 0 1\nv 0 1 0 0.5 0.25 0.125\n"
      "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0.75 0\n"
      "f 1/1 2/2 3/3 4/4\nf 1/-1 3/-3 2/2/1\n";
  Mesh m;
  MeshLoadReport r;
  ASSERT_TRUE(load_mesh(write("uv.obj", obj), m, &r).ok());
  expect_mesh(m, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 2, 3}, {0, 2, 1}});
  ASSERT_EQ(m.uv_triangles.size(), 3u);
  EXPECT_EQ(m.uv_triangles[0], uvec3(0, 1, 2));
  EXPECT_EQ(m.uv_triangles[1], uvec3(0, 2, 3));
  EXPECT_EQ(m.uv_triangles[2], uvec3(4, 2, 1));
  ASSERT_EQ(m.uvs.size(), 5u);
  EXPECT_EQ(m.uvs[4], glm::vec2(0.5f, 0.75f));
  EXPECT_EQ(m.uvs[2], glm::vec2(1, 1));
  ASSERT_EQ(m.colors.size(), 4u);
  EXPECT_EQ(m.colors[0], glm::vec4(1, 0, 0, 1));
  EXPECT_EQ(m.colors[3], glm::vec4(0.5f, 0.25f, 0.125f, 1));
  EXPECT_EQ(r.uv_count, 5u);
  EXPECT_TRUE(r.has_colors);
  EXPECT_TRUE(r.attributes_dropped.empty()) << r.attributes_dropped;
}

TEST_F(TempFiles, ObjDropsAttributesSomeElementsLack) {
  Mesh m;
  MeshLoadReport r;
  // The second face has no vt indices; the third vertex no colour.
  ASSERT_TRUE(load_mesh(write("mixed.obj",
                              "v 0 0 0 1 1 1\nv 1 0 0 1 1 1\nv 0 1 0\nv 1 1 0 1 1 1\nvt 0 0\n"
                              "f 1/1 2/1 3/1\nf 2 4 3\n"),
                        m, &r)
                  .ok());
  EXPECT_EQ(m.triangles.size(), 2u);
  EXPECT_TRUE(m.uvs.empty() && m.uv_triangles.empty());
  EXPECT_TRUE(m.colors.empty());
  EXPECT_FALSE(r.has_colors);
  EXPECT_EQ(r.uv_count, 0u);
  EXPECT_NE(r.attributes_dropped.find("texture coordinates dropped: 1 faces (the first on line 7)"), std::string::npos)
      << r.attributes_dropped;
  EXPECT_NE(r.attributes_dropped.find("vertex colours dropped: 3 of 4"), std::string::npos) << r.attributes_dropped;
  // vt lines no face uses: nothing kept, and said.
  ASSERT_TRUE(load_mesh(write("unused_vt.obj", kTri + "vt 0 0\nf 1 2 3\n"), m, &r).ok());
  EXPECT_TRUE(m.uvs.empty());
  EXPECT_NE(r.attributes_dropped.find("no face refers"), std::string::npos) << r.attributes_dropped;
}

// The quad 0-1-2-3 as PLY with colour and texture properties of the given types, in `format`.
std::string attribute_ply(std::string_view format, const std::string& colour_type, bool alpha,
                          const std::string& uv_names, bool texcoord) {
  const std::vector<vec3> pos = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  const std::string u = uv_names.substr(0, uv_names.find(' ')), v = uv_names.substr(uv_names.find(' ') + 1);
  std::string h = "ply\nformat " + std::string(format) + " 1.0\nelement vertex 4\nproperty float x\n";
  h += "property " + colour_type + " red\nproperty float y\nproperty " + colour_type + " green\n";
  h += "property " + colour_type + " blue\nproperty float z\n";
  if (alpha) h += "property " + colour_type + " alpha\n";
  h += "property float " + u + "\nproperty float " + v + "\nelement face 2\n";
  if (texcoord) h += "property list uchar float texcoord\n";  // before the indices
  h += "property list uchar int vertex_indices\nend_header\n";
  PlyBody b(format);
  const double full = colour_type == "uchar" ? 255 : (colour_type == "ushort" ? 65535 : 1);
  for (int i = 0; i < 4; ++i) {
    b.put("float", pos[i].x);
    b.put(colour_type, full * (i == 1));
    b.put("float", pos[i].y);
    b.put(colour_type, (full == 1 ? 0.5 : std::round(full * 0.5)) * (i >= 2));
    b.put(colour_type, full * (i == 3));
    b.put("float", pos[i].z);
    if (alpha) b.put(colour_type, full * (i != 0));
    b.put("float", 0.25 * i);
    b.put("float", 1.0 - 0.25 * i);
    b.end_element();
  }
  const int faces[2][3] = {{0, 1, 2}, {0, 2, 3}};
  for (int f = 0; f < 2; ++f) {
    if (texcoord) {
      b.put("uchar", 6);
      for (int k = 0; k < 3; ++k) {
        b.put("float", 10 * f + k);
        b.put("float", -0.5 * k);
      }
    }
    b.put("uchar", 3);
    for (int k = 0; k < 3; ++k) b.put("int", faces[f][k]);
    b.end_element();
  }
  return h + b.bytes();
}

TEST_F(TempFiles, PlyKeepsColoursAndTextureCoordinates) {
  struct Case {
    std::string format, colour_type;
    bool alpha;
    std::string uv_names;
  };
  for (const Case& c : {Case{"ascii", "uchar", false, "u v"}, Case{"binary_little_endian", "uchar", true, "s t"},
                        Case{"binary_big_endian", "ushort", true, "texture_u texture_v"},
                        Case{"binary_little_endian", "float", false, "texture_s texture_t"}}) {
    SCOPED_TRACE(c.format + " " + c.colour_type + " " + c.uv_names);
    Mesh m;
    MeshLoadReport r;
    ASSERT_TRUE(
        load_mesh(write("attr.ply", attribute_ply(c.format, c.colour_type, c.alpha, c.uv_names, false)), m, &r).ok());
    ASSERT_EQ(m.colors.size(), 4u);
    const float half =
        c.colour_type == "uchar" ? float(128.0 / 255.0) : (c.colour_type == "ushort" ? float(32768.0 / 65535.0) : 0.5f);
    EXPECT_EQ(m.colors[0], glm::vec4(0, 0, 0, c.alpha ? 0 : 1));
    EXPECT_EQ(m.colors[1], glm::vec4(1, 0, 0, 1));
    EXPECT_EQ(m.colors[2], glm::vec4(0, half, 0, 1));
    EXPECT_EQ(m.colors[3], glm::vec4(0, half, 1, 1));
    ASSERT_EQ(m.uvs.size(), 4u);
    EXPECT_EQ(m.uv_triangles, m.triangles);
    for (int i = 0; i < 4; ++i) EXPECT_EQ(m.uvs[i], glm::vec2(0.25f * i, 1 - 0.25f * i));
    EXPECT_EQ(r.uv_count, 4u);
    EXPECT_TRUE(r.has_colors);
  }
  // Per-corner texcoord lists win over the per-vertex pair, and fan like the corners.
  Mesh m;
  ASSERT_TRUE(
      load_mesh(write("texcoord.ply", attribute_ply("binary_little_endian", "uchar", false, "u v", true)), m).ok());
  ASSERT_EQ(m.uvs.size(), 6u);
  EXPECT_EQ(m.uv_triangles[0], uvec3(0, 1, 2));
  EXPECT_EQ(m.uv_triangles[1], uvec3(3, 4, 5));
  EXPECT_EQ(m.uvs[4], glm::vec2(11, -0.5f));
  // Only some colour channels: none kept, and said.
  MeshLoadReport r;
  ASSERT_TRUE(load_mesh(write("small.ply", small_ply("ascii", Small().positions)), m, &r).ok());
  EXPECT_TRUE(m.colors.empty());
  EXPECT_NE(r.attributes_dropped.find("lacks one of red, green, blue"), std::string::npos) << r.attributes_dropped;
}

TEST(MeshIoValidate, Attributes) {
  Mesh m = tetrahedron();
  ASSERT_TRUE(validate_mesh(m).ok());
  Mesh bad = m;
  bad.uv_triangles = {{0, 0, 0}};
  bad.uvs = {{0, 0}};
  EXPECT_NE(validate_mesh(bad).message().find("UV triangles for"), std::string::npos);
  bad = m;
  bad.uvs = {{0, 0}};
  EXPECT_NE(validate_mesh(bad).message().find("no UV triangles"), std::string::npos);
  bad = m;
  bad.uvs = {{0, 0}, {1, 0}};
  bad.uv_triangles.assign(m.triangles.size(), uvec3(0, 1, 2));
  EXPECT_NE(validate_mesh(bad).message().find("refers to texture coordinate 2"), std::string::npos)
      << validate_mesh(bad).message();
  bad.uvs.push_back({std::numeric_limits<float>::infinity(), 0});
  EXPECT_NE(validate_mesh(bad).message().find("texture coordinate 2 is not finite"), std::string::npos);
  bad = m;
  bad.colors = {{1, 1, 1, 1}};
  EXPECT_NE(validate_mesh(bad).message().find("vertex colours for"), std::string::npos);
  bad.colors.assign(m.positions.size(), glm::vec4(1));
  EXPECT_TRUE(validate_mesh(bad).ok());
  bad.colors[1].g = std::numeric_limits<float>::quiet_NaN();
  EXPECT_NE(validate_mesh(bad).message().find("vertex 1 has a non-finite colour"), std::string::npos);
}

// What the writer writes, the reader reads: float UVs exactly, colours to the writer's 1/255.
TEST_F(TempFiles, WrittenAttributesReadBack) {
  SurfaceMesh s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  s.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  s.normals.assign(4, vec3(0, 0, 1));
  s.uvs = {{0.1f, 0.2f}, {0.3f, 0.4f}, {0.5f, 0.6f}, {0.7f, 0.8f}};
  s.colors = {{0, 0.2f, 0.4f, 1}, {1, 0.5f, 0, 0.6f}, {0.3f, 0.3f, 0.3f, 1}, {0.9f, 0.1f, 0.7f, 0}};
  for (const char* name : {"out.ply", "out.obj"}) {
    SCOPED_TRACE(name);
    const std::string path = (dir_ / name).string();
    ASSERT_TRUE(write_surface_mesh(path, s).ok());
    Mesh m;
    ASSERT_TRUE(load_mesh(path, m).ok());
    ASSERT_EQ(m.uv_triangles.size(), s.triangles.size());
    ASSERT_EQ(m.colors.size(), 4u);
    const bool ply = std::string(name) == "out.ply";
    for (size_t t = 0; t < s.triangles.size(); ++t)
      for (int k = 0; k < 3; ++k) EXPECT_EQ(m.uvs[m.uv_triangles[t][k]], s.uvs[s.triangles[t][k]]);
    for (size_t i = 0; i < 4; ++i)
      for (int c = 0; c < (ply ? 4 : 3); ++c)
        EXPECT_NEAR(m.colors[i][c], s.colors[i][c], ply ? 0.5 / 255 + 1e-6 : 0) << "vertex " << i << " channel " << c;
  }
}

// Issue 15, items 10 and 11: a UTF-8 byte-order mark is skipped (it hid the first vertex), and
// OBJ statements nobody knows are counted and reported, not silently skipped.
TEST_F(TempFiles, ByteOrderMarkIsSkipped) {
  const std::string bom = "\xEF\xBB\xBF";
  Mesh m;
  ASSERT_TRUE(load_mesh(write("bom.obj", bom + "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"), m).ok());
  expect_mesh(m, {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}});
  ASSERT_TRUE(load_mesh(write("bom.ply", bom + small_ply("ascii", Small().positions)), m).ok());
  expect_mesh(m, Small().positions, Small().triangles);
}

TEST_F(TempFiles, UnknownObjStatementsAreReported) {
  Mesh m;
  MeshLoadReport r;
  ASSERT_TRUE(load_mesh(write("unknown.obj",
                              "# a comment\nv 0 0 0\nvv 1 1 1\nv 1 0 0\nv 0 1 0\ng group\nvn 0 0 1\n"
                              "this is garbage 1 2 3\nusemtl m\nf 1 2 3\n"),
                        m, &r)
                  .ok());
  expect_mesh(m, {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}});
  EXPECT_NE(r.warnings.find("2 lines with an unknown statement"), std::string::npos) << r.warnings;
  EXPECT_NE(r.warnings.find("line 3: 'vv'"), std::string::npos) << r.warnings;
  ASSERT_TRUE(load_mesh(write("known.obj", "o x\ns 1\nv 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\np 1\nf 1 2 3\n"), m, &r).ok());
  EXPECT_TRUE(r.warnings.empty()) << r.warnings;
}

// ---------------------------------------------------------------------------------------
// Reading within limits (issue 15, item 3): a stream that never ends, a file beyond memory.

// /dev/zero under a mesh file's name grew the read buffer until memory ran out, and then stopped
// at the line limit; /dev/urandom (newlines often enough) was read to the end of memory. Both
// now stop at their first control byte, naming the file and the line. The PLY header is text too.
TEST_F(TempFiles, StreamsThatAreNotTextStopAtTheirFirstBytes) {
  for (const char* name : {"zero.obj", "zero.ply", "random.obj", "random.ply"}) {
    const std::string path = (dir_ / name).string();
    fs::create_symlink(name[0] == 'z' ? "/dev/zero" : "/dev/urandom", path);
    Mesh m;
    const Status s = load_mesh(path, m);
    EXPECT_EQ(s.code(), StatusCode::kParseError) << s.message();
    EXPECT_EQ(s.message().rfind(path + ":", 0), 0u) << s.message();
    EXPECT_NE(s.message().find(": binary content (byte 0x"), std::string::npos) << s.message();
  }
  // A terminal colour's escape in a comment is found in text files (the OBJ reader skips comments).
  const std::string coloured = write("coloured.obj",
                                     "# \x1b[1mtetrahedron\x1b[0m\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"
                                     "v 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  Mesh tet;
  const Status loaded = load_mesh(coloured, tet);
  EXPECT_TRUE(loaded.ok()) << loaded.message();
  EXPECT_EQ(tet.triangles.size(), 4u);
  // A control byte after the first 64 KiB is left to the reader (the OBJ reader names its line).
  const std::string late = write("late.obj", std::string(70000, '\n') + "v 0 0 0\x01\n");
  Mesh m;
  const Status s = load_mesh(late, m);
  EXPECT_EQ(s.message().rfind(late + ":70001: binary content (byte 0x01)", 0), 0u) << s.message();
}

// A binary PLY body is not text: a long run without a newline byte there is data, while the same
// run in an ASCII body is a line (ReadLimits::text_end, from the header's format line).
TEST_F(TempFiles, LineLimitStopsAtABinaryBody) {
  ReadLimits limits;
  limits.max_line_bytes = 64;
  limits.text_end = [](std::string_view head) -> size_t {
    const size_t end = head.find("END\n");
    return end == std::string_view::npos ? kTextNotEnded : end + 4;
  };
  std::string data;
  const std::string body(1000, 'b');
  EXPECT_TRUE(read_file(write("binary.bin", "header\nEND\n" + body), data, limits).ok());
  EXPECT_EQ(data, "header\nEND\n" + body);
  limits.text_end = nullptr;
  const std::string text = write("text.txt", "header\nEND\n" + body);
  const Status s = read_file(text, data, limits);
  EXPECT_EQ(s.code(), StatusCode::kParseError);
  EXPECT_EQ(s.message().rfind(text + ":3: line longer than 64 B", 0), 0u) << s.message();
  // The limit is on each line, a complete one too, wherever the buffer's chunks end.
  const std::string long_line = write("long.txt", "a\n" + std::string(65, 'x') + "\nb\n");
  EXPECT_EQ(read_file(long_line, data, limits).message().rfind(long_line + ":2: line longer", 0), 0u);
  limits.max_line_bytes = 65;
  EXPECT_TRUE(read_file(long_line, data, limits).ok());
}

// The same for load_mesh's PLY reader: a binary body of more than the line limit without a
// newline byte (6 million vertices at the origin: float zeros) loads, the header being the only
// text it checks.
TEST_F(TempFiles, BinaryPlyBodyIsNotLineChecked) {
  constexpr uint32_t kVertices = 6'000'000;
  ASSERT_GT(uint64_t(kVertices) * 12, kMaxMeshLineBytes);
  std::string file = ply_header("binary_little_endian", int(kVertices), 1);
  const size_t header = file.size();
  file.resize(header + size_t(kVertices) * 12, '\0');
  const float one = 1.0f;                        // 0x3f800000: no newline byte either
  std::memcpy(&file[header + 12], &one, 4);      // vertex 1 = (1, 0, 0)
  std::memcpy(&file[header + 24 + 4], &one, 4);  // vertex 2 = (0, 1, 0)
  const char face[13] = {3, 0, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0};
  file.append(face, sizeof face);
  ASSERT_EQ(file.find('\n', header), std::string::npos);
  Mesh m;
  const Status s = load_mesh(write("long_body.ply", file), m);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(m.positions.size(), kVertices);
  EXPECT_EQ(m.positions[2], vec3(0, 1, 0));
  EXPECT_EQ(m.triangles, std::vector<uvec3>{uvec3(0, 1, 2)});
}

// The total: a stream read stops one byte past the limit (the memory available by default), and a
// regular file larger than it is refused before any of it is read.
TEST_F(TempFiles, ReadStopsAtTheSizeLimit) {
  ReadLimits limits;
  limits.max_line_bytes = std::numeric_limits<uint64_t>::max();
  limits.max_bytes = 1 << 20;
  limits.text_end = [](std::string_view) { return size_t(0); };  // binary from the start: no text check
  std::string data;
  Status s = read_file("/dev/zero", data, limits);
  EXPECT_EQ(s.code(), StatusCode::kOutOfMemory);
  EXPECT_EQ(s.message(),
            "/dev/zero: more than the read limit of 1.0 MiB read without reaching the end (a stream "
            "that does not end?)");
  limits.max_bytes = 100;
  const std::string big = write("big.txt", std::string(101, 'x'));
  s = read_file(big, data, limits);
  EXPECT_EQ(s.code(), StatusCode::kOutOfMemory);
  EXPECT_EQ(s.message(), big + ": the file is 101 B, more than the read limit of 100 B");
  limits.max_bytes = 101;
  EXPECT_TRUE(read_file(big, data, limits).ok());
  EXPECT_EQ(data.size(), 101u);
}

TEST(Memory, AvailableAndChecks) {
  const uint64_t available = available_memory_bytes();
  EXPECT_GT(available, 0u);
  // A size no machine has is refused, saying what it would need and what there is.
  const Status s = check_memory(saturating_product(uint64_t(1) << 40, uint64_t(1) << 40), "the test's array");
  if (available != kUnknownMemory) {
    EXPECT_EQ(s.code(), StatusCode::kOutOfMemory);
    EXPECT_EQ(s.message().rfind("the test's array would need 16 EiB or more of memory, more than the ", 0), 0u)
        << s.message();
  }
  EXPECT_TRUE(check_memory(1, "a byte").ok());
  EXPECT_EQ(saturating_product(uint64_t(1) << 32, uint64_t(1) << 32), std::numeric_limits<uint64_t>::max());
  EXPECT_EQ(saturating_product(uint64_t(1) << 31, uint64_t(1) << 32), uint64_t(1) << 63);
  EXPECT_EQ(saturating_sum(std::numeric_limits<uint64_t>::max(), 1), std::numeric_limits<uint64_t>::max());
  EXPECT_EQ(memory_size_text(0), "0 B");
  EXPECT_EQ(memory_size_text(1023), "1023 B");
  EXPECT_EQ(memory_size_text(1536), "1.5 KiB");
  EXPECT_EQ(memory_size_text(uint64_t(3) << 30), "3.0 GiB");
  EXPECT_EQ(memory_size_text(uint64_t(5) << 40), "5.0 TiB");
}

}  // namespace
}  // namespace gwnrt
