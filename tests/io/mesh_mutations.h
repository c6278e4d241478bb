// Generated hostile mesh files: small valid files (mesh_files.h) and a few hundred deterministic
// mutations of them, each named by its recipe (base, mutation, seed) so that a failure
// reproduces. The mesh readers (io/test_fuzz_readers.cpp) and the programs
// (apps/test_fuzz_inputs.cpp) are run on them.
#pragma once

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "mesh_files.h"

namespace gwnrt {
// ---------------------------------------------------------------------------------------------
// Inputs: small valid files and their mutations.

// A closed tetrahedron (outward), as OBJ: the model built from it has no boundary, so queries take
// the crossing path; the small mesh (open, polygons, attributes) takes the cone and the tree.
inline const char* const kTetraObj =
    "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
    "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

struct Base {
  const char* name;
  const char* ext;
  std::string bytes;
  bool binary_body = false;  // a PLY whose body after end_header is binary, or a binary STL
};

inline std::vector<Base> bases() {
  const test::Small small;
  return {{"small_obj", ".obj", test::kSmallObj},
          {"tetra_obj", ".obj", kTetraObj},
          {"ply_ascii", ".ply", test::small_ply("ascii", small.positions)},
          {"ply_le", ".ply", test::small_ply("binary_little_endian", small.positions), true},
          {"ply_be", ".ply", test::small_ply("binary_big_endian", small.positions), true},
          {"stl_ascii", ".stl", test::small_stl(false)},
          {"stl_binary", ".stl", test::small_stl(true), true}};
}

// Numbers a file may hold that a reader must refuse or carry safely: beyond float or double, NaN,
// infinities, denormals, and texts that only look like numbers.
inline const std::vector<std::string> kHostileReals = {"nan",    "-nan",    "inf",          "-inf",
                                                       "1e39",   "-3.5e38", "3.4028236e38", "1e400",
                                                       "-1e400", "1e-45",   "1e-320",       "4.9e-324",
                                                       "1e-400", "-0",      "0x1p3",        "1e",
                                                       "--1",    "+-1",     "1.0.0",        std::string(400, '9')};
// Indices and counts: zero, negative, at and beyond 2^31, 2^32, 2^63, 2^64, and malformed ones.
inline const std::vector<std::string> kHostileIntegers = {"0",
                                                          "-1",
                                                          "-7",
                                                          "-2147483648",
                                                          "2147483647",
                                                          "2147483648",
                                                          "4294967295",
                                                          "4294967296",
                                                          "9223372036854775807",
                                                          "-9223372036854775808",
                                                          "18446744073709551615",
                                                          "18446744073709551616",
                                                          "99999999999999999999999",
                                                          "1/0",
                                                          "1//-3",
                                                          "1/-9/2",
                                                          "1.5",
                                                          "1e3",
                                                          "0x10"};
// Binary words: float NaN, ±inf, the largest finite, a denormal, -0; integers -1, 2^31 - 1, -2^31, 255.
inline const uint32_t kHostileWords[] = {0x7fc00000u, 0x7f800000u, 0xff800000u, 0x7f7fffffu, 0x00000001u,
                                         0x80000000u, 0xffffffffu, 0x7fffffffu, 0x000000ffu, 0x0000ffffu};

enum Mutation {
  kTruncate,      // a prefix
  kFlipBytes,     // 1-6 bytes set to random values
  kRealToken,     // a number replaced by a hostile one
  kIntegerToken,  // an integer (index, count) replaced by a hostile one
  kHugePolygon,   // a face with 100000 corners (OBJ) or a header count of 4e9 and beyond (PLY)
  kBom,           // a UTF-8 byte-order mark (and a second one later)
  kLineEnds,      // CRLF, CR alone, or mixed
  kNulBytes,      // NUL bytes inserted
  kLongLine,      // a line of 4 KiB to 1 MiB: comment, number, tokens
  kLineShuffle,   // a line duplicated, deleted or swapped
  kGarbageLine,   // a line of random printable or binary bytes
  kBinaryWord,    // a 4-byte word of the binary body overwritten (text: like kFlipBytes)
  kTwo,           // two of the above
  kMutationCount
};

inline const char* const kMutationNames[] = {
    "truncate",  "flip-bytes", "real-token",   "integer-token", "huge-polygon", "bom", "line-ends",
    "nul-bytes", "long-line",  "line-shuffle", "garbage-line",  "binary-word",  "two"};

class Mutator {
 public:
  explicit Mutator(uint32_t seed) : rng_(seed) {}

