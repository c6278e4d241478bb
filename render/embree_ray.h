// An Embree ray (RTCRayHit) for a gwnrt::Ray: what the renderer, the tracing benchmark and the
// tests that compare with Embree all hand to rtcIntersect1 / rtcOccluded1. Host-only.
#pragma once

#include <embree3/rtcore.h>

#include "gwnrt/geometry/ray.h"

namespace gwnrt::render {

inline RTCRayHit embree_ray_hit(const vec3& origin, const vec3& direction, float tnear, float tfar, unsigned mask = ~0u,
                                unsigned id = 0) {
  RTCRayHit rh{};
  rh.ray.org_x = origin.x;
  rh.ray.org_y = origin.y;
  rh.ray.org_z = origin.z;
  rh.ray.dir_x = direction.x;
  rh.ray.dir_y = direction.y;
  rh.ray.dir_z = direction.z;
  rh.ray.tnear = tnear;
  rh.ray.tfar = tfar;
  rh.ray.time = 0.0f;
  rh.ray.mask = mask;
  rh.ray.id = id;
  rh.ray.flags = 0;
  rh.hit.geomID = rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
  for (unsigned& i : rh.hit.instID) i = RTC_INVALID_GEOMETRY_ID;
  return rh;
}

inline RTCRayHit embree_ray_hit(const Ray& r, unsigned mask = ~0u, unsigned id = 0) {
  return embree_ray_hit(r.origin, r.direction, r.tnear, r.tfar, mask, id);
}

}  // namespace gwnrt::render
