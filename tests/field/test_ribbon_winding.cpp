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

// A ribbon's ∇Ω and H Ω (its segment's edge term and its two sides' half-line limits) against
// central differences of its Ω and of that ∇Ω, in double, at random points off the ribbon.
TEST(RibbonWinding, DerivativesMatchFiniteDifferences) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const auto random_point = [&] { return dvec3(u(rng), u(rng), u(rng)); };
  int compared = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const dvec3 a = random_point(), b = random_point();
    dvec3 c(0.0);
    c[trial % 3] = trial % 2 ? 1.0 : -1.0;
    const dvec3 x = 2.0 * random_point();
    double omega;
    dvec3 g;
    Sym3<double> h;
    ribbon_derivatives(a - x, b - x, c, omega, g, h);
    const double step = 1e-5;
    bool smooth = true;
    dvec3 fd_g;
    dvec3 fd_h[3];
    for (int k = 0; k < 3; ++k) {
      dvec3 e(0.0);
      e[k] = step;
      double plus, minus;
      dvec3 g_plus, g_minus;
      Sym3<double> unused;
      ribbon_derivatives(a - x - e, b - x - e, c, plus, g_plus, unused);
      ribbon_derivatives(a - x + e, b - x + e, c, minus, g_minus, unused);
      smooth = smooth && std::fabs(plus - minus) < 1.0;  // not across the ribbon (a jump of 4π)
      fd_g[k] = (plus - minus) / (2.0 * step);
      fd_h[k] = (g_plus - g_minus) / (2.0 * step);
    }
    if (!smooth || glm::length(g) > 1e3) continue;
    ++compared;
    const double scale = 1.0 + glm::length(g);
    EXPECT_LT(glm::length(g - fd_g), 1e-5 * scale) << "trial " << trial;
    const double hessian[3][3] = {{h.xx, h.xy, h.xz}, {h.xy, h.yy, h.yz}, {h.xz, h.yz, h.zz}};
    double h_scale = 1.0;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) h_scale = std::max(h_scale, std::fabs(hessian[i][j]));
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        EXPECT_NEAR(hessian[i][j], fd_h[j][i], 1e-4 * h_scale) << "trial " << trial << " entry " << i << j;
  }
  EXPECT_GT(compared, 150);
}

