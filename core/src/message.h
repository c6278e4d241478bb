// Building error messages inside core: cat() joins strings, numbers and floats (shortest
// round-trip form) without iostreams; quoted() makes an untrusted token short and printable.
#pragma once

#include <charconv>
#include <string>
#include <string_view>
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

template <class... Parts>
std::string cat(const Parts&... parts) {
  std::string s;
  (append(s, parts), ...);
  return s;
}

// Tokens can come from arbitrary bytes; keep messages short and printable.
inline std::string quoted(std::string_view tok) {
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

}  // namespace gwnrt
