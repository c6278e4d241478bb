// STL, read and written: binary (recognised by its size, whatever its header says) and ASCII,
// checked corner by corner against the mesh they were made from and against Assimp, an
// independent reader, on the real STL files in data/realworld; the errors, each naming the file
// and the facet or line; and welding by position, exact and within a tolerance, against a brute
// force over all pairs.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#if GWNRT_HAVE_ASSIMP
#include <assimp/scene.h>
#include <assimp/Importer.hpp>
#endif

#include "gwnrt/geometry/boundary.h"
#include "gwnrt/geometry/surface_mesh.h"
#include "gwnrt/geometry/weld.h"
#include "gwnrt/io/mesh_io.h"
#include "gwnrt/io/mesh_writer.h"
#include "gwnrt/query/batch.h"
#include "io_fixtures.h"
#include "test_util.h"

namespace gwnrt {
namespace {

using test::data_path;
using test::num;

constexpr const char* kRealStl[] = {"realworld/kuka_kr10r1100sixx_visual_base_link.stl",
                                    "realworld/kuka_kr150r3100_2_visual_base_link.stl",
                                    "realworld/motoman_motomini_visual_link_1_s.stl"};

using test::read_bytes;

// A binary STL of the triangles given by their corners, with any 80-byte header.
std::string binary_stl(const std::vector<std::array<vec3, 3>>& facets, std::string header = "test") {
  header.resize(80, ' ');
  std::string s = header;
  auto u32 = [&](uint32_t v) {
    for (int k = 0; k < 4; ++k) s += char((v >> (8 * k)) & 0xff);
  };
  u32(uint32_t(facets.size()));
  for (const auto& f : facets) {
    for (int k = 0; k < 3; ++k) u32(0);  // a normal readers ignore
    for (const vec3& c : f)
      for (int k = 0; k < 3; ++k) u32(std::bit_cast<uint32_t>(c[k]));
    s += std::string(2, '\0');
  }
  return s;
}

std::vector<std::array<vec3, 3>> facets_of(const Mesh& m) {
  std::vector<std::array<vec3, 3>> f;
  for (const uvec3& t : m.triangles) f.push_back({m.positions[t.x], m.positions[t.y], m.positions[t.z]});
  return f;
}

// Every triangle's corners, in order, are those given (bit for bit).
void expect_facets(const Mesh& m, const std::vector<std::array<vec3, 3>>& want) {
  ASSERT_EQ(m.triangles.size(), want.size());
  for (size_t t = 0; t < want.size(); ++t)
    for (int k = 0; k < 3; ++k)
      ASSERT_TRUE(std::memcmp(&m.positions[m.triangles[t][k]], &want[t][k], sizeof(vec3)) == 0)
          << "triangle " << t << " corner " << k;
}

size_t distinct_positions(const std::vector<std::array<vec3, 3>>& facets) {
  std::vector<std::array<uint32_t, 3>> keys;
  for (const auto& f : facets)
    for (const vec3& c : f)
      keys.push_back({std::bit_cast<uint32_t>(c.x), std::bit_cast<uint32_t>(c.y), std::bit_cast<uint32_t>(c.z)});
  std::sort(keys.begin(), keys.end());
  return size_t(std::unique(keys.begin(), keys.end()) - keys.begin());
}

class Stl : public TempFiles {
 protected:
  Status load(const std::string& name, const std::string& bytes, Mesh& m, MeshLoadReport* r = nullptr) {
    return load_mesh(write(name, bytes), m, r, MeshLoadOptions{.summarize_weld = true});
  }
  void expect_error(const std::string& name, const std::string& bytes, const std::vector<std::string>& parts) {
    Mesh m;
    const Status s = load(name, bytes, m);
    ASSERT_FALSE(s.ok()) << name;
    EXPECT_NE(s.message().find(name), std::string::npos) << s.message();
    for (const std::string& p : parts) EXPECT_NE(s.message().find(p), std::string::npos) << s.message();
  }
};

TEST_F(Stl, BinaryGivesTheFacetsCornerForCornerWithIdenticalCornersOneVertex) {
  const std::vector<std::array<vec3, 3>> facets = facets_of(test::load_test_mesh("bunny.obj"));
  Mesh m;
  MeshLoadReport r;
  ASSERT_TRUE(load("bunny.stl", binary_stl(facets), m, &r).ok());
  expect_facets(m, facets);
  EXPECT_EQ(r.format, "stl-binary");
  EXPECT_EQ(r.file_vertices, 3 * facets.size());
  EXPECT_EQ(m.positions.size(), distinct_positions(facets));
  // The bunny is closed: welded, its STL has no boundary, as the indexed OBJ has none.
  EXPECT_EQ(r.weld.boundary_by_position, 0u);
  EXPECT_EQ(r.weld.boundary_by_index, 0u);
}

// A binary file whose header begins "solid" (many exporters write their name there) is binary
// when its size says so.
TEST_F(Stl, BinaryHeaderBeginningWithSolidIsReadAsBinary) {
  const std::vector<std::array<vec3, 3>> facets = facets_of(test::load_test_mesh("teapot.obj"));
  for (const char* header : {"solid teapot", "solid", "  SOLID x"}) {
    Mesh m;
    MeshLoadReport r;
    const Status s = load("teapot.stl", binary_stl(facets, header), m, &r);
    ASSERT_TRUE(s.ok()) << header << ": " << s.message();
    EXPECT_EQ(r.format, "stl-binary");
    expect_facets(m, facets);
  }
}

std::string ascii_stl(const std::vector<std::array<vec3, 3>>& facets, size_t solids, const char* eol) {
  std::string s;
  const size_t per = (facets.size() + solids - 1) / solids;
  for (size_t f = 0; f < facets.size(); ++f) {
    if (f % per == 0) s += std::string("solid part ") + std::to_string(f / per) + eol;
    // The spec's lowercase, and the uppercase some old exporters write.
    const bool upper = f % 7 == 3;
    s += std::string(upper ? "  FACET NORMAL 0 0 1" : "  facet normal 0 0 1") + eol;
    s += std::string(upper ? "    OUTER LOOP" : "    outer loop") + eol;
    for (const vec3& c : facets[f])
      s += std::string(upper ? "      VERTEX " : "      vertex ") + num(c.x) + " " + num(c.y) + " " + num(c.z) + eol;
    s += std::string("    endloop") + eol + "  endfacet" + eol;
    if (f % per == per - 1 || f + 1 == facets.size()) s += std::string("endsolid part") + eol;
  }
  return s;
}

TEST_F(Stl, AsciiGivesWhatBinaryGives) {
  const std::vector<std::array<vec3, 3>> facets = facets_of(test::load_test_mesh("bunny_holes.obj"));
  Mesh bin, text;
  ASSERT_TRUE(load("b.stl", binary_stl(facets), bin).ok());
  for (const char* eol : {"\n", "\r\n"}) {
    for (size_t solids : {1, 3}) {
      MeshLoadReport r;
      const Status s = load("a.stl", ascii_stl(facets, solids, eol), text, &r);
      ASSERT_TRUE(s.ok()) << s.message();
      EXPECT_EQ(r.format, "stl-ascii");
      expect_facets(text, facets);
      EXPECT_EQ(text.positions, bin.positions);
      EXPECT_EQ(text.triangles, bin.triangles);
      // bunny_holes' two holes: 52 boundary edges, welded; every edge by the file's own corners.
      EXPECT_EQ(r.weld.boundary_by_position, 52u);
      EXPECT_EQ(r.weld.boundary_loops, 2u);
    }
  }
}

TEST_F(Stl, AsciiPolygonsAreFanned) {
  const std::string text =
      "solid quad\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\nvertex 0 1 0\n"
      "endloop\nendfacet\nendsolid\n";
  Mesh m;
  MeshLoadReport r;
  ASSERT_TRUE(load("quad.stl", text, m, &r).ok());
  EXPECT_EQ(r.polygons_fanned, 1u);
  expect_mesh(m, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 2, 3}});
}

