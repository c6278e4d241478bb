// Exact w by signed crossings plus the boundary cone (field/crossing_winding.h): against the
// double brute force of reference/ on the bundled meshes and on soups built here, with rays
// placed exactly through vertices and edges of M and of the cone; ∇w and H_w against central
// differences of the brute-force w; the sheet classification by crossings against the
// brute-force sides; and the rule by which `auto` chooses.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "gwnrt/field/distance.h"
#include "gwnrt/field/evaluate_winding.h"
#include "reference/brute_force_winding.h"
#include "reference/parallel_over.h"
#include "test_util.h"

namespace gwnrt {
namespace {

using test::build_model;
using test::load_test_mesh;

using test::kCrossingNearMesh;
using test::kCrossingTolerance;

// A soup that lists some faces two and three times (the second copy of every seventh face, a
// third of every 31st), with its own vertices per copy: w jumps by 2 or 3 across those.
Mesh stacked_soup(const Mesh& base) {
  Mesh m = base;
  for (size_t t = 0; t < base.triangles.size(); ++t) {
    const int copies = (t % 31 == 0) ? 2 : (t % 7 == 0 ? 1 : 0);
    for (int c = 0; c < copies; ++c) {
      const uint32_t first = uint32_t(m.positions.size());
      for (int k = 0; k < 3; ++k) m.positions.push_back(base.positions[base.triangles[t][k]]);
      m.triangles.push_back({first, first + 1, first + 2});
    }
  }
  return m;
}

// Every fifth face flipped: an inconsistently oriented mesh (each flipped face's edges are ∂M
// twice over).
Mesh flipped_faces(const Mesh& base) {
  Mesh m = base;
  for (size_t t = 0; t < m.triangles.size(); t += 5) std::swap(m.triangles[t][1], m.triangles[t][2]);
  return m;
}

// Random triangles over a small pool of random vertices: non-manifold edges, intersections.
Mesh random_soup(uint32_t seed, int vertices, int triangles) {
  test::Random rng(seed);
  Mesh m;
  for (int i = 0; i < vertices; ++i)
    m.positions.push_back({rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)});
  while (int(m.triangles.size()) < triangles) {
    const uint32_t a = uint32_t(rng.index(vertices)), b = uint32_t(rng.index(vertices)),
                   c = uint32_t(rng.index(vertices));
    if (a != b && b != c && a != c) m.triangles.push_back({a, b, c});
  }
  return m;
}

// Every triangle shrunk about its centroid: no two share a corner, every edge is ∂M.
Mesh shrunk_soup(const Mesh& base) {
  Mesh m;
  for (const uvec3& t : base.triangles) {
    const vec3 c = (base.positions[t[0]] + base.positions[t[1]] + base.positions[t[2]]) / 3.0f;
    const uint32_t first = uint32_t(m.positions.size());
    for (int k = 0; k < 3; ++k) m.positions.push_back(c + 0.9f * (base.positions[t[k]] - c));
    m.triangles.push_back({first, first + 1, first + 2});
  }
  return m;
}

// The cube [-1, 1]³ with each face a 4x4 grid of squares (coordinates multiples of 1/2, exact
// in float) and the four middle squares of the top face removed: ∂M is the square of side 1
// at z = 1, the cone's apex its centre (0, 0, 1), and edge midpoints are exact too.
Mesh holed_grid_cube() {
  Mesh m;
  const int n = 4;
  auto corner = [&](int axis, float side, int i, int j) {
    vec3 p;
    p[axis] = side;
    p[(axis + 1) % 3] = -1.0f + 0.5f * float(i);
    p[(axis + 2) % 3] = -1.0f + 0.5f * float(j);
    return p;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (float side : {-1.0f, 1.0f})
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          if (axis == 2 && side > 0 && (i == 1 || i == 2) && (j == 1 || j == 2)) continue;
          const uint32_t first = uint32_t(m.positions.size());
          m.positions.insert(m.positions.end(), {corner(axis, side, i, j), corner(axis, side, i + 1, j),
                                                 corner(axis, side, i + 1, j + 1), corner(axis, side, i, j + 1)});
          // (axis+1, axis+2, axis) is right-handed: this winding faces +axis; flip for the -1 side.
          if (side > 0)
            m.triangles.insert(m.triangles.end(), {{first, first + 1, first + 2}, {first, first + 2, first + 3}});
          else
            m.triangles.insert(m.triangles.end(), {{first, first + 2, first + 1}, {first, first + 3, first + 2}});
        }
  return m;
}

struct Case {
  std::string name;
  Mesh mesh;
};

std::vector<Case> accuracy_cases() {
  std::vector<Case> cases;
  for (const char* name : {"bunny.obj", "bunny_holes.obj", "teapot.obj", "dragon_vrip_res4.ply"})
    cases.push_back({name, load_test_mesh(name)});
  const Mesh bunny_holes = load_test_mesh("bunny_holes.obj");
  cases.push_back({"stacked soup (bunny_holes)", stacked_soup(bunny_holes)});
  cases.push_back({"flipped faces (bunny)", flipped_faces(load_test_mesh("bunny.obj"))});
  cases.push_back({"random non-manifold soup", random_soup(7, 60, 300)});
  cases.push_back({"holed grid cube", holed_grid_cube()});
  // A scan whose rim (1,304 segments, pinched at 105 points) the cone spans rather than fans.
  cases.push_back({"birdBath scan", load_test_mesh("realworld/birdBath_ggg_photogrammetry.obj")});
  return cases;
}

struct Comparison {
  size_t compared = 0, skipped = 0;
  double max_error = 0;
};

// Crossing w at `points` against the brute force, for those farther than kCrossingNearMesh·diag from M.
Comparison compare_with_brute_force(const std::string& name, const GwnModel& model, const reference::ReferenceMesh& ref,
                                    const std::vector<vec3>& points) {
  const ModelView v = model.view();
  std::vector<double> error(points.size(), -1.0);
  reference::parallel_over(points.size(), [&](size_t i) {
    if (unsigned_distance(v.triangles, points[i]).distance <= kCrossingNearMesh * ref.diagonal) return;
    const double w = winding_number_crossing<false, false>(v, points[i]).w;
    error[i] = std::fabs(w - reference::reference_w(ref, dvec3(points[i])));
  });
  Comparison c;
  for (size_t i = 0; i < points.size(); ++i) {
    if (error[i] < 0) {
      ++c.skipped;
      continue;
    }
    ++c.compared;
    c.max_error = std::max(c.max_error, error[i]);
    EXPECT_LE(error[i], kCrossingTolerance)
        << name << ": point " << i << " (" << points[i].x << ", " << points[i].y << ", " << points[i].z << ")";
  }
  return c;
}

// UnwrappedAngleSum (solid_angle.h) is Σ atan2 itself, not modulo 2π, over factors of any
// magnitude; on the host its four-lane form (each lane a product of its own, added together at
// the end) gives the same sum. Half the trials take angles of one sign only, so that the running
// argument winds up to ~100 times.
TEST(CrossingWinding, UnwrappedAngleSumIsTheSumOfAtan2NotModulo2Pi) {
  std::mt19937 rng(913);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double max_error = 0, max_turns = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const int n = 1 + int(u(rng) * 400);
    UnwrappedAngleSum sum;
    long double reference = 0;
#if GWNRT_HOST_LANES && defined(__AVX__)
    UnwrappedAngleSumT<d4, l4> lanes;
    d4 numerators{}, denominators{};
#endif
    for (int k = 0; k < n; ++k) {
      double numerator, denominator;
      const double type = u(rng);
      if (type < 0.1) {  // no angle (x on a vertex, zero area)
        numerator = 0.0;
        denominator = 0.0;
      } else if (type < 0.2) {  // on an axis but the negative real one (x inside a triangle's plane, which the callers
                                // move off)
        const double m = std::pow(10.0, 80.0 * u(rng) - 40.0);
        const int axis = int(u(rng) * 3.0);
        numerator = axis == 0 ? 0.0 : (axis == 1 ? m : -m);
        denominator = axis == 0 ? m : 0.0;
      } else {  // an angle in (-π, π), or in (0, π) for odd trials, at a magnitude from 1e-40 to 1e40
        const double t = trial % 2 ? kPi * u(rng) : kPi * (2.0 * u(rng) - 1.0);
        const double m = std::pow(10.0, 80.0 * u(rng) - 40.0);
        numerator = m * std::sin(t);
        denominator = m * std::cos(t);
      }
      if (!(numerator == 0.0 && denominator == 0.0))
        reference += std::atan2((long double)numerator, (long double)denominator);
      sum.add(numerator, denominator);
#if GWNRT_HOST_LANES && defined(__AVX__)
      numerators[k % 4] = numerator;
      denominators[k % 4] = denominator;
      if (k % 4 == 3 || k == n - 1) {
        for (int l = k % 4 + 1; l < 4; ++l) numerators[l] = denominators[l] = 0.0;  // no angle
        lanes.add(numerators, denominators);
      }
#endif
    }
    // Each double product turns the running argument by ~1e-16 rad: 400 of them stay below 1e-13.
    const double error = std::fabs(sum.angle() - double(reference));
    EXPECT_LE(error, 1e-12) << "trial " << trial << " n " << n << " sum " << sum.angle() << " reference "
                            << double(reference);
    max_error = std::max(max_error, error);
    max_turns = std::max(max_turns, std::fabs(double(reference)) / (2.0 * kPi));
#if GWNRT_HOST_LANES && defined(__AVX__)
    UnwrappedAngleSum from_lanes;
    add_lanes_to(lanes, from_lanes);
    EXPECT_LE(std::fabs(from_lanes.angle() - double(reference)), 1e-12) << "trial " << trial << " (four lanes)";
#endif
  }
  EXPECT_GT(max_turns, 50.0);
  std::printf("[ angle sum     ] max |Σ - Σ atan2| %.3g rad, up to %.0f turns\n", max_error, max_turns);
}

