// Where a ray meets a GWN object in Embree: the bounds, intersect and occluded callbacks. Each
// active lane runs the core's trace_surface on (tnear, tfar) and offers every candidate hit, in
// increasing t, to the geometry's filters (docs/design.md §6). No mutable shared state: safe on
// many threads at once.
#include "callbacks.h"

#include "embree_api.h"
#include "geometry_record.h"
#include "gwnrt/trace/surface_trace.h"

namespace gwnrt::embree_plugin {
namespace {

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
  for (unsigned l = 0; l < embree_api::kInstanceLevels; ++l)
    RTCHitN_instID(to, n, i, l) = RTCHitN_instID(from, n, i, l);
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

}  // namespace

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

}  // namespace gwnrt::embree_plugin
