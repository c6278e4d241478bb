// What the tests of the mesher and of gwnrt-mesh share.
#pragma once

#include <cstdint>

#include "gwnrt/meshing/extract_surface.h"

namespace gwnrt {

inline MeshingOptions options_at(uint32_t resolution) {
  MeshingOptions o;
  o.resolution = resolution;
  return o;
}

}  // namespace gwnrt
