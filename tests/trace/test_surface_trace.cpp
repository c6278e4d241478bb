// trace_surface against independent references: Embree's triangle hits on watertight meshes,
// and the dense-sampling reference of first_crossing.h (exact w in double, bisection) on meshes with
// holes, in solid-angle mode and at levels other than 1/2; plus fuzzing of the tracer's input.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <tbb/parallel_for.h>

#include "gwnrt/field/winding_number.h"
#include "gwnrt/trace/surface_trace.h"
#include "reference/first_crossing.h"
#include "test_util.h"

#ifdef GWNRT_HAVE_EMBREE
#include "render/embree_triangles.h"
#endif

namespace gwnrt {
namespace {

using reference::ReferenceCrossing;
using reference::ReferenceMesh;
using reference::ReferenceMode;
using test::build_model;
using test::load_test_mesh;

constexpr double kInf = std::numeric_limits<double>::infinity();

double box_diagonal(const Aabb& b) { return glm::length(dvec3(b.hi) - dvec3(b.lo)); }

Aabb grown(const Aabb& b, float by) { return Aabb{b.lo - vec3(by), b.hi + vec3(by)}; }

std::string describe(const Ray& r) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "ray origin (%.9g, %.9g, %.9g) direction (%.9g, %.9g, %.9g)", r.origin.x, r.origin.y,
                r.origin.z, r.direction.x, r.direction.y, r.direction.z);
  return buf;
}

std::string describe(const RayHit& h) {
  std::ostringstream s;
  s << "tracer: hit " << h.hit << " kind " << int(h.kind) << " t " << h.t << " capped " << h.capped << " invalid "
    << h.invalid << " steps " << h.steps << " crossings " << h.crossings << " triangle " << int64_t(h.triangle);
  return s.str();
}

std::string describe(const ReferenceCrossing& c) {
  std::ostringstream s;
  s << "reference: hit " << c.hit << " t " << c.t << " sheet " << c.sheet << " rate " << c.rate;
  return s.str();
}

using test::Random;

double distance_to_triangle(const Mesh& m, uint32_t t, const dvec3& x) {
  const dvec3 a(m.positions[m.triangles[t][0]]), b(m.positions[m.triangles[t][1]]), c(m.positions[m.triangles[t][2]]);
  return glm::length(closest_point_on_triangle(a, b, c, x).point - x);
}

struct OpenCase {
  const char* name;
  size_t rays;
};
void PrintTo(const OpenCase& c, std::ostream* os) { *os << c.name << ", " << c.rays << " rays"; }

Mesh open_mesh(const std::string& name) {
  if (name == "bunny_holes") return load_test_mesh("bunny_holes.obj");
  if (name == "open_cube") return test::make_cube(true);
  return test::make_hexagon_fan();
}

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
// The dense-sampling comparison shared by tests 2-4.
// ---------------------------------------------------------------------------------------------

// What the tracer may legitimately get wrong, in units of w: `delta_w` is the error of its
// evaluation of φ; it stops where |φ - level| <= epsilon·diag·|∇w|.
struct Tolerance {
  double delta_w;
  double normal_angle;  // radians, at smooth hits
};

// Exact evaluation: φ is the double sum over the cone rounded to float (|w_C| is a few units at
// most here, so ~1e-7 absolute); 1e-6 leaves a factor of ten.
constexpr Tolerance kExactTolerance{1e-6, 1e-3};
// Multipole evaluation at beta = 2, order 2, on the cone: test MultipoleErrorOnTheLevelSetIsBounded
// measures the error of φ at reference crossings of rays like the ones used here (below 1e-5 on
// these meshes: the cones are small, so most of φ is summed exactly) and asserts it stays below
// δ = 1e-4; the level set then moves by up to δ/|∇w| along its normal, δ/|dw/ds| along the ray,
// which is what the comparison allows. For the same reason the gradient, hence the normal,
// should carry little more than float round-off; the same test asserts its relative error at
// the level set stays below 1e-3, which bounds the angle of the normal.
constexpr Tolerance kMultipoleTolerance{1e-4, 1e-3};

