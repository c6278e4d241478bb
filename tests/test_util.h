// Shared helpers for the tests: bundled meshes, analytic shapes and point sets.
#pragma once

#include <cmath>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "gwnrt/batch.h"
#include "gwnrt/io/mesh_io.h"
#include "gwnrt/geometry/mesh.h"
#include "gwnrt/geometry/model.h"
#include "point_mix.h"

namespace gwnrt::test {

inline std::string data_path(const std::string& name) { return std::string(GWNRT_TEST_DATA_DIR) + "/" + name; }

inline Mesh load_test_mesh(const std::string& name) {
  Mesh mesh;
  const Status s = load_mesh(data_path(name), mesh);
  EXPECT_TRUE(s.ok()) << s.message();
  return mesh;
}

inline GwnModel build_model(Mesh mesh) {
  GwnModel model;
  const Status s = GwnModel::build(std::move(mesh), model);
  EXPECT_TRUE(s.ok()) << s.message();
  return model;
}

// Float random numbers for rays and points (a fixed seed: the tests are reproducible).
class Random {
 public:
  explicit Random(uint32_t seed) : g_(seed) {}
  float uniform(float a, float b) { return std::uniform_real_distribution<float>(a, b)(g_); }
  int index(int n) { return std::uniform_int_distribution<int>(0, n - 1)(g_); }
  vec3 in_box(const Aabb& b) { return {uniform(b.lo.x, b.hi.x), uniform(b.lo.y, b.hi.y), uniform(b.lo.z, b.hi.z)}; }
  vec3 unit() {
    for (;;) {
      const vec3 v(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
      const float l = glm::length(v);
      if (l > 0.1f && l <= 1.0f) return v / l;
    }
  }
  // A direction length between 1e-2 and 1e2: t is in units of it, whatever it is.
  float scale() { return std::pow(10.0f, uniform(-2.0f, 2.0f)); }

 private:
  std::mt19937 g_;
};

// Hexagon fan, slightly curved: centre raised by 0.15 above the unit rim, normals up.
inline Mesh make_hexagon_fan() {
  Mesh m;
  m.positions.push_back({0.0f, 0.0f, 0.15f});
  for (int k = 0; k < 6; ++k) {
    const double a = 2.0 * kPi * k / 6.0;
    m.positions.push_back({float(std::cos(a)), float(std::sin(a)), 0.0f});
  }
  for (uint32_t k = 0; k < 6; ++k) m.triangles.push_back({0u, 1 + k, 1 + (k + 1) % 6});
  return m;
}

// Unit sphere by subdividing an icosahedron `levels` times, outward-oriented, vertices on the sphere.
inline Mesh make_sphere(int levels, float radius = 1.0f) {
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  Mesh m;
  m.positions = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                 {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  m.triangles = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (auto& p : m.positions) p = glm::normalize(p);
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      m.positions.push_back(glm::normalize(m.positions[a] + m.positions[b]));
      return mid[key] = uint32_t(m.positions.size() - 1);
    };
    std::vector<uvec3> next;
    for (const uvec3& tri : m.triangles) {
      const uint32_t a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
      next.insert(next.end(), {{tri[0], a, c}, {tri[1], b, a}, {tri[2], c, b}, {a, b, c}});
    }
    m.triangles = std::move(next);
  }
  for (auto& p : m.positions) p *= radius;
  return m;
}

// Axis-aligned cube [-1, 1]³, outward-oriented; `open_top` drops the two z = +1 triangles.
inline Mesh make_cube(bool open_top = false) {
  Mesh m;
  m.positions = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1}, {-1, -1, 1}, {1, -1, 1}, {1, 1, 1}, {-1, 1, 1}};
  m.triangles = {{0, 2, 1}, {0, 3, 2}, {0, 1, 5}, {0, 5, 4}, {1, 2, 6}, {1, 6, 5},
                 {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  if (!open_top) m.triangles.insert(m.triangles.end(), {{4, 5, 6}, {4, 6, 7}});
  return m;
}

inline Aabb mesh_bounds(const Mesh& m) {
  Aabb box;
  for (const vec3& p : m.positions) box.extend(p);
  return box;
}

// The benchmark's point mix (examples/common/point_mix.h).
inline std::vector<vec3> sample_points(const Aabb& box, size_t count, uint32_t seed) { return point_mix(box, count, seed); }

}  // namespace gwnrt::test

// ---------------------------------------------------------------------------------------------
// Ray-tracing references (tests/test_trace.cpp, tests/test_ray_crossing.cpp).
//
// An independent reference for the first point of a level set along a ray: w summed over every
// triangle in double (van Oosterom–Strackee), the ray sampled densely, the first sign change of
// (w - level) refined by bisection. w jumps by ±1 across a triangle, so the bisection converges
// either to a smooth crossing of the level or to a triangle whose jump straddles it; both lie on
// S = ∂{w > level}. In solid-angle mode w is lifted continuously across the ±1 jumps first, so
// only smooth crossings of φ = w mod 1 count.
// ---------------------------------------------------------------------------------------------

#include <algorithm>
#include <limits>

