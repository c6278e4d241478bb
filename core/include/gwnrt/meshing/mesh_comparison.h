// Two outputs of the mesher for the same model and options (the CPU and the CUDA backend) compared
// item by item. Both backends write vertices and triangles in the same order, so the i-th of one
// answers to the i-th of the other; float rounding may still move a vertex slightly, and where a
// quad's two diagonals are near a tie (flat quads) it may split the quad the other way.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <span>

#include "gwnrt/base/hd.h"

namespace gwnrt {

struct TriangleComparison {
  size_t same = 0;       // equal, index for index
  size_t resplit = 0;    // quads (two consecutive triangles) with the same outline, same
                         // orientation, split along the other diagonal
  size_t different = 0;  // the rest, and those one list has beyond the other
  bool equal_up_to_splits() const { return different == 0; }
};

namespace detail {
// The directed outline of two triangles that share an edge (in opposite directions, as the two
// halves of a consistently oriented quad do): their four other edges, sorted; is_quad is false
// when they share none.
inline std::array<uint64_t, 4> quad_outline(const uvec3& x, const uvec3& y, bool& is_quad) {
  std::array<uint64_t, 6> edges;
  for (int k = 0; k < 3; ++k) {
    edges[k] = uint64_t(x[k]) << 32 | x[(k + 1) % 3];
    edges[3 + k] = uint64_t(y[k]) << 32 | y[(k + 1) % 3];
  }
  const auto reversed = [](uint64_t e) { return e << 32 | e >> 32; };
  std::array<uint64_t, 4> outline{};
  is_quad = false;
  for (int i = 0; i < 3; ++i)
    for (int j = 3; j < 6; ++j)
      if (edges[j] == reversed(edges[i])) {
        int n = 0;
        for (int k = 0; k < 6; ++k)
          if (k != i && k != j) outline[n++] = edges[k];
        is_quad = true;
      }
  std::sort(outline.begin(), outline.end());
  return outline;
}
}  // namespace detail

// Triangles of `a` against those of `b`: equal, a quad split the other way, or different.
inline TriangleComparison compare_triangles(std::span<const uvec3> a, std::span<const uvec3> b) {
  TriangleComparison c;
  const size_t n = std::min(a.size(), b.size());
  c.different = std::max(a.size(), b.size()) - n;
  for (size_t t = 0; t < n; ++t) {
    if (a[t] == b[t]) {
      ++c.same;
      continue;
    }
    if (t + 1 < n && a[t + 1] != b[t + 1]) {
      bool quad_a = false, quad_b = false;
      const auto outline_a = detail::quad_outline(a[t], a[t + 1], quad_a);
      const auto outline_b = detail::quad_outline(b[t], b[t + 1], quad_b);
      if (quad_a && quad_b && outline_a == outline_b) {
        ++c.resplit;
        ++t;
        continue;
      }
    }
    ++c.different;
  }
  return c;
}

}  // namespace gwnrt