struct Comparison {
  size_t rays = 0, both_miss = 0, agree = 0, agree_smooth = 0, agree_sheet = 0;
  size_t refined = 0;   // the reference's sampling had stepped over a thin crossing pair
  size_t grazing = 0;   // tracer stopped at a near-tangent approach within its stopping tolerance
  size_t unstable = 0;  // reference crossing vanishes or jumps under a level change of its tolerance
  size_t capped = 0;    // step cap reached on a grazing ray
  size_t failures = 0;
  double max_normal_angle = 0;
  std::string report() const {
    std::ostringstream s;
    s << rays << " rays: " << agree << " hits agree (" << agree_smooth << " smooth, " << agree_sheet << " sheet), "
      << both_miss << " both miss, " << refined << " refined, " << grazing << " grazing, " << unstable << " unstable, "
      << capped << " capped, " << failures << " failures, max normal angle " << max_normal_angle;
    return s.str();
  }
};

struct RayReference {
  reference::ReferenceProfile profile;
};

// Samples about every 1/400 of the box diagonal (a crossing pair thinner than that can hide
// between samples: see `refined` in compare_with_reference).
std::vector<RayReference> sample_rays(const ReferenceMesh& ref, const std::vector<Ray>& rays, const Aabb& box) {
  std::vector<RayReference> out(rays.size());
  const double diag = ref.diagonal;
  tbb::parallel_for(size_t(0), rays.size(), [&](size_t i) {
    double s0, s1;
    reference::clip_ray_to_box(rays[i], box, s0, s1);
    if (!(s0 < s1)) return;
    const int samples = std::max(16, int(std::ceil((s1 - s0) / diag * 400.0)));
    out[i].profile = reference::reference_profile_between(ref, rays[i], s0, s1, samples);
  });
  return out;
}

// The distance from w to the nearest level copy that counts (winding-number mode: the level
// itself; solid-angle mode: level + k).
double level_gap(double w, double level, ReferenceMode mode) {
  double d = w - level;
  if (mode == ReferenceMode::kSolidAngle) d -= std::floor(d + 0.5);
  return std::fabs(d);
}

