// The Embree plugin: a gwnrt mesh as an Embree user geometry whose callbacks run trace_surface.
#include "gwnrt/embree.h"
#include "gwnrt/io/mesh_io.h"

#include <atomic>
#include <cstring>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "embree_api.h"
#include "gwnrt/batch.h"
#include "gwnrt/geometry/mesh.h"
#include "gwnrt/geometry/model.h"
#include "gwnrt/trace/surface_trace.h"

struct GWNRTMeshTy {
  std::atomic<uint32_t> references{1};
  gwnrt::GwnModel model;
  gwnrt::ModelView view;  // of `model`, made once
};

namespace {

using namespace gwnrt;

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

GWNRTMesh build(Mesh mesh, const std::string& source) {
  auto out = std::make_unique<GWNRTMeshTy>();
  BuildOptions build;
  build.classify_sheets = false;  // only traced: no signed distances
  if (Status s = GwnModel::build(std::move(mesh), out->model, build); !s.ok()) {
    set_error(source + ": " + s.message());
    return nullptr;
  }
  out->view = out->model.view();
  return out.release();
}

// The user data of one geometry. Embree 3 tells a user geometry nothing when it is destroyed, so
// a record (and its reference to the mesh) cannot be freed with it: records are kept until the
// process ends, when the registry gives them back (so that leak checkers see nothing left).
struct GeometryRecord {
  GWNRTMesh mesh;
  TraceOptions options;
  Aabb bounds;
};

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

// Rays come as N-wide SoA packets (N = 1, 4, 8 or 16); lanes are read and written by index.
struct Lane {
  RTCRayN* rays;
  unsigned n, i;
  float& tnear() const { return RTCRayN_tnear(rays, n, i); }
  float& tfar() const { return RTCRayN_tfar(rays, n, i); }
  Ray ray() const {
    Ray r;
    r.origin = vec3(RTCRayN_org_x(rays, n, i), RTCRayN_org_y(rays, n, i), RTCRayN_org_z(rays, n, i));
    // Inside an instance the direction is not normalised; t is in its units, as trace_surface's.
    r.direction = vec3(RTCRayN_dir_x(rays, n, i), RTCRayN_dir_y(rays, n, i), RTCRayN_dir_z(rays, n, i));
    r.tnear = tnear();
    r.tfar = tfar();
    return r;
  }
};

// An N-wide hit with one lane filled, for the filter and for copying into the ray's own hit.
struct PotentialHit {
  alignas(64) float words[16 * (7 + embree_api::kInstanceLevels)];
  RTCHitN* hit() { return reinterpret_cast<RTCHitN*>(words); }
};

uint32_t primitive_of(const RayHit& h) { return h.kind == HitKind::kSheet ? h.triangle : GWNRT_SMOOTH_PRIM_ID; }

// Barycentric coordinates of a sheet hit on its input triangle (Embree's convention).
void barycentrics(const GwnModel& model, const RayHit& h, float& u, float& v) {
  u = v = 0.0f;
  if (h.kind != HitKind::kSheet) return;
  const Mesh& mesh = model.mesh();
  const uvec3 t = mesh.triangles[h.triangle];
  const ClosestPoint<float> c =
      closest_point_on_triangle(mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]], h.position);
  u = c.u;
  v = c.v;
}

template <class Arguments>
void write_hit(RTCHitN* hit, unsigned n, unsigned i, const RayHit& h, const GeometryRecord& record, unsigned geom_id,
               const Arguments* args) {
  RTCHitN_Ng_x(hit, n, i) = h.normal.x;
  RTCHitN_Ng_y(hit, n, i) = h.normal.y;
  RTCHitN_Ng_z(hit, n, i) = h.normal.z;
  float u, v;
  barycentrics(record.mesh->model, h, u, v);
  RTCHitN_u(hit, n, i) = u;
  RTCHitN_v(hit, n, i) = v;
  RTCHitN_primID(hit, n, i) = primitive_of(h);
  RTCHitN_geomID(hit, n, i) = geom_id;
  for (unsigned l = 0; l < embree_api::kInstanceLevels; ++l)
    RTCHitN_instID(hit, n, i, l) = embree_api::instance_id(args, l);
}

