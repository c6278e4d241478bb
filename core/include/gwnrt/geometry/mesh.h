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

  // Optional surface attributes, kept by the readers when the file has them and carried onto
  // meshes of S (meshing/); w ignores them. Texture coordinates are indexed per triangle corner,
  // apart from the positions, as OBJ's vt are: where two triangles sharing an edge give it
  // different UVs the texture has a seam (meshing/attribute_transfer.h).
  std::vector<glm::vec2> uvs;
  std::vector<uvec3> uv_triangles;  // empty, or one per triangle: its corners' indices into uvs
  std::vector<glm::vec4> colors;    // empty, or one per vertex: RGBA in [0, 1]
};

// The checks load_mesh makes, for a mesh built in memory (coordinates finite, indices in range, not
// empty; attributes finite, of the right lengths and with indices in range).
// `source` names the mesh in messages.
Status validate_mesh(const Mesh& mesh, const std::string& source = "mesh");

// Zero-area test used everywhere a triangle is classified as degenerate (exact, in double).
bool is_degenerate_triangle(const vec3& a, const vec3& b, const vec3& c);

}  // namespace gwnrt
