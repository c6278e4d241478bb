// The mesher on real meshes as users bring them (data/realworld: a scan with hundreds of holes,
// STL soups of CAD parts, an assembly of intersecting shells, an inside-out shell, seams, vertex
// colours): corners settled by the block bounds (field/box_winding.h) give the mesh that
// evaluating every corner gives.
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

}  // namespace
}  // namespace gwnrt
