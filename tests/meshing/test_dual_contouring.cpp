// The corner pass of dual contouring (meshing/dual_contouring.h): the winding numbers of a line
// of cell corners, from one shared ray, and their screened values.
#include <gtest/gtest.h>

#include "gwnrt/field/crossing_winding.h"
#include "gwnrt/meshing/dual_contouring.h"
#include "test_util.h"

namespace gwnrt {
namespace {

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
        int jumps[8];
        mesh_jumps_along_axis(view, points, axis, sign, jumps);
        for (int k = 0; k < 8; ++k) w[k] = corner_winding_value(view, points[k], axis, sign, jumps[k], level);
        for (int k = 0; k < 8; ++k) {
          EXPECT_EQ(w[k] > level, exact[k] > level) << name << " line " << line << " level " << level;
          screened += w[k] != exact[k];
        }
      }
    }
    EXPECT_GT(screened, 1000) << name << ": the screen was never used";
  }
}

}  // namespace
}  // namespace gwnrt
