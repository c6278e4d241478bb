// The checks of queries, rays and their options (gwnrt/query/validation.h).
#include "gwnrt/query/validation.h"

#include <string>

#include "base/message.h"
#include "gwnrt/base/option_limits.h"

namespace gwnrt {

Status validate_points(std::span<const vec3> points) {
  for (size_t i = 0; i < points.size(); ++i) {
    const vec3& p = points[i];
    if (!query_point_served(p))
      return {StatusCode::kInvalidArgument,
              cat("point ", i, " (", p.x, ", ", p.y, ", ", p.z, ") is not finite or lies beyond +-",
                  kMaxQueryCoordinate, ", the coordinates gwnrt serves (its squared distances would overflow float)")};
  }
  return Status::Ok();
}

namespace {
constexpr const char* kBoundaryNotBuilt =
    "the model's boundary and cone are not built, and this query reads them (GwnModel::prepare with kPartBoundary)";
}  // namespace

Status validate_trace_view(const ModelView& view) {
  if (!(view.parts & kPartBoundary)) return {StatusCode::kInvalidArgument, kBoundaryNotBuilt};
  return Status::Ok();
}

Status validate_request(const QueryRequest& request, const ModelView* view) {
  if (uint32_t(request.method) >= kWindingMethodCount)
    return {StatusCode::kInvalidArgument, "winding method must be auto, crossing, taylor or brute, got the value " +
                                              std::to_string(uint32_t(request.method))};
  if (request.taylor.order < 0 || request.taylor.order > 2)
    return {StatusCode::kInvalidArgument,
            "Taylor order must be 0, 1 or 2, got " + std::to_string(request.taylor.order)};
  if (!beta_valid(request.taylor.beta)) return {StatusCode::kInvalidArgument, beta_refusal(request.taylor.beta)};
  if (!std::isfinite(request.level)) return {StatusCode::kInvalidArgument, "level w* must be a finite number"};
  const NewtonOptions& n = request.newton;
  if (!(n.tolerance > 0.0f) || !(n.max_step > 0.0f) || !(n.mesh_fraction > 0.0f && n.mesh_fraction <= 1.0f) ||
      !std::isfinite(n.tolerance) || !std::isfinite(n.max_step))
    return {StatusCode::kInvalidArgument,
            "Newton options: tolerance and max_step must be finite and > 0, mesh_fraction in (0, 1]"};
  if (view && (parts_read_by(request) & kPartBoundary) && !(view->parts & kPartBoundary))
    return {StatusCode::kInvalidArgument, kBoundaryNotBuilt};
  if (view && (request.fields & kSheetFields)) {
    if (std::isnan(view->sheet_level))
      return {StatusCode::kInvalidArgument,
              "the signed and sheet distances need the model's sheets, and it was built without them "
              "(BuildOptions::classify_sheets; GwnModel::set_sheet_level classifies them)"};
    if (request.level != view->sheet_level)
      return {StatusCode::kInvalidArgument, "level " + std::to_string(request.level) +
                                                " asked for, but the model's sheets were classified for level " +
                                                std::to_string(view->sheet_level) + " (GwnModel::set_sheet_level)"};
  }
  return Status::Ok();
}

Status validate_trace_options(const TraceOptions& options) {
  if (options.mode != TraceMode::kWindingNumber && options.mode != TraceMode::kSolidAngle)
    return {StatusCode::kInvalidArgument, "trace mode must be winding-number or solid-angle"};
  if (!trace_level_valid(options.level)) return {StatusCode::kInvalidArgument, "trace level must be a finite number"};
  if (!trace_epsilon_valid(options.epsilon))
    return {StatusCode::kInvalidArgument, "trace epsilon must lie in (0, 1) (it is relative to the box diagonal)"};
  if (!trace_beta_valid(options.beta)) return {StatusCode::kInvalidArgument, beta_refusal(options.beta)};
  if (!trace_cap_valid(options.max_steps) || !trace_cap_valid(options.max_crossings))
    return {StatusCode::kInvalidArgument, "step and crossing caps must be at least 1"};
  return Status::Ok();
}

}  // namespace gwnrt
