// w and ∇w of a triangle mesh by brute force in double: every triangle summed at every point,
// no tree, no expansion, none of gwnrt's own solid-angle code. The reference the tests check
// gwnrt's w, its tracer and its signed distance against.
#pragma once

#include <cmath>
#include <vector>

#include "gwnrt/base/hd.h"
#include "gwnrt/geometry/bvh.h"
#include "gwnrt/geometry/mesh.h"

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

// w(x) = Σ Ω_i / 4π over every triangle, in double (brute_force_winding.cpp).
double reference_w(const ReferenceMesh& r, const dvec3& x);

// ∇w(x) off the mesh, in double: the Biot–Savart field of every triangle's boundary loop.
dvec3 reference_gradient(const ReferenceMesh& r, const dvec3& x);

}  // namespace gwnrt::reference
