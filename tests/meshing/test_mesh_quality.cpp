// The mesh quality report (gwnrt/meshing/mesh_quality.h): topology and self-intersections on
// meshes whose answers are known by construction, and the distances to S where S is the mesh
// itself.
#include "gwnrt/meshing/mesh_quality.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "gwnrt/geometry/exact_predicates.h"
#include "test_util.h"

namespace gwnrt {
namespace {

SurfaceMesh to_surface(const Mesh& m) {
  SurfaceMesh s;
  s.positions = m.positions;
  s.triangles = m.triangles;
  return s;
}

// The unit corner tetrahedron, outward.
SurfaceMesh tetrahedron() {
  SurfaceMesh s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  s.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return s;
}

// Three own vertices per triangle.
SurfaceMesh to_soup(const SurfaceMesh& m) {
  SurfaceMesh s;
  for (const uvec3& t : m.triangles) {
    const uint32_t base = uint32_t(s.positions.size());
    for (int k = 0; k < 3; ++k) s.positions.push_back(m.positions[t[k]]);
    s.triangles.push_back({base, base + 1, base + 2});
  }
  return s;
}

MeshTopology topology(const SurfaceMesh& m, bool weld = false) {
  MeshTopology t;
  const Status s = mesh_topology(m, t, weld);
  EXPECT_TRUE(s.ok()) << s.message();
  return t;
}

uint64_t intersections(const SurfaceMesh& m, std::vector<glm::uvec2>* pairs = nullptr) {
  uint64_t n = ~uint64_t(0);
  const Status s = count_self_intersections(m, n, pairs);
  EXPECT_TRUE(s.ok()) << s.message();
  return n;
}

// Two triangles as a mesh of their own.
SurfaceMesh pair_mesh(const exact::Triangle& p, const exact::Triangle& q) {
  SurfaceMesh s;
  s.positions = {p[0], p[1], p[2], q[0], q[1], q[2]};
  s.triangles = {{0, 1, 2}, {3, 4, 5}};
  return s;
}

// ---------------------------------------------------------------------------------------------
// Topology

TEST(MeshQualityTopology, ClosedMeshesAreClosedManifolds) {
  const SurfaceMesh meshes[] = {tetrahedron(), to_surface(test::make_cube()), to_surface(test::make_sphere(3))};
  for (const SurfaceMesh& m : meshes) {
    const MeshTopology t = topology(m);
    EXPECT_TRUE(t.closed_manifold());
    EXPECT_EQ(t.components, 1u);
    EXPECT_EQ(t.vertices, m.positions.size());
    EXPECT_EQ(t.triangles, m.triangles.size());
    EXPECT_EQ(t.unreferenced_vertices, 0u);
    EXPECT_EQ(intersections(m), 0u);
  }
}

TEST(MeshQualityTopology, RemovedTriangleLeavesThreeBoundaryEdges) {
  SurfaceMesh cube = to_surface(test::make_cube());
  cube.triangles.pop_back();
  const MeshTopology t = topology(cube);
  EXPECT_EQ(t.boundary_edges, 3u);
  EXPECT_EQ(t.non_manifold_edges, 0u);
  EXPECT_EQ(t.non_manifold_vertices, 0u);
  EXPECT_EQ(t.inconsistent_edges, 0u);
  EXPECT_EQ(t.components, 1u);
  EXPECT_FALSE(t.closed_manifold());
}

TEST(MeshQualityTopology, FlippedTriangleHasThreeInconsistentEdges) {
  SurfaceMesh cube = to_surface(test::make_cube());
  std::swap(cube.triangles[4][1], cube.triangles[4][2]);
  const MeshTopology t = topology(cube);
  EXPECT_EQ(t.inconsistent_edges, 3u);
  EXPECT_EQ(t.boundary_edges, 0u);
  EXPECT_FALSE(t.closed_manifold());
  EXPECT_EQ(intersections(cube), 0u);  // orientation is no intersection
}

TEST(MeshQualityTopology, CubesSharingOneVertexMakeItNonManifold) {
  // A second cube moved by (2, 2, 2): its corner (-1, -1, -1) lands on the first's (1, 1, 1),
  // vertex 6, and is given that index.
  const Mesh a = test::make_cube();
  SurfaceMesh m = to_surface(a);
  for (size_t i = 1; i < a.positions.size(); ++i) m.positions.push_back(a.positions[i] + vec3(2.0f));
  auto remap = [](uint32_t v) { return v == 0 ? 6u : v + 7u; };
  for (const uvec3& t : a.triangles) m.triangles.push_back({remap(t[0]), remap(t[1]), remap(t[2])});
  const MeshTopology t = topology(m);
  EXPECT_EQ(t.non_manifold_vertices, 1u);
  EXPECT_EQ(t.components, 2u);
  EXPECT_EQ(t.boundary_edges, 0u);
  EXPECT_EQ(t.non_manifold_edges, 0u);
  EXPECT_EQ(t.vertices, 15u);
  EXPECT_FALSE(t.closed_manifold());
  EXPECT_EQ(intersections(m), 0u);  // touching in the shared vertex only
  // Welded, the same vertex from two indices: the same topology.
  SurfaceMesh split = m;
  split.positions.push_back(split.positions[6]);
  for (size_t k = 12; k < split.triangles.size(); ++k)
    for (int c = 0; c < 3; ++c)
      if (split.triangles[k][c] == 6) split.triangles[k][c] = 15;
  EXPECT_EQ(topology(split).non_manifold_vertices, 0u);
  EXPECT_EQ(topology(split, true), t);
}

TEST(MeshQualityTopology, ThreeTrianglesOnOneEdge) {
  SurfaceMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0.5f, 1, 0}, {0.5f, -1, 0}, {0.5f, 0, 1}};
  m.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  const MeshTopology t = topology(m);
  EXPECT_EQ(t.non_manifold_edges, 1u);
  EXPECT_EQ(t.boundary_edges, 6u);
  EXPECT_EQ(t.non_manifold_vertices, 0u);  // around each end the three are one fan
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(intersections(m), 0u);
}

