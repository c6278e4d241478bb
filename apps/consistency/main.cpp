// gwnrt-consistency: the same meshes, points and rays through the CPU backend and the GPU backend,
// quantity by quantity (w by each method, ∇w, H_w, the distances, sdf and its parts, ρ, the
// Newton projection, the trace's hit, t, normal and kind, the mesher's counts and vertices): the
// largest and mean differences, how many items agree within the quantity's tolerance, and each
// backend's throughput. Both backends run the same GWNRT_HD functions, so they differ only by
// float rounding (fused multiply-adds, the math libraries' last bits); the tolerances are those
// of tests/cuda, and an item may fall outside where rounding flips a discrete choice (a ray
// grazing S, a point on a sheet): at most 0.1% of them.
//
// Exit status: 0 all within tolerance, 1 some quantity beyond it, 2 no usable GPU (the reason on
// stderr). `--against cpu` compares the CPU with itself, which checks this program where no GPU
// is usable (its differences are 0). Free of Embree and OpenImageIO: it builds where only CUDA,
// TBB and GLM are (scripts/gpu-check.sh).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include <tbb/parallel_for.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "apps/common/cli_checks.h"
#include "apps/common/load_model.h"
#include "apps/common/point_io.h"
#include "apps/common/program.h"
#include "gwnrt/engine.h"
#include "gwnrt/meshing/extract_surface.h"
#include "gwnrt/meshing/mesh_comparison.h"
#include "gwnrt/query/batch.h"
#include "reference/point_mix.h"
#include "render/camera.h"
#include "render/integrators/first_hit_cuda.h"
#include "render/integrators/first_hit_pixel.h"

namespace {

using namespace gwnrt;
using apps::seconds_since;

constexpr const char* kProgram = "gwnrt-consistency";
constexpr double kMinAgreement = 0.999;  // items within tolerance, per quantity

// Exit statuses: 0 consistent, kExitInconsistent, kExitNoGpu, kExitError. An error (a flag, a file
// that cannot be read or written) has its own, so that a script tells a disagreement between the
// backends from a mistyped path.
constexpr int kExitInconsistent = 1, kExitNoGpu = 2, kExitError = 3;

int error(const std::string& message) {
  apps::fail(kProgram, message);
  return kExitError;
}

// The three things a backend does, bound to its model.
struct Backend {
  std::string name;
  std::function<Status(std::span<const vec3>, const QueryRequest&, std::span<PointResult>)> points;
  std::function<Status(std::span<const Ray>, const TraceOptions&, std::span<RayHit>)> rays;
  std::function<Status(const MeshingOptions&, SurfaceMesh&, MeshingStats&)> mesh;
  // gwnrt-render's first-hit pixels, `frames` times; seconds: one frame's.
  std::function<Status(const render::PinholeCamera&, const render::FirstHitSettings&, int,
                       std::vector<render::FirstHitSample>&, double&)>
      first_hit;
};

// The batches of `engine` on `device` (kCpu or kCuda), and gwnrt-render's first-hit pixels there.
Backend backend_on(const Engine& engine, Device device) {
  Backend b{device_name(device),
            [&engine, device](std::span<const vec3> p, const QueryRequest& q, std::span<PointResult> r) {
              return engine.evaluate_points(device, p, q, r);
            },
            [&engine, device](std::span<const Ray> r, const TraceOptions& o, std::span<RayHit> h) {
              return engine.trace_rays(device, r, o, h);
            },
            [&engine, device](const MeshingOptions& o, SurfaceMesh& m, MeshingStats& s) {
              return engine.extract_surface(device, o, m, &s);
            },
            {}};
  if (device == Device::kCuda) {
    b.first_hit = [&engine](const render::PinholeCamera& camera, const render::FirstHitSettings& settings, int frames,
                            std::vector<render::FirstHitSample>& pixels, double& seconds) {
      const cuda::DeviceModel* model = nullptr;
      if (Status s = engine.device_model(model); !s.ok()) return s;
      return render::render_first_hit_cuda(*model, camera, settings, frames, pixels, seconds);
    };
    return b;
  }
  b.first_hit = [&engine](const render::PinholeCamera& camera, const render::FirstHitSettings& settings, int frames,
                          std::vector<render::FirstHitSample>& pixels, double& seconds) {
    const ModelView view = engine.model().view();
    pixels.resize(size_t(camera.width) * size_t(camera.height));
    const auto t0 = std::chrono::steady_clock::now();
    for (int f = 0; f < frames; ++f)
      tbb::parallel_for(0, camera.height, [&](int y) {
        for (int x = 0; x < camera.width; ++x)
          pixels[size_t(y) * size_t(camera.width) + size_t(x)] = render::first_hit_pixel(view, camera, settings, x, y);
      });
    seconds = seconds_since(t0) / frames;
    return Status::Ok();
  };
  return b;
}

// One quantity's comparison: per item a difference already scaled so that the tolerance applies
// to it (NaN: the item does not count, as when neither backend has a value).
struct Row {
  std::string mesh, quantity, unit;
  double tolerance = 0;
  size_t items = 0, agree = 0;
  double max_diff = 0, sum_diff = 0;
  double cpu_per_second = 0, gpu_per_second = 0;

