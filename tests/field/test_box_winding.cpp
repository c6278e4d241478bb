// w over a box from a first-order estimate (field/box_winding.h), against the double brute force:
// at random points of random boxes near open meshes, ŵ = w + J (J: M's jumps ahead along the
// box's ray) lies within the stated bounds of the estimate from another point of the box, |∇w|
// stays below K, an estimate that settles a sign gives the exact one, and a box whose swept
// region holds ∂M gets no bounds.
#include <cmath>
#include <cstdio>
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

// A box 1/8 to 1/2^(2 + scales) of M's diagonal across, about a point of M (where S and ∂M are).
Aabb random_box_on(const GwnModel& model, test::Random& rng, int scales) {
  const float diagonal = glm::length(model.bounds().hi - model.bounds().lo);
  const uvec3 t = model.mesh().triangles[rng.index(int(model.mesh().triangles.size()))];
  const vec3 on = (model.mesh().positions[t.x] + model.mesh().positions[t.y] + model.mesh().positions[t.z]) / 3.0f;
  const float half = diagonal * std::exp2(-float(3 + rng.index(scales))) * 0.5f;
  Aabb box;
  box.lo = on + vec3(rng.uniform(-half, 0), rng.uniform(-half, 0), rng.uniform(-half, 0)) * 2.0f;
  box.hi = box.lo + vec3(2.0f * half);
  return box;
}

