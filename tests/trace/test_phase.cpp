// phase.h (φ = w mod 1, ∇w, the distance to ∂M and the Biot–Savart bound on |∇w| from one
// traversal of the cone) and what it is built from (segment_inverse_square_integral,
// HalfAngleSum, the cone over ∂M), against independent references computed in double: closed
// forms and composite Gauss–Legendre quadrature for the segment integrals, Σ atan2 for the
// rotations, brute-force sums over M for w and ∇w, projections onto every segment of ∂M for the
// distance (phase_fixtures.h).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <set>
#include <span>
#include <string>
#include <vector>

#include "gwnrt/field/distance.h"
#include "gwnrt/field/solid_angle.h"
#include "gwnrt/field/winding_number.h"
#include "gwnrt/model/model.h"
#include "gwnrt/trace/phase.h"
#include "phase_fixtures.h"
#include "test_util.h"

namespace gwnrt {
namespace {

// ---------------------------------------------------------------------------------------------
// References in double.
// ---------------------------------------------------------------------------------------------

// ∫ |dl| / |l - x|² over the segment a -> b, closed form: with u = a - x, v = b - x and α the
// angle the segment subtends at x, α L / |u × v|. On the segment's line outside the segment
// (u × v = 0, u·v > 0) the limit L / (|u||v|); on the segment itself +inf. α/|u×v| is well
// conditioned for u·v > 0 (≈ 1/(u·v)), and beside the segment |u×v| = h·L is accurate to a
// relative 1e-16·L/h.
double segment_integral_closed(const dvec3& a, const dvec3& b, const dvec3& x) {
  const dvec3 u = a - x, v = b - x;
  const double c = glm::length(glm::cross(u, v)), d = glm::dot(u, v), length = glm::length(b - a);
  if (c > 0) return std::atan2(c, d) * length / c;
  if (d > 0) return length / (glm::length(u) * glm::length(v));
  return kInf;
}

// The same integral by composite 10-point Gauss–Legendre quadrature of ds / (h² + s²) (s along
// the line from the foot of x, h the distance to the line), on panels [p, p + max(h, p)]: each
// panel's poles ±ih lie at least two half-widths from it, so each panel is exact to ~1e-15.
struct GaussLegendre10 {
  double node[10], weight[10];
  GaussLegendre10() {
    const int n = 10;
    for (int i = 0; i < n; ++i) {  // Newton on P_10 from the Chebyshev-like guess
      double z = std::cos(kPi * (i + 0.75) / (n + 0.5)), pp = 0;
      for (int it = 0; it < 100; ++it) {
        double p1 = 1, p2 = 0;
        for (int j = 1; j <= n; ++j) {
          const double p3 = p2;
          p2 = p1;
          p1 = ((2.0 * j - 1.0) * z * p2 - (j - 1.0) * p3) / j;
        }
        pp = n * (z * p1 - p2) / (z * z - 1.0);
        const double dz = p1 / pp;
        z -= dz;
        if (std::fabs(dz) < 1e-16) break;
      }
      node[i] = z;
      weight[i] = 2.0 / ((1.0 - z * z) * pp * pp);
    }
  }
};

double inverse_square_quadrature(double h, double s0, double s1) {  // ∫_{s0}^{s1} ds/(h²+s²), 0 <= s0 <= s1
  static const GaussLegendre10 gl;
  double total = 0, p = s0;
  while (p < s1) {
    const double q = std::min(s1, p + std::max(h, p));
    const double mid = 0.5 * (p + q), half = 0.5 * (q - p);
    for (int i = 0; i < 10; ++i) {
      const double s = mid + half * gl.node[i];
      total += half * gl.weight[i] / (h * h + s * s);
    }
    p = q;
  }
  return total;
}

double segment_integral_quadrature(const dvec3& a, const dvec3& b, const dvec3& x) {
  const double length = glm::length(b - a);
  const dvec3 e = (b - a) / length;
  const double sa = glm::dot(a - x, e), sb = glm::dot(b - x, e);
  const double h = glm::length((a - x) - sa * e);
  if (sa < 0 && sb > 0) {
    if (h == 0) return kInf;
    return inverse_square_quadrature(h, 0, -sa) + inverse_square_quadrature(h, 0, sb);
  }
  const double lo = std::min(std::fabs(sa), std::fabs(sb)), hi = std::max(std::fabs(sa), std::fabs(sb));
  if (h == 0 && lo == 0) return kInf;
  return inverse_square_quadrature(h, lo, hi);
}

// (1/4π) ∮_{∂M} |dl| / |l - x|², the quantity sample_phase bounds.
double boundary_integral_ref(const BoundaryRef& r, const dvec3& x) {
  double total = 0;
  for (size_t s = 0; s < r.size(); ++s) total += segment_integral_closed(r.a[s], r.b[s], x);
  return total / (4.0 * kPi);
}

// The smallest expansion radius of any cluster of the cone's tree. A cluster read from afar has
// |d| > beta·r (beta = 2), so its distance bound max(|d| - r, box) exceeds r >= this: a point
// nearer than this to ∂M gets its exact distance from the near triangles (see PhaseSum::far).
float smallest_cone_cluster_radius(const GwnModel& model) {
  const TriangleTree& cone = model.cone_tree();
  float r = kInfinity;
  for (size_t n = 0; n < cone.bvh.nodes.size(); ++n)
    for (int l = 0; l < kBvhWidth; ++l)
      if (cone.bvh.nodes[n].child[l] != kEmptyLane) r = std::min(r, cone.expansion[n].radius[l]);
  return r;
}

const char* kKindNames[4] = {"near dM", "near cone edge", "in box", "far away"};

// ---------------------------------------------------------------------------------------------
// 1. segment_inverse_square_integral
// ---------------------------------------------------------------------------------------------

TEST(Phase, SegmentIntegralBound) {
  RandomDouble rng(4101);
  double min_ratio = kInf, max_ratio = 0, max_quadrature_error = 0;
  int kind_count[5] = {0, 0, 0, 0, 0};
  for (int i = 0; i < 20000; ++i) {
    const int kind = i % 5;
    const double scale = rng.exp10(-2, 2);
    const dvec3 a = scale * (3.0 * dvec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)));
    const double length = scale * rng.exp10(-1, 0.5);
    const dvec3 dir = rng.unit();
    const dvec3 b = a + length * dir;
    dvec3 x;
    switch (kind) {
      case 0:  // anywhere around the segment
        x = a + 0.5 * (b - a) + length * rng.exp10(-1, 1) * rng.unit();
        break;
      case 1: {  // nearly on the segment's line, outside it (sometimes exactly on it in double)
        const double t = rng.chance(0.5) ? -rng.exp10(-3, 0.5) : 1.0 + rng.exp10(-3, 0.5);
        const double offset = rng.chance(0.2) ? 0.0 : length * rng.exp10(-9, -2);
        x = a + t * (b - a) + offset * rng.perpendicular(dir);
        break;
      }
      case 2:  // beside the segment, very close to it (α near π)
        x = a + rng.uniform(0.02, 0.98) * (b - a) + length * rng.exp10(-6, -0.5) * rng.perpendicular(dir);
        break;
      case 3:  // far away (α small: the 2L/Q branch, tight within 1 + α²/12)
        x = a + length * rng.exp10(1, 5) * rng.unit();
        break;
      default:  // at distances comparable to L, around α ≈ 100° where the bound is loosest
        x = a + rng.uniform(-0.5, 1.5) * (b - a) + length * rng.exp10(-1, 0.3) * rng.perpendicular(dir);
        break;
    }
    // The library sees float points; the reference uses the same float points in double.
    const dvec3 af(to_float(a)), bf(to_float(b)), xf(to_float(x));
    const dvec3 u = af - xf, v = bf - xf, c = glm::cross(u, v);
    const double exact = segment_integral_closed(af, bf, xf);
    if (!(exact < kInf) || !(exact > 0)) continue;  // x on the segment (not generated by these kinds)
    // As phase.h calls it: the products in double, rounded to float; the length rounded up (cone_segments).
    const float bound =
        segment_inverse_square_integral(float(glm::length(u) * glm::length(v)), float(glm::dot(u, v)),
                                        float(glm::dot(c, c)), std::nextafter(float(glm::length(bf - af)), kInfinity));
    const double ratio = double(bound) / exact;
    ++kind_count[kind];
    // Lower side: the bound is exact in the limit α -> 0 (far segments, ratio 1 + α²/12), where
    // the float rounding of its four inputs and its own two or three operations (a few ulps,
    // 6e-8 each) can put it a relative 1e-6 below; sample_phase rounds its sum up by 1e-5 for that.
    EXPECT_GE(ratio, 1.0 - 1e-6) << "kind " << kind << " a " << vec_string(af) << " b " << vec_string(bf) << " x "
                                 << vec_string(xf) << " bound " << bound << " exact " << exact;
    // Upper side: min(2 tan(α/2), π sin(α/2)) / α <= 1.3754 (at α ≈ 101°), 1e-4 for float.
    EXPECT_LE(ratio, 1.38 * (1.0 + 1e-4))
        << "kind " << kind << " a " << vec_string(af) << " b " << vec_string(bf) << " x " << vec_string(xf);
    min_ratio = std::min(min_ratio, ratio);
    max_ratio = std::max(max_ratio, ratio);
    // The closed form itself against quadrature (one in four samples).
    if (i % 4 == 0) {
      const double q = segment_integral_quadrature(af, bf, xf);
      // Both in double: the closed form loses a relative 1e-16·L/h beside the segment (h >= 1e-6 L here).
      const double err = std::fabs(q - exact) / exact;
      EXPECT_LE(err, 1e-8) << "closed form vs quadrature, kind " << kind << " x " << vec_string(xf);
      max_quadrature_error = std::max(max_quadrature_error, err);
    }
  }
  for (int k = 0; k < 5; ++k) EXPECT_GT(kind_count[k], 3000) << "kind " << k;
  std::printf("[ segment bound ] bound/exact in [%.9f, %.6f]; closed form vs quadrature %.3g\n", min_ratio, max_ratio,
              max_quadrature_error);
  // The sampling reaches the worst case (not just easy far segments).
  EXPECT_GT(max_ratio, 1.37);

