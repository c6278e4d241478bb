// gwnrt-bench-query: BVH build time, sheet classification time and query throughput on one mesh,
// each mode reported as a ratio to the brute-force exact sum measured in the same run, on the same
// point mix; --json writes every row for other programs.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "apps/common/cli_checks.h"
#include "apps/common/device_choice.h"
#include "apps/common/load_model.h"
#include "apps/common/program.h"
#include "gwnrt/base/memory.h"
#include "gwnrt/field/crossing_winding.h"
#include "gwnrt/geometry/mesh.h"
#include "gwnrt/io/mesh_io.h"
#include "gwnrt/model/model.h"
#include "gwnrt/query/batch.h"
#include "reference/point_mix.h"

namespace {

using namespace gwnrt;
using clock_type = std::chrono::steady_clock;

constexpr const char* kProgram = "gwnrt-bench-query";

struct Row {
  std::string mode;
  size_t points;
  double seconds;
  double max_error = NAN;       // of w against the brute force, where the mode gives w
  double kernel_seconds = NAN;  // on the GPU: the kernel alone, without the copies
  double rate() const { return double(points) / seconds; }
};

// Sheet classification alone, by one method: a model built with it, less the tree it shares.
double sheet_seconds(const Mesh& mesh, WindingMethod method) {
  BuildOptions options;
  options.sheet_method = method;
  GwnModel model;
  if (Status s = GwnModel::build(mesh, model, options); !s.ok()) apps::die(kProgram, s.message());
  return model.timings().sheet_seconds;
}

// A backend's evaluate_points: the CPU's on the model, or the GPU's on its upload.
using Evaluate = std::function<Status(std::span<const vec3>, const QueryRequest&, std::span<PointResult>)>;

// The same into columns (evaluate_points_to_columns, the Python module's path).
using EvaluateColumns = std::function<Status(std::span<const vec3>, const QueryRequest&, const PointColumns&)>;

// Seconds run() takes; dies on its failure.
template <class Run>
double seconds_of(Run&& run) {
  const auto t0 = clock_type::now();
  const Status s = run();
  const double sec = std::chrono::duration<double>(clock_type::now() - t0).count();
  if (!s.ok()) apps::die(kProgram, s.message());
  return sec;
}

double time_batch(const Evaluate& evaluate, const std::vector<vec3>& points, const QueryRequest& request,
                  std::vector<PointResult>& results) {
  results.resize(points.size());
  return seconds_of([&] { return evaluate(points, request, results); });
}

// Where a Taylor query's time goes: the lanes the traversal expands and the triangles it sums
// exactly (visit_multipole's test, the one every visitor runs).
struct TaylorCounts {
  uint64_t far_lanes = 0, near_triangles = 0;
  void far(uint32_t, int, const vec3&) { ++far_lanes; }
  void near(uint32_t, const vec3&, const vec3&, const vec3&) { ++near_triangles; }
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Query throughput of gwnrt's multipole tree against the brute-force sum"};
  std::string mesh_path = std::string(GWNRT_DATA_DIR) + "/bunny_holes.obj";
  size_t count = 1000000;
  double brute_seconds = 3.0;
  float beta = 2.0f;
  int threads = 0;
  uint32_t seed = 1;
  app.add_option("mesh", mesh_path, "OBJ or PLY mesh (default: the bundled bunny with holes)");
  app.add_option("--points", count, "number of query points")->check(gwnrt::apps::positive_number());
  app.add_option("--beta", beta, "accuracy scale")->check(gwnrt::apps::beta_number());
  app.add_option("--brute-seconds", brute_seconds, "time budget of the brute-force baseline")
      ->check(gwnrt::apps::positive_number());
  app.add_option("--threads", threads, "worker threads (default: all cores)")->check(gwnrt::apps::thread_count());
  app.add_option("--seed", seed, "random seed of the point mix");
  std::string only;
  app.add_option("--only", only, "time only the modes whose name contains this (e.g. distance)");
  std::string baseline_path;
  app.add_option("--baseline-json", baseline_path,
                 "another build's --json of this benchmark (same mesh, points and seed): each mode's throughput "
                 "as a ratio to it (scripts/bench-distance.sh runs the two interleaved)");
  std::string json_path;
  app.add_option("--json", json_path, "also write every row and the build timings to this JSON file");
  std::string device = "cpu";
  app.add_option("--device", device,
                 std::string(apps::kDeviceHelp) +
                     ". On the GPU each mode's time includes copying its points up and results down, not the "
                     "model's upload; the brute-force baseline stays on the CPU (a CPU run's --json as "
                     "--baseline-json gives GPU over CPU)")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "cpu", "cuda"}));
  if (const auto status = apps::parse_command_line(app, argc, argv)) return *status;
  Device where = Device::kCpu;
  if (Status s = apps::choose_device(kProgram, device, where); !s.ok()) return apps::fail(kProgram, s.message());

  // Checked before the mesh is loaded: the points, their subset for the brute force, the two
  // result arrays and the w column.
  if (Status s = check_memory(saturating_product(count, 2 * sizeof(vec3) + 2 * sizeof(PointResult) + sizeof(float)),
                              "--points " + std::to_string(count));
      !s.ok())
    return apps::fail(kProgram, s.message());
  // The baseline's queries/s by mode ("signed distance (sdf)" was renamed "..., auto": a mode
  // matches a baseline mode it equals or begins with, followed by a comma).
  std::vector<std::pair<std::string, double>> baseline;
  if (!baseline_path.empty()) {
    std::ifstream file(baseline_path);
    if (!file) return apps::fail(kProgram, baseline_path + ": cannot read");
    const nlohmann::json j = nlohmann::json::parse(file, nullptr, false);
    if (j.is_discarded() || !j.contains("rows") || !j["rows"].is_array())
      return apps::fail(kProgram, baseline_path + ": not a JSON file of this benchmark (no \"rows\" array)");
    for (const nlohmann::json& row : j["rows"]) {
      if (!row.is_object() || !row.contains("mode") || !row["mode"].is_string() ||
          !row.contains("queries_per_second") || !row["queries_per_second"].is_number())
        return apps::fail(kProgram, baseline_path + ": a row without \"mode\" and \"queries_per_second\"");
      baseline.emplace_back(row["mode"].get<std::string>(), row["queries_per_second"].get<double>());
    }
  }
  // A row's throughput over its baseline mode's; NaN without one (the brute force's row is its
  // own yardstick).
  // An equal name first: "w, crossing, into a column" begins with "w, crossing,".
  auto baseline_ratio = [&](const std::string& mode, double rate) -> double {
    for (const auto& [name, base_rate] : baseline)
      if (mode == name) return rate / base_rate;
    for (const auto& [name, base_rate] : baseline)
      if (mode.rfind(name + ",", 0) == 0) return rate / base_rate;
    return NAN;
  };
  const apps::ThreadLimit limit(threads);
  const int workers = int(limit.workers());

  Mesh mesh;
  MeshLoadReport report;
  const auto tl = clock_type::now();
  if (Status s = load_mesh(mesh_path, mesh, &report); !s.ok()) return apps::fail(kProgram, s.message());
  apps::print_load_warnings(kProgram, mesh_path, report);
  const double load_sec = std::chrono::duration<double>(clock_type::now() - tl).count();
  Aabb box;
  for (const vec3& p : mesh.positions) box.extend(p);
  const double sheets_by_crossing = sheet_seconds(mesh, WindingMethod::kCrossing);
  const double sheets_by_taylor = sheet_seconds(mesh, WindingMethod::kTaylor);
  GwnModel built;
  if (Status s = GwnModel::build(std::move(mesh), built); !s.ok()) return apps::fail(kProgram, s.message());
  const Engine engine(std::move(built));
  const GwnModel& model = engine.model();
  const ModelView view = model.view();
  const WindingMethod auto_method = resolve_winding_method(view, WindingMethod::kAuto);
  const size_t tris = model.mesh().triangles.size();
  std::printf("mesh            %s\n", mesh_path.c_str());
  std::printf("triangles       %zu (%zu degenerate), boundary segments %zu\n", tris, report.degenerate_triangles,
              model.boundary().segment_count());
  std::printf("threads         %d\n", workers);
  std::printf("load            %.3f s\n", load_sec);
  std::printf("tree + moments  %.3f s   (%zu nodes, depth %u)\n", model.timings().tree_seconds,
              model.triangle_tree().bvh.nodes.size(), model.triangle_tree().bvh.depth);
  std::printf("boundary + tree %.3f s\n", model.timings().boundary_seconds);
  std::printf("sheets          %.3f s   (%u of %zu triangles are sheets for w* = %g; by %s)\n",
              model.timings().sheet_seconds, model.sheet_tree().view().triangle_count, tris,
              double(model.sheet_level()), winding_method_name(model.sheet_method()));
  std::printf("sheets by crossing %.3f s (%.2fx the tree build), by taylor %.3f s (%.2fx)\n", sheets_by_crossing,
              sheets_by_crossing / model.timings().tree_seconds, sheets_by_taylor,
              sheets_by_taylor / model.timings().tree_seconds);
  std::printf("auto method     %s (%u cone triangles for %u triangles)\n\n", winding_method_name(auto_method),
              view.cone.triangle_count, view.triangles.triangle_count);

  const std::vector<vec3> points = point_mix(box, count, seed);
  std::vector<PointResult> results, reference;
  const Evaluate on_cpu = [&](std::span<const vec3> p, const QueryRequest& q, std::span<PointResult> r) {
    return engine.evaluate_points(Device::kCpu, p, q, r);
  };
  DeviceTimings device_timings;
  const Evaluate evaluate = [&](std::span<const vec3> p, const QueryRequest& q, std::span<PointResult> r) {
    return engine.evaluate_points(where, p, q, r, nullptr, &device_timings);
  };
  const EvaluateColumns evaluate_columns = [&](std::span<const vec3> p, const QueryRequest& q, const PointColumns& c) {
    return engine.evaluate_points_to_columns(where, p, q, c, nullptr, &device_timings);
  };
  if (where == Device::kCuda) {
    const auto tu = clock_type::now();
    if (Status s = engine.upload(); !s.ok()) return apps::fail(kProgram, s.message());
    // The first launch pays for the context and the scratch: not in any mode's time.
    std::vector<PointResult> warm(points.size());
    if (Status s = evaluate(points, QueryRequest{}, warm); !s.ok()) return apps::fail(kProgram, s.message());
    std::printf("device          cuda (upload %.3f s, then a warm-up batch)\n\n",
                std::chrono::duration<double>(clock_type::now() - tu).count());
  }

  // Brute force: grow the subset until it fills the time budget (its cost is O(n) per point).
  QueryRequest brute;
  brute.method = WindingMethod::kBrute;
  size_t brute_count = std::max<size_t>(4, size_t(workers) * 2);
  double brute_sec = 0;
  for (;;) {
    std::vector<vec3> subset(points.begin(), points.begin() + std::min(brute_count, points.size()));
    brute_sec = time_batch(on_cpu, subset, brute, reference);
    if (brute_sec > 0.25 * brute_seconds || subset.size() == points.size()) break;
    // In double: a budget of 1e39 s would overflow the count's integer arithmetic.
    const double grown = double(brute_count) * std::max(2.0, 0.5 * brute_seconds / std::max(brute_sec, 1e-3));
    brute_count = size_t(std::min(double(points.size()), grown));
  }
  const size_t brute_n = reference.size();
  std::vector<Row> rows;
  rows.push_back({"exact (brute force, double)", brute_n, brute_sec, 0.0});

  struct Mode {
    const char* name;
    WindingMethod method;
    int order;
    uint32_t fields;
    bool w_column = false;  // w written into a float column alone (evaluate_points_to_columns)
  };
  constexpr uint32_t kAllDerivatives = kFieldW | kFieldGradient | kFieldHessian;
  // The two "into a column" modes write 4 bytes a point, not a 116-byte PointResult (on the GPU,
  // none is copied down either): the Python module's path.
  const Mode modes[] = {{"w, Taylor order 0", WindingMethod::kTaylor, 0, kFieldW},
                        {"w, Taylor order 1", WindingMethod::kTaylor, 1, kFieldW},
                        {"w, Taylor order 2", WindingMethod::kTaylor, 2, kFieldW},
                        {"w, Taylor order 2, into a column", WindingMethod::kTaylor, 2, kFieldW, true},
                        {"w + grad, order 2", WindingMethod::kTaylor, 2, kFieldW | kFieldGradient},
                        {"w + grad + Hessian, order 2", WindingMethod::kTaylor, 2, kAllDerivatives},
                        {"w, crossing", WindingMethod::kCrossing, 2, kFieldW},
                        {"w, crossing, into a column", WindingMethod::kCrossing, 2, kFieldW, true},
                        {"w + grad + Hessian, crossing", WindingMethod::kCrossing, 2, kAllDerivatives},
                        {"unsigned distance", WindingMethod::kAuto, 2, kFieldUnsignedDistance},
                        {"boundary distance", WindingMethod::kAuto, 2, kFieldBoundaryDistance},
                        {"signed distance (sdf), auto", WindingMethod::kAuto, 2, kFieldSignedDistance},
                        {"pseudo-SDF (sdf1, sdf2), auto", WindingMethod::kAuto, 2, kFieldPseudoDistance},
                        {"sheet distance", WindingMethod::kAuto, 2, kFieldSheetDistance},
                        {"Harnack lower bound", WindingMethod::kAuto, 2, kFieldHarnackBound},
                        {"Newton projection, auto", WindingMethod::kAuto, 2, kFieldProjection}};
  std::vector<float> w_column;
  for (const Mode& m : modes) {
    if (!only.empty() && std::string(m.name).find(only) == std::string::npos) continue;
    QueryRequest request;
    request.method = m.method;
    request.taylor = {m.order, beta};
    request.fields = m.fields;
    double sec = 0;
    if (m.w_column) {
      w_column.assign(points.size(), 0.0f);
      PointColumns columns;
      columns.w = w_column.data();
      sec = seconds_of([&] { return evaluate_columns(points, request, columns); });
    } else {
      sec = time_batch(evaluate, points, request, results);
    }
    Row row{m.name, points.size(), sec};
    if (where == Device::kCuda) row.kernel_seconds = device_timings.kernel;
    if (m.fields & kFieldW) {
      row.max_error = 0;
      for (size_t i = 0; i < brute_n; ++i)
        row.max_error =
            std::max(row.max_error, double(std::abs((m.w_column ? w_column[i] : results[i].w) - reference[i].w)));
    }
    rows.push_back(row);
  }
  auto rate_of = [&](const char* mode) -> double {
    for (const Row& r : rows)
      if (r.mode == mode) return r.rate();
    return NAN;
  };

  const double base = rows[0].rate();
  std::printf("%-30s %10s %14s %12s %14s%s\n", "mode", "points", "queries/s", "x brute", "max |dw|",
              baseline.empty() ? "" : "     x baseline");
  for (const Row& r : rows) {
    std::printf("%-30s %10zu %14.4g %12.4g", r.mode.c_str(), r.points, r.rate(), r.rate() / base);
    if (!std::isnan(r.max_error) && &r != &rows[0])
      std::printf(" %14.3g", r.max_error);
    else if (!baseline.empty())
      std::printf(" %14s", "");
    if (!baseline.empty() && &r != &rows[0]) {
      const double ratio = baseline_ratio(r.mode, r.rate());
      if (std::isnan(ratio))
        std::printf(" %14s", "(not in it)");
      else
        std::printf(" %14.3g", ratio);
    }
    if (!std::isnan(r.kernel_seconds) && r.kernel_seconds > 0)
      std::printf("   (kernel alone %.4g/s)", double(r.points) / r.kernel_seconds);
    std::printf("\n");
  }
  const double w2 = rate_of("w, Taylor order 2");
  std::printf("\nw+grad+H / w (order 2): %.3f   order-1 w / brute force: %.4g   order-2 w / brute force: %.4g\n",
              rate_of("w + grad + Hessian, order 2") / w2, rate_of("w, Taylor order 1") / base, w2 / base);
  std::printf("crossing w / order-2 w: %.3f   crossing w / brute force: %.4g\n", rate_of("w, crossing") / w2,
              rate_of("w, crossing") / base);
  std::printf("sdf / w (order 2): %.3f (target >= 0.3)\n", rate_of("signed distance (sdf), auto") / w2);
  std::printf("(max |dw| is over the %zu brute-force points, beta = %g)\n", brute_n, beta);

  // Where the crossing method's time goes, per query, over (up to) the first 100k points.
  CrossingStats stats;
  const size_t sampled = std::min<size_t>(points.size(), 100000);
  for (size_t i = 0; i < sampled; ++i) (void)winding_number_crossing<false, false>(view, points[i], kConeBeta, &stats);
  const double per = 1.0 / double(sampled);
  std::printf(
      "crossing w per query: %.3f crossings of M, %.3f of the cone, %.2f exact cone triangles, %.2f cone "
      "clusters expanded\n",
      stats.mesh_crossings * per, stats.cone_crossings * per, stats.cone_near * per, stats.cone_far * per);
  TaylorCounts taylor_counts;
  for (size_t i = 0; i < sampled; ++i) visit_multipole(view.triangles, points[i], beta, taylor_counts);
  std::printf("Taylor w per query: %.2f lanes expanded, %.2f exact triangles\n", taylor_counts.far_lanes * per,
              taylor_counts.near_triangles * per);

  if (!json_path.empty()) {
    nlohmann::json out;
    out["mesh"] = mesh_path;
    out["triangles"] = tris;
    out["boundary_segments"] = model.boundary().segment_count();
    out["cone_triangles"] = view.cone.triangle_count;
    out["threads"] = workers;
    out["device"] = device_name(where);
    out["beta"] = beta;
    out["auto_method"] = winding_method_name(auto_method);
    out["build"] = {{"load_seconds", load_sec},
                    {"tree_seconds", model.timings().tree_seconds},
                    {"boundary_seconds", model.timings().boundary_seconds},
                    {"sheet_seconds", model.timings().sheet_seconds},
                    {"sheet_method", winding_method_name(model.sheet_method())},
                    {"sheet_crossing_seconds", sheets_by_crossing},
                    {"sheet_taylor_seconds", sheets_by_taylor}};
    out["crossing_per_query"] = {{"mesh_crossings", stats.mesh_crossings * per},
                                 {"cone_crossings", stats.cone_crossings * per},
                                 {"cone_exact_triangles", stats.cone_near * per},
                                 {"cone_clusters_expanded", stats.cone_far * per}};
    out["taylor_per_query"] = {{"lanes_expanded", taylor_counts.far_lanes * per},
                               {"exact_triangles", taylor_counts.near_triangles * per}};
    nlohmann::json table = nlohmann::json::array();
    auto number_or_null = [](double v) { return std::isnan(v) ? nlohmann::json() : nlohmann::json(v); };
    for (const Row& r : rows)
      table.push_back({{"mode", r.mode},
                       {"points", r.points},
                       {"queries_per_second", r.rate()},
                       {"ratio_to_brute_force", r.rate() / base},
                       {"ratio_to_baseline", number_or_null(&r == &rows[0] ? NAN : baseline_ratio(r.mode, r.rate()))},
                       {"max_abs_error", number_or_null(r.max_error)},
                       {"kernel_queries_per_second",
                        number_or_null(r.kernel_seconds > 0 ? double(r.points) / r.kernel_seconds : NAN)}});
    out["rows"] = table;
    std::ofstream file(json_path);
    file << out.dump(2) << "\n";
    if (!file) return apps::fail(kProgram, json_path + ": cannot write");
  }
  return 0;
}