TEST_F(Stl, ErrorsNameTheFileAndTheFacetOrLine) {
  const std::vector<std::array<vec3, 3>> facets = {{vec3(0, 0, 0), vec3(1, 0, 0), vec3(0, 1, 0)},
                                                   {vec3(0, 0, 1), vec3(1, 0, 1), vec3(0, 1, 1)}};
  const std::string bin = binary_stl(facets);
  expect_error("truncated.stl", bin.substr(0, bin.size() - 7), {"2 facets", "184 bytes", "177", "truncated"});
  expect_error("trailing.stl", bin + "xyz", {"2 facets", "184 bytes", "187"});
  std::vector<std::array<vec3, 3>> nan = facets;
  nan[1][2].y = std::nanf("");
  expect_error("nan.stl", binary_stl(nan), {"facet 1", "corner 2", "non-finite"});
  expect_error("short.stl", "abc", {"3 bytes", "neither"});
  expect_error("none.stl", binary_stl({}), {"no triangles"});
  expect_error("empty_solid.stl", "solid x\nendsolid x\n", {"no triangles"});

  const std::string head = "solid t\nfacet normal 0 0 1\nouter loop\n";
  expect_error("ends.stl", head + "vertex 0 0 0\nvertex 1 0 0\n", {":5:", "ends inside facet 0", "line 2"});
  expect_error("number.stl", head + "vertex 0 0 0\nvertex 1 0x 0\n", {":5:", "'0x'", "facet 0"});
  expect_error("two.stl", head + "vertex 0 0 0\nvertex 1 0 0\nendloop\nendfacet\nendsolid\n",
               {":6:", "has 2 vertices"});
  expect_error("inf.stl", head + "vertex 0 0 0\nvertex 1 1e39 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid\n",
               {":5:", "facet 0, corner 1", "non-finite"});
  expect_error("keyword.stl", head + "vertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendface\n",
               {":8:", "expected 'endfacet'", "'endface'"});
  expect_error("nosolid.stl", "solid t\nendsolid\nfacet normal 0 0 1\n", {":3:", "expected 'solid'"});
  expect_error("binary_byte.stl", "solid t\nfacet normal 0 0 1\nouter\x01 loop\n", {":3:", "byte 0x01"});
  // A header that begins "solid", then a facet count in binary: the size decides, and is wrong.
  expect_error("solid_truncated.stl", binary_stl(facets, "solid x").substr(0, 150), {"2 facets", "184 bytes"});
}

