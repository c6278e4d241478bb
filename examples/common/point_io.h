// Query points as text: one "x y z" per line, blank lines and '#' comments ignored. Parsing is
// strict (exactly three finite numbers per line) because a silently skipped or half-read line
// would shift every later row of the output against its input.
#pragma once

#include <charconv>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "gwnrt/hd.h"
#include "gwnrt/status.h"

namespace gwnrt::examples {

namespace point_io_detail {

inline bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

// Whole-stream reads: point files run to millions of lines, and one buffer is much faster than
// line-by-line stream extraction.
inline bool read_all(std::FILE* f, std::string& out) {
  char buf[1 << 16];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) out.append(buf, n);
  return !std::ferror(f);
}

}  // namespace point_io_detail

// Parses `text`; `source` names it in messages ("<source>:<line>: ...").
inline Status parse_points(std::string_view text, const std::string& source, std::vector<vec3>& points) {
  using namespace point_io_detail;
  points.clear();
  size_t line_no = 0;
  size_t pos = 0;
  while (pos < text.size()) {
    ++line_no;
    size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(pos, end - pos);
    pos = end + 1;
    if (const size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);

    // Built only on failure: one allocation per line would dominate the parse of large files.
    const auto where = [&] { return source + ":" + std::to_string(line_no) + ": "; };
    float xyz[3];
    int count = 0;
    size_t i = 0;
    while (true) {
      while (i < line.size() && is_space(line[i])) ++i;
      if (i == line.size()) break;
      size_t j = i;
      while (j < line.size() && !is_space(line[j])) ++j;
      std::string_view token = line.substr(i, j - i);
      i = j;
      if (count == 3) {
        return {StatusCode::kParseError, where() + "expected 3 numbers (x y z), found more"};
      }
      // from_chars rejects a leading '+', which people do write.
      std::string_view digits = token;
      if (digits.size() > 1 && digits[0] == '+' && digits[1] != '-' && digits[1] != '+') digits.remove_prefix(1);
      float value = 0;
      const char* const last = digits.data() + digits.size();
      std::from_chars_result r = std::from_chars(digits.data(), last, value);
      if (r.ec == std::errc::result_out_of_range) {
        // Tiny magnitudes underflow a float but are fine as coordinates; only overflow is an error.
        double wide = 0;
        r = std::from_chars(digits.data(), last, wide);
        if (r.ec == std::errc() && std::abs(wide) <= 1.0) {
          value = float(wide);
        } else {
          return {StatusCode::kParseError, where() + "number out of range: '" + std::string(token) + "'"};
        }
      }
      if (r.ec != std::errc() || r.ptr != last) {
        return {StatusCode::kParseError, where() + "not a number: '" + std::string(token) + "'"};
      }
      if (!std::isfinite(value)) {
        return {StatusCode::kParseError, where() + "non-finite coordinate: '" + std::string(token) + "'"};
      }
      xyz[count++] = value;
    }
    if (count == 0) continue;
    if (count != 3) {
      return {StatusCode::kParseError,
              where() + "expected 3 numbers (x y z), found " + std::to_string(count)};
    }
    points.emplace_back(xyz[0], xyz[1], xyz[2]);
  }
  return Status::Ok();
}

// Reads points from `path`, or from standard input when `path` is "-".
inline Status read_points(const std::string& path, std::vector<vec3>& points) {
  using namespace point_io_detail;
  std::string text;
  if (path == "-") {
    if (!read_all(stdin, text)) return {StatusCode::kIoError, "<stdin>: read error"};
    return parse_points(text, "<stdin>", points);
  }
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return {StatusCode::kIoError, path + ": cannot open points file: " + std::strerror(errno)};
  const bool ok = read_all(f, text);
  std::fclose(f);
  if (!ok) return {StatusCode::kIoError, path + ": read error"};
  return parse_points(text, path, points);
}

}  // namespace gwnrt::examples
