// gwnrt-query: evaluate the generalized winding number (and its derivatives, distances, the
// signed distance to S and the Newton projection onto it) of a triangle mesh at points read from
// a file, and write them as CSV.
#include <unistd.h>

#include <atomic>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <initializer_list>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "apps/common/cli_checks.h"
#include "apps/common/csv_writer.h"
#include "apps/common/device_choice.h"
#include "apps/common/load_model.h"
#include "apps/common/point_io.h"
#include "apps/common/program.h"
#include "apps/common/progress_bar.h"
#include "apps/common/trace_level.h"
#include "gwnrt/base/memory.h"
#include "gwnrt/geometry/mesh.h"
#include "gwnrt/io/mesh_io.h"
#include "gwnrt/model/model.h"
#include "gwnrt/query/batch.h"
#include "gwnrt/query/point_query.h"

namespace {

using gwnrt::dvec3;
using gwnrt::PointResult;
using gwnrt::vec3;
using gwnrt::apps::CsvWriter;
using gwnrt::apps::fail;
using gwnrt::apps::seconds_since;

constexpr const char* kProgram = "gwnrt-query";

// An output of --fields: what evaluate_point must compute for it, its CSV columns and how to
// write them (positions about `origin`, MeshLoadReport::origin: in the input's coordinates). "all"
// is every field before the signed-distance ones, which need a level.
struct Field {
  const char* name;
  uint32_t request_bits;
  std::initializer_list<const char*> headers;
  void (*write)(CsvWriter&, const PointResult&, const dvec3& origin);
};

const char* piece_name(gwnrt::DistancePiece piece) {
  switch (piece) {
    case gwnrt::DistancePiece::kSheet:
      return "sheet";
    case gwnrt::DistancePiece::kSmooth:
      return "smooth";
    default:
      return "bound";
  }
}

const Field kFields[] = {
    {"w", gwnrt::kFieldW, {"w"}, [](CsvWriter& c, const PointResult& r, const dvec3&) { c.field(r.w); }},
    {"grad",
     gwnrt::kFieldGradient,
     {"gx", "gy", "gz"},
     [](CsvWriter& c, const PointResult& r, const dvec3&) {
       for (int a = 0; a < 3; ++a) c.field(r.gradient[a]);
     }},
    {"hess",
     gwnrt::kFieldHessian,
     {"hxx", "hxy", "hxz", "hyy", "hyz", "hzz"},
     [](CsvWriter& c, const PointResult& r, const dvec3&) {
       for (float h : {r.hessian.xx, r.hessian.xy, r.hessian.xz, r.hessian.yy, r.hessian.yz, r.hessian.zz}) c.field(h);
     }},
    {"udist",
     gwnrt::kFieldUnsignedDistance,
     {"udist"},
     [](CsvWriter& c, const PointResult& r, const dvec3&) { c.field(r.unsigned_distance); }},
    {"bdist",
     gwnrt::kFieldBoundaryDistance,
     {"bdist"},
     [](CsvWriter& c, const PointResult& r, const dvec3&) { c.field(r.boundary_distance); }},
    {"sdf",
     gwnrt::kFieldSignedDistance,
     {"sdf", "sdf_piece"},
     [](CsvWriter& c, const PointResult& r, const dvec3&) {
       c.field(r.sdf.distance);
       c.field(piece_name(r.sdf.piece));
     }},
    {"sdf1",
     gwnrt::kFieldPseudoDistance,
     {"sdf1"},
     [](CsvWriter& c, const PointResult& r, const dvec3&) { c.field(r.sdf.first_order); }},
    {"sdf2",
     gwnrt::kFieldPseudoDistance,
     {"sdf2"},
     [](CsvWriter& c, const PointResult& r, const dvec3&) { c.field(r.sdf.second_order); }},
    {"sheet_dist",
     gwnrt::kFieldSheetDistance,
     {"sheet_dist"},
     [](CsvWriter& c, const PointResult& r, const dvec3&) { c.field(r.sdf.sheet_distance); }},
    {"proj",
     gwnrt::kFieldProjection,
     {"proj_x", "proj_y", "proj_z", "proj_iters", "proj_converged"},
     [](CsvWriter& c, const PointResult& r, const dvec3& origin) {
       for (int a = 0; a < 3; ++a) c.field(r.projection.point[a], origin[a]);
       c.field(unsigned(r.projection.iterations));
       c.field(unsigned(r.projection.converged));
     }},
    {"hbound",
     gwnrt::kFieldHarnackBound,
     {"hbound"},
     [](CsvWriter& c, const PointResult& r, const dvec3&) { c.field(r.harnack_bound); }},
};
constexpr size_t kFieldsInAll = 5;  // w, grad, hess, udist, bdist

// The indices into kFields that `name` selects.
std::optional<std::vector<size_t>> field_indices(const std::string& name) {
  if (name == "all") {
    std::vector<size_t> all(kFieldsInAll);
    for (size_t i = 0; i < kFieldsInAll; ++i) all[i] = i;
    return all;
  }
  for (size_t i = 0; i < std::size(kFields); ++i)
    if (name == kFields[i].name) return std::vector<size_t>{i};
  return std::nullopt;
}

std::string valid_field_list() {
  std::string list;
  for (const Field& f : kFields) list += std::string(list.empty() ? "" : ", ") + f.name;
  return list + ", all (= w, grad, hess, udist, bdist)";
}

// Columns in the order of kFields, whatever the order asked for. The points and the positions
// among the fields are written in the input's coordinates (about `origin`).
void write_csv(CsvWriter& csv, const std::vector<bool>& selected, const std::vector<vec3>& points,
               const std::vector<PointResult>& results, const dvec3& origin) {
  for (const char* h : {"x", "y", "z"}) csv.field(h);
  for (size_t f = 0; f < std::size(kFields); ++f)
    if (selected[f])
      for (const char* h : kFields[f].headers) csv.field(h);
  csv.end_row();
  for (size_t i = 0; i < points.size(); ++i) {
    for (int a = 0; a < 3; ++a) csv.field(points[i][a], origin[a]);
    for (size_t f = 0; f < std::size(kFields); ++f)
      if (selected[f]) kFields[f].write(csv, results[i], origin);
    csv.end_row();
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Evaluate the generalized winding number of a triangle mesh (OBJ/PLY) at points read from a text "
      "file (one 'x y z' per line) and write CSV.",
      kProgram};

  std::string mesh_path;
  std::string points_path;
  std::vector<std::string> field_names{"w"};
  int order = 2;
  float beta = 2.0f;
  bool exact = false;
  std::string method_name = "auto";
  float level = 0.5f;
  unsigned newton_iterations = gwnrt::NewtonOptions{}.max_iterations;
  float newton_tolerance = gwnrt::NewtonOptions{}.tolerance;
  std::string device = "cpu";
  int threads = 0;
  std::string output_path = "-";
  bool verbose = false;

  double weld_tolerance = 0;
  app.add_option("mesh", mesh_path, "Triangle mesh (.obj, .ply or .stl)")->required();
  gwnrt::apps::add_weld_tolerance_option(app, weld_tolerance);
  app.add_option("--points", points_path, "Points file, one 'x y z' per line ('-' for stdin)")->required();
  app.add_option("--fields", field_names, "Comma-separated outputs: " + valid_field_list())
      ->delimiter(',')
      ->capture_default_str()
      ->check(CLI::Validator(
          [](std::string& name) {
            return field_indices(name) ? std::string()
                                       : "unknown field '" + name + "' (valid: " + valid_field_list() + ")";
          },
          "FIELD"));
  app.add_option("--order", order, "Taylor expansion order of the tree approximation")
      ->capture_default_str()
      ->check(CLI::IsMember({0, 1, 2}));
  app.add_option("--beta", beta, "Accuracy parameter: expand a cluster when |x - p| > beta * radius")
      ->capture_default_str()
      ->check(gwnrt::apps::beta_number());
  CLI::Option* method_option =
      app.add_option("--method", method_name,
                     "How w, grad and hess are evaluated (and the sdf's sign, sdf1, sdf2, proj): crossing (exact: "
                     "signed ray crossings plus the boundary cone), taylor (the multipole tree, --order and --beta), "
                     "brute (double brute-force sum, the reference), auto (crossing when the mesh's boundary is "
                     "small, else taylor)")
          ->capture_default_str()
          ->check(CLI::IsMember({"auto", "crossing", "taylor", "brute"}));
  app.add_flag("--exact", exact, "The same as --method brute")->excludes(method_option);
  app.add_option("--level", level, "Level w*: S = boundary of {w > w*} (sdf, sdf1, sdf2, sheet_dist, proj, hbound)")
      ->capture_default_str()
      ->check(CLI::Validator(
          [](std::string& text) {
            // CLI11's Range lets nan through.
            float v = 0;
            const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
            if (r.ec != std::errc() || r.ptr != text.data() + text.size() || !(std::fabs(v) <= 1.0e6f))
              return "--level must be a number in [-1e6, 1e6], got '" + text + "'";
            return std::string();
          },
          "LEVEL"));
  app.add_option("--newton-iterations", newton_iterations, "Newton projection (proj): iteration cap")
      ->capture_default_str()
      ->check(CLI::Range(0u, 100000u));
  app.add_option("--newton-tolerance", newton_tolerance, "Newton projection (proj): converged when |w - w*| <= this")
      ->capture_default_str()
      ->check(gwnrt::apps::positive_number());
  app.add_option("--device", device, gwnrt::apps::kDeviceHelp)
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "cpu", "cuda"}));
  app.add_option("--threads", threads, "CPU threads (default: all)")->check(gwnrt::apps::thread_count());
  app.add_option("-o,--output", output_path, "CSV output file ('-' for stdout)")->capture_default_str();
  app.add_flag("-v,--verbose", verbose,
               "Print the load/build summary even when stderr is not a terminal (the progress bar needs one)");

  if (const auto status = gwnrt::apps::parse_command_line(app, argc, argv)) return *status;
  if (const std::string clash = gwnrt::apps::first_output_clash({{"--output", output_path}}, {mesh_path, points_path});
      !clash.empty())
    return fail(kProgram, clash);

  uint32_t fields = 0;
  std::vector<bool> selected(std::size(kFields), false);
  for (const std::string& name : field_names) {
    const std::vector<size_t> indices = field_indices(name).value();  // checked by the option's validator
    for (size_t f : indices) {
      selected[f] = true;
      fields |= kFields[f].request_bits;
    }
  }
  if (fields == 0) return fail(kProgram, "no fields requested");

  const bool chatty = verbose || ::isatty(2) == 1;

  gwnrt::QueryRequest request;
  request.fields = fields;
  request.taylor.order = order;
  request.taylor.beta = beta;
  if (exact) method_name = gwnrt::winding_method_name(gwnrt::WindingMethod::kBrute);
  (void)gwnrt::winding_method_named(method_name, request.method);  // --method's check took only these names
  request.level = level;
  request.newton.max_iterations = newton_iterations;
  request.newton.tolerance = newton_tolerance;

  // Checked before the mesh is loaded so a large load is not wasted on a request that cannot run.
  gwnrt::Device where = gwnrt::Device::kCpu;
  if (gwnrt::Status s = gwnrt::apps::choose_device(kProgram, device, where); !s.ok())
    return fail(kProgram, s.message());

  const gwnrt::apps::ThreadLimit thread_limit(threads);

  gwnrt::GwnModel model;
  gwnrt::apps::ModelLoad loaded;
  // M's tree, then only the parts the fields read (parts_read_by): the distance to M alone does
  // not pay for the boundary, the cone and the sheets (on the 871k dragon 0.6 s of a 1.3 s
  // build); the sheets are classified for --level.
  gwnrt::BuildOptions build_options;
  build_options.defer_parts = true;
  build_options.sheet_level = level;
  // A far-off mesh (a georeferenced scan) is computed about its own centre: the points are moved
  // by -origin as they are read, the positions written moved back.
  gwnrt::MeshLoadOptions load_options;
  load_options.recentre = true;
  load_options.weld_tolerance = weld_tolerance;
  load_options.summarize_weld = verbose;
  if (gwnrt::Status s = gwnrt::apps::load_model(mesh_path, model, loaded, build_options, load_options); !s.ok())
    return fail(kProgram, s.message());
  const auto t_parts = std::chrono::steady_clock::now();
  if (gwnrt::Status s = model.prepare(gwnrt::parts_read_by(request)); !s.ok())
    return fail(kProgram, mesh_path + ": " + s.message());
  const gwnrt::MeshLoadReport& report = loaded.report;
  gwnrt::apps::print_load_warnings(kProgram, mesh_path, report);
  if (verbose) gwnrt::apps::print_weld_summary(kProgram, mesh_path, report);
  const double load_seconds = loaded.load_seconds;
  const double build_seconds = loaded.build_seconds + gwnrt::apps::seconds_since(t_parts);

  if (chatty) {
    const uint32_t built = model.built_parts();
    std::fprintf(stderr, "%s: %s (%s): %zu vertices, %zu triangles", kProgram, mesh_path.c_str(), report.format.c_str(),
                 report.vertex_count, report.triangle_count);
    if (report.polygons_fanned) std::fprintf(stderr, " (%zu polygons fanned)", report.polygons_fanned);
    if (report.uv_count) std::fprintf(stderr, ", %zu UVs", report.uv_count);
    if (report.has_colors) std::fprintf(stderr, ", vertex colours");
    std::fprintf(stderr, ", %zu degenerate", report.degenerate_triangles);
    if (built & gwnrt::kPartBoundary)
      std::fprintf(stderr, ", %zu boundary segments%s", model.boundary().segment_count(),
                   model.boundary().segment_count() ? "" : " (closed)");
    std::fprintf(stderr, "; loaded in %.3f s\n", load_seconds);
    if (!report.attributes_dropped.empty())
      std::fprintf(stderr, "%s: %s: note: %s\n", kProgram, mesh_path.c_str(), report.attributes_dropped.c_str());
    std::fprintf(stderr, "%s: built in %.3f s (tree %.3f s, ", kProgram, build_seconds, model.timings().tree_seconds);
    if (built & gwnrt::kPartBoundary)
      std::fprintf(stderr, "boundary %.3f s, ", model.timings().boundary_seconds);
    else
      std::fprintf(stderr, "boundary and cone not built, ");
    if (built & gwnrt::kPartSheets)
      std::fprintf(stderr, "sheets %.3f s: %u of %zu triangles)\n", model.timings().sheet_seconds,
                   model.sheet_tree().view().triangle_count, report.triangle_count);
    else
      std::fprintf(stderr, "sheets not classified: no field asked reads them)\n");
    // Every field but the distances evaluates w (auto resolved with the cone, built for them).
    if (request.fields & ~(gwnrt::kFieldUnsignedDistance | gwnrt::kFieldBoundaryDistance | gwnrt::kFieldSheetDistance))
      std::fprintf(stderr, "%s: w by %s (--method %s)\n", kProgram,
                   gwnrt::winding_method_name(gwnrt::resolve_point_method(model.view(), request.method)),
                   method_name.c_str());
  }

  // A level w never reaches has no S: the sdf is then infinite and the projection finds nothing.
  // Said as gwnrt-trace and gwnrt-mesh say it, for the fields that read the level.
  if (request.fields & (gwnrt::kFieldSignedDistance | gwnrt::kFieldPseudoDistance | gwnrt::kFieldSheetDistance |
                        gwnrt::kFieldProjection | gwnrt::kFieldHarnackBound)) {
    gwnrt::TraceOptions surface;
    surface.level = request.level;
    gwnrt::apps::warn_if_level_out_of_reach(kProgram, model.view(), surface);
  }

  std::vector<vec3> points;
  if (gwnrt::Status s = gwnrt::apps::read_points(points_path, points, report.origin); !s.ok())
    return fail(kProgram, s.message());

  // Checked before allocating: with overcommit a size beyond memory would not fail here
  // but kill the process later, while it fills the results.
  if (gwnrt::Status s = gwnrt::check_memory(
          gwnrt::saturating_product(points.size(), sizeof(PointResult)),
          gwnrt::source_name(points_path) + ": the results of its " + std::to_string(points.size()) + " points");
      !s.ok())
    return fail(kProgram, s.message());
  std::vector<PointResult> results(points.size());
  const auto t_eval = std::chrono::steady_clock::now();
  {
    const gwnrt::Engine engine(std::move(model));
    std::atomic<size_t> progress{0};
    std::optional<gwnrt::apps::ProgressBar> bar;  // the GPU's batch reports no progress
    if (where == gwnrt::Device::kCpu) bar.emplace(progress, points.size(), "pts");
    const gwnrt::Status s = engine.evaluate_points(where, points, request, results, &progress);
    bar.reset();
    if (!s.ok()) return fail(kProgram, s.message());
  }
  if (chatty) {
    const double t = seconds_since(t_eval);
    std::fprintf(stderr, "%s: evaluated %zu points on %s in %.3f s (%.2f Mpts/s)\n", kProgram, points.size(),
                 gwnrt::device_name(where), t, t > 0 ? double(points.size()) / t * 1e-6 : 0.0);
  }

  const auto csv_rows = [&](std::FILE* out) {
    CsvWriter csv(out);
    write_csv(csv, selected, points, results, report.origin);
    return csv.flush();
  };
  if (gwnrt::Status s = gwnrt::apps::write_output(output_path, csv_rows); !s.ok()) return fail(kProgram, s.message());
  return 0;
}