#if GWNRT_HOST_LANES && defined(__AVX__)
// The batched ribbons (RibbonWindingBatch, M's jumps from their own walk): w within each meshing
// beta's allowance of the scalar form wherever the batch is sure, for blocks of 8³ corners by the
// rims along every axis (their rays pass by ∂M, so lanes in the beam must be opened) and for
// points on, within round-off of and just off segments' ribbons (the batch must be right or
// unsure); ∇w against the crossing method's at the derivatives' beta.
TEST(RibbonWinding, BatchMatchesTheScalarForm) {
  for (const char* name : {"bunny_holes.obj", "realworld/birdBath_ggg_photogrammetry.obj",
                           "realworld/kuka_kr150r3100_2_visual_base_link.stl", "teapot.obj"}) {
    const GwnModel model = build_model(load_test_mesh(name));
    ASSERT_TRUE(model.prepare(kPartBoundary).ok());
    const ModelView v = model.view();
    const float diagonal = glm::length(v.bounds.hi - v.bounds.lo);
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const auto segment_point = [&](uint32_t& s) {
      s = uint32_t(rng() % v.boundary.segment_count);
      return glm::mix(v.boundary.endpoints[2 * s], v.boundary.endpoints[2 * s + 1], u(rng));
    };
    // The meshing's betas with tenfold margins under what each use allows (as the cone batch's
    // test): the corner screen's 0.02, the refinement's 2e-3, the centres' 1e-3, the exact 1e-5.
    const float betas[4] = {1.5f, 3.0f, 5.0f, 5.0f};
    const float tolerances[4] = {2e-3f, 2e-4f, 1e-4f, 2e-5f};
    float worst[4] = {};
    int sure = 0, unsure = 0;
    const auto check = [&](const std::vector<vec3>& points, int axis, float sign, const char* where) {
      for (int pass = 0; pass < 4; ++pass) {
        RibbonWindingBatch<512> batch;
        for (const vec3& x : points) batch.add(x);
        batch.evaluate(v.ribbons, betas[pass], axis, sign);
        for (int j = 0; j < int(points.size()); ++j) {
          const vec3& x = points[j];
          const float lu[1] = {x[(axis + 1) % 3]}, lv[1] = {x[(axis + 2) % 3]}, along[1] = {x[axis]};
          int mesh_jumps[1][1];
          jumps_along_axis_lattice(v.triangles, lu, lv, along, axis, sign, mesh_jumps);
          const float w = batch.crossing_winding(j, mesh_jumps[0][0]);
          if (!(w == w)) {
            ++unsure;
            continue;
          }
          ++sure;
          const double exact = winding_number_by_ribbons(v, x);
          worst[pass] = std::max(worst[pass], float(std::fabs(w - exact)));
          ASSERT_NEAR(w, exact, tolerances[pass]) << name << " " << where << " point " << j << " beta " << betas[pass];
        }
      }
    };
    for (int block = 0; block < 12; ++block) {
      uint32_t s;
      const float h = diagonal / 256.0f;
      const vec3 origin = segment_point(s) - u(rng) * 8.0f * h * vec3(1.0f);
      std::vector<vec3> points;
      for (int k = 0; k < 512; ++k) points.push_back(origin + h * vec3(float(k % 8), float(k / 8 % 8), float(k / 64)));
      check(points, int(rng() % 3), rng() % 2 ? 1.0f : -1.0f, "block by the rim");
    }
    for (int ribbon = 0; ribbon < 40; ++ribbon) {  // on a segment's ribbon and beside it
      uint32_t s;
      const vec3 on = segment_point(s);
      const int axis = int(rng() % 3);
      const float sign = rng() % 2 ? 1.0f : -1.0f;
      vec3 behind = on;
      behind[axis] -= sign * u(rng) * 0.1f * diagonal;  // the ray from it runs into the segment
      const vec3 e = v.boundary.endpoints[2 * s + 1] - v.boundary.endpoints[2 * s];
      vec3 d(0.0f);
      d[axis] = 1.0f;
      const vec3 n = glm::normalize(glm::cross(e, d));
      std::vector<vec3> points;
      for (const float offset : {0.0f, 1e-7f, -1e-7f, 1e-5f, -1e-5f, 1e-3f, -1e-3f, 1e-2f})
        points.push_back(behind + offset * diagonal * n);
      check(points, axis, sign, "by a ribbon");
    }
    std::printf("%s: %d sure, %d unsure; largest errors %.1e %.1e %.1e %.1e\n", name, sure, unsure, worst[0], worst[1],
                worst[2], worst[3]);
    EXPECT_LT(unsure, sure / 50) << name;
    // ∇w: the Biot–Savart sum over the segments, within a relative 1e-2 of the crossing method's
    // at its derivatives' beta (the normals' allowance, as the cone batch's test).
    float worst_gradient = 0.0f;
    for (int block = 0; block < 12; ++block) {
      uint32_t s;
      const vec3 origin = segment_point(s);
      const float h = diagonal / 256.0f;
      RibbonWindingBatch<512, true> batch;
      std::vector<vec3> points;
      for (int k = 0; k < 300; ++k) {
        const vec3 dir = glm::normalize(vec3(u(rng), u(rng), u(rng)) - vec3(0.5f));
        points.push_back(origin + (0.5f + 7.5f * u(rng)) * h * dir);
        batch.add(points.back());
      }
      batch.evaluate(v.ribbons, 3.0f, -1, 1.0f);
      for (int j = 0; j < int(points.size()); ++j) {
        const vec3 reference = winding_number_crossing<true, false>(v, points[j], kConeDerivativeBeta).gradient;
        const vec3 g = batch.winding_gradient(j);
        ASSERT_TRUE(g == g) << name << " point " << j;
        worst_gradient = std::max(worst_gradient, glm::length(g - reference) / glm::length(reference));
      }
    }
    std::printf("%s: gradient's largest relative error %.2e\n", name, worst_gradient);
    EXPECT_LT(worst_gradient, 1e-2f) << name;
  }
}
#endif

}  // namespace
}  // namespace gwnrt
