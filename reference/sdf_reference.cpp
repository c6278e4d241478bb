// The accuracy study's reference: exact levels, the cloud of points on the smooth pieces and the
// refined distance to them (sdf_reference.h says what and why).
#include "reference/sdf_reference.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>

#include "gwnrt/field/distance.h"
#include "gwnrt/field/winding_number.h"
#include "gwnrt/query/validation.h"
#include "gwnrt/trace/surface_trace.h"
#include "reference/parallel_over.h"
#include "reference/seeded_random.h"

namespace gwnrt::reference {

namespace {

// Lines for the cloud (build_cloud says which).
std::vector<Ray> cloud_lines(const GwnModel& model, const ModelView& view, const TraceOptions& options, size_t first,
                             size_t count, uint64_t seed) {
  const BoundaryCurve& curve = model.boundary();
  uint32_t loop_count = 0;
  const std::vector<uint32_t> loop_of = boundary_loops(curve, loop_count);
  std::vector<Aabb> loop_box(loop_count);
  std::vector<double> cumulative(curve.segment_count());
  double total = 0;
  for (size_t s = 0; s < curve.segment_count(); ++s) {
    loop_box[loop_of[s]].extend(curve.endpoints[2 * s]);
    loop_box[loop_of[s]].extend(curve.endpoints[2 * s + 1]);
    total += glm::length(curve.endpoints[2 * s + 1] - curve.endpoints[2 * s]);
    cumulative[s] = total;
  }
  std::vector<Aabb> march;
  for (uint32_t r = 0; r < march_box_count(view, options.level); ++r)
    march.push_back(march_box(view, options.level, r));
  const Aabb all = surface_bounds(view, options);
  const dvec3 centre(all.centre());
  const double span = glm::length(dvec3(all.hi) - dvec3(all.lo));

  std::vector<Ray> rays(count);
  for (size_t j = 0; j < count; ++j) {
    const size_t i = first + j;
    std::mt19937_64 rng = item_rng(seed, 1, i);
    dvec3 p;
    const int kind = int(i % 3);
    if (kind == 0 && !march.empty()) {
      p = uniform_in_box(march[size_t(uniform(rng) * double(march.size())) % march.size()], rng);
    } else if (kind != 2) {
      const Aabb& b = loop_box[size_t(uniform(rng) * loop_count) % loop_count];
      p = uniform_in_box(b, rng);
    } else {
      const double at = uniform(rng) * total;
      const size_t s = std::min(size_t(std::lower_bound(cumulative.begin(), cumulative.end(), at) - cumulative.begin()),
                                cumulative.size() - 1);
      const dvec3 a(curve.endpoints[2 * s]), b(curve.endpoints[2 * s + 1]);
      const Aabb& lb = loop_box[loop_of[s]];
      const double size = glm::length(dvec3(lb.hi) - dvec3(lb.lo));
      p = a + uniform(rng) * (b - a) + (0.25 * size * uniform(rng)) * random_direction(rng);
    }
    const dvec3 d = random_direction(rng);
    const double reach = glm::length(p - centre) + span;
    rays[j].origin = vec3(p - reach * d);
    rays[j].direction = vec3(d);
    rays[j].tnear = 0.0f;
    rays[j].tfar = float(2.0 * reach);
  }
  return rays;
}

}  // namespace

LevelGap level_gap(const ExactLevel& e, const dvec3& x) {
  const WindingSampleExact s = winding_number_exact(e.cone, vec3(x), true, false);
  double g = s.w - e.level;
  g -= std::round(g);
  return {g, s.gradient};
}

bool onto_level(const ExactLevel& e, const dvec3& q, const dvec3& n, double limit, dvec3& out, dvec3& gradient,
                double& slack) {
  double t = 0;
  for (int it = 0; it < 30; ++it) {
    const dvec3 p = q + t * n;
    const LevelGap s = level_gap(e, p);
    const double slope = glm::dot(s.gradient, n);
    const double gn = glm::length(s.gradient);
    const bool tight = std::fabs(s.gap) < 1e-8;
    if (tight || (it > 0 && std::fabs(s.gap) < kGapTolerance && std::fabs(s.gap / slope) < 1e-7 * e.diagonal)) {
      out = p;
      gradient = s.gradient;
      slack = gn > 0 ? std::fabs(s.gap) / gn : kInfinity;
      return gn > 0;
    }
    if (!(std::fabs(slope) > 0)) return false;
    t -= s.gap / slope;
    if (!(std::fabs(t) <= limit)) return false;
  }
  return false;
}

bool on_surface_band(const ExactLevel& e, const dvec3& y) {
  return std::fabs(winding_number_exact(e.mesh, vec3(y)).w - e.level) < kBandTolerance;
}

std::vector<CloudPoint> build_cloud(const GwnModel& model, const ExactLevel& exact, float level, size_t target,
                                    size_t max_lines, uint64_t seed, CloudStats& stats) {
  const auto t0 = std::chrono::steady_clock::now();
  const ModelView view = model.view();
  TraceOptions options;
  options.level = level;
  std::vector<CloudPoint> cloud;
  constexpr size_t kBatch = 2048;
  while (cloud.size() < target && stats.lines < max_lines) {
    const std::vector<Ray> rays = cloud_lines(model, view, options, stats.lines, kBatch, seed);
    std::vector<std::vector<CloudPoint>> found(rays.size());
    std::vector<uint8_t> capped(rays.size(), 0);
    std::vector<size_t> crossings(rays.size(), 0), moved(rays.size(), 0), band(rays.size(), 0);
    std::vector<double> slack(rays.size(), 0);
    parallel_over(rays.size(), [&](size_t i) {
      std::vector<CloudPoint> raw;
      const auto record = [&raw](const RayHit& h) {
        if (h.kind == HitKind::kSmooth) raw.push_back({dvec3(h.position), -dvec3(h.normal)});
        return false;  // turn every hit down: the trace goes on and offers the next crossing
      };
      const RayHit h = trace_surface(view, rays[i], options, record);
      capped[i] = h.capped;
      crossings[i] = raw.size();
      for (const CloudPoint& c : raw) {
        // The tracer's point is on the tree's level (β = 2 on the cone, ε = 1e-5 D): move it
        // along its normal onto the exact one, not farther than a fraction of its distance to M
        // (so that no sheet lies between).
        const double to_mesh = unsigned_distance(exact.triangles, vec3(c.p)).distance;
        dvec3 y, g;
        double s;
        if (!onto_level(exact, c.p, c.n, 0.5 * to_mesh, y, g, s)) {
          ++moved[i];
          continue;
        }
        if (!on_surface_band(exact, y)) {
          ++band[i];
          continue;
        }
        slack[i] = std::max(slack[i], s);
        found[i].push_back({y, glm::normalize(g)});
      }
    });
    for (size_t i = 0; i < rays.size(); ++i) {
      cloud.insert(cloud.end(), found[i].begin(), found[i].end());
      stats.capped += capped[i];
      stats.crossings += crossings[i];
      stats.moved_off += moved[i];
      stats.wrong_band += band[i];
      stats.max_slack = std::max(stats.max_slack, slack[i]);
    }
    stats.lines += rays.size();
  }
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return cloud;
}

void smooth_reference(const ExactLevel& e, const std::vector<CloudPoint>& cloud, const KdTree& tree, const dvec3& x,
                      double skip_margin, Reference& ref) {
  uint32_t id;
  double d2;
  if (tree.nearest(x, 1, &id, &d2) == 0) return;
  ref.smooth_raw = std::sqrt(d2);
  ref.smooth = std::min(ref.smooth, ref.smooth_raw);
  if (ref.sheet < ref.smooth_raw - skip_margin) return;
  dvec3 y = cloud[id].p, n = cloud[id].n;
  struct Candidate {
    dvec3 y, n;
    double distance, slack;
  };
  std::array<Candidate, kRefineSteps> candidates;
  int count = 0;
  double current = glm::length(x - y);
  for (int k = 0; k < kRefineSteps; ++k) {
    const dvec3 v = x - y;
    dvec3 tangent = v - glm::dot(v, n) * n;
    const double step = glm::length(tangent);
    // For a flat piece the distance is off by about step² / (2|x − y|): stop far below the
    // level slack's scale.
    if (step * step < 2e-9 * e.diagonal * current) break;
    // Within half the distance to M no sheet lies between y and the next point, so the level
    // reached is y's own (w = w*); a longer step (near the rims, where the caps meet M) may reach
    // w* ± 1 beyond a sheet, so its point is confirmed by the exact w of M before it is taken.
    const double safe = 0.5 * unsigned_distance(e.triangles, vec3(y)).distance;
    // The full step reaches the foot when the piece is flat; where it curves toward x (radius
    // of curvature near |x − y|) the full step overshoots and cycles: halve until it gets nearer.
    bool moved = false;
    for (int halving = 0; halving < 10 && !moved; ++halving, tangent *= 0.5) {
      const double length = glm::length(tangent);
      dvec3 z, g;
      double slack;
      if (!onto_level(e, y + tangent, n, std::max(safe, length), z, g, slack)) continue;
      const double d = glm::length(x - z);
      if (!(d < current)) continue;
      const bool confirmed = glm::length(z - y) > safe;
      if (confirmed && !on_surface_band(e, z)) continue;
      y = z;
      n = glm::normalize(g);
      current = d;
      candidates[count++] = {y, n, d, slack};
      moved = true;
    }
    if (!moved) break;
  }
  std::sort(candidates.begin(), candidates.begin() + count,
            [](const Candidate& a, const Candidate& b) { return a.distance < b.distance; });
  for (int k = 0; k < count; ++k) {
    if (candidates[k].distance >= ref.smooth) break;
    if (!on_surface_band(e, candidates[k].y)) continue;
    ref.smooth = candidates[k].distance;
    ref.slack = candidates[k].slack;
    const dvec3 v = x - candidates[k].y;
    ref.tangent_gap = glm::length(v) - std::fabs(glm::dot(v, candidates[k].n));
    break;
  }
}

}  // namespace gwnrt::reference
