// The strict STL reader (readers.h): binary (recognised by its size, 84 + 50 bytes a facet,
// whatever its header says) and ASCII (`solid ... endsolid`, several solids in one file). STL
// repeats every corner per facet; corners with bit-identical coordinates become one vertex, which
// moves nothing (the file has no attribute a vertex could differ by).

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>
#include <limits>
#include <numeric>

#include "gwnrt/io/read_file.h"
#include "io/readers.h"
#include "io/text.h"

namespace gwnrt::io {
namespace {

constexpr size_t kStlHeaderBytes = 84;  // 80 bytes of header, then the facet count (uint32 LE)
constexpr size_t kStlFacetBytes = 50;   // normal, three corners (12 floats LE), an attribute uint16

uint32_t get_u32_le(const char* p) {
  const auto* u = reinterpret_cast<const unsigned char*>(p);
  return uint32_t(u[0]) | uint32_t(u[1]) << 8 | uint32_t(u[2]) << 16 | uint32_t(u[3]) << 24;
}

float get_f32_le(const char* p) { return std::bit_cast<float>(get_u32_le(p)); }

bool equals_nocase(string_view a, string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    char c = a[i];
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
    if (c != b[i]) return false;
  }
  return true;
}

// Whether the file's first word is `solid` (ASCII STL's first keyword; many binary headers
// begin with it too).
bool begins_with_solid(string_view data) {
  size_t i = 0;
  while (i < data.size() && (is_blank(data[i]) || data[i] == '\n')) ++i;
  return data.size() - i >= 5 && equals_nocase(data.substr(i, 5), "solid") &&
         (data.size() - i == 5 || is_blank(data[i + 5]) || data[i + 5] == '\n');
}

// A binary file's facet count holds a byte text never has unless the count is above 5e8.
bool count_is_binary(string_view data) {
  if (data.size() < kStlHeaderBytes) return false;
  for (size_t i = 80; i < kStlHeaderBytes; ++i)
    if (is_binary_byte(data[i]) || static_cast<unsigned char>(data[i]) >= 0x7f) return true;
  return false;
}

// Corners with bit-identical coordinates (the float's, or the double's when `wide` is given) become
// one vertex, numbered in order of first appearance.
template <class Key>
void weld_corners(const std::vector<Key>& keys, std::vector<uint32_t>& vertex_of_corner, std::vector<size_t>& first) {
  const size_t n = keys.size();
  std::vector<uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(),
            [&](uint32_t a, uint32_t b) { return keys[a] < keys[b] || (keys[a] == keys[b] && a < b); });
  std::vector<uint32_t> leader(n);  // the first corner with the same key
  for (size_t i = 0; i < n; ++i)
    leader[order[i]] = i > 0 && keys[order[i]] == keys[order[i - 1]] ? leader[order[i - 1]] : order[i];
  vertex_of_corner.assign(n, 0);
  first.clear();
  for (size_t c = 0; c < n; ++c) {
    if (leader[c] == c) {
      vertex_of_corner[c] = static_cast<uint32_t>(first.size());
      first.push_back(c);
    } else {
      vertex_of_corner[c] = vertex_of_corner[leader[c]];
    }
  }
}

// The corners as read, three (or more, in ASCII) per facet, turned into an indexed mesh.
struct StlCorners {
  std::vector<vec3> corners;
  std::vector<dvec3> wide;              // with MeshLoadOptions::recentre: the same in double
  std::vector<uint32_t> facet_corners;  // where each facet's corners begin; one more at the end

  void finish(Mesh& mesh, std::vector<dvec3>* world, MeshLoadReport& rep) const {
    std::vector<uint32_t> vertex_of_corner;
    std::vector<size_t> first;
    if (world) {
      std::vector<std::array<uint64_t, 3>> keys(wide.size());
      for (size_t i = 0; i < wide.size(); ++i)
        for (int k = 0; k < 3; ++k) keys[i][k] = std::bit_cast<uint64_t>(wide[i][k]);
      weld_corners(keys, vertex_of_corner, first);
    } else {
      std::vector<std::array<uint32_t, 3>> keys(corners.size());
      for (size_t i = 0; i < corners.size(); ++i)
        for (int k = 0; k < 3; ++k) keys[i][k] = std::bit_cast<uint32_t>(corners[i][k]);
      weld_corners(keys, vertex_of_corner, first);
    }
    mesh.positions.resize(first.size());
    for (size_t v = 0; v < first.size(); ++v) mesh.positions[v] = corners[first[v]];
    if (world) {
      world->resize(first.size());
      for (size_t v = 0; v < first.size(); ++v) (*world)[v] = wide[first[v]];
    }
    std::vector<uint32_t> polygon;
    for (size_t f = 0; f + 1 < facet_corners.size(); ++f) {
      polygon.assign(vertex_of_corner.begin() + facet_corners[f], vertex_of_corner.begin() + facet_corners[f + 1]);
      if (polygon.size() > 3) ++rep.polygons_fanned;
      fan(polygon, mesh.triangles);
    }
    rep.file_vertices = corners.size();
  }
};