TEST(MeshQualityTopology, WeldedSoupEqualsIndexedMesh) {
  const SurfaceMesh shapes[] = {to_surface(test::make_cube()), to_surface(test::make_sphere(2))};
  for (const SurfaceMesh& cube : shapes) {
    const SurfaceMesh soup = to_soup(cube);
    EXPECT_EQ(topology(soup, true), topology(cube));
    const MeshTopology raw = topology(soup);
    EXPECT_EQ(raw.components, cube.triangles.size());
    EXPECT_EQ(raw.boundary_edges, 3 * cube.triangles.size());
    EXPECT_EQ(intersections(soup), 0u);  // sharing is by position
  }
  // -0.0 and 0.0 are one position.
  SurfaceMesh t = tetrahedron();
  SurfaceMesh soup = to_soup(t);
  for (vec3& p : soup.positions)
    if (p == vec3(0.0f)) {
      p = vec3(-0.0f, 0.0f, -0.0f);
      break;
    }
  EXPECT_EQ(topology(soup, true), topology(t));
}

TEST(MeshQualityTopology, DegenerateTrianglesAreCounted) {
  SurfaceMesh m = tetrahedron();
  m.positions.push_back({2, 0, 0});
  m.positions.push_back({7, 7, 7});  // unreferenced
  m.triangles.push_back({0, 1, 4});  // collinear: zero area, in the edge counts
  m.triangles.push_back({2, 2, 3});  // repeated index: left out
  const MeshTopology t = topology(m);
  EXPECT_EQ(t.degenerate_triangles, 2u);
  EXPECT_EQ(t.unreferenced_vertices, 1u);
  EXPECT_EQ(t.non_manifold_edges, 1u);  // (0, 1) now has three triangles
  EXPECT_EQ(t.boundary_edges, 2u);      // (1, 4) and (4, 0)
  EXPECT_FALSE(t.closed_manifold());
  EXPECT_EQ(intersections(m), 0u);  // zero-area triangles are left out
}

