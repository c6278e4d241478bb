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

#include "gwnrt/base/hd.h"
#include "gwnrt/base/status.h"
#include "gwnrt/geometry/ray.h"
#include "gwnrt/io/read_file.h"
#include "gwnrt/query/validation.h"

namespace gwnrt::apps {

namespace point_io_detail {

inline bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

enum class Read { kOk, kOutOfRange, kNotANumber };

// Tiny magnitudes underflow a float (or a double) but are fine as coordinates (0, as the mesh
// readers read them); only overflow is an error. strtod, unlike from_chars, says which it was
// beyond double's range too (1e-400 was refused as out of range while 1e-50 read as 0).
inline Read underflow_or_overflow(std::string_view digits, double& value) {
  const std::string text(digits);
  char* end = nullptr;
  const double wide = std::strtod(text.c_str(), &end);
  if (end == text.c_str() + text.size() && std::abs(wide) <= 1.0) {
    value = wide;
    return Read::kOk;
  }
  return Read::kOutOfRange;
}

// `digits` read straight into a float: how every number was read before positions were read in
// double, and how a number exactly halfway between two floats is still read (rounded to double
// first, it could round to the other one).
inline Read read_float(std::string_view digits, float& value) {
  const char* const last = digits.data() + digits.size();
  const std::from_chars_result r = std::from_chars(digits.data(), last, value);
  if (r.ec == std::errc::result_out_of_range) {
    double wide = 0;
    if (underflow_or_overflow(digits, wide) != Read::kOk) return Read::kOutOfRange;
    value = float(wide);
    return Read::kOk;
  }
  return r.ec == std::errc() && r.ptr == last ? Read::kOk : Read::kNotANumber;
}

// Whether `d` lies exactly halfway between two floats, where rounding it to float can differ
// from rounding its decimal text to float.
inline bool halfway_between_floats(double d) {
  const float f = float(d);
  if (double(f) == d) return false;
  // Halfway between the largest float and the next power of 2 (rounded to even: overflow).
  if (std::isinf(f)) return std::fabs(d) == 0x1.ffffffp127;
  const float g = std::nextafter(f, double(f) < d ? HUGE_VALF : -HUGE_VALF);
  return !std::isinf(g) && d - double(f) == double(g) - d;
}

// `digits` in double (`wide`: a world coordinate such as 4123456.789 keeps its digits) and in
// float (`narrow`: exactly read_float's value, the one every column had before). A finite
// number beyond float's range is out of range, as it was.
inline Read read_number(std::string_view digits, double& wide, float& narrow) {
  const char* const last = digits.data() + digits.size();
  std::from_chars_result r = std::from_chars(digits.data(), last, wide);
  if (r.ec == std::errc::result_out_of_range) {
    if (underflow_or_overflow(digits, wide) != Read::kOk) return Read::kOutOfRange;
    r.ec = std::errc();
  }
  if (r.ec != std::errc() || r.ptr != last) return Read::kNotANumber;
  if (halfway_between_floats(wide)) return read_float(digits, narrow);
  narrow = float(wide);
  return std::isinf(narrow) && !std::isinf(wide) ? Read::kOutOfRange : Read::kOk;
}

// A position read in double, moved by -origin and rounded to float. With a zero origin exactly
// the float read (bit for bit what was read before).
inline float shifted(double wide, float narrow, double origin) { return origin == 0.0 ? narrow : float(wide - origin); }

}  // namespace point_io_detail

// A row is a few numbers and perhaps a comment: a longer line is not a points or rays file (or a
// stream that never ends a line, such as /dev/zero), and reading stops there.
inline constexpr uint64_t kMaxRowLineBytes = uint64_t(1) << 20;

// Parses `text` as rows of numbers; `source` names it in messages ("<source>:<line>: ...").
// A row must hold one of `counts` numbers (`layout` describes them in errors); column c may be
// +/-inf only when `infinite_ok(c)` says so, NaN never. `row(wide, values, count, line)` consumes
// it: each number in double (for positions far from the origin, point_io_detail::shifted) and in
// float.
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
    double wide[kMaxColumns];
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
      double value = 0;
      float narrow = 0;
      switch (read_number(digits, value, narrow)) {
        case Read::kOutOfRange:
          return {StatusCode::kParseError, where() + "number out of range: " + quoted_token(token)};
        case Read::kNotANumber:
          return {StatusCode::kParseError, where() + "not a number: " + quoted_token(token)};
        case Read::kOk:
          break;
      }
      if (std::isnan(value) || (std::isinf(value) && !infinite_ok(count))) {
        return {StatusCode::kParseError, where() + "non-finite value: " + quoted_token(token)};
      }
      wide[count] = value;
      values[count++] = narrow;
    }
    if (count == 0) continue;
    bool allowed = false;
    for (int c : counts) allowed = allowed || c == count;
    if (!allowed) {
      return {StatusCode::kParseError,
              where() + "expected " + layout + ", found " + std::to_string(count) + " numbers"};
    }
    if (Status s = row(wide, values, count, line_no); !s.ok()) return {s.code(), where() + s.message()};
  }
  return Status::Ok();
}

