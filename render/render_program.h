// What gwnrt-render's jobs report with: every line starts with the program's name, warnings say
// so, and counts agree with their nouns.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>

namespace gwnrt::render {

inline constexpr const char* kProgram = "gwnrt-render";

inline void warn(const std::string& message) { std::fprintf(stderr, "%s: warning: %s\n", kProgram, message.c_str()); }

// "1 ray", "2 rays".
inline std::string count_of(uint64_t n, const char* noun) {
  return std::to_string(n) + " " + noun + (n == 1 ? "" : "s");
}

}  // namespace gwnrt::render
