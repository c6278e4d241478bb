// What the tests of the sheets and of the signed distance share: the shapes (a sphere, the open
// hemisphere) and their references, among them the hemisphere's S worked out in closed form.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "reference/brute_force_winding.h"
#include "reference/exact_distance.h"
#include "test_util.h"

namespace gwnrt {

using test::build_model;
using test::make_sphere;
// The distance to the sheet triangles by brute force: the callers pass meshes whose triangles are
// all sheets.
using reference::mesh_distance;

inline constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// ---------------------------------------------------------------------------------------------
// Shapes and references.
// ---------------------------------------------------------------------------------------------

using test::make_hemisphere;

inline dvec3 unit_normal(const Mesh& m, size_t t) {
  const dvec3 a(m.positions[m.triangles[t][0]]), b(m.positions[m.triangles[t][1]]), c(m.positions[m.triangles[t][2]]);
  return glm::normalize(glm::cross(b - a, c - a));
}

// The largest gap between a polyhedron inscribed in the unit sphere and the sphere: 1 minus the
// smallest distance from the origin to a facet's plane. The polyhedron lies between radius
// 1 - sag and 1, so its distance from x differs from ||x| - 1| by at most `sag`.
inline double chord_sag(const Mesh& m) {
  double sag = 0;
  for (size_t t = 0; t < m.triangles.size(); ++t)
    sag = std::max(sag, 1.0 - std::fabs(glm::dot(unit_normal(m, t), dvec3(m.positions[m.triangles[t][0]]))));
  return sag;
}

// The hemisphere H (make_hemisphere) with its S worked out. Let D be the flat polygon bounded by
// the rim (z = 0), oriented downward: H + D is closed, so w_H + w_D = 1 inside the half-ball
// and 0 outside. Reflecting in z = 0 maps H onto the lower cap with reversed orientation, so
// w_H(x) + w_H(x̄) = 1 inside the sphere polyhedron (x̄ the mirror image): on D, w_H = 1/2
// exactly (for the tessellation too). Above D inside, w_H = 1 - w_D > 1/2 (|w_D| < 1/2 for a
// flat polygon); everywhere else |w_H| < 1/2 or w_H = |w_D| < 1/2. So {w > 1/2} is the closed
// half-ball polyhedron and S = H ∪ D: the shell triangles (sheets) and the smooth piece D.
struct HemisphereReference {
  Mesh mesh;
  reference::ReferenceMesh exact;
  std::vector<glm::dvec2> rim;  // counter-clockwise seen from +z
  explicit HemisphereReference(int rings, int segments) : mesh(make_hemisphere(rings, segments)) {
    exact = reference::reference_mesh(mesh);
    for (int j = 0; j < segments; ++j) {
      const vec3 p = mesh.positions[1 + (rings - 1) * segments + j];
      rim.push_back({p.x, p.y});
    }
  }
  bool over_disk(const dvec3& x) const {
    for (size_t j = 0; j < rim.size(); ++j) {
      const glm::dvec2 a = rim[j], b = rim[(j + 1) % rim.size()];
      if ((b.x - a.x) * (x.y - a.y) - (b.y - a.y) * (x.x - a.x) < 0) return false;
    }
    return true;
  }
  double shell_distance(const dvec3& x) const { return mesh_distance(mesh, x); }
  // The distance to D: |z| above or below it; elsewhere its nearest point is on the rim, which
  // belongs to the shell, so the shell's distance covers it.
  double disk_distance(const dvec3& x) const {
    return over_disk(x) ? std::fabs(x.z) : std::numeric_limits<double>::infinity();
  }
  double distance(const dvec3& x) const { return std::min(shell_distance(x), disk_distance(x)); }
  bool inside(const dvec3& x) const { return reference::reference_w(exact, x) > 0.5; }
  double signed_distance(const dvec3& x) const { return inside(x) ? -distance(x) : distance(x); }
};

inline std::string str(const vec3& x) {
  char buf[96];  // (GCC 12 warns falsely, -Wrestrict, on the chain of string concatenations)
  std::snprintf(buf, sizeof buf, "(%g, %g, %g)", double(x.x), double(x.y), double(x.z));
  return buf;
}

}  // namespace gwnrt