  // Uniform in [0, n) (n > 0); std::mt19937's output is fixed by the standard, a distribution's is not.
  size_t below(size_t n) { return n ? size_t(rng_() % n) : 0; }
  template <class T>
  const T& pick(const std::vector<T>& v) {
    return v[below(v.size())];
  }

  std::string apply(const std::string& file, size_t text_size, int kind) {
    std::string f = file;
    switch (kind) {
      case kTruncate:
        f.resize(below(f.size()));
        break;
      case kFlipBytes:
        for (size_t k = 0, n = 1 + below(6); k < n && !f.empty(); ++k) f[below(f.size())] = char(rng_() & 0xff);
        break;
      case kRealToken:
        replace_token(
            f, text_size, [](std::string_view t) { return is_real(t); }, kHostileReals);
        break;
      case kIntegerToken:
        replace_token(
            f, text_size, [](std::string_view t) { return is_integerish(t); }, kHostileIntegers);
        break;
      case kHugePolygon:
        if (f.compare(0, 3, "ply") == 0) {
          replace_token(f, text_size, [](std::string_view t) { return is_integerish(t); },
                        {"4000000000", "4294967296", "18446744073709551615", "99999999999999999999999", "1e9"});
        } else {
          std::string face = "f";
          for (int k = 0; k < 100000; ++k) face += k % 2 ? " -1" : " 1";
          insert_line(f, text_size, face);
        }
        break;
      case kBom:
        f = "\xEF\xBB\xBF" + f;
        insert_line(f, text_size + 3, "\xEF\xBB\xBFv 0 0 0");
        break;
      case kLineEnds: {
        const char* const ends[] = {"\r\n", "\r", "\n\r"};
        const std::string end = ends[below(3)];
        std::string out;
        for (size_t i = 0; i < f.size(); ++i) out += i < text_size && f[i] == '\n' ? end : std::string(1, f[i]);
        f = out;
        break;
      }
      case kNulBytes:
        for (size_t k = 0, n = 1 + below(3); k < n; ++k) f.insert(f.begin() + ptrdiff_t(below(f.size() + 1)), '\0');
        break;
      case kLongLine: {
        const size_t size = size_t(4096) << (2 * below(5));  // 4 KiB ... 1 MiB
        std::string line;
        switch (below(4)) {
          case 0:
            line = "# " + std::string(size, 'x');
            break;
          case 1:
            line = "v 1 2 " + std::string(size, '7');
            break;
          case 2:
            for (line = "vt"; line.size() < size;) line += " 0.5";
            break;
          default:
            line = std::string(size, 'a');
        }
        insert_line(f, text_size, line);
        break;
      }
      case kLineShuffle: {
        const std::vector<std::pair<size_t, size_t>> lines = line_spans(f, text_size);
        if (lines.size() < 2) break;
        const auto [b1, e1] = pick(lines);
        const auto [b2, e2] = pick(lines);
        const std::string l1 = f.substr(b1, e1 - b1), l2 = f.substr(b2, e2 - b2);
        switch (below(3)) {
          case 0:
            f.insert(e1, l1);
            break;
          case 1:
            f.erase(b1, e1 - b1);
            break;
          default:
            if (b1 < b2) f = f.substr(0, b1) + l2 + f.substr(e1, b2 - e1) + l1 + f.substr(e2);
        }
        break;
      }
      case kGarbageLine: {
        std::string line;
        const bool binary = below(2) == 0;
        for (size_t k = 0, n = 1 + below(60); k < n; ++k)
          line += binary ? char(rng_() & 0xff) : char(0x20 + below(0x5f));
        insert_line(f, text_size, line);
        break;
      }
      case kBinaryWord:
        if (text_size < f.size()) {
          const uint32_t w = kHostileWords[below(std::size(kHostileWords))];
          const size_t at = text_size + below(f.size() - text_size);
          std::memcpy(f.data() + at, &w, std::min<size_t>(4, f.size() - at));
        } else {
          f = apply(f, text_size, kFlipBytes);
        }
        break;
      case kTwo: {
        const int first = int(below(kTwo)), second = int(below(kTwo));
        const std::string once = apply(f, text_size, first);
        f = apply(once, std::min(text_size, once.size()), second);
        break;
      }
    }
    return f;
  }

