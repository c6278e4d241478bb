// Checks of a mesh in memory (gwnrt/geometry/mesh.h).
#include "gwnrt/geometry/mesh.h"

#include "message.h"

namespace gwnrt {

bool is_degenerate_triangle(const vec3& a, const vec3& b, const vec3& c) {
  const dvec3 n = glm::cross(dvec3(b) - dvec3(a), dvec3(c) - dvec3(a));
  return n.x == 0.0 && n.y == 0.0 && n.z == 0.0;
}

namespace {

Status validate_attributes(const Mesh& mesh, const std::string& source) {
  if (!mesh.uv_triangles.empty() && mesh.uv_triangles.size() != mesh.triangles.size()) {
    return {StatusCode::kInvalidMesh, cat(source, ": ", mesh.uv_triangles.size(), " UV triangles for ",
                                          mesh.triangles.size(), " triangles (need one per triangle, or none)")};
  }
  if (mesh.uv_triangles.empty() && !mesh.uvs.empty()) {
    return {StatusCode::kInvalidMesh, cat(source, ": ", mesh.uvs.size(), " UVs but no UV triangles to index them")};
  }
  for (size_t i = 0; i < mesh.uvs.size(); ++i) {
    const glm::vec2& t = mesh.uvs[i];
    if (!is_finite(t.x) || !is_finite(t.y)) {
      return {StatusCode::kInvalidMesh,
              cat(source, ": texture coordinate ", i, " is not finite (", t.x, ", ", t.y, ")")};
    }
  }
  for (size_t t = 0; t < mesh.uv_triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = mesh.uv_triangles[t][k];
      if (v >= mesh.uvs.size()) {
        return {StatusCode::kInvalidMesh,
                cat(source, ": triangle ", t, " refers to texture coordinate ", v, " but there are ", mesh.uvs.size())};
      }
    }
  }
  if (!mesh.colors.empty() && mesh.colors.size() != mesh.positions.size()) {
    return {StatusCode::kInvalidMesh, cat(source, ": ", mesh.colors.size(), " vertex colours for ",
                                          mesh.positions.size(), " vertices (need one per vertex, or none)")};
  }
  for (size_t i = 0; i < mesh.colors.size(); ++i) {
    const glm::vec4& c = mesh.colors[i];
    if (!is_finite(c.r) || !is_finite(c.g) || !is_finite(c.b) || !is_finite(c.a)) {
      return {StatusCode::kInvalidMesh,
              cat(source, ": vertex ", i, " has a non-finite colour (", c.r, ", ", c.g, ", ", c.b, ", ", c.a, ")")};
    }
  }
  return Status::Ok();
}

}  // namespace

Status validate_mesh(const Mesh& mesh, const std::string& source) {
  const std::vector<vec3>& pos = mesh.positions;
  for (size_t i = 0; i < pos.size(); ++i) {
    const vec3& p = pos[i];
    if (!is_finite(p.x) || !is_finite(p.y) || !is_finite(p.z)) {
      return {StatusCode::kInvalidMesh, cat(source, ": vertex ", i, " ", non_finite_coordinate(p.x, p.y, p.z))};
    }
  }
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = mesh.triangles[t][k];
      if (v >= pos.size()) {
        return {StatusCode::kInvalidMesh,
                cat(source, ": triangle ", t, " refers to vertex ", v, " but there are ", pos.size(), " vertices")};
      }
    }
  }
  if (mesh.triangles.empty()) return {StatusCode::kInvalidMesh, cat(source, ": the mesh has no triangles")};
  return validate_attributes(mesh, source);
}

}  // namespace gwnrt
