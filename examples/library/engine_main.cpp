// CPU or GPU from an application, chosen once: an Engine holds the model and runs each batch where
// it is asked (auto: the GPU when this build has the CUDA backend and a GPU is usable, else the
// CPU). CI builds it against the installed package (tests/downstream).
#include <cstdio>
#include <string>
#include <vector>

#include "gwnrt/engine.h"
#include "gwnrt/io/mesh_io.h"

int main(int argc, char** argv) {
  const char* path = argc > 1 ? argv[1] : "bunny.obj";
  gwnrt::Mesh mesh;
  gwnrt::GwnModel model;
  if (gwnrt::Status s = gwnrt::load_mesh(path, mesh); !s.ok())
    return std::fprintf(stderr, "%s\n", s.message().c_str()), 1;
  if (gwnrt::Status s = gwnrt::GwnModel::build(std::move(mesh), model); !s.ok())
    return std::fprintf(stderr, "%s\n", s.message().c_str()), 1;
  const gwnrt::Engine engine(std::move(model));

  gwnrt::DeviceChoice where;
  if (gwnrt::Status s = gwnrt::choose_device(gwnrt::Device::kAuto, where); !s.ok())
    return std::fprintf(stderr, "%s\n", s.message().c_str()), 1;
  if (!where.reason.empty()) std::printf("on the CPU: %s\n", where.reason.c_str());

  const std::vector<gwnrt::vec3> points = {engine.model().bounds().centre()};
  std::vector<gwnrt::PointResult> results(points.size());
  if (gwnrt::Status s = engine.evaluate_points(where.device, points, gwnrt::QueryRequest{}, results); !s.ok())
    return std::fprintf(stderr, "%s\n", s.message().c_str()), 1;
  std::printf("w at the box centre on the %s: %.6f\n", gwnrt::device_name(where.device), results[0].w);
  return 0;
}