// Compares trace_surface on every ray with the reference crossing of `level`:
//  - agreement: both miss, or both hit with |s_trace - s_ref| <= 2(δ_w + ε·diag·|∇w|)/|dw/ds|
//    + 1e-5·diag (smooth: the stopping gap and the evaluation error, moved along the ray at the
//    rate w changes there; the additive term is float round-off of t as in the Embree test), or
//    1e-5·diag at sheets (an exact triangle crossing, float round-off only);
//  - the tracer hits earlier: a crossing of the exact w within the same tolerance of its point
//    (resampled there) means the reference had stepped over a thin crossing pair, as happens
//    next to ∂M (`refined`). Otherwise it is legitimate only as a graze: the exact w at its
//    point lies within its own stopping tolerance 2(δ_w + ε·diag·|∇w|) of the level (a ray that
//    comes tangentially close to S without crossing);
//  - the tracer hits later or misses: legitimate only when the reference crossing is unstable
//    under a change of the level by δ' = 2(δ_w + ε·diag·|∇w|): at level ± δ' it disappears or
//    moves by more than the linear estimate 4δ'/|dw/ds| + 1e-5·diag (a tangent touch, or a
//    crossing pair thinner than the evaluation error);
//  - capped (the step cap ended the trace): legitimate only for grazing rays, see below;
//  - anything else is a failure, printed with its ray.
// At agreeing smooth hits the normal must be -∇w/|∇w| (exact gradient at the tracer's point)
// within tol.normal_angle; at sheet hits it must point from {w > level} to {w < level} (exact w
// a little way either side) and the named triangle must carry the point.
Comparison compare_with_reference(const GwnModel& model, const ReferenceMesh& ref, const std::vector<Ray>& rays,
                                  const std::vector<RayReference>& samples, const TraceOptions& options,
                                  const Tolerance& tol) {
  const ReferenceMode mode =
      options.mode == TraceMode::kSolidAngle ? ReferenceMode::kSolidAngle : ReferenceMode::kWindingNumber;
  const double level = options.level;
  const ModelView view = model.view();
  const double diag = box_diagonal(model.bounds());
  const double eps = double(options.epsilon) * diag;
  const double t_round = 1e-5 * diag;
  // 0 both miss, 1 agree smooth, 2 agree sheet, 3 refined, 4 graze, 5 unstable, 6 fail, 7 capped graze
  std::vector<int> verdicts(rays.size());
  std::vector<std::string> messages(rays.size());
  std::vector<double> angles(rays.size(), 0.0);
  tbb::parallel_for(size_t(0), rays.size(), [&](size_t i) {
    const Ray& r = rays[i];
    const RayHit h = trace_surface(view, r, options);
    const reference::ReferenceProfile& p = samples[i].profile;
    const ReferenceCrossing c = reference::reference_crossing(ref, p, level, mode);
    const double len = glm::length(dvec3(r.direction));
    const double s_trace = h.hit ? double(h.t) * len : kInf;
    auto fail = [&](const std::string& why) {
      verdicts[i] = 6;
      messages[i] = why + "\n" + describe(r) + "\n" + describe(h) + "\n" + describe(c);
    };
    if (h.invalid) return fail("invalid");
    if (h.capped) {
      // Harnack steps shrink with the gap to the level: a ray that runs nearly tangent to S (or
      // stays just short of a level) may exhaust the step cap. That is an honest answer for a
      // grazing ray only: the reference crossing is within 0.1 of tangent, or, without a
      // crossing, the ray passes within 0.02 diagonals of the level set (first-order estimate
      // |w - level| / |∇w| at the sample closest to the level).
      if (c.hit && !c.sheet && c.rate < 0.1 * glm::length(c.gradient)) {
        verdicts[i] = 7;
        return;
      }
      if (!c.hit && !p.s.empty()) {
        size_t best = 0;
        for (size_t k = 1; k < p.w.size(); ++k)
          if (level_gap(p.w[k], level, mode) < level_gap(p.w[best], level, mode)) best = k;
        const double g = glm::length(reference::reference_gradient(ref, p.point(p.s[best])));
        if (level_gap(p.w[best], level, mode) <= 0.02 * diag * g) {
          verdicts[i] = 7;
          return;
        }
      }
      return fail("capped away from any graze");
    }
    if (mode == ReferenceMode::kSolidAngle && h.hit && h.kind != HitKind::kSmooth)
      return fail("solid-angle mode reported a sheet");
    auto tolerance_at = [&](const ReferenceCrossing& x) {
      if (x.sheet) return t_round;
      return 2.0 * (tol.delta_w + eps * glm::length(x.gradient)) / x.rate + t_round;
    };
    auto check_hit_details = [&]() -> bool {
      const dvec3 x(h.position);
      if (h.kind == HitKind::kSmooth) {
        const dvec3 g = reference::reference_gradient(ref, x);
        const double cosine = glm::dot(dvec3(h.normal), -g / glm::length(g)) / glm::length(dvec3(h.normal));
        angles[i] = std::acos(std::clamp(cosine, -1.0, 1.0));
        if (!(angles[i] <= tol.normal_angle)) {
          fail("smooth normal off by " + std::to_string(angles[i]) + " rad");
          return false;
        }
      } else {
        const Mesh& m = model.mesh();
        if (!(h.triangle < m.triangles.size()) || distance_to_triangle(m, h.triangle, x) > t_round) {
          fail("sheet hit away from its triangle");
          return false;
        }
        // w a little way along ±normal: beyond round-off (1e-6 diag), well inside one triangle.
        const dvec3 n(h.normal);
        const double ahead = reference::reference_w(ref, x + 1e-6 * diag * n);
        const double behind = reference::reference_w(ref, x - 1e-6 * diag * n);
        if (!(ahead < level + 1e-3 && behind > level - 1e-3)) {
          fail("sheet normal does not point from w > level to w < level (w ahead " + std::to_string(ahead) +
               ", behind " + std::to_string(behind) + ")");
          return false;
        }
      }
      return true;
    };
    if (!h.hit && !c.hit) {
      verdicts[i] = 0;
      return;
    }
    if (h.hit && c.hit && std::fabs(s_trace - c.s) <= tolerance_at(c)) {
      if (check_hit_details()) verdicts[i] = c.sheet ? 2 : 1;
      return;
    }
    if (h.hit && s_trace < c.s) {
      // Earlier than the reference: a crossing pair the sampling stepped over (they can be
      // arbitrarily thin next to ∂M)? Look for a crossing within the tolerance of the tracer's
      // point, with the rate and gradient taken there.
      const dvec3 xg(h.position);
      const dvec3 gx = reference::reference_gradient(ref, xg);
      const double rate_x = std::fabs(glm::dot(gx, p.direction));
      const double local =
          h.kind == HitKind::kSheet ? t_round : 2.0 * (tol.delta_w + eps * glm::length(gx)) / rate_x + t_round;
      if (local < 0.05 * diag) {
        const reference::ReferenceProfile fine =
            reference::reference_profile_between(ref, r, std::max(p.s.front(), s_trace - local), s_trace + local, 16);
        if (reference::reference_crossing(ref, fine, level, mode).hit) {
          if (check_hit_details()) verdicts[i] = 3;
          return;
        }
      }
      const dvec3 x(h.position);
      const double w = reference::reference_w(ref, x);
      const double g = glm::length(reference::reference_gradient(ref, x));
      if (h.kind == HitKind::kSmooth && level_gap(w, level, mode) <= 2.0 * (tol.delta_w + eps * g)) {
        verdicts[i] = 4;
        return;
      }
      return fail("false hit: w there is " + std::to_string(w));
    }
    // The tracer missed the reference crossing or hit later.
    const double g = c.sheet ? 0.0 : glm::length(c.gradient);
    const double dl = 2.0 * (tol.delta_w + eps * g);
    for (const double sign : {-1.0, 1.0}) {
      const ReferenceCrossing moved = reference::reference_crossing(ref, p, level + sign * dl, mode);
      double rate = std::min(c.rate, moved.rate);
      if (!moved.hit || std::fabs(moved.s - c.s) > 4.0 * dl / rate + t_round) {
        verdicts[i] = 5;
        return;
      }
    }
    fail(h.hit ? "late hit" : "missed hit");
  });
  Comparison out;
  out.rays = rays.size();
  int printed = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    switch (verdicts[i]) {
      case 0:
        ++out.both_miss;
        break;
      case 1:
        ++out.agree;
        ++out.agree_smooth;
        break;
      case 2:
        ++out.agree;
        ++out.agree_sheet;
        break;
      case 3:
        ++out.refined;
        break;
      case 4:
        ++out.grazing;
        break;
      case 5:
        ++out.unstable;
        break;
      case 7:
        ++out.capped;
        break;
      default:
        ++out.failures;
        if (printed++ < 10) ADD_FAILURE() << "ray " << i << ": " << messages[i];
    }
    out.max_normal_angle = std::max(out.max_normal_angle, angles[i]);
  }
  return out;
}

