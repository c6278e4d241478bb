// Signed distance to S = ∂{w > w*} (docs/design.md §4): the distance to the sheets, the
// pseudo-SDF and its curvature correction, Newton projection and the Harnack lower bound, each
// against a reference that does not go through the code under test: analytic distances (sphere,
// the flat disk that caps a hemisphere), the winding number on the axis of a hemisphere in closed
// form, brute-force double sums of w (brute_force_winding.h) and brute-force distances to
// triangles.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "gwnrt/query/batch.h"
#include "gwnrt/sdf/sheets.h"
#include "gwnrt/sdf/signed_distance.h"
#include "reference/brute_force_winding.h"
#include "reference/exact_distance.h"
#include "sdf_fixtures.h"
#include "test_util.h"

namespace gwnrt {
namespace {

// w on the axis of the exact unit hemisphere: the disk of radius 1 seen from (0,0,z) subtends
// 2π(1 - |z|/sqrt(1 + z²)), and w_H = 1 - w_D inside (w_D > 0 from above), -w_D outside below (w_D
// < 0 there): both give w_H(0,0,z) = 1/2 + z / (2 sqrt(1 + z²)) for |z| < 1.
double hemisphere_axis_w(double z) { return 0.5 + z / (2.0 * std::sqrt(1.0 + z * z)); }

// The tessellated cap differs from the exact one only through the rim: both close with their
// own flat disk, so on the axis w_tess - w_exact = w_D,exact - w_D,tess, the solid angle of the
// m lunes between the circle and the inscribed m-gon (area π - (m/2) sin(2π/m)) seen from
// (0,0,z). They lie between radius cos(π/m) and 1 in the plane z = 0, so that is at most
// area·|z| / (cos²(π/m) + z²)^(3/2) / 4π; 1% more for the float vertices.
double hemisphere_axis_tolerance(double z, int segments) {
  const double lunes = kPi - 0.5 * segments * std::sin(2.0 * kPi / segments);
  return 1.01 * lunes * std::fabs(z) / std::pow(std::cos(kPi / segments) * std::cos(kPi / segments) + z * z, 1.5) /
         (4.0 * kPi);
}

// All results of one request for many points.
std::vector<PointResult> evaluate(const GwnModel& model, const std::vector<vec3>& points, const QueryRequest& request) {
  std::vector<PointResult> results(points.size());
  const Status s = evaluate_points(model, points, request, results);
  EXPECT_TRUE(s.ok()) << s.message();
  return results;
}

QueryRequest sdf_request(uint32_t fields, float level = 0.5f, bool exact = false) {
  QueryRequest r;
  r.fields = fields;
  r.level = level;
  r.method = exact ? WindingMethod::kBrute : WindingMethod::kTaylor;
  return r;
}

// A point uniform in the disk of radius `radius` about the origin (the hemisphere's rim disk).
glm::vec2 uniform_in_disk(test::Random& rng, float radius) {
  const float r = radius * std::sqrt(rng.uniform(0.0f, 1.0f)), a = rng.uniform(0.0f, 2.0f * float(kPi));
  return {r * std::cos(a), r * std::sin(a)};
}

// ---------------------------------------------------------------------------------------------
// 2. Closed sphere: S is the mesh, all sheets.
// ---------------------------------------------------------------------------------------------

TEST(SignedDistance, ClosedSphereIsRadiusMinusOneToTheChordSag) {
  // sdf against two references: the brute-force distance to the facets (tight: only float
  // round-off, 1e-6 at radius <= 2), and |x| - 1 within the chord sag (chord_sag: the facets
  // lie between radius 1 - sag and 1; 1.2e-3 for the level-4 sphere). The sign is negative
  // exactly inside (|x| < 1 - sag), positive outside (|x| > 1); every point is a sheet point
  // (∇w = 0 off a closed mesh, so the smooth estimate is infinite or huge).
  const Mesh mesh = make_sphere(4);
  const GwnModel model = build_model(mesh);
  const double sag = chord_sag(mesh);
  EXPECT_GT(sag, 5e-4);
  EXPECT_LT(sag, 2e-3);
  test::Random rng(2);
  std::vector<vec3> points;
  for (float radius : {0.2f, 0.6f, 0.9f, 0.98f, 0.995f, 1.005f, 1.02f, 1.1f, 1.5f, 2.0f})
    for (int k = 0; k < 40; ++k) points.push_back(rng.unit() * radius * rng.uniform(0.999f, 1.001f));
  const std::vector<PointResult> r = evaluate(model, points, sdf_request(kFieldSignedDistance));
  double worst_analytic = 0, worst_brute = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const dvec3 x(points[i]);
    const double radius = glm::length(x);
    const float sdf = r[i].sdf.distance;
    EXPECT_EQ(r[i].sdf.piece, DistancePiece::kSheet) << str(points[i]);
    const double brute = mesh_distance(mesh, x);
    worst_brute = std::max(worst_brute, std::fabs(std::fabs(sdf) - brute));
    worst_analytic = std::max(worst_analytic, std::fabs(sdf - (radius - 1.0)));
    EXPECT_NEAR(std::fabs(sdf), brute, 2e-6) << str(points[i]);
    EXPECT_NEAR(sdf, radius - 1.0, sag + 1e-6) << str(points[i]);
    if (radius < 1.0 - sag) {
      EXPECT_LT(sdf, 0.0f) << str(points[i]);
    }
    if (radius > 1.0) {
      EXPECT_GT(sdf, 0.0f) << str(points[i]);
    }
    EXPECT_EQ(r[i].sdf.sheet_distance, std::fabs(sdf));
  }
  std::printf("closed sphere: sag %.2e, max |sdf - (|x| - 1)| %.2e, max ||sdf| - brute| %.2e\n", sag, worst_analytic,
              worst_brute);
}

// ---------------------------------------------------------------------------------------------
// 3. Open hemisphere: S = shell (sheets) + the flat disk D (smooth, w = 1/2 by symmetry).
// ---------------------------------------------------------------------------------------------

TEST(SignedDistance, HemisphereAxisWindingNumberMatchesClosedForm) {
  // w on the axis: the tessellated cap's exact double sum against the closed form of the exact
  // hemisphere, within the lune bound (hemisphere_axis_tolerance, about 1.8e-4·|z| for 96
  // segments) plus 1e-9 of round-off; and the tree (order 2, beta 2) against the exact sum of
  // the same triangles within 2e-3, test_winding_number.cpp's bound for order 2 (measured
  // 1.2e-3 at z = 0.9, 0.1 below the pole).
  constexpr int kSegments = 96;
  const HemisphereReference h(24, kSegments);
  const GwnModel model = build_model(h.mesh);
  const ModelView v = model.view();
  double worst_tree = 0;
  for (double z = -0.95; z <= 0.95; z += 0.05) {
    const vec3 x(0.0f, 0.0f, float(z));
    const double exact = winding_number_exact(v.triangles, x).w;
    EXPECT_NEAR(exact, hemisphere_axis_w(double(x.z)), hemisphere_axis_tolerance(x.z, kSegments) + 1e-9) << "z " << z;
    // The tessellation effect is real, not hidden in the tolerance: at |z| = 0.5 it is above a
    // third of the bound.
    if (std::fabs(std::fabs(z) - 0.5) < 1e-9) {
      EXPECT_GT(std::fabs(exact - hemisphere_axis_w(double(x.z))), 0.3 * hemisphere_axis_tolerance(x.z, kSegments));
    }
    const float tree = winding_number(v.triangles, x, TaylorOptions{}).w;
    worst_tree = std::max(worst_tree, std::fabs(tree - exact));
    EXPECT_NEAR(tree, exact, 2e-3) << "z " << z;
    EXPECT_NEAR(reference::reference_w(h.exact, dvec3(x)), exact, 1e-12);  // two independent double sums
  }
  // w = 1/2 on the whole disk (the symmetry argument of HemisphereReference), off the axis too.
  test::Random rng(4);
  for (int k = 0; k < 50; ++k) {
    const vec3 x(rng.uniform(-0.7f, 0.7f), rng.uniform(-0.7f, 0.7f), 0.0f);
    EXPECT_NEAR(reference::reference_w(h.exact, dvec3(x)), 0.5, 1e-12) << str(x);
  }
  std::printf("hemisphere axis: max |w_tree - w_exact| %.2e\n", worst_tree);
}

TEST(SignedDistance, HemisphereNearDiskIsSmoothMinusZ) {
  // Near the disk's centre S is the disk, so the signed distance is -z (inside = above). The
  // estimate is the curvature-corrected pseudo-SDF: its analytic error on the axis is z³/2
  // (CurvatureCorrectionHalvesTheErrorOnTheDiskAxis), off the axis of the same order (measured
  // 0.47|z|³ to 0.61|z|³ for ρ <= 0.4, |z| <= 0.1); the tree adds its error in w over |∇w| >= 1/2
  // (at most 1e-3 in w: 2e-3; measured 6e-4). Tolerance 0.6|z|³ + 2e-3 for the tree; with the
  // exact sum 0.6|z|³ + 1e-5 (measured 1.4e-5 above |z|³/2).
  const HemisphereReference h(24, 96);
  const GwnModel model = build_model(h.mesh);
  test::Random rng(8);
  std::vector<vec3> points;
  for (int k = 0; k < 300; ++k) {
    const glm::vec2 q = uniform_in_disk(rng, 0.4f);
    const float z = rng.uniform(0.02f, 0.15f) * (k % 2 ? 1.0f : -1.0f);
    points.push_back({q.x, q.y, z});
  }
  for (bool exact : {false, true}) {
    const std::vector<PointResult> res = evaluate(model, points, sdf_request(kFieldSignedDistance, 0.5f, exact));
    double worst = 0;
    for (size_t i = 0; i < points.size(); ++i) {
      const float z = points[i].z;
      const double reference = h.signed_distance(dvec3(points[i]));
      ASSERT_NEAR(reference, -z, 1e-7) << str(points[i]);  // the disk is the nearest part of S
      EXPECT_EQ(res[i].sdf.piece, DistancePiece::kSmooth) << str(points[i]);
      const double tolerance = 0.6 * std::fabs(z * z * z) + (exact ? 1e-5 : 2e-3);
      EXPECT_NEAR(res[i].sdf.distance, -z, tolerance) << str(points[i]) << (exact ? " exact" : " tree");
      EXPECT_EQ(std::signbit(res[i].sdf.distance), z > 0) << str(points[i]);
      worst = std::max(worst, std::fabs(res[i].sdf.distance + z) - 0.5 * std::fabs(z * z * z));
    }
    std::printf("hemisphere disk (%s): max |sdf + z| - |z|³/2 = %.2e\n", exact ? "exact" : "tree", worst);
  }
}

TEST(SignedDistance, HemisphereNearShellIsTheSheetDistance) {
  // Points at radius 1 ± δ (δ up to 0.05) and polar angle below 60°: the shell is nearer than
  // the disk (z = cos θ >= 1/2 > δ), so sdf is ∓ the distance to the shell, which is the
  // distance to the sheet triangles: compared with brute force over the shell in double (only
  // float round-off: 1e-6). Inside (radius < 1 - sag) negative, outside positive.
  const HemisphereReference h(24, 96);
  const GwnModel model = build_model(h.mesh);
  test::Random rng(9);
  std::vector<vec3> points;
  for (int k = 0; k < 300; ++k) {
    const float theta = std::acos(rng.uniform(0.5f, 1.0f)), phi = rng.uniform(0.0f, 2.0f * float(kPi));
    const float radius = 1.0f + rng.uniform(0.003f, 0.05f) * (k % 2 ? 1.0f : -1.0f);
    points.push_back(radius * vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)));
  }
  const std::vector<PointResult> res = evaluate(model, points, sdf_request(kFieldSignedDistance));
  const double sag = chord_sag(h.mesh);
  for (size_t i = 0; i < points.size(); ++i) {
    const dvec3 x(points[i]);
    const double reference = h.signed_distance(x);
    EXPECT_EQ(res[i].sdf.piece, DistancePiece::kSheet) << str(points[i]);
    EXPECT_NEAR(res[i].sdf.distance, reference, 1e-6) << str(points[i]);
    EXPECT_NEAR(res[i].sdf.sheet_distance, h.shell_distance(x), 1e-6) << str(points[i]);
    const double radius = glm::length(x);
    if (radius < 1.0 - sag) {
      EXPECT_LT(res[i].sdf.distance, 0.0f) << str(points[i]);
    }
    if (radius > 1.0) {
      EXPECT_GT(res[i].sdf.distance, 0.0f) << str(points[i]);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// 4. The curvature correction, where the answer is known.
// ---------------------------------------------------------------------------------------------

TEST(SignedDistance, CurvatureCorrectionHalvesTheErrorOnTheDiskAxis) {
  // On the axis of the exact hemisphere w = 1/2 + z/(2√(1+z²)), w' = 1/(2(1+z²)^(3/2)),
  // w'' = -3z/(2(1+z²)^(5/2)), and ∇w, H_w∇w lie along the axis. So
  //   d₁ = (1/2 - w)/w' = -z(1 + z²)                    (error -z³ against the true -z)
  //   κ = w''/w' = -3z/(1+z²), κd₁ = 3z²,
  //   d₂ = 2d₁/(1 + √(1 + 2κd₁)) = -z(1+z²)·2/(1 + √(1+6z²)) = -z + z³/2 + O(z⁵).
  // The errors are -z³ and about +z³/2: the correction must halve the error and flip its sign
  // (the wrong sign of the correction would make it 5z³/2). Evaluated with the exact double sum
  // (the tree's 1e-4-level error in w would swamp z³ at small z); the tessellation changes w
  // by a relative 3.6e-4 (hemisphere_axis_tolerance), which cancels to first order in
  // (1/2 - w)/w', leaving relative errors of ~1e-3 in these z³ terms (measured: 1e-3 for d₁,
  // 5e-4 for d₂): tolerance 1% of the analytic error plus 2e-7 of float round-off.
  const HemisphereReference h(24, 96);
  const GwnModel model = build_model(h.mesh);
  std::vector<vec3> points;
  for (float z : {0.05f, 0.08f, 0.12f, 0.2f, 0.3f}) {
    points.push_back({0.0f, 0.0f, z});
    points.push_back({0.0f, 0.0f, -z});
  }
  const std::vector<PointResult> res = evaluate(model, points, sdf_request(kFieldPseudoDistance, 0.5f, true));
  for (size_t i = 0; i < points.size(); ++i) {
    const double z = points[i].z;
    const double err1 = -z * z * z;
    const double err2 = z - 2.0 * z * (1.0 + z * z) / (1.0 + std::sqrt(1.0 + 6.0 * z * z));
    const double got1 = res[i].sdf.first_order + z, got2 = res[i].sdf.second_order + z;
    EXPECT_NEAR(got1, err1, 0.01 * std::fabs(err1) + 2e-7) << "z " << z;
    EXPECT_NEAR(got2, err2, 0.01 * std::fabs(err2) + 2e-7) << "z " << z;
    EXPECT_LT(std::fabs(got2), std::fabs(got1)) << "z " << z;
    // The ratio -1/2 + O(z²): -0.493 at z = 0.05, -0.30 at z = 0.3 (from the closed forms).
    EXPECT_NEAR(got2 / got1, err2 / err1, 0.02) << "z " << z;
    if (std::fabs(z) <= 0.08) {
      EXPECT_NEAR(got2 / got1, -0.5, 0.03) << "z " << z;
    }
    std::printf("axis z %+.2f: sdf1 error %+.3e (analytic %+.3e), sdf2 error %+.3e (analytic %+.3e)\n", z, got1, err1,
                got2, err2);
  }
}

// The level set {w = w*} of the hemisphere in the meridian plane y = 0, by bisection (40 steps:
// 1e-12) of the exact double sum along vertical lines x = ρ between z_lo and z_hi (below the
// disk w increases with z, so there is one root there). Returns the sampled curve (ρ, z(ρ)).
std::vector<glm::dvec2> level_curve(const HemisphereReference& h, double level, double rho_max, int samples,
                                    double z_lo, double z_hi) {
  std::vector<glm::dvec2> curve;
  for (int i = 0; i <= samples; ++i) {
    const double rho = rho_max * i / samples;
    double a = z_lo, b = z_hi;
    if (!(reference::reference_w(h.exact, {rho, 0, a}) < level && reference::reference_w(h.exact, {rho, 0, b}) > level))
      continue;
    for (int it = 0; it < 40; ++it) {
      const double m = 0.5 * (a + b);
      (reference::reference_w(h.exact, {rho, 0, m}) < level ? a : b) = m;
    }
    curve.push_back({rho, 0.5 * (a + b)});
  }
  return curve;
}

// Distance from (ρ0, 0, z0) to the surface of revolution of `curve` (the nearest point of a
// surface of revolution lies in the point's meridian half-plane): the polyline's distance.
double distance_to_curve(const std::vector<glm::dvec2>& curve, const glm::dvec2& p) {
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i + 1 < curve.size(); ++i) {
    const glm::dvec2 a = curve[i], e = curve[i + 1] - a;
    const double t = std::clamp(glm::dot(p - a, e) / glm::dot(e, e), 0.0, 1.0);
    best = std::min(best, glm::length(a + t * e - p));
  }
  return best;
}

TEST(SignedDistance, CurvatureCorrectionWinsOnACurvedLevel) {
  // A level with w'' != 0 where it is crossed: w* = 0.3 on the hemisphere is a bowl below the
  // disk (on the axis at z* = -0.4/√0.84 = -0.436 by the closed form), curved, and its normal
  // second derivative w''/w' = 1.1 there, so d₁'s error is second order, d₂'s third. The
  // reference distance: the level curve in the meridian plane y = 0 by bisection of the exact
  // w (the 96-gon cap is a surface of revolution but for its rim, which changes w by a relative
  // 4e-4: hemisphere_axis_tolerance), as a polyline of 240 segments over ρ in [0, 0.6] (chord
  // error (Δρ)²κ/8 < 1e-6), distance from the point's (ρ, z). Compared where the level is
  // nearer than the shell (the sheets): |z - z*| <= 0.2, ρ <= 0.3.
  const HemisphereReference h(24, 96);
  GwnModel model = build_model(h.mesh);
  const double z_star = -0.4 / std::sqrt(0.84);
  const std::vector<glm::dvec2> curve = level_curve(h, 0.3, 0.6, 240, -0.7, -0.2);
  ASSERT_EQ(curve.size(), 241u);
  EXPECT_NEAR(curve.front().y, z_star, 2e-3);  // the tessellated level is where the closed form says
  ASSERT_TRUE(model.set_sheet_level(0.3f).ok());
  std::vector<vec3> points;
  for (float rho : {0.0f, 0.1f, 0.2f, 0.3f})
    for (float dz : {-0.2f, -0.12f, -0.06f, 0.06f, 0.12f, 0.2f}) points.push_back({rho, 0.0f, float(z_star) + dz});
  const std::vector<PointResult> res =
      evaluate(model, points, sdf_request(kFieldSignedDistance | kFieldPseudoDistance, 0.3f, true));
  double worst1 = 0, worst2 = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const dvec3 x(points[i]);
    const double d = distance_to_curve(curve, {x.x, x.z});
    const double reference = reference::reference_w(h.exact, x) > 0.3 ? -d : d;
    const double e1 = std::fabs(res[i].sdf.first_order - reference),
                 e2 = std::fabs(res[i].sdf.second_order - reference);
    worst1 = std::max(worst1, e1);
    worst2 = std::max(worst2, e2);
    EXPECT_EQ(res[i].sdf.piece, DistancePiece::kSmooth) << str(points[i]);
    EXPECT_EQ(res[i].sdf.distance, res[i].sdf.second_order) << str(points[i]);
    // d₁'s error is second order (6e-4 to 4e-2 here, far above the reference's 1e-5), d₂'s
    // third: measured at most 0.17 of d₁'s at every point.
    ASSERT_GT(e1, 1e-4) << str(points[i]);
    EXPECT_LT(e2, 0.25 * e1) << str(points[i]) << " reference " << reference << " sdf1 " << res[i].sdf.first_order
                             << " sdf2 " << res[i].sdf.second_order;
  }
  std::printf("level 0.3 bowl: max |sdf1 - ref| %.2e, max |sdf2 - ref| %.2e\n", worst1, worst2);
}

