// The strict PLY reader (readers.h): ASCII, binary little and big endian; vertex x, y, z, colour
// (red green blue [alpha]) and texture coordinates (u v, s t, texture_u texture_v or texture_s
// texture_t), face vertex_indices and texcoord (per-corner UVs); every other element and property
// skipped by its declared type.
#include <algorithm>
#include <bit>
#include <cstring>
#include <optional>

#include "gwnrt/io/read_file.h"
#include "io/readers.h"
#include "io/text.h"

namespace gwnrt::io {
namespace {

// PLY

enum class Ty : uint8_t { kI8, kU8, kI16, kU16, kI32, kU32, kF32, kF64 };

struct TyInfo {
  const char* name;
  const char* alias;
  uint32_t size;
  bool is_int;
  int64_t lo, hi;
};

constexpr TyInfo kTyInfo[] = {
    {"char", "int8", 1, true, INT8_MIN, INT8_MAX},
    {"uchar", "uint8", 1, true, 0, UINT8_MAX},
    {"short", "int16", 2, true, INT16_MIN, INT16_MAX},
    {"ushort", "uint16", 2, true, 0, UINT16_MAX},
    {"int", "int32", 4, true, INT32_MIN, INT32_MAX},
    {"uint", "uint32", 4, true, 0, UINT32_MAX},
    {"float", "float32", 4, false, 0, 0},
    {"double", "float64", 8, false, 0, 0},
};

const TyInfo& info(Ty t) { return kTyInfo[static_cast<int>(t)]; }

std::optional<Ty> parse_ty(string_view s) {
  for (int i = 0; i < 8; ++i) {
    if (s == kTyInfo[i].name || s == kTyInfo[i].alias) return static_cast<Ty>(i);
  }
  return std::nullopt;
}

struct PlyProp {
  std::string name;
  Ty type = Ty::kF32;  // the item type for a list
  bool list = false;
  Ty count_type = Ty::kU8;
  int role = -1;  // what a vertex property holds: a VertexRole, or -1 (skipped)
};

// The vertex properties kept, as indices into the values read per vertex.
enum VertexRole { kX, kY, kZ, kU, kV, kRed, kGreen, kBlue, kAlpha, kRoleCount };

struct PlyElem {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProp> props;
};

enum class PlyFormat { kAscii, kBinaryLe, kBinaryBe };

struct PlyHeader {
  PlyFormat format = PlyFormat::kAscii;
  std::vector<PlyElem> elems;
  int vertex = -1;  // element indices
  int face = -1;
  int face_list = -1;      // property index of vertex_indices within the face element
  int face_texcoord = -1;  // property index of texcoord (2 floats per corner), or -1
  bool vertex_uvs = false, vertex_colors = false;
  std::string dropped;  // why colour properties found were not kept
  size_t data_offset = 0;
  size_t end_header_line = 0;
};

Status parse_ply_header(const std::string& path, string_view data, PlyHeader& h) {
  size_t off = 0;
  size_t line_no = 0;
  auto next_line = [&](string_view& line) {
    if (off >= data.size()) return false;
    const size_t nl = data.find('\n', off);
    const size_t le = nl == string_view::npos ? data.size() : nl;
    line = data.substr(off, le - off);
    off = nl == string_view::npos ? data.size() : nl + 1;
    ++line_no;
    return true;
  };
  auto err = [&](const auto&... parts) {
    return Status{StatusCode::kParseError, cat(path, ":", line_no, ": ", parts...)};
  };

  string_view line;
  string_view magic;
  if (next_line(line)) {
    LineTokens tk{line.data(), line.data() + line.size()};
    string_view extra;
    if (!tk.next(magic) || tk.next(extra)) magic = {};
  }
  if (magic != "ply") return {StatusCode::kParseError, cat(path, ": not a PLY file (the first line is not 'ply')")};

  bool have_format = false;
  bool have_end = false;
  while (next_line(line)) {
    LineTokens tk{line.data(), line.data() + line.size()};
    string_view kw, a, b, c, d, extra;
    if (!tk.next(kw)) continue;
    if (kw == "comment" || kw == "obj_info") continue;
    if (kw == "end_header") {
      if (tk.next(extra)) return err("unexpected ", quoted_token(extra), " after end_header");
      have_end = true;
      break;
    }
    if (kw == "format") {
      if (have_format) return err("duplicate 'format' line");
      if (!tk.next(a) || !tk.next(b) || tk.next(extra)) {
        return err("malformed format line (expected 'format ascii|binary_little_endian|binary_big_endian 1.0')");
      }
      if (a == "ascii") {
        h.format = PlyFormat::kAscii;
      } else if (a == "binary_little_endian") {
        h.format = PlyFormat::kBinaryLe;
      } else if (a == "binary_big_endian") {
        h.format = PlyFormat::kBinaryBe;
      } else {
        return err("unsupported PLY format ", quoted_token(a));
      }
      if (b != "1.0" && b != "1") return err("unsupported PLY format version ", quoted_token(b), " (expected 1.0)");
      have_format = true;
    } else if (kw == "element") {
      if (!have_format) return err("'element' before the 'format' line (missing format line?)");
      if (!tk.next(a) || !tk.next(b) || tk.next(extra))
        return err("malformed element line (expected 'element NAME COUNT')");
      const char* const e = b.data() + b.size();
      uint64_t count = 0;
      const auto [ptr, ec] = std::from_chars(b.data(), e, count);
      if (ec != std::errc() || ptr != e) return err("malformed element count ", quoted_token(b));
      h.elems.push_back({std::string(a), count, {}});
    } else if (kw == "property") {
      if (h.elems.empty()) return err("'property' before any 'element'");
      PlyProp prop;
      if (!tk.next(a)) return err("malformed property line");
      if (a == "list") {
        if (!tk.next(b) || !tk.next(c) || !tk.next(d) || tk.next(extra)) {
          return err("malformed list property (expected 'property list COUNT_TYPE ITEM_TYPE NAME')");
        }
        const auto ct = parse_ty(b);
        const auto it = parse_ty(c);
        if (!ct) return err("unknown property type ", quoted_token(b));
        if (!it) return err("unknown property type ", quoted_token(c));
        if (!info(*ct).is_int) return err("list count type ", quoted_token(b), " is not an integer type");
        prop.list = true;
        prop.count_type = *ct;
        prop.type = *it;
        prop.name = std::string(d);
      } else {
        if (!tk.next(b) || tk.next(extra)) return err("malformed property line (expected 'property TYPE NAME')");
        const auto t = parse_ty(a);
        if (!t) return err("unknown property type ", quoted_token(a));
        prop.type = *t;
        prop.name = std::string(b);
      }
      h.elems.back().props.push_back(std::move(prop));
    } else {
      return err("unknown PLY header keyword ", quoted_token(kw), " (missing end_header?)");
    }
  }
  if (!have_end) return {StatusCode::kParseError, cat(path, ": the PLY header has no end_header line")};
  if (!have_format) return {StatusCode::kParseError, cat(path, ": the PLY header has no 'format' line")};
  h.data_offset = off;
  h.end_header_line = line_no;

  for (size_t e = 0; e < h.elems.size(); ++e) {
    int* slot = h.elems[e].name == "vertex" ? &h.vertex : h.elems[e].name == "face" ? &h.face : nullptr;
    if (!slot) continue;
    if (*slot >= 0) return {StatusCode::kParseError, cat(path, ": duplicate '", h.elems[e].name, "' element")};
    *slot = static_cast<int>(e);
  }
  if (h.vertex < 0) return {StatusCode::kParseError, cat(path, ": the PLY header declares no 'vertex' element")};
  PlyElem& vertex = h.elems[static_cast<size_t>(h.vertex)];
  if (vertex.count > kMaxVertices) {
    return {StatusCode::kInvalidMesh, cat(path, ": too many vertices (", vertex.count, ", at most 2^32)")};
  }
  auto find_scalar = [&](const char* name, PlyProp*& found) -> Status {
    found = nullptr;
    for (PlyProp& p : vertex.props) {
      if (p.name == name) {
        found = &p;
        break;
      }
    }
    if (found && found->list) {
      return {StatusCode::kParseError, cat(path, ": vertex property '", name, "' is a list, not a scalar")};
    }
    return Status::Ok();
  };
  static constexpr const char* kCoordNames[3] = {"x", "y", "z"};
  for (int k = 0; k < 3; ++k) {
    PlyProp* found = nullptr;
    if (Status s = find_scalar(kCoordNames[k], found); !s.ok()) return s;
    if (!found) {
      return {StatusCode::kParseError, cat(path, ": the vertex element has no '", kCoordNames[k], "' property")};
    }
    found->role = k;
  }
  // Colours: all three channels, or none kept.
  static constexpr const char* kColourNames[4] = {"red", "green", "blue", "alpha"};
  PlyProp* colour[4] = {};
  for (int k = 0; k < 4; ++k)
    if (Status s = find_scalar(kColourNames[k], colour[k]); !s.ok()) return s;
  if (colour[0] && colour[1] && colour[2]) {
    for (int k = 0; k < 4; ++k)
      if (colour[k]) colour[k]->role = kRed + k;
    h.vertex_colors = true;
  } else if (colour[0] || colour[1] || colour[2]) {
    h.dropped = "vertex colours dropped: the vertex element lacks one of red, green, blue";
  }
  // Texture coordinates: the first pair present, by the names exporters use.
  static constexpr const char* kUvNames[4][2] = {
      {"u", "v"}, {"s", "t"}, {"texture_u", "texture_v"}, {"texture_s", "texture_t"}};
  for (const auto& names : kUvNames) {
    PlyProp *u = nullptr, *v = nullptr;
    if (Status s = find_scalar(names[0], u); !s.ok()) return s;
    if (Status s = find_scalar(names[1], v); !s.ok()) return s;
    if (u && v) {
      u->role = kU;
      v->role = kV;
      h.vertex_uvs = true;
      break;
    }
  }
  if (h.face >= 0) {
    const PlyElem& face = h.elems[static_cast<size_t>(h.face)];
    for (size_t j = 0; j < face.props.size() && h.face_list < 0; ++j) {
      if (face.props[j].name == "vertex_indices" || face.props[j].name == "vertex_index")
        h.face_list = static_cast<int>(j);
    }
    if (h.face_list < 0) {
      return {StatusCode::kParseError, cat(path, ": the face element has no 'vertex_indices' list property")};
    }
    const PlyProp& fl = face.props[static_cast<size_t>(h.face_list)];
    if (!fl.list) return {StatusCode::kParseError, cat(path, ": face property '", fl.name, "' is not a list")};
    if (!info(fl.type).is_int) {
      return {StatusCode::kParseError,
              cat(path, ": face property '", fl.name, "' has non-integer index type '", info(fl.type).name, "'")};
    }
    for (size_t j = 0; j < face.props.size(); ++j) {
      if (face.props[j].name != "texcoord") continue;
      if (!face.props[j].list) return {StatusCode::kParseError, cat(path, ": face property 'texcoord' is not a list")};
      h.face_texcoord = static_cast<int>(j);
      break;
    }
  }
  return Status::Ok();
}

enum class Res { kOk, kEnd, kBad };

template <bool kSwap, class U>
inline U load_bits(const unsigned char* p) {
  U u;
  std::memcpy(&u, p, sizeof(U));
  if constexpr (kSwap) {
    if constexpr (sizeof(U) == 2) u = __builtin_bswap16(u);
    if constexpr (sizeof(U) == 4) u = __builtin_bswap32(u);
    if constexpr (sizeof(U) == 8) u = __builtin_bswap64(u);
  }
  return u;
}

template <bool kSwap>
struct BinarySource {
  static constexpr bool kAscii = false;
  const unsigned char* p;
  const unsigned char* end;
  string_view bad_tok;  // never set: every byte pattern is a valid binary value
  Ty bad_ty = Ty::kF32;

