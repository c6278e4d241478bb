// trace_surface on hostile rays: exact ties and degenerate starts, non-finite, zero, tiny and huge
// directions, ray intervals, and the step and crossing caps. Every ray must end with a coherent,
// finite answer.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include <tbb/parallel_for.h>

#include "gwnrt/trace/surface_trace.h"
#include "test_util.h"
#include "trace_fixtures.h"

namespace gwnrt {
namespace {

// ---------------------------------------------------------------------------------------------
// 5. Fuzz: every ray terminates with a coherent, finite answer.
// ---------------------------------------------------------------------------------------------

// What every RayHit must satisfy, whatever the ray.
::testing::AssertionResult coherent(const RayHit& h, const Ray& r, const TraceOptions& o, size_t triangle_count,
                                    double diag) {
  auto bad = [&](const std::string& why) { return ::testing::AssertionFailure() << why << "\n" << describe(h); };
  if (h.invalid) return bad("a finite ray with a nonzero direction was rejected");
  if (h.steps > o.max_steps) return bad("ran past the step cap");
  if (h.crossings > o.max_crossings) return bad("ran past the crossing cap");
  if (h.capped && h.hit) return bad("capped traces report a miss");
  if (!h.hit) {
    if (h.kind != HitKind::kNone) return bad("a miss with a kind");
    return ::testing::AssertionSuccess();
  }
  if (!std::isfinite(h.t) || h.t < r.tnear || h.t > r.tfar) return bad("t outside [tnear, tfar]");
  const vec3 q[] = {h.position, h.normal};
  for (const vec3& v : q)
    if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z)) return bad("non-finite position or normal");
  if (std::fabs(glm::length(h.normal) - 1.0f) > 1e-4f) return bad("normal not unit");
  const dvec3 along = dvec3(r.origin) + double(h.t) * dvec3(r.direction);
  // Float round-off of o + t·d, with |o| up to a few diagonals.
  if (glm::length(dvec3(h.position) - along) > 1e-5 * (diag + glm::length(dvec3(r.origin))))
    return bad("position is not origin + t·direction");
  if (h.kind == HitKind::kSheet) {
    if (!(h.triangle < triangle_count)) return bad("sheet hit without a valid triangle");
    if (o.mode == TraceMode::kSolidAngle) return bad("sheet hit in solid-angle mode");
  } else if (h.kind == HitKind::kSmooth) {
    if (h.triangle != kEmptyLane) return bad("smooth hit naming a triangle");
  } else {
    return bad("hit without a kind");
  }
  return ::testing::AssertionSuccess();
}

// Rays with exact ties and degenerate starts: aimed at vertices and at edge midpoints, starting
// on vertices, running along boundary edges, axis-aligned through vertices, plain random ones.
std::vector<Ray> fuzz_rays(const GwnModel& model, size_t per_kind, uint32_t seed) {
  Random rng(seed);
  const Mesh& m = model.mesh();
  const Aabb box = model.bounds();
  const float diag = float(box_diagonal(box));
  const Aabb around = grown(box, 0.5f * diag);
  auto vertex = [&]() { return m.positions[size_t(rng.index(int(m.positions.size())))]; };
  auto midpoint = [&]() {
    const uvec3& t = m.triangles[size_t(rng.index(int(m.triangles.size())))];
    const int k = rng.index(3);
    return 0.5f * (m.positions[t[k]] + m.positions[t[(k + 1) % 3]]);
  };
  const std::vector<vec3>& rim = model.boundary().endpoints;
  std::vector<Ray> rays;
  auto add = [&](const vec3& o, const vec3& d) {
    if (glm::length(d) > 0.0f) rays.push_back(Ray{o, d});
  };
  for (size_t i = 0; i < per_kind; ++i) {
    add(rng.in_box(around), rng.unit() * rng.scale());
    vec3 o = rng.in_box(around);
    add(o, vertex() - o);
    o = rng.in_box(around);
    add(o, midpoint() - o);
    add(vertex(), rng.unit());
    add(midpoint(), rng.unit());
    if (!rim.empty()) {
      const size_t s = 2 * size_t(rng.index(int(rim.size() / 2)));
      add(rim[s], rim[s + 1] - rim[s]);                          // along a boundary edge, from its start
      add(rim[s] - (rim[s + 1] - rim[s]), rim[s + 1] - rim[s]);  // the same line, from before it
    }
    vec3 axis(0.0f);
    axis[rng.index(3)] = rng.index(2) ? 1.0f : -1.0f;
    add(vertex() - 2.0f * diag * axis, axis);
    add(midpoint() - 2.0f * diag * axis, axis * 1e3f);
  }
  return rays;
}

