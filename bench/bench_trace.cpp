// gwnrt-bench-trace: the same camera and the same rays traced three ways on each mesh,
//  (a) by Embree's own triangle intersection on the mesh (rtcIntersect1), the speed of light
//      for "first triangle along the ray";
//  (b) by gwnrt on S = ∂{w > level} (trace_rays: crossing walk + Harnack steps near ∂M);
//  (c) by the brute-force Harnack tracer of brute_force_trace.h (O(n) exact sum per step,
//      R = distance to every edge), on a fixed subset of the pixels;
// with rays/s for each, the ratios b/a and b/c, gwnrt's step statistics, and how far the three
// agree (hit/miss and |Δt| relative to the box diagonal).
//
// With no meshes given it runs bunny.obj, bunny_holes.obj and teapot.obj from data/,
// and the full 871k-triangle dragon when /tmp/dragon_vrip.ply exists (make it with
// `gunzip -c ../shared/meshes/dragon_vrip.ply.gz > /tmp/dragon_vrip.ply`, or pass its path).
// The camera is gwnrt-render's (frame_box), so both programs shoot exactly these rays.
// Timings: (a) and (b) best of 3 runs over all pixels (a run repeats the image until it has
// taken 0.1 s); (c) one run over its subset, which stops early (a prefix of a fixed order spread
// over the image) when --brute-seconds is spent; gwnrt is timed on that subset too, so that
// b/c can also be read on the very same rays. After the timings, --check traces with the
// brute force the rays most likely to show a problem (where (a) and (b) disagree, where (b)
// hits a smooth piece or is capped) and prints any ray that disagrees, as a gwnrt-trace line.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>
#include <CLI/CLI.hpp>

#include "apps/common/cli_checks.h"
#include "reference/brute_force_trace.h"
#include "render/camera.h"
#if defined(GWNRT_HAVE_EMBREE)
#include "render/embree_triangles.h"
#endif
#include "apps/common/load_model.h"
#include "apps/common/program.h"
#include "gwnrt/base/memory.h"
#include "gwnrt/geometry/mesh.h"
#include "gwnrt/io/mesh_io.h"
#include "gwnrt/model/model.h"
#include "gwnrt/query/batch.h"

namespace {

using namespace gwnrt;
using clock_type = std::chrono::steady_clock;
using apps::seconds_since;

constexpr const char* kProgram = "gwnrt-bench-trace";

const char* kind_name(HitKind kind) {
  switch (kind) {
    case HitKind::kSheet:
      return "sheet";
    case HitKind::kSmooth:
      return "smooth";
    default:
      return "none";
  }
}

// A first hit as the comparisons see it: t in the ray's units (the rays are unit length).
struct SimpleHit {
  bool hit = false;
  float t = kInfinity;
};

#if defined(GWNRT_HAVE_EMBREE)

// All rays through Embree's rtcIntersect1 on the mesh's triangles, in parallel; returns the
// seconds taken.
double trace_embree(const render::TriangleScene& embree, const std::vector<Ray>& rays, std::vector<SimpleHit>& hits) {
  hits.assign(rays.size(), SimpleHit{});
  const auto t0 = clock_type::now();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), 64), [&](const tbb::blocked_range<size_t>& range) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (size_t i = range.begin(); i != range.end(); ++i) {
      const RTCRayHit rh = embree.intersect(rays[i], context);
      if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) hits[i] = {true, rh.ray.tfar};
    }
  });
  return seconds_since(t0);
}

#endif  // GWNRT_HAVE_EMBREE

double trace_gwnrt(const GwnModel& model, const std::vector<Ray>& rays, const TraceOptions& options,
                   std::vector<RayHit>& hits) {
  hits.assign(rays.size(), RayHit{});
  const auto t0 = clock_type::now();
  if (Status s = trace_rays(model, rays, options, hits); !s.ok()) apps::die(kProgram, s.message());
  return seconds_since(t0);
}

struct Rate {
  size_t rays = 0;  // over all passes
  double seconds = 0;
  size_t passes = 1;
  double pass_seconds() const { return seconds / double(passes); }
  double per_second() const { return seconds > 0 ? double(rays) / seconds : NAN; }
};

