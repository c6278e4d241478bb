// What the tests of phase.h and harnack.h share: references in double for the distance to ∂M,
// the points they sample (beside ∂M, beside the cone's inner edges, around M, far away) and how
// they print them.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "gwnrt/model/model.h"
#include "test_util.h"

namespace gwnrt {

using test::build_model;
using test::load_test_mesh;

using test::kInf;
inline constexpr double kTwoPi = 2.0 * kPi;

class RandomDouble {
 public:
  explicit RandomDouble(uint32_t seed) : g_(seed) {}
  double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(g_); }
  double exp10(double lo, double hi) { return std::pow(10.0, uniform(lo, hi)); }  // log-uniform
  int index(int n) { return std::uniform_int_distribution<int>(0, n - 1)(g_); }
  bool chance(double p) { return uniform(0.0, 1.0) < p; }
  double sign() { return chance(0.5) ? 1.0 : -1.0; }
  dvec3 unit() {
    for (;;) {
      const dvec3 v(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
      const double l = glm::length(v);
      if (l > 0.1 && l <= 1.0) return v / l;
    }
  }
  // A unit vector perpendicular to `d` (unit).
  dvec3 perpendicular(const dvec3& d) {
    for (;;) {
      const dvec3 v = unit();
      const dvec3 p = v - d * glm::dot(v, d);
      const double l = glm::length(p);
      if (l > 0.1) return p / l;
    }
  }
  dvec3 in_box(const Aabb& b) { return {uniform(b.lo.x, b.hi.x), uniform(b.lo.y, b.hi.y), uniform(b.lo.z, b.hi.z)}; }

 private:
  std::mt19937 g_;
};

// A point rounded to float, in a function of its own: GCC 12.2's SLP vectorizer (-O2 and up)
// drops the rounding in dvec3(vec3(d)) when both happen in one function, so that the double
// reference would see the unrounded point while the library sees the float one.
[[gnu::noinline]] inline vec3 to_float(const dvec3& v) { return vec3(v); }

// Differences on the circle: turns (w mod 1) to [-1/2, 1/2), radians to [-π, π].
inline double wrap_turns(double d) { return d - std::floor(d + 0.5); }
inline double wrap_angle(double a) { return std::remainder(a, kTwoPi); }

// ∂M as double segments, straight from GwnModel::boundary().
struct BoundaryRef {
  std::vector<dvec3> a, b;
  size_t size() const { return a.size(); }
};

inline BoundaryRef boundary_ref(const GwnModel& model) {
  BoundaryRef r;
  const std::vector<vec3>& e = model.boundary().endpoints;
  for (size_t s = 0; s + 1 < e.size(); s += 2) {
    r.a.push_back(dvec3(e[s]));
    r.b.push_back(dvec3(e[s + 1]));
  }
  return r;
}

inline dvec3 closest_on_segment(const dvec3& a, const dvec3& b, const dvec3& x) {
  const dvec3 ab = b - a;
  const double len2 = glm::dot(ab, ab);
  const double t = len2 > 0 ? std::clamp(glm::dot(x - a, ab) / len2, 0.0, 1.0) : 0.0;
  return a + t * ab;
}

// The distance from x to ∂M and its nearest point.
inline double boundary_distance_ref(const BoundaryRef& r, const dvec3& x, dvec3* nearest = nullptr) {
  double best = kInf;
  for (size_t s = 0; s < r.size(); ++s) {
    const dvec3 c = closest_on_segment(r.a[s], r.b[s], x);
    const double d = glm::length(c - x);
    if (d < best) {
      best = d;
      if (nearest) *nearest = c;
    }
  }
  return best;
}

template <class V>
inline std::string vec_string(const V& v) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "(%.17g, %.17g, %.17g)", double(v.x), double(v.y), double(v.z));
  return buf;
}

inline std::string point_string(const vec3& x) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "x = (%.9g, %.9g, %.9g)", x.x, x.y, x.z);
  return buf;
}

// Where the tests sample: beside ∂M, beside the cone's inner edges (apex to a boundary vertex,
// where the terms of two cone triangles are singular and cancel), and anywhere around M.
// Far away too, where |w| is so small that w mod 1 of a negative w rounds to 1 unless folded.
enum class PointKind { kNearBoundary = 0, kNearConeEdge = 1, kBox = 2, kFar = 3 };

inline vec3 sample_point(const GwnModel& model, const BoundaryRef& boundary, PointKind kind, RandomDouble& rng) {
  switch (kind) {
    case PointKind::kNearBoundary: {
      const size_t s = size_t(rng.index(int(boundary.size())));
      const dvec3 on = boundary.a[s] + rng.uniform(0, 1) * (boundary.b[s] - boundary.a[s]);
      return to_float(on + rng.exp10(-3, 0) * rng.unit());
    }
    case PointKind::kNearConeEdge: {
      const std::vector<vec3>& v = model.cone_tree().vertices;
      const size_t t = size_t(rng.index(int(v.size() / 3)));
      const dvec3 apex(v[3 * t]), a(v[3 * t + 1]);
      const dvec3 on = apex + rng.uniform(0.02, 0.98) * (a - apex);
      return to_float(on + rng.exp10(-5, -3) * rng.unit());
    }
    case PointKind::kBox: {
      const Aabb b = model.bounds();
      const float grow = 0.5f * glm::length(b.hi - b.lo);
      return to_float(rng.in_box(Aabb{b.lo - vec3(grow), b.hi + vec3(grow)}));
    }
    default: {
      const Aabb b = model.bounds();
      return to_float(dvec3(b.centre()) + glm::length(dvec3(b.hi - b.lo)) * rng.exp10(2, 6) * rng.unit());
    }
  }
}

}  // namespace gwnrt