struct FuzzCase {
  const char* name;
  TraceMode mode;
};
void PrintTo(const FuzzCase& c, std::ostream* os) { *os << c.name; }

Mesh fuzz_mesh(const std::string& name) {
  if (name == "bunny") return load_test_mesh("bunny.obj");
  if (name == "nonplanar_quad") {
    Mesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0.3f}, {1, 1, 0}, {0, 1, 0.3f}};
    m.triangles = {{0, 1, 2}, {0, 2, 3}};
    return m;
  }
  return open_mesh(name);
}

// Distance between segments [p0, p1] and [q0, q1] (double): the unclamped closest pair, then
// each parameter clamped to [0, 1] and the other re-solved for it.
double segment_distance(const dvec3& p0, const dvec3& p1, const dvec3& q0, const dvec3& q1) {
  const dvec3 u = p1 - p0, v = q1 - q0, r = p0 - q0;
  const double a = glm::dot(u, u), b = glm::dot(u, v), c = glm::dot(v, v), d = glm::dot(u, r), e = glm::dot(v, r);
  const double den = a * c - b * b;
  double s = den > 1e-300 ? std::clamp((b * e - c * d) / den, 0.0, 1.0) : 0.0;
  double t = c > 0 ? std::clamp((b * s + e) / c, 0.0, 1.0) : 0.0;
  s = a > 0 ? std::clamp((b * t - d) / a, 0.0, 1.0) : 0.0;
  return glm::length(p0 + s * u - (q0 + t * v));
}

// Closest approach of the ray (within `reach` of its origin) to ∂M.
double distance_to_boundary(const GwnModel& model, const Ray& r, double reach) {
  const dvec3 o(r.origin), d = glm::normalize(dvec3(r.direction));
  const std::vector<vec3>& e = model.boundary().endpoints;
  double best = kInf;
  for (size_t k = 0; k + 1 < e.size(); k += 2)
    best = std::min(best, segment_distance(o, o + reach * d, dvec3(e[k]), dvec3(e[k + 1])));
  return best;
}

class TraceFuzz : public ::testing::TestWithParam<FuzzCase> {};

TEST_P(TraceFuzz, EveryRayTerminatesCoherently) {
  const GwnModel model = build_model(fuzz_mesh(GetParam().name));
  const ModelView view = model.view();
  const double diag = box_diagonal(model.bounds());
  const std::vector<Ray> rays = fuzz_rays(model, 60, 501);
  TraceOptions options;
  options.mode = GetParam().mode;
  std::vector<RayHit> results(rays.size());
  tbb::parallel_for(size_t(0), rays.size(), [&](size_t i) { results[i] = trace_surface(view, rays[i], options); });
  // Rays through or along ∂M (w is undefined there and every value of w is near): their
  // answer is ill-defined, only its coherence is checked. ∂M lies in the closure of S, so a hit
  // anywhere there, or running out of steps while following it (capped), are both honest.
  std::vector<bool> on_rim(rays.size());
  size_t rim_count = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    const double reach = glm::length(dvec3(rays[i].origin) - dvec3(model.bounds().centre())) + diag;
    on_rim[i] = distance_to_boundary(model, rays[i], reach) < 1e-4 * diag;
    rim_count += on_rim[i];
  }
  size_t hits = 0, capped = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    ASSERT_TRUE(coherent(results[i], rays[i], options, model.mesh().triangles.size(), diag)) << describe(rays[i]);
    hits += results[i].hit;
    if (on_rim[i]) continue;
    capped += results[i].capped;
    EXPECT_FALSE(results[i].capped) << describe(rays[i]);
  }
  // t is in units of the ray's own direction. Scaling the direction by 2^-40 or 2^40 is exact
  // in float and so is its normalisation: the answer must be bit for bit the same, t scaled by
  // the inverse, for every ray, ties included.
  for (size_t i = 0; i < rays.size(); ++i) {
    for (const float scale : {std::ldexp(1.0f, -40), std::ldexp(1.0f, 40)}) {
      Ray r = rays[i];
      r.direction *= scale;
      const RayHit h = trace_surface(view, r, options);
      const RayHit& g = results[i];
      const bool same = h.hit == g.hit && h.kind == g.kind && h.capped == g.capped && h.triangle == g.triangle &&
                        h.steps == g.steps && h.crossings == g.crossings && h.position == g.position &&
                        h.normal == g.normal && (g.hit ? h.t * scale == g.t : h.t == g.t);
      ASSERT_TRUE(same) << "direction scaled by " << scale << "\n"
                        << describe(rays[i]) << "\n"
                        << describe(g) << "\nscaled: " << describe(h);
    }
  }
  // Any other scale (here 1e-6 and 1e6) rounds the direction by an ulp or so: on rays without
  // ties (random origin, aimed into the box) the hit moves by float round-off only (1e-4·diag
  // is the smooth-hit tolerance of a 1/10 cosine), and at most 1% of them may flip by grazing S.
  Random rng(503);
  size_t flips = 0, generic = 0;
  const Aabb box = model.bounds();
  for (int i = 0; i < 300; ++i) {
    Ray r;
    r.origin = rng.in_box(grown(box, 0.5f * float(diag)));
    r.direction = rng.in_box(box) - r.origin;
    if (!(glm::length(r.direction) > 0.0f)) continue;
    ++generic;
    const RayHit g = trace_surface(view, r, options);
    for (const float scale : {1e-6f, 1e6f}) {
      Ray q = r;
      q.direction *= scale;
      const RayHit h = trace_surface(view, q, options);
      ASSERT_TRUE(coherent(h, q, options, model.mesh().triangles.size(), diag)) << describe(q);
      const double s0 = double(g.t) * glm::length(dvec3(r.direction));
      const double s1 = double(h.t) * glm::length(dvec3(q.direction));
      if (h.hit != g.hit || (h.hit && std::fabs(s0 - s1) > 1e-4 * diag)) {
        ++flips;
        std::printf("direction scaled by %g changes the answer: %s\n%s\nscaled: %s\n", scale, describe(r).c_str(),
                    describe(g).c_str(), describe(h).c_str());
      }
    }
  }
  EXPECT_LE(flips, generic / 50);
  std::printf("[ %s ] %zu fuzz rays (%zu through or along the rim): %zu hits, %zu capped; %zu of %zu flips\n",
              GetParam().name, rays.size(), rim_count, hits, capped, flips, 2 * generic);
  EXPECT_GT(hits, rays.size() / 10);
}

