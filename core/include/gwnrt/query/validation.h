// What the batch drivers, the CUDA backend and the programs accept: query points, requests,
// trace options, and a model view that holds the parts a request reads. Each check names what it
// refuses.
#pragma once

#include <cmath>
#include <span>

#include "gwnrt/base/status.h"
#include "gwnrt/geometry/model_view.h"
#include "gwnrt/query/point_query.h"
#include "gwnrt/trace/trace_types.h"

namespace gwnrt {

// The query points the drivers serve: finite, every coordinate within +-kMaxQueryCoordinate
// (beyond, the squared distances to M overflow float and the distances and the sdf's sign go
// wrong; within it, at the limits of kMaxMeshCoordinate and kMinMeshExtent, w, the distances and
// the sdf are right). Names the first point that is not.
inline constexpr float kMaxQueryCoordinate = 1e18f;
// Whether `p` is such a point (NaN and inf are not).
inline bool query_point_served(const vec3& p) {
  return std::fabs(p.x) <= kMaxQueryCoordinate && std::fabs(p.y) <= kMaxQueryCoordinate &&
         std::fabs(p.z) <= kMaxQueryCoordinate;
}
Status validate_points(std::span<const vec3> points);

// Order, beta, level and Newton options; with `view`, also that it holds the parts the request
// reads and that sdf and sheet-distance requests ask for the level its sheets were classified for.
Status validate_request(const QueryRequest& request, const ModelView* view = nullptr);

// That `view` holds ∂M and its cone, which the tracer reads (a view without them would be traced
// as a closed mesh).
Status validate_trace_view(const ModelView& view);

// Level finite, epsilon in (0, 1), beta finite and >= 1 (beta_valid), caps > 0.
Status validate_trace_options(const TraceOptions& options);

}  // namespace gwnrt