void copy_hit_lane(RTCHitN* to, RTCHitN* from, unsigned n, unsigned i) {
  RTCHitN_Ng_x(to, n, i) = RTCHitN_Ng_x(from, n, i);
  RTCHitN_Ng_y(to, n, i) = RTCHitN_Ng_y(from, n, i);
  RTCHitN_Ng_z(to, n, i) = RTCHitN_Ng_z(from, n, i);
  RTCHitN_u(to, n, i) = RTCHitN_u(from, n, i);
  RTCHitN_v(to, n, i) = RTCHitN_v(from, n, i);
  RTCHitN_primID(to, n, i) = RTCHitN_primID(from, n, i);
  RTCHitN_geomID(to, n, i) = RTCHitN_geomID(from, n, i);
  for (unsigned l = 0; l < embree_api::kInstanceLevels; ++l) RTCHitN_instID(to, n, i, l) = RTCHitN_instID(from, n, i, l);
}

// Offers a candidate hit of lane i to the intersection (or occlusion) filters, with the ray's
// tfar set to it as Embree does for its own primitives; true when accepted (tfar then stays).
template <class Arguments>
bool filter_accepts(const Arguments* args, const Lane& lane, RTCHitN* potential, float t) {
  int valid[16] = {};
  valid[lane.i] = -1;
  const float old_tfar = lane.tfar();
  lane.tfar() = t;
  const embree_api::FilterArguments filter = embree_api::filter_arguments(args, valid, potential);
  embree_api::invoke_filter(args, &filter);
  if (valid[lane.i] == -1) return true;
  lane.tfar() = old_tfar;
  return false;
}

void bounds_callback(const RTCBoundsFunctionArguments* args) {
  const auto* record = static_cast<const GeometryRecord*>(args->geometryUserPtr);
  RTCBounds& b = *args->bounds_o;
  b.lower_x = record->bounds.lo.x;
  b.lower_y = record->bounds.lo.y;
  b.lower_z = record->bounds.lo.z;
  b.upper_x = record->bounds.hi.x;
  b.upper_y = record->bounds.hi.y;
  b.upper_z = record->bounds.hi.z;
}

void intersect_callback(const RTCIntersectFunctionNArguments* args) {
  const auto* record = static_cast<const GeometryRecord*>(args->geometryUserPtr);
  const unsigned n = args->N;
  RTCRayN* rays = RTCRayHitN_RayN(args->rayhit, n);
  RTCHitN* hits = RTCRayHitN_HitN(args->rayhit, n);
  PotentialHit potential;
  for (unsigned i = 0; i < n; ++i) {
    if (args->valid[i] != -1) continue;
    const Lane lane{rays, n, i};
    const float tnear = lane.tnear();
    bool accepted = false;
    // Embree accepts hits strictly inside (tnear, tfar); tfar shrinks as hits are accepted.
    trace_surface(record->mesh->view, lane.ray(), record->options, [&](const RayHit& h) {
      if (!(h.t > tnear && h.t < lane.tfar())) return false;
      write_hit(potential.hit(), n, i, h, *record, args->geomID, args);
      accepted = filter_accepts(args, lane, potential.hit(), h.t);
      return accepted;
    });
    if (accepted) copy_hit_lane(hits, potential.hit(), n, i);
  }
}

void occluded_callback(const RTCOccludedFunctionNArguments* args) {
  const auto* record = static_cast<const GeometryRecord*>(args->geometryUserPtr);
  const unsigned n = args->N;
  PotentialHit potential;
  for (unsigned i = 0; i < n; ++i) {
    if (args->valid[i] != -1) continue;
    const Lane lane{args->ray, n, i};
    const float tnear = lane.tnear();
    bool occluded = false;
    // Any accepted hit occludes: the trace stops at the first one.
    trace_surface(record->mesh->view, lane.ray(), record->options, [&](const RayHit& h) {
      if (!(h.t > tnear && h.t < lane.tfar())) return false;
      write_hit(potential.hit(), n, i, h, *record, args->geomID, args);
      occluded = filter_accepts(args, lane, potential.hit(), h.t);
      return occluded;
    });
    if (occluded) lane.tfar() = -kInfinity;
  }
}

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

GWNRTMesh gwnrtLoadMesh(const char* path) {
  return guard_c_api("gwnrtLoadMesh", GWNRTMesh(nullptr), [&]() -> GWNRTMesh {
  if (!path) {
    set_error("gwnrtLoadMesh: NULL path");
    return nullptr;
  }
  Mesh mesh;
  if (Status s = load_mesh(path, mesh); !s.ok()) {
    set_error(s.message());
    return nullptr;
  }
  return build(std::move(mesh), path);
  });
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