  void add(double diff) {
    if (std::isnan(diff)) return;
    ++items;
    agree += diff <= tolerance;
    max_diff = std::max(max_diff, diff);
    sum_diff += diff;
  }
  double agreement() const { return items ? double(agree) / double(items) : 1.0; }
  bool passes() const { return agreement() >= kMinAgreement; }
};

struct Timed {
  double cpu = 0, gpu = 0;  // seconds
};

double relative(double a, double b, double scale) {
  if (std::isinf(a) && std::isinf(b) && (a > 0) == (b > 0)) return 0.0;
  return std::abs(a - b) / scale;
}

double frobenius(const sym3& h) {
  return std::sqrt(double(h.xx * h.xx + h.yy * h.yy + h.zz * h.zz) +
                   2.0 * double(h.xy * h.xy + h.xz * h.xz + h.yz * h.yz));
}

class Comparison {
 public:
  Comparison(std::string mesh, const Backend& a, const Backend& b) : mesh_(std::move(mesh)), a_(a), b_(b) {}

  // Both backends on `points` for `request`; each field compared by `diffs`.
  Status points(const std::string& group, std::span<const vec3> points, const QueryRequest& request,
                const std::function<void(const PointResult&, const PointResult&, std::vector<Row>&)>& diffs,
                std::vector<Row> rows) {
    std::vector<PointResult> ra(points.size()), rb(points.size());
    Timed t;
    if (Status s = timed(t.cpu, [&] { return a_.points(points, request, ra); }); !s.ok()) return named(group, s);
    if (Status s = timed(t.gpu, [&] { return b_.points(points, request, rb); }); !s.ok()) return named(group, s);
    for (size_t i = 0; i < points.size(); ++i) diffs(ra[i], rb[i], rows);
    finish(rows, points.size(), t);
    return Status::Ok();
  }

  Status rays(std::span<const Ray> rays, const TraceOptions& options, float diagonal) {
    std::vector<RayHit> ha(rays.size()), hb(rays.size());
    Timed t;
    if (Status s = timed(t.cpu, [&] { return a_.rays(rays, options, ha); }); !s.ok()) return named("trace", s);
    if (Status s = timed(t.gpu, [&] { return b_.rays(rays, options, hb); }); !s.ok()) return named("trace", s);
    std::vector<Row> rows = {{mesh_, "trace hit", "0/1", 0.0},
                             {mesh_, "trace kind", "0/1", 0.0},
                             {mesh_, "trace t", "tolerances", 1.0},
                             {mesh_, "trace normal", "rad", 1e-2}};
    const double eps = double(options.epsilon) * diagonal;
    for (size_t i = 0; i < rays.size(); ++i) {
      const RayHit &x = ha[i], &y = hb[i];
      rows[0].add(x.hit != y.hit);
      if (!(x.hit && y.hit)) continue;
      rows[1].add(x.kind != y.kind);
      if (x.kind != y.kind) continue;
      const double dt = std::abs(double(x.t) - double(y.t)) * glm::length(rays[i].direction);
      // A sheet hit to round-off (1e-6 of the diagonal, over |cos|: the crossing of a triangle
      // met at an angle moves along the ray by its rounding across it over the cosine); a smooth
      // one within a few stopping distances along the ray, ε / |cos| likewise. Grazing rays are
      // left out (with the sheets' round-off unscaled, 5 of the teapot's 5410 sheet hits were
      // beyond it with and without fused multiply-adds on the CPU, all grazing).
      const double cosine = std::abs(double(glm::dot(x.normal, glm::normalize(rays[i].direction))));
      if (cosine > 0.05) rows[2].add(dt * cosine / (x.kind == HitKind::kSheet ? 1e-6 * diagonal : 4.0 * eps));
      // The angle between unit normals from their chord (acos of a dot product near 1 is off by
      // 7e-4 rad for identical floats).
      rows[3].add(2.0 * std::asin(std::min(1.0, 0.5 * double(glm::length(x.normal - y.normal)))));
    }
    finish(rows, rays.size(), t);
    return Status::Ok();
  }

