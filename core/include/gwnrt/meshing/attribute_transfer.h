// The source's attributes carried onto a mesh of S (docs/design.md §11, attributes): each output
// vertex takes its nearest source triangle and the barycentrics of the nearest point on it, and
// interpolates the source's colours and texture coordinates there. A texture has seams where
// neighbouring triangles map a shared edge to different places (UV charts, uv_charts below);
// an output face whose corners land in different charts would stretch its texture across the
// atlas, so such a face takes all its UVs from one source triangle (the one nearest its centre:
// the dominant primitive), and its corners from the other charts get vertices of their own.
//
// Per-item passes (GWNRT_HD) over trivially copyable views, as the rest of the mesher; the driver
// is core/src/meshing/attribute_transfer.cpp.
#pragma once

#include <cstdint>
#include <vector>

#include "gwnrt/base/status.h"
#include "gwnrt/field/distance.h"
#include "gwnrt/geometry/mesh.h"
#include "gwnrt/geometry/surface_mesh.h"
#include "gwnrt/geometry/triangle_tree.h"

namespace gwnrt {

// The source mesh's attributes, in input order (null where the source has none).
struct SourceAttributesView {
  const vec3* positions = nullptr;
  const uvec3* triangles = nullptr;
  const glm::vec2* uvs = nullptr;
  const uvec3* uv_triangles = nullptr;
  const uint32_t* charts = nullptr;  // per triangle: its UV chart (uv_charts)
  const glm::vec4* colors = nullptr;
};

// Per source triangle: the UV chart it belongs to, numbered from 0 in order of first triangle.
// Two triangles are in one chart when joined by a chain of edges that each give both sides the
// same positions and the same UVs at both ends (compared by value, so a soup's duplicated
// vertices and an OBJ's repeated vt do not cut charts). Empty when the mesh has no UVs.
std::vector<uint32_t> uv_charts(const Mesh& mesh);

// values[t] interpolated at barycentrics (u, v): (1 - u - v) a + u b + v c.
template <class T>
GWNRT_HD inline T interpolate_corners(const T* values, uvec3 t, float u, float v) {
  return (1.0f - u - v) * values[t.x] + u * values[t.y] + v * values[t.z];
}

// The barycentrics of x's projection onto the plane of (p0, p1, p2), not clamped to the
// triangle: interpolating with them extends the triangle's attributes affinely across its plane.
// False for a triangle without area.
GWNRT_HD inline bool plane_barycentrics(const vec3& p0, const vec3& p1, const vec3& p2, const vec3& x, float& u,
                                        float& v) {
  const dvec3 e1 = dvec3(p1) - dvec3(p0), e2 = dvec3(p2) - dvec3(p0), d = dvec3(x) - dvec3(p0);
  const double a = glm::dot(e1, e1), b = glm::dot(e1, e2), c = glm::dot(e2, e2);
  const double det = a * c - b * b;
  if (!(det > 1e-12 * a * c)) return false;
  const double r1 = glm::dot(d, e1), r2 = glm::dot(d, e2);
  u = float((c * r1 - b * r2) / det);
  v = float((a * r2 - b * r1) / det);
  return true;
}

// The UV that source triangle `t` gives the point x (its affine extension; the clamped nearest
// point's when t has no area).
GWNRT_HD inline glm::vec2 uv_from_triangle(const SourceAttributesView& src, uint32_t t, const vec3& x) {
  const uvec3 tri = src.triangles[t];
  float u = 0, v = 0;
  if (!plane_barycentrics(src.positions[tri.x], src.positions[tri.y], src.positions[tri.z], x, u, v)) {
    const ClosestPoint<float> c =
        closest_point_on_triangle(src.positions[tri.x], src.positions[tri.y], src.positions[tri.z], x);
    u = c.u;
    v = c.v;
  }
  return interpolate_corners(src.uvs, src.uv_triangles[t], u, v);
}

// Per output vertex: the nearest source triangle and barycentrics, and from them the colour and
// UV (outputs left null are not written).
struct VertexAttributePass {
  TriangleTreeView tree;
  SourceAttributesView src;
  const vec3* positions;
  uint32_t* source_triangle;
  glm::vec2* barycentrics;
  glm::vec4* colors;
  glm::vec2* uvs;

  GWNRT_HD void operator()(uint64_t i) const {
    const NearestPrimitive n = unsigned_distance(tree, positions[i]);
    source_triangle[i] = n.primitive;
    barycentrics[i] = {n.u, n.v};
    if (colors) colors[i] = interpolate_corners(src.colors, src.triangles[n.primitive], n.u, n.v);
    if (uvs) uvs[i] = interpolate_corners(src.uvs, src.uv_triangles[n.primitive], n.u, n.v);
  }
};

constexpr uint32_t kSingleChart = 0xffffffffu;

// Per output face: kSingleChart when its corners' source triangles lie in one UV chart, else the
// dominant primitive (the source triangle nearest the face's centre) its UVs come from.
struct FaceChartPass {
  TriangleTreeView tree;
  SourceAttributesView src;
  const vec3* positions;
  const uvec3* faces;
  const uint32_t* source_triangle;  // per output vertex
  uint32_t* dominant;

  GWNRT_HD void operator()(uint64_t f) const {
    const uvec3 t = faces[f];
    const uint32_t c0 = src.charts[source_triangle[t.x]];
    if (src.charts[source_triangle[t.y]] == c0 && src.charts[source_triangle[t.z]] == c0) {
      dominant[f] = kSingleChart;
      return;
    }
    const vec3 centre = (positions[t.x] + positions[t.y] + positions[t.z]) * (1.0f / 3.0f);
    dominant[f] = unsigned_distance(tree, centre).primitive;
  }
};

// Whether `source` has the attributes asked for (UVs, colours): the mesher checks before it starts.
Status check_attributes(const Mesh& source, uint32_t attributes);

// Carries the requested attributes (kAttributeSource | kAttributeUv | kAttributeColor of
// meshing/extract_surface.h) from `source` onto `out`, an indexed mesh of S, splitting vertices
// at UV seams. `tree` is the source's triangle tree (GwnModel::view().triangles).
Status transfer_attributes(const Mesh& source, const TriangleTreeView& tree, uint32_t attributes, SurfaceMesh& out);

}  // namespace gwnrt