// ---------------------------------------------------------------------------------------------
// 5. Continuity across the switch between pieces, and |∇sdf| = 1 near S.
// ---------------------------------------------------------------------------------------------

struct Segment {
  vec3 a, b;
  const char* what;
};

TEST(SignedDistance, ContinuousWhereThePieceSwitches) {
  // Two segments on the hemisphere along which the nearer part of S changes from the disk to
  // the shell: vertically at ρ = 0.5 inside the dome (disk distance z, shell 1 - |x|: equal at
  // z = 0.375) and radially at z = -0.1 below the disk out past the rim (the disk, then the
  // rim). sdf = ±min(sheet distance, |d₂|) is continuous if each is: consecutive samples may
  // differ by at most the spacing Δs (a distance is 1-Lipschitz) times 1.1 (d₂ is not exactly
  // a distance: its slope is 1 + O(z²) near the disk and up to sqrt(1 + θ²) beside the rim),
  // and the piece must really switch along each (measured max |Δsdf|/Δs: 1.012). With the
  // exact sum (a smooth w); the tree's w is piecewise smooth (clusters switch between expansion
  // and exact sums from one point to the next) with jumps below its error, a few 1e-4 in w near
  // the disk (2× that in distance): there |Δsdf| <= 1.1 Δs + 1e-3 (measured 1.053 Δs).
  const HemisphereReference h(24, 96);
  const GwnModel model = build_model(h.mesh);
  for (const Segment& seg : {Segment{{0.5f, 0.0f, 0.05f}, {0.5f, 0.0f, 0.6f}, "vertical at rho 0.5"},
                             Segment{{0.5f, 0.0f, -0.1f}, {1.4f, 0.0f, -0.1f}, "radial at z -0.1"}}) {
    constexpr int kSamples = 300;
    std::vector<vec3> points;
    for (int i = 0; i <= kSamples; ++i) points.push_back(glm::mix(seg.a, seg.b, float(i) / kSamples));
    const float ds = glm::length(seg.b - seg.a) / kSamples;
    for (bool exact : {true, false}) {
      const std::vector<PointResult> r = evaluate(model, points, sdf_request(kFieldSignedDistance, 0.5f, exact));
      int switches = 0;
      bool seen[3] = {};
      double worst = 0;
      for (int i = 0; i < kSamples; ++i) {
        const float step = std::fabs(r[i + 1].sdf.distance - r[i].sdf.distance);
        worst = std::max(worst, double(step / ds));
        EXPECT_LE(step, 1.1f * ds + (exact ? 0.0f : 1e-3f))
            << seg.what << (exact ? " exact" : " tree") << " between " << str(points[i]) << " and "
            << str(points[i + 1]) << ": " << r[i].sdf.distance << " -> " << r[i + 1].sdf.distance;
        switches += r[i + 1].sdf.piece != r[i].sdf.piece;
        seen[unsigned(r[i].sdf.piece)] = true;
      }
      EXPECT_TRUE(seen[unsigned(DistancePiece::kSheet)]) << seg.what;
      EXPECT_TRUE(seen[unsigned(DistancePiece::kSmooth)]) << seg.what;
      EXPECT_GE(switches, 1) << seg.what;
      std::printf("%s (%s): max |dsdf|/ds %.3f, %d switches\n", seg.what, exact ? "exact" : "tree", worst, switches);
    }
  }
}