TEST(CrossingWinding, MatchesBruteForceOnMeshesAndSoups) {
  for (Case& c : accuracy_cases()) {
    const reference::ReferenceMesh ref = reference::reference_mesh(c.mesh);
    const Aabb box = test::mesh_bounds(c.mesh);
    const GwnModel model = build_model(std::move(c.mesh));
    // Fewer points on the scan under AddressSanitizer (its 35k triangles' brute force).
    const size_t count = test::kAddressSanitizer && model.mesh().triangles.size() > 20000 ? 400 : 1500;
    const std::vector<vec3> points = test::sample_points(box, count, 3);
    const Comparison r = compare_with_brute_force(c.name, model, ref, points);
    EXPECT_GT(r.compared, count * 2 / 3) << c.name;
    std::printf(
        "[ %-26s ] %zu triangles, %u cone triangles over %zu segments: max |dw| %.2e over %zu points (%zu "
        "nearer M)\n",
        c.name.c_str(), model.mesh().triangles.size(), model.view().cone.triangle_count,
        model.boundary().segment_count(), r.max_error, r.compared, r.skipped);
  }
}

// BuildOptions allows leaves of up to kMaxLeafSize triangles; the host's cone sum took a near
// leaf four triangles at a time and left out the rest (w up to 0.5 off with leaves of 8).
TEST(CrossingWinding, EveryLeafSizeMatchesBruteForce) {
  const Mesh mesh = load_test_mesh("bunny_holes.obj");
  const reference::ReferenceMesh ref = reference::reference_mesh(mesh);
  const std::vector<vec3> points = test::sample_points(test::mesh_bounds(mesh), 400, 5);
  for (const uint32_t leaf : {1u, 5u, 8u, kMaxLeafSize}) {
    BuildOptions options;
    options.max_leaf_triangles = leaf;
    GwnModel model;
    ASSERT_TRUE(GwnModel::build(mesh, model, options).ok());
    const Comparison r = compare_with_brute_force("leaves of " + std::to_string(leaf), model, ref, points);
    EXPECT_GT(r.compared, 300u);
    std::printf("[ leaves of %2u ] max |dw| %.2e over %zu points\n", leaf, r.max_error, r.compared);
  }
}

