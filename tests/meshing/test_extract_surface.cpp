// The mesher of S (meshing/): the per-cell functions against brute force, and whole meshes
// against the analytic surfaces and S itself.
#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "cli_util.h"
#include "gwnrt/io/mesh_io.h"
#include "gwnrt/meshing/cell_topology.h"
#include "gwnrt/meshing/dual_contouring.h"
#include "gwnrt/meshing/extract_surface.h"
#include "gwnrt/meshing/mesh_comparison.h"
#include "gwnrt/meshing/mesh_quality.h"
#include "gwnrt/meshing/qef.h"
#include "mesh_files.h"
#include "reference/brute_force_winding.h"
#include "reference/exact_distance.h"
#include "test_util.h"

namespace gwnrt {
namespace {

// ---------------------------------------------------------------------------------------------
// Cell components against a flood fill over the cube's surface: the patch's loops are the
// boundaries between the inside regions (inside corners joined along cube edges) and the
// outside regions (outside corners joined along cube edges and across the ambiguous faces, where
// the rule keeps the inside corners apart); on the cube's surface, a sphere, two adjacent
// regions share exactly one loop, so an edge's loop is named by the pair of regions it joins.

struct Regions {
  int of_corner[8];
};

Regions flood_regions(uint32_t inside) {
  int parent[8];
  for (int c = 0; c < 8; ++c) parent[c] = c;
  const auto find = [&](int c) {
    while (parent[c] != c) c = parent[c];
    return c;
  };
  const auto join = [&](int a, int b) { parent[find(a)] = find(b); };
  const auto in = [&](int c) { return (inside >> c) & 1u; };
  for (int c = 0; c < 8; ++c)
    for (int a = 0; a < 3; ++a) {
      const int d = c ^ (1 << a);
      if (in(c) == in(d)) join(c, d);
    }
  for (int a = 0; a < 3; ++a)
    for (int side = 0; side < 2; ++side) {
      const int b = (a + 1) % 3, c = (a + 2) % 3, base = side << a;
      const int p = base, q = base | (1 << b), r = base | (1 << b) | (1 << c), s = base | (1 << c);
      const bool ambiguous = in(p) == in(r) && in(q) == in(s) && in(p) != in(q);
      if (ambiguous) {  // the outside diagonal is joined across the face
        if (in(p))
          join(q, s);
        else
          join(p, r);
      }
    }
  Regions out;
  for (int c = 0; c < 8; ++c) out.of_corner[c] = find(c);
  return out;
}

TEST(MeshingCell, ComponentsMatchFloodFillForAll256Patterns) {
  for (uint32_t mask = 0; mask < 256; ++mask) {
    const CellComponents parts = cell_components(mask);
    const Regions regions = flood_regions(mask);
    std::map<std::pair<int, int>, int> loop_of_pair;
    std::map<int, std::pair<int, int>> pair_of_loop;
    for (int e = 0; e < kCellEdges; ++e) {
      const int c0 = edge_corner(e), c1 = c0 | (1 << edge_axis(e));
      const bool changes = ((mask >> c0) & 1u) != ((mask >> c1) & 1u);
      ASSERT_EQ(parts.of_edge[e] >= 0, changes) << "pattern " << mask << " edge " << e;
      if (!changes) continue;
      const int inside = (mask >> c0) & 1u ? c0 : c1, outside = inside == c0 ? c1 : c0;
      const std::pair<int, int> key{regions.of_corner[inside], regions.of_corner[outside]};
      const auto [it, fresh] = loop_of_pair.emplace(key, parts.of_edge[e]);
      EXPECT_EQ(it->second, parts.of_edge[e]) << "pattern " << mask << " edge " << e << ": two loops for one pair";
      const auto [jt, fresh2] = pair_of_loop.emplace(parts.of_edge[e], key);
      EXPECT_EQ(jt->second, key) << "pattern " << mask << " edge " << e << ": one loop for two pairs";
    }
    EXPECT_EQ(int(loop_of_pair.size()), parts.count) << "pattern " << mask;
  }
}

// Whether some face of the cell holds both edges.
bool share_a_face(int a, int b) {
  for (int face = 0; face < 6; ++face) {
    const CellFace f = cell_face(face);
    bool has_a = false, has_b = false;
    for (int k = 0; k < 4; ++k) {
      has_a |= f.edge[k] == a;
      has_b |= f.edge[k] == b;
    }
    if (has_a && has_b) return true;
  }
  return false;
}

// Every pair of cells sharing an ambiguous face (the face's 4 signs, the two cells' other 4 each):
// where both have a tunnel through it, all four of the face's crossed edges are one component
// in both cells under the default pairing (their two vertices would be joined by four triangles),
// and after the flip in neither.
TEST(MeshingCell, FlippingAFaceWithTunnelsOnBothSidesSeparatesItsSegments) {
  const auto one_component = [](uint32_t inside, int face, uint32_t flipped) {
    const CellComponents parts = cell_components(inside, flipped);
    const CellFace f = cell_face(face);
    for (int k = 1; k < 4; ++k)
      if (parts.of_edge[f.edge[k]] != parts.of_edge[f.edge[0]]) return false;
    return true;
  };
  int both_tunnels = 0;
  for (int face = 0; face < 6; ++face) {
    const CellFace f = cell_face(face), g = cell_face(face ^ 1);  // g: the same corners, one cell over
    for (uint32_t a = 0; a < 256; ++a)
      for (uint32_t far = 0; far < 16; ++far) {
        // The cell across: its face g holds a's face f corners; its other four corners from `far`.
        uint32_t b = 0;
        for (int k = 0; k < 4; ++k) b |= ((a >> f.corner[k]) & 1u) << g.corner[k];
        for (int k = 0; k < 4; ++k) b |= ((far >> k) & 1u) << cell_face(face).corner[k];
        if (!tunnel_through_face(a, face) || !tunnel_through_face(b, face ^ 1)) continue;
        ++both_tunnels;
        ASSERT_TRUE(one_component(a, face, 0) && one_component(b, face ^ 1, 0)) << a << " " << b;
        EXPECT_FALSE(one_component(a, face, 1u << face)) << "pattern " << a << " face " << face;
        EXPECT_FALSE(one_component(b, face ^ 1, 1u << (face ^ 1))) << "pattern " << b << " face " << (face ^ 1);
      }
  }
  EXPECT_GT(both_tunnels, 0);
}

TEST(MeshingCell, LoopsAreTheComponentsInOrder) {
  for (uint32_t mask = 0; mask < 256; ++mask) {
    const CellComponents parts = cell_components(mask);
    const CellLoops loops = cell_loops(mask);
    ASSERT_EQ(loops.count, parts.count) << "pattern " << mask;
    int first = 0, seen = 0;
    for (int l = 0; l < loops.count; ++l) {
      const int n = loops.length[l];
      ASSERT_GE(n, 3) << "pattern " << mask;
      const int component = parts.of_edge[loops.edge[first]];
      for (int k = 0; k < n; ++k) {
        const int e = loops.edge[first + k], next = loops.edge[first + (k + 1) % n];
        EXPECT_EQ(parts.of_edge[e], component) << "pattern " << mask << ": a loop crosses components";
        EXPECT_TRUE(share_a_face(e, next)) << "pattern " << mask << ": consecutive edges " << e << ", " << next;
      }
      first += n;
      seen += n;
    }
    int crossed = 0;
    for (int e = 0; e < kCellEdges; ++e) crossed += parts.of_edge[e] >= 0;
    EXPECT_EQ(seen, crossed) << "pattern " << mask;
  }
}

TEST(MeshingCell, EdgeNumberingIsConsistent) {
  for (int e = 0; e < kCellEdges; ++e) {
    const int c = edge_corner(e);
    EXPECT_EQ((c >> edge_axis(e)) & 1, 0);
    EXPECT_EQ(corner_edge(c, edge_axis(e)), e);
  }
}

// ---------------------------------------------------------------------------------------------
// The QEF on known configurations.

dvec3 solve_planes(const std::vector<std::pair<dvec3, dvec3>>& planes, const dvec3& lo = dvec3(0.0),
                   const dvec3& hi = dvec3(1.0)) {
  Qef q;
  for (const auto& [p, n] : planes) q.add(p, glm::normalize(n));
  return solve_qef(q, lo, hi);
}

TEST(MeshingOptions, MethodsAndAttributesByName) {
  // The names the programs and the Python module take: each finds its own method, others none.
  for (MeshingMethod m : {MeshingMethod::kDualContouring, MeshingMethod::kMarchingCubes}) {
    MeshingMethod found =
        m == MeshingMethod::kDualContouring ? MeshingMethod::kMarchingCubes : MeshingMethod::kDualContouring;
    ASSERT_TRUE(meshing_method_named(meshing_method_name(m), found)) << meshing_method_name(m);
    EXPECT_EQ(found, m);
  }
  EXPECT_STREQ(meshing_method_name(MeshingMethod::kMarchingCubes), "mc");
  MeshingMethod untouched = MeshingMethod::kMarchingCubes;
  for (const char* other : {"", "DC", "dual", "mc ", "m"}) {
    EXPECT_FALSE(meshing_method_named(other, untouched)) << other;
    EXPECT_EQ(untouched, MeshingMethod::kMarchingCubes);
  }
  EXPECT_EQ(mesh_attribute_named("uv"), uint32_t(kAttributeUv));
  EXPECT_EQ(mesh_attribute_named("colour"), 0u);
}

TEST(MeshingQef, ThreePlanesMeetAtTheCorner) {
  const dvec3 corner(0.3, 0.6, 0.45);
  const dvec3 x = solve_planes({{corner + dvec3(0, 0.2, 0.1), {1, 0, 0}},
                                {corner + dvec3(0.3, 0, -0.2), {0, 1, 0}},
                                {corner + dvec3(-0.1, 0.3, 0), {0, 0, 1}},
                                {corner + dvec3(0, -0.3, 0.2), {1, 0, 0}}});
  EXPECT_NEAR(glm::length(x - corner), 0.0, 1e-9);
}

TEST(MeshingQef, TwoPlanesGiveTheCreaseNearestTheMassPoint) {
  // Planes x = 0.5 and y = 0.4 (crease along z); the points' mean z is 0.3.
  const dvec3 x = solve_planes({{{0.5, 0.1, 0.2}, {1, 0, 0}},
                                {{0.5, 0.9, 0.4}, {1, 0, 0}},
                                {{0.2, 0.4, 0.1}, {0, 1, 0}},
                                {{0.8, 0.4, 0.5}, {0, 1, 0}}});
  EXPECT_NEAR(x.x, 0.5, 1e-9);
  EXPECT_NEAR(x.y, 0.4, 1e-9);
  EXPECT_NEAR(x.z, 0.3, 1e-9);
}

TEST(MeshingQef, NearParallelNormalsStayNearTheMassPoint) {
  // A gently curved patch: two points at z = 0.5 with normals tilted 1 and 2 degrees. Their
  // planes meet at x = 1.4, far outside the cell; the full solve would go there (clamped to the
  // face x = 1). Truncated, the nearly free direction is left at the mass point: the vertex
  // moves only along the normals, by their planes' mean offset (about 0.003).
  const double a = 1.0 * kPi / 180.0, b = 2.0 * kPi / 180.0;
  const dvec3 x = solve_planes(
      {{{0.2, 0.5, 0.5}, {std::sin(a), 0, std::cos(a)}}, {{0.8, 0.5, 0.5}, {std::sin(b), 0, std::cos(b)}}});
  EXPECT_NEAR(x.x, 0.5, 1e-3);
  EXPECT_NEAR(x.y, 0.5, 1e-12);
  EXPECT_NEAR(x.z, 0.5, 5e-3);
}

TEST(MeshingQef, ParallelPlanesAndOnePointAndTheClamp) {
  // Two parallel planes z = 0.2 and z = 0.6 (one component cannot hold both, but the solve must
  // stay finite): between them, at the mass point's x, y.
  const dvec3 x = solve_planes({{{0.2, 0.3, 0.2}, {0, 0, 1}}, {{0.6, 0.5, 0.6}, {0, 0, 1}}});
  EXPECT_NEAR(x.x, 0.4, 1e-9);
  EXPECT_NEAR(x.y, 0.4, 1e-9);
  EXPECT_NEAR(x.z, 0.4, 1e-9);
  const dvec3 one = solve_planes({{{0.7, 0.1, 0.9}, {0, 1, 0}}});
  EXPECT_NEAR(glm::length(one - dvec3(0.7, 0.1, 0.9)), 0.0, 1e-12);
  // Planes meeting at (2, 0.5, 0.5), outside the cell: clamped into it.
  const dvec3 c =
      solve_planes({{{0.0, 0.5, 0.5}, {1, 1, 0}}, {{0.0, 0.5, 0.5}, {1, -1, 0}}, {{0.5, 0.5, 0.5}, {0, 0, 1}}});
  EXPECT_GE(c.x, 0.0);
  EXPECT_LE(c.x, 1.0);
}

TEST(MeshingQef, ACreaseLeavingTheCellIsFollowedInsideIt) {
  // Planes y = x + 0.9 and z = 0.5: their crease cuts the cell's corner near (0, 1), from (0, 0.9)
  // to (0.1, 1). The mass point (0.5, 0.85, 0.5) projects onto it at (0.275, 1.175), outside;
  // clamping would leave the vertex 0.25 off the crease; following the crease gives its end in
  // the cell nearest that projection.
  const double s = std::sqrt(0.5);
  const dvec3 x = solve_planes({{{0.05, 0.95, 0.3}, {s, -s, 0}},
                                {{0.05, 0.95, 0.7}, {s, -s, 0}},
                                {{1.0, 0.5, 0.5}, {0, 0, 1}},
                                {{0.9, 1.0, 0.5}, {0, 0, 1}}});
  EXPECT_NEAR(glm::length(x - dvec3(0.1, 1.0, 0.5)), 0.0, 1e-9);
}

TEST(MeshingQef, EigenDecompositionReconstructsTheMatrix) {
  std::mt19937 g(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int k = 0; k < 100; ++k) {
    const Sym3<double> a{u(g), u(g), u(g), u(g), u(g), u(g)};
    double lambda[3];
    dvec3 v[3];
    symmetric_eigen(a, lambda, v);
    for (int i = 0; i < 3; ++i) {
      const dvec3 av = a.apply(v[i]);
      EXPECT_NEAR(glm::length(av - lambda[i] * v[i]), 0.0, 1e-10);
      EXPECT_NEAR(glm::length(v[i]), 1.0, 1e-12);
    }
  }
}

// The corner pass's shared ray: every point of a line gets the w that winding_number_crossing
// gives it alone (which tests/field/test_crossing_winding.cpp checks against the brute force).
TEST(MeshingCorners, WindingAlongAnAxisIsEachPointsOwn) {
  for (const char* name : {"bunny_holes.obj", "bunny.obj", "teapot.obj"}) {
    const GwnModel model = test::build_model(test::load_test_mesh(name));
    const ModelView view = model.view();
    test::Random random(11);
    const Aabb box = model.bounds();
    for (int line = 0; line < 300; ++line) {
      const int axis = random.index(3);
      const float sign = random.index(2) ? 1.0f : -1.0f;
      const float step = 0.02f * glm::length(box.hi - box.lo);
      vec3 points[8];
      points[0] = random.in_box(box);
      for (int k = 1; k < 8; ++k) {
        points[k] = points[0];
        points[k][axis] += sign * step * float(k);
      }
      float w[8];
      winding_numbers_along_axis(view, points, axis, sign, w);
      for (int k = 0; k < 8; ++k) {
        const float alone = winding_number_crossing<false, false>(view, points[k]).w;
        EXPECT_NEAR(w[k], alone, 2e-6f) << name << " line " << line;
      }
    }
  }
}

// The corner pass's screened values: the same side of the level as the exact w, whatever the
// level, also levels within a hair of w itself.
TEST(MeshingCorners, ScreenedValuesHaveTheExactSigns) {
  for (const char* name : {"bunny_holes.obj", "teapot.obj"}) {
    const GwnModel model = test::build_model(test::load_test_mesh(name));
    const ModelView view = model.view();
    test::Random random(5);
    const Aabb box = model.bounds();
    int screened = 0;
    for (int line = 0; line < 300; ++line) {
      const int axis = random.index(3);
      const float sign = random.index(2) ? 1.0f : -1.0f;
      vec3 points[8];
      points[0] = random.in_box(box);
      for (int k = 1; k < 8; ++k) {
        points[k] = points[0];
        points[k][axis] += sign * 0.01f * glm::length(box.hi - box.lo) * float(k);
      }
      float exact[8];
      for (int k = 0; k < 8; ++k) exact[k] = winding_number_crossing<false, false>(view, points[k]).w;
      for (const float level : {0.5f, exact[3] + 1e-4f, exact[5] - 1e-3f, exact[0] + 0.015f}) {
        float w[8];
        corner_winding_values(view, points, axis, sign, level, w);
        for (int k = 0; k < 8; ++k) {
          EXPECT_EQ(w[k] > level, exact[k] > level) << name << " line " << line << " level " << level;
          screened += w[k] != exact[k];
        }
      }
    }
    EXPECT_GT(screened, 1000) << name << ": the screen was never used";
  }
}

// ---------------------------------------------------------------------------------------------
// Whole meshes.

// Closed, manifold (edges and vertices) and consistently oriented, by the quality report's
// topology (tests/meshing/test_mesh_quality.cpp checks it on analytic cases); with up to
// `degenerate_allowed` zero-area triangles (whose edges still count).
void expect_closed_oriented(const SurfaceMesh& m, const std::string& what, uint64_t degenerate_allowed = 0) {
  MeshTopology t;
  ASSERT_TRUE(mesh_topology(m, t).ok()) << what;
  EXPECT_EQ(t.boundary_edges, 0u) << what;
  EXPECT_EQ(t.non_manifold_edges, 0u) << what;
  EXPECT_EQ(t.non_manifold_vertices, 0u) << what;
  EXPECT_EQ(t.inconsistent_edges, 0u) << what;
  EXPECT_LE(t.degenerate_triangles, degenerate_allowed) << what;
  EXPECT_EQ(t.unreferenced_vertices, 0u) << what;
}

void expect_no_self_intersections(const SurfaceMesh& m, const std::string& what) {
  uint64_t count = 0;
  ASSERT_TRUE(count_self_intersections(m, count).ok()) << what;
  EXPECT_EQ(count, 0u) << what << ": triangle pairs that intersect";
}

Mesh as_mesh(const SurfaceMesh& m) {
  Mesh out;
  out.positions = m.positions;
  out.triangles = m.triangles;
  return out;
}

MeshingOptions options_at(uint32_t resolution) {
  MeshingOptions o;
  o.resolution = resolution;
  return o;
}

TEST(Meshing, FarFromTheOriginTheGridStaysOffTheFaces) {
  // The unit tetrahedron at 1e4 (float steps there are 1e-3): the box's 1e-4 padding fell below
  // one step, the grid centred on it put corners exactly on the faces, and every resolution gave
  // zero-area triangles (16 at 8 cells, 92 at 32). Now as at the origin: none, the same counts.
  Mesh tet;
  tet.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  tet.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  Mesh far = tet;
  for (vec3& p : far.positions) p += vec3(1e4f);
  const GwnModel near_model = test::build_model(tet), far_model = test::build_model(far);
  for (const uint32_t resolution : {8u, 32u}) {
    SurfaceMesh near_out, far_out;
    ASSERT_TRUE(extract_surface(near_model, options_at(resolution), near_out).ok());
    ASSERT_TRUE(extract_surface(far_model, options_at(resolution), far_out).ok());
    EXPECT_EQ(far_out.triangles.size(), near_out.triangles.size()) << resolution;
    size_t degenerate = 0;
    for (const uvec3& t : far_out.triangles)
      degenerate += is_degenerate_triangle(far_out.positions[t.x], far_out.positions[t.y], far_out.positions[t.z]);
    EXPECT_EQ(degenerate, 0u) << resolution;
  }
}

TEST(Meshing, SphereIsClosedOutwardAndOnS) {
  Mesh sphere = test::make_sphere(5);
  const Mesh reference = sphere;
  const GwnModel model = test::build_model(std::move(sphere));
  SurfaceMesh out;
  MeshingStats stats;
  ASSERT_TRUE(extract_surface(model, options_at(40), out, &stats).ok());
  ASSERT_GT(out.triangles.size(), 1000u);
  expect_closed_oriented(out, "sphere");
  expect_no_self_intersections(out, "sphere");
  EXPECT_EQ(stats.open_edges, 0u);
  double worst = 0, worst_angle = 0;
  for (size_t i = 0; i < out.positions.size(); ++i) {
    // Every 8th vertex against the polyhedron by brute force (all 20480 triangles each).
    if (i % 8 == 0) worst = std::max(worst, reference::mesh_distance(reference, dvec3(out.positions[i])));
    const vec3 radial = glm::normalize(out.positions[i]);
    worst_angle = std::max(worst_angle, double(std::acos(std::min(1.0f, glm::dot(radial, out.normals[i])))));
  }
  EXPECT_LT(worst, 0.05 * stats.cell_size);
  EXPECT_LT(worst_angle, 2.0 * kPi / 180.0);
  // Outward: the enclosed volume is positive.
  double volume = 0;
  for (const uvec3& t : out.triangles)
    volume +=
        glm::dot(dvec3(out.positions[t[0]]), glm::cross(dvec3(out.positions[t[1]]), dvec3(out.positions[t[2]]))) / 6.0;
  EXPECT_NEAR(volume, 4.0 / 3.0 * kPi, 0.02 * 4.0 / 3.0 * kPi);
}

// The output's own winding number at x (brute force in double): 1 inside a closed outward mesh.
double output_winding(const SurfaceMesh& m, const dvec3& x) {
  return reference::reference_w(reference::reference_mesh(as_mesh(m)), x);
}

// A rotation taking +z to (1, 1, 1)/√3 (and x, y to an orthonormal pair): faces no longer
// aligned with the grid.
Mesh transformed(Mesh m, const glm::dmat3& r, const dvec3& shift, double scale = 1.0) {
  for (vec3& p : m.positions) p = vec3(r * (dvec3(p) * scale) + shift);
  return m;
}

glm::dmat3 diagonal_rotation() {
  const dvec3 z = glm::normalize(dvec3(1, 1, 1));
  const dvec3 x = glm::normalize(glm::cross(dvec3(0, 1, 0), z));
  const dvec3 y = glm::cross(z, x);
  return glm::dmat3(x, y, z);  // columns: the images of e_x, e_y, e_z
}

Mesh join(Mesh a, const Mesh& b) {
  const uint32_t base = uint32_t(a.positions.size());
  a.positions.insert(a.positions.end(), b.positions.begin(), b.positions.end());
  for (const uvec3& t : b.triangles) a.triangles.push_back(t + uvec3(base));
  return a;
}

TEST(Meshing, CubeCornersAndEdgesAreSharp) {
  // A cube of side 2 turned off the grid's axes (generic angles) and shifted.
  const glm::dmat3 r = glm::dmat3(glm::rotate(glm::dmat4(1.0), 0.4, glm::normalize(glm::dvec3(1, 2, 3))));
  const dvec3 shift(0.0123, 0.0456, 0.0789);
  const GwnModel model = test::build_model(transformed(test::make_cube(), r, shift));
  SurfaceMesh out;
  MeshingStats stats;
  MeshingOptions o = options_at(24);
  o.smooth_angle = 0.0f;
  ASSERT_TRUE(extract_surface(model, o, out, &stats).ok());
  expect_closed_oriented(out, "cube");
  const double h = stats.cell_size;
  std::vector<dvec3> corners;
  for (int k = 0; k < 8; ++k)
    corners.push_back(r * dvec3((k & 1) ? 1 : -1, (k & 2) ? 1 : -1, (k & 4) ? 1 : -1) + shift);
  for (const dvec3& c : corners) {
    double nearest = 1e30;
    for (const vec3& p : out.positions) nearest = std::min(nearest, glm::length(dvec3(p) - c));
    EXPECT_LT(nearest, 0.1 * h) << "cube corner " << c.x << " " << c.y << " " << c.z;
  }
  // Each edge: there is about one vertex per cell along it whose QEF saw both of its faces (its
  // normal, unsmoothed, the mean of the two faces', far from either). Those of the cells the edge
  // passes through lie on it (within 0.1 cell: the QEF's crease is followed inside the cell).
  // The others belong to cells the edge passes just outside of, where the crease's point is
  // clamped back into the cell (within 0.3 cell: the vertex stays in its cell, and the edge is
  // within a few tenths of a cell of it).
  const dvec3 origin(stats.origin[0], stats.origin[1], stats.origin[2]);
  for (int a = 0; a < 8; ++a)
    for (int axis = 0; axis < 3; ++axis) {
      const int b = a | (1 << axis);
      if (b == a) continue;
      const dvec3 p = corners[a], q = corners[b];
      dvec3 face_normals[2];
      for (int k = 0, axis2 = 0; axis2 < 3; ++axis2) {
        if (axis2 == axis) continue;
        dvec3 n(0.0);
        n[axis2] = ((a >> axis2) & 1) ? 1.0 : -1.0;
        face_normals[k++] = r * n;
      }
      int on_edge = 0, in_crossed_cell = 0;
      double worst = 0, worst_crossed = 0;
      for (size_t i = 0; i < out.positions.size(); ++i) {
        const dvec3 x(out.positions[i]), n(out.normals[i]);
        const double t = glm::dot(x - p, q - p) / glm::dot(q - p, q - p);
        // Beyond 1.5 cells of the corners, whose cells see a third face (and place their vertex at
        // the corner, clamped to the cell).
        const double margin = 1.5 * h / glm::length(q - p);
        if (t < margin || t > 1 - margin || glm::length(closest_point_on_segment(p, q, x).point - x) > h) continue;
        if (glm::dot(n, face_normals[0]) > 0.95 || glm::dot(n, face_normals[1]) > 0.95) continue;
        ++on_edge;
        const double d = glm::length(closest_point_on_segment(p, q, x).point - x);
        worst = std::max(worst, d);
        // The vertex's cell: a clamped vertex lies on its cell's boundary and may belong to any
        // cell there, so it counts only when all of them are crossed.
        const dvec3 c = (x - origin) / h;
        bool crossed = true;
        for (int corner = 0; corner < 8 && crossed; ++corner) {
          const dvec3 nudge = 1e-6 * dvec3((corner & 1) ? 1 : -1, (corner & 2) ? 1 : -1, (corner & 4) ? 1 : -1);
          const dvec3 lo = glm::floor(c + nudge);
          double t0, t1;
          crossed = detail::clip_line_to_box((p - origin) / h, (q - p) / h, lo, lo + 1.0, t0, t1) && t1 >= 0 && t0 <= 1;
        }
        if (!crossed) continue;
        ++in_crossed_cell;
        worst_crossed = std::max(worst_crossed, d);
      }
      EXPECT_GE(in_crossed_cell, 0.5 * on_edge) << "cube edge " << a << "-" << b;
      EXPECT_LT(worst_crossed, 0.1 * h) << "cube edge " << a << "-" << b;
      EXPECT_GT(on_edge, int(0.5 * (2.0 / h - 3.0))) << "cube edge " << a << "-" << b;
      EXPECT_LT(worst, 0.3 * h) << "cube edge " << a << "-" << b;
    }
}

TEST(Meshing, MarchingCubesIsClosedOnSAndCoarserThanDualContouring) {
  // The turned cube: marching cubes cuts its edges and corners (its vertices are the edges'
  // points of S, exact here), dual contouring keeps them, so DC's Chamfer distance to S is lower.
  const glm::dmat3 r = glm::dmat3(glm::rotate(glm::dmat4(1.0), 0.4, glm::normalize(glm::dvec3(1, 2, 3))));
  const Mesh cube = transformed(test::make_cube(), r, dvec3(0.0123, 0.0456, 0.0789));
  const GwnModel model = test::build_model(cube);
  MeshingOptions o = options_at(24);
  SurfaceMesh dc, mc;
  MeshingStats stats;
  ASSERT_TRUE(extract_surface(model, o, dc).ok());
  o.method = MeshingMethod::kMarchingCubes;
  ASSERT_TRUE(extract_surface(model, o, mc, &stats).ok());
  expect_closed_oriented(mc, "marching cubes, cube");
  expect_no_self_intersections(mc, "marching cubes, cube");
  for (const vec3& p : mc.positions) EXPECT_LT(reference::mesh_distance(cube, dvec3(p)), 1e-5 * stats.cell_size);
  SurfaceDistanceOptions d;
  d.output_samples = 20000;
  d.surface_rays = 20000;
  SurfaceDistances dc_d, mc_d;
  ASSERT_TRUE(surface_distances(model, dc, d, dc_d).ok());
  ASSERT_TRUE(surface_distances(model, mc, d, mc_d).ok());
  EXPECT_LT(dc_d.chamfer, mc_d.chamfer);
  EXPECT_LT(dc_d.hausdorff_from_surface, mc_d.hausdorff_from_surface);
  // On bunny_holes too: closed, manifold, intersection-free.
  const GwnModel holes = test::build_model(test::load_test_mesh("bunny_holes.obj"));
  SurfaceMesh out;
  ASSERT_TRUE(extract_surface(holes, o, out).ok());
  expect_closed_oriented(out, "marching cubes, bunny_holes");
  expect_no_self_intersections(out, "marching cubes, bunny_holes");
}

TEST(Meshing, OpenHemisphereIsClosedByItsFlatCap) {
  const double z0 = 0.0137;
  // test::make_hemisphere's rim lies in z = 0: on its disk w = 1/2 exactly (the shell covers half
  // the directions), so S's cap is that disk, here moved to z = z0 off the grid's planes.
  const GwnModel model =
      test::build_model(transformed(test::make_hemisphere(24, 64), glm::dmat3(1.0), dvec3(0, 0, z0)));
  SurfaceMesh out;
  MeshingStats stats;
  ASSERT_TRUE(extract_surface(model, options_at(48), out, &stats).ok());
  expect_closed_oriented(out, "hemisphere");
  expect_no_self_intersections(out, "hemisphere");
  EXPECT_GT(stats.smooth_edges, 100u);
  const double h = stats.cell_size;
  size_t cap = 0;
  double worst = 0;
  for (size_t i = 0; i < out.positions.size(); ++i) {
    const dvec3 p(out.positions[i]);
    const double r = std::hypot(p.x, p.y);
    if (r >= 0.9 || p.z > z0 + 0.3) continue;  // the rim's neighbourhood and the shell (r > 0.95 below z0 + 0.3)
    ++cap;
    worst = std::max(worst, std::abs(p.z - z0));
    EXPECT_LT(out.normals[i].z, -0.99f) << "cap normal points down, out of the half-ball";
  }
  EXPECT_GT(cap, 100u);
  EXPECT_LT(worst, 0.05 * h);
}

// A point on S along the line from `from` toward `to` (w − 1/2 changes sign between them),
// found by bisection on the model's exact w: with the side it is inside.
dvec3 surface_point_between(const GwnModel& model, dvec3 from, dvec3 to) {
  const reference::ReferenceMesh ref = reference::reference_mesh(model.mesh());
  const bool from_inside = reference::reference_w(ref, from) > 0.5;
  EXPECT_NE(from_inside, reference::reference_w(ref, to) > 0.5);
  for (int k = 0; k < 60; ++k) {
    const dvec3 mid = 0.5 * (from + to);
    ((reference::reference_w(ref, mid) > 0.5) == from_inside ? from : to) = mid;
  }
  return 0.5 * (from + to);
}

TEST(Meshing, BunnyWithHolesIsClosedAndCapped) {
  const GwnModel model = test::build_model(test::load_test_mesh("bunny_holes.obj"));
  uint32_t loop_count = 0;
  const std::vector<uint32_t> loop = boundary_loops(model.boundary(), loop_count);
  ASSERT_EQ(loop_count, 2u);
  for (uint32_t resolution : {64u, 128u, 256u}) {
    SurfaceMesh out;
    MeshingStats stats;
    ASSERT_TRUE(extract_surface(model, options_at(resolution), out, &stats).ok());
    const std::string what = "bunny_holes at " + std::to_string(resolution);
    expect_closed_oriented(out, what);
    expect_no_self_intersections(out, what);
    EXPECT_EQ(stats.open_edges, 0u) << what;
    EXPECT_GT(stats.smooth_edges, 0u) << what;
    const double h = stats.cell_size;
    // Under each hole: the cap crosses the line through the loop's centre along its normal.
    for (uint32_t l = 0; l < loop_count; ++l) {
      dvec3 centre(0.0), normal(0.0);
      int n = 0;
      const auto& e = model.boundary().endpoints;
      for (size_t s = 0; s < loop.size(); ++s)
        if (loop[s] == l) {
          centre += dvec3(e[2 * s]);
          ++n;
        }
      centre /= double(n);
      for (size_t s = 0; s < loop.size(); ++s)  // the loop's vector area
        if (loop[s] == l) normal += glm::cross(dvec3(e[2 * s]) - centre, dvec3(e[2 * s + 1]) - centre);
      normal = glm::normalize(normal);
      const double reach = 0.3 * glm::length(dvec3(model.bounds().hi - model.bounds().lo));
      dvec3 a = centre - reach * normal, b = centre + reach * normal;
      const reference::ReferenceMesh ref = reference::reference_mesh(model.mesh());
      // The point nearest the centre where S crosses the line.
      const int samples = 400;
      double best = 1e30;
      dvec3 hit(0.0);
      for (int k = 0; k < samples; ++k) {
        const dvec3 p = a + (b - a) * (double(k) / samples), q = a + (b - a) * (double(k + 1) / samples);
        if ((reference::reference_w(ref, p) > 0.5) == (reference::reference_w(ref, q) > 0.5)) continue;
        const dvec3 x = surface_point_between(model, p, q);
        if (glm::length(x - centre) < best) {
          best = glm::length(x - centre);
          hit = x;
          a = p;
          b = q;
        }
      }
      ASSERT_LT(best, 1e29) << what << " loop " << l;
      const dvec3 step = glm::normalize(b - a) * (3.0 * h);
      const bool forward_inside = reference::reference_w(ref, hit + step) > 0.5;
      const dvec3 inside = forward_inside ? hit + step : hit - step, outside = forward_inside ? hit - step : hit + step;
      EXPECT_NEAR(output_winding(out, inside), 1.0, 1e-6) << what << " loop " << l << ": inside S under the cap";
      EXPECT_NEAR(output_winding(out, outside), 0.0, 1e-6) << what << " loop " << l << ": outside S over the cap";
    }
  }
}

TEST(Meshing, TwoSheetsInOneCellStayApartAndManifold) {
  // Faces perpendicular to (1,1,1): a cell spans √3 cells across them, so a slab or a gap 1.5
  // cells thick can lie inside one cell's span with corners outside it on both sides (two
  // components, two vertices). Whether it does depends on where the grid falls, which follows
  // the box: a small far tetrahedron moved along x shifts the grid by fractions of a cell.
  const glm::dmat3 r = diagonal_rotation();
  const double h = 2.0 / 20.0;
  const dvec3 centre(0.013, 0.021, 0.0);
  const Mesh slab = transformed(test::make_cube(), glm::dmat3(r[0], r[1], r[2] * (0.75 * h)), centre);
  const Mesh boxes = join(transformed(test::make_cube(), r, r * dvec3(0, 0, -1.0 - 0.75 * h) + centre),
                          transformed(test::make_cube(), r, r * dvec3(0, 0, 1.0 + 0.75 * h) + centre));
  struct Case {
    const char* name;
    Mesh mesh;
    std::vector<std::pair<dvec3, double>> probes;  // point, the output's expected w there
  };
  const std::vector<Case> cases = {
      {"slab", slab, {{centre, 1.0}, {centre + r * dvec3(0, 0, 1.5 * h), 0.0}}},
      {"two boxes",
       boxes,
       {{centre, 0.0}, {centre + r * dvec3(0, 0, 1.0), 1.0}, {centre - r * dvec3(0, 0, 1.0), 1.0}}}};
  for (const Case& c : cases) {
    uint64_t two_vertex_cells = 0;
    for (int k = 0; k < 8; ++k) {
      const Mesh anchor = transformed(test::make_cube(), glm::dmat3(0.05), dvec3(4.0 + 0.25 * h * k, 0, 0));
      const GwnModel model = test::build_model(join(c.mesh, anchor));
      MeshingOptions o;
      o.cell_size = float(h);
      SurfaceMesh out;
      MeshingStats stats;
      ASSERT_TRUE(extract_surface(model, o, out, &stats).ok()) << c.name;
      const std::string what = std::string(c.name) + ", shift " + std::to_string(k);
      // A few triangles come out with zero area here (at most 5 per run measured; not yet traced
      // to their cause); they do not open the mesh.
      expect_closed_oriented(out, what, out.triangles.size() / 200);
      two_vertex_cells += stats.multi_component_cells;
      for (const auto& [p, w] : c.probes) EXPECT_NEAR(output_winding(out, p), w, 1e-6) << what;
    }
    EXPECT_GT(two_vertex_cells, 10u) << c.name << ": no grid placement put both sheets in one cell";
  }
}

TEST(Meshing, SoupGivesTheIndexedMeshesOutput) {
  const Mesh indexed = test::load_test_mesh("bunny.obj");
  Mesh soup;
  for (const uvec3& t : indexed.triangles) {
    const uint32_t base = uint32_t(soup.positions.size());
    for (int k = 0; k < 3; ++k) soup.positions.push_back(indexed.positions[t[k]]);
    soup.triangles.push_back({base, base + 1, base + 2});
  }
  const GwnModel a = test::build_model(indexed), b = test::build_model(std::move(soup));
  SurfaceMesh out_a, out_b;
  ASSERT_TRUE(extract_surface(a, options_at(64), out_a).ok());
  ASSERT_TRUE(extract_surface(b, options_at(64), out_b).ok());
  ASSERT_EQ(out_a.positions.size(), out_b.positions.size());
  ASSERT_EQ(out_a.triangles.size(), out_b.triangles.size());
  for (size_t i = 0; i < out_a.positions.size(); ++i)
    ASSERT_LT(glm::length(out_a.positions[i] - out_b.positions[i]), 1e-6f) << "vertex " << i;
  for (size_t i = 0; i < out_a.triangles.size(); ++i) ASSERT_EQ(out_a.triangles[i], out_b.triangles[i]);
}

TEST(Meshing, SoupOutputHasThreeVerticesPerTriangleAndTheSameSurface) {
  const GwnModel model = test::build_model(test::load_test_mesh("bunny.obj"));
  SurfaceMesh indexed, soup;
  MeshingOptions o = options_at(48);
  o.attributes = kAttributeSource;
  ASSERT_TRUE(extract_surface(model, o, indexed).ok());
  o.soup = true;
  ASSERT_TRUE(extract_surface(model, o, soup).ok());
  ASSERT_EQ(soup.triangles.size(), indexed.triangles.size());
  ASSERT_EQ(soup.positions.size(), 3 * indexed.triangles.size());
  ASSERT_EQ(soup.source_triangles.size(), soup.positions.size());
  for (size_t f = 0; f < soup.triangles.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(soup.triangles[f][k], 3 * f + k);
      EXPECT_EQ(soup.positions[3 * f + k], indexed.positions[indexed.triangles[f][k]]);
      EXPECT_EQ(soup.source_triangles[3 * f + k], indexed.source_triangles[indexed.triangles[f][k]]);
    }
}

TEST(Meshing, SourceTriangleIsTheNearest) {
  const Mesh mesh = test::load_test_mesh("bunny.obj");
  const GwnModel model = test::build_model(mesh);
  MeshingOptions o = options_at(32);
  o.attributes = kAttributeSource;
  SurfaceMesh out;
  ASSERT_TRUE(extract_surface(model, o, out).ok());
  ASSERT_EQ(out.source_triangles.size(), out.positions.size());
  for (size_t i = 0; i < out.positions.size(); i += 7) {
    const dvec3 x(out.positions[i]);
    const double best = reference::mesh_distance(mesh, x);
    const uint32_t t = out.source_triangles[i];
    ASSERT_LT(t, mesh.triangles.size());
    EXPECT_NEAR(reference::triangle_distance(mesh, t, x), best, 1e-5 * (1 + best));
    const uvec3 tri = mesh.triangles[t];
    const glm::vec2 uv = out.source_barycentrics[i];
    const dvec3 on = (1.0 - uv.x - uv.y) * dvec3(mesh.positions[tri[0]]) +
                     double(uv.x) * dvec3(mesh.positions[tri[1]]) + double(uv.y) * dvec3(mesh.positions[tri[2]]);
    EXPECT_NEAR(glm::length(on - x), best, 1e-4 * (1 + best));
  }
}

// compare_triangles (gwnrt-consistency and the CUDA tests compare the backends' meshes by it): a
// mesh against itself with some quads split along their other diagonal, one triangle changed, one
// quad turned inside out (the same corners, the other orientation) and one triangle dropped.
TEST(MeshComparison, TellsResplitQuadsFromOtherChanges) {
  const GwnModel model = test::build_model(test::load_test_mesh("bunny_holes.obj"));
  MeshingOptions options;
  options.resolution = 48;
  SurfaceMesh mesh;
  ASSERT_TRUE(extract_surface(model, options, mesh).ok());
  const std::vector<uvec3>& a = mesh.triangles;
  ASSERT_GT(a.size(), 1000u);
  EXPECT_EQ(compare_triangles(a, a).same, a.size());
  std::vector<uvec3> b = a;
  std::vector<bool> was_resplit(a.size() / 2, false);
  size_t resplit = 0;
  for (size_t q = 0; 2 * q + 1 < b.size(); q += 7) {
    // The dual contouring writes quad q as triangles 2q, 2q + 1 over a diagonal: the corners
    // (v0 v1 v2 v3) in order around it are recovered and split along the other diagonal.
    const uvec3 x = b[2 * q], y = b[2 * q + 1];
    if (x[0] == y[0] && x[2] == y[1]) {  // (0,1,2), (0,2,3) -> (0,1,3), (1,2,3)
      b[2 * q] = {x[0], x[1], y[2]};
      b[2 * q + 1] = {x[1], x[2], y[2]};
    } else if (x[1] == y[0] && x[2] == y[2]) {  // (0,1,3), (1,2,3) -> (0,1,2), (0,2,3)
      b[2 * q] = {x[0], x[1], y[1]};
      b[2 * q + 1] = {x[0], y[1], y[2]};
    } else {
      continue;
    }
    was_resplit[q] = true;
    ++resplit;
  }
  ASSERT_GT(resplit, a.size() / 20);
  TriangleComparison c = compare_triangles(a, b);
  EXPECT_EQ(c.resplit, resplit);
  EXPECT_EQ(c.same, a.size() - 2 * resplit);
  EXPECT_TRUE(c.equal_up_to_splits());
  // A changed corner (quad 7 otherwise as in a), and quad 14 turned inside out, are differences.
  b[2 * 7] = a[2 * 7];
  b[2 * 7 + 1] = a[2 * 7 + 1];
  b[2 * 7][0] = a[2 * 7][0] + 1;
  std::swap(b[2 * 14][1], b[2 * 14][2]);
  std::swap(b[2 * 14 + 1][1], b[2 * 14 + 1][2]);
  c = compare_triangles(a, b);
  EXPECT_FALSE(c.equal_up_to_splits());
  EXPECT_EQ(c.resplit, resplit - was_resplit[7] - was_resplit[14]);
  EXPECT_EQ(c.different, 3u) << "the changed triangle and both halves of the inverted quad";
  // Triangles one list has beyond the other.
  const std::vector<uvec3> shorter(a.begin(), a.end() - 1);
  c = compare_triangles(a, shorter);
  EXPECT_EQ(c.same, a.size() - 1);
  EXPECT_EQ(c.different, 1u);
}

TEST(Meshing, BadOptionsAreRefusedWithTheReason) {
  const GwnModel model = test::build_model(test::load_test_mesh("bunny.obj"));
  SurfaceMesh out;
  MeshingOptions o = options_at(0);
  Status s = extract_surface(model, o, out);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("resolution"), std::string::npos) << s.message();
  o = options_at(64);
  o.cell_size = -1.0f;
  s = extract_surface(model, o, out);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("cell size"), std::string::npos) << s.message();
  o.cell_size = std::nanf("");
  EXPECT_FALSE(extract_surface(model, o, out).ok());
  o = options_at(64);
  o.level = 0.0f;
  EXPECT_FALSE(extract_surface(model, o, out).ok());
  o.level = std::nanf("");
  EXPECT_FALSE(extract_surface(model, o, out).ok());
  // Beyond the grid's limits, and beyond the memory budget: refused with the size it needs.
  o = options_at(4000000000u);
  s = extract_surface(model, o, out);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("cells along an axis"), std::string::npos) << s.message();
  o = options_at(256);
  o.memory_budget = 1u << 20;
  s = extract_surface(model, o, out);
  EXPECT_EQ(s.code(), StatusCode::kOutOfMemory);
  EXPECT_NE(s.message().find("needs at least"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("beyond the memory budget of 1.0 MiB"), std::string::npos) << s.message();
  EXPECT_TRUE(out.positions.empty() && out.triangles.empty());
  // A budget below a MiB is said as it is (it was rounded up to "1 MiB", as was what it needs).
  o.memory_budget = 1000;
  s = extract_surface(model, o, out);
  EXPECT_NE(s.message().find("beyond the memory budget of 1000 B"), std::string::npos) << s.message();
  // A grid whose block map alone is beyond the budget is refused before scouting (at 20000 cells
  // scouting took 18 s and 1.3 GB before the refusal, at 100000 over a minute).
  o = options_at(20000);
  MeshingStats stats;
  s = extract_surface(model, o, out, &stats);
  EXPECT_EQ(s.code(), StatusCode::kOutOfMemory);
  EXPECT_NE(s.message().find("(the block map)"), std::string::npos) << s.message();
  EXPECT_EQ(stats.active_blocks, 0u);
}

