#include <chrono>
#include <cmath>
#include <string>

#include "gwnrt/model.h"

namespace gwnrt {

Status GwnModel::build(Mesh mesh, GwnModel& out, const BuildOptions& options) {
  if (Status s = validate_mesh(mesh); !s.ok()) return s;
  using clock = std::chrono::steady_clock;
  GwnModel model;
  model.mesh_ = std::move(mesh);
  auto t0 = clock::now();
  model.triangles_ = build_triangle_tree(model.mesh_, options.max_leaf_triangles);
  // The tree leaves zero-area triangles out; with none left there is nothing to evaluate.
  if (model.triangles_.triangle_ids.empty())
    return {StatusCode::kInvalidMesh, "mesh: all " + std::to_string(model.mesh_.triangles.size()) +
                                          " triangles have zero area (nothing to evaluate)"};
  auto t1 = clock::now();
  model.boundary_ = extract_boundary(model.mesh_);
  model.boundary_tree_ = build_segment_tree(model.boundary_.endpoints, options.max_leaf_segments);
  model.cone_ = build_triangle_tree(boundary_cone(model.boundary_), options.max_leaf_triangles);
  double area = 0;
  for (const uvec3& t : model.mesh_.triangles) {
    const dvec3 p0(model.mesh_.positions[t[0]]), p1(model.mesh_.positions[t[1]]), p2(model.mesh_.positions[t[2]]);
    area += 0.5 * glm::length(glm::cross(p1 - p0, p2 - p0));
    model.bounds_.extend(model.mesh_.positions[t[0]]);
    model.bounds_.extend(model.mesh_.positions[t[1]]);
    model.bounds_.extend(model.mesh_.positions[t[2]]);
  }
  // |w(x)| <= A / (4π d²) at distance d from the box, so beyond sqrt(A / 2π) no level w* + k
  // with |w*| <= 1/2 is reached; 1% more absorbs round-off.
  model.surface_margin_ = float(1.01 * std::sqrt(area / (2 * kPi)));
  auto t2 = clock::now();
  model.timings_.tree_seconds = std::chrono::duration<double>(t1 - t0).count();
  model.timings_.boundary_seconds = std::chrono::duration<double>(t2 - t1).count();
  out = std::move(model);
  return Status::Ok();
}

ModelView GwnModel::view() const {
  return {triangles_.view(), boundary_tree_.view(), cone_.view(), bounds_, surface_margin_};
}

}  // namespace gwnrt
