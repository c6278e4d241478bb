// ∂M extraction: exact expectations on small meshes and an independent half-edge count on the
// bundled meshes.
#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "reference/brute_force_winding.h"
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

// Random triangles over few vertices: a non-manifold soup whose ∂M is many short scattered
// loops and edges of every multiplicity.
Mesh make_random_soup(uint32_t seed, int vertices, int triangles) {
  test::Random rng(seed);
  Mesh m;
  for (int i = 0; i < vertices; ++i) m.positions.push_back(rng.in_box({{0, 0, 0}, {1, 1, 1}}));
  for (int t = 0; t < triangles; ++t)
    m.triangles.push_back(
        {uint32_t(rng.index(vertices)), uint32_t(rng.index(vertices)), uint32_t(rng.index(vertices))});
  return m;
}

struct SpanningCase {
  std::string name;
  Mesh mesh;
};

std::vector<SpanningCase> spanning_cases() {
  std::vector<SpanningCase> cases;
  cases.push_back({"bunny_holes", load_test_mesh("bunny_holes.obj")});
  cases.push_back({"teapot", load_test_mesh("teapot.obj")});
  cases.push_back({"open cone of 3000", test::make_open_cone(3000)});
  cases.push_back({"star polygon fan", test::make_fanned_polygon(2000, 0.5, {0.5, 0.5, 0.0}, 0.9)});
  cases.push_back({"open hemisphere", test::make_hemisphere(12, 40)});
  cases.push_back({"random soup", make_random_soup(11, 40, 200)});
  return cases;
}

// The edges of ∂(surface) − curve as chains that do not cancel: every edge of the surface's
// triangles (zero-area ones too) counted with its orientation, less the curve's segments, by exact
// position; 0 when ∂(surface) = curve.
size_t edges_left_of_boundary_less_curve(const Mesh& surface, const BoundaryCurve& curve) {
  std::map<Segment, int> chain;  // (min, max) -> count of min -> max
  auto add = [&](const vec3& a, const vec3& b, int k) {
    const Point pa = key(a + 0.0f), pb = key(b + 0.0f);
    if (pa == pb) return;
    if (pa < pb)
      chain[{pa, pb}] += k;
    else
      chain[{pb, pa}] -= k;
  };
  for (const uvec3& t : surface.triangles)
    for (int k = 0; k < 3; ++k) add(surface.positions[t[k]], surface.positions[t[(k + 1) % 3]], 1);
  for (size_t s = 0; s < curve.segment_count(); ++s) add(curve.endpoints[2 * s], curve.endpoints[2 * s + 1], -1);
  size_t left = 0;
  for (const auto& [edge, count] : chain) left += count != 0;
  return left;
}

// The cone C: ∂C = ∂M as chains; its first segment_triangles triangles carry the segments, one
// each, with non-zero area; a long loop that is a curve (the open cone's rim, the star polygon's)
// is spanned (more triangles than segments) and stays near the curve as S does (test below), a
// short loop or a soup's branching curve is a fan (one triangle a segment).
TEST(Cone, SpansLongRimsAndFansTheRest) {
  for (const SpanningCase& c : spanning_cases()) {
    const BoundaryCurve curve = extract_boundary(c.mesh);
    uint32_t loops = 0;
    const std::vector<uint32_t> loop_of_segment = boundary_loops(curve, loops);
    const Cone cone = boundary_cone(curve, loop_of_segment, loops);
    EXPECT_EQ(edges_left_of_boundary_less_curve(cone.mesh, curve), 0u) << c.name;
    ASSERT_EQ(cone.loop_of_triangle.size(), cone.mesh.triangles.size()) << c.name;
    ASSERT_EQ(cone.segment_triangles, curve.segment_count()) << c.name;
    std::map<Segment, int> carried;
    for (size_t s = 0; s < curve.segment_count(); ++s)
      ++carried[{key(curve.endpoints[2 * s] + 0.0f), key(curve.endpoints[2 * s + 1] + 0.0f)}];
    for (size_t t = 0; t < cone.segment_triangles; ++t) {
      const uvec3 tri = cone.mesh.triangles[t];
      const vec3 &z = cone.mesh.positions[tri[0]], &a = cone.mesh.positions[tri[1]], &b = cone.mesh.positions[tri[2]];
      --carried[{key(a + 0.0f), key(b + 0.0f)}];
      EXPECT_FALSE(is_degenerate_triangle(z, a, b)) << c.name << ": triangle " << t;
    }
    for (const auto& [segment, count] : carried) EXPECT_EQ(count, 0) << c.name;
    const bool long_curve = c.name == "open cone of 3000" || c.name == "star polygon fan";
    if (long_curve) {
      EXPECT_GT(cone.mesh.triangles.size(), curve.segment_count()) << c.name;
    } else {
      EXPECT_EQ(cone.mesh.triangles.size(), curve.segment_count()) << c.name;
    }
    std::printf("[ %-18s ] %zu segments in %u loops: C has %zu triangles\n", c.name.c_str(), curve.segment_count(),
                loops, cone.mesh.triangles.size());
  }
}

