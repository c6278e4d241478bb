// The plugin's C API (gwnrt/embree.h): meshes, options, geometries and the last error. Nothing
// thrown inside crosses into the C caller (guard_c_api). The callbacks are callbacks.cpp.
#include "gwnrt/embree.h"

#include <atomic>
#include <cstring>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "callbacks.h"
#include "embree_api.h"
#include "geometry_record.h"
#include "gwnrt/geometry/mesh.h"
#include "gwnrt/io/mesh_io.h"
#include "gwnrt/model/model.h"
#include "gwnrt/query/validation.h"
#include "gwnrt/trace/surface_trace.h"

namespace {

using namespace gwnrt;
using namespace gwnrt::embree_plugin;

static_assert(sizeof(GWNRTMode) == sizeof(int), "GWNRTOptions::mode is read as an int");

thread_local std::string g_last_error;

void set_error(std::string message) { g_last_error = std::move(message); }

// The C API's boundary: runs body and, should it throw (an allocation failure, a size beyond
// memory), records the error and returns `failed`. Nothing crosses into the C caller.
template <class T, class Fn>
T guard_c_api(const char* where, T failed, Fn&& body) noexcept {
  T result = failed;
  const Status s = guard_status(where, [&] {
    result = body();
    return Status::Ok();
  });
  if (!s.ok()) {
    set_error(s.message());
    return failed;
  }
  return result;
}

// `note` follows a refusal's message (recentred_note for a recentred mesh).
GWNRTMesh build(Mesh mesh, const std::string& source, const std::string& note = "") {
  auto out = std::make_unique<GWNRTMeshTy>();
  BuildOptions build;
  build.classify_sheets = false;  // only traced: no signed distances
  if (Status s = GwnModel::build(std::move(mesh), out->model, build); !s.ok()) {
    set_error(source + ": " + s.message() + note);
    return nullptr;
  }
  // The tracer's level-free cells for w* = 1/2 (BuildOptions' level): a geometry traced at
  // another phase goes without them.
  if (Status s = out->model.prepare(kPartLevelFreeCells); !s.ok()) {
    set_error(source + ": " + s.message() + note);
    return nullptr;
  }
  out->view = out->model.view();
  return out.release();
}

class RecordRegistry {
 public:
  static GeometryRecord* add(GeometryRecord record) {
    RecordRegistry& r = instance();
    std::lock_guard<std::mutex> lock(r.mutex_);
    r.records_.push_back(std::make_unique<GeometryRecord>(record));
    return r.records_.back().get();
  }
  ~RecordRegistry() {
    for (const auto& record : records_) gwnrtReleaseMesh(record->mesh);
  }

 private:
  static RecordRegistry& instance() {
    static RecordRegistry registry;
    return registry;
  }
  std::mutex mutex_;
  std::vector<std::unique_ptr<GeometryRecord>> records_;
};

TraceOptions trace_options(const GWNRTOptions& o) {
  TraceOptions t;
  t.mode = o.mode == GWNRT_MODE_SOLID_ANGLE ? TraceMode::kSolidAngle : TraceMode::kWindingNumber;
  t.level = o.level;
  t.epsilon = o.epsilon;
  t.max_steps = o.max_steps;
  t.max_crossings = o.max_crossings;
  t.beta = o.beta;
  return t;
}

}  // namespace

