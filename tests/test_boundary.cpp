// ∂M extraction: exact expectations on small meshes and an independent half-edge count on the
// bundled meshes.
#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "test_util.h"

namespace gwnrt {
namespace {

using test::load_test_mesh;
using test::make_cube;
using test::make_sphere;

using Point = std::array<float, 3>;
using Segment = std::pair<Point, Point>;

Point key(const vec3& p) { return {p.x, p.y, p.z}; }

// The boundary as a sorted multiset of oriented segments.
std::vector<Segment> segments(const BoundaryCurve& curve) {
  EXPECT_EQ(curve.endpoints.size() % 2, 0u);
  std::vector<Segment> s;
  for (size_t i = 0; i < curve.segment_count(); ++i)
    s.emplace_back(key(curve.endpoints[2 * i]), key(curve.endpoints[2 * i + 1]));
  std::sort(s.begin(), s.end());
  return s;
}

Mesh as_soup(const Mesh& m) {
  Mesh soup;
  for (const uvec3& t : m.triangles) {
    const uint32_t base = uint32_t(soup.positions.size());
    for (int k = 0; k < 3; ++k) soup.positions.push_back(m.positions[t[k]]);
    soup.triangles.push_back({base, base + 1, base + 2});
  }
  return soup;
}

TEST(Boundary, OpenCubeIsItsTopSquare) {
  const std::vector<Segment> s = segments(extract_boundary(make_cube(true)));
  // With the lid gone, ∂M is the lid's own loop reversed (the closed cube's boundary is zero):
  // (-1,-1) -> (-1,1) -> (1,1) -> (1,-1) at z = 1.
  std::vector<Segment> expected = {
      {{-1, -1, 1}, {-1, 1, 1}}, {{-1, 1, 1}, {1, 1, 1}}, {{1, 1, 1}, {1, -1, 1}}, {{1, -1, 1}, {-1, -1, 1}}};
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(s, expected);
  // A closed loop: every corner starts exactly one segment and ends exactly one.
  std::map<Point, int> starts, ends;
  for (const auto& [a, b] : s) {
    ++starts[a];
    ++ends[b];
  }
  EXPECT_EQ(starts.size(), 4u);
  for (const auto& [p, n] : starts) {
    EXPECT_EQ(n, 1);
    EXPECT_EQ(ends[p], 1);
  }
}

TEST(Boundary, ClosedMeshesHaveNone) {
  EXPECT_EQ(extract_boundary(make_cube()).segment_count(), 0u);
  EXPECT_EQ(extract_boundary(make_sphere(2)).segment_count(), 0u);
  EXPECT_EQ(extract_boundary(load_test_mesh("bunny.obj")).segment_count(), 0u);
}

TEST(Boundary, SoupIsWeldedByPosition) {
  const Mesh cube = make_cube(true);
  EXPECT_EQ(segments(extract_boundary(as_soup(cube))), segments(extract_boundary(cube)));
  EXPECT_EQ(extract_boundary(as_soup(make_cube())).segment_count(), 0u);
  EXPECT_EQ(extract_boundary(as_soup(make_sphere(1))).segment_count(), 0u);
}

TEST(Boundary, NegativeZeroWeldsWithPositiveZero) {
  // Two triangles sharing the edge (0,0,0)-(1,1,0), one of them spelling the origin as -0.
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-0.0f, -0.0f, -0.0f}, {1, 1, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}, {3, 4, 5}};
  EXPECT_EQ(extract_boundary(m).segment_count(), 4u);
}

TEST(Boundary, MultiplicityCountsAndCancels) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}, {0, 1, 2}};
  std::vector<Segment> expected = {{{0, 0, 0}, {1, 0, 0}}, {{1, 0, 0}, {0, 1, 0}}, {{0, 1, 0}, {0, 0, 0}}};
  expected.insert(expected.end(), expected.begin(), expected.end());
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(segments(extract_boundary(m)), expected);

  m.triangles = {{0, 1, 2}, {0, 2, 1}};
  EXPECT_EQ(extract_boundary(m).segment_count(), 0u);
}