  // x on the segment (exactly, in float and double): no finite bound.
  const vec3 a(0.0f, 0.0f, 0.0f), b(1.0f, 2.0f, 3.0f), x = 0.5f * (a + b);
  const dvec3 u = dvec3(a) - dvec3(x), v = dvec3(b) - dvec3(x), c = glm::cross(u, v);
  EXPECT_EQ(glm::dot(c, c), 0.0);
  EXPECT_EQ(segment_inverse_square_integral(float(glm::length(u) * glm::length(v)), float(glm::dot(u, v)),
                                            float(glm::dot(c, c)), glm::length(b - a)),
            kInfinity);
}

// ---------------------------------------------------------------------------------------------
// 2. HalfAngleSum
// ---------------------------------------------------------------------------------------------

TEST(Phase, HalfAngleSumMatchesAtan2Sum) {
  RandomDouble rng(4202);
  double max_error = 0;
  int zeros = 0, on_cut = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int n = 1 + rng.index(300);
    HalfAngleSum sum, sum_without_zeros;
    double reference = 0;
    for (int k = 0; k < n; ++k) {
      float num, den;
      const int type = rng.index(10);
      if (type == 0) {  // no angle: (±0, ±0)
        num = rng.chance(0.5) ? 0.0f : -0.0f;
        den = rng.chance(0.5) ? 0.0f : -0.0f;
      } else if (type == 1) {  // on the cut: (±0, negative) is ±π
        num = rng.chance(0.5) ? 0.0f : -0.0f;
        den = -float(rng.exp10(-20, 20));
      } else if (type == 2) {  // axes
        const float m = float(rng.exp10(-20, 20));
        const int axis = rng.index(3);
        num = axis == 0 ? 0.0f : float(rng.sign()) * m;
        den = axis == 0 ? m : (axis == 1 ? 0.0f : -0.0f);
      } else if (type < 6) {  // independent magnitudes from 1e-20 to 1e20
        num = float(rng.sign() * rng.exp10(-20, 20));
        den = float(rng.sign() * rng.exp10(-20, 20));
      } else {  // a uniform angle at a random magnitude
        const double m = rng.exp10(-20, 20), t = rng.uniform(-kPi, kPi);
        num = float(m * std::sin(t));
        den = float(m * std::cos(t));
      }
      sum.add({num, den});
      if (num == 0.0f && den == 0.0f) {  // atan2(±0, -0) would be ±π: such a factor has no angle
        ++zeros;
        continue;
      }
      if (num == 0.0f && den < 0.0f) ++on_cut;
      sum_without_zeros.add({num, den});
      reference += std::atan2(double(num), double(den));
    }
    // Skipping is exact: the state is untouched by a zero factor.
    EXPECT_EQ(sum.angle(), sum_without_zeros.angle()) << "trial " << trial;
    const double angle = sum.angle();
    EXPECT_GT(angle, -kPi - 1e-6);
    EXPECT_LE(angle, kPi + 1e-6);
    // Each float complex product turns the running product by at most ~2 ulps (1.2e-7 rad),
    // the final atan2f adds one more; the errors are independent, so for n <= 300 factors they
    // sum to ~sqrt(n)·1e-7 = 2e-6 (the worst case n·1.2e-7 = 4e-5 needs every rounding aligned).
    const double error = std::fabs(wrap_angle(angle - reference));
    EXPECT_LE(error, 1e-5) << "trial " << trial << " n " << n << " angle " << angle << " reference "
                           << wrap_angle(reference);
    max_error = std::max(max_error, error);
  }
  EXPECT_GT(zeros, 100);
  EXPECT_GT(on_cut, 100);
  std::printf("[ half angles   ] max |angle - Σ atan2| on the circle %.3g rad\n", max_error);

  // A long product of the same factor: 10000 · atan2(1, 3) (each 16-factor rescale exercised).
  HalfAngleSum sum;
  for (int k = 0; k < 10000; ++k) sum.add({1.0f, 3.0f});
  const double error = std::fabs(wrap_angle(double(sum.angle()) - 10000.0 * std::atan2(1.0, 3.0)));
  std::printf("[ half angles   ] 10000 equal factors: error %.3g rad\n", error);
  // 10000 roundings of a systematic sign can add up: sqrt(n)·1e-7 is 1e-5, n·1.2e-7 is 1.2e-3.
  EXPECT_LE(error, 2e-3);
}

