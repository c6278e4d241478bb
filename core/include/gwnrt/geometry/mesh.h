// Triangle meshes: the owning container and its checks (core/src/geometry/mesh.cpp). Loading
// from files is gwnrt/io/mesh_io.h.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "gwnrt/hd.h"
#include "gwnrt/status.h"

namespace gwnrt {

struct Mesh {
  std::vector<vec3> positions;
  std::vector<uvec3> triangles;  // oriented: (a, b, c) counter-clockwise seen from the outside
};

// The checks load_mesh makes, for a mesh built in memory (coordinates finite, indices in range, not empty).
// `source` names the mesh in messages.
Status validate_mesh(const Mesh& mesh, const std::string& source = "mesh");

// Zero-area test used everywhere a triangle is classified as degenerate (exact, in double).
bool is_degenerate_triangle(const vec3& a, const vec3& b, const vec3& c);

}  // namespace gwnrt