// Points from which the ray (the shortest axis exit, shortest_exit_axis_ray) passes exactly
// through `target`: target moved back along each axis direction by `back`, kept where that
// direction is the one the method picks. The other two coordinates equal the target's exactly.
std::vector<vec3> points_with_rays_through(const Aabb& box, const vec3& target, float back) {
  std::vector<vec3> out;
  for (int k = 0; k < 3; ++k)
    for (float sign : {1.0f, -1.0f}) {
      vec3 x = target;
      x[k] -= sign * back;
      const RayFrame f = shortest_exit_axis_ray(box, x);
      if (f.kz == k && (f.sz > 0.0f) == (sign > 0.0f)) out.push_back(x);
    }
  return out;
}

TEST(CrossingWinding, RaysExactlyThroughVerticesAndEdgesOfMeshAndCone) {
  struct Mesh_ {
    std::string name;
    Mesh mesh;
  };
  std::vector<Mesh_> meshes;
  meshes.push_back({"holed grid cube", holed_grid_cube()});
  meshes.push_back({"bunny_holes", load_test_mesh("bunny_holes.obj")});
  meshes.push_back({"teapot", load_test_mesh("teapot.obj")});
  for (Mesh_& m : meshes) {
    const reference::ReferenceMesh ref = reference::reference_mesh(m.mesh);
    const Aabb box = test::mesh_bounds(m.mesh);
    const float diagonal = float(ref.diagonal);
    // Targets: every vertex of M; every edge midpoint that is exactly the midpoint (so on the
    // edge: all of them for the grid); the cone's vertices (its apexes and ∂M) and the exact
    // midpoints of its edges.
    std::vector<vec3> targets = m.mesh.positions;
    auto add_midpoint = [&](const vec3& a, const vec3& b) {
      const vec3 mid = 0.5f * (a + b);
      if (dvec3(mid) - dvec3(a) == dvec3(b) - dvec3(mid)) targets.push_back(mid);
    };
    for (const uvec3& t : m.mesh.triangles)
      for (int k = 0; k < 3; ++k) add_midpoint(m.mesh.positions[t[k]], m.mesh.positions[t[(k + 1) % 3]]);
    const GwnModel model = build_model(std::move(m.mesh));
    const TriangleTreeView cone = model.view().cone;
    size_t cone_targets = 0;
    for (uint32_t t = 0; t < cone.triangle_count; ++t)
      for (int k = 0; k < 3; ++k) {
        targets.push_back(cone.vertices[3 * t + k]);
        add_midpoint(cone.vertices[3 * t + k], cone.vertices[3 * t + (k + 1) % 3]);
        cone_targets += 2;
      }
    std::vector<vec3> points;
    for (const vec3& target : targets)
      for (float back : {0.01f, 0.13f})
        for (const vec3& x : points_with_rays_through(box, target, back * diagonal)) points.push_back(x);
    const Comparison r = compare_with_brute_force(m.name, model, ref, points);
    EXPECT_GT(r.compared, points.size() / 2) << m.name;
    std::printf("[ %-16s ] %zu rays through %zu targets (%zu on the cone): max |dw| %.2e (%zu nearer M)\n",
                m.name.c_str(), r.compared, targets.size(), cone_targets, r.max_error, r.skipped);
  }
}