// Every count of mesh_topology by definition, the slow way: edges in a map, fans and components
// by breadth-first search, zero area by an exact cross product (the test's coordinates are small
// integers), equal positions by value.
MeshTopology reference_topology(const SurfaceMesh& m, bool weld) {
  MeshTopology out;
  out.triangles = m.triangles.size();
  std::vector<uint32_t> id(m.positions.size());
  std::map<std::array<float, 3>, uint32_t> distinct;
  for (size_t i = 0; i < id.size(); ++i) {
    const vec3 p = m.positions[i] + vec3(0.0f);  // -0.0 is 0.0
    id[i] = weld ? distinct.try_emplace({p.x, p.y, p.z}, uint32_t(distinct.size())).first->second : uint32_t(i);
  }
  const size_t vertices = weld ? distinct.size() : m.positions.size();
  out.vertices = vertices;
  std::vector<std::array<uint32_t, 3>> tris;  // the triangles with three distinct ids
  std::vector<size_t> proper;                 // their input indices
  for (size_t t = 0; t < m.triangles.size(); ++t) {
    const uvec3& o = m.triangles[t];
    const std::array<uint32_t, 3> v = {id[o[0]], id[o[1]], id[o[2]]};
    const dvec3 a(m.positions[o[0]]), b(m.positions[o[1]]), c(m.positions[o[2]]);
    const bool repeated = v[0] == v[1] || v[1] == v[2] || v[2] == v[0];
    if (repeated || glm::cross(b - a, c - a) == dvec3(0.0)) ++out.degenerate_triangles;
    if (repeated) continue;
    tris.push_back(v);
    proper.push_back(t);
  }
  std::map<std::pair<uint32_t, uint32_t>, std::vector<std::pair<size_t, bool>>> edges;  // (triangle, runs low -> high)
  std::vector<std::vector<size_t>> at_vertex(vertices);
  for (size_t t = 0; t < tris.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = tris[t][k], b = tris[t][(k + 1) % 3];
      edges[{std::min(a, b), std::max(a, b)}].push_back({t, a < b});
      at_vertex[a].push_back(t);
    }
  std::vector<std::vector<size_t>> neighbours(tris.size());
  for (const auto& [key, on] : edges) {
    if (on.size() == 1) ++out.boundary_edges;
    if (on.size() > 2) ++out.non_manifold_edges;
    if (on.size() == 2 && on[0].second == on[1].second) ++out.inconsistent_edges;
    for (const auto& [t, dir] : on)
      for (const auto& [u, dir2] : on)
        if (t != u) neighbours[t].push_back(u);
  }
  std::vector<bool> seen(tris.size(), false);
  for (size_t t = 0; t < tris.size(); ++t) {
    if (seen[t]) continue;
    ++out.components;
    std::vector<size_t> stack = {t};
    seen[t] = true;
    while (!stack.empty()) {
      const size_t s = stack.back();
      stack.pop_back();
      for (size_t u : neighbours[s])
        if (!seen[u]) {
          seen[u] = true;
          stack.push_back(u);
        }
    }
  }
  // Around v two triangles are in one fan when both hold an edge {v, u}.
  auto holds_edge = [&](size_t t, uint32_t v, uint32_t u) {
    const auto& x = tris[t];
    return std::count(x.begin(), x.end(), v) == 1 && std::count(x.begin(), x.end(), u) == 1;
  };
  for (uint32_t v = 0; v < vertices; ++v) {
    const std::vector<size_t>& around = at_vertex[v];
    if (around.empty()) {
      ++out.unreferenced_vertices;
      continue;
    }
    std::vector<bool> reached(around.size(), false);
    std::vector<size_t> stack = {0};
    reached[0] = true;
    while (!stack.empty()) {
      const size_t i = stack.back();
      stack.pop_back();
      for (size_t j = 0; j < around.size(); ++j) {
        if (reached[j]) continue;
        for (const uint32_t u : tris[around[i]])
          if (u != v && holds_edge(around[j], v, u)) {
            reached[j] = true;
            stack.push_back(j);
            break;
          }
      }
    }
    if (std::find(reached.begin(), reached.end(), false) != reached.end()) ++out.non_manifold_vertices;
  }
  return out;
}

TEST(MeshQualityTopology, AgreesWithTheDefinitionOnRandomDefects) {
  test::Random random(7);
  // A closed sphere with holes punched, triangles flipped and repeated, stray and collinear
  // triangles, and some vertices split off at their positions (soups and seams); large enough
  // that the threads share the work.
  const SurfaceMesh sphere = to_surface(test::make_sphere(5));
  for (int trial = 0; trial < 12; ++trial) {
    SurfaceMesh m;
    for (const vec3& p : sphere.positions) m.positions.push_back(glm::round(p * 1024.0f));
    for (const uvec3& t : sphere.triangles) {
      const uint32_t roll = random.index(40);
      if (roll == 0) continue;  // a hole
      m.triangles.push_back(roll == 1 ? uvec3(t[0], t[2], t[1]) : t);
      if (roll == 2) m.triangles.push_back(t);  // the same triangle twice: a non-manifold edge
    }
    const uint32_t n = uint32_t(m.positions.size());
    auto any = [&] { return uint32_t(random.index(int(n))); };
    for (int extra = 0; extra < 50; ++extra) m.triangles.push_back({any(), any(), any()});  // strays, repeats too
    m.positions.push_back(m.positions[0] * 2.0f - m.positions[1]);  // on the line through 0 and 1
    m.triangles.push_back({0, 1, n});
    m.positions.push_back(vec3(-0.0f, 0.0f, 0.0f));
    m.positions.push_back(vec3(0.0f, -0.0f, 0.0f));  // one position, two vertices
    m.triangles.push_back({n + 1, 0, 1});
    m.triangles.push_back({n + 2, 1, 0});
    m.positions.push_back(vec3(4096.0f));  // unreferenced
    for (uvec3& t : m.triangles)
      for (int k = 0; k < 3; ++k)
        if (random.index(20) == 0) {  // split off
          m.positions.push_back(m.positions[t[k]]);
          t[k] = uint32_t(m.positions.size() - 1);
        }
    ASSERT_GT(m.positions.size(), 10000u);
    for (const bool weld : {false, true}) {
      const MeshTopology got = topology(m, weld), want = reference_topology(m, weld);
      EXPECT_EQ(got, want) << "trial " << trial << (weld ? " welded" : "");
      EXPECT_GT(want.boundary_edges * want.non_manifold_edges * want.inconsistent_edges, 0u);
      EXPECT_GT(want.degenerate_triangles * want.non_manifold_vertices * want.unreferenced_vertices, 0u);
    }
  }
}