// ---------------------------------------------------------------------------------------------
// 3. The bounds of sample_phase on open meshes
// ---------------------------------------------------------------------------------------------

using SegmentKey = std::array<float, 6>;
SegmentKey segment_key(const vec3& a, const vec3& b) { return {a.x, a.y, a.z, b.x, b.y, b.z}; }

// Per leaf-order cone triangle, the length of the segment of ∂M it carries: its edge 1 -> 2 when
// that is a segment of the curve (by exact position), else 0 (an inner triangle of a spanned loop,
// whose edges are spokes between apexes).
std::vector<double> carried_lengths(const GwnModel& model) {
  const BoundaryCurve& curve = model.boundary();
  const std::vector<vec3>& cone = model.cone_tree().vertices;
  std::set<SegmentKey> segments;
  for (size_t s = 0; s < curve.segment_count(); ++s)
    segments.insert(segment_key(curve.endpoints[2 * s], curve.endpoints[2 * s + 1]));
  std::vector<double> out(cone.size() / 3, 0.0);
  for (size_t t = 0; t < out.size(); ++t)
    if (segments.count(segment_key(cone[3 * t + 1], cone[3 * t + 2])))
      out[t] = glm::length(dvec3(cone[3 * t + 2]) - dvec3(cone[3 * t + 1]));
  return out;
}