TEST(Meshing, EmptySurfaceGivesAnEmptyMeshAndSaysSo) {
  const GwnModel model = test::build_model(test::load_test_mesh("bunny.obj"));
  MeshingOptions o = options_at(64);
  o.level = 1.5f;  // w <= 1 everywhere for a closed mesh
  SurfaceMesh out;
  MeshingStats stats;
  ASSERT_TRUE(extract_surface(model, o, out, &stats).ok());
  EXPECT_TRUE(out.positions.empty());
  EXPECT_TRUE(out.triangles.empty());
  EXPECT_FALSE(stats.message.empty());
}

// gwnrt-mesh as a subprocess: it writes what the library gives, and refuses what it cannot do.
class MeshCliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    binary_ = test::program_binary("gwnrt-mesh");
    if (binary_.empty()) GTEST_SKIP() << "gwnrt-mesh not built next to the tests (expected <build>/bin/gwnrt-mesh)";
  }
  std::string binary_;
};

TEST_F(MeshCliTest, WritesTheLibrarysMesh) {
  const std::string out = test::temp_path("bunny_mesh.ply");
  const test::RunResult r = test::run_program(
      binary_, test::quote(test::data_path("bunny.obj")) + " -o " + test::quote(out) + " --resolution 40 -v");
  ASSERT_TRUE(r.exited && r.exit_code == 0) << r.err;
  EXPECT_NE(r.err.find("triangles"), std::string::npos) << r.err;
  Mesh read;
  ASSERT_TRUE(load_mesh(out, read).ok());
  const GwnModel model = test::build_model(test::load_test_mesh("bunny.obj"));
  SurfaceMesh lib;
  ASSERT_TRUE(extract_surface(model, options_at(40), lib).ok());
  ASSERT_EQ(read.positions.size(), lib.positions.size());
  ASSERT_EQ(read.triangles.size(), lib.triangles.size());
  for (size_t i = 0; i < lib.positions.size(); ++i) ASSERT_EQ(read.positions[i], lib.positions[i]);
}

