// Distances by brute force in double: every triangle (or boundary segment) measured, no tree.
// The primitives are gwnrt's closest_point_on_triangle and closest_point_on_segment, which
// tests/field/test_distance.cpp checks against dense sampling; zero-area triangles are measured as
// their three edges, where closest_point_on_triangle is shown to be unreliable.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>

#include "gwnrt/field/distance.h"
#include "gwnrt/geometry/boundary.h"
#include "gwnrt/geometry/mesh.h"

namespace gwnrt::reference {

// Distance in double from x to the triangle (a, b, c) of float corners.
inline double triangle_distance(const vec3& a, const vec3& b, const vec3& c, const dvec3& x) {
  const dvec3 p[3] = {dvec3(a), dvec3(b), dvec3(c)};
  if (!is_degenerate_triangle(a, b, c)) return glm::length(closest_point_on_triangle(p[0], p[1], p[2], x).point - x);
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k)
    best = std::min(best, glm::length(closest_point_on_segment(p[k], p[(k + 1) % 3], x).point - x));
  return best;
}

// Distance from x to triangle `id` of the mesh.
inline double triangle_distance(const Mesh& m, uint32_t id, const dvec3& x) {
  const uvec3 t = m.triangles[id];
  return triangle_distance(m.positions[t[0]], m.positions[t[1]], m.positions[t[2]], x);
}

// Distance from x to the nearest triangle of the mesh (+inf when it has none).
inline double mesh_distance(const Mesh& m, const dvec3& x) {
  double best = std::numeric_limits<double>::infinity();
  for (uint32_t id = 0; id < m.triangles.size(); ++id) best = std::min(best, triangle_distance(m, id, x));
  return best;
}

// The same for a triangle soup, 3 corners per triangle (a TriangleTree's vertices).
inline double soup_distance(std::span<const vec3> corners, const dvec3& x) {
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i + 2 < corners.size(); i += 3)
    best = std::min(best, triangle_distance(corners[i], corners[i + 1], corners[i + 2], x));
  return best;
}

// Distance from x to the boundary curve ∂M (+inf when M is closed).
inline double boundary_distance(const BoundaryCurve& curve, const dvec3& x) {
  double best = std::numeric_limits<double>::infinity();
  for (size_t s = 0; s < curve.segment_count(); ++s) {
    const ClosestPoint<double> c =
        closest_point_on_segment(dvec3(curve.endpoints[2 * s]), dvec3(curve.endpoints[2 * s + 1]), x);
    best = std::min(best, glm::dot(c.point - x, c.point - x));
  }
  return std::sqrt(best);
}

}  // namespace gwnrt::reference