// What the tracer reads off the cone's tree: each triangle's segment length (rounded up) and
// 1/length² (0 for an inner triangle), and per lane the length of ∂M below it (rounded up, never
// short), against double sums over the carried segments.
void check_cone_lengths(const GwnModel& model) {
  const BoundaryCurve& curve = model.boundary();
  const std::vector<vec3>& cone = model.cone_tree().vertices;
  const std::span<const ConeSegment> segments = model.cone_segments();
  const std::vector<double> carried = carried_lengths(model);
  ASSERT_EQ(segments.size(), cone.size() / 3);
  for (size_t t = 0; t < segments.size(); ++t) {
    const double length = carried[t];
    if (length == 0.0) {
      EXPECT_EQ(segments[t].length, 0.0f) << "inner cone triangle " << t;
      continue;
    }
    EXPECT_GE(double(segments[t].length), length);
    EXPECT_LE(double(segments[t].length), length * (1 + 3e-7));
    EXPECT_NEAR(double(segments[t].inverse_length2) * length * length, 1.0, 3e-7);
  }
  const TriangleTree& tree = model.cone_tree();
  const std::span<const WideNodeLength> lengths = model.cone_boundary_lengths();
  ASSERT_EQ(lengths.size(), tree.bvh.nodes.size());
  auto below = [&](auto& self, uint32_t node, int lane) -> double {
    const WideNode& n = tree.bvh.nodes[node];
    if (n.child[lane] == kEmptyLane) return 0.0;
    double total = 0;
    if (n.count[lane] > 0) {
      for (uint32_t t = n.child[lane]; t < n.child[lane] + n.count[lane]; ++t) total += carried[t];
    } else {
      for (int l = 0; l < kBvhWidth; ++l) total += self(self, n.child[lane], l);
    }
    // Rounded up from the double sum: never short, at most an ulp or two long.
    EXPECT_GE(double(lengths[node].length[lane]), total) << "node " << node << " lane " << lane;
    EXPECT_LE(double(lengths[node].length[lane]), total * (1 + 3e-7)) << "node " << node << " lane " << lane;
    return total;
  };
  double total = 0;
  for (int l = 0; l < kBvhWidth; ++l) total += below(below, 0, l);
  double curve_length = 0;
  for (size_t s = 0; s < curve.segment_count(); ++s)
    curve_length += glm::length(dvec3(curve.endpoints[2 * s + 1]) - dvec3(curve.endpoints[2 * s]));
  EXPECT_NEAR(total, curve_length, 1e-12 * curve_length);
}

struct KindStats {
  int count = 0;
  double min_distance_ratio = kInf, max_distance_ratio = 0;  // R / exact distance
  double max_exact_distance_error = 0;                       // where R must be exact
  int exact_distance_points = 0;
  double min_bound_over_gradient = kInf;  // K / |∇w|
  double max_bound_over_integral = 0;     // K / (1/4π)∮|dl|/|l-x|²
  double min_bound_over_integral = kInf;
  double max_near_phi_error = 0;             // turns, beta = ∞
  double max_phi_error = 0;                  // turns, beta = 2
  double max_near_gradient_error = 0;        // |g - ∇w| / |∇w|, beta = ∞
  double max_gradient_error = 0;             // |g - ∇w| / |∇w|, beta = 2, 1e-2 or more from ∂M
  double max_gradient_error_over_bound = 0;  // |g - ∇w| / K, the same points
  int gradient_points = 0;
};

// sample_phase at the tracer's beta = 2 against exact sums: what the far clusters' order-2
// expansion leaves, about twice the largest measured (2.4e-4 for φ, 2.6e-3·K for ∇w, both at
// points of the box around bunny_holes several units from its holes). Tighter near ∂M and the
// cone's edges in practice (printed per kind of point).
constexpr double kPhiToleranceBeta2 = 5e-4;
constexpr double kGradientToleranceBeta2 = 5e-3;

