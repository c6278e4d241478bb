// What the mesh readers share: strict number parsing (a malformed number is an error, never a
// 0), line tokens and polygon fanning (files are read by gwnrt/io/read_file.h); and with the
// writers, the format a path names.
#pragma once

#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <string_view>
#include <system_error>
#include <type_traits>
#include <vector>

#include "base/message.h"
#include "gwnrt/base/status.h"
#include "gwnrt/geometry/mesh.h"

namespace gwnrt::io {

using std::int64_t;
using std::string_view;
using std::uint32_t;
using std::uint64_t;

// A path's extension in lower case ("" without one): the format it names.
inline std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) {
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  return ext;
}

// Numbers

// std::from_chars rejects the leading '+' that some exporters write.
inline string_view drop_plus(string_view s) {
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

inline IntParse parse_int(string_view s, int64_t& out) {
  s = drop_plus(s);
  const char* const b = s.data();
  const char* const e = b + s.size();
  if (b == e) return IntParse::kMalformed;
  const auto [ptr, ec] = std::from_chars(b, e, out);
  if (ptr != e) return IntParse::kMalformed;
  if (ec == std::errc::result_out_of_range) return IntParse::kOutOfRange;
  return ec == std::errc() ? IntParse::kOk : IntParse::kMalformed;
}

// Text scanning

inline bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

// A byte that text does not hold: a control byte other than whitespace and the newline.
inline bool is_binary_byte(char c) { return static_cast<unsigned char>(c) < 0x20 && !is_blank(c) && c != '\n'; }

// "binary content (byte 0x1a)": how the readers name such a byte.
inline std::string binary_byte_text(char c) {
  const auto b = static_cast<unsigned char>(c);
  const char hex[] = "0123456789abcdef", byte[3] = {hex[b >> 4], hex[b & 15], 0};
  return cat("binary content (byte 0x", byte, ")");
}

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

inline constexpr uint64_t kMaxVertices = uint64_t(std::numeric_limits<uint32_t>::max()) + 1;

inline void fan(const std::vector<uint32_t>& corners, std::vector<uvec3>& tris) {
  for (size_t i = 1; i + 1 < corners.size(); ++i) tris.emplace_back(corners[0], corners[i], corners[i + 1]);
}

}  // namespace gwnrt::io
