// trace_surface against references with known answers: the dense-sampling reference of
// first_crossing.h itself on closed forms, Embree's triangle hits on watertight meshes, a closed
// mesh's one walk over its crossings; and the accept functor that filters hits, against every
// crossing of the line.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include <tbb/parallel_for.h>

#include "gwnrt/field/winding_number.h"
#include "gwnrt/trace/surface_trace.h"
#include "reference/first_crossing.h"
#include "test_util.h"
#include "trace_fixtures.h"

#ifdef GWNRT_HAVE_EMBREE
#include "render/embree_triangles.h"
#endif

namespace gwnrt {
namespace {

// ---------------------------------------------------------------------------------------------
// The reference itself (test_util.h), on cases with known answers.
// ---------------------------------------------------------------------------------------------

TEST(TraceReference, AgreesWithTheLibraryAndClosedForms) {
  // w and ∇w against the library's double brute force and against central differences.
  const Mesh fan = test::make_hexagon_fan();
  const GwnModel model = build_model(fan);
  const ReferenceMesh ref = reference::reference_mesh(fan);
  Random rng(91);
  for (int i = 0; i < 200; ++i) {
    const vec3 x = rng.in_box(Aabb{vec3(-1.5f), vec3(1.5f)});
    const WindingSampleExact e = winding_number_exact(model.triangle_view(), x, true);
    const double w = reference::reference_w(ref, dvec3(x));
    const dvec3 g = reference::reference_gradient(ref, dvec3(x));
    EXPECT_NEAR(w, e.w, 1e-12);  // both double sums of the same terms
    EXPECT_LE(glm::length(g - e.gradient), 1e-9 * (1.0 + glm::length(g)));
    // The steps spelled out: GCC 12.2 at -O3 (its -fipa-cp-clone) compiled `dvec3 step(0.0);
    // step[k] = h;` in this loop into a step along z for k = 0 and along x for k = 2 (a cmovne of
    // the wrong sense, read in the object code) once reference_w was out of line.
    const double h = 1e-6;
    const dvec3 steps[3] = {{h, 0.0, 0.0}, {0.0, h, 0.0}, {0.0, 0.0, h}};
    double fd_along[3];
    for (int k = 0; k < 3; ++k)
      fd_along[k] =
          (reference::reference_w(ref, dvec3(x) + steps[k]) - reference::reference_w(ref, dvec3(x) - steps[k])) /
          (2 * h);
    const dvec3 fd(fd_along[0], fd_along[1], fd_along[2]);
    // O(h²) truncation and 1e-16/h cancellation, away from the mesh (points within 1e-3 of it
    // are rare and may straddle it: skipped).
    if (std::fabs(x.z) > 1e-3f) {
      EXPECT_LE(glm::length(fd - g), 1e-6 * (1.0 + glm::length(g)));
    }
  }
  // First crossing of a closed unit icosphere from outside: the sheet at the analytic distance
  // (the facets lie within 1 - cos(half the edge angle) of the sphere: 1% at 3 subdivisions).
  const Mesh sphere = test::make_sphere(3);
  const ReferenceMesh sref = reference::reference_mesh(sphere);
  for (int i = 0; i < 20; ++i) {
    const vec3 d = rng.unit();
    const Ray r{-3.0f * d, d * 2.0f};
    const ReferenceCrossing c = reference::reference_first_crossing(sref, r, 0.5, grown(sref.box, 1.0f), 400);
    ASSERT_TRUE(c.hit);
    EXPECT_TRUE(c.sheet);
    EXPECT_NEAR(c.t * 2.0, 2.0, 0.02);
    // From inside, the way out.
    const Ray in{vec3(0.0f), d};
    const ReferenceCrossing o = reference::reference_first_crossing(sref, in, 0.5, grown(sref.box, 1.0f), 400);
    ASSERT_TRUE(o.hit);
    EXPECT_NEAR(o.t, 1.0, 0.02);
    // Solid-angle mode: a closed mesh has no smooth level set.
    EXPECT_FALSE(
        reference::reference_first_crossing(sref, r, 0.5, grown(sref.box, 1.0f), 400, ReferenceMode::kSolidAngle).hit);
  }
  // A flat square's level 1/2 in solid-angle mode is the square itself (w → ∓1/2 on either
  // side, |w| < 1/2 elsewhere): reached smoothly from both sides.
  Mesh square;
  square.positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
  square.triangles = {{0, 1, 2}, {0, 2, 3}};
  const ReferenceMesh qref = reference::reference_mesh(square);
  for (const float z : {-2.0f, 2.0f}) {
    const Ray r{vec3(0.3f, -0.2f, z), vec3(0.1f, 0.05f, -z)};
    // An odd sample count: no sample falls exactly on the square (w is undefined on M).
    const ReferenceCrossing c =
        reference::reference_first_crossing(qref, r, 0.5, grown(qref.box, 1.0f), 399, ReferenceMode::kSolidAngle);
    ASSERT_TRUE(c.hit);
    EXPECT_NEAR(c.t, 1.0, 1e-9);
    EXPECT_FALSE(c.sheet);
  }
}

// ---------------------------------------------------------------------------------------------
// 1. Watertight meshes against Embree.
// ---------------------------------------------------------------------------------------------

#ifdef GWNRT_HAVE_EMBREE

// The outward unit normal of triangle t by its winding.
vec3 triangle_normal(const Mesh& m, uint32_t t) {
  const vec3 a = m.positions[m.triangles[t][0]], b = m.positions[m.triangles[t][1]], c = m.positions[m.triangles[t][2]];
  return glm::normalize(glm::cross(b - a, c - a));
}

struct EmbreeHit {
  bool hit = false;
  float t = kInfinity;
  uint32_t prim = kEmptyLane;
  float u = 0, v = 0;
};

// Embree's own ray–triangle intersection over the same float triangles, in robust (watertight)
// mode and without back-face culling.
class EmbreeScene {
 public:
  explicit EmbreeScene(const Mesh& m) : scene_(m, 1, RTC_SCENE_FLAG_ROBUST, RTC_BUILD_QUALITY_HIGH) {
    EXPECT_TRUE(scene_.status().ok()) << scene_.status().message();
  }