Status read_binary_stl(const std::string& path, string_view data, uint32_t count, Mesh& mesh, MeshLoadReport& rep,
                       std::vector<dvec3>* world) {
  StlCorners c;
  c.corners.reserve(3 * size_t(count));
  if (world) c.wide.reserve(3 * size_t(count));
  c.facet_corners.reserve(size_t(count) + 1);
  for (uint32_t f = 0; f < count; ++f) {
    const char* p = data.data() + kStlHeaderBytes + size_t(f) * kStlFacetBytes + 12;  // past the stored normal
    c.facet_corners.push_back(static_cast<uint32_t>(c.corners.size()));
    for (int k = 0; k < 3; ++k, p += 12) {
      const vec3 x(get_f32_le(p), get_f32_le(p + 4), get_f32_le(p + 8));
      if (!is_finite(x.x) || !is_finite(x.y) || !is_finite(x.z)) {
        return {StatusCode::kInvalidMesh,
                cat(path, ": facet ", f, " (counting from 0), corner ", k, ", ", non_finite_coordinate(x.x, x.y, x.z))};
      }
      c.corners.push_back(x);
      if (world) c.wide.emplace_back(x);
    }
  }
  c.facet_corners.push_back(static_cast<uint32_t>(c.corners.size()));
  c.finish(mesh, world, rep);
  rep.format = "stl-binary";
  return Status::Ok();
}

// ASCII STL's words, with the line each is on.
struct StlWords {
  const char* p;
  const char* end;
  size_t line = 1;       // where p is
  size_t word_line = 1;  // the line of the last word read: what messages name
  bool next(string_view& word) {
    for (; p < end && (is_blank(*p) || *p == '\n'); ++p) line += *p == '\n';
    if (p == end) return false;
    word_line = line;
    const char* const b = p;
    while (p < end && !is_blank(*p) && *p != '\n') ++p;
    word = string_view(b, static_cast<size_t>(p - b));
    return true;
  }
  void skip_line() {
    while (p < end && *p != '\n') ++p;
  }
};