// The loops of ∂M (segments joined at bit-identical endpoints) and their centroids.
struct BoundaryLoops {
  std::vector<uint32_t> of_endpoint;  // loop of each endpoint of BoundaryCurve::endpoints
  std::vector<vec3> centroid;
};

BoundaryLoops boundary_loops(const BoundaryCurve& curve) {
  const std::vector<vec3>& e = curve.endpoints;
  std::vector<uint32_t> parent(e.size());
  for (uint32_t i = 0; i < e.size(); ++i) parent[i] = i;
  auto find = [&](uint32_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  auto key = [](const vec3& p) { return std::tuple(p.x, p.y, p.z); };
  std::map<std::tuple<float, float, float>, uint32_t> first;
  for (uint32_t i = 0; i < e.size(); ++i) {
    if (i % 2 == 1) parent[find(i)] = find(i - 1);  // a segment joins its two ends
    const auto [it, fresh] = first.emplace(key(e[i]), i);
    if (!fresh) parent[find(i)] = find(it->second);
  }
  BoundaryLoops loops;
  loops.of_endpoint.resize(e.size());
  std::map<uint32_t, uint32_t> index;
  std::vector<dvec3> sum;
  std::vector<double> count;
  for (uint32_t i = 0; i < e.size(); ++i) {
    const auto [it, fresh] = index.emplace(find(i), uint32_t(sum.size()));
    if (fresh) {
      sum.emplace_back(0.0);
      count.push_back(0);
    }
    loops.of_endpoint[i] = it->second;
    sum[it->second] += dvec3(e[i]);
    count[it->second] += 1;
  }
  for (size_t l = 0; l < sum.size(); ++l) loops.centroid.push_back(vec3(sum[l] / count[l]));
  return loops;
}

// Rays for a mesh with holes: a third from outside aimed into the box, a third from inside the
// box in any direction, a third aimed across the holes (where the smooth part of S is).
std::vector<Ray> open_rays(const GwnModel& model, size_t count, uint32_t seed) {
  Random rng(seed);
  const Aabb box = model.bounds();
  const float diag = float(box_diagonal(box));
  const std::vector<vec3>& rim = model.boundary().endpoints;
  const BoundaryLoops loops = boundary_loops(model.boundary());
  std::vector<Ray> rays;
  while (rays.size() < count) {
    Ray r;
    switch (rays.size() % 3) {
      case 0:
        r.origin = rng.in_box(grown(box, 0.5f * diag));
        r.direction = rng.in_box(box) - r.origin;
        break;
      case 1:
        r.origin = rng.in_box(box);
        r.direction = rng.unit();
        break;
      default: {
        // Between a rim point and the centroid of its loop: across the hole, where S is smooth.
        r.origin = rng.in_box(grown(box, 0.5f * diag));
        vec3 target = rng.in_box(box);
        if (!rim.empty()) {
          const size_t k = size_t(rng.index(int(rim.size())));
          target = glm::mix(rim[k], loops.centroid[loops.of_endpoint[k]], rng.uniform(0, 1)) +
                   0.02f * diag * rng.unit() * rng.uniform(0, 1);
        }
        r.direction = target - r.origin;
      }
    }
    if (!(glm::length(r.direction) > 1e-3f * diag)) continue;
    r.direction = glm::normalize(r.direction) * rng.scale();
    rays.push_back(r);
  }
  return rays;
}

// The reference looks well beyond the tracer's own search box (bounds + surface_margin): a piece
// of S out there would show as a miss of the tracer.
Aabb reference_box(const GwnModel& model) {
  return grown(model.bounds(), 1.5f * model.surface_margin() + 0.1f * float(box_diagonal(model.bounds())));
}

void expect_meaningful(const Comparison& c, size_t min_smooth, size_t min_sheet) {
  EXPECT_EQ(c.failures, 0u) << c.report();
  // Relaxed rays (grazing or unstable) must stay rare, or the comparison would say little.
  EXPECT_LE(c.grazing + c.unstable + c.capped, c.rays / 20) << c.report();
  EXPECT_GE(c.agree_smooth, min_smooth) << c.report();
  EXPECT_GE(c.agree_sheet, min_sheet) << c.report();
}

// ---------------------------------------------------------------------------------------------
// 2. Meshes with holes, level 1/2, exact and multipole evaluation.
// ---------------------------------------------------------------------------------------------

class TraceOpenMesh : public ::testing::TestWithParam<OpenCase> {};

TEST_P(TraceOpenMesh, MatchesDenseSamplingReference) {
  const GwnModel model = build_model(open_mesh(GetParam().name));
  ASSERT_GT(model.boundary().segment_count(), 0u);
  const ReferenceMesh ref = reference::reference_mesh(model.mesh());
  const std::vector<Ray> rays = open_rays(model, GetParam().rays, 201);
  const std::vector<RayReference> samples = sample_rays(ref, rays, reference_box(model));
  for (const bool exact : {true, false}) {
    SCOPED_TRACE(exact ? "exact" : "multipole");
    TraceOptions options;
    options.exact = exact;
    const Comparison c =
        compare_with_reference(model, ref, rays, samples, options, exact ? kExactTolerance : kMultipoleTolerance);
    std::printf("[ %s %s ] %s\n", GetParam().name, exact ? "exact" : "multipole", c.report().c_str());
    expect_meaningful(c, rays.size() / 20, rays.size() / 20);
  }
}

INSTANTIATE_TEST_SUITE_P(Meshes, TraceOpenMesh,
                         ::testing::Values(OpenCase{"bunny_holes", 150}, OpenCase{"open_cube", 1500},
                                           OpenCase{"hexagon_fan", 1500}),
                         [](const auto& info) { return std::string(info.param.name); });

// The tolerance of the multipole comparisons, measured: the error of φ and of ∇w as the tracer
// evaluates them by default (multipole, on the cone) at the reference crossings of rays like
// the ones above.
TEST(TraceOpenMesh, MultipoleErrorOnTheLevelSetIsBounded) {
  for (const char* name : {"bunny_holes", "open_cube", "hexagon_fan"}) {
    SCOPED_TRACE(name);
    const GwnModel model = build_model(open_mesh(name));
    const ReferenceMesh ref = reference::reference_mesh(model.mesh());
    const std::vector<Ray> rays = open_rays(model, std::string(name) == "bunny_holes" ? 90 : 600, 202);
    const std::vector<RayReference> samples = sample_rays(ref, rays, reference_box(model));
    const ModelView view = model.view();
    double max_w = 0, max_g = 0;
    size_t points = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
      const ReferenceCrossing c =
          reference::reference_crossing(ref, samples[i].profile, 0.5, ReferenceMode::kWindingNumber);
      if (!c.hit || c.sheet) continue;
      const dvec3 x = samples[i].profile.point(c.s);
      // What the tracer evaluates (φ for its steps, ∇w for its stopping test and its normal).
      const PhaseSample sample = sample_phase(view, vec3(x), TraceOptions{}.beta, true);
      const double w = reference::reference_w(ref, x);
      max_w = std::max(max_w, level_gap(double(sample.phi), w, ReferenceMode::kSolidAngle));  // equal mod 1
      max_g = std::max(max_g, glm::length(dvec3(sample.gradient) - c.gradient) / glm::length(c.gradient));
      ++points;
    }
    std::printf("[ %s ] multipole at %zu level-set points: |dw| <= %.3g, |dgrad|/|grad| <= %.3g\n", name, points, max_w,
                max_g);
    EXPECT_GT(points, rays.size() / 20);
    EXPECT_LE(max_w, kMultipoleTolerance.delta_w);
    EXPECT_LE(max_g, kMultipoleTolerance.normal_angle);
  }
}