TEST(SignedDistance, GradientHasUnitLengthNearS) {
  // |∇sdf| = 1 wherever sdf is a distance, by central differences (h = 2e-3) at points within
  // 3% of S and away from where the pieces switch and from the medial axis: above and below the
  // disk (ρ < 0.4, 0.01 <= |z| <= 0.03: smooth, |∇d₂| = 1 + O(z²) = 1 ± 2e-3, and the
  // difference quotient's own error h²/6 times the third derivative is negligible), and beside
  // the shell (radius 1 ± [0.01, 0.03], polar angle < 50°: sheet; from inside, points near an
  // edge sit near the bisector of its two facets, where central differences across the kink
  // give cos(3.75°/2) ≈ 0.9995). With the exact sum, tolerance 1% (measured 2.3e-3); with the
  // tree 10% (its w error, a few 1e-4 near the disk, may jump by that much between the two
  // samples 4e-3 apart; measured 1.6e-2).
  const HemisphereReference h(24, 96);
  const GwnModel model = build_model(h.mesh);
  test::Random rng(14);
  std::vector<vec3> centres;
  for (int k = 0; k < 60; ++k) {
    const glm::vec2 q = uniform_in_disk(rng, 0.4f);
    centres.push_back({q.x, q.y, rng.uniform(0.01f, 0.03f) * (k % 2 ? 1.0f : -1.0f)});
  }
  for (int k = 0; k < 60; ++k) {
    const float theta = std::acos(rng.uniform(std::cos(50.0f * float(kPi) / 180.0f), 1.0f));
    const float phi = rng.uniform(0.0f, 2.0f * float(kPi));
    const float radius = 1.0f + rng.uniform(0.01f, 0.03f) * (k % 2 ? 1.0f : -1.0f);
    centres.push_back(radius * vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)));
  }
  constexpr float kH = 2e-3f;
  std::vector<vec3> points;
  for (const vec3& c : centres)
    for (int axis = 0; axis < 3; ++axis)
      for (float sign : {1.0f, -1.0f}) {
        vec3 p = c;
        p[axis] += sign * kH;
        points.push_back(p);
      }
  for (bool exact : {true, false}) {
    const std::vector<PointResult> r = evaluate(model, points, sdf_request(kFieldSignedDistance, 0.5f, exact));
    double worst = 0;
    for (size_t k = 0; k < centres.size(); ++k) {
      vec3 g;
      for (int axis = 0; axis < 3; ++axis)
        g[axis] = (r[6 * k + 2 * axis].sdf.distance - r[6 * k + 2 * axis + 1].sdf.distance) / (2.0f * kH);
      const float norm = glm::length(g);
      worst = std::max(worst, double(std::fabs(norm - 1.0f)));
      EXPECT_NEAR(norm, 1.0f, exact ? 0.01f : 0.1f) << str(centres[k]) << (exact ? " exact" : " tree");
    }
    std::printf("|grad sdf| (%s): max ||g| - 1| %.2e\n", exact ? "exact" : "tree", worst);
  }
}