Status read_ascii_stl(const std::string& path, string_view data, Mesh& mesh, MeshLoadReport& rep,
                      std::vector<dvec3>* world) {
  StlCorners c;
  StlWords in{data.data(), data.data() + data.size()};
  string_view word;
  size_t facet = 0, facet_line = 0;
  auto at = [&](const auto&... parts) { return cat(path, ":", in.word_line, ": ", parts...); };
  auto expect = [&](string_view want, string_view where) -> Status {
    if (!in.next(word)) return {StatusCode::kParseError, at("the file ends ", where, " (expected '", want, "')")};
    if (!equals_nocase(word, want))
      return {StatusCode::kParseError, at("expected '", want, "' ", where, ", found ", quoted_token(word))};
    return Status::Ok();
  };
  auto numbers = [&](float* out, double* wide, string_view what) -> Status {
    for (int k = 0; k < 3; ++k) {
      if (!in.next(word))
        return {StatusCode::kParseError,
                at("the file ends in the ", what, " of facet ", facet, " (3 numbers expected)")};
      if (!parse_real(word, out[k]))
        return {StatusCode::kParseError,
                at("malformed number ", quoted_token(word), " in the ", what, " of facet ", facet)};
      if (wide) (void)parse_real(word, wide[k]);  // parsed again: the float is what a plain load reads
    }
    return Status::Ok();
  };
  for (const char* b = data.data(); b < in.end; ++b)
    if (is_binary_byte(*b)) {
      in.word_line = 1 + size_t(std::count(data.data(), b, '\n'));
      return {StatusCode::kParseError, at(binary_byte_text(*b), ": not a text STL file")};
    }

  size_t solids = 0;
  while (in.next(word)) {
    if (!equals_nocase(word, "solid"))
      return {StatusCode::kParseError, at("expected 'solid', found ", quoted_token(word))};
    ++solids;
    in.skip_line();  // the solid's name
    for (;;) {
      if (!in.next(word))
        return {StatusCode::kParseError, at("the file ends inside solid ", solids, " (expected 'endsolid')")};
      if (equals_nocase(word, "endsolid")) {
        in.skip_line();
        break;
      }
      if (!equals_nocase(word, "facet"))
        return {StatusCode::kParseError, at("expected 'facet' or 'endsolid', found ", quoted_token(word))};
      facet_line = in.word_line;
      if (Status s = expect("normal", "after 'facet'"); !s.ok()) return s;
      float normal[3];
      if (Status s = numbers(normal, nullptr, "normal"); !s.ok()) return s;
      if (Status s = expect("outer", "after the facet's normal"); !s.ok()) return s;
      if (Status s = expect("loop", "after 'outer'"); !s.ok()) return s;
      c.facet_corners.push_back(static_cast<uint32_t>(c.corners.size()));
      size_t corners = 0;
      for (;;) {
        if (!in.next(word))
          return {StatusCode::kParseError,
                  at("the file ends inside facet ", facet, " (begun on line ", facet_line, ")")};
        if (equals_nocase(word, "endloop")) break;
        if (!equals_nocase(word, "vertex"))
          return {StatusCode::kParseError, at("expected 'vertex' or 'endloop', found ", quoted_token(word))};
        float x[3];
        double wide[3] = {0, 0, 0};
        if (Status s = numbers(x, world ? wide : nullptr, "vertex"); !s.ok()) return s;
        if (!is_finite(x[0]) || !is_finite(x[1]) || !is_finite(x[2]))
          return {StatusCode::kInvalidMesh,
                  at("facet ", facet, ", corner ", corners, ", ", non_finite_coordinate(x[0], x[1], x[2]))};
        if (c.corners.size() == std::numeric_limits<uint32_t>::max())
          return {StatusCode::kInvalidMesh, at("too many corners (more than 2^32)")};
        c.corners.emplace_back(x[0], x[1], x[2]);
        if (world) c.wide.emplace_back(wide[0], wide[1], wide[2]);
        ++corners;
      }
      if (corners < 3)
        return {StatusCode::kInvalidMesh,
                at("facet ", facet, " (begun on line ", facet_line, ") has ", corners, " vertices, needs at least 3")};
      if (Status s = expect("endfacet", "after 'endloop'"); !s.ok()) return s;
      ++facet;
    }
  }
  if (solids == 0) return {StatusCode::kParseError, cat(path, ": empty file (an ASCII STL begins with 'solid')")};
  c.facet_corners.push_back(static_cast<uint32_t>(c.corners.size()));
  c.finish(mesh, world, rep);
  rep.format = "stl-ascii";
  return Status::Ok();
}

}  // namespace

size_t stl_text_end(string_view head) {
  if (!begins_with_solid(head)) return head.size() >= 5 ? 0 : kTextNotEnded;  // binary: no lines
  if (head.size() < kStlHeaderBytes) return kTextNotEnded;
  return count_is_binary(head) ? 0 : kAllText;
}

Status read_stl(const std::string& path, string_view data, Mesh& mesh, MeshLoadReport& rep, std::vector<dvec3>* world) {
  const bool solid = begins_with_solid(data);
  if (data.size() >= kStlHeaderBytes) {
    const uint64_t count = get_u32_le(data.data() + 80);
    const uint64_t expected = kStlHeaderBytes + kStlFacetBytes * count;
    if (expected == data.size()) return read_binary_stl(path, data, uint32_t(count), mesh, rep, world);
    if (!solid || count_is_binary(data)) {
      return {StatusCode::kParseError,
              cat(path, ": a binary STL of ", count, " facets (its count at byte 80) is ", expected,
                  " bytes, but the file has ", data.size(),
                  expected > data.size() ? " (truncated?)" : " (a wrong count, or data after the facets?)")};
    }
  } else if (!solid) {
    return {StatusCode::kParseError, cat(path, ": ", data.size(),
                                         " bytes: neither an ASCII STL (which begins with 'solid') nor a binary one "
                                         "(84 bytes of header and count, then 50 a facet)")};
  }
  return read_ascii_stl(path, data, mesh, rep, world);
}

}  // namespace gwnrt::io