TEST(MeshQualityTopology, EmptyAndBadInput) {
  const SurfaceMesh empty;
  EXPECT_EQ(topology(empty), MeshTopology{});
  EXPECT_EQ(intersections(empty), 0u);

  SurfaceMesh bad = tetrahedron();
  bad.triangles[1][2] = 17;
  MeshTopology t;
  uint64_t n = 0;
  for (const Status& s : {mesh_topology(bad, t), count_self_intersections(bad, n)}) {
    EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
    EXPECT_NE(s.message().find("triangle 1 refers to vertex 17"), std::string::npos) << s.message();
  }
  SurfaceMesh nan = tetrahedron();
  nan.positions[2].y = std::nanf("");
  const Status s = mesh_topology(nan, t, true);
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
  EXPECT_NE(s.message().find("vertex 2"), std::string::npos) << s.message();
}

// ---------------------------------------------------------------------------------------------
// Self-intersections

TEST(MeshQualitySelfIntersection, AnalyticPairs) {
  const exact::Triangle base = {vec3(0, 0, 0), vec3(2, 0, 0), vec3(0, 2, 0)};
  struct Case {
    const char* name;
    exact::Triangle q;
    bool meet;
  };
  const Case cases[] = {
      {"crossing", {vec3(0.5f, 0.5f, -1), vec3(0.5f, 0.5f, 1), vec3(1.5f, 0.2f, 0)}, true},
      {"above", {vec3(0.5f, 0.5f, 1), vec3(1.5f, 0.5f, 1), vec3(0.5f, 1.5f, 2)}, false},
      {"vertex on the face", {vec3(0.5f, 0.5f, 0), vec3(1, 1, 1), vec3(0, 1, 1)}, true},
      {"vertex on an edge (T-junction)", {vec3(1, 0, 0), vec3(1, -1, 1), vec3(1, 1, 1)}, true},
      {"coplanar, inside", {vec3(0.2f, 0.2f, 0), vec3(0.6f, 0.2f, 0), vec3(0.2f, 0.6f, 0)}, true},
      {"coplanar, apart", {vec3(2, 2, 0), vec3(3, 2, 0), vec3(2, 3, 0)}, false},
      {"folded onto the shared edge", {vec3(2, 0, 0), vec3(0, 0, 0), vec3(1, 0.5f, 0)}, true},
      {"unfolded at the shared edge", {vec3(2, 0, 0), vec3(0, 0, 0), vec3(1, -0.5f, 0)}, false},
      {"dihedral at the shared edge", {vec3(2, 0, 0), vec3(0, 0, 0), vec3(1, 0.5f, 0.5f)}, false},
      {"shared vertex, crossing", {vec3(0, 0, 0), vec3(0.25f, 0.25f, -1), vec3(0.25f, 0.25f, 1)}, true},
      {"shared vertex, apart", {vec3(0, 0, 0), vec3(-1, 0, 1), vec3(0, -1, 1)}, false},
      {"shared vertex, coplanar wedges apart", {vec3(0, 0, 0), vec3(-1, 0, 0), vec3(0, -1, 0)}, false},
      {"shared vertex, coplanar wedges overlap", {vec3(0, 0, 0), vec3(1, 1, 0), vec3(-1, 1, 0)}, true},
      {"shared vertex, touching along an edge line", {vec3(0, 0, 0), vec3(1, 0, 1), vec3(1, 0, -1)}, true},
      {"shared vertex, coplanar, an edge on the line beyond it",
       {vec3(0, 0, 0), vec3(-1, 0, 0), vec3(-1, -1, 0)},
       false},
      {"shared vertex, coplanar, an edge along the line onto it", {vec3(0, 0, 0), vec3(1, 0, 0), vec3(1, -1, 0)}, true},
      {"shared vertex, coplanar, a vertex on the line beyond it",
       {vec3(0, 0, 0), vec3(-1, 0, 0), vec3(0, -1, 0)},
       false},
      {"duplicate", {vec3(0, 2, 0), vec3(0, 0, 0), vec3(2, 0, 0)}, true},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(exact::triangles_intersect(base, c.q), c.meet) << c.name;
    EXPECT_EQ(exact::triangles_intersect(c.q, base), c.meet) << c.name;
    std::vector<glm::uvec2> pairs;
    EXPECT_EQ(intersections(pair_mesh(base, c.q), &pairs), c.meet ? 1u : 0u) << c.name;
    if (c.meet) {
      ASSERT_EQ(pairs.size(), 1u);
      EXPECT_EQ(pairs[0], glm::uvec2(0, 1));
    }
  }
}

