// Exact w by crossings of M alone: the spanning surface of ∂M taken as each segment's ribbon,
// swept from the segment to infinity opposite the axis ray that counts M's jumps. The ray runs
// parallel to every ribbon and crosses none, so no cone and no cone crossings are needed, and
// no inner triangles pass by points near the rim (docs/performance.md, the scan's near cone work).
// This is the scalar O(|∂M|) form, in double, that a clustered form must reproduce.
#pragma once

#include "gwnrt/base/hd.h"
#include "gwnrt/field/crossing_winding.h"
#include "gwnrt/field/solid_angle.h"
#include "gwnrt/geometry/model_view.h"
#include "gwnrt/geometry/ray.h"

namespace gwnrt {

// The ribbon of a segment a -> b (relative to x), swept to infinity along the unit direction c,
// subtends from x the spherical triangle (a, b, c): van Oosterom and Strackee with |c| = 1. Its
// boundary holds a -> b as a cone triangle (z, a, b) holds it, so the ribbons of ∂M's segments
// span ∂M as the cone does.
// w at x: the ribbons' solid angles over 4π (swept along −d) less M's jumps ahead of x along the
// axis ray d that leaves M's box soonest. Exact up to round-off where x is off M. Where x lies on
// a ribbon (the ray runs into ∂M: a query point in the plane of a planar hole, the ray in that
// plane), the term is ±2π by round-off and M's faces lie along the ray: x is moved as the cone's
// crossing method moves it (ConeNudge), w being continuous there.
GWNRT_HD inline double winding_number_by_ribbons(const ModelView& m, const vec3& x_in) {
  vec3 x = x_in;
  ConeNudge nudge(m.bounds, x_in);
  for (;;) {
    const RayFrame frame = shortest_exit_axis_ray(m.bounds, x);
    dvec3 behind(0.0);
    behind[frame.kz] = -double(frame.sz);  // sz = 1 / d[kz] = ±1
    const dvec3 xd(x);
    double omega = 0;
    bool on_ribbon = false;
    for (uint32_t s = 0; s < m.boundary.segment_count; ++s) {
      const dvec3 a = dvec3(m.boundary.endpoints[2 * s]) - xd, b = dvec3(m.boundary.endpoints[2 * s + 1]) - xd;
      const SolidAngleTangent<double> t = solid_angle_tangent(a, b, behind, glm::length(a), glm::length(b), 1.0,
                                                              glm::cross(b, behind), glm::dot(b, behind));
      on_ribbon = on_ribbon || (t.numerator == 0.0 && t.denominator <= 0.0);
      omega += 2.0 * atan2(t.numerator, t.denominator);
    }
    if (on_ribbon && nudge.left()) {
      x = nudge.next();
      continue;
    }
    int mesh_jumps = 0;
    visit_axis_crossings(m.triangles.bvh, m.triangles.vertices, frame, 0.0f,
                         [&](uint32_t, float, int jump) { mesh_jumps += jump; });
    return omega * (0.25 / kPi) - double(mesh_jumps);
  }
}

}  // namespace gwnrt