// Best of 3 runs; each run repeats `trace` (which returns its seconds) until it has taken at
// least kMinRunSeconds, so that short traces are not dominated by the start of the parallel loop.
constexpr double kMinRunSeconds = 0.1;

template <class TraceFn>
Rate best_of_3(size_t rays, const TraceFn& trace) {
  Rate best;
  for (int run = 0; run < 3; ++run) {
    Rate r;
    r.passes = 0;
    do {
      r.seconds += trace();
      r.rays += rays;
      ++r.passes;
    } while (r.seconds < kMinRunSeconds);
    if (run == 0 || r.per_second() > best.per_second()) best = r;
  }
  return best;
}

struct MeshSummary {
  std::string name;
  size_t triangles = 0;
  Rate a, b, c, b_subset;
};

// One line "ox oy oz dx dy dz", as gwnrt-trace reads rays.
void print_ray(const char* label, const Ray& r) {
  std::printf("      %s ray (origin, direction): %.9g %.9g %.9g %.9g %.9g %.9g\n", label, r.origin.x, r.origin.y,
              r.origin.z, r.direction.x, r.direction.y, r.direction.z);
}

std::string fmt_rate(double r) {
  if (std::isnan(r)) return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", r);
  return buf;
}

std::string mesh_label(const std::string& path) { return std::filesystem::path(path).filename().string(); }

// The brute-force tracer on rays[pixels[m]], in parallel, in the order given; stops starting new
// rays once `budget` seconds are spent. hits holds the first m results, m the returned count.
Rate brute_trace(const reference::BruteForceTracer& brute, const std::vector<Ray>& rays,
                 const std::vector<size_t>& pixels, const TraceOptions& options, double budget, int workers,
                 std::vector<RayHit>& hits) {
  hits.assign(pixels.size(), RayHit{});
  std::atomic<size_t> next{0};
  const auto t0 = clock_type::now();
  tbb::task_group group;
  for (int w = 0; w < workers; ++w)
    group.run([&] {
      for (;;) {
        if (seconds_since(t0) > budget) return;
        const size_t m = next.fetch_add(1);
        if (m >= pixels.size()) return;
        hits[m] = brute.trace(rays[pixels[m]], options);
      }
    });
  group.wait();
  Rate r;
  r.rays = std::min(next.load(), pixels.size());
  r.seconds = seconds_since(t0);
  hits.resize(r.rays);
  return r;
}