// A georeferenced scan (the bunny moved to UTM metres, where float steps by 0.25): gwnrt-mesh meshes
// it about its own centre and writes it back where it lies, in double. The library's mesh of the
// bunny at the origin, moved there in double, is the reference: the two models differ by float
// rounding of coordinates about 10 across, as the CPU's and the GPU's results do, so the CUDA
// comparison's tolerances hold: vertices within 2e-3 cells, 90% within 1e-5 cells, a flat quad
// maybe split the other way (measured: worst 5.2e-5 cells, 99.5% within 1e-5, 2 quads resplit).
TEST_F(MeshCliTest, MeshesAScanFarFromTheOriginWhereItLies) {
  const dvec3 offset(512345.678, 4123456.789, 123.25);
  const Mesh near_mesh = test::load_test_mesh("bunny.obj");
  std::string text;
  for (const vec3& p : near_mesh.positions) {
    const dvec3 x = dvec3(p) + offset;
    text += "v " + test::num(x.x) + " " + test::num(x.y) + " " + test::num(x.z) + "\n";
  }
  for (const uvec3& t : near_mesh.triangles)
    text += "f " + std::to_string(t.x + 1) + " " + std::to_string(t.y + 1) + " " + std::to_string(t.z + 1) + "\n";
  const std::string in = test::temp_path("utm_bunny.obj"), out = test::temp_path("utm_bunny_mesh.ply");
  std::ofstream(in, std::ios::binary) << text;
  const test::RunResult r =
      test::run_program(binary_, test::quote(in) + " -o " + test::quote(out) + " --resolution 40 -v");
  ASSERT_TRUE(r.exited && r.exit_code == 0) << r.err;
  EXPECT_NE(r.err.find("far from the origin for its size: computed relative to ("), std::string::npos) << r.err;

  // Read back in double: the file's coordinates are origin + position.
  Mesh read;
  MeshLoadReport report;
  ASSERT_TRUE(load_mesh(out, read, &report, {.recentre = true}).ok());
  SurfaceMesh lib;
  MeshingStats stats;
  ASSERT_TRUE(extract_surface(test::build_model(near_mesh), options_at(40), lib, &stats).ok());
  ASSERT_EQ(read.positions.size(), lib.positions.size());
  const double cell = stats.cell_size;
  double worst = 0;
  size_t within = 0;
  for (size_t i = 0; i < lib.positions.size(); ++i) {
    const double d = glm::length(report.origin + dvec3(read.positions[i]) - (dvec3(lib.positions[i]) + offset));
    worst = std::max(worst, d);
    within += d <= 1e-5 * cell;
  }
  EXPECT_LT(worst, 2e-3 * cell) << "cell " << cell;
  EXPECT_GE(double(within), 0.9 * double(lib.positions.size()));
  const TriangleComparison c = compare_triangles(read.triangles, lib.triangles);
  EXPECT_TRUE(c.equal_up_to_splits()) << c.different << " of " << lib.triangles.size() << " triangles differ";
}