// ---------------------------------------------------------------------------------------------
// 6. Newton projection onto the smooth pieces.
// ---------------------------------------------------------------------------------------------

TEST(SignedDistance, NewtonProjectsOntoTheDisk) {
  // From points in a band around the disk (|z| < 0.2, ρ < 0.5) Newton must converge onto it:
  // the residual w - 1/2 at the returned point, evaluated independently by the exact double
  // sum, within the tolerance (1e-4) plus the tree's error in w that Newton iterated on (up to
  // 3e-4 near the disk, see HemisphereNearDiskIsSmoothMinusZ): 5e-4. The point then lies within
  // that residual over |∇w| >= 1/2 of z = 0 (1e-3). Laterally it follows ∇w, not the normal:
  // near the disk w ≈ 1/2 + a(ρ)z with a growing toward the rim, so ∇w ≈ (a'z, a) and the path
  // bends toward the axis by about (a'/a)·z₀²/2 (measured up to 1.0·z₀² at ρ <= 0.5): it must
  // move inward, by at most 1.5·z₀² + 1e-3.
  const HemisphereReference h(24, 96);
  const GwnModel model = build_model(h.mesh);
  test::Random rng(15);
  std::vector<vec3> points;
  for (int k = 0; k < 200; ++k) {
    const glm::vec2 q = uniform_in_disk(rng, 0.5f);
    points.push_back({q.x, q.y, rng.uniform(-0.2f, 0.2f)});
  }
  QueryRequest request = sdf_request(kFieldProjection | kFieldW);
  const std::vector<PointResult> res = evaluate(model, points, request);
  double worst_residual = 0, worst_z = 0, worst_drift = 0;
  uint32_t max_iterations = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const SurfaceProjection& p = res[i].projection;
    ASSERT_TRUE(p.converged) << str(points[i]) << " -> " << str(p.point) << " after " << p.iterations;
    EXPECT_LE(std::fabs(p.residual), request.newton.tolerance) << str(points[i]);
    const double exact_residual = reference::reference_w(h.exact, dvec3(p.point)) - 0.5;
    EXPECT_LE(std::fabs(exact_residual), 5e-4) << str(points[i]) << " -> " << str(p.point);
    EXPECT_LE(std::fabs(p.point.z), 1e-3f) << str(points[i]) << " -> " << str(p.point);
    const float z0 = points[i].z;
    const float drift = glm::length(glm::vec2(p.point) - glm::vec2(points[i]));
    EXPECT_LE(drift, 1.5f * z0 * z0 + 1e-3f) << str(points[i]) << " -> " << str(p.point);
    EXPECT_LE(glm::length(glm::vec2(p.point)), glm::length(glm::vec2(points[i])) + 1e-4f) << str(points[i]);
    worst_residual = std::max(worst_residual, std::fabs(exact_residual));
    worst_z = std::max(worst_z, double(std::fabs(p.point.z)));
    if (std::fabs(z0) > 0.05f) worst_drift = std::max(worst_drift, double(drift / (z0 * z0)));
    max_iterations = std::max(max_iterations, p.iterations);
  }
  std::printf("Newton onto the disk: max exact |w - 1/2| %.2e, max |z| %.2e, max drift/z0^2 %.3f, max %u iterations\n",
              worst_residual, worst_z, worst_drift, max_iterations);
}

