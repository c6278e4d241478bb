// The ribbon tree over ∂M (built in core/src/geometry/ribbon_tree.cpp): a wide BVH over ∂M's
// segments that keeps each closed trail of them whole while a lane holds more than one and cuts
// it only into runs of consecutive segments, so that a lane's segments have few loose ends (none
// for whole trails, two for a run). Per lane, the fan of its segments from one of their loose
// ends, with its multipole moments, and the other loose ends: far from a lane, its ribbons sum to
// the fan plus one ribbon per loose end (field/ribbon_winding.h).
#pragma once

#include <span>
#include <vector>

#include "gwnrt/geometry/bvh.h"

namespace gwnrt {

struct RibbonTree {
  WideBvh bvh;
  std::vector<vec3> endpoints;               // 2 per segment, leaf order
  std::vector<WideNodeExpansion> expansion;  // per node: the fans'
  std::vector<WideNodeOrder1> order1;
  std::vector<WideNodeOrder2> order2;
  std::vector<WideNodeFan> fan_ends;
  std::vector<LooseEnd> loose_ends;
  RibbonTreeView view() const;
};

// From ∂M's segments (2 endpoints each, segments a -> b), leaves of up to max_leaf_size.
Status build_ribbon_tree(std::span<const vec3> endpoints, uint32_t max_leaf_size, RibbonTree& out);

}  // namespace gwnrt