TEST_F(Stl, WriterWritesWhatTheReaderAndAssimpRead) {
  const Mesh bunny = test::load_test_mesh("bunny_holes.obj");
  SurfaceMesh out;
  out.positions = bunny.positions;
  out.triangles = bunny.triangles;
  const std::string path = (dir_ / "out.stl").string();
  ASSERT_TRUE(write_surface_mesh(path, out).ok());
  const std::string bytes = read_bytes(path);
  ASSERT_EQ(bytes.size(), 84 + 50 * bunny.triangles.size());
  EXPECT_NE(bytes.substr(0, 5), "solid");  // would make some readers try ASCII
  Mesh back;
  ASSERT_TRUE(load_mesh(path, back).ok());
  expect_facets(back, facets_of(bunny));
  // The stored normals: the corners' unit normal.
  for (size_t t = 0; t < bunny.triangles.size(); t += 97) {
    float n[3];
    std::memcpy(n, bytes.data() + 84 + 50 * t, 12);
    const vec3 a = bunny.positions[bunny.triangles[t].x], b = bunny.positions[bunny.triangles[t].y],
               c = bunny.positions[bunny.triangles[t].z];
    const vec3 want = glm::normalize(glm::cross(b - a, c - a));
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(n[k], want[k], 1e-5f) << "triangle " << t;
  }
  // STL keeps float coordinates only: a recentred mesh would be rounded where it lies.
  MeshWriteOptions far;
  far.origin = dvec3(5e5, 4e6, 0);
  const Status s = write_surface_mesh((dir_ / "far.stl").string(), out, far);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("write .ply or .obj"), std::string::npos) << s.message();
}