  uint64_t remaining() const { return static_cast<uint64_t>(end - p); }
  std::string where(const std::string& path) const { return path; }

  Res read_real(Ty t, double& v) { return read_value(t, v); }
  // A binary value is its own double.
  Res read_real(Ty t, double& v, double& wide) {
    const Res r = read_value(t, v);
    wide = v;
    return r;
  }
  // Only called with integer types (the header rejects others where integers are needed).
  Res read_int(Ty t, int64_t& v) { return read_value(t, v); }

 private:
  // One value of type t; float types never decode into an integer V.
  template <class V>
  Res read_value(Ty t, V& v) {
    if (remaining() < info(t).size) return Res::kEnd;
    switch (t) {
      case Ty::kI8:
        v = static_cast<int8_t>(*p);
        break;
      case Ty::kU8:
        v = *p;
        break;
      case Ty::kI16:
        v = std::bit_cast<int16_t>(load_bits<kSwap, uint16_t>(p));
        break;
      case Ty::kU16:
        v = load_bits<kSwap, uint16_t>(p);
        break;
      case Ty::kI32:
        v = std::bit_cast<int32_t>(load_bits<kSwap, uint32_t>(p));
        break;
      case Ty::kU32:
        v = load_bits<kSwap, uint32_t>(p);
        break;
      case Ty::kF32:
        if constexpr (std::is_integral_v<V>)
          return Res::kBad;
        else
          v = std::bit_cast<float>(load_bits<kSwap, uint32_t>(p));
        break;
      case Ty::kF64:
        if constexpr (std::is_integral_v<V>)
          return Res::kBad;
        else
          v = std::bit_cast<double>(load_bits<kSwap, uint64_t>(p));
        break;
    }
    p += info(t).size;
    return Res::kOk;
  }