// Issue 17: --device. cuda meshes on the GPU or, without one (or without the CUDA backend built
// in), fails saying why; auto says which it took and writes the CPU's mesh when it took the CPU.
TEST_F(MeshCliTest, DeviceCudaOrAutoSaysWhereItRan) {
  const std::string out = test::temp_path("device_mesh.ply");
  const std::string base = test::quote(test::data_path("bunny.obj")) + " -o " + test::quote(out) + " --resolution 24";
  const test::RunResult cuda = test::run_program(binary_, base + " --device cuda");
  ASSERT_TRUE(cuda.exited);
  if (cuda.exit_code != 0) {
    EXPECT_EQ(cuda.exit_code, 1);
    EXPECT_NE(cuda.err.find("--device cuda: "), std::string::npos) << cuda.err;
  }
  const test::RunResult automatic = test::run_program(binary_, base + " --device auto");
  ASSERT_TRUE(automatic.exited && automatic.exit_code == 0) << automatic.err;
  const bool took_cpu = automatic.err.find("--device auto: the CPU (") != std::string::npos;
  EXPECT_TRUE(took_cpu || automatic.err.find("--device auto: the GPU") != std::string::npos) << automatic.err;
  EXPECT_EQ(took_cpu, cuda.exit_code != 0) << "auto must take the GPU exactly when cuda works";
  Mesh read;
  ASSERT_TRUE(load_mesh(out, read).ok());
  const GwnModel model = test::build_model(test::load_test_mesh("bunny.obj"));
  SurfaceMesh lib;
  ASSERT_TRUE(extract_surface(model, options_at(24), lib).ok());
  ASSERT_EQ(read.triangles.size(), lib.triangles.size());
  if (took_cpu) {
    for (size_t i = 0; i < lib.positions.size(); ++i) ASSERT_EQ(read.positions[i], lib.positions[i]);
  }
}

