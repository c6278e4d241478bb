// Building error messages inside core: cat() joins strings, integers, floats and doubles (shortest
// round-trip form) without iostreams (tokens from files: quoted_token, gwnrt/io/read_file.h).
#pragma once

#include <charconv>
#include <cmath>
#include <string>
#include <string_view>
#include <system_error>
#include <type_traits>

namespace gwnrt {

inline void append(std::string& s, std::string_view v) { s.append(v); }

template <class T>
requires std::is_integral_v<T>
inline void append(std::string& s, T v) {
  char buf[24];
  s.append(buf, std::to_chars(buf, buf + sizeof buf, v).ptr);
}

inline void append(std::string& s, float v) {
  char buf[32];
  s.append(buf, std::to_chars(buf, buf + sizeof buf, v).ptr);
}

inline void append(std::string& s, double v) {
  char buf[40];
  s.append(buf, std::to_chars(buf, buf + sizeof buf, v).ptr);
}

template <class... Parts>
std::string cat(const Parts&... parts) {
  std::string s;
  (append(s, parts), ...);
  return s;
}

// "has a non-finite coordinate (x, y, z)", for a vertex's message. Readers round a number beyond
// float's range to infinity, so an infinity is said to be either (the file may hold neither
// "inf" nor anything non-finite: 3.5e38, or a double far out).
inline std::string non_finite_coordinate(float x, float y, float z) {
  const bool infinite = std::isinf(x) || std::isinf(y) || std::isinf(z);
  return cat("has a non-finite coordinate (", x, ", ", y, ", ", z, ")",
             infinite ? std::string_view(": infinite, or beyond float's range (+-3.4e38)") : std::string_view());
}

// The refusal of an accuracy scale beta outside beta_valid (gwnrt/base/option_limits.h).
inline std::string beta_refusal(float beta) {
  return cat(
      "accuracy scale beta must be a finite number >= 1 (clusters are expanded beyond beta radii, where "
      "their series converge), got ",
      beta);
}

// The system's words for an errno value (0: the call set none).
inline std::string errno_text(int err) {
  return err ? std::error_code(err, std::generic_category()).message() : std::string("unknown error");
}

}  // namespace gwnrt
