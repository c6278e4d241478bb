// The CUDA backend from an application: upload a model and query it on the GPU, or say why no GPU
// can be used. CI builds it against the installed package (tests/downstream) where gwnrt::cuda is.
#include <cstdio>
#include <string>
#include <vector>

#include "gwnrt/cuda.h"
#include "gwnrt/io/mesh_io.h"

int main(int argc, char** argv) {
  const char* path = argc > 1 ? argv[1] : "bunny.obj";
  gwnrt::Mesh mesh;
  gwnrt::GwnModel model;
  if (gwnrt::Status s = gwnrt::load_mesh(path, mesh); !s.ok())
    return std::fprintf(stderr, "%s\n", s.message().c_str()), 1;
  if (gwnrt::Status s = gwnrt::GwnModel::build(std::move(mesh), model); !s.ok())
    return std::fprintf(stderr, "%s\n", s.message().c_str()), 1;
  std::string why;
  if (!gwnrt::cuda::device_available(&why)) {
    std::printf("no CUDA device: %s\n", why.c_str());
    return 0;
  }
  gwnrt::cuda::DeviceModel device_model;
  if (gwnrt::Status s = gwnrt::cuda::DeviceModel::upload(model, device_model); !s.ok())
    return std::fprintf(stderr, "%s\n", s.message().c_str()), 1;
  const std::vector<gwnrt::vec3> points = {model.bounds().centre()};
  std::vector<gwnrt::PointResult> results(points.size());
  if (gwnrt::Status s = gwnrt::cuda::evaluate_points(device_model, points, gwnrt::QueryRequest{}, results); !s.ok())
    return std::fprintf(stderr, "%s\n", s.message().c_str()), 1;
  std::printf("w at the box centre on the GPU: %.6f\n", results[0].w);
  return 0;
}
