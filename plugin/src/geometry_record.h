// What the plugin's C API and its callbacks share: the mesh behind a GWNRTMesh handle and the
// user data of one geometry.
#pragma once

#include <atomic>
#include <cstdint>

#include "gwnrt/embree.h"
#include "gwnrt/model/model.h"
#include "gwnrt/trace/trace_types.h"

struct GWNRTMeshTy {
  std::atomic<uint32_t> references{1};
  gwnrt::GwnModel model;
  gwnrt::ModelView view;  // of `model`, made once
};

namespace gwnrt::embree_plugin {

// The user data of one geometry. Embree 3 tells a user geometry nothing when it is destroyed, so
// a record (and its reference to the mesh) cannot be freed with it: records are kept until the
// process ends, when the registry gives them back (so that leak checkers see nothing left).
struct GeometryRecord {
  GWNRTMesh mesh;
  TraceOptions options;
  Aabb bounds;
};

}  // namespace gwnrt::embree_plugin