void check_bounds_on(const char* name, const Mesh& mesh, uint32_t seed, const int counts[4]) {
  SCOPED_TRACE(name);
  const GwnModel model = build_model(mesh);
  const ModelView view = model.view();
  const BoundaryRef boundary = boundary_ref(model);
  ASSERT_GT(boundary.size(), 0u);
  const float exact_radius = smallest_cone_cluster_radius(model);
  check_cone_lengths(model);
  RandomDouble rng(seed);
  KindStats stats[4];
  for (int k = 0; k < 4; ++k)
    for (int i = 0; i < counts[k]; ++i) {
      const PointKind kind = PointKind(k);
      const vec3 x = sample_point(model, boundary, kind, rng);
      const dvec3 xd(x);
      const PhaseSample s = sample_phase(view, x, 2.0f, false);
      const PhaseSample sg = sample_phase(view, x, 2.0f, true);
      const PhaseSample sn = sample_phase(view, x, kInfinity, true);  // every cone triangle near
      const WindingSampleExact e = winding_number_exact(model.triangle_view(), x, true);
      const double distance = boundary_distance_ref(boundary, xd);
      const double integral = boundary_integral_ref(boundary, xd);
      const double gradient_norm = glm::length(e.gradient);
      if (!(distance > 0)) continue;  // on ∂M (not generated in practice)
      KindStats& st = stats[k];
      ++st.count;
      const std::string where = std::string(kKindNames[k]) + ", " + point_string(x);

      // Asking for ∇w changes nothing else (FMA contraction may differ between the two
      // specialisations by an ulp or so).
      EXPECT_LE(std::fabs(wrap_turns(double(sg.phi) - s.phi)), 1e-6) << where;
      EXPECT_NEAR(sg.boundary_distance, s.boundary_distance, 1e-6 * s.boundary_distance) << where;
      EXPECT_NEAR(sg.gradient_bound, s.gradient_bound, 1e-6 * s.gradient_bound) << where;
      // The device's sums (one lane and one near triangle at a time) give the host's lanes' φ, R
      // and K to float round-off (K is then rounded up by 1e-5, hence 2e-5 for it).
      detail::PhaseSum<false> scalar{
          view.cone, view.cone_boundary_lengths, view.cone_segments, x, {}, {}, {}, kInfinity, 0.0f, {}};
      visit_multipole(view.cone, x, 2.0f, scalar);
      const float scalar_w = scalar.far_field.omega * kInv4Pi + scalar.near_angle() * float(0.5 / kPi);
      EXPECT_LE(std::fabs(wrap_turns(double(scalar_w) - s.phi)), 1e-6) << where;
      EXPECT_NEAR(std::sqrt(scalar.nearest2), s.boundary_distance, 1e-6 * s.boundary_distance) << where;
      EXPECT_NEAR(scalar.integral * kInv4Pi, s.gradient_bound, 2e-5 * s.gradient_bound) << where;

      // (a) A lower bound on the distance to ∂M (1e-5: float products and one square root), tight
      // to a factor 2 everywhere (a little over: a spanned loop's clusters mix rim triangles with
      // inner ones, whose boxes reach into the loop; 0.499 seen beside the open hemisphere's
      // cone), and exact wherever no far cluster can be nearer than ∂M.
      const double ratio = s.boundary_distance / distance;
      EXPECT_LE(ratio, 1.0 + 1e-5) << where << " R " << s.boundary_distance << " exact " << distance;
      EXPECT_GE(ratio, 0.45) << where << " R " << s.boundary_distance << " exact " << distance;
      st.min_distance_ratio = std::min(st.min_distance_ratio, ratio);
      st.max_distance_ratio = std::max(st.max_distance_ratio, ratio);
      if (distance < exact_radius) {
        EXPECT_NEAR(ratio, 1.0, 1e-5) << where << " R " << s.boundary_distance << " exact " << distance;
        st.max_exact_distance_error = std::max(st.max_exact_distance_error, std::fabs(ratio - 1.0));
        ++st.exact_distance_points;
      }

      // (b) An upper bound on |∇w| (∇w of M by brute force in double), up to a relative 1e-6.
      EXPECT_GE(double(s.gradient_bound), gradient_norm * (1.0 - 1e-6))
          << where << " K " << s.gradient_bound << " |grad w| " << gradient_norm;
      if (gradient_norm > 0)
        st.min_bound_over_gradient = std::min(st.min_bound_over_gradient, s.gradient_bound / gradient_norm);

      // (c) An upper bound on the integral itself, with no slack: the float rounding of its terms
      // (a relative 1e-7 or so, test 1) is what sample_phase's final round-up by 1e-5 covers. Not
      // vacuous: at most 2.5 times the integral (1.38 for near segments; far clusters use their
      // length over the squared lower bound on their distance).
      const double over = s.gradient_bound / integral;
      EXPECT_LE(over, 2.5) << where << " K " << s.gradient_bound << " integral " << integral;
      EXPECT_GE(over, 1.0) << where << " K " << s.gradient_bound << " integral " << integral;
      st.max_bound_over_integral = std::max(st.max_bound_over_integral, over);
      st.min_bound_over_integral = std::min(st.min_bound_over_integral, over);

      // (d) φ = w mod 1 of M, on the circle. Every cone triangle as near (beta = ∞): only the
      // arithmetic of the near field is left (terms in double, their tangents rounded to float,
      // HalfAngleSum: ~1e-7 rad per term over at most a few hundred terms, /2π), measured 1e-7.
      const double exact_phi_error = std::fabs(wrap_turns(double(sn.phi) - e.w));
      EXPECT_LE(exact_phi_error, 2e-6) << where << " beta inf phi " << sn.phi << " w " << e.w;
      st.max_near_phi_error = std::max(st.max_near_phi_error, exact_phi_error);
      // At the tracer's beta = 2 the far clusters' order-2 expansion adds its truncation error,
      // which decays like (r/|d|)³ with beta (measured: 2.4e-4 at beta 2, 4e-6 at 4, 1e-7 at 8,
      // largest at points in the box several units from bunny_holes' holes).
      const double phi_error = std::fabs(wrap_turns(double(s.phi) - e.w));
      EXPECT_LE(phi_error, kPhiToleranceBeta2) << where << " phi " << s.phi << " w " << e.w;
      EXPECT_GE(s.phi, 0.0f);
      EXPECT_LT(s.phi, 1.0f);
      st.max_phi_error = std::max(st.max_phi_error, phi_error);

      // (e) ∇w. All near: double sums rounded to float, at any distance from ∂M (1e-5 relative).
      // The absolute 1e-6 covers far away points (|∇w| ~ 1e-10 there), where the terms of both
      // double sums (~1/d² each, ~1/d³ together) cancel to a few digits.
      const double near_gradient_error = glm::length(dvec3(sn.gradient) - e.gradient);
      EXPECT_LE(near_gradient_error, 1e-5 * gradient_norm + 1e-6)
          << where << " beta inf gradient " << vec_string(sn.gradient) << " exact " << vec_string(e.gradient);
      st.max_near_gradient_error = std::max(st.max_near_gradient_error, near_gradient_error / gradient_norm);
      // At beta = 2, farther than 1e-2 from ∂M: the truncation error of far clusters is a share of
      // their own field, so it is measured against K (the sum of the fields' magnitudes), not
      // |∇w| (which cancels to almost nothing far away: relative errors reach 15% there).
      if (distance > 1e-2) {
        const double gradient_error = glm::length(dvec3(sg.gradient) - e.gradient);
        EXPECT_LE(gradient_error, kGradientToleranceBeta2 * s.gradient_bound)
            << where << " gradient " << vec_string(sg.gradient) << " exact " << vec_string(e.gradient) << " K "
            << s.gradient_bound;
        st.max_gradient_error = std::max(st.max_gradient_error, gradient_error / gradient_norm);
        st.max_gradient_error_over_bound =
            std::max(st.max_gradient_error_over_bound, gradient_error / s.gradient_bound);
        ++st.gradient_points;
      }
    }
  for (int k = 0; k < 4; ++k) {
    const KindStats& st = stats[k];
    std::printf(
        "[ %-11s ] %-14s %4d pts: R/d in [%.6f, %.8f] (exact at %d, err %.2g); K/|grad w| >= %.4f; "
        "K/integral in [%.7f, %.4f]; phi err %.2g (all near %.2g); grad err/|grad| %.2g, /K %.2g (%d pts; all near "
        "%.2g)\n",
        name, kKindNames[k], st.count, st.min_distance_ratio, st.max_distance_ratio, st.exact_distance_points,
        st.max_exact_distance_error, st.min_bound_over_gradient, st.min_bound_over_integral, st.max_bound_over_integral,
        st.max_phi_error, st.max_near_phi_error, st.max_gradient_error, st.max_gradient_error_over_bound,
        st.gradient_points, st.max_near_gradient_error);
  }
  // The exact-distance claim was exercised beside ∂M and the near field beside the cone's edges.
  EXPECT_GT(stats[0].exact_distance_points, counts[0] / 4);
}