  EmbreeHit intersect(const Ray& r) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    const RTCRayHit rh = scene_.intersect(r, context);
    EmbreeHit h;
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return h;
    h.hit = true;
    h.t = rh.ray.tfar;
    h.prim = rh.hit.primID;
    h.u = rh.hit.u;
    h.v = rh.hit.v;
    return h;
  }

 private:
  render::TriangleScene scene_;
};

// Rays for a closed mesh: origins outside aimed at the box, origins outside in any direction, and
// origins inside (w > 1/2 by the reference) in any direction; random direction lengths.
std::vector<Ray> watertight_rays(const Mesh& mesh, const ReferenceMesh& ref, size_t count, uint32_t seed,
                                 std::vector<bool>& inside) {
  Random rng(seed);
  const Aabb box = test::mesh_bounds(mesh);
  const float diag = float(box_diagonal(box));
  const Aabb far = grown(box, 0.75f * diag);
  std::vector<Ray> rays;
  inside.clear();
  while (rays.size() < count) {
    Ray r;
    const int kind = int(rays.size() % 4);  // 0, 1: aimed; 2: any direction; 3: inside
    r.origin = rng.in_box(far);
    const double w = reference::reference_w(ref, dvec3(r.origin));
    if (kind < 3 && w > 0.25) continue;  // origins outside the solid
    if (kind == 3) {
      r.origin = rng.in_box(box);
      if (reference::reference_w(ref, dvec3(r.origin)) < 0.75) continue;
    }
    const vec3 to = kind < 2 ? rng.in_box(box) - r.origin : rng.unit();
    r.direction = glm::normalize(to) * rng.scale();
    rays.push_back(r);
    inside.push_back(kind == 3);
  }
  return rays;
}

// Embree's barycentrics (u, v, 1-u-v) of its hit all above this: the ray pierces the interior of
// that triangle, far from its edges compared with float round-off (~1e-7), so no other triangle
// can be hit at the same t and the tracer must name the same one.
constexpr float kUnambiguousBarycentric = 1e-3f;

void check_against_embree(const Mesh& mesh, size_t ray_count, uint32_t seed) {
  const GwnModel model = build_model(mesh);
  ASSERT_EQ(model.boundary().segment_count(), 0u) << "the mesh must be closed";
  const ModelView view = model.view();
  const ReferenceMesh ref = reference::reference_mesh(mesh);
  const EmbreeScene embree(mesh);
  const double diag = box_diagonal(model.bounds());
  std::vector<bool> inside;
  const std::vector<Ray> rays = watertight_rays(mesh, ref, ray_count, seed, inside);
  TraceOptions options;
  size_t hits = 0, entering = 0, leaving = 0, same_triangle = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    const Ray& r = rays[i];
    const RayHit h = trace_surface(view, r, options);
    const EmbreeHit e = embree.intersect(r);
    SCOPED_TRACE(describe(r) + "\n" + describe(h));
    ASSERT_FALSE(h.invalid);
    ASSERT_FALSE(h.capped);
    // A closed mesh has no ∂M, hence no cone and no Harnack steps: one walk over crossings.
    ASSERT_EQ(h.steps, 0u);
    ASSERT_EQ(h.hit, e.hit) << "embree t " << e.t;
    if (!h.hit) {
      EXPECT_EQ(h.kind, HitKind::kNone);
      continue;
    }
    ++hits;
    EXPECT_EQ(h.kind, HitKind::kSheet);
    EXPECT_GE(h.crossings, 1u);
    // Both intersect the same float ray with the same float triangles; each t carries a few
    // float ulps of the coordinates (|x| <= ~2 diagonals here, so ~1e-7 of the diagonal each).
    // 1e-5 of the diagonal leaves two orders of magnitude of slack and is still far below the
    // spacing of distinct surfaces along a ray (bunny: mean edge 2.4% of the diagonal).
    const double len = glm::length(dvec3(r.direction));
    ASSERT_LE(std::fabs(double(h.t) - double(e.t)) * len, 1e-5 * diag) << "embree t " << e.t;
    EXPECT_LE(glm::length(dvec3(h.position) - (dvec3(r.origin) + double(h.t) * dvec3(r.direction))), 1e-5 * diag);
    // The named triangle carries the hit point (float round-off of the same size as t's).
    ASSERT_LT(h.triangle, mesh.triangles.size());
    EXPECT_LE(distance_to_triangle(mesh, h.triangle, dvec3(h.position)), 1e-5 * diag);
    // Outward from {w > 1/2} (the solid) toward {w < 1/2}: the triangle's outward normal. It
    // faces against the ray entering from outside and along it leaving from inside.
    EXPECT_NEAR(glm::length(h.normal), 1.0f, 1e-5f);
    EXPECT_GE(glm::dot(h.normal, triangle_normal(mesh, h.triangle)), 1.0f - 1e-5f);
    const float facing = glm::dot(h.normal, r.direction);
    if (inside[i]) {
      EXPECT_GT(facing, 0.0f) << "leaving the solid";
      ++leaving;
    } else {
      EXPECT_LT(facing, 0.0f) << "entering the solid";
      ++entering;
    }
    const float bw = 1.0f - e.u - e.v;
    if (e.u > kUnambiguousBarycentric && e.v > kUnambiguousBarycentric && bw > kUnambiguousBarycentric) {
      EXPECT_EQ(h.triangle, e.prim);
      ++same_triangle;
    }
  }
  // The ray sets are built to hit often, from both sides.
  EXPECT_GT(hits, rays.size() / 2);
  EXPECT_GT(entering, rays.size() / 4);
  EXPECT_GT(leaving, rays.size() / 8);
  EXPECT_GT(same_triangle, hits * 9 / 10);
}

