// Checks of a mesh in memory, and of the scales gwnrt serves (gwnrt/geometry/mesh.h).
#include "gwnrt/geometry/mesh.h"

#include <algorithm>
#include <cmath>

#include "base/message.h"
#include "gwnrt/geometry/bvh.h"

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

Status check_mesh_scale(const Mesh& mesh) {
  float largest = 0.0f;
  size_t largest_vertex = 0;
  Aabb box;
  for (const uvec3& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const vec3& p = mesh.positions[t[k]];
      box.extend(p);
      const float m = std::max({std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)});
      if (m > largest) {
        largest = m;
        largest_vertex = t[k];
      }
    }
  const vec3 extent = box.hi - box.lo;
  const float across = std::max({extent.x, extent.y, extent.z});
  const std::string range = cat("gwnrt computes in float and serves meshes whose coordinates lie within +-",
                                kMaxMeshCoordinate, " and whose box is at least ", kMinMeshExtent, " across");
  if (largest > kMaxMeshCoordinate)
    return {StatusCode::kInvalidMesh,
            cat("mesh: vertex ", largest_vertex, " (counting from 0) has a coordinate of magnitude ", largest, "; ",
                range, ": scale the mesh down")};
  const double diagonal = glm::length(dvec3(extent));  // in double: squares of tiny extents underflow in float
  if (!mesh.triangles.empty() && diagonal < double(kMinMeshExtentPerCoordinate) * largest)
    return {StatusCode::kInvalidMesh,
            cat("mesh: its box is ", float(diagonal), " across (diagonal) at ", largest, " from the origin (vertex ",
                largest_vertex, ", counting from 0), where float coordinates step by ",
                std::nextafter(largest, kMaxMeshCoordinate * 2.0f) - largest,
                "; gwnrt computes in float and needs the box's diagonal to be at least ", kMinMeshExtentPerCoordinate,
                " of its largest coordinate: translate the mesh near the origin",
                across < kMinMeshExtent ? cat(" (and scale it up: its box is below ", kMinMeshExtent, " across)")
                                        : std::string())};
  if (!mesh.triangles.empty() && across < kMinMeshExtent)
    return {StatusCode::kInvalidMesh, cat("mesh: its box is ", across, " across; ", range, ": scale the mesh up")};
  return Status::Ok();
}

}  // namespace gwnrt
