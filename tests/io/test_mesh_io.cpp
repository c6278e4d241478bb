// load_mesh, the front of the OBJ and PLY readers: the bundled files, the same mesh in both
// formats, the reader chosen by the extension, files that are not there or not files,
// degenerate triangles kept and counted, recentring of far-off meshes (MeshLoadOptions::recentre),
// and what the writers write read back.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "gwnrt/geometry/mesh.h"
#include "gwnrt/io/mesh_io.h"
#include "gwnrt/io/mesh_writer.h"
#include "gwnrt/model/model.h"
#include "gwnrt/query/batch.h"
#include "io_fixtures.h"
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

TEST_F(TempFiles, ExtensionIsCaseInsensitive) {
  Mesh m;
  EXPECT_TRUE(load_mesh(write("SMALL.OBJ", kSmallObj), m).ok());
  EXPECT_TRUE(load_mesh(write("SMALL.Ply", small_ply("ascii", Small().positions)), m).ok());
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

TEST_F(TempFiles, FileProblems) {
  Mesh m;
  const std::string missing = (dir_ / "does_not_exist.obj").string();
  Status s = load_mesh(missing, m);
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_NE(s.message().find(missing), std::string::npos) << s.message();

  s = load_mesh(write("mesh.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"), m);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("'.off'"), std::string::npos) << s.message();

  s = load_mesh(write("no_extension", kSmallObj), m);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);

  fs::create_directories(dir_ / "folder.obj");
  s = load_mesh((dir_ / "folder.obj").string(), m);
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_NE(s.message().find("directory"), std::string::npos) << s.message();
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

}  // namespace
}  // namespace gwnrt
