#include <chrono>
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
  auto t2 = clock::now();
  model.timings_.tree_seconds = std::chrono::duration<double>(t1 - t0).count();
  model.timings_.boundary_seconds = std::chrono::duration<double>(t2 - t1).count();
  out = std::move(model);
  return Status::Ok();
}

}  // namespace gwnrt