// ---------------------------------------------------------------------------------------------
// 3. Solid-angle mode.
// ---------------------------------------------------------------------------------------------

// A planar polygon's level set Ω = 2π (w ≡ 1/2) is the polygon itself: w → ±1/2 on it, |w| < 1/2
// everywhere else. Fan of a regular pentagon around its centre in the plane z = 0.25 (exactly
// planar in float), and a tilted square (planar up to float rounding of its corners).
void check_planar_polygon(const std::vector<vec3>& rim, uint32_t seed) {
  Mesh m;
  vec3 centre(0.0f);
  for (const vec3& p : rim) centre += p / float(rim.size());
  m.positions.push_back(centre);
  m.positions.insert(m.positions.end(), rim.begin(), rim.end());
  const uint32_t n = uint32_t(rim.size());
  for (uint32_t k = 0; k < n; ++k) m.triangles.push_back({0u, 1 + k, 1 + (k + 1) % n});
  const GwnModel model = build_model(m);
  const ModelView view = model.view();
  const double diag = box_diagonal(model.bounds());
  const dvec3 normal = glm::normalize(dvec3(glm::cross(rim[1] - rim[0], rim[2] - rim[0])));
  const dvec3 c(centre);
  // Signed distance of the plane point x to the polygon's rim (positive inside); convex polygon.
  auto inside_by = [&](const dvec3& x) {
    double d = kInf;
    for (uint32_t k = 0; k < n; ++k) {
      const dvec3 a(rim[k]), b(rim[(k + 1) % n]);
      const dvec3 inward = glm::normalize(glm::cross(normal, b - a));
      d = std::min(d, glm::dot(x - a, inward));
    }
    return d;
  };
  Random rng(seed);
  TraceOptions options;
  options.mode = TraceMode::kSolidAngle;
  size_t hits = 0, misses = 0, skipped = 0;
  for (int i = 0; i < 1500; ++i) {
    Ray r;
    r.origin = rng.in_box(grown(model.bounds(), float(diag)));
    // Aim at the plane within 1.6 circumradii of the centre, or anywhere.
    const dvec3 u = glm::normalize(dvec3(rim[0]) - c), v = glm::cross(normal, u);
    const double radius = glm::length(dvec3(rim[0]) - c);
    const dvec3 target = c + radius * 1.6 * (double(rng.uniform(-1, 1)) * u + double(rng.uniform(-1, 1)) * v);
    r.direction = i % 4 == 3 ? rng.unit() : glm::normalize(vec3(target - dvec3(r.origin)));
    r.direction *= rng.scale();
    for (const bool exact : {false, true}) {
      options.exact = exact;
      const RayHit h = trace_surface(view, r, options);
      SCOPED_TRACE(describe(r) + "\n" + describe(h) + (exact ? " exact" : " multipole"));
      ASSERT_FALSE(h.invalid);
      // Where does the line meet the plane, ahead of the origin?
      const dvec3 o(r.origin), d = glm::normalize(dvec3(r.direction));
      const double dn = glm::dot(d, normal);
      const double s = dn != 0 ? glm::dot(c - o, normal) / dn : -1.0;
      const double margin = s > 0 ? inside_by(o + s * d) : -kInf;
      // Within 1% of the circumradius of the rim the ray passes next to ∂M, where the level set
      // meets the rim; either answer is right there. Rays within 3° of the plane are skipped too:
      // they may run out of Harnack steps (each step shrinks with the distance to the plane, so
      // their number grows like 1/|cos|), or legitimately stop where they pass within ε·diag of
      // the rim, far from where the line meets the plane.
      if (std::fabs(margin) < 0.01 * radius || std::fabs(dn) < 0.05) {
        ++skipped;
        continue;
      }
      ASSERT_FALSE(h.capped);
      if (margin < 0) {
        EXPECT_FALSE(h.hit) << "the line meets the plane outside the polygon (by " << -margin << ")";
        ++misses;
        continue;
      }
      ASSERT_TRUE(h.hit) << "the line crosses the polygon " << margin << " inside its rim";
      ++hits;
      EXPECT_EQ(h.kind, HitKind::kSmooth);  // solid-angle mode has no sheets
      // The tracer stops once |φ - 1/2| <= ε·diag·|∇w|, i.e. within ε·diag of the plane to first
      // order (w is linear across the plane inside the polygon); it approaches from one side,
      // so twice that bounds it, plus 1e-6·diag of float round-off of the position.
      const dvec3 x(h.position);
      EXPECT_LE(std::fabs(glm::dot(x - c, normal)), 2.0 * options.epsilon * diag + 1e-6 * diag);
      EXPECT_GE(inside_by(x - glm::dot(x - c, normal) * normal), 0.0);
      // Along the ray: the same bound divided by the cosine of the incidence.
      EXPECT_LE(std::fabs(double(h.t) * glm::length(dvec3(r.direction)) - s),
                (2.0 * options.epsilon * diag + 1e-6 * diag) / std::fabs(dn));
      // -∇w is the polygon's geometric normal reversed, seen from either side.
      EXPECT_GE(-glm::dot(dvec3(h.normal), normal), 1.0 - 1e-3);
    }
  }
  // 1500 rays, each traced exact and multipole.
  std::printf("[ planar polygon ] %zu hits, %zu misses, %zu skipped\n", hits, misses, skipped);
  EXPECT_GT(hits, 300u);
  EXPECT_GT(misses, 1000u);
  EXPECT_LT(skipped, 400u);
}

