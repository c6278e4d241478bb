// The PLY reader: the small reference mesh in the three encodings with every scalar type, integer
// coordinates, and colours and texture coordinates as vertex properties or per-corner lists.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "gwnrt/io/mesh_io.h"
#include "io_fixtures.h"
#include "mesh_files.h"

namespace gwnrt {
namespace {

using test::PlyBody;
using test::PlyTypes;
using test::Small;
using test::small_ply;

// ---------------------------------------------------------------------------------------
// One mesh, every encoding

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

// A header that declares fewer elements than the file holds is refused in every encoding (a
// binary file had loaded as the partial mesh); a line break after binary data is not an element.
TEST_F(TempFiles, PlyWithMoreDataThanDeclaredIsRefused) {
  const Small ref;
  int n = 0;
  for (const std::string format : {"ascii", "binary_little_endian", "binary_big_endian"}) {
    SCOPED_TRACE(format);
    std::string text = small_ply(format, ref.positions);
    const size_t at = text.find("element edge 2");
    ASSERT_NE(at, std::string::npos);
    Mesh m;
    ASSERT_TRUE(load_mesh(write("whole" + std::to_string(n++) + ".ply", text), m).ok());
    if (format != "ascii") {
      ASSERT_TRUE(load_mesh(write("newline" + std::to_string(n++) + ".ply", text + "\n"), m).ok());
      expect_mesh(m, ref.positions, ref.triangles);
      const Status junk = load_mesh(write("junk" + std::to_string(n++) + ".ply", text + std::string("\x01\0", 2)), m);
      EXPECT_EQ(junk.code(), StatusCode::kParseError);
      EXPECT_NE(junk.message().find("2 bytes of data after the last element declared"), std::string::npos)
          << junk.message();
    }
    text.replace(at, 14, "element edge 1");  // the second edge, two ints, is undeclared
    const std::string file = write("short" + std::to_string(n++) + ".ply", text);
    const Status s = load_mesh(file, m);
    EXPECT_EQ(s.code(), StatusCode::kParseError) << s.message();
    EXPECT_NE(s.message().find(file), std::string::npos) << s.message();
    EXPECT_NE(s.message().find("after the last element declared in the header"), std::string::npos) << s.message();
    if (format != "ascii") {
      EXPECT_NE(s.message().find("8 bytes of data"), std::string::npos) << s.message();
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

}  // namespace
}  // namespace gwnrt