TEST(SignedDistance, NewtonReportsFailureWhereTheLevelIsOutOfReach) {
  // Above the shell, outside, w rises from -0.15 toward 0 at infinity along ∇w (the closed form:
  // w = -1/2 + z/(2√(1+z²)) for z > 1 on the axis), and the steps may not cross the shell: the
  // level 1/2 cannot be reached, so it must report converged = false with a finite point (not a
  // point on the shell, not NaN), and early: the iterate soon leaves the box beyond which
  // |w| < 1/2 (signed_distance.h), well before the iteration cap. Same on a closed sphere, where
  // ∇w = 0 off the mesh (only the tree's round-off) and w is 0 or 1: from inside and outside,
  // and it has no smooth piece to project onto at all. And a NaN start must not converge.
  const HemisphereReference h(16, 64);
  const GwnModel hemi = build_model(h.mesh);
  const GwnModel sphere = build_model(make_sphere(3));
  struct Case {
    const GwnModel* model;
    vec3 start;
    const char* what;
  };
  for (const Case& c : {Case{&hemi, {0.0f, 0.0f, 1.1f}, "above the hemisphere's pole"},
                        Case{&hemi, {0.3f, 0.2f, 1.5f}, "above the hemisphere"},
                        Case{&sphere, {0.1f, 0.2f, 0.3f}, "inside a closed sphere"},
                        Case{&sphere, {1.5f, 0.2f, 0.3f}, "outside a closed sphere"},
                        Case{&sphere, {0.0f, 0.0f, 0.0f}, "at a closed sphere's centre"}}) {
    const PointResult r = evaluate(*c.model, {c.start}, sdf_request(kFieldProjection))[0];
    EXPECT_FALSE(r.projection.converged) << c.what << ": " << str(r.projection.point);
    EXPECT_TRUE(std::isfinite(r.projection.point.x) && std::isfinite(r.projection.point.y) &&
                std::isfinite(r.projection.point.z))
        << c.what;
    EXPECT_TRUE(std::isfinite(r.projection.residual)) << c.what;
    EXPECT_LT(r.projection.iterations, QueryRequest{}.newton.max_iterations / 2) << c.what;
    // Where it stopped, w is still far from the level (it did not stop on a sheet).
    EXPECT_GT(std::fabs(winding_number_exact(c.model->triangle_view(), r.projection.point).w - 0.5), 0.3) << c.what;
    std::printf("%s: stopped after %u iterations at %s, residual %g\n", c.what, r.projection.iterations,
                str(r.projection.point).c_str(), r.projection.residual);
  }
  // (The batch drivers refuse a NaN point, validate_points; the per-point function a kernel calls
  // must still not claim convergence for one.)
  const PointResult nan = evaluate_point(hemi.view(), vec3(kNaN, 0.0f, 0.0f), sdf_request(kFieldProjection));
  EXPECT_FALSE(nan.projection.converged);
}