TEST(TraceSolidAngle, PlanarPentagonIsItsOwnLevelSet) {
  std::vector<vec3> rim;
  for (int k = 0; k < 5; ++k) {
    const double a = 2.0 * kPi * k / 5.0 + 0.3;
    rim.push_back({float(0.5 + std::cos(a)), float(-0.25 + std::sin(a)), 0.25f});
  }
  check_planar_polygon(rim, 301);
}

TEST(TraceSolidAngle, TiltedSquareIsItsOwnLevelSet) {
  const vec3 u = glm::normalize(vec3(1.0f, 0.3f, -0.2f));
  const vec3 v = glm::normalize(glm::cross(vec3(0.2f, 0.1f, 1.0f), u));
  const vec3 o(0.1f, 0.2f, 0.3f);
  check_planar_polygon({o - u - v, o + u - v, o + u + v, o - u + v}, 302);
}

TEST(TraceSolidAngle, NonplanarQuadMatchesDenseSamplingReference) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0.3f}, {1, 1, 0}, {0, 1, 0.3f}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  const GwnModel model = build_model(m);
  const ReferenceMesh ref = reference::reference_mesh(m);
  const std::vector<Ray> rays = open_rays(model, 1500, 303);
  const std::vector<RayReference> samples = sample_rays(ref, rays, reference_box(model));
  for (const bool exact : {true, false}) {
    SCOPED_TRACE(exact ? "exact" : "multipole");
    TraceOptions options;
    options.mode = TraceMode::kSolidAngle;
    options.exact = exact;
    const Comparison c =
        compare_with_reference(model, ref, rays, samples, options, exact ? kExactTolerance : kMultipoleTolerance);
    std::printf("[ nonplanar quad %s ] %s\n", exact ? "exact" : "multipole", c.report().c_str());
    expect_meaningful(c, rays.size() / 5, 0);
  }
}

