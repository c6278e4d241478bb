// Per-item random generators seeded from (seed, stream, index): the accuracy study draws the same
// points and lines whatever the thread count, and its reference the same lines.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>

#include "gwnrt/base/hd.h"
#include "gwnrt/geometry/bvh.h"

namespace gwnrt::reference {

inline std::mt19937_64 item_rng(uint64_t seed, uint64_t stream, uint64_t index) {
  std::seed_seq seq{uint32_t(seed), uint32_t(seed >> 32), uint32_t(stream), uint32_t(index), uint32_t(index >> 32)};
  return std::mt19937_64(seq);
}

inline double uniform(std::mt19937_64& rng) { return std::uniform_real_distribution<double>(0.0, 1.0)(rng); }

inline dvec3 random_direction(std::mt19937_64& rng) {
  const double z = 2.0 * uniform(rng) - 1.0, a = 2.0 * kPi * uniform(rng), r = std::sqrt(std::max(0.0, 1.0 - z * z));
  return {r * std::cos(a), r * std::sin(a), z};
}

inline dvec3 uniform_in_box(const Aabb& box, std::mt19937_64& rng) {
  const dvec3 lo(box.lo), hi(box.hi);
  return lo + (hi - lo) * dvec3(uniform(rng), uniform(rng), uniform(rng));
}

}  // namespace gwnrt::reference
