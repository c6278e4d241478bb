// w, ∇w and H_w: analytic cases, Taylor orders against the exact double sum, and derivatives
// against central differences of the exact w.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "gwnrt/field/winding_number.h"
#include "test_util.h"

namespace gwnrt {
namespace {

using test::build_model;
using test::load_test_mesh;

TEST(SolidAngle, OctantTriangleIsAnEighthOfTheSphere) {
  // The triangle with corners on the three axes covers one octant seen from the origin; its
  // normal (1,1,1) points away from the origin, so Ω is positive.
  const dvec3 o(0.0);
  EXPECT_NEAR(triangle_solid_angle(dvec3(1, 0, 0), dvec3(0, 1, 0), dvec3(0, 0, 1), o), kPi / 2, 1e-14);
  EXPECT_NEAR(triangle_solid_angle(dvec3(1, 0, 0), dvec3(0, 0, 1), dvec3(0, 1, 0), o), -kPi / 2, 1e-14);
  EXPECT_NEAR(triangle_solid_angle(vec3(2, 0, 0), vec3(0, 2, 0), vec3(0, 0, 2), vec3(0.0f)), float(kPi / 2), 1e-6f);
}

TEST(SolidAngle, SquareOnItsAxisMatchesClosedForm) {
  // Square [-a, a]² at height h seen from the origin: Ω = 4 asin(a² / (a² + h²)).
  for (double a : {0.1, 1.0, 3.0})
    for (double h : {0.01, 0.5, 2.0, 40.0}) {
      const dvec3 p[4] = {{-a, -a, h}, {a, -a, h}, {a, a, h}, {-a, a, h}};
      const dvec3 o(0.0);
      const double omega = triangle_solid_angle(p[0], p[1], p[2], o) + triangle_solid_angle(p[0], p[2], p[3], o);
      EXPECT_NEAR(omega, 4 * std::asin(a * a / (a * a + h * h)), 1e-12) << "a=" << a << " h=" << h;
    }
}

TEST(SolidAngle, DegenerateTrianglesContributeNothing) {
  const dvec3 x(0.3, -0.2, 0.5);
  EXPECT_EQ(triangle_solid_angle(dvec3(1, 0, 0), dvec3(1, 0, 0), dvec3(0, 1, 0), x), 0.0);
  EXPECT_NEAR(triangle_solid_angle(dvec3(0, 0, 0), dvec3(1, 1, 1), dvec3(2, 2, 2), x), 0.0, 1e-15);
}

TEST(WindingNumber, ClosedSphereIsOneInsideZeroOutside) {
  const GwnModel model = build_model(test::make_sphere(4));
  const auto view = model.triangle_view();
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  int checked = 0;
  for (int i = 0; i < 2000; ++i) {
    const vec3 x(3 * u(rng), 3 * u(rng), 3 * u(rng));
    const float r = glm::length(x);
    // The tessellation lies between radius cos(edge/2)-ish and 1; stay clear of that shell.
    if (r > 0.97f && r < 1.03f) continue;
    const double expected = r < 1.0f ? 1.0 : 0.0;
    EXPECT_NEAR(winding_number_exact(view, x).w, expected, 1e-6) << "x=" << x.x << "," << x.y << "," << x.z;
    // The bound is for order 2; orders 0 and 1 truncate one and two orders earlier
    // ((1/beta)^(k+1) relative per cluster), so they get a correspondingly looser bound.
    EXPECT_NEAR(winding_number(view, x, {2, 2.0f}).w, expected, 2e-3);
    EXPECT_NEAR(winding_number(view, x, {1, 2.0f}).w, expected, 0.1);
    EXPECT_NEAR(winding_number(view, x, {0, 2.0f}).w, expected, 0.1);
    ++checked;
  }
  EXPECT_GT(checked, 1000);
}

TEST(WindingNumber, CubeIsOneInsideZeroOutside) {
  const GwnModel model = build_model(test::make_cube());
  const auto view = model.triangle_view();
  for (const vec3 x : {vec3(0.0f), vec3(0.9f, -0.5f, 0.3f), vec3(-0.99f, 0.99f, 0.99f)})
    EXPECT_NEAR(winding_number_exact(view, x).w, 1.0, 1e-6);
  for (const vec3 x : {vec3(1.01f, 0, 0), vec3(5, 5, 5), vec3(-30, 2, 0.5f)}) {
    EXPECT_NEAR(winding_number_exact(view, x).w, 0.0, 1e-6);
    EXPECT_NEAR(winding_number(view, x, {2, 2.0f}).w, 0.0f, 2e-3f);  // the Taylor tolerance
  }
}

TEST(WindingNumber, FlatDiskOnItsAxis) {
  // A disk of radius R seen from height h on its axis subtends 2π(1 - h/√(h² + R²)). The
  // n-gon lies between its inscribed circle (radius R cos(π/n)) and the circle itself, so the
  // exact answer is bracketed by the two closed forms.
  const int n = 256;
  const float R = 1.0f;
  Mesh disk;
  disk.positions.push_back(vec3(0.0f));
  for (int i = 0; i < n; ++i) {
    const double phi = 2 * kPi * i / n;
    disk.positions.push_back(vec3(float(R * std::cos(phi)), float(R * std::sin(phi)), 0.0f));
  }
  for (int i = 0; i < n; ++i) disk.triangles.push_back({0u, uint32_t(1 + i), uint32_t(1 + (i + 1) % n)});
  const GwnModel model = build_model(std::move(disk));
  auto closed_form = [](double h, double radius) { return (1 - h / std::sqrt(h * h + radius * radius)) / 2; };
  for (float h : {-2.0f, -0.3f, 0.05f, 0.5f, 3.0f}) {
    const double w = winding_number_exact(model.triangle_view(), vec3(0, 0, h)).w;
    // Normal +z: points below the disk (h < 0) see it from the back: w > 0.
    const double sign = h < 0 ? 1.0 : -1.0;
    const double a = sign * closed_form(std::abs(h), R), b = sign * closed_form(std::abs(h), R * std::cos(kPi / n));
    EXPECT_GE(w, std::min(a, b) - 1e-9) << "h=" << h;
    EXPECT_LE(w, std::max(a, b) + 1e-9) << "h=" << h;
    EXPECT_NEAR(winding_number(model.triangle_view(), vec3(0, 0, h), {2, 2.0f}).w, w, 2e-3);
  }
}

struct TaylorErrors {
  double max[3] = {0, 0, 0};
  double rms[3] = {0, 0, 0};
};

TaylorErrors taylor_errors(const GwnModel& model, size_t count, float beta) {
  const auto view = model.triangle_view();
  const auto points = test::sample_points(test::mesh_bounds(model.mesh()), count, 11);
  TaylorErrors e;
  for (const vec3& x : points) {
    const double exact = winding_number_exact(view, x).w;
    for (int order = 0; order <= 2; ++order) {
      const double err = std::abs(winding_number(view, x, {order, beta}).w - exact);
      e.max[order] = std::max(e.max[order], err);
      e.rms[order] += err * err;
    }
  }
  for (double& r : e.rms) r = std::sqrt(r / double(points.size()));
  return e;
}

struct TaylorCase {
  const char* mesh;
  float beta;
};
std::ostream& operator<<(std::ostream& os, const TaylorCase& c) { return os << c.mesh << " beta=" << c.beta; }

class TaylorOnRealMeshes : public ::testing::TestWithParam<TaylorCase> {};

TEST_P(TaylorOnRealMeshes, OrderTwoWithinToleranceAndErrorsFallWithOrder) {
  const GwnModel model = build_model(load_test_mesh(GetParam().mesh));
  const TaylorErrors e = taylor_errors(model, 3000, GetParam().beta);
  RecordProperty("max_err_order0", std::to_string(e.max[0]));
  RecordProperty("max_err_order2", std::to_string(e.max[2]));
  EXPECT_LE(e.max[2], 2e-3);
  EXPECT_LT(e.rms[1], e.rms[0]);
  EXPECT_LT(e.rms[2], e.rms[1]);
  EXPECT_LT(e.max[2], e.max[0]);
}

INSTANTIATE_TEST_SUITE_P(Meshes, TaylorOnRealMeshes,
                         ::testing::Values(TaylorCase{"bunny.obj", 2.0f}, TaylorCase{"teapot.obj", 2.0f},
                                           TaylorCase{"bunny_holes.obj", 2.0f},
                                           TaylorCase{"dragon_vrip_res4.ply", 2.0f}));

#if GWNRT_HOST_LANES && defined(__AVX2__)
// Records what a lane traversal hands its visitor: each far cluster as (node, lane) and each
// near triangle. With far_lane_pair when Pairs, so that visit_multipole_lanes visits node pairs.
template <bool Pairs>
struct VisitRecord {
  std::vector<std::pair<uint32_t, int>> far;
  std::vector<uint32_t> near_triangles;
  void far_lanes(uint32_t node, i4 mask, f4, f4, f4) {
    for (int l = 0; l < 4; ++l)
      if (mask[l]) far.emplace_back(node, l);
  }
  void far_lane_pair(uint32_t a, uint32_t b, i8 mask, f8, f8, f8) requires Pairs {
    for (int l = 0; l < 8; ++l)
      if (mask[l]) far.emplace_back(l < 4 ? a : b, l & 3);
  }
  void near(uint32_t t, const vec3&, const vec3&, const vec3&) { near_triangles.push_back(t); }
  void sort() {
    std::sort(far.begin(), far.end());
    std::sort(near_triangles.begin(), near_triangles.end());
  }
};

template <int PairsBelow>
VisitRecord<true> visit_in_pairs(const TriangleTreeView& tree, const vec3& x, float scale2) {
  VisitRecord<true> r;
  detail::visit_multipole_lanes<PairsBelow>(tree, x, scale2, scale2 * kLeafExpansionScale * kLeafExpansionScale, r);
  r.sort();
  return r;
}

// The node-pair traversal (Taylor w on AVX2) hands over exactly the clusters and triangles that
// one node at a time does, also once its stack passes the point where it falls back to single
// nodes (forced here by a threshold of 2); with nothing far, every triangle exactly once.
TEST(WindingNumber, NodePairTraversalVisitsWhatSingleNodesDo) {
  const GwnModel model = build_model(load_test_mesh("dragon_vrip_res4.ply"));
  const TriangleTreeView tree = model.triangle_view();
  for (const vec3& x : test::sample_points(test::mesh_bounds(model.mesh()), 300, 5)) {
    for (const float beta : {0.5f, 2.0f, kInfinity}) {
      const float scale2 = beta * beta;
      VisitRecord<false> single;
      detail::visit_multipole_lanes(tree, x, scale2, scale2 * kLeafExpansionScale * kLeafExpansionScale, single);
      single.sort();
      for (const VisitRecord<true>& pairs :
           {visit_in_pairs<kTraversalStackSize>(tree, x, scale2), visit_in_pairs<2>(tree, x, scale2)}) {
        ASSERT_EQ(pairs.far, single.far) << "beta " << beta;
        ASSERT_EQ(pairs.near_triangles, single.near_triangles) << "beta " << beta;
      }
      if (beta == kInfinity) {
        ASSERT_TRUE(single.far.empty());
        ASSERT_EQ(single.near_triangles.size(), model.mesh().triangles.size());
        for (size_t i = 0; i < single.near_triangles.size(); ++i) ASSERT_EQ(single.near_triangles[i], i);
      }
    }
  }
}
#endif

// ∇w without H_w goes through the host's lane visitor (TaylorLanesSum<Order, true>): far lanes
// four or eight at a time, near triangles' w eight at a time, their ∇Ω in float or, where the
// lane finds float ill-conditioned, in double. The scalar visitor (the device's, and the host's
// when H_w is asked) sums the same terms in float in another order, so the two differ by the
// rounding of the sum, which scales with its largest terms, not with its result: beside an edge
// two triangles' terms of 1e5 cancel to 1e-2. Measured here: at most 7.8 float epsilons of
// Σ|∇Ω_t|/4π (the triangles' terms, in double), against 64 allowed; leaving out the far lanes of
// node pairs, or the ill-conditioned near triangles' double ∇Ω, gave 3.6e6 epsilons and more.
// w is w alone's, to rounding.
template <int Order>
vec3 scalar_visitor_gradient(const TriangleTreeView& tree, const vec3& x, float beta) {
  detail::TaylorSum<Order, true, false> sum{tree, x, {}};
  visit_multipole(tree, x, beta, sum);
  return sum.acc.gradient * kInv4Pi;
}

TEST(WindingNumber, GradientByLanesIsTheScalarVisitorsUpToRounding) {
  constexpr double kEpsilon = 0x1p-24;
  for (const char* name : {"bunny_holes.obj", "teapot.obj", "dragon_vrip_res4.ply"}) {
    const GwnModel model = build_model(load_test_mesh(name));
    const TriangleTreeView tree = model.triangle_view();
    const Aabb box = test::mesh_bounds(model.mesh());
    const float diag = glm::length(box.hi - box.lo);
    std::vector<vec3> points = test::sample_points(box, 300, 17);
    // And points beside edges and faces, where near triangles are ill-conditioned in float.
    const Mesh& m = model.mesh();
    for (size_t t = 0; t < m.triangles.size(); t += m.triangles.size() / 100) {
      const vec3 a = m.positions[m.triangles[t][0]], b = m.positions[m.triangles[t][1]],
                 c = m.positions[m.triangles[t][2]];
      const vec3 normal = glm::normalize(glm::cross(b - a, c - a));
      points.push_back(0.5f * (a + b) + 1e-6f * diag * normal);
      points.push_back((a + b + c) / 3.0f + 1e-4f * diag * normal);
    }
    double worst = 0;
    for (const vec3& x : points) {
      double terms = 0;  // Σ|∇Ω_t| / 4π
      for (uint32_t t = 0; t < tree.triangle_count; ++t)
        terms += glm::length(triangle_solid_angle_gradient(dvec3(tree.vertices[3 * t]), dvec3(tree.vertices[3 * t + 1]),
                                                           dvec3(tree.vertices[3 * t + 2]), dvec3(x)));
      terms /= 4 * kPi;
      const auto check = [&]<int Order>() {
        const WindingSample lanes = winding_number_taylor<Order, true, false>(tree, x, 2.0f);
        const vec3 scalar = scalar_visitor_gradient<Order>(tree, x, 2.0f);
        const float w_alone = winding_number_taylor<Order, false, false>(tree, x, 2.0f).w;
        EXPECT_NEAR(lanes.w, w_alone, 1e-6f) << name << " order " << Order;
        const double epsilons = glm::length(dvec3(lanes.gradient) - dvec3(scalar)) / (kEpsilon * terms);
        worst = std::max(worst, epsilons);
        EXPECT_LE(epsilons, 64.0) << name << " order " << Order << " at " << x.x << " " << x.y << " " << x.z;
      };
      check.template operator()<0>();
      check.template operator()<1>();
      check.template operator()<2>();
    }
    std::printf("%s: lanes against the scalar visitor's gradient: at most %.3g epsilons of the terms\n", name, worst);
  }
}

// Points at least `clearance` from every triangle, so that w is smooth around them.
std::vector<vec3> points_away_from_mesh(const GwnModel& model, size_t count, float clearance, uint32_t seed) {
  const Aabb box = test::mesh_bounds(model.mesh());
  std::vector<vec3> out;
  for (const vec3& x : test::sample_points(box, 20 * count, seed)) {
    double best = 1e30;
    const auto& m = model.mesh();
    for (const uvec3& t : m.triangles) {
      const dvec3 p0(m.positions[t[0]]), p1(m.positions[t[1]]), p2(m.positions[t[2]]);
      // Cheap lower bound first: distance to the triangle's bounding sphere.
      const dvec3 c = (p0 + p1 + p2) / 3.0;
      const double rad = std::max({glm::length(p0 - c), glm::length(p1 - c), glm::length(p2 - c)});
      best = std::min(best, glm::length(dvec3(x) - c) - rad);
    }
    if (best > clearance) out.push_back(x);
    if (out.size() == count) break;
  }
  return out;
}

class DerivativesOnRealMeshes : public ::testing::TestWithParam<const char*> {};

TEST_P(DerivativesOnRealMeshes, GradientAndHessianMatchFiniteDifferences) {
  const GwnModel model = build_model(load_test_mesh(GetParam()));
  const auto view = model.triangle_view();
  const Aabb box = test::mesh_bounds(model.mesh());
  const double diag = glm::length(box.hi - box.lo);
  const double clearance = 0.02 * diag;
  const auto points = points_away_from_mesh(model, 40, float(clearance), 5);
  ASSERT_GE(points.size(), 20u);
  const double h = 1e-4 * diag;
  for (const vec3& xf : points) {
    const dvec3 x(xf);
    // Finite differences in double of the exact (double) sum; the error is O(h²) relative to the
    // third derivative, far below the tolerance at this clearance.
    auto w_at = [&](const dvec3& p) {
      double omega = 0;
      for (uint32_t t = 0; t < view.triangle_count; ++t)
        omega += triangle_solid_angle(dvec3(view.vertices[3 * t]), dvec3(view.vertices[3 * t + 1]),
                                      dvec3(view.vertices[3 * t + 2]), p);
      return omega / (4 * kPi);
    };
    dvec3 fd_grad;
    double fd_hess[3][3];
    for (int i = 0; i < 3; ++i) {
      dvec3 e(0.0);
      e[i] = h;
      fd_grad[i] = (w_at(x + e) - w_at(x - e)) / (2 * h);
      for (int j = 0; j < 3; ++j) {
        dvec3 f(0.0);
        f[j] = h;
        fd_hess[i][j] = (w_at(x + e + f) - w_at(x + e - f) - w_at(x - e + f) + w_at(x - e - f)) / (4 * h * h);
      }
    }
    const WindingSampleExact exact = winding_number_exact(view, xf, true, true);
    const double gscale = glm::length(fd_grad) + 1e-3 / diag;
    double hscale = 1e-3 / (diag * diag);
    for (auto& row : fd_hess)
      for (double v : row) hscale = std::max(hscale, std::abs(v));
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(exact.gradient[i], fd_grad[i], 1e-4 * gscale);
    const double eh[3][3] = {{exact.hessian.xx, exact.hessian.xy, exact.hessian.xz},
                             {exact.hessian.xy, exact.hessian.yy, exact.hessian.yz},
                             {exact.hessian.xz, exact.hessian.yz, exact.hessian.zz}};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) EXPECT_NEAR(eh[i][j], fd_hess[i][j], 1e-3 * hscale) << i << j;
    EXPECT_NEAR(exact.hessian.trace(), 0.0, 1e-9 * hscale);

    // The tree's order-2 far field and float near field, against the exact derivatives. The
    // truncation error of w is absolute (~2e-3 at beta = 2, see TaylorOnRealMeshes) and every
    // expanded cluster is at least `clearance` away, so each derivative scales it by ~1/clearance.
    const WindingSample taylor = winding_number(view, xf, {2, 2.0f}, true, true);
    const double gtol = 4e-3 / clearance, htol = 8e-3 / (clearance * clearance);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(taylor.gradient[i], exact.gradient[i], gtol);
    const float th[3][3] = {{taylor.hessian.xx, taylor.hessian.xy, taylor.hessian.xz},
                            {taylor.hessian.xy, taylor.hessian.yy, taylor.hessian.yz},
                            {taylor.hessian.xz, taylor.hessian.yz, taylor.hessian.zz}};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) EXPECT_NEAR(th[i][j], eh[i][j], htol) << i << j;
    // Each far term and each near term is harmonic, so the trace is round-off only.
    EXPECT_NEAR(taylor.hessian.trace(), 0.0f, 1e-4 * htol);
  }
}