// ∂S = ∂M, as chains: every edge of S's triangles (zero-area ones too) counted with its
// orientation, less the curve's segments, cancels, by exact position.
TEST(SpanningSurface, BoundaryIsTheMeshBoundary) {
  for (const SpanningCase& c : spanning_cases()) {
    const BoundaryCurve curve = extract_boundary(c.mesh);
    ASSERT_GT(curve.segment_count(), 0u) << c.name;
    const SpanningSurface spanning = spanning_surface(curve);
    EXPECT_EQ(edges_left_of_boundary_less_curve(spanning.mesh, curve), 0u) << c.name;
    // A level has at most 3/4 of the segments of the one below (or the rest is one fan): S at
    // most 4 times as many triangles as ∂M has segments. Along curves a level is about a quarter
    // of the one below (two spokes a group of 8), so about 4/3 times; the one fan at the end is
    // small there (the teapot's 64 segments end in 20) and may be large only for scattered loops.
    const size_t n = curve.segment_count();
    EXPECT_LE(spanning.mesh.triangles.size(), 4 * n + kSpanningGroup) << c.name;
    if (c.name != "random soup") {
      EXPECT_LE(spanning.mesh.triangles.size(), n * 3 / 2 + 4 * kSpanningGroup) << c.name;
      EXPECT_LE(spanning.single_apex_segments, 4 * kSpanningGroup) << c.name;
    }
    std::printf("[ %-18s ] %zu segments: S %zu triangles, %zu of them from one apex at the end\n", c.name.c_str(), n,
                spanning.mesh.triangles.size(), spanning.single_apex_segments);
  }
}

// S and the cone C span the same curve, so w_S − w_C is a whole number off both (their union,
// one reversed, is closed): checked with the brute-force sum in double at random points.
TEST(SpanningSurface, FieldDiffersFromTheConesByWholeNumbers) {
  for (const SpanningCase& c : spanning_cases()) {
    const BoundaryCurve curve = extract_boundary(c.mesh);
    uint32_t loops = 0;
    const std::vector<uint32_t> loop_of_segment = boundary_loops(curve, loops);
    const reference::ReferenceMesh spanning = reference::reference_mesh(spanning_surface(curve).mesh);
    const reference::ReferenceMesh cone = reference::reference_mesh(boundary_cone(curve, loop_of_segment, loops).mesh);
    test::Random rng(5);
    Aabb box = test::mesh_bounds(c.mesh);
    const vec3 pad = 0.2f * (box.hi - box.lo);
    box = {box.lo - pad, box.hi + pad};
    double worst = 0;
    int not_zero = 0;
    for (int k = 0; k < 200; ++k) {
      const dvec3 x(rng.in_box(box));
      const double difference = reference::reference_w(spanning, x) - reference::reference_w(cone, x);
      worst = std::max(worst, std::fabs(difference - std::round(difference)));
      not_zero += std::round(difference) != 0;
    }
    EXPECT_LT(worst, 1e-9) << c.name;
    std::printf("[ %-18s ] max distance from a whole number %.1e; %d of 200 points where w_S != w_C\n", c.name.c_str(),
                worst, not_zero);
  }
}

// S stays near the curve: a triangle of a level reaches from its group's mean to one of the
// group's segments, at most half the group's length along a circle, so a level's longest edges
// add up to at most 8 halves of each group's length: 4 perimeters, over log_4 n levels. C's, from
// the one apex, add up to n radii.
TEST(SpanningSurface, StaysNearACircle) {
  const int n = 100000;
  const Mesh cone = test::make_open_cone(n);
  const BoundaryCurve curve = extract_boundary(cone);
  ASSERT_EQ(curve.segment_count(), size_t(n));
  const SpanningSurface spanning = spanning_surface(curve);
  double edges = 0;
  for (const uvec3& t : spanning.mesh.triangles) {
    double longest = 0;
    for (int k = 0; k < 3; ++k)
      longest = std::max(
          longest, glm::length(dvec3(spanning.mesh.positions[t[k]]) - dvec3(spanning.mesh.positions[t[(k + 1) % 3]])));
    edges += longest;
  }
  const double perimeter = 2 * kPi * 0.5, levels = std::ceil(std::log(double(n)) / std::log(4.0));
  EXPECT_LT(edges, 4.0 * perimeter * levels);
  EXPECT_LE(spanning.mesh.triangles.size(), size_t(n) * 4 / 3 + kSpanningGroup);
  std::printf("circle of %d segments: S has %zu triangles, longest edges %.1f (perimeter %.2f, %g levels)\n", n,
              spanning.mesh.triangles.size(), edges, perimeter, levels);
}

}  // namespace
}  // namespace gwnrt