extern "C" {

GWNRTMesh gwnrtNewMesh(const float* xyz, size_t vertexCount, const uint32_t* triangles, size_t triangleCount) {
  return guard_c_api("gwnrtNewMesh", GWNRTMesh(nullptr), [&]() -> GWNRTMesh {
    if ((vertexCount > 0 && !xyz) || (triangleCount > 0 && !triangles)) {
      set_error("gwnrtNewMesh: NULL vertex or triangle array");
      return nullptr;
    }
    Mesh mesh;
    mesh.positions.resize(vertexCount);
    for (size_t i = 0; i < vertexCount; ++i) mesh.positions[i] = vec3(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    mesh.triangles.resize(triangleCount);
    for (size_t t = 0; t < triangleCount; ++t)
      mesh.triangles[t] = uvec3(triangles[3 * t], triangles[3 * t + 1], triangles[3 * t + 2]);
    return build(std::move(mesh), "gwnrtNewMesh");
  });
}

namespace {

// gwnrtLoadMesh and gwnrtLoadMeshRecentred: `origin` is NULL for the first.
GWNRTMesh load_and_build(const char* function, const char* path, double* origin) {
  return guard_c_api(function, GWNRTMesh(nullptr), [&]() -> GWNRTMesh {
    if (origin) origin[0] = origin[1] = origin[2] = 0.0;
    if (!path) {
      set_error(std::string(function) + ": NULL path");
      return nullptr;
    }
    Mesh mesh;
    MeshLoadReport report;
    if (Status s = load_mesh(path, mesh, &report, MeshLoadOptions{.recentre = origin != nullptr}); !s.ok()) {
      set_error(s.message());
      return nullptr;
    }
    GWNRTMesh built = build(std::move(mesh), path, recentred_note(report.origin));
    if (built && origin) {
      origin[0] = report.origin.x;
      origin[1] = report.origin.y;
      origin[2] = report.origin.z;
    }
    return built;
  });
}

}  // namespace

GWNRTMesh gwnrtLoadMesh(const char* path) { return load_and_build("gwnrtLoadMesh", path, nullptr); }

GWNRTMesh gwnrtLoadMeshRecentred(const char* path, double origin[3]) {
  if (!origin) {
    set_error("gwnrtLoadMeshRecentred: NULL origin");
    return nullptr;
  }
  return load_and_build("gwnrtLoadMeshRecentred", path, origin);
}

void gwnrtRetainMesh(GWNRTMesh mesh) {
  if (mesh) mesh->references.fetch_add(1, std::memory_order_relaxed);
}

void gwnrtReleaseMesh(GWNRTMesh mesh) {
  if (mesh && mesh->references.fetch_sub(1, std::memory_order_acq_rel) == 1) delete mesh;
}

size_t gwnrtGetMeshTriangleCount(GWNRTMesh mesh) { return mesh ? mesh->model.mesh().triangles.size() : 0; }
size_t gwnrtGetMeshVertexCount(GWNRTMesh mesh) { return mesh ? mesh->model.mesh().positions.size() : 0; }

void gwnrtInitOptions(GWNRTOptions* options) {
  if (!options) return;
  const TraceOptions d;
  options->mode = d.mode == TraceMode::kSolidAngle ? GWNRT_MODE_SOLID_ANGLE : GWNRT_MODE_GWN;
  options->level = d.level;
  options->epsilon = d.epsilon;
  options->max_steps = d.max_steps;
  options->max_crossings = d.max_crossings;
  options->beta = d.beta;
}

RTCGeometry gwnrtNewGeometry(RTCDevice device, GWNRTMesh mesh, const GWNRTOptions* options) {
  return guard_c_api("gwnrtNewGeometry", RTCGeometry(nullptr), [&]() -> RTCGeometry {
    if (!device || !mesh) {
      set_error(!device ? "gwnrtNewGeometry: NULL device" : "gwnrtNewGeometry: NULL mesh");
      return nullptr;
    }
    GWNRTOptions o;
    gwnrtInitOptions(&o);
    if (options) {
      // Read as the integer it is: a C caller may pass any int, and loading an out-of-range
      // value as the enum would be undefined in C++.
      int mode;
      std::memcpy(&mode, &options->mode, sizeof mode);
      if (mode != GWNRT_MODE_GWN && mode != GWNRT_MODE_SOLID_ANGLE) {
        set_error("gwnrtNewGeometry: mode must be GWNRT_MODE_GWN or GWNRT_MODE_SOLID_ANGLE");
        return nullptr;
      }
      o = *options;
    }
    const TraceOptions trace = trace_options(o);
    if (Status s = validate_trace_options(trace); !s.ok()) {
      set_error("gwnrtNewGeometry: " + s.message());
      return nullptr;
    }
    Aabb bounds = surface_bounds(mesh->view, trace);
    if (!bounds.valid()) bounds = mesh->model.bounds();  // S is empty: any box will do
    // The record first: adding it is what may throw, and until it exists nothing is held. Should
    // Embree then fail, the record keeps its reference until the process ends, as all records do.
    GeometryRecord* record = RecordRegistry::add({mesh, trace, bounds});
    gwnrtRetainMesh(mesh);
    RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
    if (!geometry) {
      set_error("gwnrtNewGeometry: Embree could not create a user geometry (see the device's error)");
      return nullptr;
    }
    rtcSetGeometryUserPrimitiveCount(geometry, 1);
    rtcSetGeometryUserData(geometry, record);
    embree_api::set_callbacks(geometry, bounds_callback, intersect_callback, occluded_callback);
    // Committed, so that it can be attached as it is; an application that changes it later (mask,
    // filters) commits it again, as any Embree geometry.
    rtcCommitGeometry(geometry);
    return geometry;
  });
}

const char* gwnrtGetLastError(void) { return g_last_error.c_str(); }

}  // extern "C"