  Status mesh(const MeshingOptions& options) {
    SurfaceMesh ma, mb;
    MeshingStats sa, sb;
    Timed t;
    if (Status s = timed(t.cpu, [&] { return a_.mesh(options, ma, sa); }); !s.ok()) return named("meshing", s);
    if (Status s = timed(t.gpu, [&] { return b_.mesh(options, mb, sb); }); !s.ok()) return named("meshing", s);
    // Vertices to 2e-3 of a cell: rounding alone (the CPU code with and without fused multiply-
    // adds) moved the worst by up to 4e-4 cells and a few percent by more than 1e-5
    // (tests/cuda/test_cuda_meshing.cpp); the max and mean columns say how close they came.
    std::vector<Row> rows = {{mesh_, "mesh vertex count", "vertices", 0.0},
                             {mesh_, "mesh triangle count", "triangles", 0.0},
                             {mesh_, "mesh triangles", "0/1", 0.0},
                             {mesh_, "mesh vertex offset", "cells", 2e-3}};
    rows[0].add(std::abs(double(ma.positions.size()) - double(mb.positions.size())));
    rows[1].add(std::abs(double(ma.triangles.size()) - double(mb.triangles.size())));
    if (ma.positions.size() == mb.positions.size() && ma.triangles.size() == mb.triangles.size()) {
      // A quad split along its other diagonal (a near tie that rounding decides) is the same mesh.
      const TriangleComparison c = compare_triangles(ma.triangles, mb.triangles);
      for (size_t i = 0; i < c.same + 2 * c.resplit; ++i) rows[2].add(0.0);
      for (size_t i = 0; i < c.different; ++i) rows[2].add(1.0);
      for (size_t i = 0; i < ma.positions.size(); ++i)
        rows[3].add(glm::length(ma.positions[i] - mb.positions[i]) / sa.cell_size);
    }
    // Counts and triangles exactly, all or nothing: the same mesh up to rounding has the same
    // topology (the 99.9% allowance is for items that rounding may flip, not for a mesh).
    for (size_t k = 0; k < 3; ++k)
      if (rows[k].agree != rows[k].items) rows[k].agree = 0;
    finish(rows, std::max<size_t>(1, ma.triangles.size()), t);
    return Status::Ok();
  }

  // gwnrt-render's first hit: hit or miss, kind, colour; the rates are frames a second.
  Status first_hit(const render::PinholeCamera& camera, int frames) {
    std::vector<render::FirstHitSample> pa, pb;
    const render::FirstHitSettings settings;
    Timed t;
    if (Status s = a_.first_hit(camera, settings, frames, pa, t.cpu); !s.ok()) return named("first hit", s);
    if (Status s = b_.first_hit(camera, settings, frames, pb, t.gpu); !s.ok()) return named("first hit", s);
    const std::string frame = std::to_string(camera.width) + "x" + std::to_string(camera.height);
    std::vector<Row> rows = {{mesh_, "first-hit hit " + frame, "0/1", 0.0},
                             {mesh_, "first-hit kind " + frame, "0/1", 0.0},
                             {mesh_, "first-hit colour " + frame, "max channel", 1e-2}};
    for (size_t i = 0; i < pa.size(); ++i) {
      const bool ha = pa[i].trace.kind != HitKind::kNone, hb = pb[i].trace.kind != HitKind::kNone;
      rows[0].add(ha != hb);
      if (!(ha && hb)) continue;
      rows[1].add(pa[i].trace.kind != pb[i].trace.kind);
      const vec3 d = glm::abs(pa[i].colour - pb[i].colour);
      rows[2].add(std::max({d.x, d.y, d.z}));
    }
    finish(rows, 1, t);  // one item a frame: the rates are frames per second
    return Status::Ok();
  }

  std::vector<Row>& rows() { return rows_; }

 private:
  template <class Fn>
  static Status timed(double& seconds, Fn fn) {
    const auto t0 = std::chrono::steady_clock::now();
    Status s = fn();
    seconds = seconds_since(t0);
    return s;
  }
  Status named(const std::string& what, const Status& s) const {
    return {s.code(), mesh_ + ": " + what + ": " + s.message()};
  }
  void finish(std::vector<Row>& rows, size_t items, const Timed& t) {
    for (Row& r : rows) {
      r.cpu_per_second = t.cpu > 0 ? double(items) / t.cpu : 0.0;
      r.gpu_per_second = t.gpu > 0 ? double(items) / t.gpu : 0.0;
      rows_.push_back(r);
    }
  }