// Brute force (c) against gwnrt (b) on rays[pixels[m]], for the first brute.size() of them.
void compare_with_brute(const char* label, const std::vector<Ray>& rays, const std::vector<size_t>& pixels,
                        const std::vector<RayHit>& brute, const std::vector<RayHit>& ghits, double diag, int show) {
  const size_t n = std::min(pixels.size(), brute.size());
  size_t agree = 0, kinds = 0, both = 0, c_capped = 0, c_only = 0, b_only = 0, far = 0;
  double max_dt = 0, c_steps = 0;
  size_t worst = SIZE_MAX;
  std::vector<size_t> bad;
  for (size_t m = 0; m < n; ++m) {
    const RayHit& hc = brute[m];
    const RayHit& hb = ghits[pixels[m]];
    c_capped += hc.capped;
    c_steps += hc.steps;
    const bool same = hc.hit == hb.hit;
    agree += same;
    if (!same) {
      bad.push_back(m);
      (hc.hit ? c_only : b_only)++;
    }
    if (!(hc.hit && hb.hit)) continue;
    ++both;
    kinds += hc.kind == hb.kind;
    const double dt = std::fabs(double(hc.t) - double(hb.t)) / diag;
    far += dt > 1e-4;
    if (dt > max_dt) {
      max_dt = dt;
      worst = m;
    }
  }
  std::printf(
      "   %s (%zu rays): hit/miss agree %zu (%.2f%%); only c hits %zu, only b hits %zu; both hit %zu, "
      "same kind %zu, max |dt|/diag %.3g, > 1e-4: %zu; c steps/ray %.1f, c capped %zu\n",
      label, n, agree, 100.0 * double(agree) / double(n), c_only, b_only, both, kinds, max_dt, far, c_steps / double(n),
      c_capped);
  const auto describe = [&](size_t m) {
    const size_t i = pixels[m];
    std::printf("     c: %s t = %.9g (steps %u, capped %d); b: %s t = %.9g (steps %u, crossings %u, capped %d)\n",
                kind_name(brute[m].kind), brute[m].t, brute[m].steps, int(brute[m].capped), kind_name(ghits[i].kind),
                ghits[i].t, ghits[i].steps, ghits[i].crossings, int(ghits[i].capped));
    print_ray("that", rays[i]);
  };
  if (worst != SIZE_MAX && max_dt > 1e-4) {
    std::printf("     largest |dt|:\n");
    describe(worst);
  }
  for (size_t j = 0; j < bad.size() && j < size_t(show); ++j) describe(bad[j]);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Ray tracing throughput: Embree on the mesh, gwnrt on S = ∂{w > level}, a brute-force Harnack tracer"};
  std::vector<std::string> meshes;
  int width = 256, height = 192;
  size_t brute_rays = 200;
  double brute_seconds = 120;
  int threads = 0;
  int show = 3;
  size_t check = 64;
  TraceOptions options;
  app.add_option("meshes", meshes,
                 "OBJ or PLY meshes (default: bunny.obj, bunny_holes.obj, teapot.obj from data/, and "
                 "/tmp/dragon_vrip.ply when it exists)");
  app.add_option("--width", width, "image width in pixels (one ray per pixel)")->check(gwnrt::apps::positive_number());
  app.add_option("--height", height, "image height in pixels")->check(gwnrt::apps::positive_number());
  app.add_option("--brute-rays", brute_rays, "rays of the brute-force tracer: every k-th pixel")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--brute-seconds", brute_seconds,
                 "time budget of the brute-force tracer per mesh (it stops after the rays started by then)")
      ->check(gwnrt::apps::positive_number());
  app.add_option("--threads", threads, "worker threads (default: all cores)")->check(gwnrt::apps::thread_count());
  app.add_option("--eps", options.epsilon, "stopping distance relative to the box diagonal")
      ->check(gwnrt::apps::trace_epsilon_number());
  app.add_option("--beta", options.beta, "accuracy scale of gwnrt's multipole evaluation")
      ->check(gwnrt::apps::beta_number());
  app.add_option("--level", options.level, "the level w* of S = ∂{w > w*}")->check(gwnrt::apps::trace_level_number());
  app.add_option("--check", check,
                 "after the timings, also trace with the brute force up to this many of the rays where (a) and (b) "
                 "disagree or (b) is capped, hits a smooth piece or takes Harnack steps")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--show", show, "disagreeing rays printed per comparison")->check(CLI::NonNegativeNumber);
  if (const auto status = apps::parse_command_line(app, argc, argv)) return *status;
  if (Status s = validate_trace_options(options); !s.ok()) apps::die(kProgram, s.message());
  // Checked before allocating, against the arrays each pixel has: its ray, the hits of (a) and (b),
  // and at most one entry in the check's groups and the step statistics (a bad_alloc otherwise).
  const uint64_t per_pixel = sizeof(Ray) + sizeof(SimpleHit) + sizeof(RayHit) + sizeof(size_t) + sizeof(uint32_t);
  if (Status s = check_memory(saturating_product(saturating_product(uint64_t(width), uint64_t(height)), per_pixel),
                              "--width " + std::to_string(width) + " --height " + std::to_string(height) + ": " +
                                  "the arrays of " + std::to_string(uint64_t(width) * uint64_t(height)) + " rays");
      !s.ok())
    apps::die(kProgram, s.message());

  if (meshes.empty()) {
    for (const char* name : {"bunny.obj", "bunny_holes.obj", "teapot.obj"})
      meshes.push_back(std::string(GWNRT_DATA_DIR) + "/" + name);
    if (std::filesystem::exists("/tmp/dragon_vrip.ply")) meshes.push_back("/tmp/dragon_vrip.ply");
  }
  if (const std::string bad = apps::first_bad_input_file(meshes); !bad.empty()) apps::die(kProgram, bad);

  const apps::ThreadLimit limit(threads);
  const int workers = int(limit.workers());
  std::printf("%s: %dx%d rays per mesh, %d threads, level %g, eps %g (of the box diagonal), beta %g\n", kProgram, width,
              height, workers, options.level, options.epsilon, options.beta);
