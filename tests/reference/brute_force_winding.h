// w and ∇w of a triangle mesh by brute force in double: every triangle summed at every point,
// no tree, no expansion, none of gwnrt's own solid-angle code. The reference the tests check
// gwnrt's w, its tracer and its signed distance against.
#pragma once

#include <cmath>
#include <vector>

#include "gwnrt/geometry/bvh.h"
#include "gwnrt/geometry/mesh.h"
#include "gwnrt/hd.h"

namespace gwnrt::reference {

struct ReferenceMesh {
  std::vector<dvec3> corners;  // 3 per triangle, zero-area triangles left out
  Aabb box;                    // of all input vertices
  double diagonal = 0;
};

inline ReferenceMesh reference_mesh(const Mesh& m) {
  ReferenceMesh r;
  for (const uvec3& t : m.triangles) {
    const dvec3 a(m.positions[t[0]]), b(m.positions[t[1]]), c(m.positions[t[2]]);
    const dvec3 n = glm::cross(b - a, c - a);
    if (n.x == 0 && n.y == 0 && n.z == 0) continue;
    r.corners.insert(r.corners.end(), {a, b, c});
  }
  for (const vec3& p : m.positions) r.box.extend(p);
  r.diagonal = glm::length(dvec3(r.box.hi) - dvec3(r.box.lo));
  return r;
}

// w(x) = Σ Ω_i / 4π; Ω of one triangle is 2·atan2(a·(b×c), |a||b||c| + (a·b)|c| + (b·c)|a| + (c·a)|b|)
// with a, b, c its corners relative to x: positive behind the normal (b-a)×(c-a), so w = 1 inside
// a closed outward-oriented mesh.
inline double reference_w(const ReferenceMesh& r, const dvec3& x) {
  double omega = 0;
  for (size_t i = 0; i < r.corners.size(); i += 3) {
    const dvec3 a = r.corners[i] - x, b = r.corners[i + 1] - x, c = r.corners[i + 2] - x;
    const double la = glm::length(a), lb = glm::length(b), lc = glm::length(c);
    const double num = glm::dot(a, glm::cross(b, c));
    const double den = la * lb * lc + glm::dot(a, b) * lc + glm::dot(b, c) * la + glm::dot(c, a) * lb;
    omega += 2.0 * std::atan2(num, den);
  }
  return omega / (4.0 * kPi);
}

// ∇w(x) off the mesh: each directed edge a→b of each triangle (relative to x) contributes
// (a×b)(|a|+|b|) / (|a||b|(|a||b| + a·b)) to ∇Ω (the Biot–Savart field of the boundary loop).
inline dvec3 reference_gradient(const ReferenceMesh& r, const dvec3& x) {
  dvec3 g(0.0);
  auto edge = [&](const dvec3& a, const dvec3& b) {
    const double la = glm::length(a), lb = glm::length(b);
    const double den = la * lb * (la * lb + glm::dot(a, b));
    if (!(den > 0)) return;  // x on the edge's line, outside the segment: no contribution in the limit
    g += glm::cross(a, b) * ((la + lb) / den);
  };
  for (size_t i = 0; i < r.corners.size(); i += 3) {
    const dvec3 a = r.corners[i] - x, b = r.corners[i + 1] - x, c = r.corners[i + 2] - x;
    edge(a, b);
    edge(b, c);
    edge(c, a);
  }
  return g / (4.0 * kPi);
}

}  // namespace gwnrt::reference