TEST(Phase, BoundsHoldOnOpenMeshes) {
  const int bunny_counts[4] = {1000, 600, 500, 100}, small_counts[4] = {700, 500, 400, 100};
  check_bounds_on("bunny_holes", load_test_mesh("bunny_holes.obj"), 4301, bunny_counts);
  check_bounds_on("open cube", test::make_cube(true), 4302, small_counts);
  check_bounds_on("hexagon fan", test::make_hexagon_fan(), 4303, small_counts);
  // A rim the cone spans: inner triangles carry no segment (none of R's or K's terms).
  const Mesh hemisphere = test::make_hemisphere(12, 200);
  ASSERT_GT(build_model(hemisphere).view().cone.triangle_count, 200u);
  check_bounds_on("open hemisphere", hemisphere, 4304, small_counts);
}

// ---------------------------------------------------------------------------------------------
// 6. The cone keeps every segment of ∂M
// ---------------------------------------------------------------------------------------------

// A plate on a grid of 0.25 cells over [x0, x1] × [y0, y1], without the cells for which `hole`
// is true; vertices not on ∂M are lifted by a smooth bump so that w varies. Every side of the
// boundary is a run of collinear segments.
template <class Hole>
Mesh make_grid_plate(float x0, float y0, float x1, float y1, Hole hole) {
  const float h = 0.25f;
  const int nx = int(std::lround((x1 - x0) / h)), ny = int(std::lround((y1 - y0) / h));
  auto cell_in = [&](int i, int j) {
    return i >= 0 && j >= 0 && i < nx && j < ny && !hole(x0 + (i + 0.5f) * h, y0 + (j + 0.5f) * h);
  };
  Mesh m;
  auto id = [&](int i, int j) { return uint32_t(j * (nx + 1) + i); };
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      const float x = x0 + i * h, y = y0 + j * h;
      const bool interior = cell_in(i - 1, j - 1) && cell_in(i, j - 1) && cell_in(i - 1, j) && cell_in(i, j);
      const float z = interior ? 0.2f + 0.15f * std::sin(1.3f * x) * std::cos(0.9f * y) : 0.0f;
      m.positions.push_back({x, y, z});
    }
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      if (cell_in(i, j)) {
        m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
        m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
      }
  return m;
}