#if !defined(GWNRT_HAVE_EMBREE)
  std::printf("(built without Embree: column (a) is empty)\n");
#endif

  std::vector<MeshSummary> summaries;
  for (const std::string& path : meshes) {
    // --- load and build
    GwnModel model;
    apps::ModelLoad loaded;
    if (Status s = apps::load_model(path, model, loaded); !s.ok()) apps::die(kProgram, s.message());
    apps::print_load_warnings(kProgram, path, loaded.report);
    const MeshLoadReport& report = loaded.report;
    const double load_sec = loaded.load_seconds, build_sec = loaded.build_seconds;
    const ModelView view = model.view();
    const float diag = glm::length(model.bounds().hi - model.bounds().lo);
    MeshSummary sum;
    sum.name = mesh_label(path);
    sum.triangles = model.mesh().triangles.size();

    std::printf("\n== %s: %zu triangles (%zu degenerate), %zu boundary segments, box diagonal %.4g\n", path.c_str(),
                sum.triangles, report.degenerate_triangles, model.boundary().segment_count(), diag);
    std::printf("   load %.3f s; gwnrt build %.3f s (tree + moments %.3f s, boundary + cone %.3f s)", load_sec,
                build_sec, model.timings().tree_seconds, model.timings().boundary_seconds);

    // --- rays: one per pixel, gwnrt-render's camera
    const render::PinholeCamera camera = render::frame_box(model.bounds(), width, height);
    std::vector<Ray> rays;
    rays.reserve(size_t(width) * size_t(height));
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) rays.push_back(camera.ray(x, y));

    // --- (a) Embree
    std::vector<SimpleHit> ehits;
#if defined(GWNRT_HAVE_EMBREE)
    {
      const render::TriangleScene embree(model.mesh(), threads);
      if (Status st = embree.status(); !st.ok()) apps::die(kProgram, st.message());
      std::printf("; Embree build %.3f s\n", embree.build_seconds());
      sum.a = best_of_3(rays.size(), [&] { return trace_embree(embree, rays, ehits); });
    }
#else
    std::printf("\n");
#endif

    // --- (b) gwnrt
    std::vector<RayHit> ghits;
    {
      sum.b = best_of_3(rays.size(), [&] { return trace_gwnrt(model, rays, options, ghits); });
    }

    // --- (c) brute force: every k-th pixel, visited in a fixed order spread over the image (a
    // golden-ratio stride), so that a prefix cut short by the budget still covers the image.
    const size_t n_sub = std::min(brute_rays, rays.size());
    std::vector<size_t> subset;  // pixel indices, in visiting order
    if (n_sub > 0) {
      const size_t k = rays.size() / n_sub;
      size_t stride = std::max<size_t>(1, size_t(0.6180339887 * double(n_sub)));
      while (std::gcd(stride, n_sub) != 1) ++stride;
      for (size_t m = 0; m < n_sub; ++m) subset.push_back(((m * stride) % n_sub) * k + k / 2);
    }
    const reference::BruteForceTracer brute(view);
    std::vector<RayHit> bhits;
    sum.c = brute_trace(brute, rays, subset, options, brute_seconds, workers, bhits);
    const size_t brute_done = sum.c.rays;
    // gwnrt on the very same subset, repeated until it takes measurable time.
    if (brute_done > 0) {
      std::vector<Ray> sub_rays;
      for (size_t m = 0; m < brute_done; ++m) sub_rays.push_back(rays[subset[m]]);
      std::vector<RayHit> tmp;
      sum.b_subset = best_of_3(sub_rays.size(), [&] { return trace_gwnrt(model, sub_rays, options, tmp); });
    }

    // --- table
    const auto row = [](const char* name, const Rate& r, const char* note) {
      std::printf("   %-30s %9zu %7zu %12.4g %12.4g%s\n", name, r.passes ? r.rays / r.passes : 0, r.passes,
                  r.pass_seconds(), r.per_second(), note);
    };
    std::printf("   %-30s %9s %7s %12s %12s\n", "tracer", "rays", "passes", "s per pass", "rays/s");
#if defined(GWNRT_HAVE_EMBREE)
    row("(a) Embree rtcIntersect1", sum.a, "");
