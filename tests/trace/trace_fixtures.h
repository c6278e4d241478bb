// What the tests of trace_surface share: descriptions of rays and hits for their messages, the
// meshes with holes, the tolerances of the comparison with the dense-sampling reference
// (first_crossing.h), and rays through the holes of those meshes.
#pragma once

#include <cstdint>
#include <cstdio>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "gwnrt/trace/surface_trace.h"
#include "reference/first_crossing.h"
#include "test_util.h"

namespace gwnrt {

using reference::ReferenceCrossing;
using reference::ReferenceMesh;
using reference::ReferenceMode;
using test::build_model;
using test::load_test_mesh;

using test::kInf;

inline double box_diagonal(const Aabb& b) { return glm::length(dvec3(b.hi) - dvec3(b.lo)); }

inline Aabb grown(const Aabb& b, float by) { return Aabb{b.lo - vec3(by), b.hi + vec3(by)}; }

inline std::string describe(const Ray& r) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "ray origin (%.9g, %.9g, %.9g) direction (%.9g, %.9g, %.9g)", r.origin.x, r.origin.y,
                r.origin.z, r.direction.x, r.direction.y, r.direction.z);
  return buf;
}

inline std::string describe(const RayHit& h) {
  std::ostringstream s;
  s << "tracer: hit " << h.hit << " kind " << int(h.kind) << " t " << h.t << " capped " << h.capped << " invalid "
    << h.invalid << " steps " << h.steps << " crossings " << h.crossings << " triangle " << int64_t(h.triangle);
  return s.str();
}

inline std::string describe(const ReferenceCrossing& c) {
  std::ostringstream s;
  s << "reference: hit " << c.hit << " t " << c.t << " sheet " << c.sheet << " rate " << c.rate;
  return s.str();
}

using test::Random;

inline double distance_to_triangle(const Mesh& m, uint32_t t, const dvec3& x) {
  const dvec3 a(m.positions[m.triangles[t][0]]), b(m.positions[m.triangles[t][1]]), c(m.positions[m.triangles[t][2]]);
  return glm::length(closest_point_on_triangle(a, b, c, x).point - x);
}

inline Mesh open_mesh(const std::string& name) {
  if (name == "bunny_holes") return load_test_mesh("bunny_holes.obj");
  if (name == "open_cube") return test::make_cube(true);
  // A rim of 200 segments: the cone spans it (boundary_cone) rather than fanning it.
  if (name == "open_hemisphere") return test::make_hemisphere(12, 200);
  return test::make_hexagon_fan();
}

// What the tracer may legitimately get wrong, in units of w: `delta_w` is the error of its
// evaluation of φ; it stops where |φ - level| <= epsilon·diag·|∇w|.
struct Tolerance {
  double delta_w;
  double normal_angle;  // radians, at smooth hits
};

// Exact evaluation: φ is the double sum over the cone rounded to float (|w_C| is a few units at
// most here, so ~1e-7 absolute); 1e-6 leaves a factor of ten.
inline constexpr Tolerance kExactTolerance{1e-6, 1e-3};
// Multipole evaluation at beta = 2, order 2, on the cone: test MultipoleErrorOnTheLevelSetIsBounded
// measures the error of φ at reference crossings of rays like the ones used here (below 1e-5 on
// these meshes: the cones are small, so most of φ is summed exactly) and asserts it stays below
// δ = 1e-4; the level set then moves by up to δ/|∇w| along its normal, δ/|dw/ds| along the ray,
// which is what the comparison allows. For the same reason the gradient, hence the normal,
// should carry little more than float round-off; the same test asserts its relative error at
// the level set stays below 1e-3, which bounds the angle of the normal.
inline constexpr Tolerance kMultipoleTolerance{1e-4, 1e-3};

// The loops of ∂M (segments joined at bit-identical endpoints) and their centroids.
struct BoundaryLoops {
  std::vector<uint32_t> of_endpoint;  // loop of each endpoint of BoundaryCurve::endpoints
  std::vector<vec3> centroid;
};

inline BoundaryLoops boundary_loops(const BoundaryCurve& curve) {
  const std::vector<vec3>& e = curve.endpoints;
  std::vector<uint32_t> parent(e.size());
  for (uint32_t i = 0; i < e.size(); ++i) parent[i] = i;
  auto find = [&](uint32_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  auto key = [](const vec3& p) { return std::tuple(p.x, p.y, p.z); };
  std::map<std::tuple<float, float, float>, uint32_t> first;
  for (uint32_t i = 0; i < e.size(); ++i) {
    if (i % 2 == 1) parent[find(i)] = find(i - 1);  // a segment joins its two ends
    const auto [it, fresh] = first.emplace(key(e[i]), i);
    if (!fresh) parent[find(i)] = find(it->second);
  }
  BoundaryLoops loops;
  loops.of_endpoint.resize(e.size());
  std::map<uint32_t, uint32_t> index;
  std::vector<dvec3> sum;
  std::vector<double> count;
  for (uint32_t i = 0; i < e.size(); ++i) {
    const auto [it, fresh] = index.emplace(find(i), uint32_t(sum.size()));
    if (fresh) {
      sum.emplace_back(0.0);
      count.push_back(0);
    }
    loops.of_endpoint[i] = it->second;
    sum[it->second] += dvec3(e[i]);
    count[it->second] += 1;
  }
  for (size_t l = 0; l < sum.size(); ++l) loops.centroid.push_back(vec3(sum[l] / count[l]));
  return loops;
}

// Rays for a mesh with holes: a third from outside aimed into the box, a third from inside the
// box in any direction, a third aimed across the holes (where the smooth part of S is).
inline std::vector<Ray> open_rays(const GwnModel& model, size_t count, uint32_t seed) {
  Random rng(seed);
  const Aabb box = model.bounds();
  const float diag = float(box_diagonal(box));
  const std::vector<vec3>& rim = model.boundary().endpoints;
  const BoundaryLoops loops = boundary_loops(model.boundary());
  std::vector<Ray> rays;
  while (rays.size() < count) {
    Ray r;
    switch (rays.size() % 3) {
      case 0:
        r.origin = rng.in_box(grown(box, 0.5f * diag));
        r.direction = rng.in_box(box) - r.origin;
        break;
      case 1:
        r.origin = rng.in_box(box);
        r.direction = rng.unit();
        break;
      default: {
        // Between a rim point and the centroid of its loop: across the hole, where S is smooth.
        r.origin = rng.in_box(grown(box, 0.5f * diag));
        vec3 target = rng.in_box(box);
        if (!rim.empty()) {
          const size_t k = size_t(rng.index(int(rim.size())));
          target = glm::mix(rim[k], loops.centroid[loops.of_endpoint[k]], rng.uniform(0, 1)) +
                   0.02f * diag * rng.unit() * rng.uniform(0, 1);
        }
        r.direction = target - r.origin;
      }
    }
    if (!(glm::length(r.direction) > 1e-3f * diag)) continue;
    r.direction = glm::normalize(r.direction) * rng.scale();
    rays.push_back(r);
  }
  return rays;
}

// The reference looks well beyond the tracer's own search box (bounds + surface_margin): a piece
// of S out there would show as a miss of the tracer.
inline Aabb reference_box(const GwnModel& model) {
  return grown(model.bounds(), 1.5f * model.surface_margin() + 0.1f * float(box_diagonal(model.bounds())));
}

}  // namespace gwnrt
