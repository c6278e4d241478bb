// The strict OBJ reader (readers.h): v and f statements; every other statement is skipped.

#include <cstring>

#include "io/readers.h"
#include "io/text.h"

namespace gwnrt::io {
namespace {

// OBJ

// Accepts i, i/t, i//n and i/t/n; texture and normal indices are checked for syntax only.
IntParse parse_obj_corner(string_view tok, int64_t& index) {
  auto is_int = [](string_view s) {
    int64_t v;
    return parse_int(s, v) == IntParse::kOk;
  };
  const size_t s1 = tok.find('/');
  const IntParse r = parse_int(tok.substr(0, s1), index);
  if (r != IntParse::kOk || s1 == string_view::npos) return r;
  const string_view rest = tok.substr(s1 + 1);
  const size_t s2 = rest.find('/');
  const string_view t = rest.substr(0, s2);
  if (s2 == string_view::npos) return is_int(t) ? IntParse::kOk : IntParse::kMalformed;
  const string_view n = rest.substr(s2 + 1);  // a third '/' makes this fail to parse
  return (t.empty() || is_int(t)) && is_int(n) ? IntParse::kOk : IntParse::kMalformed;
}

}  // namespace

Status read_obj(const std::string& path, string_view data, Mesh& mesh, MeshLoadReport& rep) {
  std::vector<vec3>& pos = mesh.positions;
  std::vector<uvec3>& tris = mesh.triangles;
  std::vector<uint32_t> corners;
  // Positive indices are checked against the final vertex count, so a face may precede the
  // vertices it names; the largest one and its line are enough to report a violation.
  uint64_t max_index = 0;
  size_t max_index_line = 0;
  size_t line_no = 0;
  auto at = [&](const auto&... parts) { return cat(path, ":", line_no, ": ", parts...); };

  const char* p = data.data();
  const char* const end = p + data.size();
  while (p < end) {
    const char* const nl = static_cast<const char*>(std::memchr(p, '\n', static_cast<size_t>(end - p)));
    const char* const line_end = nl ? nl : end;
    ++line_no;
    // '#' cannot occur inside the statements read here, so it ends the line wherever it is.
    const char* const hash = static_cast<const char*>(std::memchr(p, '#', static_cast<size_t>(line_end - p)));
    LineTokens tk{p, hash ? hash : line_end};
    p = nl ? nl + 1 : end;

    string_view kw;
    if (!tk.next(kw)) continue;
    if (kw == "v") {
      float c[3] = {0, 0, 0};
      int n = 0;
      string_view tok;
      // Components after x y z (w, or vertex colours) are ignored but must still be numbers.
      while (tk.next(tok)) {
        float v;
        if (!parse_real(tok, v)) return {StatusCode::kParseError, at("malformed number ", quoted(tok), " in vertex")};
        if (n < 3) c[n] = v;
        ++n;
      }
      if (n < 3) {
        return {StatusCode::kParseError, at("vertex has ", n, " coordinates, needs at least 3 (x y z)")};
      }
      if (pos.size() == kMaxVertices) return {StatusCode::kInvalidMesh, at("too many vertices (more than 2^32)")};
      pos.emplace_back(c[0], c[1], c[2]);
      if (!is_finite(c[0]) || !is_finite(c[1]) || !is_finite(c[2])) {
        return {StatusCode::kInvalidMesh,
                at("vertex ", pos.size(), " has a non-finite coordinate (", c[0], ", ", c[1], ", ", c[2], ")")};
      }
    } else if (kw == "f") {
      corners.clear();
      string_view tok;
      while (tk.next(tok)) {
        int64_t idx = 0;
        const IntParse r = parse_obj_corner(tok, idx);
        if (r == IntParse::kMalformed) {
          return {StatusCode::kParseError,
                  at("malformed face corner ", quoted(tok), " (expected i, i/t, i//n or i/t/n)")};
        }
        if (r == IntParse::kOutOfRange) {
          return {StatusCode::kInvalidMesh, at("vertex index ", quoted(tok), " is out of range")};
        }
        if (idx == 0) return {StatusCode::kInvalidMesh, at("vertex index 0 is invalid (OBJ indices start at 1)")};
        uint64_t zero_based;
        if (idx < 0) {
          if (idx < -static_cast<int64_t>(pos.size())) {
            return {StatusCode::kInvalidMesh, at("relative vertex index ", idx, " is out of range: only ", pos.size(),
                                                 " vertices are defined above this line")};
          }
          zero_based = pos.size() - static_cast<uint64_t>(-idx);
        } else {
          if (static_cast<uint64_t>(idx) > kMaxVertices) {
            return {StatusCode::kInvalidMesh, at("vertex index ", idx, " is out of range")};
          }
          zero_based = static_cast<uint64_t>(idx) - 1;
          if (static_cast<uint64_t>(idx) > max_index) {
            max_index = static_cast<uint64_t>(idx);
            max_index_line = line_no;
          }
        }
        corners.push_back(static_cast<uint32_t>(zero_based));
      }
      if (corners.size() < 3) {
        return {StatusCode::kInvalidMesh, at("face has ", corners.size(), " corners, needs at least 3")};
      }
      if (corners.size() > 3) ++rep.polygons_fanned;
      fan(corners, tris);
    }
    // Everything else (vt vn vp o g s usemtl mtllib l p, curves, ...) carries nothing a
    // winding-number mesh needs.
  }
  if (max_index > pos.size()) {
    line_no = max_index_line;
    return {StatusCode::kInvalidMesh,
            at("vertex index ", max_index, " is out of range (the file has ", pos.size(), " vertices)")};
  }
  rep.format = "obj";
  return Status::Ok();
}

}  // namespace gwnrt::io