// ---------------------------------------------------------------------------------------------
// 7. The Harnack lower bound.
// ---------------------------------------------------------------------------------------------

TEST(SignedDistance, HarnackBoundNeverExceedsTheDistanceToS) {
  // ρ(x) <= dist(x, S) on random points around the hemisphere (the reference: min of the
  // brute-force distance to the shell and the distance to the rim polygon's disk) and the closed
  // sphere (brute-force distance to the facets), from both the single-point function and the
  // batch field; the only slack is float round-off of the distances (1e-6 absolute at |x| <= 2).
  // Also |sdf| >= ρ everywhere: sdf is clamped by the bound. And the bound is not vacuous: near
  // S it is a fair fraction of the distance (the median ratio is checked, > 0.5).
  const HemisphereReference h(16, 64);
  const GwnModel hemi = build_model(h.mesh);
  const Mesh sphere_mesh = make_sphere(3);
  const GwnModel sphere = build_model(sphere_mesh);
  test::Random rng(16);
  for (const bool closed : {false, true}) {
    const GwnModel& model = closed ? sphere : hemi;
    std::vector<vec3> points;
    for (int k = 0; k < 1500; ++k)
      points.push_back({rng.uniform(-1.5f, 1.5f), rng.uniform(-1.5f, 1.5f), rng.uniform(closed ? -1.5f : -1.0f, 1.5f)});
    const std::vector<PointResult> r = evaluate(model, points, sdf_request(kFieldSignedDistance | kFieldHarnackBound));
    const ModelView v = model.view();
    std::vector<double> ratios;
    for (size_t i = 0; i < points.size(); ++i) {
      const dvec3 x(points[i]);
      const double reference = closed ? mesh_distance(sphere_mesh, x) : h.distance(x);
      const float mesh_distance = unsigned_distance(v.triangles, points[i]).distance;
      const float single = harnack_lower_bound(v, points[i], 0.5f, 2.0f, mesh_distance);
      EXPECT_EQ(single, r[i].harnack_bound) << str(points[i]);
      EXPECT_LE(r[i].harnack_bound, reference + 1e-6) << str(points[i]) << (closed ? " sphere" : " hemisphere");
      EXPECT_GE(r[i].harnack_bound, 0.0f) << str(points[i]);
      EXPECT_GE(std::fabs(r[i].sdf.distance), r[i].harnack_bound) << str(points[i]);
      if (reference < 0.2) ratios.push_back(r[i].harnack_bound / reference);
    }
    std::sort(ratios.begin(), ratios.end());
    ASSERT_FALSE(ratios.empty());
    EXPECT_GT(ratios[ratios.size() / 2], 0.5) << (closed ? "sphere" : "hemisphere");
    // A closed mesh has no smooth pieces: ρ is the distance to M, exactly the sdf's magnitude.
    if (closed) {
      for (size_t i = 0; i < points.size(); ++i) EXPECT_EQ(r[i].harnack_bound, std::fabs(r[i].sdf.distance));
    }
    std::printf("%s: median rho/dist within 0.2 of S %.3f, min %.3f\n", closed ? "sphere" : "hemisphere",
                ratios[ratios.size() / 2], ratios.front());
  }
}

TEST(SignedDistance, HarnackBoundClampsTheSmoothEstimateNearTheDisk) {
  // Very near the disk (|z| in [1e-3, 4e-3]) the tree's error in w (up to 2.5e-4, i.e. 5e-4 of
  // distance) can make |d₂| fall below the distance, and below ρ, which there is nearly the
  // whole distance (z(1 - 2z) on the axis). Where it does, sdf must be ρ (piece kHarnackBound),
  // never below it, and never farther from the truth (-z) than d₂ was.
  const HemisphereReference h(16, 64);
  const GwnModel model = build_model(h.mesh);
  test::Random rng(17);
  std::vector<vec3> points;
  for (int k = 0; k < 2000; ++k) {
    const glm::vec2 q = uniform_in_disk(rng, 0.6f);
    points.push_back({q.x, q.y, rng.uniform(1e-3f, 4e-3f) * (k % 2 ? 1.0f : -1.0f)});
  }
  const std::vector<PointResult> r =
      evaluate(model, points, sdf_request(kFieldSignedDistance | kFieldPseudoDistance | kFieldHarnackBound));
  int clamped = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const float truth = -points[i].z;
    EXPECT_LE(r[i].harnack_bound, std::fabs(truth) + 1e-6f) << str(points[i]);
    EXPECT_GE(std::fabs(r[i].sdf.distance), r[i].harnack_bound) << str(points[i]);
    EXPECT_LE(std::fabs(r[i].sdf.distance - truth), std::fabs(r[i].sdf.second_order - truth) + 1e-7f) << str(points[i]);
    if (r[i].sdf.piece == DistancePiece::kHarnackBound) {
      ++clamped;
      EXPECT_EQ(std::fabs(r[i].sdf.distance), r[i].harnack_bound) << str(points[i]);
      EXPECT_LT(std::fabs(r[i].sdf.second_order), r[i].harnack_bound) << str(points[i]);
    }
  }
  std::printf("near the disk: %d of %zu clamped to the Harnack bound\n", clamped, points.size());
  EXPECT_GT(clamped, 0);
}

