// The OBJ reader: the small reference mesh with every statement a reader must tolerate, texture
// coordinates and vertex colours (kept, or dropped where some elements lack them), a byte-order
// mark, and statements it does not know, which it reports.
#include <gtest/gtest.h>

#include <string>

#include "gwnrt/io/mesh_io.h"
#include "io_fixtures.h"
#include "mesh_files.h"

namespace gwnrt {
namespace {

using test::kSmallObj;
using test::Small;
using test::small_ply;
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

// A UTF-8 byte-order mark is skipped (it hid the first vertex), and
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

}  // namespace
}  // namespace gwnrt