 private:
  static bool is_real(std::string_view t) {
    double v;
    const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
    return r.ptr == t.data() + t.size() && !t.empty();
  }
  static bool is_integerish(std::string_view t) {
    return !t.empty() && t.find_first_not_of("-0123456789/") == std::string_view::npos &&
           t.find_first_of("0123456789") != std::string_view::npos;
  }

  // The lines (with their '\n') that start within the first text_size bytes.
  static std::vector<std::pair<size_t, size_t>> line_spans(const std::string& f, size_t text_size) {
    std::vector<std::pair<size_t, size_t>> lines;
    for (size_t b = 0; b < std::min(text_size, f.size());) {
      const size_t nl = f.find('\n', b);
      const size_t e = nl == std::string::npos ? f.size() : nl + 1;
      lines.emplace_back(b, e);
      b = e;
    }
    return lines;
  }

  void insert_line(std::string& f, size_t text_size, const std::string& line) {
    const std::vector<std::pair<size_t, size_t>> lines = line_spans(f, text_size);
    // In a PLY with a binary body, only within the header (before end_header).
    const size_t at = lines.empty() ? 0 : pick(lines).first;
    f.insert(at, line + "\n");
  }

  template <class Accept>
  void replace_token(std::string& f, size_t text_size, Accept accept, const std::vector<std::string>& with) {
    std::vector<std::pair<size_t, size_t>> tokens;
    const size_t end = std::min(text_size, f.size());
    for (size_t b = 0; b < end;) {
      while (b < end && std::isspace(static_cast<unsigned char>(f[b]))) ++b;
      size_t e = b;
      while (e < end && !std::isspace(static_cast<unsigned char>(f[e]))) ++e;
      if (e > b && accept(std::string_view(f).substr(b, e - b))) tokens.emplace_back(b, e);
      b = e;
    }
    if (tokens.empty()) return;
    const auto [b, e] = pick(tokens);
    f.replace(b, e - b, pick(with));
  }

  std::mt19937 rng_;
};

// Where the text of a file ends: after end_header for a binary PLY, at once for a binary STL,
// else at its end.
inline size_t text_size(const Base& base) {
  if (!base.binary_body) return base.bytes.size();
  if (std::string_view(base.ext) == ".stl") return 0;
  return base.bytes.find("end_header\n") + std::strlen("end_header\n");
}

struct Generated {
  std::string recipe;  // how to make it again: base, mutation, seed
  std::string ext;
  std::string bytes;
};

// `per_kind` inputs of each mutation kind for each base.
inline std::vector<Generated> generate(int per_kind) {
  std::vector<Generated> out;
  for (const Base& base : bases()) {
    for (int kind = 0; kind < kMutationCount; ++kind) {
      for (int k = 0; k < per_kind; ++k) {
        const uint32_t seed = uint32_t(1000 * kind + k);
        Mutator m(seed);
        out.push_back({std::string(base.name) + " " + kMutationNames[kind] + " seed " + std::to_string(seed), base.ext,
                       m.apply(base.bytes, text_size(base), kind)});
      }
    }
  }
  return out;
}

class FuzzDir : public test::TempDirTest {};

}  // namespace gwnrt
