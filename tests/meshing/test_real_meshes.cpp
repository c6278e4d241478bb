// The mesher on real meshes as users bring them (data/realworld: a scan with hundreds of holes,
// STL soups of CAD parts, an assembly of intersecting shells, an inside-out shell, seams, vertex
// colours): corners settled by the block bounds (field/box_winding.h) give the mesh that
// evaluating every corner gives, and the output is closed, manifold and free of intersecting
// triangles by the quality report's independent count (a BVH over the whole output).
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "gwnrt/meshing/extract_surface.h"
#include "gwnrt/meshing/mesh_comparison.h"
#include "gwnrt/meshing/mesh_quality.h"
#include "meshing_fixtures.h"
#include "test_util.h"

namespace gwnrt {
namespace {

const char* const kOpenMeshes[] = {"bunny_holes.obj",
                                   "teapot.obj",
                                   "realworld/dolphins_colored.ply",
                                   "realworld/birdBath_ggg_photogrammetry.obj",
                                   "realworld/kuka_kr10r1100sixx_visual_base_link.stl",
                                   "realworld/kuka_kr150r3100_2_visual_base_link.stl"};

// The same sign at every corner: the same edges, cells and triangles (a quad may split the other
// way where its diagonals tie), and vertices where every corner's evaluation puts them up to the
// smooth roots' tolerance (1e-4 of an edge; the QEF may move a vertex several times that).
TEST(RealMeshes, CornersSettledByBoundsGiveTheSameMesh) {
  for (const char* name : kOpenMeshes) {
    SCOPED_TRACE(name);
    const GwnModel model = test::build_model(test::load_test_mesh(name));
    ASSERT_GT(model.boundary().segment_count(), 0u);
    // The scan's every-corner reference is the slow half of this test: one resolution, and under
    // AddressSanitizer (which looks for memory errors, not differences) none.
    const bool scan = std::string(name).find("birdBath") != std::string::npos;
    if (scan && test::kAddressSanitizer) continue;
    for (const uint32_t resolution : {48u, 96u}) {
      if ((scan || test::kAddressSanitizer) && resolution > 48) continue;
      MeshingOptions settled = options_at(resolution), every = settled;
      every.settle_corners_by_bounds = false;
      SurfaceMesh a, b;
      MeshingStats sa, sb;
      ASSERT_TRUE(extract_surface(model, settled, a, &sa).ok());
      ASSERT_TRUE(extract_surface(model, every, b, &sb).ok());
      EXPECT_EQ(sa.crossing_edges, sb.crossing_edges) << resolution;
      EXPECT_EQ(sa.smooth_edges, sb.smooth_edges) << resolution;
      ASSERT_EQ(a.positions.size(), b.positions.size()) << resolution;
      const TriangleComparison t = compare_triangles(a.triangles, b.triangles);
      EXPECT_TRUE(t.equal_up_to_splits()) << resolution << ": " << t.different << " triangles differ";
      size_t moved = 0;
      for (size_t v = 0; v < a.positions.size(); ++v) {
        const float d = glm::length(a.positions[v] - b.positions[v]) / sa.cell_size;
        EXPECT_LT(d, 2e-3f) << resolution << " vertex " << v;
        moved += d > 1e-5f;
      }
      EXPECT_LT(moved, a.positions.size() / 10 + 1) << resolution;
    }
  }
}

const char* const kAllMeshes[] = {"bunny.obj",
                                  "bunny_holes.obj",
                                  "teapot.obj",
                                  "dragon_vrip_res4.ply",
                                  "realworld/dolphins_colored.ply",
                                  "realworld/spot_triangulated.obj",
                                  "realworld/birdBath_ggg_photogrammetry.obj",
                                  "realworld/kuka_kr10r1100sixx_visual_base_link.stl",
                                  "realworld/kuka_kr150r3100_2_visual_base_link.stl",
                                  "realworld/motoman_motomini_visual_link_1_s.stl"};

// The output's promises at several resolutions: closed, manifold, consistently oriented, no
// zero-area triangle, and no two triangles that meet other than in a shared vertex or edge,
// counted by count_self_intersections (a BVH over all triangles), not by the mesher's own
// cell-by-cell test. The resolutions include those at which the unrepaired output intersects
// itself on these meshes (RepairIsWhatRemovesTheIntersections).
TEST(RealMeshes, OutputIsClosedManifoldAndFreeOfIntersections) {
  for (const char* name : kAllMeshes) {
    SCOPED_TRACE(name);
    const bool scan = std::string(name).find("birdBath") != std::string::npos;
    if (scan && test::kAddressSanitizer) continue;
    const GwnModel model = test::build_model(test::load_test_mesh(name));
    for (const uint32_t resolution : {64u, 96u, 128u}) {
      if ((scan || test::kAddressSanitizer) && resolution > 64) continue;
      SurfaceMesh out;
      MeshingStats stats;
      ASSERT_TRUE(extract_surface(model, options_at(resolution), out, &stats).ok());
      ASSERT_GT(out.triangles.size(), 0u);
      MeshTopology topology;
      ASSERT_TRUE(mesh_topology(out, topology).ok());
      EXPECT_TRUE(topology.closed_manifold()) << resolution << ": " << topology.boundary_edges << " boundary, "
                                              << topology.non_manifold_edges << " non-manifold edges";
      EXPECT_EQ(topology.degenerate_triangles, 0u) << resolution;
      uint64_t pairs = ~uint64_t(0);
      ASSERT_TRUE(count_self_intersections(out, pairs).ok());
      EXPECT_EQ(pairs, 0u) << resolution;
      EXPECT_EQ(stats.self_intersections_left, 0u) << resolution;
    }
  }
}

// Without the repair the same outputs intersect themselves (so the test above can fail), and
// the repair reports what it found and moved.
TEST(RealMeshes, RepairIsWhatRemovesTheIntersections) {
  const GwnModel model = test::build_model(test::load_test_mesh("realworld/motoman_motomini_visual_link_1_s.stl"));
  MeshingOptions options = options_at(64);
  SurfaceMesh repaired, raw;
  MeshingStats with, without;
  ASSERT_TRUE(extract_surface(model, options, repaired, &with).ok());
  options.repair_self_intersections = false;
  ASSERT_TRUE(extract_surface(model, options, raw, &without).ok());
  uint64_t raw_pairs = 0, repaired_pairs = ~uint64_t(0);
  ASSERT_TRUE(count_self_intersections(raw, raw_pairs).ok());
  ASSERT_TRUE(count_self_intersections(repaired, repaired_pairs).ok());
  EXPECT_GT(raw_pairs, 10u);
  EXPECT_EQ(repaired_pairs, 0u);
  // The mesher's cell-by-cell count finds every pair the BVH count finds.
  EXPECT_EQ(with.self_intersections_repaired, raw_pairs);
  EXPECT_GE(with.repair_rounds, 1u);
  EXPECT_GT(with.repaired_vertex_moves, 0u);
  EXPECT_EQ(with.self_intersections_left, 0u);
  EXPECT_EQ(without.repair_rounds, 0u);
  // Same connectivity; only the flagged vertices moved, and each within its cell.
  ASSERT_EQ(repaired.triangles, raw.triangles);
  ASSERT_EQ(repaired.positions.size(), raw.positions.size());
  size_t moved = 0;
  for (size_t v = 0; v < raw.positions.size(); ++v) {
    const vec3 d = glm::abs(repaired.positions[v] - raw.positions[v]) / with.cell_size;
    EXPECT_LT(std::max({d.x, d.y, d.z}), 1.0f) << v;
    moved += d != vec3(0.0f);
  }
  EXPECT_GT(moved, 0u);
  EXPECT_LE(moved, with.repaired_vertex_moves);
}

// An assembly of two intersecting boxes: the top face of the first is cut by the second, and its
// two triangles' centroids lie inside the second (so neither is a sheet) while the strip of the
// face outside it is part of S. Scouted by the sheets alone, blocks S passes through were
// dropped at 256 and the output had holes; the mesher meshes again scouted by the distance to M.
TEST(RealMeshes, IntersectingPartsCloseWhereTheSheetsMissS) {
  Mesh mesh;
  const auto add_box = [&](const vec3& lo, const vec3& hi) {
    const uint32_t b = uint32_t(mesh.positions.size());
    for (int i = 0; i < 8; ++i)
      mesh.positions.push_back(vec3(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z));
    const uint32_t faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& f : faces) {
      mesh.triangles.push_back({b + f[0], b + f[1], b + f[2]});
      mesh.triangles.push_back({b + f[0], b + f[2], b + f[3]});
    }
  };
  add_box(vec3(0.0f), vec3(1.0f));
  add_box(vec3(0.3f, -1.0f, 0.5f), vec3(2.0f));
  const GwnModel model = test::build_model(std::move(mesh));
  SurfaceMesh out;
  MeshingStats stats;
  ASSERT_TRUE(extract_surface(model, options_at(256), out, &stats).ok());
  EXPECT_GT(stats.rescouted_open_edges, 0u);
  EXPECT_EQ(stats.open_edges, 0u);
  MeshTopology topology;
  ASSERT_TRUE(mesh_topology(out, topology).ok());
  EXPECT_TRUE(topology.closed_manifold()) << topology.boundary_edges << " boundary edges";
  uint64_t pairs = ~uint64_t(0);
  ASSERT_TRUE(count_self_intersections(out, pairs).ok());
  EXPECT_EQ(pairs, 0u);
  // The union's volume: 1 + 1.7·3·1.5 − 0.7·1·0.5, within a cell's layer of the surface.
  double volume = 0;
  for (const uvec3& t : out.triangles)
    volume += glm::dot(dvec3(out.positions[t.x]), glm::cross(dvec3(out.positions[t.y]), dvec3(out.positions[t.z]))) / 6;
  const double expected = 1.0 + 1.7 * 3.0 * 1.5 - 0.7 * 1.0 * 0.5;
  EXPECT_NEAR(volume, expected, 0.01 * expected);
}

}  // namespace
}  // namespace gwnrt
