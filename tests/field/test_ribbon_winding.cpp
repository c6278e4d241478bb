// w by ribbons (field/ribbon_winding.h): against the double brute force of reference/ on open
// meshes, a scan with 329 loops, a CAD STL and a closed mesh, at random points and at points
// placed beside ∂M's segments along every axis, where a ray passes by the rim and M's jumps must
// make up for the ribbon's own (on the STL's planar holes some lie in the hole's plane, on a
// ribbon, and are moved).
#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "gwnrt/field/distance.h"
#include "gwnrt/field/ribbon_winding.h"
#include "reference/brute_force_winding.h"
#include "reference/parallel_over.h"
#include "test_util.h"

namespace gwnrt {
namespace {

using test::build_model;
using test::load_test_mesh;

using test::kCrossingNearMesh;
using test::kCrossingTolerance;

TEST(RibbonWinding, MatchesBruteForceOnOpenAndClosedMeshes) {
  for (const char* name : {"bunny_holes.obj", "realworld/birdBath_ggg_photogrammetry.obj",
                           "realworld/kuka_kr150r3100_2_visual_base_link.stl", "bunny.obj"}) {
    const Mesh mesh = load_test_mesh(name);
    const GwnModel model = build_model(mesh);
    ASSERT_TRUE(model.prepare(kPartBoundary).ok());
    const ModelView v = model.view();
    const reference::ReferenceMesh ref = reference::reference_mesh(mesh);
    std::mt19937 rng(5);
    std::vector<vec3> points;
    // Random points in the box grown by a fifth, and points a little behind and beside the
    // segments' midpoints along each axis (the rays from them pass by the rim).
    const vec3 lo = v.bounds.lo, hi = v.bounds.hi, grow = 0.2f * (hi - lo);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (int i = 0; i < 400; ++i) points.push_back(lo - grow + vec3(u(rng), u(rng), u(rng)) * (hi - lo + 2.0f * grow));
    const float step = 1e-3f * glm::length(hi - lo);
    for (uint32_t s = 0; s < v.boundary.segment_count && points.size() < 1600; s += 1 + v.boundary.segment_count / 200)
      for (int axis = 0; axis < 3; ++axis)
        for (const float side : {-1.0f, 1.0f}) {
          vec3 p = 0.5f * (v.boundary.endpoints[2 * s] + v.boundary.endpoints[2 * s + 1]);
          p[axis] += side * step;
          p[(axis + 1) % 3] += 0.3f * step;
          points.push_back(p);
        }
    std::vector<double> error(points.size(), -1.0);
    reference::parallel_over(points.size(), [&](size_t i) {
      if (unsigned_distance(v.triangles, points[i]).distance <= kCrossingNearMesh * ref.diagonal) return;
      // A point on a ribbon (those in the plane of a planar hole) is answered at a moved point:
      // the value must be w there, at x or at one of the first moves.
      const double w = winding_number_by_ribbons(v, points[i]);
      ConeNudge nudge(v.bounds, points[i]);
      error[i] = std::fabs(w - reference::reference_w(ref, dvec3(points[i])));
      for (int k = 0; k < 2; ++k)
        error[i] = std::min(error[i], std::fabs(w - reference::reference_w(ref, dvec3(nudge.next()))));
    });
    size_t compared = 0;
    double worst = 0;
    for (const double e : error)
      if (e >= 0) ++compared, worst = std::max(worst, e);
    EXPECT_GT(compared, points.size() / 2) << name;
    EXPECT_LE(worst, kCrossingTolerance) << name << ": " << compared << " points";
  }
}

}  // namespace
}  // namespace gwnrt
