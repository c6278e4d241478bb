// SurfaceMesh: what the mesher of S produces (meshing/extract_surface.h) and the writers
// (io/mesh_writer.h) and the quality report (meshing/mesh_quality.h) consume. Indexed by
// default; a triangle soup has three vertices of its own per triangle. Per-vertex arrays are
// either empty or as long as `positions`.
#pragma once

#include <cstdint>
#include <vector>

#include "gwnrt/base/hd.h"

namespace gwnrt {

struct SurfaceMesh {
  std::vector<vec3> positions;
  std::vector<vec3> normals;     // unit, outward (pointing out of {w > w*})
  std::vector<uvec3> triangles;  // counter-clockwise seen from outside
  // The nearest source triangle (input index) and the barycentrics (u, v) of the nearest point
  // on it: point = (1 - u - v) p0 + u p1 + v p2.
  std::vector<uint32_t> source_triangles;
  std::vector<glm::vec2> source_barycentrics;
  std::vector<glm::vec2> uvs;     // carried from the source's texture coordinates
  std::vector<glm::vec4> colors;  // carried from the source's vertex colours, RGBA in [0, 1]
};

// fn(array) for each per-vertex array of m, for the code that treats them alike (soup expansion,
// vertex splitting and removal); a new per-vertex array is added here.
template <class M, class Fn>
void for_each_vertex_array(M& m, Fn&& fn) {
  fn(m.positions);
  fn(m.normals);
  fn(m.source_triangles);
  fn(m.source_barycentrics);
  fn(m.uvs);
  fn(m.colors);
}

}  // namespace gwnrt
