// Loading meshes from OBJ and PLY files (core/src/io/), and what loading found.
#pragma once

#include <cstddef>
#include <string>

#include "gwnrt/geometry/mesh.h"
#include "gwnrt/status.h"

namespace gwnrt {

// What loading found, for the user to read; none of it is an error.
struct MeshLoadReport {
  std::size_t vertex_count = 0;
  std::size_t triangle_count = 0;        // after fanning polygons
  std::size_t polygons_fanned = 0;       // input faces with more than three corners
  std::size_t degenerate_triangles = 0;  // zero area (repeated or collinear corners): contribute nothing
  std::string format;                    // "obj", "ply-ascii", "ply-binary-le", "ply-binary-be"
  std::size_t uv_count = 0;              // texture coordinates kept (Mesh::uvs)
  bool has_colors = false;               // vertex colours kept (Mesh::colors)
  // Empty, or why UVs or colours in the file were not kept (e.g. only some faces have them).
  std::string attributes_dropped;
  // Empty, or what was skipped that the user may not expect (OBJ lines with unknown statements).
  std::string warnings;
};

// Loads an OBJ or PLY file (chosen by the extension, case-insensitive). Polygons are fanned
// into triangles. Texture coordinates (OBJ vt; PLY u v, s t, texture_u texture_v, texture_s
// texture_t per vertex, or a face texcoord list) and vertex colours (OBJ v x y z r g b; PLY red
// green blue [alpha], integers scaled to [0, 1]) are kept when every face or vertex has them. Fails, naming the file
// and the line or element, on malformed content, non-finite coordinates, out-of-range indices and meshes without
// triangles; and, as it reads, on a text line longer than kMaxMeshLineBytes (the header of a binary PLY included) or
// more bytes than the memory available (gwnrt/io/read_file.h): /dev/zero stops there.
Status load_mesh(const std::string& path, Mesh& mesh, MeshLoadReport* report = nullptr);

}  // namespace gwnrt
