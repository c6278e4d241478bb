// Everything a query or a ray needs from a GwnModel, as trivially copyable views: what the
// host-and-device functions take and what the CUDA backend fills with device pointers.
#pragma once

#include "gwnrt/bvh.h"

namespace gwnrt {

struct ModelView {
  TriangleTreeView triangles;  // M
  SegmentTreeView boundary;    // ∂M
  // The cone C over ∂M: triangles (z, a, b) for each boundary segment a→b, z the mean of the
  // boundary vertices. M − C is closed, so w − w_C is an integer off M ∪ C and w mod 1 =
  // w_C mod 1 (DESIGN §3): the tracer's Harnack steps evaluate C, not M. Empty when ∂M is.
  TriangleTreeView cone;
  Aabb bounds;               // of M
  float surface_margin = 0;  // S lies inside `bounds` grown by this: |w| < 1/2 beyond (DESIGN §5)
};

}  // namespace gwnrt