// ---------------------------------------------------------------------------------------------
// 4. Levels other than 1/2.
// ---------------------------------------------------------------------------------------------

class TraceLevel : public ::testing::TestWithParam<OpenCase> {};

TEST_P(TraceLevel, MatchesDenseSamplingReference) {
  const GwnModel model = build_model(open_mesh(GetParam().name));
  const ReferenceMesh ref = reference::reference_mesh(model.mesh());
  const std::vector<Ray> rays = open_rays(model, GetParam().rays, 401);
  const std::vector<RayReference> samples = sample_rays(ref, rays, reference_box(model));
  for (const float level : {0.3f, 0.7f}) {
    for (const bool exact : {true, false}) {
      SCOPED_TRACE("level " + std::to_string(level) + (exact ? " exact" : " multipole"));
      TraceOptions options;
      options.level = level;
      options.exact = exact;
      const Comparison c =
          compare_with_reference(model, ref, rays, samples, options, exact ? kExactTolerance : kMultipoleTolerance);
      std::printf("[ %s level %.1f %s ] %s\n", GetParam().name, level, exact ? "exact" : "multipole",
                  c.report().c_str());
      expect_meaningful(c, rays.size() / 20, rays.size() / 20);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Meshes, TraceLevel,
                         ::testing::Values(OpenCase{"bunny_holes", 90}, OpenCase{"open_cube", 1000}),
                         [](const auto& info) { return std::string(info.param.name); });

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
  // Issue 15 item 8: denormal directions (1e-44 reported a hit at t = inf) are too short to
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