 public:
  Res skip(Ty t, uint64_t n) {
    if (n > remaining() / info(t).size) return Res::kEnd;
    p += n * info(t).size;
    return Res::kOk;
  }

  // A line break or spaces after the data (some writers end the file with one) and nothing else:
  // more bytes are elements the header did not declare, which a reader that stopped at the
  // count would drop without a word.
  bool only_whitespace_left() const {
    for (const unsigned char* q = p; q < end; ++q)
      if (*q != '\n' && *q != '\r' && *q != ' ' && *q != '\t') return false;
    return true;
  }
};

struct AsciiSource {
  static constexpr bool kAscii = true;
  const char* p;
  const char* end;
  size_t line;      // line of the scan position
  size_t tok_line;  // line of the last token read, for messages
  string_view tok;
  string_view bad_tok;
  Ty bad_ty = Ty::kF32;

  uint64_t remaining() const { return static_cast<uint64_t>(end - p); }
  std::string where(const std::string& path) const { return cat(path, ":", tok_line); }

  bool next() {
    for (; p < end; ++p) {
      if (*p == '\n') {
        ++line;
      } else if (!is_blank(*p)) {
        break;
      }
    }
    if (p == end) return false;
    const char* const b = p;
    while (p < end && *p != '\n' && !is_blank(*p)) ++p;
    tok = string_view(b, static_cast<size_t>(p - b));
    tok_line = line;
    return true;
  }