TEST(TraceWatertight, BunnyMatchesEmbree) { check_against_embree(load_test_mesh("bunny.obj"), 3000, 101); }

TEST(TraceWatertight, IcosphereMatchesEmbree) { check_against_embree(test::make_sphere(3), 3000, 102); }

TEST(TraceWatertight, CubeMatchesEmbree) { check_against_embree(test::make_cube(), 3000, 103); }

#endif  // GWNRT_HAVE_EMBREE

// ---------------------------------------------------------------------------------------------
// 7. A closed mesh costs one walk over its crossings: no Harnack steps, whatever the options.
// ---------------------------------------------------------------------------------------------

TEST(TraceWatertight, ClosedMeshTakesNoHarnackSteps) {
  for (const char* name : {"bunny", "sphere", "cube"}) {
    SCOPED_TRACE(name);
    const Mesh mesh = std::string(name) == "bunny"    ? load_test_mesh("bunny.obj")
                      : std::string(name) == "sphere" ? test::make_sphere(2)
                                                      : test::make_cube();
    const GwnModel model = build_model(mesh);
    ASSERT_EQ(model.boundary().segment_count(), 0u);
    EXPECT_EQ(model.view().cone.triangle_count, 0u);
    const ModelView view = model.view();
    const Aabb box = model.bounds();
    const float diag = float(box_diagonal(box));
    Random rng(7);
    TraceOptions plain, exact, low, high, solid;
    exact.exact = true;
    exact.max_steps = 1;  // any Harnack step would end the trace as capped
    low.level = 0.3f;
    high.level = 0.7f;
    solid.mode = TraceMode::kSolidAngle;
    size_t hits = 0;
    for (int i = 0; i < 1000; ++i) {
      Ray r;
      r.origin = rng.in_box(grown(box, 0.5f * diag));
      r.direction = i % 2 ? rng.in_box(box) - r.origin : rng.unit();
      const RayHit h = trace_surface(view, r, plain);
      SCOPED_TRACE(describe(r));
      EXPECT_EQ(h.steps, 0u);
      hits += h.hit;
      // Every level strictly between 0 and 1 has the same S on a closed mesh (w is 0 or 1).
      for (const TraceOptions* o : {&exact, &low, &high}) {
        const RayHit g = trace_surface(view, r, *o);
        EXPECT_EQ(g.steps, 0u);
        EXPECT_FALSE(g.capped);
        EXPECT_EQ(g.hit, h.hit);
        EXPECT_EQ(g.t, h.t);
        EXPECT_EQ(g.triangle, h.triangle);
      }
      // Solid-angle mode: w mod 1 is 0 everywhere off the mesh, so no level 1/2 exists.
      const RayHit s = trace_surface(view, r, solid);
      EXPECT_FALSE(s.hit);
      EXPECT_EQ(s.steps, 0u);
    }
    EXPECT_GT(hits, 300u);
  }
}

