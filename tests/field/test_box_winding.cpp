// w over a box from a first-order estimate (field/box_winding.h), against the double brute force:
// at random points of random boxes near open meshes, ŵ = w + J (J: M's jumps ahead along the
// box's ray) lies within the stated bounds of the estimate from another point of the box, |∇w|
// stays below K, an estimate that settles a sign gives the exact one, and a box whose swept
// region holds ∂M gets no bounds.
#include <cmath>
#include <string>
#include <vector>

#include "gwnrt/field/box_winding.h"
#include "gwnrt/geometry/boundary.h"
#include "reference/brute_force_winding.h"
#include "test_util.h"

namespace gwnrt {
namespace {

using reference::reference_gradient;
using reference::reference_mesh;
using reference::reference_w;
using reference::ReferenceMesh;

// J(x): M's jumps ahead of x along (axis, sign).
int jumps_at(const ModelView& m, const vec3& x, int axis, float sign) {
  const vec3 points[1] = {x};
  int jumps[1];
  mesh_jumps_along_axis(m, points, axis, sign, jumps);
  return jumps[0];
}

struct BoundCounts {
  int boxes = 0, usable = 0, points = 0, settled = 0;
};

BoundCounts check_bounds_on(const std::string& name, int box_count) {
  SCOPED_TRACE(name);
  const GwnModel model = test::build_model(test::load_test_mesh(name));
  const ModelView m = model.view();
  const ReferenceMesh ref = reference_mesh(model.mesh());
  const Aabb bounds = model.bounds();
  const float diagonal = glm::length(bounds.hi - bounds.lo);
  test::Random rng(11);
  BoundCounts counts;
  for (int i = 0; i < box_count; ++i) {
    // Boxes 1/64 to 1/8 of the diagonal across, about a point of M (where S and ∂M are).
    const uvec3 t = model.mesh().triangles[rng.index(int(model.mesh().triangles.size()))];
    const vec3 on = (model.mesh().positions[t.x] + model.mesh().positions[t.y] + model.mesh().positions[t.z]) / 3.0f;
    const float half = diagonal * std::exp2(-float(3 + rng.index(4))) * 0.5f;
    Aabb box;
    box.lo = on + vec3(rng.uniform(-half, 0), rng.uniform(-half, 0), rng.uniform(-half, 0)) * 2.0f;
    box.hi = box.lo + vec3(2.0f * half);
    const int axis = rng.index(3);
    const float sign = rng.index(2) ? 1.0f : -1.0f;
    ++counts.boxes;
    const BoxFieldBounds b = box_field_bounds(m, box, axis, sign);
    if (!b.usable) continue;
    ++counts.usable;
    TaylorPoint p;
    const vec3 at = rng.in_box(box);
    if (!taylor_point(m, at, axis, sign, p)) continue;
    const double w_at = reference_w(ref, dvec3(at)) + jumps_at(m, at, axis, sign);
    EXPECT_NEAR(p.w_hat, w_at, 1e-4) << "box " << i;
    for (int k = 0; k < 24; ++k) {
      const vec3 x = rng.in_box(box);
      const double w = reference_w(ref, dvec3(x));
      const double w_hat = w + jumps_at(m, x, axis, sign);
      const double r = glm::length(dvec3(x) - dvec3(at));
      const double linear = p.w_hat + glm::dot(dvec3(p.gradient), dvec3(x) - dvec3(at));
      // Taylor's remainder and the Lipschitz bound, with the centre's gradient error and 1e-4.
      EXPECT_LE(std::abs(w_hat - linear),
                0.5 * b.hessian * r * r + kTaylorGradientError * glm::length(p.gradient) * r + 1e-4)
          << "box " << i << " point " << k;
      EXPECT_LE(std::abs(w_hat - p.w_hat), b.gradient * r + 1e-4) << "box " << i << " point " << k;
      EXPECT_LE(glm::length(reference_gradient(ref, dvec3(x))), b.gradient * (1 + 1e-4)) << "box " << i;
      // A settled sign is the exact one, at levels near w's own value too.
      for (const float level : {0.5f, float(w) - 0.01f, float(w) + 0.01f}) {
        const float f = taylor_estimate(p, b, jumps_at(m, x, axis, sign), x - at, level);
        ++counts.points;
        if (f != f) continue;
        ++counts.settled;
        EXPECT_EQ(f > 0, w > level) << "box " << i << " point " << k << " level " << level << " w " << w;
      }
    }
  }
  return counts;
}

TEST(BoxWinding, EstimatesStayWithinTheirBoundsNearOpenMeshes) {
  for (const char* name : {"bunny_holes.obj", "teapot.obj", "realworld/dolphins_colored.ply"}) {
    const BoundCounts c = check_bounds_on(name, 60);
    // The bounds apply to most boxes and settle most points (the test would pass vacuously else).
    EXPECT_GT(c.usable, c.boxes / 4) << name;
    EXPECT_GT(c.settled, c.points / 3) << name;
  }
}

// A box about a vertex of ∂M holds ∂M: no bounds, whichever way it is swept.
TEST(BoxWinding, NoBoundsWhereTheSweptBoxHoldsTheBoundary) {
  const GwnModel model = test::build_model(test::load_test_mesh("bunny_holes.obj"));
  const BoundaryCurve curve = extract_boundary(model.mesh());
  ASSERT_GT(curve.segment_count(), 0u);
  const vec3 on = curve.endpoints[0];
  Aabb box;
  box.lo = on - vec3(0.01f);
  box.hi = on + vec3(0.01f);
  for (int axis = 0; axis < 3; ++axis)
    for (const float sign : {-1.0f, 1.0f}) EXPECT_FALSE(box_field_bounds(model.view(), box, axis, sign).usable);
  // A closed mesh has no boundary: bounds of 0 everywhere.
  const GwnModel closed = test::build_model(test::load_test_mesh("bunny.obj"));
  const BoxFieldBounds b = box_field_bounds(closed.view(), box, 0, 1.0f);
  EXPECT_TRUE(b.usable);
  EXPECT_EQ(b.gradient, 0.0f);
}

}  // namespace
}  // namespace gwnrt