#if GWNRT_HAVE_ASSIMP
// Assimp (no post-processing: a corner per face corner) gives the corners of every facet of the
// real STL files, in the file's order: ours must be the same floats.
std::vector<std::array<vec3, 3>> assimp_facets(const std::string& path) {
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(path, 0);
  std::vector<std::array<vec3, 3>> facets;
  EXPECT_NE(scene, nullptr) << importer.GetErrorString();
  if (!scene) return facets;
  for (unsigned mi = 0; mi < scene->mNumMeshes; ++mi) {
    const aiMesh* am = scene->mMeshes[mi];
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
      std::array<vec3, 3> c;
      EXPECT_EQ(am->mFaces[f].mNumIndices, 3u);
      for (int k = 0; k < 3; ++k) {
        const aiVector3D& v = am->mVertices[am->mFaces[f].mIndices[k]];
        c[k] = vec3(v.x, v.y, v.z);
      }
      facets.push_back(c);
    }
  }
  return facets;
}

TEST_F(Stl, RealFilesReadAsAssimpReadsThem) {
  for (const char* name : kRealStl) {
    SCOPED_TRACE(name);
    Mesh m;
    MeshLoadReport r;
    ASSERT_TRUE(load_mesh(data_path(name), m, &r).ok());
    EXPECT_EQ(r.format, "stl-binary");
    const std::vector<std::array<vec3, 3>> want = assimp_facets(data_path(name));
    expect_facets(m, want);
    EXPECT_EQ(m.positions.size(), distinct_positions(want));
  }
  // And what our writer wrote.
  const Mesh teapot = test::load_test_mesh("teapot.obj");
  SurfaceMesh out;
  out.positions = teapot.positions;
  out.triangles = teapot.triangles;
  const std::string path = (dir_ / "teapot.stl").string();
  ASSERT_TRUE(write_surface_mesh(path, out).ok());
  EXPECT_EQ(assimp_facets(path), facets_of(teapot));
}
#endif

// ---------------------------------------------------------------------------------------
// Welding

TEST(Weld, ASoupWeldedIsTheMeshItCameFrom) {
  for (const char* name : {"bunny.obj", "bunny_holes.obj", "teapot.obj"}) {
    SCOPED_TRACE(name);
    const Mesh mesh = test::load_test_mesh(name);
    Mesh soup;
    for (const uvec3& t : mesh.triangles) {
      const uint32_t base = uint32_t(soup.positions.size());
      for (int k = 0; k < 3; ++k) soup.positions.push_back(mesh.positions[t[k]]);
      soup.triangles.emplace_back(base, base + 1, base + 2);
    }
    const WeldSummary indexed = summarize_weld(mesh), welded = summarize_weld(soup);
    EXPECT_EQ(welded.vertices_used, 3 * mesh.triangles.size());
    EXPECT_EQ(welded.positions_used, indexed.positions_used);
    EXPECT_EQ(welded.boundary_by_index, 3 * mesh.triangles.size());  // every edge a soup's own
    EXPECT_EQ(welded.boundary_by_position, indexed.boundary_by_position);
    EXPECT_EQ(welded.boundary_loops, indexed.boundary_loops);
    EXPECT_EQ(extract_boundary(soup).segment_count(), extract_boundary(mesh).segment_count());
    // Nothing moved: w by the exact method is the indexed mesh's at random points.
    const GwnModel a = test::build_model(mesh), b = test::build_model(soup);
    test::Random rng(7);
    std::vector<vec3> points(500);
    for (vec3& p : points) p = rng.in_box(a.bounds());
    std::vector<PointResult> ra(points.size()), rb(points.size());
    QueryRequest q;
    q.method = WindingMethod::kCrossing;
    ASSERT_TRUE(evaluate_points(a, points, q, ra).ok());
    ASSERT_TRUE(evaluate_points(b, points, q, rb).ok());
    for (size_t i = 0; i < points.size(); ++i) EXPECT_NEAR(ra[i].w, rb[i].w, 1e-5f) << "point " << i;
  }
}

// A position shared by used vertices counts once, also where the group's first vertex is one no
// triangle uses.
TEST(Weld, PositionsAreCountedOncePerGroup) {
  Mesh m;
  m.positions = {{0, 0, 0}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 0}, {0, 0, 1}};
  m.triangles = {{1, 2, 3}, {4, 3, 5}};  // vertex 0 unused; 1 and 4 share its position
  const WeldSummary w = summarize_weld(m);
  EXPECT_EQ(w.vertices_used, 5u);
  EXPECT_EQ(w.positions_used, 4u);
}