INSTANTIATE_TEST_SUITE_P(Meshes, TraceFuzz,
                         ::testing::Values(FuzzCase{"bunny", TraceMode::kWindingNumber},
                                           FuzzCase{"bunny_holes", TraceMode::kWindingNumber},
                                           FuzzCase{"open_cube", TraceMode::kWindingNumber},
                                           FuzzCase{"hexagon_fan", TraceMode::kWindingNumber},
                                           FuzzCase{"nonplanar_quad", TraceMode::kSolidAngle}),
                         [](const auto& info) { return std::string(info.param.name); });

TEST(TraceFuzz, NonFiniteOrZeroRaysAreInvalid) {
  const GwnModel model = build_model(test::make_cube(true));
  const ModelView view = model.view();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const Ray good{vec3(0.1f, 0.2f, -3.0f), vec3(0.0f, 0.0f, 1.0f)};
  ASSERT_TRUE(trace_surface(view, good, TraceOptions{}).hit);
  std::vector<Ray> bad;
  for (int k = 0; k < 3; ++k) {
    for (const float v : {nan, kInfinity, -kInfinity}) {
      Ray r = good;
      r.origin[k] = v;
      bad.push_back(r);
      r = good;
      r.direction[k] = v;
      bad.push_back(r);
    }
  }
  Ray zero = good;
  zero.direction = vec3(0.0f);
  bad.push_back(zero);
  zero.direction = vec3(-0.0f, 0.0f, -0.0f);
  bad.push_back(zero);
  // Denormal directions (1e-44 reported a hit at t = inf) are too short to
  // normalise.
  for (const float tiny : {1e-44f, 1e-40f, 5e-39f}) {
    zero.direction = vec3(tiny, 0.0f, 0.0f);
    bad.push_back(zero);
    zero.direction = vec3(0.0f, -tiny, tiny);
    bad.push_back(zero);
  }
  Ray r = good;
  r.tnear = nan;
  bad.push_back(r);
  r = good;
  r.tfar = nan;
  bad.push_back(r);
  for (const TraceMode mode : {TraceMode::kWindingNumber, TraceMode::kSolidAngle}) {
    for (const bool exact : {false, true}) {
      TraceOptions o;
      o.mode = mode;
      o.exact = exact;
      for (const Ray& b : bad) {
        const RayHit h = trace_surface(view, b, o);
        EXPECT_TRUE(h.invalid) << describe(b);
        EXPECT_FALSE(h.hit) << describe(b);
        EXPECT_EQ(h.kind, HitKind::kNone);
        EXPECT_EQ(h.steps, 0u);
        EXPECT_EQ(h.crossings, 0u);
      }
    }
  }
  // The batch driver reports them per ray, not as an error of the batch.
  std::vector<Ray> batch = bad;
  batch.push_back(good);
  std::vector<RayHit> hits(batch.size());
  ASSERT_TRUE(trace_rays(model, batch, TraceOptions{}, hits).ok());
  for (size_t i = 0; i + 1 < batch.size(); ++i) EXPECT_TRUE(hits[i].invalid);
  EXPECT_TRUE(hits.back().hit);
  EXPECT_FALSE(hits.back().invalid);
}