BoundCounts check_bounds_on(const std::string& name, int box_count) {
  SCOPED_TRACE(name);
  const GwnModel model = test::build_model(test::load_test_mesh(name));
  const ModelView m = model.view();
  const ReferenceMesh ref = reference_mesh(model.mesh());
  test::Random rng(11);
  BoundCounts counts;
  for (int i = 0; i < box_count; ++i) {
    const Aabb box = random_box_on(model, rng, 4);  // 1/64 to 1/8 of the diagonal
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

// The bounds of a box's eighths from the box's own traversal (the batch of boxes a block's
// centres take): usable where the box's are, no looser than the box's, and holding on the
// eighth: |∇w| below K and Taylor's remainder from its centre below ½·H·r², by the double brute
// force.
TEST(BoxWinding, EighthsBoundsFromTheBoxsTraversalHoldOnEachEighth) {
  for (const char* name : {"bunny_holes.obj", "teapot.obj"}) {
    SCOPED_TRACE(name);
    const GwnModel model = test::build_model(test::load_test_mesh(name));
    const ModelView m = model.view();
    const ReferenceMesh ref = reference_mesh(model.mesh());
    test::Random rng(17);
    int usable = 0;
    for (int i = 0; i < 40; ++i) {
      Aabb boxes[9];
      boxes[0] = random_box_on(model, rng, 3);
      const vec3 mid = boxes[0].centre();
      for (int k = 0; k < 8; ++k)
        for (int a = 0; a < 3; ++a) {
          const bool upper = (k >> a) & 1;
          boxes[1 + k].lo[a] = upper ? mid[a] : boxes[0].lo[a];
          boxes[1 + k].hi[a] = upper ? boxes[0].hi[a] : mid[a];
        }
      const int axis = rng.index(3);
      const float sign = rng.index(2) ? 1.0f : -1.0f;
      BoxFieldBounds b[9];
      box_field_bounds(m, boxes, axis, sign, b);
      const BoxFieldBounds whole = box_field_bounds(m, boxes[0], axis, sign);
      EXPECT_EQ(b[0].usable, whole.usable) << "box " << i;
      if (!b[0].usable) continue;
      ++usable;
      EXPECT_FLOAT_EQ(b[0].gradient, whole.gradient) << "box " << i;
      EXPECT_FLOAT_EQ(b[0].hessian, whole.hessian) << "box " << i;
      for (int k = 1; k < 9; ++k) {
        SCOPED_TRACE("box " + std::to_string(i) + " eighth " + std::to_string(k - 1));
        ASSERT_TRUE(b[k].usable);
        EXPECT_LE(b[k].gradient, b[0].gradient * (1 + 1e-4f));
        EXPECT_LE(b[k].hessian, b[0].hessian * (1 + 1e-4f));
        const dvec3 c(boxes[k].centre());
        const double w_c = reference_w(ref, c) + jumps_at(m, vec3(c), axis, sign);
        const dvec3 g_c = reference_gradient(ref, c);
        for (int q = 0; q < 6; ++q) {
          const dvec3 x(rng.in_box(boxes[k]));
          EXPECT_LE(glm::length(reference_gradient(ref, x)), b[k].gradient * (1 + 1e-4));
          const double w_x = reference_w(ref, x) + jumps_at(m, vec3(x), axis, sign);
          const double r = glm::length(x - c);
          EXPECT_LE(std::abs(w_x - w_c - glm::dot(g_c, x - c)), 0.5 * b[k].hessian * r * r + 1e-6);
        }
      }
    }
    EXPECT_GE(usable, 10);  // not vacuous
  }
}

// Many small holes far from the box (a scan's): the clusters' expansions about their centres
// (closed loops have no net length) give K and H below the clusters' plain sums (by a third and
// a tenth here: a cluster is taken whole at one diagonal, where the expansion's remainder is
// still large), and still hold at random points of the box, by the double brute force.
TEST(BoxWinding, FarSmallLoopsTakeTheirExpansions) {
  test::Random rng(19);
  Mesh discs;
  for (int d = 0; d < 300; ++d) {
    const dvec3 centre(rng.uniform(0, 10), rng.uniform(0, 10), rng.uniform(-0.2f, 0.2f));
    const Mesh disc = test::make_fanned_polygon(6, rng.uniform(0.01f, 0.05f), centre);
    const uint32_t base = uint32_t(discs.positions.size());
    discs.positions.insert(discs.positions.end(), disc.positions.begin(), disc.positions.end());
    for (const uvec3& t : disc.triangles) discs.triangles.push_back(t + uvec3(base));
  }
  const GwnModel model = test::build_model(std::move(discs));
  const ModelView m = model.view();
  ModelView plain = m;
  plain.boundary.net_lengths = nullptr;  // the clusters' plain sums
  const ReferenceMesh ref = reference_mesh(model.mesh());
  double gradient_ratio = 0, hessian_ratio = 0;
  int boxes = 0;
  for (int i = 0; i < 30; ++i) {
    Aabb box;
    box.lo = vec3(rng.uniform(1, 8.8f), rng.uniform(1, 8.8f), rng.uniform(0.5f, 2.0f));
    box.hi = box.lo + vec3(0.2f);
    const BoxFieldBounds b = box_field_bounds(m, box, 2, 1.0f), loose = box_field_bounds(plain, box, 2, 1.0f);
    ASSERT_TRUE(b.usable && loose.usable) << "box " << i;
    EXPECT_LE(b.gradient, loose.gradient * (1 + 1e-4f)) << "box " << i;
    EXPECT_LE(b.hessian, loose.hessian * (1 + 1e-4f)) << "box " << i;
    gradient_ratio += loose.gradient / b.gradient;
    hessian_ratio += loose.hessian / b.hessian;
    ++boxes;
    const dvec3 c(box.centre());
    const double w_c = reference_w(ref, c) + jumps_at(m, vec3(c), 2, 1.0f);
    const dvec3 g_c = reference_gradient(ref, c);
    for (int k = 0; k < 12; ++k) {
      const dvec3 x(rng.in_box(box));
      EXPECT_LE(glm::length(reference_gradient(ref, x)), b.gradient * (1 + 1e-4)) << "box " << i;
      const double w_x = reference_w(ref, x) + jumps_at(m, vec3(x), 2, 1.0f);
      const double r = glm::length(x - c);
      EXPECT_LE(std::abs(w_x - w_c - glm::dot(g_c, x - c)), 0.5 * b.hessian * r * r + 1e-7) << "box " << i;
    }
  }
  std::printf("plain sums / expansions over %d boxes: K %.2f, H %.2f on average\n", boxes, gradient_ratio / boxes,
              hessian_ratio / boxes);
  EXPECT_GT(gradient_ratio / boxes, 1.25);
  EXPECT_GT(hessian_ratio / boxes, 1.05);
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
