// Triangle meshes: the owning container, loading from OBJ/PLY, and the load report.
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

// What loading found, for the user to read; none of it is an error.
struct MeshLoadReport {
  std::size_t vertex_count = 0;
  std::size_t triangle_count = 0;         // after fanning polygons
  std::size_t polygons_fanned = 0;        // input faces with more than three corners
  std::size_t degenerate_triangles = 0;   // zero area (repeated or collinear corners): contribute nothing
  std::string format;                     // "obj", "ply-ascii", "ply-binary-le", "ply-binary-be"
};

// Loads an OBJ or PLY file (chosen by the extension, case-insensitive). Polygons are fanned
// into triangles. Fails, naming the file and the line or element, on malformed content,
// non-finite coordinates, out-of-range indices and meshes without triangles.
Status load_mesh(const std::string& path, Mesh& mesh, MeshLoadReport* report = nullptr);

// Same checks for a mesh built in memory (coordinates finite, indices in range, not empty).
// `source` names the mesh in messages.
Status validate_mesh(const Mesh& mesh, const std::string& source = "mesh");

// Zero-area test used everywhere a triangle is classified as degenerate (exact, in double).
bool is_degenerate_triangle(const vec3& a, const vec3& b, const vec3& c);

}  // namespace gwnrt