// UVs and colours from an OBJ (a cube, per-corner vt of six charts, v x y z r g b) to the PLY
// written: the library's transfer, and a clear refusal for a mesh without them.
TEST_F(MeshCliTest, CarriesTheInputsUvsAndColours) {
  const Mesh cube = test::make_cube();
  std::ostringstream obj;
  for (const vec3& p : cube.positions)
    obj << "v " << p.x << ' ' << p.y << ' ' << p.z << ' ' << 0.5 + 0.5 * p.x << " 0.25 " << 0.5 - 0.5 * p.z << '\n';
  for (size_t t = 0; t < cube.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) obj << "vt " << 0.1 * double(t / 2) + 0.01 * k << ' ' << 0.3 * k << '\n';
  for (size_t t = 0; t < cube.triangles.size(); ++t) {
    obj << 'f';
    for (int k = 0; k < 3; ++k) obj << ' ' << cube.triangles[t][k] + 1 << '/' << 3 * t + k + 1;
    obj << '\n';
  }
  const std::string in = test::temp_path("textured_cube.obj"), out = test::temp_path("textured_cube.ply");
  {
    std::ofstream f(in);
    f << obj.str();
  }
  const test::RunResult r = test::run_program(
      binary_, test::quote(in) + " -o " + test::quote(out) + " --resolution 16 --attributes uv,color -v");
  ASSERT_TRUE(r.exited && r.exit_code == 0) << r.err;
  EXPECT_NE(r.err.find("36 UVs, vertex colours"), std::string::npos) << r.err;
  Mesh source, read;
  ASSERT_TRUE(load_mesh(in, source).ok());
  ASSERT_TRUE(load_mesh(out, read).ok());
  MeshingOptions o = options_at(16);
  o.attributes = kAttributeUv | kAttributeColor;
  SurfaceMesh lib;
  ASSERT_TRUE(extract_surface(test::build_model(source), o, lib).ok());
  ASSERT_EQ(read.positions.size(), lib.positions.size());
  ASSERT_EQ(read.uvs.size(), lib.uvs.size());
  ASSERT_EQ(read.colors.size(), lib.colors.size());
  for (size_t i = 0; i < lib.positions.size(); ++i) {
    ASSERT_EQ(read.uvs[i], lib.uvs[i]) << "vertex " << i;
    for (int c = 0; c < 4; ++c) ASSERT_NEAR(read.colors[i][c], lib.colors[i][c], 0.5 / 255 + 1e-6) << "vertex " << i;
  }
  const test::RunResult refused = test::run_program(binary_, test::quote(test::data_path("bunny.obj")) + " -o " +
                                                                 test::quote(out) + " --resolution 16 --attributes uv");
  ASSERT_TRUE(refused.exited);
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.err.find("bunny.obj: meshing: UVs were asked for but the source mesh has no texture coordinates"),
            std::string::npos)
      << refused.err;
}

