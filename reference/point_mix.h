// The benchmark's query points, shared with the tests so that accuracy is measured on the same
// distribution as speed: 70% uniform in the mesh box, 30% uniform in the box scaled 3× about
// its centre but outside the box.
#pragma once

#include <random>
#include <vector>

#include "gwnrt/geometry/bvh.h"

namespace gwnrt {

inline std::vector<vec3> point_mix(const Aabb& box, size_t count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const vec3 c = box.centre(), half = 0.5f * (box.hi - box.lo);
  std::vector<vec3> points;
  points.reserve(count);
  while (points.size() < count) {
    const bool inside = u(rng) < 0.7f;
    const float scale = inside ? 1.0f : 3.0f;
    const vec3 p = c + scale * half * vec3(2 * u(rng) - 1, 2 * u(rng) - 1, 2 * u(rng) - 1);
    const bool in_box = glm::all(glm::lessThanEqual(box.lo, p)) && glm::all(glm::lessThanEqual(p, box.hi));
    if (inside || !in_box) points.push_back(p);
  }
  return points;
}

}  // namespace gwnrt