  std::string mesh_;
  const Backend &a_, &b_;
  std::vector<Row> rows_;
};

Status compare_mesh(const std::string& path, const Backend& cpu, const Backend& other,
                    const std::vector<vec3>* given_points, const std::vector<Ray>* given_rays, size_t count,
                    uint32_t resolution, int image_width, int image_height, const GwnModel& model,
                    std::vector<Row>& all) {
  const Aabb box = model.bounds();
  const float diag = glm::length(box.hi - box.lo);
  const std::vector<vec3> points = given_points ? *given_points : point_mix(box, count, 7);
  Comparison c(path, cpu, other);
  using Rows = std::vector<Row>;
  const auto row = [&](const char* q, const char* unit, double tol) { return Row{path, q, unit, tol}; };

  for (const WindingMethod method : {WindingMethod::kTaylor, WindingMethod::kCrossing, WindingMethod::kBrute}) {
    QueryRequest r;
    r.fields = kFieldW | kFieldGradient | kFieldHessian;
    r.method = method;
    const std::string name = winding_method_name(method);
    // The brute force sums every triangle per point: a few thousand points say enough.
    const std::span<const vec3> some = method == WindingMethod::kBrute
                                           ? std::span<const vec3>(points).first(std::min<size_t>(points.size(), 2000))
                                           : std::span<const vec3>(points);
    Rows rows = {row(("w, " + name).c_str(), "|dw|", 1e-4), row(("grad w, " + name).c_str(), "rel. to 1/diag", 1e-3),
                 row(("hessian w, " + name).c_str(), "rel. to 1/diag^2", 1e-2)};
    if (Status s = c.points(
            "w by " + name, some, r,
            [&](const PointResult& a, const PointResult& b, Rows& out) {
              out[0].add(std::abs(double(a.w) - double(b.w)));
              out[1].add(double(glm::length(a.gradient - b.gradient)) * diag / (1.0 + glm::length(a.gradient) * diag));
              sym3 d = a.hessian;
              d.xx -= b.hessian.xx, d.xy -= b.hessian.xy, d.xz -= b.hessian.xz;
              d.yy -= b.hessian.yy, d.yz -= b.hessian.yz, d.zz -= b.hessian.zz;
              out[2].add(frobenius(d) * diag * diag / (1.0 + frobenius(a.hessian) * diag * diag));
            },
            rows);
        !s.ok())
      return s;
  }
  {
    QueryRequest r;
    r.fields = kFieldUnsignedDistance | kFieldBoundaryDistance;
    Rows rows = {row("unsigned distance", "/diag", 1e-6), row("boundary distance", "/diag", 1e-6)};
    if (Status s = c.points(
            "distances", points, r,
            [&](const PointResult& a, const PointResult& b, Rows& out) {
              out[0].add(relative(a.unsigned_distance, b.unsigned_distance, diag));
              out[1].add(relative(a.boundary_distance, b.boundary_distance, diag));
            },
            rows);
        !s.ok())
      return s;
  }
  {
    QueryRequest r;
    r.fields = kFieldSignedDistance | kFieldPseudoDistance | kFieldHarnackBound;
    Rows rows = {row("sdf", "rel.", 1e-4),  row("sdf sign", "0/1", 0.0),          row("sdf1", "rel.", 1e-3),
                 row("sdf2", "rel.", 1e-3), row("sheet distance", "/diag", 1e-6), row("harnack bound", "rel.", 1e-4)};
    if (Status s = c.points(
            "signed distance", points, r,
            [&](const PointResult& a, const PointResult& b, Rows& out) {
              const auto rel = [&](float x, float y) {
                if (std::isnan(x) && std::isnan(y)) return std::nan("");
                return relative(x, y, diag + std::abs(double(x)));
              };
              out[0].add(rel(a.sdf.distance, b.sdf.distance));
              out[1].add(std::signbit(a.sdf.distance) != std::signbit(b.sdf.distance));
              out[2].add(rel(a.sdf.first_order, b.sdf.first_order));
              out[3].add(rel(a.sdf.second_order, b.sdf.second_order));
              out[4].add(relative(a.sdf.sheet_distance, b.sdf.sheet_distance, diag));
              out[5].add(rel(a.harnack_bound, b.harnack_bound));
            },
            rows);
        !s.ok())
      return s;
  }
  {
    QueryRequest r;
    r.fields = kFieldProjection;
    // Newton stops anywhere within |w − w*| <= its tolerance: one iteration apart is ~1e-3 diag.
    Rows rows = {row("projection converged", "0/1", 0.0), row("projection point", "/diag", 1e-3)};
    if (Status s = c.points(
            "projection", points, r,
            [&](const PointResult& a, const PointResult& b, Rows& out) {
              out[0].add(a.projection.converged != b.projection.converged);
              if (a.projection.converged && b.projection.converged)
                out[1].add(glm::length(a.projection.point - b.projection.point) / diag);
            },
            rows);
        !s.ok())
      return s;
  }
  std::vector<Ray> rays;
  if (given_rays) {
    rays = *given_rays;
  } else {
    for (const float azimuth : {30.0f, 150.0f, 260.0f}) {
      const render::PinholeCamera camera = render::frame_box(box, 200, 150, azimuth, 20.0f);
      for (int y = 0; y < camera.height; ++y)
        for (int x = 0; x < camera.width; ++x) rays.push_back(camera.ray(x, y));
    }
  }
  if (Status s = c.rays(rays, TraceOptions{}, diag); !s.ok()) return s;
  // Three frames, for the rate.
  if (image_width > 0) {
    if (Status s = c.first_hit(render::frame_box(box, image_width, image_height), 3); !s.ok()) return s;
  }
  if (resolution > 0) {
    MeshingOptions options;
    options.resolution = resolution;
    if (Status s = c.mesh(options); !s.ok()) return s;
  }
  for (Row& r : c.rows()) all.push_back(std::move(r));
  return Status::Ok();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Runs meshes, points and rays through the CPU and the GPU backends and prints, per quantity, the largest and "
      "mean difference, the share of items within tolerance and both throughputs. Exit 0: consistent; 1: a quantity "
      "beyond its tolerance; 2: no usable GPU.",
      kProgram};
  std::vector<std::string> meshes;
  std::string points_path, rays_path, json_path, against = "cuda";
  size_t count = 100000;
  uint32_t resolution = 128;
  int threads = 0;
  app.add_option("--mesh", meshes, "Meshes (OBJ/PLY; default: the bundled bunny, bunny_holes and teapot)");
  app.add_option("--points", points_path, "Query points, one 'x y z' a line (default: --count of the benchmarks' mix)");
  app.add_option("--rays", rays_path, "Rays, 'ox oy oz dx dy dz [tnear tfar]' a line (default: three camera views)");
  app.add_option("--count", count, "Generated points per mesh")->capture_default_str()->check(CLI::Range(1, 100000000));
  app.add_option("--resolution", resolution, "Meshing grid (cells along the longest side; 0: no meshing)")
      ->capture_default_str()
      ->check(CLI::Range(0, 2048));
  int image_width = 1920, image_height = 1080;
  app.add_option("--image-width", image_width, "gwnrt-render's first hit at this width (0: none)")
      ->capture_default_str()
      ->check(CLI::Range(0, 16384));
  app.add_option("--image-height", image_height, "and height")->capture_default_str()->check(CLI::Range(1, 16384));
  app.add_option("--threads", threads, "CPU threads (default: all)")->check(apps::thread_count());
  app.add_option("--against", against, "The second backend: cuda, or cpu to check this program without a GPU")
      ->capture_default_str()
      ->check(CLI::IsMember({"cuda", "cpu"}));
  app.add_option("--json", json_path, "Also write every row to this JSON file");
  if (const auto status = apps::parse_command_line(app, argc, argv, kExitError)) return *status;

