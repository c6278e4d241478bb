// Everything in the plugin that depends on the Embree major version (this is Embree 3.13's).
// An Embree 4 port changes only this file: the query context is RTCRayQueryContext and the
// instance IDs move to it, the filter calls are rtcInvokeIntersectFilterFromGeometry /
// rtcInvokeOccludedFilterFromGeometry taking argument structs, and the callbacks must write
// valid[] (-1 / 0), which the plugin already does.
#pragma once

#include <embree3/rtcore.h>

namespace gwnrt::embree_api {

using IntersectArguments = RTCIntersectFunctionNArguments;
using OccludedArguments = RTCOccludedFunctionNArguments;
using FilterArguments = RTCFilterFunctionNArguments;

// The instance IDs of the instances the ray is inside of, for the hit's instID.
template <class Arguments>
unsigned int instance_id(const Arguments* args, unsigned level) {
  return args->context->instID[level];
}
inline constexpr unsigned kInstanceLevels = RTC_MAX_INSTANCE_LEVEL_COUNT;

inline FilterArguments filter_arguments(const IntersectArguments* args, int* valid, RTCHitN* hit) {
  return {valid, args->geometryUserPtr, args->context, RTCRayHitN_RayN(args->rayhit, args->N), hit, args->N};
}
inline FilterArguments filter_arguments(const OccludedArguments* args, int* valid, RTCHitN* hit) {
  return {valid, args->geometryUserPtr, args->context, args->ray, hit, args->N};
}
inline void invoke_filter(const IntersectArguments* args, const FilterArguments* filter) {
  rtcFilterIntersection(args, filter);
}
inline void invoke_filter(const OccludedArguments* args, const FilterArguments* filter) {
  rtcFilterOcclusion(args, filter);
}

inline void set_callbacks(RTCGeometry geometry, RTCBoundsFunction bounds, RTCIntersectFunctionN intersect,
                          RTCOccludedFunctionN occluded) {
  rtcSetGeometryBoundsFunction(geometry, bounds, nullptr);
  rtcSetGeometryIntersectFunction(geometry, intersect);
  rtcSetGeometryOccludedFunction(geometry, occluded);
}

}  // namespace gwnrt::embree_api