// ---------------------------------------------------------------------------------------------
// 8. Filters: trace_surface with an accept functor is offered every hit in increasing t and goes
//    on past those it turns down (what the Embree plugin's intersection filters rest on).
// ---------------------------------------------------------------------------------------------

// Every crossing of the line with a triangle, by Möller–Trumbore in double, sorted by t; false
// when one lies within `margin` (barycentric) of a triangle's edge, where float and double may
// count it differently.
bool all_crossings(const Mesh& m, const Ray& r, double margin, std::vector<double>& ts) {
  ts.clear();
  const dvec3 o(r.origin), d(r.direction);
  for (const uvec3& tri : m.triangles) {
    const dvec3 a(m.positions[tri[0]]), b(m.positions[tri[1]]), c(m.positions[tri[2]]);
    const dvec3 e1 = b - a, e2 = c - a, p = glm::cross(d, e2);
    const double det = glm::dot(e1, p);
    if (det == 0) continue;
    const dvec3 s = o - a;
    const double u = glm::dot(s, p) / det;
    const dvec3 q = glm::cross(s, e1);
    const double v = glm::dot(d, q) / det, t = glm::dot(e2, q) / det;
    if (u < -margin || v < -margin || u + v > 1 + margin) continue;
    if (u < margin || v < margin || u + v > 1 - margin) return false;
    if (t >= double(r.tnear) && t <= double(r.tfar)) ts.push_back(t);
  }
  std::sort(ts.begin(), ts.end());
  return true;
}

