// Triangle meshes: the owning container and its checks (core/src/geometry/mesh.cpp). Loading
// from files is gwnrt/io/mesh_io.h.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "gwnrt/base/hd.h"
#include "gwnrt/base/status.h"

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

// The scales gwnrt serves (GwnModel::build refuses others, saying so; docs/design.md §1). Every
// query is in float: products of three or four lengths (van Oosterom's denominator, the
// point-triangle distance) overflow or fall into denormals outside this range: the coordinates of
// the triangles' corners lie within +-kMaxMeshCoordinate, and their box is at least kMinMeshExtent
// across along its longest side and, along its diagonal, kMinMeshExtentPerCoordinate of its largest
// coordinate.
inline constexpr float kMaxMeshCoordinate = 1e8f;
inline constexpr float kMinMeshExtent = 1e-8f;
// Far from the origin float resolves a mesh coarsely: a point's coordinates round to a step of
// 1.2e-7 of their magnitude, and the sheets' probe step (2e-6 of the coordinates) must stay
// within the mesh. The box's diagonal must be at least this fraction of its largest coordinate
// (about 840 float steps across the box, with a margin over the smallest that is still right).
inline constexpr float kMinMeshExtentPerCoordinate = 1e-4f;
Status check_mesh_scale(const Mesh& mesh);

// Zero-area test used everywhere a triangle is classified as degenerate (exact, in double).
bool is_degenerate_triangle(const vec3& a, const vec3& b, const vec3& c);

}  // namespace gwnrt