#endif
    row("(b) gwnrt trace_rays", sum.b, "");
    row("(c) brute-force Harnack", sum.c, brute_done < subset.size() ? "   (cut short by --brute-seconds)" : "");
    row("(b) gwnrt on (c)'s rays", sum.b_subset, "");
    std::printf("   b/a = %s   b/c = %s   (b on c's rays)/c = %s\n",
                fmt_rate(sum.b.per_second() / sum.a.per_second()).c_str(),
                fmt_rate(sum.b.per_second() / sum.c.per_second()).c_str(),
                fmt_rate(sum.b_subset.per_second() / sum.c.per_second()).c_str());

    // gwnrt statistics
    size_t g_sheet = 0, g_smooth = 0, g_capped = 0, g_invalid = 0;
    double steps = 0, crossings = 0;
    uint32_t max_steps = 0;
    for (const RayHit& h : ghits) {
      g_sheet += h.hit && h.kind == HitKind::kSheet;
      g_smooth += h.hit && h.kind == HitKind::kSmooth;
      g_capped += h.capped;
      g_invalid += h.invalid;
      steps += h.steps;
      crossings += h.crossings;
      max_steps = std::max(max_steps, h.steps);
    }
    std::printf(
        "   gwnrt: hits %zu (sheet %zu, smooth %zu) of %zu; steps/ray %.3f (max %u), crossings/ray %.3f; "
        "capped %zu, invalid %zu\n",
        g_sheet + g_smooth, g_sheet, g_smooth, ghits.size(), steps / double(ghits.size()), max_steps,
        crossings / double(ghits.size()), g_capped, g_invalid);
    {
      // Where the Harnack steps go: their distribution over the rays that take any.
      std::vector<uint32_t> stepped;
      for (const RayHit& h : ghits)
        if (h.steps > 0) stepped.push_back(h.steps);
      if (!stepped.empty()) {
        std::sort(stepped.begin(), stepped.end());
        const auto pct = [&](double q) {
          return stepped[std::min(stepped.size() - 1, size_t(q * double(stepped.size())))];
        };
        const size_t top = std::max<size_t>(1, stepped.size() / 100);
        double top_steps = 0;
        for (size_t j = stepped.size() - top; j < stepped.size(); ++j) top_steps += stepped[j];
        std::printf(
            "   gwnrt rays with Harnack steps: %zu; steps p50 %u, p90 %u, p99 %u; the top 1%% of them take %.1f%% "
            "of all steps\n",
            stepped.size(), pct(0.5), pct(0.9), pct(0.99), 100.0 * top_steps / steps);
      }
    }
    for (size_t i = 0, shown = 0; i < ghits.size() && shown < size_t(show); ++i)
      if (ghits[i].capped) {
        print_ray("capped gwnrt", rays[i]);
        ++shown;
      }

#if defined(GWNRT_HAVE_EMBREE)
    // (a) vs (b): all rays
    {
      size_t agree = 0, both = 0, a_only = 0, b_only = 0, sheet_both = 0, sheet_off = 0, smooth_where_a = 0;
      double max_dt_sheet = 0, max_dt_all = 0;
      size_t worst_sheet = SIZE_MAX;
      std::vector<size_t> missed;
      for (size_t i = 0; i < rays.size(); ++i) {
        const bool ha = ehits[i].hit, hb = ghits[i].hit;
        agree += ha == hb;
        if (ha && !hb) {
          ++a_only;
          missed.push_back(i);
        }
        if (hb && !ha) ++b_only;
        if (!(ha && hb)) continue;
        ++both;
        const double dt = std::fabs(double(ehits[i].t) - double(ghits[i].t)) / diag;
        max_dt_all = std::max(max_dt_all, dt);
        if (ghits[i].kind == HitKind::kSheet) {
          ++sheet_both;
          if (dt > max_dt_sheet) {
            max_dt_sheet = dt;
            worst_sheet = i;
          }
          sheet_off += dt > 1e-4;
        } else {
          ++smooth_where_a;
        }
      }
      std::printf("   a vs b (all %zu rays): hit/miss agree %zu (%.3f%%); only a hits %zu, only b hits %zu\n",
                  rays.size(), agree, 100.0 * double(agree) / double(rays.size()), a_only, b_only);
      std::printf(
          "     both hit %zu: b sheet %zu, max |dt|/diag %.3g, of them off a's first triangle (> 1e-4) %zu; "
          "b smooth %zu (of b's %zu smooth hits); max |dt|/diag over all both-hit %.3g\n",
          both, sheet_both, max_dt_sheet, sheet_off, smooth_where_a, g_smooth, max_dt_all);
      if (worst_sheet != SIZE_MAX && max_dt_sheet > 1e-4) {
        std::printf("     largest sheet |dt|: a t = %.9g, b t = %.9g (b steps %u, crossings %u)\n",
                    ehits[worst_sheet].t, ghits[worst_sheet].t, ghits[worst_sheet].steps, ghits[worst_sheet].crossings);
        print_ray("that", rays[worst_sheet]);
      }
      for (size_t j = 0; j < missed.size() && j < size_t(show); ++j) {
        const size_t i = missed[j];
        std::printf("     a hits at t = %.9g, b misses (capped %d, steps %u, crossings %u)\n", ehits[i].t,
                    int(ghits[i].capped), ghits[i].steps, ghits[i].crossings);
        print_ray("that", rays[i]);
      }
    }