TEST(CrossingWinding, PointsExactlyOnTheConeAtTheOrigin) {
  // The holed grid cube moved down by 1: its hole lies in the plane z = 0 and its cone is the
  // flat square there with the apex at the origin. Points exactly on it (the apex itself, on an
  // inner edge, inside a cone triangle, on the hole's rim line's extension) have w_C undefined;
  // w is continuous there and must match the brute force. Coordinates near 0 must still be moved
  // far enough off the cone to leave it (a move by ulps of x alone would not).
  Mesh mesh = holed_grid_cube();
  for (vec3& p : mesh.positions) p.z -= 1.0f;
  const reference::ReferenceMesh ref = reference::reference_mesh(mesh);
  const GwnModel model = build_model(std::move(mesh));
  const ModelView v = model.view();
  ASSERT_EQ(v.cone.triangle_count, 8u);
  const vec3 points[] = {{0.0f, 0.0f, 0.0f},   {0.25f, 0.0f, 0.0f},  {0.0f, -0.25f, 0.0f}, {0.1f, 0.2f, 0.0f},
                         {-0.3f, 0.05f, 0.0f}, {0.25f, 0.25f, 0.0f}, {1e-30f, 0.0f, 0.0f}, {0.0f, 0.0f, 1e-20f}};
  for (const vec3& x : points) {
    const double want = reference::reference_w(ref, dvec3(x));
    const float w = winding_number_crossing<false, false>(v, x).w, w_all = winding_number_crossing<true, true>(v, x).w;
    EXPECT_NEAR(w, want, kCrossingTolerance) << x.x << ", " << x.y << ", " << x.z;
    EXPECT_NEAR(w_all, want, kCrossingTolerance) << x.x << ", " << x.y << ", " << x.z;
  }
}

// Central differences of the brute-force w: ∇w with h = 1e-4·diag (truncation (h/d)²/6 < 1e-6
// of |∇w| at d >= 0.05·diag; rounding 1e-14/h), H_w from second differences.
dvec3 difference_gradient(const reference::ReferenceMesh& ref, const dvec3& x, double h) {
  dvec3 g;
  for (int a = 0; a < 3; ++a) {
    dvec3 e(0.0);
    e[a] = h;
    g[a] = (reference::reference_w(ref, x + e) - reference::reference_w(ref, x - e)) / (2 * h);
  }
  return g;
}

