// Small valid mesh files as text, for the tests that read meshes (io/) and for the
// generated hostile inputs made from them (io/mesh_mutations.h): the small reference mesh as
// OBJ with every statement a reader must tolerate, and as PLY in every encoding with distractions;
// and the temporary directory those tests write them to.
#pragma once

#include <algorithm>
#include <bit>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include <gtest/gtest.h>

#include "gwnrt/base/hd.h"

namespace gwnrt::test {

// Shortest text that reads back to the same float, so text formats round-trip exactly.
inline std::string num(float v) {
  char buf[32];
  return std::string(buf, std::to_chars(buf, buf + sizeof buf, v).ptr);
}

inline std::string num(double v) {
  char buf[40];
  return std::string(buf, std::to_chars(buf, buf + sizeof buf, v).ptr);
}

// The small reference mesh: a triangle, a quad, a pentagon and another triangle.

struct Small {
  std::vector<vec3> positions = {{0, 0, 0},      {1.5f, 0, 0},     {1.5f, 2.25f, 0}, {0, 2.25f, -0.75f},
                                 {-1, 1, 3.25f}, {0.5f, -0.5f, 1}, {2, 1, -2.5f}};
  std::vector<std::vector<uint32_t>> faces = {{0, 1, 2}, {0, 2, 3, 4}, {1, 5, 6, 2, 3}, {4, 3, 6}};
  std::vector<uvec3> triangles = {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {1, 5, 6}, {1, 6, 2}, {1, 2, 3}, {4, 3, 6}};
};

// The small reference mesh's triangles as an STL: ASCII (a facet per triangle, the shortest text
// of each float) or binary (a header that begins "solid", as many exporters write).
inline std::string small_stl(bool binary) {
  const Small small;
  std::string s;
  if (!binary) {
    s = "solid small\n";
    for (const uvec3& t : small.triangles) {
      s += " facet normal 0 0 0\n  outer loop\n";
      for (int k = 0; k < 3; ++k) {
        const vec3& p = small.positions[t[k]];
        s += "   vertex " + num(p.x) + " " + num(p.y) + " " + num(p.z) + "\n";
      }
      s += "  endloop\n endfacet\n";
    }
    return s + "endsolid small\n";
  }
  s = "solid small (binary)";
  s.resize(80, ' ');
  auto word = [&](uint32_t v) {
    for (int k = 0; k < 4; ++k) s += char((v >> (8 * k)) & 0xff);
  };
  word(uint32_t(small.triangles.size()));
  for (const uvec3& t : small.triangles) {
    for (int k = 0; k < 3; ++k) word(0);
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) word(std::bit_cast<uint32_t>(small.positions[t[k]][a]));
    s += std::string(2, '\0');
  }
  return s;
}

// Writes PLY bodies in any of the three encodings with any scalar type.
class PlyBody {
 public:
  explicit PlyBody(std::string_view format) : ascii_(format == "ascii"), big_(format == "binary_big_endian") {}

  void put(std::string_view type, double v) {
    if (ascii_) {
      if (!text_.empty() && text_.back() != '\n') text_ += ' ';
      if (type == "float" || type == "float32") {
        text_ += num(static_cast<float>(v));
      } else if (type == "double" || type == "float64") {
        text_ += num(v);
      } else {
        text_ += std::to_string(static_cast<long long>(v));
      }
      return;
    }
    if (type == "char" || type == "int8") return bin(static_cast<int8_t>(v));
    if (type == "uchar" || type == "uint8") return bin(static_cast<uint8_t>(v));
    if (type == "short" || type == "int16") return bin(static_cast<int16_t>(v));
    if (type == "ushort" || type == "uint16") return bin(static_cast<uint16_t>(v));
    if (type == "int" || type == "int32") return bin(static_cast<int32_t>(v));
    if (type == "uint" || type == "uint32") return bin(static_cast<uint32_t>(v));
    if (type == "float" || type == "float32") return bin(static_cast<float>(v));
    if (type == "double" || type == "float64") return bin(v);
    ADD_FAILURE() << "bad type " << type;
  }

  void end_element() {
    if (ascii_) text_ += '\n';
  }

  const std::string& bytes() const { return text_; }

 private:
  template <class T>
  void bin(T x) {
    char b[sizeof(T)];
    std::memcpy(b, &x, sizeof(T));
    if (big_ != (std::endian::native == std::endian::big)) std::reverse(b, b + sizeof(T));
    text_.append(b, sizeof(T));
  }

  bool ascii_;
  bool big_;
  std::string text_;
};

struct PlyTypes {
  std::string xyz = "float";
  std::string count = "uchar";
  std::string index = "int";
  std::string list_name = "vertex_indices";
  std::string eol = "\n";
};