// weld_within against every pair: the groups are those that chains of pairs within the distance
// make, no more and no fewer, and each vertex ends on its group's lowest-numbered member.
TEST(Weld, WithinADistanceMergesExactlyThePairsWithinIt) {
  std::mt19937 g(3);
  std::uniform_real_distribution<float> u(0.0f, 1.0f), jitter(-0.004f, 0.004f);
  Mesh m;
  for (int i = 0; i < 600; ++i) {
    const vec3 p(u(g), u(g), u(g));
    m.positions.push_back(p);
    if (i % 3 == 0) m.positions.push_back(p + vec3(jitter(g), jitter(g), jitter(g)));  // a near twin
  }
  for (uint32_t i = 0; i + 2 < m.positions.size(); i += 3) m.triangles.emplace_back(i, i + 1, i + 2);
  const Mesh before = m;
  const double d = 0.005;
  const size_t moved = weld_within(m, d);
  EXPECT_GT(moved, 100u);
  // Groups by the brute force: union of all pairs within d.
  const size_t n = before.positions.size();
  std::vector<uint32_t> group(n);
  std::iota(group.begin(), group.end(), 0u);
  std::function<uint32_t(uint32_t)> find = [&](uint32_t i) { return group[i] == i ? i : group[i] = find(group[i]); };
  for (uint32_t i = 0; i < n; ++i)
    for (uint32_t j = 0; j < i; ++j) {
      const dvec3 a(before.positions[i]), b(before.positions[j]);
      if (glm::dot(a - b, a - b) <= d * d) {
        const uint32_t x = find(i), y = find(j);
        group[std::max(x, y)] = std::min(x, y);
      }
    }
  size_t want_moved = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t root = find(i);
    EXPECT_EQ(m.positions[i], before.positions[root]) << "vertex " << i;
    want_moved += before.positions[root] != before.positions[i];
  }
  EXPECT_EQ(moved, want_moved);
}

TEST(Weld, ToleranceClosesTheCracksOfARealStl) {
  Mesh m;
  MeshLoadReport exact, tolerant;
  const std::string path = data_path("realworld/kuka_kr10r1100sixx_visual_base_link.stl");
  ASSERT_TRUE(load_mesh(path, m, &exact, MeshLoadOptions{.summarize_weld = true}).ok());
  EXPECT_EQ(exact.weld.boundary_by_position, 182u);
  EXPECT_EQ(exact.tolerance_welded, 0u);
  MeshLoadOptions o;
  o.weld_tolerance = 1e-6;
  o.summarize_weld = true;
  Mesh welded;
  ASSERT_TRUE(load_mesh(path, welded, &tolerant, o).ok());
  EXPECT_GT(tolerant.tolerance_welded, 0u);
  EXPECT_EQ(tolerant.weld.boundary_by_position, 0u);
  // Each moved vertex moved by at most the tolerance (no chains here), triangles otherwise the same.
  ASSERT_EQ(welded.triangles, m.triangles);
  dvec3 lo(INFINITY), hi(-INFINITY);
  for (const vec3& p : m.positions) {
    lo = glm::min(lo, dvec3(p));
    hi = glm::max(hi, dvec3(p));
  }
  const double diagonal = glm::length(hi - lo);
  for (size_t v = 0; v < m.positions.size(); ++v)
    EXPECT_LE(glm::length(dvec3(welded.positions[v]) - dvec3(m.positions[v])), 1e-6 * diagonal) << "vertex " << v;
  // The bunny has no vertices that close: nothing moves.
  Mesh bunny;
  MeshLoadReport r;
  ASSERT_TRUE(load_mesh(data_path("bunny.obj"), bunny, &r, o).ok());
  EXPECT_EQ(r.tolerance_welded, 0u);
}

TEST_F(Stl, WeldToleranceOutsideItsRangeIsRefused) {
  for (double t : {-1e-3, 0.5, double(NAN)}) {
    MeshLoadOptions o;
    o.weld_tolerance = t;
    Mesh m;
    const Status s = load_mesh(data_path("bunny.obj"), m, nullptr, o);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << t;
    EXPECT_NE(s.message().find("weld tolerance"), std::string::npos) << s.message();
  }
}

}  // namespace
}  // namespace gwnrt