  if (against == "cuda") {
    DeviceChoice gpu;
    if (Status s = choose_device(Device::kCuda, gpu); !s.ok()) {
      std::fprintf(stderr, "%s: no usable GPU, nothing to compare: %s\n", kProgram, s.message().c_str());
      return kExitNoGpu;
    }
  }
  if (meshes.empty())
    for (const char* m : {"bunny.obj", "bunny_holes.obj", "teapot.obj"})
      meshes.push_back(std::string(GWNRT_DATA_DIR) + "/" + m);
  const apps::ThreadLimit thread_limit(threads);
  std::vector<vec3> given_points;
  std::vector<Ray> given_rays;
  // Read once (standard input cannot be read again), parsed again for a recentred mesh.
  std::string points_text, points_source, rays_text, rays_source;
  if (!points_path.empty()) {
    if (Status s = apps::read_text(points_path, points_text, points_source); !s.ok()) return error(s.message());
    if (Status s = apps::parse_points(points_text, points_source, given_points); !s.ok()) return error(s.message());
  }
  if (!rays_path.empty()) {
    if (Status s = apps::read_text(rays_path, rays_text, rays_source); !s.ok()) return error(s.message());
    if (Status s = apps::parse_rays(rays_text, rays_source, given_rays); !s.ok()) return error(s.message());
  }

