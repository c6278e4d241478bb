// Checks of a mesh in memory (gwnrt/geometry/mesh.h).
#include "gwnrt/geometry/mesh.h"

#include "message.h"

namespace gwnrt {

bool is_degenerate_triangle(const vec3& a, const vec3& b, const vec3& c) {
  const dvec3 n = glm::cross(dvec3(b) - dvec3(a), dvec3(c) - dvec3(a));
  return n.x == 0.0 && n.y == 0.0 && n.z == 0.0;
}

Status validate_mesh(const Mesh& mesh, const std::string& source) {
  const std::vector<vec3>& pos = mesh.positions;
  for (size_t i = 0; i < pos.size(); ++i) {
    const vec3& p = pos[i];
    if (!is_finite(p.x) || !is_finite(p.y) || !is_finite(p.z)) {
      return {StatusCode::kInvalidMesh,
              cat(source, ": vertex ", i, " has a non-finite coordinate (", p.x, ", ", p.y, ", ", p.z, ")")};
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
  return Status::Ok();
}

}  // namespace gwnrt