// Points: exactly three finite numbers per line, read in double and moved by -`origin` (the
// MeshLoadReport::origin of a recentred mesh: the model's coordinates are the file's minus it)
// before they are rounded to float. The coordinates served are those after the move: the ones
// the library is asked about.
inline Status parse_points(std::string_view text, const std::string& source, std::vector<vec3>& points,
                           const dvec3& origin = dvec3(0.0)) {
  points.clear();
  return parse_rows(
      text, source, {3}, "3 numbers (x y z)", [](int) { return false; },
      [&](const double* w, const float* v, int, size_t) -> Status {
        using point_io_detail::shifted;
        // The library refuses these too, but names only the point's index: here the file and line.
        const vec3 p(shifted(w[0], v[0], origin.x), shifted(w[1], v[1], origin.y), shifted(w[2], v[2], origin.z));
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

// Reads points from `path`, or from standard input when `path` is "-" (parse_points).
inline Status read_points(const std::string& path, std::vector<vec3>& points, const dvec3& origin = dvec3(0.0)) {
  std::string text, source;
  if (Status s = read_text(path, text, source); !s.ok()) return s;
  return parse_points(text, source, points, origin);
}

// One ray per line: "ox oy oz dx dy dz [tnear tfar]"; tfar may be inf. The ray's origin is read
// as parse_points reads a point (moved by -`origin`); its direction, tnear and tfar are not moved.
inline Status parse_rays(std::string_view text, const std::string& source, std::vector<Ray>& rays,
                         const dvec3& origin = dvec3(0.0)) {
  rays.clear();
  return parse_rows(
      text, source, {6, 8}, "6 or 8 numbers (ox oy oz dx dy dz [tnear tfar])", [](int column) { return column == 7; },
      [&](const double* w, const float* v, int count, size_t) -> Status {
        using point_io_detail::shifted;
        Ray r;
        r.origin = vec3(shifted(w[0], v[0], origin.x), shifted(w[1], v[1], origin.y), shifted(w[2], v[2], origin.z));
        // Only a huge origin can move a float's worth of coordinate beyond float's range.
        if (!std::isfinite(r.origin.x) || !std::isfinite(r.origin.y) || !std::isfinite(r.origin.z))
          return {StatusCode::kParseError, "ray origin beyond float's range about the mesh's origin"};
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

// Reads rays from `path`, or from standard input when `path` is "-" (parse_rays).
inline Status read_rays(const std::string& path, std::vector<Ray>& rays, const dvec3& origin = dvec3(0.0)) {
  std::string text, source;
  if (Status s = read_text(path, text, source); !s.ok()) return s;
  return parse_rays(text, source, rays, origin);
}

}  // namespace gwnrt::apps