  Res bad(Ty t) {
    bad_tok = tok;
    bad_ty = t;
    return Res::kBad;
  }

  Res read_int(Ty t, int64_t& v) {
    if (!next()) return Res::kEnd;
    const TyInfo& ti = info(t);
    if (!ti.is_int || parse_int(tok, v) != IntParse::kOk || v < ti.lo || v > ti.hi) return bad(t);
    return Res::kOk;
  }

  Res read_real(Ty t, double& v) {
    if (info(t).is_int) {
      int64_t i = 0;
      const Res r = read_int(t, i);
      v = static_cast<double>(i);
      return r;
    }
    if (!next()) return Res::kEnd;
    if (t == Ty::kF32) {
      float f;
      if (!parse_real(tok, f)) return bad(t);
      v = f;
    } else if (!parse_real(tok, v)) {
      return bad(t);
    }
    return Res::kOk;
  }

  // A coordinate also in double (MeshLoadOptions::recentre): a float property's text keeps the
  // digits that its float loses far from the origin (4123456.789 would read as 4123456.75).
  Res read_real(Ty t, double& v, double& wide) {
    const Res r = read_real(t, v);
    wide = v;
    if (r == Res::kOk && t == Ty::kF32 && !parse_real(tok, wide)) return bad(t);
    return r;
  }

  // Skipped values are still checked: a malformed token would otherwise shift every value
  // after it.
  Res skip(Ty t, uint64_t n) {
    for (uint64_t i = 0; i < n; ++i) {
      double v;
      const Res r = read_real(t, v);
      if (r != Res::kOk) return r;
    }
    return Res::kOk;
  }

