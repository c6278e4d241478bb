// Broken mesh files: a table of inputs each reader must refuse with a message that names the
// file, the line or element and the problem; random bytes; and every prefix and random corruption
// of valid files, which may load or fail but never crash.
#include <gtest/gtest.h>

#include <limits>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include "gwnrt/io/mesh_io.h"
#include "io_fixtures.h"
#include "mesh_files.h"

namespace gwnrt {
namespace {

using test::kSmallObj;
using test::PlyBody;
using test::Small;
using test::small_ply;

// ---------------------------------------------------------------------------------------
// Broken inputs

struct BadCase {
  std::string name;  // file name, extension chooses the reader
  std::string content;
  StatusCode code;
  std::vector<std::string> fragments;  // each must appear in the message
};
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

}  // namespace
}  // namespace gwnrt
