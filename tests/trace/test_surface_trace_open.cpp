// trace_surface on meshes with holes against the dense-sampling reference of first_crossing.h
// (exact w in double, bisection): at level 1/2 with exact and multipole evaluation, in
// solid-angle mode, and at levels other than 1/2.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include <tbb/parallel_for.h>

#include "gwnrt/field/winding_number.h"
#include "gwnrt/trace/surface_trace.h"
#include "reference/first_crossing.h"
#include "test_util.h"
#include "trace_fixtures.h"

namespace gwnrt {
namespace {

struct OpenCase {
  const char* name;
  size_t rays;
};
void PrintTo(const OpenCase& c, std::ostream* os) { *os << c.name << ", " << c.rays << " rays"; }

// ---------------------------------------------------------------------------------------------
// The dense-sampling comparison shared by tests 2-4.
// ---------------------------------------------------------------------------------------------

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
// With level_free_cells the model's view keeps its level-free cells (where prepared), else drops them.
Comparison compare_with_reference(const GwnModel& model, const ReferenceMesh& ref, const std::vector<Ray>& rays,
                                  const std::vector<RayReference>& samples, const TraceOptions& options,
                                  const Tolerance& tol, bool level_free_cells = false) {
  const ReferenceMode mode =
      options.mode == TraceMode::kSolidAngle ? ReferenceMode::kSolidAngle : ReferenceMode::kWindingNumber;
  const double level = options.level;
  ModelView view = model.view();
  if (!level_free_cells) view.level_free = {};
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

// The number of level-free cells of a prepared model's view.
size_t level_free_count(const GwnModel& model) {
  size_t n = 0;
  for (const uint8_t f : model.level_free_cells().free) n += f;
  return n;
}

TEST_P(TraceOpenMesh, MatchesDenseSamplingReference) {
  const GwnModel model = build_model(open_mesh(GetParam().name));
  ASSERT_GT(model.boundary().segment_count(), 0u);
  ASSERT_TRUE(model.prepare(kPartLevelFreeCells).ok());
  ASSERT_GT(level_free_count(model), 0u);
  const ReferenceMesh ref = reference::reference_mesh(model.mesh());
  const std::vector<Ray> rays = open_rays(model, GetParam().rays, 201);
  const std::vector<RayReference> samples = sample_rays(ref, rays, reference_box(model));
  // The exact march never takes the cells (it is their reference); the multipole's with and without.
  for (const int variant : {0, 1, 2}) {
    const bool exact = variant == 0, cells = variant == 2;
    const char* name = exact ? "exact" : (cells ? "multipole, level-free cells" : "multipole");
    SCOPED_TRACE(name);
    TraceOptions options;
    options.exact = exact;
    const Comparison c = compare_with_reference(model, ref, rays, samples, options,
                                                exact ? kExactTolerance : kMultipoleTolerance, cells);
    std::printf("[ %s %s ] %s\n", GetParam().name, name, c.report().c_str());
    expect_meaningful(c, rays.size() / 20, rays.size() / 20);
  }
}

INSTANTIATE_TEST_SUITE_P(Meshes, TraceOpenMesh,
                         ::testing::Values(OpenCase{"bunny_holes", 150}, OpenCase{"open_cube", 1500},
                                           OpenCase{"hexagon_fan", 1500},
                                           OpenCase{"open_hemisphere", test::kAddressSanitizer ? 60u : 200u}),
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
  GwnModel model = build_model(open_mesh(GetParam().name));
  ASSERT_TRUE(model.prepare(kPartLevelFreeCells).ok());
  const ReferenceMesh ref = reference::reference_mesh(model.mesh());
  const std::vector<Ray> rays = open_rays(model, GetParam().rays, 401);
  const std::vector<RayReference> samples = sample_rays(ref, rays, reference_box(model));
  for (const float level : {0.3f, 0.7f}) {
    // The cells built for 1/2 are made again for this level's phase.
    ASSERT_TRUE(model.set_sheet_level(level).ok());
    ASSERT_EQ(model.view().level_free.phase, level);
    ASSERT_GT(level_free_count(model), 0u);
    for (const int variant : {0, 1, 2}) {
      const bool exact = variant == 0, cells = variant == 2;
      const char* name = exact ? "exact" : (cells ? "multipole, level-free cells" : "multipole");
      SCOPED_TRACE("level " + std::to_string(level) + " " + name);
      TraceOptions options;
      options.level = level;
      options.exact = exact;
      const Comparison c = compare_with_reference(model, ref, rays, samples, options,
                                                  exact ? kExactTolerance : kMultipoleTolerance, cells);
      std::printf("[ %s level %.1f %s ] %s\n", GetParam().name, level, name, c.report().c_str());
      expect_meaningful(c, rays.size() / 20, rays.size() / 20);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Meshes, TraceLevel,
                         ::testing::Values(OpenCase{"bunny_holes", 90}, OpenCase{"open_cube", 1000}),
                         [](const auto& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace gwnrt