double second_difference(const reference::ReferenceMesh& ref, const dvec3& x, double h, int a, int b) {
  dvec3 ea(0.0), eb(0.0);
  ea[a] = h;
  eb[b] = h;
  if (a == b)
    return (reference::reference_w(ref, x + ea) - 2 * reference::reference_w(ref, x) +
            reference::reference_w(ref, x - ea)) /
           (h * h);
  return (reference::reference_w(ref, x + ea + eb) - reference::reference_w(ref, x + ea - eb) -
          reference::reference_w(ref, x - ea + eb) + reference::reference_w(ref, x - ea - eb)) /
         (4 * h * h);
}

// Richardson's extrapolation of the second differences at h and h/2: truncation O(h⁴), about
// (h/d)⁴ = 3e-6 relative at d >= 0.05·diag with h = 2e-3·diag; rounding 1e-14/(h/2)² =
// 1e-8/diag².
double difference_hessian(const reference::ReferenceMesh& ref, const dvec3& x, double h, int a, int b) {
  return (4.0 * second_difference(ref, x, 0.5 * h, a, b) - second_difference(ref, x, h, a, b)) / 3.0;
}

TEST(CrossingWinding, GradientAndHessianFromTheConeMatchDifferences) {
  std::vector<Case> cases;
  cases.push_back({"bunny_holes", load_test_mesh("bunny_holes.obj")});
  cases.push_back({"teapot", load_test_mesh("teapot.obj")});
  cases.push_back({"holed grid cube", holed_grid_cube()});
  for (Case& c : cases) {
    const reference::ReferenceMesh ref = reference::reference_mesh(c.mesh);
    const Aabb box = test::mesh_bounds(c.mesh);
    const GwnModel model = build_model(std::move(c.mesh));
    const ModelView v = model.view();
    const double diag = ref.diagonal;
    std::vector<vec3> points;
    for (const vec3& x : test::sample_points(box, 3000, 5))
      if (unsigned_distance(v.triangles, x).distance > 0.05 * diag && points.size() < 150) points.push_back(x);
    ASSERT_GE(points.size(), 100u) << c.name;
    std::vector<double> grad_error(points.size()), hess_error(points.size());
    reference::parallel_over(
        points.size(),
        [&](size_t i) {
          const dvec3 x(points[i]);
          const WindingSample s = winding_number_crossing<true, true>(v, points[i]);
          const dvec3 g = difference_gradient(ref, x, 1e-4 * diag);
          // Relative 1e-4 where |∇w| > 1e-3/diag, absolute 1e-7/diag elsewhere.
          grad_error[i] = glm::length(dvec3(s.gradient) - g) / std::max(1e-4 * glm::length(g), 1e-7 / diag);
          const double h = 2e-3 * diag;
          const double got[6] = {s.hessian.xx, s.hessian.xy, s.hessian.xz, s.hessian.yy, s.hessian.yz, s.hessian.zz};
          const int pairs[6][2] = {{0, 0}, {0, 1}, {0, 2}, {1, 1}, {1, 2}, {2, 2}};
          double want[6], norm = 0, diff = 0;
          for (int k = 0; k < 6; ++k) {
            want[k] = difference_hessian(ref, x, h, pairs[k][0], pairs[k][1]);
            norm = std::max(norm, std::fabs(want[k]));
          }
          for (int k = 0; k < 6; ++k) diff = std::max(diff, std::fabs(got[k] - want[k]));
          // The same tolerances for H_w: relative 1e-4, absolute 1e-7/diag² where it is small.
          hess_error[i] = diff / std::max(1e-4 * norm, 1e-7 / (diag * diag));
        },
        4);
    double worst_g = 0, worst_h = 0;
    for (size_t i = 0; i < points.size(); ++i) {
      EXPECT_LE(grad_error[i], 1.0) << c.name << " gradient at point " << i;
      EXPECT_LE(hess_error[i], 1.0) << c.name << " Hessian at point " << i;
      worst_g = std::max(worst_g, grad_error[i]);
      worst_h = std::max(worst_h, hess_error[i]);
    }
    std::printf("[ %-16s ] %zu points: gradient error / tolerance %.3f, Hessian error / tolerance %.3f\n",
                c.name.c_str(), points.size(), worst_g, worst_h);
  }
}