INSTANTIATE_TEST_SUITE_P(Meshes, DerivativesOnRealMeshes, ::testing::Values("bunny_holes.obj", "teapot.obj"));

TEST(WindingNumber, FarFieldDerivativesAreTheDerivativesOfItsValue) {
  // Self-consistency of the expansion formulas: the order-k gradient and Hessian must be the
  // derivatives of the order-k value (finite differences in float of a cluster far away).
  const GwnModel model = build_model(load_test_mesh("teapot.obj"));
  const auto view = model.triangle_view();
  const Aabb box = test::mesh_bounds(model.mesh());
  const float diag = glm::length(box.hi - box.lo);
  for (int order = 0; order <= 2; ++order) {
    const vec3 x = box.centre() + vec3(1.3f, -0.7f, 0.9f) * diag;  // whole tree is far: pure expansion
    const WindingSample s = winding_number(view, x, {order, 2.0f}, true, true);
    const float h = 1e-3f * diag;
    for (int i = 0; i < 3; ++i) {
      vec3 e(0.0f);
      e[i] = h;
      const float fd =
          (winding_number(view, x + e, {order, 2.0f}).w - winding_number(view, x - e, {order, 2.0f}).w) / (2 * h);
      EXPECT_NEAR(s.gradient[i], fd, 2e-3f * glm::length(s.gradient) + 1e-9f) << "order " << order << " axis " << i;
      const WindingSample sp = winding_number(view, x + e, {order, 2.0f}, true, false);
      const WindingSample sm = winding_number(view, x - e, {order, 2.0f}, true, false);
      const vec3 col = (sp.gradient - sm.gradient) / (2 * h);
      const float hrow[3][3] = {{s.hessian.xx, s.hessian.xy, s.hessian.xz},
                                {s.hessian.xy, s.hessian.yy, s.hessian.yz},
                                {s.hessian.xz, s.hessian.yz, s.hessian.zz}};
      const float scale = glm::length(col) + 1e-12f;
      for (int j = 0; j < 3; ++j) EXPECT_NEAR(hrow[j][i], col[j], 5e-3f * scale) << "order " << order;
    }
    EXPECT_NEAR(s.hessian.trace(), 0.0f, 1e-4f * std::abs(s.hessian.xx) + 1e-12f);
  }
}

}  // namespace
}  // namespace gwnrt