  std::vector<Row> rows;
  for (const std::string& path : meshes) {
    GwnModel model;
    apps::ModelLoad loaded;
    // Recentred when far off, as the other programs do; given points and rays are then read
    // again, moved by the mesh's origin (both backends answer about the same moved model).
    if (Status s = apps::load_model(path, model, loaded, {}, MeshLoadOptions{.recentre = true}); !s.ok())
      return error(s.message());
    apps::print_load_warnings(kProgram, path, loaded.report, false);
    const dvec3 origin = loaded.report.origin;
    std::vector<vec3> moved_points;
    std::vector<Ray> moved_rays;
    if (origin != dvec3(0.0) && !points_path.empty()) {
      if (Status s = apps::parse_points(points_text, points_source, moved_points, origin); !s.ok())
        return error(s.message());
    }
    if (origin != dvec3(0.0) && !rays_path.empty()) {
      if (Status s = apps::parse_rays(rays_text, rays_source, moved_rays, origin); !s.ok()) return error(s.message());
    }
    const std::vector<vec3>& points = origin != dvec3(0.0) ? moved_points : given_points;
    const std::vector<Ray>& rays = origin != dvec3(0.0) ? moved_rays : given_rays;
    const Engine engine(std::move(model));
    const Backend cpu = backend_on(engine, Device::kCpu);
    const Backend other = backend_on(engine, against == "cuda" ? Device::kCuda : Device::kCpu);
    if (against == "cuda") {
      if (Status s = engine.upload(); !s.ok()) return error(path + ": " + s.message());
    }
    if (Status s =
            compare_mesh(path, cpu, other, points_path.empty() ? nullptr : &points, rays_path.empty() ? nullptr : &rays,
                         count, resolution, image_width, image_height, engine.model(), rows);
        !s.ok())
      return error(s.message());
  }

  const std::string second = against == "cuda" ? "gpu" : "cpu again";
  std::printf("%-22s %-24s %10s %10s %10s %9s %12s %12s %8s\n", "mesh", "quantity", "max diff", "mean diff",
              "tolerance", "agree", "cpu items/s", (second + " /s").c_str(), "ratio");
  bool all_pass = true;
  nlohmann::json json = nlohmann::json::array();
  for (const Row& r : rows) {
    const std::string mesh = r.mesh.substr(r.mesh.find_last_of('/') + 1);
    const double mean = r.items ? r.sum_diff / double(r.items) : 0.0;
    const double ratio = r.cpu_per_second > 0 ? r.gpu_per_second / r.cpu_per_second : 0.0;
    std::printf("%-22s %-24s %10.3g %10.3g %10.3g %8.4f%s %12.4g %12.4g %8.3g\n", mesh.c_str(), r.quantity.c_str(),
                r.max_diff, mean, r.tolerance, r.agreement(), r.passes() ? " " : "!", r.cpu_per_second,
                r.gpu_per_second, ratio);
    all_pass = all_pass && r.passes();
    json.push_back({{"mesh", r.mesh},
                    {"quantity", r.quantity},
                    {"unit", r.unit},
                    {"items", r.items},
                    {"max_diff", r.max_diff},
                    {"mean_diff", mean},
                    {"tolerance", r.tolerance},
                    {"agreement", r.agreement()},
                    {"passes", r.passes()},
                    {"cpu_per_second", r.cpu_per_second},
                    {"other_per_second", r.gpu_per_second},
                    {"other_over_cpu", ratio}});
  }
  std::printf("%s (agreement: the share of items within tolerance, at least %.1f%% each; '!' marks a failure)\n",
              all_pass ? "consistent" : "NOT consistent", 100.0 * kMinAgreement);
  if (!json_path.empty()) {
    const nlohmann::json doc = {{"against", against}, {"min_agreement", kMinAgreement}, {"rows", json}};
    std::ofstream file(json_path);
    file << doc.dump(2) << "\n";
    file.flush();
    if (!file) return error(json_path + ": cannot write");
  }
  return all_pass ? 0 : kExitInconsistent;
}