TEST(MeshQualitySelfIntersection, ClosedMeshesAndDefects) {
  // A fine icosphere and a cube's soup: nothing but shared vertices and edges.
  EXPECT_EQ(intersections(to_surface(test::make_sphere(5))), 0u);
  // The sphere and a copy moved by half its radius cross along a circle.
  const Mesh a = test::make_sphere(3);
  SurfaceMesh two = to_surface(a);
  const uint32_t offset = uint32_t(two.positions.size());
  for (const vec3& p : a.positions) two.positions.push_back(p + vec3(0.5f, 0.01f, 0.02f));
  for (const uvec3& t : a.triangles) two.triangles.push_back(t + uvec3(offset));
  std::vector<glm::uvec2> pairs;
  const uint64_t n = intersections(two, &pairs);
  EXPECT_GT(n, 20u);
  ASSERT_EQ(pairs.size(), n);
  for (const glm::uvec2& p : pairs) {
    EXPECT_LT(p.x, a.triangles.size());  // every pair has one triangle of each sphere
    EXPECT_GE(p.y, a.triangles.size());
  }
  // As soups (three vertices of its own per triangle) both count the same: corners are shared by
  // position, not by index.
  EXPECT_EQ(intersections(to_soup(to_surface(test::make_sphere(5)))), 0u);
  EXPECT_EQ(intersections(to_soup(two)), n);
  // A vertex pushed through the opposite side of the cube.
  SurfaceMesh dent = to_surface(test::make_cube());
  dent.positions[6] = {-0.5f, -0.5f, -1.5f};
  EXPECT_GT(intersections(dent), 0u);
}

// The grid's pairs against every pair by the exact test, on soups of small triangles with a few
// wide ones (which take the BVH), corners shared with earlier triangles (the filters' shared-vertex
// cases), and copies on a plane (coplanar pairs).
TEST(MeshQualitySelfIntersection, GridFindsEveryPair) {
  test::Random random(31);
  uint64_t total = 0;
  for (int round = 0; round < 6; ++round) {
    SurfaceMesh m;
    const int n = 400;
    for (int t = 0; t < n; ++t) {
      const float size = random.index(20) == 0 ? 0.6f : random.uniform(0.01f, 0.08f);
      const vec3 at = random.in_box({vec3(0.0f), vec3(1.0f)});
      const uint32_t base = uint32_t(m.positions.size());
      for (int k = 0; k < 3; ++k) {
        vec3 p = at + size * random.unit();
        if (round % 2 == 1) p.z = 0.5f;  // all in one plane
        m.positions.push_back(p);
      }
      uvec3 tri(base, base + 1, base + 2);
      if (t > 0 && random.index(3) == 0) tri[0] = m.triangles[size_t(random.index(t))][random.index(3)];
      m.triangles.push_back(tri);
    }
    std::vector<glm::uvec2> pairs;
    const uint64_t count = intersections(m, &pairs);
    std::vector<glm::uvec2> expected;
    for (uint32_t i = 0; i < uint32_t(n); ++i)
      for (uint32_t j = i + 1; j < uint32_t(n); ++j) {
        const exact::Triangle p = {m.positions[m.triangles[i][0]], m.positions[m.triangles[i][1]],
                                   m.positions[m.triangles[i][2]]};
        const exact::Triangle q = {m.positions[m.triangles[j][0]], m.positions[m.triangles[j][1]],
                                   m.positions[m.triangles[j][2]]};
        if (exact::triangles_intersect(p, q)) expected.push_back({i, j});
      }
    EXPECT_EQ(count, expected.size()) << "round " << round;
    EXPECT_EQ(pairs, expected) << "round " << round;
    total += count;
  }
  EXPECT_GT(total, 500u) << "too few pairs to tell";
}

// ---------------------------------------------------------------------------------------------
// Distances

struct SphereFixture {
  static constexpr float kRadius = 1.0f;
  Mesh mesh = test::make_sphere(4, kRadius);
  GwnModel model = test::build_model(mesh);
};

SurfaceDistances distances(const GwnModel& model, const SurfaceMesh& m, uint32_t samples = 20000,
                           uint32_t rays = 4000) {
  SurfaceDistanceOptions o;
  o.output_samples = samples;
  o.surface_rays = rays;
  SurfaceDistances d;
  const Status s = surface_distances(model, m, o, d);
  EXPECT_TRUE(s.ok()) << s.message();
  return d;
}

// The largest angle between a face's normal and its vertices' normals (radial, on the sphere):
// how far interpolated normals can lean from the faceted S.
double faceting_angle_deg(const Mesh& m) {
  double worst = 0;
  for (const uvec3& t : m.triangles) {
    const dvec3 p0(m.positions[t[0]]), p1(m.positions[t[1]]), p2(m.positions[t[2]]);
    const dvec3 n = glm::normalize(glm::cross(p1 - p0, p2 - p0));
    for (const dvec3& p : {p0, p1, p2})
      worst = std::max(worst, std::acos(std::min(1.0, glm::dot(n, glm::normalize(p)))) * 180.0 / kPi);
  }
  return worst;
}