TEST(TraceFilter, RejectingEveryHitVisitsEveryCrossingOfAClosedMesh) {
  const Mesh mesh = load_test_mesh("bunny.obj");
  const GwnModel model = build_model(mesh);
  const ModelView view = model.view();
  const Aabb box = model.bounds();
  const double diag = box_diagonal(box);
  Random rng(301);
  size_t rays = 0, multi = 0;
  for (int i = 0; i < 600; ++i) {
    Ray r;
    r.origin = rng.in_box(grown(box, 0.3f * float(diag)));
    r.direction = (rng.in_box(box) - r.origin) * rng.scale();
    std::vector<double> expected;
    if (!all_crossings(mesh, r, 1e-6, expected)) continue;
    std::vector<RayHit> offered;
    const RayHit h = trace_surface(view, r, TraceOptions{}, [&](const RayHit& c) {
      offered.push_back(c);
      return false;
    });
    ++rays;
    multi += expected.size() >= 2;
    const bool inside = winding_number_exact(model.triangle_view(), r.origin).w > 0.5;
    EXPECT_FALSE(h.hit);  // none accepted: a miss
    ASSERT_EQ(offered.size(), expected.size()) << describe(r);
    const double len = glm::length(dvec3(r.direction));
    for (size_t k = 0; k < offered.size(); ++k) {
      // Same tolerance as against Embree above: float round-off of one crossing.
      EXPECT_LE(std::fabs(double(offered[k].t) - expected[k]) * len, 1e-5 * diag) << describe(r) << " hit " << k;
      EXPECT_EQ(offered[k].kind, HitKind::kSheet);
      // In and out of the solid in turn: the outward normal faces against the ray entering,
      // along it leaving.
      EXPECT_EQ(glm::dot(offered[k].normal, r.direction) < 0.0f, (k % 2 == 0) != inside) << describe(r) << " hit " << k;
    }
    // Accepting the k-th offer reports exactly it.
    for (size_t k = 0; k < offered.size(); ++k) {
      size_t seen = 0;
      const RayHit hk = trace_surface(view, r, TraceOptions{}, [&](const RayHit&) { return seen++ == k; });
      ASSERT_TRUE(hk.hit);
      EXPECT_EQ(hk.t, offered[k].t);
      EXPECT_EQ(hk.triangle, offered[k].triangle);
    }
  }
  EXPECT_GT(rays, 500u);
  EXPECT_GT(multi, rays / 3);
}

TEST(TraceFilter, RejectingTheFirstHitReportsTheSecondOnAnOpenMesh) {
  const GwnModel model = build_model(load_test_mesh("bunny_holes.obj"));
  const ModelView view = model.view();
  const ReferenceMesh ref = reference::reference_mesh(model.mesh());
  const Aabb box = reference_box(model);
  const double diag = box_diagonal(model.bounds());
  const std::vector<Ray> rays = open_rays(model, 90, 302);
  const TraceOptions options;
  const double eps = double(options.epsilon) * diag;
  // The reference's first two crossings; the second is the first of the ray resampled past the
  // first (the dense sums in parallel: they are the slow part).
  std::vector<ReferenceCrossing> firsts(rays.size()), seconds(rays.size());
  tbb::parallel_for(size_t(0), rays.size(), [&](size_t i) {
    const reference::ReferenceProfile profile = reference::reference_profile(ref, rays[i], box, 1500);
    firsts[i] = reference::reference_crossing(ref, profile, 0.5);
    if (!firsts[i].hit) return;
    const double past = firsts[i].s + 1e-4 * diag;
    seconds[i] = reference::reference_crossing(
        ref, reference::reference_profile_between(ref, rays[i], past, profile.s.back(), 1500), 0.5);
  });
  size_t compared = 0, smooth_first = 0, agree = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    const Ray& r = rays[i];
    const ReferenceCrossing &first = firsts[i], &second = seconds[i];
    if (!first.hit || (!first.sheet && first.rate < 0.05)) continue;  // no hit, or a graze
    if (second.hit && !second.sheet && second.rate < 0.05) continue;
    bool first_offer = true;
    const RayHit h = trace_surface(view, r, options, [&](const RayHit&) { return !std::exchange(first_offer, false); });
    ++compared;
    smooth_first += !first.sheet;
    const double len = glm::length(dvec3(r.direction));
    // Sheets to float round-off; smooth pieces to where the stopping test may end, as in §2.
    auto tolerance = [&](const ReferenceCrossing& c) {
      return c.sheet ? 1e-5 * diag
                     : 2.0 * (kMultipoleTolerance.delta_w + eps * glm::length(c.gradient)) / c.rate + 1e-5 * diag;
    };
    EXPECT_EQ(h.hit, second.hit) << describe(r) << "\n" << describe(h);
    if (h.hit && second.hit) {
      EXPECT_LE(std::fabs(double(h.t) * len - second.s), tolerance(second)) << describe(r) << "\n" << describe(h);
      EXPECT_EQ(h.kind == HitKind::kSheet, second.sheet) << describe(r);
      agree += std::fabs(double(h.t) * len - second.s) <= tolerance(second);
    } else {
      agree += h.hit == second.hit;
    }
  }
  std::printf("[ bunny_holes ] %zu rays compared (%zu with a smooth first hit), %zu agree\n", compared, smooth_first,
              agree);
  EXPECT_GT(compared, rays.size() / 3);
  EXPECT_GT(smooth_first, 5u);
}

}  // namespace
}  // namespace gwnrt