  bool only_whitespace_left() {
    if (!next()) return true;
    bad_tok = tok;
    return false;
  }
};

template <class Src>
Status read_ply_body(const std::string& path, Src& src, const PlyHeader& h, Mesh& mesh, MeshLoadReport& rep,
                     std::vector<dvec3>* world) {
  const uint64_t nverts = h.elems[static_cast<size_t>(h.vertex)].count;
  std::vector<uint32_t> corners, uv_corners;
  std::vector<float> texcoord;  // one face's texcoord list
  std::vector<glm::vec2> vertex_uvs, corner_uvs;
  std::vector<uvec3> corner_uv_triangles;
  std::vector<glm::vec4> colors;

  for (size_t e = 0; e < h.elems.size(); ++e) {
    const PlyElem& el = h.elems[e];
    if (el.props.empty() || el.count == 0) continue;
    const bool is_vertex = static_cast<int>(e) == h.vertex;
    const bool is_face = static_cast<int>(e) == h.face;

    // Every instance occupies a minimum number of bytes, so a declared count beyond what is
    // left is truncation; catching it here also keeps a forged count from driving a huge
    // allocation or loop.
    uint64_t min_size = 0;
    for (const PlyProp& pr : el.props) min_size += Src::kAscii ? 2 : info(pr.list ? pr.count_type : pr.type).size;
    const uint64_t slack = Src::kAscii ? 1 : 0;  // the last ascii token needs no separator after it
    if (el.count > (src.remaining() + slack) / min_size) {
      return {StatusCode::kParseError, cat(src.where(path), ": truncated data: the header declares ", el.count, " ",
                                           el.name, " elements but only ", src.remaining(), " bytes of data remain")};
    }
    if (is_vertex) {
      mesh.positions.resize(el.count);
      if (world) world->resize(el.count);
      if (h.vertex_uvs) vertex_uvs.resize(el.count);
      if (h.vertex_colors) colors.resize(el.count);
    }

    for (uint64_t i = 0; i < el.count; ++i) {
      float value[kRoleCount] = {0, 0, 0, 0, 0, 0, 0, 0, 1};
      dvec3 wide(0.0);
      texcoord.clear();
      bool face_has_texcoord = false;
      for (size_t j = 0; j < el.props.size(); ++j) {
        const PlyProp& pr = el.props[j];
        Res r;
        if (!pr.list) {
          if (is_vertex && pr.role >= 0) {
            double v = 0;
            if (world && pr.role <= kZ) {
              r = src.read_real(pr.type, v, wide[pr.role]);
            } else {
              r = src.read_real(pr.type, v);
            }
            // Integer colour channels span their type's range (uchar: 0-255).
            if (pr.role >= kRed && info(pr.type).is_int) v = std::max(v, 0.0) / double(info(pr.type).hi);
            value[pr.role] = static_cast<float>(v);  // IEC 559 narrowing: rounds, overflows to infinity
          } else {
            r = src.skip(pr.type, 1);
          }
        } else {
          int64_t n = 0;
          r = src.read_int(pr.count_type, n);
          if (r == Res::kOk && n < 0) {
            return {StatusCode::kParseError, cat(src.where(path), ": negative list length ", n, " in ", el.name, " ", i,
                                                 ", property '", pr.name, "'")};
          }
          if (r == Res::kOk && is_face && static_cast<int>(j) == h.face_list) {
            if (n < 3) {
              return {StatusCode::kInvalidMesh,
                      cat(src.where(path), ": face ", i, " has ", n, " corners, needs at least 3")};
            }
            corners.clear();
            for (int64_t k = 0; k < n && r == Res::kOk; ++k) {
              int64_t idx = 0;
              r = src.read_int(pr.type, idx);
              if (r != Res::kOk) break;
              if (idx < 0 || static_cast<uint64_t>(idx) >= nverts) {
                return {StatusCode::kInvalidMesh, cat(src.where(path), ": face ", i, " refers to vertex ", idx,
                                                      " but there are ", nverts, " vertices")};
              }
              corners.push_back(static_cast<uint32_t>(idx));
            }
            if (r == Res::kOk) {
              if (corners.size() > 3) ++rep.polygons_fanned;
              fan(corners, mesh.triangles);
            }
          } else if (r == Res::kOk && is_face && static_cast<int>(j) == h.face_texcoord) {
            if (static_cast<uint64_t>(n) > src.remaining()) {
              r = Res::kEnd;
            } else {
              face_has_texcoord = true;
              texcoord.resize(static_cast<size_t>(n));
              for (int64_t k = 0; k < n && r == Res::kOk; ++k) {
                double v = 0;
                r = src.read_real(pr.type, v);
                texcoord[static_cast<size_t>(k)] = static_cast<float>(v);
              }
            }
          } else if (r == Res::kOk) {
            r = src.skip(pr.type, static_cast<uint64_t>(n));
          }
        }
        if (r == Res::kEnd) {
          return {StatusCode::kParseError, cat(src.where(path), ": truncated data: the file ends inside ", el.name, " ",
                                               i, " of ", el.count, " (property '", pr.name, "')")};
        }
        if (r == Res::kBad) {
          return {StatusCode::kParseError,
                  cat(src.where(path), ": invalid ", info(src.bad_ty).name, " value ", quoted_token(src.bad_tok),
                      " in ", el.name, " ", i, ", property '", pr.name, "'")};
        }
      }
      if (is_vertex) {
        mesh.positions[i] = vec3(value[kX], value[kY], value[kZ]);
        if (world) (*world)[i] = wide;
        if (h.vertex_uvs) vertex_uvs[i] = {value[kU], value[kV]};
        if (h.vertex_colors) colors[i] = {value[kRed], value[kGreen], value[kBlue], value[kAlpha]};
      }
      if (is_face && h.face_texcoord >= 0) {
        // Checked once the whole face is read: texcoord may precede vertex_indices.
        if (!face_has_texcoord || texcoord.size() != 2 * corners.size()) {
          return {StatusCode::kInvalidMesh,
                  cat(src.where(path), ": face ", i, " has ", texcoord.size(), " texcoord values for its ",
                      corners.size(), " corners (needs ", 2 * corners.size(), ")")};
        }
        uv_corners.clear();
        for (size_t k = 0; k < corners.size(); ++k) {
          uv_corners.push_back(static_cast<uint32_t>(corner_uvs.size()));
          corner_uvs.emplace_back(texcoord[2 * k], texcoord[2 * k + 1]);
        }
        fan(uv_corners, corner_uv_triangles);
      }
    }
  }
  if (!src.only_whitespace_left()) {
    if constexpr (!Src::kAscii)
      return {StatusCode::kParseError,
              cat(path, ": ", src.remaining(),
                  " bytes of data after the last element declared in the header (it declares fewer elements than "
                  "the file holds, or the file has data after them)")};
    return {StatusCode::kParseError, cat(src.where(path), ": unexpected data ", quoted_token(src.bad_tok),
                                         " after the last element declared in the header")};
  }
  // Per-corner texture coordinates win over per-vertex ones (they can hold seams).
  if (h.face_texcoord >= 0 && h.face >= 0) {
    mesh.uvs = std::move(corner_uvs);
    mesh.uv_triangles = std::move(corner_uv_triangles);
  } else if (h.vertex_uvs) {
    mesh.uvs = std::move(vertex_uvs);
    mesh.uv_triangles = mesh.triangles;
  }
  if (h.vertex_colors) mesh.colors = std::move(colors);
  rep.attributes_dropped = h.dropped;
  return Status::Ok();
}

}  // namespace

size_t ply_text_end(string_view head) {
  if (head.substr(0, 3) == "\xEF\xBB\xBF") head.remove_prefix(3);  // load_mesh drops a BOM
  string_view format;
  for (size_t off = 0, line = 0;; ++line) {
    const size_t nl = head.find('\n', off);
    if (nl == string_view::npos) return kTextNotEnded;  // only whole lines are read
    LineTokens tk{head.data() + off, head.data() + nl};
    off = nl + 1;
    string_view kw;
    const bool blank = !tk.next(kw);
    if (line == 0 && (blank || kw != "ply")) return kAllText;  // not a PLY: read_ply says so
    if (blank) continue;
    if (kw == "format" && !tk.next(format)) format = {};
    if (kw == "end_header") return format == "ascii" ? kAllText : off;
  }
}

Status read_ply(const std::string& path, string_view data, Mesh& mesh, MeshLoadReport& rep, std::vector<dvec3>* world) {
  PlyHeader h;
  if (Status s = parse_ply_header(path, data, h); !s.ok()) return s;
  const string_view body = data.substr(h.data_offset);
  const auto* const ub = reinterpret_cast<const unsigned char*>(body.data());
  constexpr bool kLittleHost = std::endian::native == std::endian::little;
  Status s;
  switch (h.format) {
    case PlyFormat::kAscii: {
      AsciiSource src{body.data(), body.data() + body.size(), h.end_header_line + 1, h.end_header_line, {}, {}};
      s = read_ply_body(path, src, h, mesh, rep, world);
      rep.format = "ply-ascii";
      break;
    }
    case PlyFormat::kBinaryLe: {
      BinarySource<!kLittleHost> src{ub, ub + body.size(), {}};
      s = read_ply_body(path, src, h, mesh, rep, world);
      rep.format = "ply-binary-le";
      break;
    }
    case PlyFormat::kBinaryBe: {
      BinarySource<kLittleHost> src{ub, ub + body.size(), {}};
      s = read_ply_body(path, src, h, mesh, rep, world);
      rep.format = "ply-binary-be";
      break;
    }
  }
  return s;
}

}  // namespace gwnrt::io
