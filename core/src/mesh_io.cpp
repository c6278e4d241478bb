// Strict OBJ and PLY readers. General-purpose loaders turn a malformed number into 0, accept
// out-of-range indices or stop quietly at a truncated file; a silently wrong mesh gives
// silently wrong winding numbers, so here every such defect is an error that names the file
// and the line or element.
//
// Numbering in messages follows each format's own convention for references: OBJ vertices
// are 1-based (as in its `f` statements) and come with the line number; PLY elements are
// 0-based (as in its vertex_indices lists). Meshes checked by validate_mesh are 0-based.
//
// On failure, load_mesh leaves `mesh` and `report` untouched.

#include <bit>
#include <cerrno>
#include <charconv>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <string_view>
#include <system_error>
#include <type_traits>

#include "gwnrt/mesh.h"

namespace gwnrt {
namespace {

using std::int64_t;
using std::string_view;
using std::uint32_t;
using std::uint64_t;

// ---------------------------------------------------------------------------------------
// Messages

void append(std::string& s, string_view v) { s.append(v); }

template <class T>
  requires std::is_integral_v<T>
void append(std::string& s, T v) {
  char buf[24];
  s.append(buf, std::to_chars(buf, buf + sizeof buf, v).ptr);
}

void append(std::string& s, float v) {
  char buf[32];
  s.append(buf, std::to_chars(buf, buf + sizeof buf, v).ptr);
}

template <class... Parts>
std::string cat(const Parts&... parts) {
  std::string s;
  (append(s, parts), ...);
  return s;
}

// Tokens can come from arbitrary bytes; keep messages short and printable.
std::string quoted(string_view tok) {
  constexpr size_t kMax = 40;
  std::string s = "'";
  for (size_t i = 0; i < tok.size() && i < kMax; ++i) {
    const unsigned char c = static_cast<unsigned char>(tok[i]);
    s += (c >= 0x20 && c < 0x7f) ? static_cast<char>(c) : '?';
  }
  if (tok.size() > kMax) s += "...";
  s += '\'';
  return s;
}

// ---------------------------------------------------------------------------------------
// Numbers


// std::from_chars rejects the leading '+' that some exporters write.
string_view drop_plus(string_view s) {
  if (s.size() >= 2 && s[0] == '+' && s[1] != '+' && s[1] != '-') s.remove_prefix(1);
  return s;
}

template <class F>
bool parse_real(string_view s, F& out) {
  s = drop_plus(s);
  const char* const b = s.data();
  const char* const e = b + s.size();
  if (b == e) return false;
  F v{};
  const auto [ptr, ec] = std::from_chars(b, e, v);
  if (ptr != e) return false;
  if (ec == std::errc()) {
    out = v;
    return true;
  }
  if (ec != std::errc::result_out_of_range) return false;
  // A well-formed number beyond the type's range keeps IEEE semantics: an overflow becomes
  // an infinity (then reported as a non-finite coordinate), an underflow becomes zero.
  if constexpr (std::is_same_v<F, float>) {
    double d;
    if (!parse_real(s, d)) return false;
    out = static_cast<float>(d);  // IEC 559 narrowing: rounds, overflows to infinity
    return true;
  } else {
    // from_chars leaves the value unset; only the exponent's sign tells the two cases apart
    // (without an exponent, out of range needs more than 300 digits: an overflow).
    const bool negative = s[0] == '-';
    const size_t epos = s.find_first_of("eE");
    const bool underflow = epos != string_view::npos && epos + 1 < s.size() && s[epos + 1] == '-';
    const F mag = underflow ? F(0) : std::numeric_limits<F>::infinity();
    out = negative ? -mag : mag;
    return true;
  }
}

enum class IntParse { kOk, kMalformed, kOutOfRange };

IntParse parse_int(string_view s, int64_t& out) {
  s = drop_plus(s);
  const char* const b = s.data();
  const char* const e = b + s.size();
  if (b == e) return IntParse::kMalformed;
  const auto [ptr, ec] = std::from_chars(b, e, out);
  if (ptr != e) return IntParse::kMalformed;
  if (ec == std::errc::result_out_of_range) return IntParse::kOutOfRange;
  return ec == std::errc() ? IntParse::kOk : IntParse::kMalformed;
}

// ---------------------------------------------------------------------------------------
// Text scanning

inline bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

// Whitespace-separated tokens of one line.
struct LineTokens {
  const char* p;
  const char* end;
  bool next(string_view& tok) {
    while (p < end && is_blank(*p)) ++p;
    if (p == end) return false;
    const char* const b = p;
    while (p < end && !is_blank(*p)) ++p;
    tok = string_view(b, static_cast<size_t>(p - b));
    return true;
  }
};

// ---------------------------------------------------------------------------------------
// File access

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};

std::string errno_text(int err) { return std::error_code(err, std::generic_category()).message(); }

Status read_whole_file(const std::string& path, std::string& data) {
  std::error_code ec;
  // fopen succeeds on a directory on Linux and only the read fails, with a vaguer message.
  if (std::filesystem::is_directory(path, ec)) {
    return {StatusCode::kIoError, cat(path, ": cannot read: it is a directory")};
  }
  errno = 0;
  std::unique_ptr<std::FILE, FileCloser> f(std::fopen(path.c_str(), "rb"));
  if (!f) {
    const int err = errno;
    return {StatusCode::kIoError, cat(path, ": cannot open: ", err ? errno_text(err) : "unknown error")};
  }
  // The size is only a hint (the file may change, or be a pipe); one spare byte lets the
  // read that meets end-of-file finish without growing the buffer.
  const auto hint = std::filesystem::file_size(path, ec);
  data.resize(ec ? size_t(1) << 16 : static_cast<size_t>(hint) + 1);
  size_t n = 0;
  for (;;) {
    if (n == data.size()) data.resize(data.size() * 2);
    const size_t want = data.size() - n;
    const size_t got = std::fread(data.data() + n, 1, want, f.get());
    n += got;
    if (got < want) break;
  }
  if (std::ferror(f.get())) {
    return {StatusCode::kIoError, cat(path, ": read error: ", errno_text(errno))};
  }
  data.resize(n);
  return Status::Ok();
}

constexpr uint64_t kMaxVertices = uint64_t(std::numeric_limits<uint32_t>::max()) + 1;

void fan(const std::vector<uint32_t>& corners, std::vector<uvec3>& tris) {
  for (size_t i = 1; i + 1 < corners.size(); ++i) tris.emplace_back(corners[0], corners[i], corners[i + 1]);
}

// ---------------------------------------------------------------------------------------
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

// ---------------------------------------------------------------------------------------
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
    {"char", "int8", 1, true, INT8_MIN, INT8_MAX},       {"uchar", "uint8", 1, true, 0, UINT8_MAX},
    {"short", "int16", 2, true, INT16_MIN, INT16_MAX},   {"ushort", "uint16", 2, true, 0, UINT16_MAX},
    {"int", "int32", 4, true, INT32_MIN, INT32_MAX},     {"uint", "uint32", 4, true, 0, UINT32_MAX},
    {"float", "float32", 4, false, 0, 0},                {"double", "float64", 8, false, 0, 0},
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
  int coord = -1;  // 0, 1, 2 for the vertex x, y, z
};