namespace gwnrt::test {

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

enum class ReferenceMode { kWindingNumber, kSolidAngle };

// w sampled along a ray: s is the distance along the unit direction.
struct ReferenceProfile {
  dvec3 origin, direction;  // direction unit
  double length = 1;        // |ray.direction|: t = s / length
  std::vector<double> s, w;
  dvec3 point(double si) const { return origin + si * direction; }
};

// The ray from s0 to s1 (distances along the unit direction), sampled at `samples` + 1 evenly
// spaced points.
inline ReferenceProfile reference_profile_between(const ReferenceMesh& r, const Ray& ray, double s0, double s1,
                                                  int samples) {
  ReferenceProfile p;
  p.origin = dvec3(ray.origin);
  p.length = glm::length(dvec3(ray.direction));
  p.direction = dvec3(ray.direction) / p.length;
  if (!(s0 < s1)) return p;
  p.s.resize(samples + 1);
  p.w.resize(samples + 1);
  for (int i = 0; i <= samples; ++i) {
    p.s[i] = s0 + (s1 - s0) * double(i) / samples;
    p.w[i] = reference_w(r, p.point(p.s[i]));
  }
  return p;
}

// [s0, s1] of the ray (from tnear on) inside `box`; s0 > s1 when it misses.
inline void clip_ray_to_box(const Ray& ray, const Aabb& box, double& s0, double& s1) {
  const dvec3 o(ray.origin);
  const double length = glm::length(dvec3(ray.direction));
  const dvec3 d = dvec3(ray.direction) / length;
  s0 = std::max(0.0, double(ray.tnear) * length);
  s1 = double(ray.tfar) * length;
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0) {
      if (o[k] < box.lo[k] || o[k] > box.hi[k]) s1 = -1;
      continue;
    }
    double a = (box.lo[k] - o[k]) / d[k], b = (box.hi[k] - o[k]) / d[k];
    if (a > b) std::swap(a, b);
    s0 = std::max(s0, a);
    s1 = std::min(s1, b);
  }
}

// The part of the ray inside `box`, sampled at `samples` + 1 evenly spaced points (none when
// the ray misses the box).
inline ReferenceProfile reference_profile(const ReferenceMesh& r, const Ray& ray, const Aabb& box, int samples) {
  double s0, s1;
  clip_ray_to_box(ray, box, s0, s1);
  return reference_profile_between(r, ray, s0, s1, samples);
}

struct ReferenceCrossing {
  bool hit = false;
  double s = std::numeric_limits<double>::infinity();  // along the unit direction
  double t = std::numeric_limits<double>::infinity();  // in units of the ray's direction
  bool sheet = false;     // a triangle whose ±1 jump straddles the level (winding-number mode)
  dvec3 gradient{0.0};    // ∇w at the crossing (smooth crossings)
  double rate = 0;        // |dw/ds| there: how fast the ray crosses the level (infinite for sheets)
};

namespace detail {
// The change of w from a to b with whole jumps removed (solid-angle mode): right while the
// smooth change over the interval stays below 1/2.
inline double wrapped_change(double a, double b) {
  const double d = b - a;
  return d - std::floor(d + 0.5);
}
}  // namespace detail

// First crossing of `level` along a sampled profile, refined by bisection to double precision.
// Winding-number mode: the first sign change of w - level (a smooth crossing or a triangle whose
// jump straddles the level). Solid-angle mode: w is lifted continuously across the ±1 jumps and
// the first copy level + k that the lift meets counts.
inline ReferenceCrossing reference_crossing(const ReferenceMesh& r, const ReferenceProfile& p, double level,
                                            ReferenceMode mode = ReferenceMode::kWindingNumber) {
  ReferenceCrossing out;
  const bool lifted = mode == ReferenceMode::kSolidAngle;
  double lift = p.w.empty() ? 0.0 : p.w[0];
  for (size_t i = 0; i + 1 < p.s.size(); ++i) {
    const double next = lifted ? lift + detail::wrapped_change(p.w[i], p.w[i + 1]) : p.w[i + 1];
    double target = level;
    if (lifted) target += next >= lift ? std::floor(lift - level) + 1 : std::ceil(lift - level) - 1;
    double ga = lift - target, gb = next - target;
    lift = next;
    if (ga != 0 && (ga > 0) == (gb > 0)) continue;
    double a = p.s[i], b = p.s[i + 1], wa = p.w[i], lift_a = ga + target;
    for (int it = 0; it < 200; ++it) {
      const double m = 0.5 * (a + b);
      if (m <= a || m >= b) break;
      const double wm = reference_w(r, p.point(m));
      const double lift_m = lifted ? lift_a + detail::wrapped_change(wa, wm) : wm;
      const double gm = lift_m - target;
      if (gm != 0 && (gm > 0) == (ga > 0)) {
        a = m;
        ga = gm;
        wa = wm;
        lift_a = lift_m;
      } else {
        b = m;
        gb = gm;
      }
    }
    out.hit = true;
    out.s = 0.5 * (a + b);
    out.t = out.s / p.length;
    out.sheet = !lifted && std::fabs(gb - ga) > 0.5;  // a whole jump of w, not a smooth change
    if (out.sheet) {
      out.rate = std::numeric_limits<double>::infinity();
    } else {
      out.gradient = reference_gradient(r, p.point(out.s));
      out.rate = std::fabs(glm::dot(out.gradient, p.direction));
    }
    return out;
  }
  return out;
}

// The whole reference in one call: the first point of S = ∂{w > level} (solid-angle mode: of
// {w ≡ level mod 1}, smooth crossings only) along `ray` inside `box`, or none.
inline ReferenceCrossing reference_first_crossing(const ReferenceMesh& r, const Ray& ray, double level,
                                                  const Aabb& box, int samples,
                                                  ReferenceMode mode = ReferenceMode::kWindingNumber) {
  return reference_crossing(r, reference_profile(r, ray, box, samples), level, mode);
}

}  // namespace gwnrt::test
