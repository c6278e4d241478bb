// The README's "Using the library" example as a whole program: load a mesh, build the model,
// query w and ∇w at two points, trace one ray onto S. CI builds it in the tree and against the
// installed package (tests/downstream).
#include <cstdio>
#include <vector>

#include "gwnrt/io/mesh_io.h"
#include "gwnrt/query/batch.h"

int main(int argc, char** argv) {
  const char* path = argc > 1 ? argv[1] : "bunny.obj";
  // [readme-library-begin]
  gwnrt::Mesh mesh;
  if (gwnrt::Status s = gwnrt::load_mesh(path, mesh); !s.ok()) {
    std::fprintf(stderr, "%s\n", s.message().c_str());  // names the file and the line
    return 1;
  }
  gwnrt::GwnModel model;
  if (gwnrt::Status s = gwnrt::GwnModel::build(std::move(mesh), model); !s.ok()) {
    std::fprintf(stderr, "%s\n", s.message().c_str());
    return 1;
  }

  // Bulk queries: w and ∇w by QueryRequest's default method, auto (here exact by crossings).
  const std::vector<gwnrt::vec3> points = {model.bounds().centre(), model.bounds().hi * 2.0f};
  gwnrt::QueryRequest request;
  request.fields = gwnrt::kFieldW | gwnrt::kFieldGradient;
  std::vector<gwnrt::PointResult> results(points.size());
  if (gwnrt::Status s = gwnrt::evaluate_points(model, points, request, results); !s.ok()) {
    std::fprintf(stderr, "%s\n", s.message().c_str());
    return 1;
  }

  // Rays onto S = ∂{w > 1/2} (TraceOptions: level, mode, epsilon, caps).
  gwnrt::Ray ray;
  ray.origin = model.bounds().lo - 1.0f;
  ray.direction = model.bounds().centre() - ray.origin;
  const std::vector<gwnrt::Ray> rays = {ray};
  std::vector<gwnrt::RayHit> hits(rays.size());
  if (gwnrt::Status s = gwnrt::trace_rays(model, rays, gwnrt::TraceOptions{}, hits); !s.ok()) {
    std::fprintf(stderr, "%s\n", s.message().c_str());
    return 1;
  }
  // Per ray on the host or inside a CUDA kernel: gwnrt::trace_surface(model.view(), ray, options).
  // [readme-library-end]

  std::printf("w at the box centre %.6f, far away %.6f; ray %s S at t = %.6f\n", results[0].w, results[1].w,
              hits[0].hit ? "hits" : "misses", hits[0].t);
  return 0;
}
