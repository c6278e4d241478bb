// gwnrt-bench-query: BVH build time and query throughput on one mesh, each mode reported as a
// ratio to the brute-force exact sum measured in the same run, on the same point mix.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "gwnrt/batch.h"
#include "gwnrt/geometry/mesh.h"
#include "gwnrt/geometry/model.h"
#include "gwnrt/io/mesh_io.h"
#include "point_mix.h"
#include "program.h"

namespace {

using namespace gwnrt;
using clock_type = std::chrono::steady_clock;

constexpr const char* kProgram = "gwnrt-bench-query";

struct Row {
  std::string mode;
  size_t points;
  double seconds;
  double rate() const { return double(points) / seconds; }
};

double time_batch(const GwnModel& model, const std::vector<vec3>& points, const QueryRequest& request,
                  std::vector<PointResult>& results) {
  results.resize(points.size());
  const auto t0 = clock_type::now();
  const Status s = evaluate_points(model, points, request, results);
  const double sec = std::chrono::duration<double>(clock_type::now() - t0).count();
  if (!s.ok()) examples::die(kProgram, s.message());
  return sec;
}

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
  app.add_option("--points", count, "number of query points")->check(CLI::PositiveNumber);
  app.add_option("--beta", beta, "accuracy scale")->check(CLI::PositiveNumber);
  app.add_option("--brute-seconds", brute_seconds, "time budget of the brute-force baseline")
      ->check(CLI::PositiveNumber);
  app.add_option("--threads", threads, "worker threads (default: all cores)")->check(CLI::PositiveNumber);
  app.add_option("--seed", seed, "random seed of the point mix");
  CLI11_PARSE(app, argc, argv);

  const examples::ThreadLimit limit(threads);
  const int workers = int(limit.workers());

  Mesh mesh;
  MeshLoadReport report;
  const auto tl = clock_type::now();
  if (Status s = load_mesh(mesh_path, mesh, &report); !s.ok()) return examples::fail(kProgram, s.message());
  const double load_sec = std::chrono::duration<double>(clock_type::now() - tl).count();
  Aabb box;
  for (const vec3& p : mesh.positions) box.extend(p);
  GwnModel model;
  if (Status s = GwnModel::build(std::move(mesh), model); !s.ok()) return examples::fail(kProgram, s.message());
  const size_t tris = model.mesh().triangles.size();
  std::printf("mesh            %s\n", mesh_path.c_str());
  std::printf("triangles       %zu (%zu degenerate), boundary segments %zu\n", tris, report.degenerate_triangles,
              model.boundary().segment_count());
  std::printf("threads         %d\n", workers);
  std::printf("load            %.3f s\n", load_sec);
  std::printf("tree + moments  %.3f s   (%zu nodes, depth %u)\n", model.timings().tree_seconds,
              model.triangle_tree().bvh.nodes.size(), model.triangle_tree().bvh.depth);
  std::printf("boundary + tree %.3f s\n", model.timings().boundary_seconds);
  std::printf("sheets          %.3f s   (%u of %zu triangles are sheets for w* = %g)\n\n",
              model.timings().sheet_seconds, model.sheet_tree().view().triangle_count, tris,
              double(model.sheet_level()));

  const std::vector<vec3> points = point_mix(box, count, seed);
  std::vector<PointResult> results, reference;

  // Brute force: grow the subset until it fills the time budget (its cost is O(n) per point).
  QueryRequest brute;
  brute.exact = true;
  size_t brute_count = std::max<size_t>(4, size_t(workers) * 2);
  double brute_sec = 0;
  for (;;) {
    std::vector<vec3> subset(points.begin(), points.begin() + std::min(brute_count, points.size()));
    brute_sec = time_batch(model, subset, brute, reference);
    if (brute_sec > 0.25 * brute_seconds || subset.size() == points.size()) break;
    brute_count = std::min(points.size(),
                           brute_count * std::max<size_t>(2, size_t(0.5 * brute_seconds / std::max(brute_sec, 1e-3))));
  }
  const size_t brute_n = reference.size();
  std::vector<Row> rows;
  rows.push_back({"exact (brute force, double)", brute_n, brute_sec});

  struct Mode {
    const char* name;
    int order;
    uint32_t fields;
  };
  const Mode modes[] = {{"w, Taylor order 0", 0, kFieldW},
                        {"w, Taylor order 1", 1, kFieldW},
                        {"w, Taylor order 2", 2, kFieldW},
                        {"w + grad, order 2", 2, kFieldW | kFieldGradient},
                        {"w + grad + Hessian, order 2", 2, kFieldW | kFieldGradient | kFieldHessian},
                        {"unsigned distance", 2, kFieldUnsignedDistance},
                        {"boundary distance", 2, kFieldBoundaryDistance},
                        {"signed distance (sdf)", 2, kFieldSignedDistance},
                        {"pseudo-SDF (sdf1, sdf2)", 2, kFieldPseudoDistance},
                        {"sheet distance", 2, kFieldSheetDistance},
                        {"Harnack lower bound", 2, kFieldHarnackBound},
                        {"Newton projection", 2, kFieldProjection}};
  std::vector<double> max_err;
  for (const Mode& m : modes) {
    QueryRequest request;
    request.taylor = {m.order, beta};
    request.fields = m.fields;
    const double sec = time_batch(model, points, request, results);
    rows.push_back({m.name, points.size(), sec});
    double err = 0;
    if (m.fields & kFieldW)
      for (size_t i = 0; i < brute_n; ++i) err = std::max(err, double(std::abs(results[i].w - reference[i].w)));
    max_err.push_back(m.fields & kFieldW ? err : NAN);
  }

  const double base = rows[0].rate();
  std::printf("%-30s %10s %14s %12s %14s\n", "mode", "points", "queries/s", "x brute", "max |dw|");
  for (size_t i = 0; i < rows.size(); ++i) {
    std::printf("%-30s %10zu %14.4g %12.4g", rows[i].mode.c_str(), rows[i].points, rows[i].rate(),
                rows[i].rate() / base);
    if (i > 0 && !std::isnan(max_err[i - 1])) std::printf(" %14.3g", max_err[i - 1]);
    std::printf("\n");
  }
  const double w1 = rows[2].rate(), w2 = rows[3].rate(), wgh = rows[5].rate(), sdf = rows[8].rate();
  std::printf("\nw+grad+H / w (order 2): %.3f   order-1 w / brute force: %.4g   order-2 w / brute force: %.4g\n",
              wgh / w2, w1 / base, w2 / base);
  std::printf("sdf / w (order 2): %.3f (target >= 0.3)\n", sdf / w2);
  std::printf("(max |dw| is over the %zu brute-force points, beta = %g)\n", brute_n, beta);
  return 0;
}