// A fan from a raised point over the L-shaped polygon (0,0) (2,0) (2,1) (1,1) (1,2) (0,2), its
// sides subdivided so that the mean of its 16 vertices is exactly the reflex corner (1, 1): the
// corner's two segments and the collinear ones beside them lie on lines through the mean.
Mesh make_l_fan() {
  const std::vector<vec3> rim = {{0, 0, 0},     {1.25f, 0, 0}, {1.5f, 0, 0}, {2, 0, 0},    {2, 0.25f, 0}, {2, 0.5f, 0},
                                 {2, 1, 0},     {1.5f, 1, 0},  {1, 1, 0},    {1, 1.5f, 0}, {1, 2, 0},     {0.5f, 2, 0},
                                 {0.25f, 2, 0}, {0, 2, 0},     {0, 1.5f, 0}, {0, 1.25f, 0}};
  Mesh m;
  m.positions.push_back({0.5f, 0.5f, 0.3f});  // in the L's kernel [0,1]², off every side's line
  m.positions.insert(m.positions.end(), rim.begin(), rim.end());
  const uint32_t n = uint32_t(rim.size());
  for (uint32_t k = 0; k < n; ++k) m.triangles.push_back({0u, 1 + k, 1 + (k + 1) % n});
  return m;
}

void check_cone_on(const char* name, const Mesh& mesh, bool expect_mean_on_a_segment_line, uint32_t seed) {
  SCOPED_TRACE(name);
  const GwnModel model = build_model(mesh);
  const BoundaryCurve& curve = model.boundary();
  const std::vector<vec3>& cone = model.cone_tree().vertices;
  ASSERT_GT(curve.segment_count(), 0u);

  // The case is the one meant: some loop's mean lies on the line of one of its segments (the
  // apex boundary_cone starts from), so a cone triangle would have zero area there.
  uint32_t loop_count = 0;
  const std::vector<uint32_t> loop = boundary_loops(curve, loop_count);
  std::vector<dvec3> sum(loop_count, dvec3(0.0));
  std::vector<double> count(loop_count, 0.0);
  for (size_t s = 0; s < curve.segment_count(); ++s) {
    sum[loop[s]] += dvec3(curve.endpoints[2 * s]) + dvec3(curve.endpoints[2 * s + 1]);
    count[loop[s]] += 2;
  }
  int collinear_with_mean = 0;
  for (size_t s = 0; s < curve.segment_count(); ++s) {
    const dvec3 mean = sum[loop[s]] / count[loop[s]];
    const dvec3 a(curve.endpoints[2 * s]), b(curve.endpoints[2 * s + 1]);
    const dvec3 apex(to_float(mean));  // as boundary_cone rounds it
    const dvec3 n = glm::cross(a - apex, b - apex);
    collinear_with_mean += n == dvec3(0.0);
  }
  if (expect_mean_on_a_segment_line) {
    EXPECT_GE(collinear_with_mean, 4);
  }

  // Every segment carried by one cone triangle of non-zero area (none dropped); the other
  // triangles are inner ones of spanned loops, which carry none.
  ASSERT_EQ(cone.size() % 3, 0u);
  const std::vector<double> carried = carried_lengths(model);
  std::map<SegmentKey, int> unmatched;
  for (size_t s = 0; s < curve.segment_count(); ++s)
    ++unmatched[segment_key(curve.endpoints[2 * s], curve.endpoints[2 * s + 1])];
  size_t carrying = 0;
  for (size_t t = 0; t < cone.size() / 3; ++t) {
    if (carried[t] == 0.0) continue;
    ++carrying;
    EXPECT_FALSE(is_degenerate_triangle(cone[3 * t], cone[3 * t + 1], cone[3 * t + 2])) << "cone triangle " << t;
    --unmatched[segment_key(cone[3 * t + 1], cone[3 * t + 2])];
  }
  EXPECT_EQ(carrying, curve.segment_count());
  for (const auto& [key, n] : unmatched)
    EXPECT_EQ(n, 0) << "segment (" << key[0] << ", " << key[1] << ", " << key[2] << ") -> (" << key[3] << ", " << key[4]
                    << ", " << key[5] << ") carried by " << -n << " extra cone triangles";
  // An apex moved off the lines stays near its loop's mean (a fanned loop) or inside its loop's
  // box (a spanned one: the group's mean): at most 8 tries of 1e-3 of the box diagonal (of the
  // loop, or of the group, which is smaller) each (boundary_cone), plus float rounding.
  std::vector<Aabb> loop_box(loop_count);
  std::vector<size_t> loop_segments(loop_count, 0);
  for (size_t s = 0; s < curve.segment_count(); ++s) {
    loop_box[loop[s]].extend(curve.endpoints[2 * s]);
    loop_box[loop[s]].extend(curve.endpoints[2 * s + 1]);
    ++loop_segments[loop[s]];
  }
  for (size_t t = 0; t < cone.size() / 3; ++t) {
    if (carried[t] == 0.0) continue;
    size_t s = 0;  // the segment the triangle carries, hence its loop
    while (s < curve.segment_count() && segment_key(curve.endpoints[2 * s], curve.endpoints[2 * s + 1]) !=
                                            segment_key(cone[3 * t + 1], cone[3 * t + 2]))
      ++s;
    ASSERT_LT(s, curve.segment_count());
    const Aabb& box = loop_box[loop[s]];
    const double size = glm::length(dvec3(box.hi) - dvec3(box.lo)), reach = 8e-3 * size * (1 + 1e-5) + 1e-6 * size;
    if (loop_segments[loop[s]] <= kFannedLoopSegments) {
      const dvec3 mean = sum[loop[s]] / count[loop[s]];
      EXPECT_LE(glm::length(dvec3(cone[3 * t]) - mean), reach) << "cone triangle " << t;
    } else {
      for (int k = 0; k < 3; ++k) {
        EXPECT_GE(double(cone[3 * t][k]), double(box.lo[k]) - reach) << "cone triangle " << t;
        EXPECT_LE(double(cone[3 * t][k]), double(box.hi[k]) + reach) << "cone triangle " << t;
      }
    }
  }

  check_cone_lengths(model);

  // sample_phase sees every segment: beside each of them (the ones on lines through the mean
  // included) R is the exact distance, K bounds |∇w| and φ is w mod 1.
  const ModelView view = model.view();
  const BoundaryRef boundary = boundary_ref(model);
  const float exact_radius = smallest_cone_cluster_radius(model);
  RandomDouble rng(seed);
  double worst_distance_error = 0, worst_phi_error = 0, worst_near_phi_error = 0;
  int exact_points = 0;
  for (size_t s = 0; s < boundary.size(); ++s)
    for (int k = 0; k < 8; ++k) {
      const dvec3 on = boundary.a[s] + rng.uniform(0.05, 0.95) * (boundary.b[s] - boundary.a[s]);
      const vec3 x = to_float(on + rng.exp10(-4, -1.5) * rng.unit());
      const dvec3 xd(x);
      const double distance = boundary_distance_ref(boundary, xd);
      const PhaseSample p = sample_phase(view, x, 2.0f, false);
      const WindingSampleExact e = winding_number_exact(model.triangle_view(), x, true);
      const std::string where = "segment " + std::to_string(s) + ", " + point_string(x);
      EXPECT_LE(p.boundary_distance, distance * (1 + 1e-5)) << where;
      if (distance < exact_radius) {
        ++exact_points;
        EXPECT_NEAR(p.boundary_distance / distance, 1.0, 1e-5) << where << " R " << p.boundary_distance;
        worst_distance_error = std::max(worst_distance_error, std::fabs(p.boundary_distance / distance - 1.0));
      }
      EXPECT_GE(double(p.gradient_bound), glm::length(e.gradient) * (1 - 1e-6)) << where;
      // φ: with every cone triangle near, only float rounding (see test 3 (d)); at beta = 2, the
      // far field's truncation too.
      const double near_phi_error = std::fabs(wrap_turns(double(sample_phase(view, x, kInfinity, false).phi) - e.w));
      EXPECT_LE(near_phi_error, 2e-6) << where;
      const double phi_error = std::fabs(wrap_turns(double(p.phi) - e.w));
      EXPECT_LE(phi_error, kPhiToleranceBeta2) << where;
      worst_phi_error = std::max(worst_phi_error, phi_error);
      worst_near_phi_error = std::max(worst_near_phi_error, near_phi_error);
    }
  EXPECT_EQ(exact_points, int(8 * boundary.size()));
  std::printf(
      "[ %-11s ] %zu segments in %u loops (%d on a line through their loop's mean), %zu cone "
      "triangles; beside them R err %.2g, phi err %.2g (all near %.2g)\n",
      name, curve.segment_count(), loop_count, collinear_with_mean, cone.size() / 3, worst_distance_error,
      worst_phi_error, worst_near_phi_error);
}

TEST(Phase, ConeKeepsEverySegment) {
  // A square with four collinear segments per side (its mean, the centre, is on no side's line).
  check_cone_on("grid square", make_grid_plate(0, 0, 1, 1, [](float, float) { return false; }), false, 4601);
  // A plate with an S-shaped hole [0,2]×[0,1] ∪ [1,3]×[1,2]: the hole's vertices are symmetric
  // about (1.5, 1), its mean, which lies on the line y = 1 of eight of its segments.
  check_cone_on("S hole",
                make_grid_plate(-1, -1, 4, 3,
                                [](float x, float y) {
                                  return (x > 0 && x < 2 && y > 0 && y < 1) || (x > 1 && x < 3 && y > 1 && y < 2);
                                }),
                true, 4602);
  // The L fan: the mean is the reflex corner, on the lines of four segments.
  check_cone_on("L fan", make_l_fan(), true, 4603);
}

}  // namespace
}  // namespace gwnrt