#endif

    // (c) vs (b): the brute-force subset
    if (brute_done > 0) compare_with_brute("c vs b", rays, subset, bhits, ghits, diag, show);

    // The rays most likely to show a problem, checked by the brute-force tracer too (not timed).
    if (check > 0) {
      // Three groups, in this priority: (a)/(b) hit-miss disagreements and capped rays; (b)'s
      // smooth hits; (b)'s other rays that took Harnack steps (where a smooth hit could be missed).
      std::vector<size_t> groups[3];
      for (size_t i = 0; i < rays.size(); ++i) {
        bool disagree = ghits[i].capped;
#if defined(GWNRT_HAVE_EMBREE)
        disagree = disagree || ehits[i].hit != ghits[i].hit;
#endif
        if (disagree)
          groups[0].push_back(i);
        else if (ghits[i].hit && ghits[i].kind == HitKind::kSmooth)
          groups[1].push_back(i);
        else if (ghits[i].steps > 0)
          groups[2].push_back(i);
      }
      const auto take_evenly = [](const std::vector<size_t>& from, size_t count, std::vector<size_t>& into) {
        count = std::min(count, from.size());
        for (size_t j = 0; j < count; ++j) into.push_back(from[j * from.size() / count]);
      };
      std::vector<size_t> picked;
      take_evenly(groups[0], check, picked);
      const size_t left = check - picked.size();
      const size_t smooth_share = std::max(left / 2, left - std::min(left, groups[2].size()));
      take_evenly(groups[1], smooth_share, picked);
      take_evenly(groups[2], check - picked.size(), picked);
      if (!picked.empty()) {
        std::vector<RayHit> chits;
        const Rate r = brute_trace(brute, rays, picked, options, brute_seconds, workers, chits);
        picked.resize(r.rays);
        char label[160];
        std::snprintf(label, sizeof label, "check (%zu a/b disagree or capped, %zu smooth, %zu stepped; %.1f s)",
                      groups[0].size(), groups[1].size(), groups[2].size(), r.seconds);
        if (!picked.empty()) compare_with_brute(label, rays, picked, chits, ghits, diag, show);
      }
    }
    std::fflush(stdout);
    summaries.push_back(sum);
  }

  std::printf("\n%-20s %10s %12s %12s %12s %10s %10s %14s\n", "mesh", "triangles", "a rays/s", "b rays/s", "c rays/s",
              "b/a", "b/c", "b/c same rays");
  for (const MeshSummary& s : summaries)
    std::printf("%-20s %10zu %12s %12s %12s %10s %10s %14s\n", s.name.c_str(), s.triangles,
                fmt_rate(s.a.per_second()).c_str(), fmt_rate(s.b.per_second()).c_str(),
                fmt_rate(s.c.per_second()).c_str(), fmt_rate(s.b.per_second() / s.a.per_second()).c_str(),
                fmt_rate(s.b.per_second() / s.c.per_second()).c_str(),
                fmt_rate(s.b_subset.per_second() / s.c.per_second()).c_str());
  return 0;
}