struct PlyElem {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProp> props;
};

enum class PlyFormat { kAscii, kBinaryLe, kBinaryBe };

struct PlyHeader {
  PlyFormat format = PlyFormat::kAscii;
  std::vector<PlyElem> elems;
  int vertex = -1;     // element indices
  int face = -1;
  int face_list = -1;  // property index of vertex_indices within the face element
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
      if (tk.next(extra)) return err("unexpected ", quoted(extra), " after end_header");
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
        return err("unsupported PLY format ", quoted(a));
      }
      if (b != "1.0" && b != "1") return err("unsupported PLY format version ", quoted(b), " (expected 1.0)");
      have_format = true;
    } else if (kw == "element") {
      if (!have_format) return err("'element' before the 'format' line (missing format line?)");
      if (!tk.next(a) || !tk.next(b) || tk.next(extra)) return err("malformed element line (expected 'element NAME COUNT')");
      const char* const e = b.data() + b.size();
      uint64_t count = 0;
      const auto [ptr, ec] = std::from_chars(b.data(), e, count);
      if (ec != std::errc() || ptr != e) return err("malformed element count ", quoted(b));
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
        if (!ct) return err("unknown property type ", quoted(b));
        if (!it) return err("unknown property type ", quoted(c));
        if (!info(*ct).is_int) return err("list count type ", quoted(b), " is not an integer type");
        prop.list = true;
        prop.count_type = *ct;
        prop.type = *it;
        prop.name = std::string(d);
      } else {
        if (!tk.next(b) || tk.next(extra)) return err("malformed property line (expected 'property TYPE NAME')");
        const auto t = parse_ty(a);
        if (!t) return err("unknown property type ", quoted(a));
        prop.type = *t;
        prop.name = std::string(b);
      }
      h.elems.back().props.push_back(std::move(prop));
    } else {
      return err("unknown PLY header keyword ", quoted(kw), " (missing end_header?)");
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
  static constexpr const char* kCoordNames[3] = {"x", "y", "z"};
  for (int k = 0; k < 3; ++k) {
    PlyProp* found = nullptr;
    for (PlyProp& p : vertex.props) {
      if (p.name == kCoordNames[k]) {
        found = &p;
        break;
      }
    }
    if (!found) {
      return {StatusCode::kParseError, cat(path, ": the vertex element has no '", kCoordNames[k], "' property")};
    }
    if (found->list) {
      return {StatusCode::kParseError, cat(path, ": vertex property '", kCoordNames[k], "' is a list, not a scalar")};
    }
    found->coord = k;
  }
  if (h.face >= 0) {
    const PlyElem& face = h.elems[static_cast<size_t>(h.face)];
    for (size_t j = 0; j < face.props.size() && h.face_list < 0; ++j) {
      if (face.props[j].name == "vertex_indices" || face.props[j].name == "vertex_index") h.face_list = static_cast<int>(j);
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
  // Only called with integer types (the header rejects others where integers are needed).
  Res read_int(Ty t, int64_t& v) { return read_value(t, v); }

 private:
  // One value of type t; float types never decode into an integer V.
  template <class V>
  Res read_value(Ty t, V& v) {
    if (remaining() < info(t).size) return Res::kEnd;
    switch (t) {
      case Ty::kI8: v = static_cast<int8_t>(*p); break;
      case Ty::kU8: v = *p; break;
      case Ty::kI16: v = std::bit_cast<int16_t>(load_bits<kSwap, uint16_t>(p)); break;
      case Ty::kU16: v = load_bits<kSwap, uint16_t>(p); break;
      case Ty::kI32: v = std::bit_cast<int32_t>(load_bits<kSwap, uint32_t>(p)); break;
      case Ty::kU32: v = load_bits<kSwap, uint32_t>(p); break;
      case Ty::kF32:
        if constexpr (std::is_integral_v<V>) return Res::kBad;
        else v = std::bit_cast<float>(load_bits<kSwap, uint32_t>(p));
        break;
      case Ty::kF64:
        if constexpr (std::is_integral_v<V>) return Res::kBad;
        else v = std::bit_cast<double>(load_bits<kSwap, uint64_t>(p));
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

  bool only_whitespace_left() const { return true; }  // trailing bytes after binary data are tolerated
};

struct AsciiSource {
  static constexpr bool kAscii = true;
  const char* p;
  const char* end;
  size_t line;       // line of the scan position
  size_t tok_line;   // line of the last token read, for messages
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
Status read_ply_body(const std::string& path, Src& src, const PlyHeader& h, Mesh& mesh, MeshLoadReport& rep) {
  const uint64_t nverts = h.elems[static_cast<size_t>(h.vertex)].count;
  std::vector<uint32_t> corners;

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
    if (is_vertex) mesh.positions.resize(el.count);

    for (uint64_t i = 0; i < el.count; ++i) {
      float xyz[3] = {0, 0, 0};
      for (size_t j = 0; j < el.props.size(); ++j) {
        const PlyProp& pr = el.props[j];
        Res r;
        if (!pr.list) {
          if (is_vertex && pr.coord >= 0) {
            double v = 0;
            r = src.read_real(pr.type, v);
            xyz[pr.coord] = static_cast<float>(v);  // IEC 559 narrowing: rounds, overflows to infinity
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
              return {StatusCode::kInvalidMesh, cat(src.where(path), ": face ", i, " has ", n, " corners, needs at least 3")};
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
          } else if (r == Res::kOk) {
            r = src.skip(pr.type, static_cast<uint64_t>(n));
          }
        }
        if (r == Res::kEnd) {
          return {StatusCode::kParseError, cat(src.where(path), ": truncated data: the file ends inside ", el.name, " ", i,
                                               " of ", el.count, " (property '", pr.name, "')")};
        }
        if (r == Res::kBad) {
          return {StatusCode::kParseError, cat(src.where(path), ": invalid ", info(src.bad_ty).name, " value ",
                                               quoted(src.bad_tok), " in ", el.name, " ", i, ", property '", pr.name, "'")};
        }
      }
      if (is_vertex) mesh.positions[i] = vec3(xyz[0], xyz[1], xyz[2]);
    }
  }
  if (!src.only_whitespace_left()) {
    return {StatusCode::kParseError,
            cat(src.where(path), ": unexpected data ", quoted(src.bad_tok), " after the last element declared in the header")};
  }
  return Status::Ok();
}

Status read_ply(const std::string& path, string_view data, Mesh& mesh, MeshLoadReport& rep) {
  PlyHeader h;
  if (Status s = parse_ply_header(path, data, h); !s) return s;
  const string_view body = data.substr(h.data_offset);
  const auto* const ub = reinterpret_cast<const unsigned char*>(body.data());
  constexpr bool kLittleHost = std::endian::native == std::endian::little;
  Status s;
  switch (h.format) {
    case PlyFormat::kAscii: {
      AsciiSource src{body.data(), body.data() + body.size(), h.end_header_line + 1, h.end_header_line, {}, {}};
      s = read_ply_body(path, src, h, mesh, rep);
      rep.format = "ply-ascii";
      break;
    }
    case PlyFormat::kBinaryLe: {
      BinarySource<!kLittleHost> src{ub, ub + body.size(), {}};
      s = read_ply_body(path, src, h, mesh, rep);
      rep.format = "ply-binary-le";
      break;
    }
    case PlyFormat::kBinaryBe: {
      BinarySource<kLittleHost> src{ub, ub + body.size(), {}};
      s = read_ply_body(path, src, h, mesh, rep);
      rep.format = "ply-binary-be";
      break;
    }
  }
  return s;
}

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) {
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  return ext;
}

}  // namespace

bool is_degenerate_triangle(const vec3& a, const vec3& b, const vec3& c) {
  const dvec3 n = glm::cross(dvec3(b) - dvec3(a), dvec3(c) - dvec3(a));
  return n.x == 0.0 && n.y == 0.0 && n.z == 0.0;
}

Status validate_mesh(const Mesh& mesh, const std::string& source) {
  const std::vector<vec3>& pos = mesh.positions;
  for (size_t i = 0; i < pos.size(); ++i) {
    const vec3& p = pos[i];
    if (!is_finite(p.x) || !is_finite(p.y) || !is_finite(p.z)) {
      return {StatusCode::kInvalidMesh,
              cat(source, ": vertex ", i, " has a non-finite coordinate (", p.x, ", ", p.y, ", ", p.z, ")")};
    }
  }
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = mesh.triangles[t][k];
      if (v >= pos.size()) {
        return {StatusCode::kInvalidMesh,
                cat(source, ": triangle ", t, " refers to vertex ", v, " but there are ", pos.size(), " vertices")};
      }
    }
  }
  if (mesh.triangles.empty()) return {StatusCode::kInvalidMesh, cat(source, ": the mesh has no triangles")};
  return Status::Ok();
}

Status load_mesh(const std::string& path, Mesh& mesh, MeshLoadReport* report) {
  const std::string ext = lower_extension(path);
  const bool is_obj = ext == ".obj";
  if (!is_obj && ext != ".ply") {
    return {StatusCode::kInvalidArgument,
            cat(path, ": unsupported mesh file extension '", ext, "' (expected .obj or .ply)")};
  }
  std::string data;
  if (Status s = read_whole_file(path, data); !s) return s;

  Mesh m;
  MeshLoadReport rep;
  Status s = is_obj ? read_obj(path, data, m, rep) : read_ply(path, data, m, rep);
  if (!s) return s;
  if (s = validate_mesh(m, path); !s) return s;

  rep.vertex_count = m.positions.size();
  rep.triangle_count = m.triangles.size();
  for (const uvec3& t : m.triangles) {
    rep.degenerate_triangles += is_degenerate_triangle(m.positions[t.x], m.positions[t.y], m.positions[t.z]);
  }
  mesh = std::move(m);
  if (report) *report = std::move(rep);
  return Status::Ok();
}

}  // namespace gwnrt
