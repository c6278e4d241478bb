// The user-geometry callbacks that Embree calls for a GWN object (callbacks.cpp): its bounds, and
// intersect and occluded for N = 1, 4, 8, 16, each running trace_surface per active lane.
#pragma once

#include <embree3/rtcore.h>

namespace gwnrt::embree_plugin {

void bounds_callback(const RTCBoundsFunctionArguments* args);
void intersect_callback(const RTCIntersectFunctionNArguments* args);
void occluded_callback(const RTCOccludedFunctionNArguments* args);

}  // namespace gwnrt::embree_plugin