// Issue 15 item 16: a count or size that must be positive says so, not CLI11's range with a
// 300-digit bound; nan is refused too.
TEST_F(MeshCliTest, PositiveOptionsSayTheyMustBePositive) {
  for (const std::string args : {" --threads 0", " --threads -2", " --cell-size nan", " --cell-size 0"}) {
    const test::RunResult r = test::run_program(
        binary_, test::quote(test::data_path("bunny.obj")) + " -o " + test::quote(test::temp_path("p.ply")) + args);
    ASSERT_TRUE(r.exited) << args;
    EXPECT_NE(r.exit_code, 0) << args;
    EXPECT_NE(r.err.find("> 0"), std::string::npos) << args << ": " << r.err;
    EXPECT_EQ(r.err.find("17976931"), std::string::npos) << args << ": " << r.err;
  }
}

TEST_F(MeshCliTest, RefusesBadArgumentsAndUnwritableOutput) {
  const std::string mesh = test::quote(test::data_path("bunny.obj"));
  for (const std::string args :
       {" --resolution 0", " --cell-size -1", " --resolution 40 --level 0", " --attributes nonsense",
        " --resolution 40 -o /nonexistent-dir/x.ply", " --resolution 40 -o out.stl"}) {
    const std::string full =
        mesh + (args.find(" -o ") == std::string::npos ? " -o " + test::quote(test::temp_path("x.ply")) : "") + args;
    const test::RunResult r = test::run_program(binary_, full);
    ASSERT_TRUE(r.exited) << args;
    EXPECT_NE(r.exit_code, 0) << args;
    EXPECT_FALSE(r.err.empty()) << args;
  }
}

}  // namespace
}  // namespace gwnrt