// ---------------------------------------------------------------------------------------------
// 8. Batch and API.
// ---------------------------------------------------------------------------------------------

TEST(SignedDistance, BatchRefusesALevelTheSheetsWereNotClassifiedFor) {
  // sdf and sheet distance read the sheets, classified for one level: another level is refused
  // with a message naming both; set_sheet_level makes it work. The fields that do not read the
  // sheets (sdf1, sdf2, the projection, ρ) take any level.
  GwnModel model = build_model(make_hemisphere(8, 32));
  const std::vector<vec3> points = {{0.1f, 0.2f, 0.05f}, {0.0f, 0.0f, 1.2f}};
  std::vector<PointResult> results(points.size());
  for (uint32_t fields : {uint32_t(kFieldSignedDistance), uint32_t(kFieldSheetDistance)}) {
    const Status s = evaluate_points(model, points, sdf_request(fields, 0.3f), results);
    EXPECT_FALSE(s.ok());
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
    EXPECT_NE(s.message().find("0.3"), std::string::npos) << s.message();
    EXPECT_NE(s.message().find("0.5"), std::string::npos) << s.message();
  }
  EXPECT_TRUE(evaluate_points(model, points,
                              sdf_request(kFieldPseudoDistance | kFieldProjection | kFieldHarnackBound, 0.3f), results)
                  .ok());
  ASSERT_TRUE(model.set_sheet_level(0.3f).ok());
  EXPECT_TRUE(evaluate_points(model, points, sdf_request(kFieldSignedDistance, 0.3f), results).ok());
  const Status back = evaluate_points(model, points, sdf_request(kFieldSignedDistance, 0.5f), results);
  EXPECT_FALSE(back.ok());
  // The point above the disk centre, at level 0.3: w ≈ 0.53 > 0.3, inside.
  ASSERT_TRUE(evaluate_points(model, points, sdf_request(kFieldSignedDistance, 0.3f), results).ok());
  EXPECT_LT(results[0].sdf.distance, 0.0f);
}

TEST(SignedDistance, ModelBuiltWithoutSheetsRefusesSdfUntilClassified) {
  // BuildOptions::classify_sheets = false skips the classification (for models only traced):
  // sdf and sheet distance must then be refused with a message that says how to get them, the
  // other fields still work, and set_sheet_level classifies them on demand, after which sdf
  // agrees with a model built with them.
  const Mesh mesh = make_hemisphere(8, 32);
  BuildOptions options;
  options.classify_sheets = false;
  GwnModel model;
  ASSERT_TRUE(GwnModel::build(mesh, model, options).ok());
  EXPECT_EQ(model.sheet_tree().view().triangle_count, 0u);
  const std::vector<vec3> points = {{0.1f, 0.2f, 0.05f}, {0.0f, 0.0f, 1.2f}, {0.5f, 0.0f, 0.8f}};
  std::vector<PointResult> results(points.size());
  for (uint32_t fields : {uint32_t(kFieldSignedDistance), uint32_t(kFieldSheetDistance)}) {
    const Status s = evaluate_points(model, points, sdf_request(fields), results);
    EXPECT_FALSE(s.ok());
    EXPECT_NE(s.message().find("set_sheet_level"), std::string::npos) << s.message();
  }
  EXPECT_TRUE(
      evaluate_points(model, points, sdf_request(kFieldPseudoDistance | kFieldHarnackBound | kFieldW), results).ok());
  ASSERT_TRUE(model.set_sheet_level(0.5f).ok());
  ASSERT_TRUE(evaluate_points(model, points, sdf_request(kFieldSignedDistance), results).ok());
  const GwnModel reference = build_model(mesh);
  const std::vector<PointResult> expected = evaluate(reference, points, sdf_request(kFieldSignedDistance));
  for (size_t i = 0; i < points.size(); ++i) EXPECT_EQ(results[i].sdf.distance, expected[i].sdf.distance) << i;
}

// Points uniform in the model's box grown by a fifth on each side.
std::vector<vec3> points_around(const GwnModel& model, int count, test::Random& rng) {
  Aabb box = model.bounds();
  const vec3 centre = box.centre(), half = 0.6f * (box.hi - box.lo);
  box = {centre - half, centre + half};
  std::vector<vec3> points;
  for (int k = 0; k < count; ++k) points.push_back(rng.in_box(box));
  return points;
}

TEST(SignedDistance, SameAnswerWhateverElseIsAsked) {
  // signed_distance evaluates w, ∇w and H_w only as far as it needs them, unless the request
  // asks for them anyway (w, sdf1/sdf2), when it is handed the full sample: the two paths must
  // give the same sdf, bit for bit, on an open mesh with smooth pieces and on a real one.
  for (const bool hemisphere : {true, false}) {
    const GwnModel model = build_model(hemisphere ? make_hemisphere(16, 64) : test::load_test_mesh("bunny_holes.obj"));
    test::Random rng(23);
    const std::vector<vec3> points = points_around(model, 3000, rng);
    const std::vector<PointResult> alone = evaluate(model, points, sdf_request(kFieldSignedDistance));
    const std::vector<PointResult> with_w = evaluate(model, points, sdf_request(kFieldSignedDistance | kFieldW));
    const std::vector<PointResult> with_pseudo =
        evaluate(model, points, sdf_request(kFieldSignedDistance | kFieldPseudoDistance));
    size_t smooth = 0;
    for (size_t i = 0; i < points.size(); ++i) {
      EXPECT_EQ(alone[i].sdf.distance, with_w[i].sdf.distance) << str(points[i]);
      EXPECT_EQ(alone[i].sdf.distance, with_pseudo[i].sdf.distance) << str(points[i]);
      EXPECT_EQ(alone[i].sdf.piece, with_pseudo[i].sdf.piece) << str(points[i]);
      smooth += alone[i].sdf.piece != DistancePiece::kSheet;
    }
    EXPECT_GT(smooth, 10u) << (hemisphere ? "hemisphere" : "bunny_holes");  // both paths were exercised
  }
}