// The host's lane visitors (ConeCrossingVisitor) give what the scalar one (the device's) gives:
// w_C and ∇w_C up to float round-off in the order of the far sums, the same jumps ahead and the
// same on-cone decisions, at the betas the mesher and the queries use.
TEST(CrossingWinding, LaneVisitorsMatchTheScalarConeSum) {
  for (const char* name : {"bunny_holes.obj", "teapot.obj", "realworld/birdBath_ggg_photogrammetry.obj"}) {
    const GwnModel model = build_model(load_test_mesh(name));
    const ModelView v = model.view();
    const Aabb box = model.bounds();
    const vec3 extent = box.hi - box.lo;
    const double diag = glm::length(dvec3(extent));
    double worst_w = 0, worst_g = 0;
    for (const vec3& x : test::sample_points({box.lo - 0.1f * extent, box.hi + 0.1f * extent}, 400, 41))
      for (const float beta : {kConeBeta, 8.0f, kConeDerivativeBeta}) {
        const RayFrame frame = shortest_exit_axis_ray(v.bounds, x);
        detail::ConeCrossingSum<true, false> scalar(v.cone, frame, x, beta, nullptr);
        scalar.traverse();
        detail::ConeCrossingVisitor<true, false>::type lanes(v.cone, frame, x, beta, nullptr);
        lanes.traverse();
        detail::ConeCrossingVisitor<false, false>::type w_lanes(v.cone, frame, x, beta, nullptr);
        w_lanes.traverse();
        ASSERT_EQ(lanes.on_cone, scalar.on_cone) << name;
        if (scalar.on_cone) continue;
        EXPECT_EQ(lanes.jumps, scalar.jumps) << name;
        EXPECT_EQ(w_lanes.jumps, scalar.jumps) << name;
        const double w = detail::crossing_winding(scalar, 0);
        const double dw = std::max(std::fabs(detail::crossing_winding(lanes, 0) - w),
                                   std::fabs(detail::crossing_winding(w_lanes, 0) - w));
        const dvec3 g(detail::cone_gradient(scalar));
        const double dg = glm::length(dvec3(detail::cone_gradient(lanes)) - g) / (glm::length(g) + 1.0 / diag);
        EXPECT_LE(dw, 1e-6) << name << " beta " << beta;
        EXPECT_LE(dg, 1e-5) << name << " beta " << beta;
        worst_w = std::max(worst_w, dw);
        worst_g = std::max(worst_g, dg);
      }
    std::printf("[ %-26.26s ] lanes against scalar: max |dw| %.2e, max |dg| / (|g| + 1/diag) %.2e\n", name, worst_w,
                worst_g);
  }
}

TEST(CrossingWinding, ClosedMeshHasZeroGradientAndHessianAndWholeNumbers) {
  const GwnModel model = build_model(load_test_mesh("bunny.obj"));
  const ModelView v = model.view();
  ASSERT_EQ(v.cone.triangle_count, 0u);
  for (const vec3& x : test::sample_points(model.bounds(), 500, 9)) {
    const WindingSample s = winding_number_crossing<true, true>(v, x);
    EXPECT_TRUE(s.w == 0.0f || s.w == 1.0f) << s.w;
    EXPECT_EQ(s.gradient, vec3(0.0f));
    EXPECT_EQ(s.hessian.xx, 0.0f);
    EXPECT_EQ(s.hessian.xy, 0.0f);
    EXPECT_EQ(s.hessian.zz, 0.0f);
  }
}

// w by `auto` (whichever method it takes on each) within 2e-3 of the double brute force at
// points off M, on the real meshes of data/realworld: the scan with its hundreds of holes, the
// STL soups (welded by position as they are read), the inside-out and coloured ones.
TEST(CrossingWinding, AutoMatchesBruteForceOnRealMeshes) {
  for (const char* name :
       {"realworld/birdBath_ggg_photogrammetry.obj", "realworld/dolphins_colored.ply",
        "realworld/spot_triangulated.obj", "realworld/kuka_kr10r1100sixx_visual_base_link.stl",
        "realworld/kuka_kr150r3100_2_visual_base_link.stl", "realworld/motoman_motomini_visual_link_1_s.stl"}) {
    const Mesh mesh = load_test_mesh(name);
    const reference::ReferenceMesh ref = reference::reference_mesh(mesh);
    const Aabb box = test::mesh_bounds(mesh);
    // About 5e7 brute-force triangle terms a mesh (fewer points on the larger ones; a quarter of
    // them under AddressSanitizer, which looks for memory errors, not differences).
    const size_t terms = test::kAddressSanitizer ? 12500000 : 50000000;
    const size_t count = std::clamp<size_t>(terms / mesh.triangles.size(), 100, 1500);
    const GwnModel model = build_model(Mesh(mesh));
    const ModelView v = model.view();
    const std::vector<vec3> points = test::sample_points(box, count, 17);
    std::vector<double> error(points.size(), -1.0);
    reference::parallel_over(points.size(), [&](size_t i) {
      if (unsigned_distance(v.triangles, points[i]).distance <= kCrossingNearMesh * ref.diagonal) return;
      const double w =
          evaluate_winding(v, points[i], WindingOptions{resolve_point_method(v, WindingMethod::kAuto), {}}).w;
      error[i] = std::fabs(w - reference::reference_w(ref, dvec3(points[i])));
    });
    size_t compared = 0;
    double max_error = 0;
    for (size_t i = 0; i < points.size(); ++i) {
      if (error[i] < 0) continue;
      ++compared;
      max_error = std::max(max_error, error[i]);
      EXPECT_LE(error[i], 2e-3) << name << ": point " << i;
    }
    EXPECT_GT(compared, count * 9 / 10) << name;
    std::printf("[ %-26.26s ] %s: max |dw| %.2e over %zu points\n", name,
                winding_method_name(resolve_point_method(v, WindingMethod::kAuto)), max_error, compared);
  }
}

