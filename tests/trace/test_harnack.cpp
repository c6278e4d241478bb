// The Harnack step (harnack.h): gradient_bound_step against the root of its equation, and the
// safe step from phase.h's bounds, which never reaches a level (Monte Carlo against the exact w
// along the step).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "gwnrt/field/winding_number.h"
#include "gwnrt/model/model.h"
#include "gwnrt/trace/harnack.h"
#include "gwnrt/trace/phase.h"
#include "phase_fixtures.h"
#include "test_util.h"

namespace gwnrt {
namespace {
// ---------------------------------------------------------------------------------------------
// 4. gradient_bound_step
// ---------------------------------------------------------------------------------------------

// The root θ* of θ / (1 - θ)² = 1/p, by bisection on y = log θ of
// h(y) = log p + y - 2 log(1 - e^y) (increasing), which keeps 1 - θ* accurate near θ* = 1.
double step_root(double p) {
  double lo = -800.0, hi = 0.0;
  const double log_p = std::log(p);
  for (int it = 0; it < 80; ++it) {  // 800 / 2^80: y to 1e-21, θ* to double precision
    const double mid = 0.5 * (lo + hi);
    const double h = log_p + mid - 2.0 * std::log(-std::expm1(mid));
    (h < 0 ? lo : hi) = mid;
  }
  return std::exp(0.5 * (lo + hi));
}

TEST(Phase, GradientBoundStepSolvesItsEquation) {
  RandomDouble rng(4404);
  double max_theta_error = 0, max_equation_error = 0;
  int near_one = 0, zero_steps_on_overflow = 0;
  for (int i = 0; i < 40000; ++i) {
    const float radius = float(rng.exp10(-6, 3));
    const float bound = float(i % 7 == 0 ? rng.exp10(-16, -6) : rng.exp10(-6, 6));  // K·R tiny: θ -> 1
    const float gap = float(i % 5 == 0 ? rng.exp10(-12, -3) : rng.uniform(0.0, 0.5));
    const float step = gradient_bound_step(radius, bound, gap);
    const std::string where = "R " + std::to_string(radius) + " K " + std::to_string(bound) + " gap " +
                              std::to_string(gap) + " step " + std::to_string(step);
    ASSERT_GE(step, 0.0f) << where;
    ASSERT_LE(step, radius) << where;
    const double p = double(radius) * double(bound) / double(gap);
    const double theta_star = step_root(p);
    const double theta = double(step) / double(radius);
    if (1.0 - theta_star > 4e-7) {  // θ* R lies below R by more than float's rounding of R
      EXPECT_LT(step, radius) << where;
    } else {
      ++near_one;
    }
    if (double(radius) * double(bound) / double(gap) > 1e19) {
      // p (4 + p) overflows float: the step may come out as 0, which is safe (and p > 1e19 needs a
      // gap below 1e-19 of a level); it must never exceed the root.
      EXPECT_LE(theta, theta_star * (1 + 1e-6)) << where;
      zero_steps_on_overflow += step == 0.0f;
      continue;
    }
    // The step: a few float roundings of 2R / (2 + p + sqrt(p(4 + p))), 6e-8 each.
    const double theta_error = std::fabs(theta - theta_star) / theta_star;
    EXPECT_LE(theta_error, 2e-6) << where << " theta* " << theta_star;
    max_theta_error = std::max(max_theta_error, theta_error);
    // Its equation, θ/(1 - θ)² = gap/(R K), to 1e-4 where it is well conditioned: a relative
    // error δ in θ moves the left side by δ(1 + 2θ/(1 - θ)), which float θ near 1 cannot meet.
    if (1.0 - theta_star > 1e-2) {
      const double equation_error = std::fabs(theta / ((1 - theta) * (1 - theta)) * p - 1.0);
      EXPECT_LE(equation_error, 1e-4) << where;
      max_equation_error = std::max(max_equation_error, equation_error);
    } else {  // 1 - θ itself to 1e-4 relative, plus float's spacing of θ near 1
      EXPECT_NEAR(1.0 - theta, 1.0 - theta_star, 1e-4 * (1.0 - theta_star) + 2e-7) << where;
    }
  }
  // The two limits exactly.
  EXPECT_EQ(gradient_bound_step(1.0f, 1.0f, 0.0f), 0.0f);    // on a level: no step
  EXPECT_EQ(gradient_bound_step(2.5f, 3.0f, 1e-30f), 0.0f);  // p = 7.5e30: overflow, still 0
  // K R tiny: θ = 1 - sqrt(p) + O(p), p = 5e-12, and 1 - θ rounds to 0 only once p < 1e-14 or so.
  EXPECT_NEAR(gradient_bound_step(2.5f, 1e-12f, 0.5f) / 2.5, 1.0 - std::sqrt(5e-12), 2e-7);
  EXPECT_EQ(gradient_bound_step(2.5f, 1e-20f, 0.5f), 2.5f);
  EXPECT_GT(near_one, 100);
  std::printf(
      "[ step          ] max |theta - theta*|/theta* %.3g; max equation error %.3g; %d samples with "
      "theta* within float of 1; %d zero steps where p > 1e19\n",
      max_theta_error, max_equation_error, near_one, zero_steps_on_overflow);
}

// ---------------------------------------------------------------------------------------------
// 5. A safe step never reaches a level (Monte Carlo)
// ---------------------------------------------------------------------------------------------

void check_steps_on(const char* name, const Mesh& mesh, uint32_t seed, int points) {
  SCOPED_TRACE(name);
  const GwnModel model = build_model(mesh);
  const ModelView view = model.view();
  const BoundaryRef boundary = boundary_ref(model);
  const TriangleTreeView triangles = model.triangle_view();
  RandomDouble rng(seed);
  constexpr int kSamples = 20;
  double worst_use = 0;  // the largest share of the gap to a level that a step used
  int steps = 0, crossings_at_triple = 0, triple_tries = 0;
  for (int i = 0; i < points; ++i) {
    const PointKind kind = PointKind(i % 3);
    const vec3 x = sample_point(model, boundary, kind, rng);
    const dvec3 xd(x);
    dvec3 nearest(0.0);
    if (!(boundary_distance_ref(boundary, xd, &nearest) > 0)) continue;
    // As SurfaceTracer::march does.
    const PhaseSample s = sample_phase(view, x, 2.0f, false);
    const float phase = i % 2 == 0 ? 0.5f : float(rng.uniform(0, 1));
    const LevelBracket levels = bracket_levels(s.phi, phase);
    const float gap = min_of(s.phi - levels.below, levels.above - s.phi);
    const float step = fmaxf(angle_valued_step(s.boundary_distance, s.phi, levels),
                             gradient_bound_step(s.boundary_distance, s.gradient_bound, gap));
    if (!(step > 0.0f)) continue;
    const WindingSampleExact e0 = winding_number_exact(triangles, x, true);
    // The exact w at x on φ's branch; φ's own error (test 3 (d)) counts toward the slack.
    const double lift0 = double(s.phi) + wrap_turns(e0.w - double(s.phi));
    const double slack = 1e-6 + std::fabs(lift0 - double(s.phi));
    // The directions that reach a level first: up and down the gradient, toward the nearest
    // point of ∂M (where the Biot–Savart bound grows fastest), and one at random.
    std::vector<dvec3> directions = {rng.unit(), glm::normalize(nearest - xd)};
    if (glm::length(e0.gradient) > 0) {
      directions.push_back(glm::normalize(e0.gradient));
      directions.push_back(-glm::normalize(e0.gradient));
    }
    for (const dvec3& d : directions) {
      ++steps;
      double lift = lift0, w_prev = e0.w, use = 0;
      for (int k = 1; k <= kSamples; ++k) {
        const vec3 y = to_float(xd + (double(step) * k / kSamples) * d);
        const double w = winding_number_exact(triangles, y).w;
        lift += wrap_turns(w - w_prev);  // M's ±1 jumps removed: the smooth change per sample is far below 1/2
        w_prev = w;
        EXPECT_GT(lift, double(levels.below) - slack)
            << point_string(x) << " d " << vec_string(d) << " step " << step << " at " << k << "/" << kSamples
            << " phi " << s.phi << " levels [" << levels.below << ", " << levels.above << "] R " << s.boundary_distance
            << " K " << s.gradient_bound;
        EXPECT_LT(lift, double(levels.above) + slack)
            << point_string(x) << " d " << vec_string(d) << " step " << step << " at " << k << "/" << kSamples
            << " phi " << s.phi << " levels [" << levels.below << ", " << levels.above << "] R " << s.boundary_distance
            << " K " << s.gradient_bound;
        const double toward = lift >= lift0 ? double(levels.above) - lift0 : lift0 - double(levels.below);
        if (toward > 1e-4) use = std::max(use, std::fabs(lift - lift0) / toward);
      }
      worst_use = std::max(worst_use, use);
      // The probe can see a crossing: three times the step, up the gradient, often crosses.
      if (d == directions.back() && directions.size() == 4) {
        ++triple_tries;
        double lift3 = lift0, prev3 = e0.w;
        for (int k = 1; k <= kSamples; ++k) {
          const vec3 y = to_float(xd + (3.0 * step * k / kSamples) * d);
          const double w = winding_number_exact(triangles, y).w;
          lift3 += wrap_turns(w - prev3);
          prev3 = w;
          if (lift3 <= levels.below || lift3 >= levels.above) {
            ++crossings_at_triple;
            break;
          }
        }
      }
    }
  }
  std::printf(
      "[ %-11s ] %d steps, none crossed a level; largest share of the gap used %.3f; "
      "3x the step crossed in %d of %d tries\n",
      name, steps, worst_use, crossings_at_triple, triple_tries);
  EXPECT_GT(crossings_at_triple, 0);  // the check has teeth
}

TEST(Phase, StepsNeverCrossALevel) {
  check_steps_on("bunny_holes", load_test_mesh("bunny_holes.obj"), 4501, 150);
  check_steps_on("open cube", test::make_cube(true), 4502, 600);
}

}  // namespace
}  // namespace gwnrt
