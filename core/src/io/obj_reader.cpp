// The strict OBJ reader (readers.h): v (with r g b vertex colours), vt and f statements; every
// other statement is skipped.

#include <cstring>

#include "gwnrt/io/read_file.h"
#include "io/readers.h"
#include "io/text.h"

namespace gwnrt::io {
namespace {

// OBJ

// Accepts i, i/t, i//n and i/t/n; `texture` receives t (0 when absent: OBJ indices start at 1,
// so 0 is never a valid one and is refused by the caller when written); normal indices are
// checked for syntax only.
IntParse parse_obj_corner(string_view tok, int64_t& index, int64_t& texture) {
  auto is_int = [](string_view s) {
    int64_t v;
    return parse_int(s, v) == IntParse::kOk;
  };
  texture = 0;
  const size_t s1 = tok.find('/');
  const IntParse r = parse_int(tok.substr(0, s1), index);
  if (r != IntParse::kOk || s1 == string_view::npos) return r;
  const string_view rest = tok.substr(s1 + 1);
  const size_t s2 = rest.find('/');
  const string_view t = rest.substr(0, s2);
  const bool has_t = !t.empty() || s2 == string_view::npos;
  if (has_t) {
    const IntParse rt = parse_int(t, texture);
    if (rt != IntParse::kOk) return rt;
    if (texture == 0) return IntParse::kOutOfRange;
  }
  if (s2 == string_view::npos) return IntParse::kOk;
  const string_view n = rest.substr(s2 + 1);  // a third '/' makes this fail to parse
  return is_int(n) ? IntParse::kOk : IntParse::kMalformed;
}

// The OBJ statements a reader may meet that say nothing about the triangles' geometry.
bool is_known_obj_statement(string_view kw) {
  static constexpr string_view kKnown[] = {
      "vn",     "vp",    "o",     "g",      "s",      "usemtl",     "mtllib",    "l",        "p",
      "cstype", "deg",   "bmat",  "step",   "curv",   "curv2",      "surf",      "parm",     "trim",
      "hole",   "scrv",  "sp",    "end",    "con",    "mg",         "bevel",     "c_interp", "d_interp",
      "lod",    "ctech", "stech", "maplib", "usemap", "shadow_obj", "trace_obj", "call",     "csh"};
  for (string_view k : kKnown)
    if (kw == k) return true;
  return false;
}

// A 1-based (or negative, relative) OBJ reference into `defined` items so far, resolved to 0-based;
// positive ones are checked against the final count by the caller (the largest is tracked).
struct ObjIndex {
  uint64_t max_index = 0;
  size_t max_index_line = 0;
  // False when a relative index reaches before the first item.
  bool resolve(int64_t idx, uint64_t defined, size_t line, uint64_t& zero_based) {
    if (idx < 0) {
      if (idx < -static_cast<int64_t>(defined)) return false;
      zero_based = defined - static_cast<uint64_t>(-idx);
      return true;
    }
    zero_based = static_cast<uint64_t>(idx) - 1;
    if (static_cast<uint64_t>(idx) > max_index) {
      max_index = static_cast<uint64_t>(idx);
      max_index_line = line;
    }
    return true;
  }
};

}  // namespace

Status read_obj(const std::string& path, string_view data, Mesh& mesh, MeshLoadReport& rep, std::vector<dvec3>* world) {
  std::vector<vec3>& pos = mesh.positions;
  std::vector<uvec3>& tris = mesh.triangles;
  std::vector<glm::vec2> uvs;
  std::vector<uvec3> uv_tris;
  std::vector<glm::vec4> colors;
  std::vector<uint32_t> corners, uv_corners;
  // Positive indices are checked against the final counts, so a face may precede the vertices
  // it names; the largest one and its line are enough to report a violation.
  ObjIndex vertex_index, uv_index;
  size_t unknown_statements = 0, first_unknown_line = 0;
  std::string first_unknown;
  size_t colored_vertices = 0, faces_with_uv = 0, faces_without_uv = 0, first_face_without_uv_line = 0;
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

    // Text only: a control byte (other than whitespace) means the file is not an OBJ at all.
    for (const char* c = tk.p; c < tk.end; ++c)
      if (is_binary_byte(*c)) return {StatusCode::kParseError, at(binary_byte_text(*c), ": not a text OBJ file")};
    string_view kw;
    if (!tk.next(kw)) continue;
    if (kw == "v") {
      float c[6] = {0, 0, 0, 0, 0, 0};
      dvec3 wide(0.0);
      int n = 0;
      string_view tok;
      // x y z, then w or (the common extension) r g b; other counts' extra numbers are ignored
      // but must still be numbers.
      while (tk.next(tok)) {
        float v;
        if (!parse_real(tok, v))
          return {StatusCode::kParseError, at("malformed number ", quoted_token(tok), " in vertex")};
        // Parsed again rather than widened: the float is what a plain load reads, bit for bit.
        if (world && n < 3) (void)parse_real(tok, wide[n]);
        if (n < 6) c[n] = v;
        ++n;
      }
      if (n < 3) {
        return {StatusCode::kParseError, at("vertex has ", n, " coordinates, needs at least 3 (x y z)")};
      }
      if (pos.size() == kMaxVertices) return {StatusCode::kInvalidMesh, at("too many vertices (more than 2^32)")};
      pos.emplace_back(c[0], c[1], c[2]);
      if (world) world->push_back(wide);
      if (!is_finite(c[0]) || !is_finite(c[1]) || !is_finite(c[2])) {
        return {StatusCode::kInvalidMesh, at("vertex ", pos.size(), " ", non_finite_coordinate(c[0], c[1], c[2]))};
      }
      if (n == 6) {
        if (!is_finite(c[3]) || !is_finite(c[4]) || !is_finite(c[5])) {
          return {StatusCode::kInvalidMesh,
                  at("vertex ", pos.size(), " has a non-finite colour (", c[3], ", ", c[4], ", ", c[5], ")")};
        }
        // Colours of the vertices before the first coloured one are unknown: kept only if all have one.
        if (colored_vertices + 1 == pos.size()) colors.emplace_back(c[3], c[4], c[5], 1.0f);
        ++colored_vertices;
      }
    } else if (kw == "vt") {
      float c[2] = {0, 0};
      int n = 0;
      string_view tok;
      while (tk.next(tok)) {
        float v;
        if (!parse_real(tok, v))
          return {StatusCode::kParseError, at("malformed number ", quoted_token(tok), " in texture coordinate")};
        if (n < 2) c[n] = v;
        ++n;
      }
      if (n < 1 || n > 3) {
        return {StatusCode::kParseError, at("texture coordinate has ", n, " numbers, needs 1 to 3 (u [v [w]])")};
      }
      if (uvs.size() == kMaxVertices)
        return {StatusCode::kInvalidMesh, at("too many texture coordinates (more than 2^32)")};
      uvs.emplace_back(c[0], c[1]);
      if (!is_finite(c[0]) || !is_finite(c[1])) {
        return {StatusCode::kInvalidMesh,
                at("texture coordinate ", uvs.size(), " is not finite (", c[0], ", ", c[1], ")")};
      }
    } else if (kw == "f") {
      corners.clear();
      uv_corners.clear();
      string_view tok;
      while (tk.next(tok)) {
        int64_t idx = 0, tex = 0;
        const IntParse r = parse_obj_corner(tok, idx, tex);
        if (r == IntParse::kMalformed) {
          return {StatusCode::kParseError,
                  at("malformed face corner ", quoted_token(tok), " (expected i, i/t, i//n or i/t/n)")};
        }
        if (r == IntParse::kOutOfRange) {
          return {StatusCode::kInvalidMesh, at("index in face corner ", quoted_token(tok), " is out of range")};
        }
        if (idx == 0) return {StatusCode::kInvalidMesh, at("vertex index 0 is invalid (OBJ indices start at 1)")};
        if (idx > 0 && static_cast<uint64_t>(idx) > kMaxVertices) {
          return {StatusCode::kInvalidMesh, at("vertex index ", idx, " is out of range")};
        }
        uint64_t zero_based = 0;
        if (!vertex_index.resolve(idx, pos.size(), line_no, zero_based)) {
          return {StatusCode::kInvalidMesh, at("relative vertex index ", idx, " is out of range: only ", pos.size(),
                                               " vertices are defined above this line")};
        }
        corners.push_back(static_cast<uint32_t>(zero_based));
        if (tex != 0) {
          if (tex > 0 && static_cast<uint64_t>(tex) > kMaxVertices) {
            return {StatusCode::kInvalidMesh, at("texture index ", tex, " is out of range")};
          }
          if (!uv_index.resolve(tex, uvs.size(), line_no, zero_based)) {
            return {StatusCode::kInvalidMesh, at("relative texture index ", tex, " is out of range: only ", uvs.size(),
                                                 " texture coordinates are defined above this line")};
          }
          uv_corners.push_back(static_cast<uint32_t>(zero_based));
        }
      }
      if (corners.size() < 3) {
        return {StatusCode::kInvalidMesh, at("face has ", corners.size(), " corners, needs at least 3")};
      }
      if (!uv_corners.empty() && uv_corners.size() != corners.size()) {
        return {StatusCode::kInvalidMesh, at("face gives texture indices for ", uv_corners.size(), " of its ",
                                             corners.size(), " corners (all or none)")};
      }
      if (corners.size() > 3) ++rep.polygons_fanned;
      fan(corners, tris);
      if (uv_corners.empty()) {
        if (faces_without_uv++ == 0) first_face_without_uv_line = line_no;
      } else {
        ++faces_with_uv;
        fan(uv_corners, uv_tris);
      }
    } else if (!is_known_obj_statement(kw)) {
      // Known statements (vn vp o g s usemtl mtllib l p, curves, ...) carry nothing the winding
      // number or the attribute transfer needs; anything else is counted and reported.
      if (unknown_statements++ == 0) {
        first_unknown_line = line_no;
        first_unknown = std::string(kw.substr(0, 32));
      }
    }
  }
  if (unknown_statements > 0) {
    rep.warnings = cat(unknown_statements, unknown_statements == 1 ? " line" : " lines",
                       " with an unknown statement ignored (the first, line ", first_unknown_line, ": ",
                       quoted_token(first_unknown), ")");
  }
  if (vertex_index.max_index > pos.size()) {
    line_no = vertex_index.max_index_line;
    return {StatusCode::kInvalidMesh,
            at("vertex index ", vertex_index.max_index, " is out of range (the file has ", pos.size(), " vertices)")};
  }
  if (faces_with_uv > 0 && uv_index.max_index > uvs.size()) {
    line_no = uv_index.max_index_line;
    return {StatusCode::kInvalidMesh, at("texture index ", uv_index.max_index, " is out of range (the file has ",
                                         uvs.size(), " texture coordinates)")};
  }
  if (faces_with_uv > 0 && faces_without_uv == 0) {
    mesh.uvs = std::move(uvs);
    mesh.uv_triangles = std::move(uv_tris);
  } else if (faces_with_uv > 0) {
    rep.attributes_dropped = cat("texture coordinates dropped: ", faces_without_uv, " faces (the first on line ",
                                 first_face_without_uv_line, ") have no texture indices while ", faces_with_uv, " do");
  } else if (!uvs.empty()) {
    rep.attributes_dropped = cat("texture coordinates dropped: no face refers to the ", uvs.size(), " vt lines");
  }
  if (colored_vertices == pos.size() && !pos.empty()) {
    mesh.colors = std::move(colors);
  } else if (colored_vertices > 0) {
    if (!rep.attributes_dropped.empty()) rep.attributes_dropped += "; ";
    rep.attributes_dropped +=
        cat("vertex colours dropped: ", colored_vertices, " of ", pos.size(), " vertices have one (v x y z r g b)");
  }
  rep.format = "obj";
  return Status::Ok();
}

}  // namespace gwnrt::io