TEST(CrossingWinding, AutoPicksTaylorForAllBoundarySoupAndCrossingForSmallBoundary) {
  const GwnModel holes = build_model(load_test_mesh("bunny_holes.obj"));
  EXPECT_EQ(resolve_winding_method(holes.view(), WindingMethod::kAuto), WindingMethod::kCrossing);
  const GwnModel closed = build_model(load_test_mesh("bunny.obj"));
  EXPECT_EQ(resolve_winding_method(closed.view(), WindingMethod::kAuto), WindingMethod::kCrossing);
  const GwnModel soup = build_model(shrunk_soup(load_test_mesh("bunny.obj")));
  EXPECT_EQ(soup.view().cone.triangle_count, 3 * soup.view().triangles.triangle_count);
  EXPECT_EQ(resolve_winding_method(soup.view(), WindingMethod::kAuto), WindingMethod::kTaylor);
  // An explicit method is kept.
  EXPECT_EQ(resolve_winding_method(soup.view(), WindingMethod::kCrossing), WindingMethod::kCrossing);
  EXPECT_EQ(resolve_winding_method(holes.view(), WindingMethod::kBrute), WindingMethod::kBrute);
  // And the sheets were classified by the method auto chose.
  EXPECT_EQ(holes.sheet_method(), WindingMethod::kCrossing);
  EXPECT_EQ(soup.sheet_method(), WindingMethod::kTaylor);
}

// Point queries' auto goes by the work sampled at build on a lattice: the same ratio, within a
// factor of 1.5, from an independent count at 1000 random points of the same box, and the choice:
// the birdBath scan (hundreds of holes around a long rim: its ∂M is under the segment rule's
// threshold) by Taylor, meshes with few or small loops and closed ones by crossings; the mesher's
// and the sheets' rule keeps crossings on the scan.
TEST(CrossingWinding, AutoForPointsGoesByTheSampledWork) {
  struct Expected {
    const char* name;
    WindingMethod method;
  };
  for (const Expected& e :
       {Expected{"realworld/birdBath_ggg_photogrammetry.obj", WindingMethod::kTaylor},
        Expected{"bunny_holes.obj", WindingMethod::kCrossing}, Expected{"teapot.obj", WindingMethod::kCrossing},
        Expected{"realworld/dolphins_colored.ply", WindingMethod::kCrossing},
        Expected{"realworld/kuka_kr150r3100_2_visual_base_link.stl", WindingMethod::kCrossing},
        Expected{"bunny.obj", WindingMethod::kCrossing}}) {
    const GwnModel model = build_model(load_test_mesh(e.name));
    const ModelView v = model.view();
    struct Count {
      uint64_t units = 0;
      void far(uint32_t, int, const vec3&) { ++units; }
      void near(uint32_t, const vec3&, const vec3&, const vec3&) { ++units; }
    } taylor;
    CrossingStats crossing;
    const vec3 extent = v.bounds.hi - v.bounds.lo;
    const Aabb grown{v.bounds.lo - 0.2f * extent, v.bounds.hi + 0.2f * extent};
    for (const vec3& x : test::sample_points(grown, 1000, 29)) {
      (void)winding_number_crossing<false, false>(v, x, kConeBeta, &crossing);
      visit_multipole(v.triangles, x, 2.0f, taylor);
    }
    const double ratio = double(crossing.cone_near + crossing.cone_far) / double(taylor.units);
    if (v.cone.triangle_count == 0) {
      EXPECT_EQ(v.crossing_work_ratio, 0.0f) << e.name;
    } else {
      EXPECT_GT(v.crossing_work_ratio, ratio / 1.5) << e.name;
      EXPECT_LT(v.crossing_work_ratio, ratio * 1.5) << e.name;
    }
    EXPECT_EQ(resolve_point_method(v, WindingMethod::kAuto), e.method) << e.name;
    EXPECT_EQ(resolve_point_method(v, WindingMethod::kCrossing), WindingMethod::kCrossing) << e.name;
    EXPECT_EQ(resolve_winding_method(v, WindingMethod::kAuto), WindingMethod::kCrossing) << e.name;
    std::printf("[ %-26.26s ] work ratio %.3f on the lattice, %.3f at random points: %s\n", e.name,
                double(v.crossing_work_ratio), ratio,
                winding_method_name(resolve_point_method(v, WindingMethod::kAuto)));
  }
}

