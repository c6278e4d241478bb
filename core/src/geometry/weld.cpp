// Welding vertices by position, exactly or within a distance (gwnrt/geometry/weld.h).
#include "gwnrt/geometry/weld.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <numeric>

#include <tbb/parallel_sort.h>

#include "gwnrt/geometry/boundary.h"

namespace gwnrt {
namespace {

std::array<uint32_t, 3> position_key(const vec3& p) {
  std::array<uint32_t, 3> k;
  for (int a = 0; a < 3; ++a) {
    const float v = p[a] + 0.0f;  // -0 + 0 = +0
    std::memcpy(&k[a], &v, sizeof v);
  }
  return k;
}

}  // namespace

std::vector<uint32_t> vertices_by_position(const std::vector<vec3>& positions) {
  const size_t n = positions.size();
  std::vector<uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  tbb::parallel_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    const auto ka = position_key(positions[a]), kb = position_key(positions[b]);
    return ka != kb ? ka < kb : a < b;
  });
  std::vector<uint32_t> first(n);
  for (size_t i = 0; i < n; ++i) {
    const bool same = i > 0 && position_key(positions[order[i]]) == position_key(positions[order[i - 1]]);
    first[order[i]] = same ? first[order[i - 1]] : order[i];
  }
  return first;
}

WeldSummary summarize_weld(const Mesh& mesh) {
  WeldSummary s;
  std::vector<char> used(mesh.positions.size(), 0);
  for (const uvec3& t : mesh.triangles) used[t.x] = used[t.y] = used[t.z] = 1;
  const std::vector<uint32_t> first = vertices_by_position(mesh.positions);
  std::vector<char> counted(mesh.positions.size(), 0);  // per group (its first vertex, used or not)
  for (size_t v = 0; v < used.size(); ++v) {
    if (!used[v]) continue;
    ++s.vertices_used;
    if (!counted[first[v]]) {
      counted[first[v]] = 1;
      ++s.positions_used;
    }
  }
  const BoundaryCurve curve = extract_boundary(mesh, first);
  s.boundary_by_position = curve.segment_count();
  if (s.boundary_by_position > 0) (void)boundary_loops(curve, s.boundary_loops);
  if (s.positions_used == s.vertices_used) {
    s.boundary_by_index = s.boundary_by_position;  // no two vertices share a position: the same topology
  } else {
    std::vector<uint32_t> identity(mesh.positions.size());
    std::iota(identity.begin(), identity.end(), 0u);
    s.boundary_by_index = extract_boundary(mesh, identity).segment_count();
  }
  return s;
}

std::size_t weld_within(Mesh& mesh, double distance) {
  if (!(distance > 0)) return 0;
  const size_t n = mesh.positions.size();
  std::vector<char> used(n, 0);
  for (const uvec3& t : mesh.triangles) used[t.x] = used[t.y] = used[t.z] = 1;
  dvec3 lo(INFINITY);
  for (size_t v = 0; v < n; ++v)
    if (used[v]) lo = glm::min(lo, dvec3(mesh.positions[v]));
  // Cells of the weld distance: a vertex's partners lie in its cell or the 26 around it.
  using Cell = std::array<int64_t, 3>;
  auto cell_of = [&](size_t v) {
    const dvec3 c = glm::floor((dvec3(mesh.positions[v]) - lo) / distance);
    return Cell{int64_t(c.x), int64_t(c.y), int64_t(c.z)};
  };
  std::vector<std::pair<Cell, uint32_t>> cells;
  for (size_t v = 0; v < n; ++v)
    if (used[v]) cells.emplace_back(cell_of(v), uint32_t(v));
  tbb::parallel_sort(cells.begin(), cells.end());

  std::vector<uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](uint32_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  const double d2 = distance * distance;
  for (const auto& [cell, v] : cells) {
    const dvec3 p(mesh.positions[v]);
    for (int64_t dx = -1; dx <= 1; ++dx)
      for (int64_t dy = -1; dy <= 1; ++dy)
        for (int64_t dz = -1; dz <= 1; ++dz) {
          const Cell c{cell[0] + dx, cell[1] + dy, cell[2] + dz};
          auto it = std::lower_bound(cells.begin(), cells.end(), std::make_pair(c, uint32_t(0)));
          for (; it != cells.end() && it->first == c; ++it) {
            const uint32_t u = it->second;
            if (u >= v) continue;  // each pair once
            const dvec3 q(mesh.positions[u]);
            if (glm::dot(p - q, p - q) <= d2) {
              const uint32_t a = find(u), b = find(v);
              if (a != b) parent[std::max(a, b)] = std::min(a, b);  // the root stays the lowest index
            }
          }
        }
  }
  size_t moved = 0;
  for (size_t v = 0; v < n; ++v) {
    if (!used[v]) continue;
    const uint32_t r = find(uint32_t(v));
    if (r != v && mesh.positions[r] != mesh.positions[v]) {
      mesh.positions[v] = mesh.positions[r];
      ++moved;
    }
  }
  return moved;
}

}  // namespace gwnrt