// The contract names only non-finite numbers and directions shorter than the smallest normal
// float as invalid: any other finite direction is a ray, and t comes back in its units. |d| = 1e-25 and 1e25 keep
// t (about 2e25 and 2e-25 here) representable in float.
TEST(TraceFuzz, TinyAndHugeFiniteDirectionsAreTraced) {
  const GwnModel model = build_model(test::make_cube(true));
  const ModelView view = model.view();
  for (const float scale : {1e-25f, 1e-20f, 1e20f, 1e25f}) {
    Ray r{vec3(0.1f, 0.2f, -3.0f), vec3(0.1f, 0.05f, 1.0f) * scale};
    const RayHit h = trace_surface(view, r, TraceOptions{});
    SCOPED_TRACE(describe(r));
    EXPECT_FALSE(h.invalid);
    ASSERT_TRUE(h.hit);
    // The bottom face z = -1 is two units of z ahead.
    EXPECT_NEAR(double(h.t) * double(scale), 2.0, 1e-5);
  }
}

TEST(TraceFuzz, RayIntervalIsRespected) {
  const GwnModel model = build_model(test::make_cube(true));
  const ModelView view = model.view();
  Ray r{vec3(0.1f, 0.2f, -3.0f), vec3(0.0f, 0.0f, 2.0f)};  // bottom face at t = 1, open top at t = 2
  RayHit h = trace_surface(view, r, TraceOptions{});
  ASSERT_TRUE(h.hit);
  EXPECT_EQ(h.kind, HitKind::kSheet);
  EXPECT_NEAR(h.t, 1.0f, 1e-6f);
  r.tfar = 0.9f;  // ends before the cube
  EXPECT_FALSE(trace_surface(view, r, TraceOptions{}).hit);
  r.tfar = kInfinity;
  r.tnear = 1.25f;  // starts inside the cube (w ≈ 5/6): leaves through the smooth cap over the hole
  h = trace_surface(view, r, TraceOptions{});
  ASSERT_TRUE(h.hit);
  EXPECT_EQ(h.kind, HitKind::kSmooth);
  EXPECT_NEAR(h.t, 2.0f, 1e-3f);
  EXPECT_GT(glm::dot(h.normal, r.direction), 0.0f);  // leaving {w > 1/2}
  r.tnear = 1.0f;
  r.tfar = 0.5f;  // empty interval
  EXPECT_FALSE(trace_surface(view, r, TraceOptions{}).hit);
}

TEST(TraceFuzz, StepAndCrossingCapsEndRaysAsCapped) {
  const GwnModel model = build_model(load_test_mesh("bunny_holes.obj"));
  const ModelView view = model.view();
  const double diag = box_diagonal(model.bounds());
  const std::vector<Ray> rays = open_rays(model, 600, 502);
  TraceOptions steps3;
  steps3.max_steps = 3;
  TraceOptions crossings1;
  crossings1.max_crossings = 1;
  size_t capped_steps = 0, capped_crossings = 0, uncapped_same = 0, uncapped = 0;
  for (const Ray& r : rays) {
    const RayHit full = trace_surface(view, r, TraceOptions{});
    const RayHit a = trace_surface(view, r, steps3);
    ASSERT_TRUE(coherent(a, r, steps3, model.mesh().triangles.size(), diag)) << describe(r);
    EXPECT_LE(a.steps, 3u);
    capped_steps += a.capped;
    // A trace that needed no more than the cap is the very same trace.
    if (!a.capped) {
      ++uncapped;
      uncapped_same += a.hit == full.hit && a.t == full.t && a.kind == full.kind;
    }
    const RayHit b = trace_surface(view, r, crossings1);
    ASSERT_TRUE(coherent(b, r, crossings1, model.mesh().triangles.size(), diag)) << describe(r);
    EXPECT_LE(b.crossings, 1u);
    capped_crossings += b.capped;
  }
  std::printf("[ caps ] %zu rays: %zu capped at 3 steps, %zu capped at 1 crossing\n", rays.size(), capped_steps,
              capped_crossings);
  EXPECT_GT(capped_steps, rays.size() / 10);
  EXPECT_EQ(uncapped_same, uncapped);
}

}  // namespace
}  // namespace gwnrt
