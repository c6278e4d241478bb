// The source's attributes on meshes of S (meshing/attribute_transfer.h): colours and UVs that are
// affine functions of position on the source, so that the value at each output vertex is known
// in closed form at its nearest point on the source; and a cube with six UV charts, whose seams
// no output face may straddle.
#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "gwnrt/meshing/attribute_transfer.h"
#include "gwnrt/meshing/extract_surface.h"
#include "gwnrt/meshing/mesh_quality.h"
#include "reference/exact_distance.h"
#include "test_util.h"

namespace gwnrt {
namespace {

const dvec3 kShift(0.0123, 0.0456, 0.0789);  // keeps the cube's faces off the grid's planes

Mesh shifted_cube() {
  Mesh m = test::make_cube();
  for (vec3& p : m.positions) p = vec3(dvec3(p) + kShift);
  return m;
}

SurfaceMesh mesh_of(const Mesh& source, uint32_t resolution, uint32_t attributes, bool soup = false) {
  const GwnModel model = test::build_model(source);
  MeshingOptions o;
  o.resolution = resolution;
  o.attributes = attributes;
  o.soup = soup;
  SurfaceMesh out;
  const Status s = extract_surface(model, o, out);
  EXPECT_TRUE(s.ok()) << s.message();
  return out;
}

// The six faces of the cube [-1, 1]³ (before the shift): the axis and side of each face's
// normal, and the face's two in-plane axes.
struct CubeFace {
  int axis;
  float side;
  int s, t;
};
constexpr CubeFace kCubeFaces[6] = {{0, -1, 1, 2}, {0, 1, 1, 2},  {1, -1, 0, 2},
                                    {1, 1, 0, 2},  {2, -1, 0, 1}, {2, 1, 0, 1}};

// Chart k's map of a point of face k into its own strip of the atlas, u ∈ k/6 + [0.1, 0.9]/6,
// v ∈ [0.1, 0.9]: affine in position, and far enough from the other strips that the chart of a
// UV is floor(6u) even a few cells outside the face.
glm::vec2 chart_uv(int k, const dvec3& p) {
  const dvec3 q = p - kShift;
  const double s = (q[kCubeFaces[k].s] + 1) / 2, t = (q[kCubeFaces[k].t] + 1) / 2;
  return glm::vec2(float((k + 0.1 + 0.8 * s) / 6), float(0.1 + 0.8 * t));
}

// The cube with each face its own chart: 24 texture coordinates, indexed per corner.
Mesh six_chart_cube() {
  Mesh m = shifted_cube();
  m.uv_triangles.resize(m.triangles.size());
  for (size_t t = 0; t < m.triangles.size(); ++t) {
    const uvec3 tri = m.triangles[t];
    const dvec3 centre =
        (dvec3(m.positions[tri.x]) + dvec3(m.positions[tri.y]) + dvec3(m.positions[tri.z])) / 3.0 - kShift;
    int face = 0;
    for (int k = 0; k < 6; ++k)
      if (std::abs(centre[kCubeFaces[k].axis] - kCubeFaces[k].side) < 1e-6) face = k;
    for (int c = 0; c < 3; ++c) {
      m.uv_triangles[t][c] = uint32_t(m.uvs.size());
      m.uvs.push_back(chart_uv(face, dvec3(m.positions[tri[c]])));
    }
  }
  return m;
}

int chart_of(const glm::vec2& uv) { return int(std::floor(uv.x * 6)); }

TEST(MeshAttributes, ChartsJoinAcrossEdgesWithEqualUvs) {
  const Mesh six = six_chart_cube();
  const std::vector<uint32_t> charts = uv_charts(six);
  ASSERT_EQ(charts.size(), six.triangles.size());
  // Each face's two triangles share a chart; the six faces' charts differ.
  std::map<int, uint32_t> chart_of_face;
  for (size_t t = 0; t < six.triangles.size(); ++t) {
    const int face = chart_of(six.uvs[six.uv_triangles[t].x]);
    if (!chart_of_face.count(face)) chart_of_face[face] = charts[t];
    EXPECT_EQ(charts[t], chart_of_face[face]) << "triangle " << t;
  }
  ASSERT_EQ(chart_of_face.size(), 6u);
  std::map<uint32_t, int> distinct;
  for (const auto& [face, chart] : chart_of_face) distinct[chart] = face;
  EXPECT_EQ(distinct.size(), 6u);

  // One UV per vertex (a planar projection): no seam, one chart; the same as a soup, whose
  // triangles share no vertex index but the same positions and UVs.
  Mesh planar = shifted_cube();
  planar.uv_triangles = planar.triangles;
  for (const vec3& p : planar.positions) planar.uvs.push_back({p.x, p.y});
  for (uint32_t c : uv_charts(planar)) EXPECT_EQ(c, 0u);
  Mesh soup;
  for (const uvec3& t : planar.triangles) {
    const uint32_t base = uint32_t(soup.positions.size());
    for (int k = 0; k < 3; ++k) {
      soup.positions.push_back(planar.positions[t[k]]);
      soup.uvs.push_back(planar.uvs[t[k]]);
    }
    soup.triangles.push_back({base, base + 1, base + 2});
  }
  soup.uv_triangles = soup.triangles;
  for (uint32_t c : uv_charts(soup)) EXPECT_EQ(c, 0u);
}

// UV = (x, y) on every face of the cube (a plane's projection map; one chart): each output
// vertex's UV is the map at its nearest point q on the source, and |q − p| bounds how far that is
// from the map at the vertex p itself.
TEST(MeshAttributes, PlanarUvsAreTheMapAtTheNearestPoint) {
  Mesh source = shifted_cube();
  source.uv_triangles = source.triangles;
  for (const vec3& p : source.positions) source.uvs.push_back({p.x, p.y});
  const SurfaceMesh out = mesh_of(source, 24, kAttributeUv);
  const SurfaceMesh plain = mesh_of(source, 24, 0);
  ASSERT_EQ(out.uvs.size(), out.positions.size());
  EXPECT_EQ(out.positions.size(), plain.positions.size()) << "one chart: no vertex is split";
  EXPECT_TRUE(out.source_triangles.empty()) << "only what was asked for";
  for (size_t i = 0; i < out.positions.size(); ++i) {
    const dvec3 p(out.positions[i]);
    const double d = reference::mesh_distance(source, p);
    EXPECT_LE(glm::length(dvec3(out.uvs[i].x, out.uvs[i].y, 0) - dvec3(p.x, p.y, 0)), d + 1e-5) << "vertex " << i;
  }
}

// Colour = an affine function of position on an icosphere: the interpolated colour is that
// function at the nearest point, within half the distance to it (the map's gain is 1/2).
TEST(MeshAttributes, VertexColoursAreTheFunctionAtTheNearestPoint) {
  Mesh source = test::make_sphere(3);
  const auto colour = [](const dvec3& p) { return glm::dvec4(0.5 + 0.5 * p.x, 0.5 + 0.5 * p.y, 0.5 - 0.5 * p.z, 1); };
  for (const vec3& p : source.positions) source.colors.push_back(glm::vec4(colour(dvec3(p))));
  const SurfaceMesh out = mesh_of(source, 32, kAttributeColor | kAttributeSource);
  ASSERT_EQ(out.colors.size(), out.positions.size());
  ASSERT_EQ(out.source_triangles.size(), out.positions.size());
  for (size_t i = 0; i < out.positions.size(); ++i) {
    const dvec3 p(out.positions[i]);
    const double d = reference::mesh_distance(source, p);
    EXPECT_LE(glm::length(glm::dvec4(out.colors[i]) - colour(p)), 0.5 * d + 1e-5) << "vertex " << i;
    EXPECT_NEAR(out.colors[i].a, 1.0f, 1e-6f);
  }
}

// Six charts: no output face takes UVs from two charts; each corner's UV is its face's chart map
// at the corner; seam vertices are split, and welding them back gives the closed mesh.
TEST(MeshAttributes, SixChartCubeHasNoFaceAcrossASeam) {
  const Mesh source = six_chart_cube();
  const SurfaceMesh out = mesh_of(source, 24, kAttributeUv);
  const SurfaceMesh plain = mesh_of(source, 24, 0);
  ASSERT_EQ(out.uvs.size(), out.positions.size());
  ASSERT_EQ(out.triangles.size(), plain.triangles.size());
  EXPECT_GT(out.positions.size(), plain.positions.size()) << "the seams split vertices";
  size_t across = 0;
  for (size_t f = 0; f < out.triangles.size(); ++f) {
    const uvec3 t = out.triangles[f];
    const int chart = chart_of(out.uvs[t.x]);
    ASSERT_GE(chart, 0);
    ASSERT_LT(chart, 6);
    if (chart_of(out.uvs[t.y]) != chart || chart_of(out.uvs[t.z]) != chart) {
      ++across;
      continue;
    }
    // The chart's map at the corner's projection onto the chart's face: exact for a corner that
    // projects into the face; one beyond the face's edge took the map at the edge's nearest point
    // (its own nearest point on the source) or its affine extension (a split corner), which
    // differ by at most the map's gain (0.4 per unit) times the distance beyond the edge.
    const CubeFace& face = kCubeFaces[chart];
    for (int k = 0; k < 3; ++k) {
      dvec3 p = dvec3(out.positions[t[k]]) - kShift;
      p[face.axis] = face.side;
      const double beyond =
          glm::length(glm::dvec2(std::max(std::abs(p[face.s]) - 1, 0.0), std::max(std::abs(p[face.t]) - 1, 0.0)));
      const glm::vec2 expected = chart_uv(chart, p + kShift);
      EXPECT_LE(glm::length(dvec3(out.uvs[t[k]] - expected, 0)), 0.4 * beyond + 1e-5)
          << "face " << f << " corner " << k;
    }
  }
  EXPECT_EQ(across, 0u) << "faces whose corners take UVs from two charts";
  // The same faces as without UVs, and closed once the seams' copies are welded.
  for (size_t f = 0; f < out.triangles.size(); ++f)
    for (int k = 0; k < 3; ++k)
      ASSERT_EQ(out.positions[out.triangles[f][k]], plain.positions[plain.triangles[f][k]]) << "face " << f;
  MeshTopology topology;
  ASSERT_TRUE(mesh_topology(out, topology).ok());
  EXPECT_EQ(topology.unreferenced_vertices, 0u);
  ASSERT_TRUE(mesh_topology(out, topology, /*weld_equal_positions=*/true).ok());
  EXPECT_EQ(topology.boundary_edges, 0u);
  EXPECT_EQ(topology.non_manifold_edges, 0u);
  EXPECT_EQ(topology.inconsistent_edges, 0u);

  // As a soup: each face's corners carry the same UVs as the indexed mesh's.
  const SurfaceMesh soup = mesh_of(source, 24, kAttributeUv, true);
  ASSERT_EQ(soup.uvs.size(), 3 * out.triangles.size());
  for (size_t f = 0; f < out.triangles.size(); ++f)
    for (int k = 0; k < 3; ++k) ASSERT_EQ(soup.uvs[3 * f + k], out.uvs[out.triangles[f][k]]) << "face " << f;
}

TEST(MeshAttributes, MissingAttributesAreRefused) {
  const GwnModel model = test::build_model(test::make_cube());
  MeshingOptions o;
  o.resolution = 16;
  SurfaceMesh out;
  o.attributes = kAttributeUv;
  Status s = extract_surface(model, o, out);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("texture coordinates"), std::string::npos) << s.message();
  o.attributes = kAttributeColor;
  s = extract_surface(model, o, out);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("colours"), std::string::npos) << s.message();
  o.attributes = 1u << 7;
  EXPECT_FALSE(extract_surface(model, o, out).ok());
}

}  // namespace
}  // namespace gwnrt