// The mesh with distractions: an unknown element before and after, extra scalar and list
// properties on vertices, and extra properties on both sides of the face list.
// `Position` is vec3 or dvec3 (coordinates written at the file's type, from double).
template <class Position>
std::string small_ply(std::string_view format, const std::vector<Position>& pos, const PlyTypes& t = {}) {
  const Small s;
  std::string h;
  auto line = [&](const std::string& l) { h += l + t.eol; };
  line("ply");
  line("format " + std::string(format) + " 1.0");
  line("comment written by test_mesh_io");
  line("obj_info distractions included");
  line("element material 2");
  line("property uchar r");
  line("property list uchar int ids");
  line("element vertex " + std::to_string(pos.size()));
  line("property " + t.xyz + " x");
  line("property float nx");
  line("property " + t.xyz + " y");
  line("property uchar red");
  line("property " + t.xyz + " z");
  line("property list uchar float extra");
  line("element face " + std::to_string(s.faces.size()));
  line("property uchar flags");
  line("property list " + t.count + " " + t.index + " " + t.list_name);
  line("property double quality");
  line("element edge 2");
  line("property int vertex1");
  line("property int vertex2");
  line("end_header");

  PlyBody b(format);
  for (int m = 0; m < 2; ++m) {
    b.put("uchar", 7 + m);
    b.put("uchar", m + 1);
    for (int k = 0; k <= m; ++k) b.put("int", -5 * k);
    b.end_element();
  }
  for (size_t i = 0; i < pos.size(); ++i) {
    b.put(t.xyz, pos[i].x);
    b.put("float", 0.25);
    b.put(t.xyz, pos[i].y);
    b.put("uchar", 200);
    b.put(t.xyz, pos[i].z);
    b.put("uchar", i % 3);
    for (size_t k = 0; k < i % 3; ++k) b.put("float", 1.5 * k);
    b.end_element();
  }
  for (const auto& f : s.faces) {
    b.put("uchar", 1);
    b.put(t.count, static_cast<double>(f.size()));
    for (uint32_t v : f) b.put(t.index, v);
    b.put("double", 0.125);
    b.end_element();
  }
  for (int e = 0; e < 2; ++e) {
    b.put("int", e);
    b.put("int", e + 1);
    b.end_element();
  }
  std::string body = b.bytes();
  if (format == "ascii" && t.eol != "\n") {
    std::string converted;
    for (char c : body) converted += c == '\n' ? t.eol : std::string(1, c);
    body = converted;
  }
  return h + body;
}

// A directory of its own for each test's files, removed after it; write() puts a file there.
class TempDirTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::random_device rd;
    // ctest may run tests of several build trees at once; a random suffix keeps them apart.
    dir_ = std::filesystem::path(::testing::TempDir()) /
           (std::string("gwnrt_") + info->test_suite_name() + "_" + info->name() + "_" + std::to_string(rd()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }

  std::string write(const std::string& name, std::string_view bytes) const {
    const std::filesystem::path p = dir_ / name;
    // Replacing rather than truncating: ext4 flushes a truncated-and-rewritten file to disk
    // on close, which made the many rewrites of the reader tests (io/) take seconds.
    std::error_code ec;
    std::filesystem::remove(p, ec);
    std::ofstream f(p, std::ios::binary);
    f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    f.close();
    EXPECT_TRUE(f.good()) << p;
    return p.string();
  }

  std::filesystem::path dir_;
};

// One mesh, every encoding: the small mesh as OBJ.
inline const char* const kSmallObj =
    "# the small mesh, with every statement a reader must tolerate\r\n"
    "mtllib small.mtl\r\n"
    "o small\r\n"
    "\r\n"
    "v 0 0 0 1.0\r\n"
    "v 1.5 0 0 0.1 0.2 0.3\r\n"
    "v +1.5 2.25 0\r\n"
    "v 0 2.25e0 -0.75\r\n"
    "\tv  -1   1 3.25  \r\n"
    "v 0.5 -0.5 1\r\n"
    "v 2 1 -2.5 # trailing comment\r\n"
    "vt 0 0\r\n"
    "vt 1 0\r\n"
    "vn 0 0 1\r\n"
    "vp 0.5\r\n"
    "g part\r\n"
    "s off\r\n"
    "usemtl red\r\n"
    "f 1 2 3\r\n"
    "f 1/1 3/2 4/1 5/2\r\n"
    "f -6//1 6//1 7//1 3//1 4//1\r\n"
    "f 5/1/1 4/2/1 -1/1/1 # relative index\r\n"
    "l 1 2\r\n"
    "p 1\r\n"
    "unknownkeyword 1 2 3";  // no final newline

}  // namespace gwnrt::test