TEST(MeshQualityDistances, SameMeshIsAtZeroDistance) {
  const SphereFixture f;
  const SurfaceMesh out = to_surface(f.mesh);
  const SurfaceDistances d = distances(f.model, out);
  EXPECT_EQ(d.output_samples, 20000u + f.mesh.positions.size());
  EXPECT_EQ(d.sheet_points, SurfaceDistanceOptions{}.sheet_samples);
  EXPECT_GT(d.surface_points - d.sheet_points, 4000u);  // about two hits a ray (entering and leaving)
  const double tol = 1e-5 * SphereFixture::kRadius;
  EXPECT_LT(d.hausdorff_to_surface, tol);
  EXPECT_LT(d.hausdorff_from_surface, tol);
  EXPECT_LT(d.chamfer, tol);
  EXPECT_LE(d.mean_to_surface, d.hausdorff_to_surface);
  // Face normals against the sheet hits' face normals: float round-off.
  EXPECT_LT(d.normal_deviation_max_deg, 1e-3);
  EXPECT_LT(d.normal_deviation_mean_deg, 1e-4);

  // With radial vertex normals the interpolated normal leans from the faces by at most the
  // faceting angle.
  SurfaceMesh smooth = out;
  for (const vec3& p : out.positions) smooth.normals.push_back(glm::normalize(p));
  const SurfaceDistances ds = distances(f.model, smooth);
  EXPECT_LT(ds.hausdorff_from_surface, tol);
  EXPECT_GT(ds.normal_deviation_max_deg, 0.1);
  EXPECT_LE(ds.normal_deviation_max_deg, faceting_angle_deg(f.mesh) + 1e-3);

  // Inside out: the normals are opposite.
  SurfaceMesh flipped = out;
  for (uvec3& t : flipped.triangles) std::swap(t[1], t[2]);
  const SurfaceDistances df = distances(f.model, flipped, 1000, 1000);
  EXPECT_GT(df.normal_deviation_mean_deg, 179.99);
}

TEST(MeshQualityDistances, ScaledMeshIsAtOnePercent) {
  // The output is S scaled by 1.01 about the centre. S is convex with its vertices on the sphere
  // of radius r; each face F lies in a plane at distance h_F <= r from the centre.
  //  - A point p of the output is outside S and p / 1.01 is in S, so dist(p, S) <= 0.01|p| / 1.01
  //    <= 0.01 r; it is beyond F's plane by at least 0.01 h_F, so dist >= 0.01 min h_F. At the
  //    scaled vertices (samples too) the nearest point of S is the vertex: exactly 0.01 r.
  //  - A point q of S is inside the output; its distance to a scaled face's plane is
  //    1.01 h_F − n_F·q >= 0.01 h_F, and to its own face's, 0.01 h_F <= 0.01 r.
  // So both Hausdorff distances and both means lie in [0.01 min h_F, 0.01 r], min h_F = r cos of
  // the faces' angular radius (0.9985 r at 4 subdivisions), and to S the maximum is 0.01 r.
  const SphereFixture f;
  SurfaceMesh out = to_surface(f.mesh);
  for (vec3& p : out.positions) p *= 1.01f;
  double h_min = SphereFixture::kRadius;
  for (const uvec3& t : f.mesh.triangles) {
    const dvec3 p0(f.mesh.positions[t[0]]), p1(f.mesh.positions[t[1]]), p2(f.mesh.positions[t[2]]);
    h_min = std::min(h_min, glm::dot(glm::normalize(glm::cross(p1 - p0, p2 - p0)), p0));
  }
  const double lo = 0.01 * h_min - 1e-6, hi = 0.01 * SphereFixture::kRadius + 1e-6;  // + float round-off
  const SurfaceDistances d = distances(f.model, out);
  for (const double v :
       {d.hausdorff_to_surface, d.hausdorff_from_surface, d.mean_to_surface, d.mean_from_surface, d.chamfer}) {
    EXPECT_GE(v, lo);
    EXPECT_LE(v, hi);
  }
  EXPECT_NEAR(d.hausdorff_to_surface, 0.01 * SphereFixture::kRadius, 1e-6);
}

