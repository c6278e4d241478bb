// compare_triangles (meshing/mesh_comparison.h), which tells quads split along their other
// diagonal from other changes to a mesh.
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "gwnrt/meshing/extract_surface.h"
#include "gwnrt/meshing/mesh_comparison.h"
#include "test_util.h"

namespace gwnrt {
namespace {

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

}  // namespace
}  // namespace gwnrt