// The brute-force sides of a triangle: w_o = the mean of w just off its centroid on either side
// (1e-7 along its unit normal), the jump k = their difference (both in double).
struct ReferenceSides {
  double other = NAN;
  int jump = 0;
};

ReferenceSides reference_sides(const reference::ReferenceMesh& ref, const Mesh& m, size_t t) {
  const dvec3 a(m.positions[m.triangles[t][0]]), b(m.positions[m.triangles[t][1]]), c(m.positions[m.triangles[t][2]]);
  const dvec3 n = glm::cross(b - a, c - a);
  if (n == dvec3(0.0)) return {};
  const dvec3 centroid = (a + b + c) / 3.0, u = glm::normalize(n);
  const double behind = reference::reference_w(ref, centroid - 1e-7 * u),
               front = reference::reference_w(ref, centroid + 1e-7 * u);
  return {0.5 * (behind + front), int(std::lround(behind - front))};
}

TEST(CrossingWinding, SheetClassificationAgreesWithBruteForceSides) {
  std::vector<Case> cases;
  cases.push_back({"bunny_holes", load_test_mesh("bunny_holes.obj")});
  cases.push_back({"teapot", load_test_mesh("teapot.obj")});
  cases.push_back({"stacked soup", stacked_soup(load_test_mesh("bunny_holes.obj"))});
  // A scan with 329 holes: its triangles are classified four at a time (a batch of eight sides).
  cases.push_back({"scan", load_test_mesh("realworld/birdBath_ggg_photogrammetry.obj")});
  for (Case& c : cases) {
    const reference::ReferenceMesh ref = reference::reference_mesh(c.mesh);
    const Mesh mesh = c.mesh;
    // The brute force at every 16th triangle of a large mesh (its sums cost n each).
    const size_t stride = mesh.triangles.size() > 20000 ? 16 : 1;
    BuildOptions options;
    options.sheet_method = WindingMethod::kCrossing;
    GwnModel model;
    ASSERT_TRUE(GwnModel::build(std::move(c.mesh), model, options).ok());
    ASSERT_EQ(model.sheet_method(), WindingMethod::kCrossing);
    std::vector<ReferenceSides> sides(mesh.triangles.size());
    reference::parallel_over(mesh.triangles.size(), [&](size_t t) {
      if (t % stride == 0) sides[t] = reference_sides(ref, mesh, t);
    });
    double max_error = 0;
    size_t decided = 0, stacked = 0;
    for (float level : {0.5f, 0.2f, 0.9f}) {
      ASSERT_TRUE(model.set_sheet_level(level).ok());
      std::vector<bool> in_tree(mesh.triangles.size(), false);
      for (uint32_t id : model.sheet_tree().triangle_ids) in_tree.at(id) = true;
      for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        if (std::isnan(sides[t].other)) continue;
        const double error = std::fabs(model.other_winding()[t] - sides[t].other);
        max_error = std::max(max_error, error);
        EXPECT_LE(error, kCrossingTolerance) << c.name << " triangle " << t;
        EXPECT_EQ(std::abs(int(model.sheet_jump()[t])), std::abs(sides[t].jump)) << c.name << " triangle " << t;
        stacked += level == 0.5f && std::abs(sides[t].jump) > 1;
        const double half = 0.5 * std::abs(sides[t].jump);
        // Sides within the tolerance of w* are left to round-off.
        if (std::fabs(std::fabs(sides[t].other - level) - half) < kCrossingTolerance) continue;
        ++decided;
        EXPECT_EQ(in_tree[t], std::fabs(sides[t].other - level) < half)
            << c.name << " level " << level << " triangle " << t << " reference " << sides[t].other;
      }
    }
    std::printf("[ %-12s ] %zu decisions over 3 levels agree; max |w_o - reference| %.2e; %zu stacked triangles\n",
                c.name.c_str(), decided, max_error, stacked);
  }
}

}  // namespace
}  // namespace gwnrt