// S's points on its sheets lie on the sheet triangles only, outward: inside a sphere, a smaller
// one of the same orientation makes w = 2 within it, so its triangles (sides 1 and 2) are no
// sheets for w* = 1/2, and the outer sphere alone is S. Measured from the sheet points alone (no
// rays), the outer sphere is at zero distance with S's normals; the inner one, as output, at the
// radii's difference.
TEST(MeshQualityDistances, SheetPointsLieOnTheSheetsOnly) {
  const Mesh outer = test::make_sphere(3, 1.0f), inner = test::make_sphere(3, 0.5f);
  Mesh both = outer;
  const uint32_t base = uint32_t(both.positions.size());
  both.positions.insert(both.positions.end(), inner.positions.begin(), inner.positions.end());
  for (const uvec3& t : inner.triangles) both.triangles.push_back(t + base);
  const GwnModel model = test::build_model(both);
  SurfaceDistanceOptions o;
  o.output_samples = 1000;
  o.surface_rays = 0;
  o.sheet_samples = 5000;
  SurfaceDistances d;
  ASSERT_TRUE(surface_distances(model, to_surface(outer), o, d).ok());
  EXPECT_EQ(d.surface_points, 5000u);
  EXPECT_EQ(d.sheet_points, 5000u);
  EXPECT_LT(d.hausdorff_from_surface, 1e-5);
  EXPECT_LT(d.normal_deviation_max_deg, 1e-3);
  ASSERT_TRUE(surface_distances(model, to_surface(inner), o, d).ok());
  // A point p of the outer faces has h_outer <= |p| <= 1 (h: the nearest face plane's distance
  // from the centre); the inner mesh lies within radius 0.5 and holds the ball of radius h_inner.
  const auto nearest_plane = [](const Mesh& m) {
    double h = 1e30;
    for (const uvec3& t : m.triangles) {
      const dvec3 p0(m.positions[t[0]]), p1(m.positions[t[1]]), p2(m.positions[t[2]]);
      h = std::min(h, glm::dot(glm::normalize(glm::cross(p1 - p0, p2 - p0)), p0));
    }
    return h;
  };
  EXPECT_GT(d.mean_from_surface, nearest_plane(outer) - 0.5 - 1e-6);
  EXPECT_LT(d.hausdorff_from_surface, 1.0 - nearest_plane(inner) + 1e-6);
  EXPECT_GT(d.hausdorff_from_surface, 0.45);
}

// S's points find their nearest output triangles in the grid's rings of cells, among the wide
// triangles by their own tree, or, beyond the rings, in blocks of cells by a tree: the same distances
// whichever finds them. The output: a coarse sphere with a cap cut off (points of S by the hole
// lie beyond the rings) and every other triangle split in sixteen (the unsplit ones are wide); again
// with a speck far away, whose grid has too many cells for a map (two rings, looked up by search).
// (The speck widens the output's box, and with it what counts as a tie for the normals: only the
// distances are compared.)
TEST(MeshQualityDistances, TheGridsPathsAgree) {
  const SphereFixture f;
  const Mesh coarse = test::make_sphere(3, 0.98f * SphereFixture::kRadius);
  SurfaceMesh out;
  out.positions = coarse.positions;
  int split = 0;
  for (const uvec3& t : coarse.triangles) {
    const vec3 c = (coarse.positions[t[0]] + coarse.positions[t[1]] + coarse.positions[t[2]]) / 3.0f;
    if (c.z > 0.8f) continue;  // the hole
    const auto split_in_four = [&](auto&& self, const uvec3& s, int depth) -> void {
      if (depth == 0) {
        out.triangles.push_back(s);
        return;
      }
      uint32_t m[3];
      for (int k = 0; k < 3; ++k) {
        m[k] = uint32_t(out.positions.size());
        out.positions.push_back(0.5f * (out.positions[s[k]] + out.positions[s[(k + 1) % 3]]));
      }
      for (const uvec3& q :
           {uvec3(s[0], m[0], m[2]), uvec3(m[0], s[1], m[1]), uvec3(m[2], m[1], s[2]), uvec3(m[0], m[1], m[2])})
        self(self, q, depth - 1);
    };
    split_in_four(split_in_four, t, split++ % 2 == 0 ? 0 : 2);  // sixteen pieces: the others are wide
  }
  SurfaceMesh speck = out;
  const uint32_t base = uint32_t(speck.positions.size());
  speck.positions.insert(speck.positions.end(), {vec3(1e4f, 0, 0), vec3(1e4f + 0.01f, 0, 0), vec3(1e4f, 0.01f, 0)});
  speck.triangles.push_back({base, base + 1, base + 2});
  const SurfaceDistances a = distances(f.model, out, 2000, 4000), b = distances(f.model, speck, 2000, 4000);
  EXPECT_GT(a.hausdorff_from_surface, 0.3);  // the hole's rim is far from S's cap
  EXPECT_EQ(a.surface_points, b.surface_points);
  EXPECT_DOUBLE_EQ(a.mean_from_surface, b.mean_from_surface);
  EXPECT_DOUBLE_EQ(a.hausdorff_from_surface, b.hausdorff_from_surface);
  // And against the distances to the unsplit sphere with the same hole, within the midpoints'
  // rounding.
  SurfaceMesh unsplit;
  unsplit.positions = coarse.positions;
  for (const uvec3& t : coarse.triangles)
    if ((coarse.positions[t[0]] + coarse.positions[t[1]] + coarse.positions[t[2]]).z / 3.0f <= 0.8f)
      unsplit.triangles.push_back(t);
  const SurfaceDistances u = distances(f.model, unsplit, 2000, 4000);
  EXPECT_NEAR(a.mean_from_surface, u.mean_from_surface, 1e-6);
  EXPECT_NEAR(a.hausdorff_from_surface, u.hausdorff_from_surface, 1e-6);
}