// Without the sign (the mesh report's distances to S), the magnitude of the signed answer, bit
// for bit, on the sheet and the smooth pieces, and on points of M itself (where w alone would
// take the tree's sum).
TEST(SignedDistance, UnsignedIsTheMagnitudeOfTheSigned) {
  for (const bool hemisphere : {true, false}) {
    const GwnModel model = build_model(hemisphere ? make_hemisphere(16, 64) : test::load_test_mesh("bunny_holes.obj"));
    const ModelView view = model.view();
    test::Random rng(29);
    std::vector<vec3> points = points_around(model, 5000, rng);
    for (int k = 0; k < 500; ++k) {  // on M's triangles
      const uint32_t t = uint32_t(rng.index(int(view.triangles.triangle_count)));
      const vec3* v = view.triangles.vertices + 3 * t;
      const float a = rng.uniform(0, 1), b = rng.uniform(0, 1 - a);
      points.push_back(v[0] + a * (v[1] - v[0]) + b * (v[2] - v[0]));
    }
    const WindingOptions winding{resolve_point_method(view, WindingMethod::kAuto), TaylorOptions{}};
    size_t smooth = 0, sheet = 0;
    for (const vec3& x : points) {
      const SignedDistance with_sign = signed_distance(view, x, 0.5f, winding);
      const SignedDistance without = signed_distance(view, x, 0.5f, winding, nullptr, false);
      EXPECT_EQ(without.distance, std::fabs(with_sign.distance)) << str(x);
      EXPECT_EQ(without.piece, with_sign.piece) << str(x);
      (with_sign.piece == DistancePiece::kSheet ? sheet : smooth) += 1;
    }
    EXPECT_GT(smooth, 10u) << (hemisphere ? "hemisphere" : "bunny_holes");
    EXPECT_GT(sheet, 500u) << (hemisphere ? "hemisphere" : "bunny_holes");
  }
}

TEST(SignedDistance, BadNewtonOptionsAndLevelsAreRefused) {
  const GwnModel model = build_model(make_hemisphere(8, 32));
  const ModelView v = model.view();
  const float inf = std::numeric_limits<float>::infinity();
  auto with = [](auto change) {
    QueryRequest r = sdf_request(kFieldProjection);
    change(r.newton);
    return r;
  };
  EXPECT_TRUE(validate_request(with([](NewtonOptions&) {}), &v).ok());
  const std::vector<QueryRequest> bad = {
      with([](NewtonOptions& n) { n.tolerance = 0.0f; }),     with([](NewtonOptions& n) { n.tolerance = -1e-4f; }),
      with([](NewtonOptions& n) { n.tolerance = kNaN; }),     with([&](NewtonOptions& n) { n.tolerance = inf; }),
      with([](NewtonOptions& n) { n.max_step = 0.0f; }),      with([](NewtonOptions& n) { n.max_step = kNaN; }),
      with([&](NewtonOptions& n) { n.max_step = inf; }),      with([](NewtonOptions& n) { n.mesh_fraction = 0.0f; }),
      with([](NewtonOptions& n) { n.mesh_fraction = 1.5f; }), with([](NewtonOptions& n) { n.mesh_fraction = kNaN; }),
  };
  for (size_t i = 0; i < bad.size(); ++i) {
    const Status s = validate_request(bad[i], &v);
    EXPECT_FALSE(s.ok()) << "case " << i;
    EXPECT_NE(s.message().find("Newton"), std::string::npos) << s.message();
    std::vector<PointResult> results(1);
    EXPECT_FALSE(evaluate_points(model, std::vector<vec3>{vec3(0.1f)}, bad[i], results).ok()) << "case " << i;
  }
  QueryRequest level = sdf_request(kFieldPseudoDistance, kNaN);
  EXPECT_FALSE(validate_request(level, &v).ok());
  level.level = inf;
  EXPECT_FALSE(validate_request(level, &v).ok());
}

TEST(SignedDistance, NonFinitePointsDoNotCrash) {
  // NaN and infinite points through every signed-distance field: the batch refuses them naming the
  // first (validate_points); the per-point function (what a kernel calls) does not crash or hang,
  // and claims no finite sdf or converged projection for a NaN point.
  const GwnModel model = build_model(make_hemisphere(8, 32));
  const float inf = std::numeric_limits<float>::infinity();
  const std::vector<vec3> points = {{kNaN, 0.0f, 0.0f}, {0.0f, kNaN, 0.5f}, {kNaN, kNaN, kNaN},
                                    {inf, 0.0f, 0.0f},  {0.0f, 0.0f, -inf}, {0.1f, 0.1f, 0.1f}};
  std::vector<PointResult> refused(points.size());
  const Status status = evaluate_points(model, points, sdf_request(kFieldSignedDistance), refused);
  EXPECT_FALSE(status.ok());
  EXPECT_NE(status.message().find("point 0 "), std::string::npos) << status.message();
  for (bool exact : {false, true}) {
    const QueryRequest request = sdf_request(kFieldSignedDistance | kFieldPseudoDistance | kFieldSheetDistance |
                                                 kFieldProjection | kFieldHarnackBound | kFieldW,
                                             0.5f, exact);
    std::vector<PointResult> r;
    for (const vec3& x : points) r.push_back(evaluate_point(model.view(), x, request));
    for (size_t i = 0; i < 3; ++i) {
      EXPECT_FALSE(std::isfinite(r[i].sdf.distance)) << i << " sdf " << r[i].sdf.distance;
      EXPECT_FALSE(r[i].projection.converged) << i;
    }
    EXPECT_TRUE(std::isfinite(r[5].sdf.distance));
  }
}

}  // namespace
}  // namespace gwnrt