TEST(Boundary, ZeroAreaTrianglesAreIgnored) {
  Mesh m = make_cube();
  m.triangles.push_back({0, 1, 1});                                 // repeated corner
  m.triangles.push_back({0, 0, 0});                                 // a point
  m.positions.push_back({0, -1, -1});                               // midpoint of the edge 0-1
  m.triangles.push_back({0, 1, uint32_t(m.positions.size() - 1)});  // collinear
  m.triangles.push_back({0, 6, 6});                                 // repeated corner across the cube's diagonal
  EXPECT_EQ(extract_boundary(m).segment_count(), 0u);
}

// Independent reference: count oriented half-edges by index; an edge {a, b} is a boundary
// edge with multiplicity |count(a->b) - count(b->a)|. With `weld`, indices that share a
// position (after folding -0 into +0) are first mapped to the lowest such index.
std::vector<Segment> reference_boundary(const Mesh& m, bool weld) {
  std::vector<uint32_t> canonical(m.positions.size());
  std::map<Point, uint32_t> first;
  for (uint32_t i = 0; i < m.positions.size(); ++i)
    canonical[i] = weld ? first.try_emplace(key(m.positions[i] + 0.0f), i).first->second : i;
  std::map<std::pair<uint32_t, uint32_t>, int> half_edges;
  for (const uvec3& t : m.triangles) {
    if (is_degenerate_triangle(m.positions[t[0]], m.positions[t[1]], m.positions[t[2]])) continue;
    for (int k = 0; k < 3; ++k) ++half_edges[{canonical[t[k]], canonical[t[(k + 1) % 3]]}];
  }
  std::vector<Segment> s;
  for (const auto& [e, n] : half_edges) {
    const auto it = half_edges.find({e.second, e.first});
    const int net = n - (it == half_edges.end() ? 0 : it->second);
    for (int i = 0; i < net; ++i) s.emplace_back(key(m.positions[e.first]), key(m.positions[e.second]));
  }
  std::sort(s.begin(), s.end());
  return s;
}

bool has_repeated_positions(const Mesh& m) {
  std::vector<Point> positions;
  for (const vec3& p : m.positions) positions.push_back(key(p + 0.0f));
  std::sort(positions.begin(), positions.end());
  return std::adjacent_find(positions.begin(), positions.end()) != positions.end();
}

TEST(Boundary, BundledOpenMeshesHaveTheDocumentedCounts) {
  const Mesh bunny_holes = load_test_mesh("bunny_holes.obj");
  EXPECT_FALSE(has_repeated_positions(bunny_holes));
  EXPECT_EQ(extract_boundary(bunny_holes).segment_count(), 52u);
  // The meshes README counts 528 boundary half-edges by index; the teapot repeats positions
  // along its patch seams, and welding by position (our definition of ∂M) cancels all but 64.
  const Mesh teapot = load_test_mesh("teapot.obj");
  EXPECT_TRUE(has_repeated_positions(teapot));
  EXPECT_EQ(reference_boundary(teapot, false).size(), 528u);
  EXPECT_EQ(extract_boundary(teapot).segment_count(), 64u);
}

class BoundaryOnRealMeshes : public ::testing::TestWithParam<const char*> {};

TEST_P(BoundaryOnRealMeshes, MatchesHalfEdgeCount) {
  const Mesh mesh = load_test_mesh(GetParam());
  const std::vector<Segment> expected = reference_boundary(mesh, has_repeated_positions(mesh));
  EXPECT_EQ(segments(extract_boundary(mesh)), expected);
  // The model keeps the same curve.
  const GwnModel model = test::build_model(mesh);
  EXPECT_EQ(segments(model.boundary()), expected);
}

INSTANTIATE_TEST_SUITE_P(Meshes, BoundaryOnRealMeshes,
                         ::testing::Values("bunny.obj", "bunny_holes.obj", "teapot.obj", "dragon_vrip_res4.ply"),
                         [](const auto& info) {
                           std::string name = info.param;
                           return name.substr(0, name.find('.'));
                         });

}  // namespace
}  // namespace gwnrt
