// Points and rays as text: rows of numbers, blank lines and '#' comments ignored. Parsing is
// strict (the exact count of numbers per line) because a silently skipped or half-read line
// would shift every later row of the output against its input.
#pragma once

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "gwnrt/batch.h"
#include "gwnrt/hd.h"
#include "gwnrt/io/read_file.h"
#include "gwnrt/status.h"
#include "gwnrt/trace/ray.h"

namespace gwnrt::examples {

namespace point_io_detail {

inline bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

}  // namespace point_io_detail

// A row is a few numbers and perhaps a comment: a longer line is not a points or rays file (or a
// stream that never ends a line, such as /dev/zero), and reading stops there.
inline constexpr uint64_t kMaxRowLineBytes = uint64_t(1) << 20;

// Parses `text` as rows of numbers; `source` names it in messages ("<source>:<line>: ...").
// A row must hold one of `counts` numbers (`layout` describes them in errors); column c may be
// +/-inf only when `infinite_ok(c)` says so, NaN never. `row(values, count, line)` consumes it.
template <class InfiniteOk, class RowFn>
inline Status parse_rows(std::string_view text, const std::string& source, std::initializer_list<int> counts,
                         const char* layout, InfiniteOk infinite_ok, RowFn row) {
  using namespace point_io_detail;
  constexpr int kMaxColumns = 16;
  int max_count = 0;
  for (int c : counts) max_count = c > max_count ? c : max_count;
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
    float values[kMaxColumns];
    int count = 0;
    size_t i = 0;
    while (true) {
      while (i < line.size() && is_space(line[i])) ++i;
      if (i == line.size()) break;
      size_t j = i;
      while (j < line.size() && !is_space(line[j])) ++j;
      std::string_view token = line.substr(i, j - i);
      i = j;
      if (count == max_count || count == kMaxColumns) {
        return {StatusCode::kParseError, where() + "expected " + layout + ", found more numbers"};
      }
      // from_chars rejects a leading '+', which people do write.
      std::string_view digits = token;
      if (digits.size() > 1 && digits[0] == '+' && digits[1] != '-' && digits[1] != '+') digits.remove_prefix(1);
      float value = 0;
      const char* const last = digits.data() + digits.size();
      std::from_chars_result r = std::from_chars(digits.data(), last, value);
      if (r.ec == std::errc::result_out_of_range) {
        // Tiny magnitudes underflow a float but are fine as coordinates (0, as the mesh readers
        // read them); only overflow is an error. strtod, unlike from_chars, says which it was
        // beyond double's range too (1e-400 was refused as out of range while 1e-50 read as 0).
        const std::string text(digits);
        char* end = nullptr;
        const double wide = std::strtod(text.c_str(), &end);
        if (end == text.c_str() + text.size() && std::abs(wide) <= 1.0) {
          value = float(wide);
          r.ec = std::errc();
        } else {
          return {StatusCode::kParseError, where() + "number out of range: " + quoted_token(token)};
        }
      }
      if (r.ec != std::errc() || r.ptr != last) {
        return {StatusCode::kParseError, where() + "not a number: " + quoted_token(token)};
      }
      if (std::isnan(value) || (std::isinf(value) && !infinite_ok(count))) {
        return {StatusCode::kParseError, where() + "non-finite value: " + quoted_token(token)};
      }
      values[count++] = value;
    }
    if (count == 0) continue;
    bool allowed = false;
    for (int c : counts) allowed = allowed || c == count;
    if (!allowed) {
      return {StatusCode::kParseError,
              where() + "expected " + layout + ", found " + std::to_string(count) + " numbers"};
    }
    if (Status s = row(values, count, line_no); !s.ok()) return {s.code(), where() + s.message()};
  }
  return Status::Ok();
}

// Points: exactly three finite numbers per line.
inline Status parse_points(std::string_view text, const std::string& source, std::vector<vec3>& points) {
  points.clear();
  return parse_rows(
      text, source, {3}, "3 numbers (x y z)", [](int) { return false; },
      [&](const float* v, int, size_t) -> Status {
        // The library refuses these too, but names only the point's index: here the file and line.
        const vec3 p(v[0], v[1], v[2]);
        if (!query_point_served(p)) {
          char limit[32];
          std::snprintf(limit, sizeof limit, "%g", double(kMaxQueryCoordinate));
          return {StatusCode::kParseError,
                  std::string("coordinate beyond +-") + limit + ", the coordinates gwnrt serves"};
        }
        points.push_back(p);
        return Status::Ok();
      });
}

// The whole of `path`, or of standard input when `path` is "-" (whole-stream reads: point files
// run to millions of lines, and one buffer is much faster than line-by-line extraction), within
// kMaxRowLineBytes per line and the memory available; `source` becomes its name in messages.
inline Status read_text(const std::string& path, std::string& text, std::string& source) {
  source = source_name(path);
  ReadLimits limits;
  limits.max_line_bytes = kMaxRowLineBytes;
  return read_file(path, text, limits);
}

// Reads points from `path`, or from standard input when `path` is "-".
inline Status read_points(const std::string& path, std::vector<vec3>& points) {
  std::string text, source;
  if (Status s = read_text(path, text, source); !s.ok()) return s;
  return parse_points(text, source, points);
}

// One ray per line: "ox oy oz dx dy dz [tnear tfar]"; tfar may be inf.
inline Status read_rays(const std::string& path, std::vector<Ray>& rays) {
  std::string text, source;
  if (Status s = read_text(path, text, source); !s.ok()) return s;
  rays.clear();
  return parse_rows(
      text, source, {6, 8}, "6 or 8 numbers (ox oy oz dx dy dz [tnear tfar])", [](int column) { return column == 7; },
      [&](const float* v, int count, size_t) -> Status {
        Ray r;
        r.origin = vec3(v[0], v[1], v[2]);
        r.direction = vec3(v[3], v[4], v[5]);
        if (r.direction == vec3(0.0f)) return {StatusCode::kParseError, "ray direction is zero"};
        if (!(glm::length(dvec3(r.direction)) >= double(kMinDirectionLength)))
          return {StatusCode::kParseError, "ray direction is too short to normalise (below 1.2e-38)"};
        if (!std::isfinite(glm::length(r.direction)))
          return {StatusCode::kParseError, "ray direction is too long (its length overflows a float)"};
        if (count == 8) {
          r.tnear = v[6];
          r.tfar = v[7];
          if (!(r.tnear <= r.tfar)) return {StatusCode::kParseError, "tnear must not exceed tfar"};
        }
        rays.push_back(r);
        return Status::Ok();
      });
}

}  // namespace gwnrt::examples