TEST(MeshQualityDistances, SamplesFollowTheOutputsSize) {
  SurfaceDistanceOptions full;
  full.output_samples = 1000;
  full.vertex_samples = 0;  // none stays none
  full.surface_rays = 250;
  full.sheet_samples = 333;
  full.seed = 9;
  full.level = 0.25f;
  for (const size_t triangles : {kFullSampleTriangles, 10 * kFullSampleTriangles}) {
    const SurfaceDistanceOptions o = samples_for_output(triangles, full);
    EXPECT_EQ(o.output_samples, 1000u);
    EXPECT_EQ(o.surface_rays, 250u);
    EXPECT_EQ(o.sheet_samples, 333u);
  }
  const SurfaceDistanceOptions half = samples_for_output(kFullSampleTriangles / 2, full);
  EXPECT_EQ(half.output_samples, 500u);
  EXPECT_EQ(half.vertex_samples, 0u);
  EXPECT_EQ(half.surface_rays, 125u);
  EXPECT_EQ(half.sheet_samples, 167u);  // rounded up
  EXPECT_EQ(half.seed, 9u);
  EXPECT_EQ(half.level, 0.25f);
  for (const size_t triangles : {size_t(0), size_t(12), kFullSampleTriangles / 20}) {
    const SurfaceDistanceOptions tenth = samples_for_output(triangles, full);
    EXPECT_EQ(tenth.output_samples, 100u);
    EXPECT_EQ(tenth.surface_rays, 25u);
    EXPECT_EQ(tenth.sheet_samples, 34u);
  }
  EXPECT_EQ(samples_for_output(kFullSampleTriangles).output_samples, SurfaceDistanceOptions{}.output_samples);
}

TEST(MeshQualityDistances, RefusesModelsWithoutMatchingSheetsAndBadInput) {
  const SphereFixture f;
  const SurfaceMesh out = to_surface(f.mesh);
  SurfaceDistanceOptions o;
  o.output_samples = 100;
  o.surface_rays = 100;
  SurfaceDistances d;
  o.level = 0.25f;  // the model's sheets are for 0.5
  EXPECT_EQ(surface_distances(f.model, out, o, d).code(), StatusCode::kInvalidArgument);
  o.level = 0.5f;
  GwnModel bare;
  BuildOptions b;
  b.classify_sheets = false;
  ASSERT_TRUE(GwnModel::build(f.mesh, bare, b).ok());
  const Status s = surface_distances(bare, out, o, d);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("sheets"), std::string::npos) << s.message();

  SurfaceMesh bad = out;
  bad.normals.resize(3);
  EXPECT_EQ(surface_distances(f.model, bad, o, d).code(), StatusCode::kInvalidMesh);
  bad = out;
  bad.triangles[5][0] = uint32_t(bad.positions.size());
  const Status si = surface_distances(f.model, bad, o, d);
  EXPECT_NE(si.message().find("triangle 5"), std::string::npos) << si.message();

  // An empty output: nothing to measure from it, and S is infinitely far from it.
  ASSERT_TRUE(surface_distances(f.model, SurfaceMesh{}, o, d).ok());
  EXPECT_EQ(d.output_samples, 0u);
  EXPECT_EQ(d.hausdorff_to_surface, 0.0);
  EXPECT_GT(d.surface_points, 0u);
  EXPECT_TRUE(std::isinf(d.hausdorff_from_surface));
}

// Not a check: the time of the topology and the intersection count on a 1.3M-triangle sphere
// (--gtest_also_run_disabled_tests to see it).
TEST(MeshQualityTiming, DISABLED_MillionTriangles) {
  const SurfaceMesh m = to_surface(test::make_sphere(8));
  using clock = std::chrono::steady_clock;
  auto t0 = clock::now();
  const MeshTopology t = topology(m);
  auto t1 = clock::now();
  const MeshTopology tw = topology(m, true);
  auto t2 = clock::now();
  const uint64_t n = intersections(m);
  auto t3 = clock::now();
  auto sec = [](auto a, auto b) { return std::chrono::duration<double>(b - a).count(); };
  std::printf("%zu triangles: mesh_topology %.3f s (welded %.3f s), count_self_intersections %.3f s\n",
              m.triangles.size(), sec(t0, t1), sec(t1, t2), sec(t2, t3));
  EXPECT_TRUE(t.closed_manifold());
  EXPECT_EQ(tw, t);
  EXPECT_EQ(n, 0u);
}

}  // namespace
}  // namespace gwnrt
