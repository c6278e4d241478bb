// Point queries and ray traces: numpy rows in, one numpy array per result column out, filled by
// the C++ batch drivers (evaluate_points into PointColumns, trace_rays) with the GIL released.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <iterator>
#include <string>
#include <vector>

#include "gwnrt/query/batch.h"
#include "python_model.h"

namespace gwnrt::python {
namespace {

// Adds result column `key` (each key once: for_each_column names a shared column once) to `out`
// and points `column` at its rows.
template <class T, class P>
void add_column(py::dict& out, const char* key, size_t rows, std::vector<py::ssize_t> trailing, P*& column) {
  static_assert(sizeof(T) == sizeof(P));
  py::array_t<T> array = new_rows<T>(rows, std::move(trailing));
  out[key] = array;
  column = reinterpret_cast<P*>(array.mutable_data());
}

struct FieldName {
  const char* name;
  uint32_t field;
};
constexpr FieldName kFieldNames[] = {
    {"w", kFieldW},
    {"gradient", kFieldGradient},
    {"hessian", kFieldHessian},
    {"unsigned_distance", kFieldUnsignedDistance},
    {"boundary_distance", kFieldBoundaryDistance},
    {"signed_distance", kFieldSignedDistance},
    {"pseudo_distance", kFieldPseudoDistance},
    {"sheet_distance", kFieldSheetDistance},
    {"projection", kFieldProjection},
    {"harnack_bound", kFieldHarnackBound},
};

uint32_t fields_named(const std::vector<std::string>& names) {
  std::string known;
  for (const FieldName& f : kFieldNames) known += std::string(known.empty() ? "" : ", ") + f.name;
  if (names.empty()) throw py::value_error("fields must name at least one of: " + known);
  uint32_t fields = 0;
  for (const std::string& name : names) {
    const auto* f = std::find_if(std::begin(kFieldNames), std::end(kFieldNames),
                                 [&](const FieldName& f) { return name == f.name; });
    if (f == std::end(kFieldNames)) throw py::value_error("unknown field '" + name + "' (fields: " + known + ")");
    fields |= f->field;
  }
  return fields;
}

// The result columns of `fields`, each as column.template operator()<T>(key, trailing shape,
// PointColumns pointer): the one table of which field writes which array (element types: float32
// values, int32 indices with -1 for none (kEmptyLane's bits), uint8 codes, bool flags).
template <class Column>
void for_each_column(uint32_t fields, PointColumns& c, Column&& column) {
  if (fields & kFieldW) column.template operator()<float>("w", {}, c.w);
  if (fields & kFieldGradient) column.template operator()<float>("gradient", {3}, c.gradient);
  if (fields & kFieldHessian) column.template operator()<float>("hessian", {3, 3}, c.hessian);
  if (fields & kFieldUnsignedDistance) {
    column.template operator()<float>("distance", {}, c.unsigned_distance);
    column.template operator()<int32_t>("triangle", {}, c.nearest_triangle);
    column.template operator()<float>("barycentrics", {2}, c.barycentrics);
  }
  if (fields & kFieldBoundaryDistance) {
    column.template operator()<float>("boundary_distance", {}, c.boundary_distance);
    column.template operator()<int32_t>("boundary_segment", {}, c.nearest_boundary_segment);
  }
  if (fields & kFieldSignedDistance) {
    column.template operator()<float>("sdf", {}, c.sdf);
    column.template operator()<uint8_t>("piece", {}, c.sdf_piece);
  }
  if (fields & (kFieldSignedDistance | kFieldPseudoDistance)) {
    column.template operator()<float>("sdf1", {}, c.sdf1);
    column.template operator()<float>("sdf2", {}, c.sdf2);
  }
  if (fields & (kFieldSignedDistance | kFieldSheetDistance)) {
    column.template operator()<float>("sheet_distance", {}, c.sheet_distance);
    column.template operator()<int32_t>("sheet_triangle", {}, c.sheet_triangle);
  }
  if (fields & kFieldProjection) {
    column.template operator()<float>("projection", {3}, c.projection);
    column.template operator()<uint32_t>("iterations", {}, c.projection_iterations);
    column.template operator()<bool>("converged", {}, c.projection_converged);
    column.template operator()<float>("residual", {}, c.projection_residual);
  }
  if (fields & kFieldHarnackBound) column.template operator()<float>("harnack_bound", {}, c.harnack_bound);
}

// The columns of `fields`, allocated in `out`.
PointColumns point_columns(uint32_t fields, size_t k, py::dict& out) {
  PointColumns c;
  for_each_column(fields, c, [&]<class T, class P>(const char* key, std::vector<py::ssize_t> trailing, P*& column) {
    add_column<T>(out, key, k, std::move(trailing), column);
  });
  return c;
}

// [(key, dtype, trailing shape)] of the columns of `fields`, in for_each_column's order: for
// callers that lay out the results before any is computed (gwnrt.dask).
py::list query_columns(const std::vector<std::string>& names) {
  py::list out;
  PointColumns unused;
  for_each_column(fields_named(names), unused,
                  [&]<class T, class P>(const char* key, std::vector<py::ssize_t> trailing, P*&) {
                    out.append(py::make_tuple(key, py::dtype::of<T>(), py::tuple(py::cast(trailing))));
                  });
  return out;
}

// The request but its level, which evaluate_on sets under the level lock (a default read
// before it could be stale by the time the batch runs).
QueryRequest query_request(const std::vector<std::string>& fields, const std::string& method, int64_t order, float beta,
                           int64_t newton_iterations, float newton_tolerance) {
  QueryRequest request;
  request.fields = fields_named(fields);
  request.method = winding_method_argument(method);
  request.taylor.order = checked_integer<int>(order, "order");
  request.taylor.beta = beta;
  request.newton.max_iterations = checked_integer<uint32_t>(newton_iterations, "max_iterations");
  request.newton.tolerance = newton_tolerance;
  return request;
}

Status evaluate_on(const PythonModel& p, Device where, std::span<const vec3> points, QueryRequest request,
                   std::optional<float> level, const PointColumns& columns) {
  std::shared_lock lock(p.level_mutex);
  request.level = level_or_default(p, level);
  return p.engine.evaluate_points_to_columns(where, points, request, columns);
}

py::dict query(const PythonModel& p, const py::handle& points_obj, const std::vector<std::string>& fields,
               const std::string& method, int64_t order, float beta, std::optional<float> level,
               int64_t newton_iterations, float newton_tolerance, Threads threads, const std::string& device) {
  const QueryRequest request = query_request(fields, method, order, beta, newton_iterations, newton_tolerance);
  const Device where = device_argument(device);
  const FloatArray points = float_rows(points_obj, "points", 3);
  py::dict out;
  const PointColumns columns = point_columns(request.fields, size_t(points.shape(0)), out);
  check(run_released(threads, [&] { return evaluate_on(p, where, as_vec3(points), request, level, columns); }));
  return out;
}

TraceMode trace_mode_named(const std::string& name) {
  if (name == "gwn") return TraceMode::kWindingNumber;
  if (name == "solid_angle") return TraceMode::kSolidAngle;
  throw py::value_error("mode must be 'gwn' (S = boundary of {w > level}) or 'solid_angle', got '" + name + "'");
}

py::dict trace(const PythonModel& p, const py::handle& origins_obj, const py::handle& directions_obj,
               const py::handle& tnear_obj, const py::handle& tfar_obj, const std::string& mode, float level,
               float epsilon, int64_t max_steps, int64_t max_crossings, float beta, bool exact, Threads threads,
               const std::string& device) {
  TraceOptions options;
  options.mode = trace_mode_named(mode);
  options.level = level;
  options.epsilon = epsilon;
  options.max_steps = checked_integer<uint32_t>(max_steps, "max_steps");
  options.max_crossings = checked_integer<uint32_t>(max_crossings, "max_crossings");
  options.beta = beta;
  options.exact = exact;
  const Device where = device_argument(device);
  const FloatArray origins = float_rows(origins_obj, "origins", 3);
  const FloatArray directions = float_rows(directions_obj, "directions", 3);
  const FloatArray tnear = float_rows(tnear_obj, "tnear", 1);
  const FloatArray tfar = float_rows(tfar_obj, "tfar", 1);
  const size_t k = size_t(origins.shape(0));
  if (size_t(directions.shape(0)) != k || size_t(tnear.shape(0)) != k || size_t(tfar.shape(0)) != k)
    throw py::value_error("origins, directions, tnear and tfar must have the same number of rows, got " +
                          std::to_string(k) + ", " + std::to_string(directions.shape(0)) + ", " +
                          std::to_string(tnear.shape(0)) + " and " + std::to_string(tfar.shape(0)));
  // Refused as the programs refuse them in a ray file, rather than traced as misses.
  const std::span<const vec3> o_rows = as_vec3(origins), d_rows = as_vec3(directions);
  for (size_t i = 0; i < k; ++i)
    if (const char* why = ray_refusal(Ray{o_rows[i], d_rows[i], tnear.data()[i], tfar.data()[i]}))
      throw py::value_error("ray " + std::to_string(i) + ": " + why);
  py::dict out;
  bool *hit, *capped, *invalid;
  float *t, *position, *normal;
  uint8_t* kind;
  uint32_t *triangle, *steps, *crossings;
  add_column<bool>(out, "hit", k, {}, hit);
  add_column<float>(out, "t", k, {}, t);
  add_column<float>(out, "position", k, {3}, position);
  add_column<float>(out, "normal", k, {3}, normal);
  add_column<uint8_t>(out, "kind", k, {}, kind);
  add_column<int32_t>(out, "triangle", k, {}, triangle);
  add_column<uint32_t>(out, "steps", k, {}, steps);
  add_column<uint32_t>(out, "crossings", k, {}, crossings);
  add_column<bool>(out, "capped", k, {}, capped);
  add_column<bool>(out, "invalid", k, {}, invalid);
  check(run_released(threads, [&] {
    return guard_status("trace", [&] {
      std::vector<Ray> rays(k);
      std::vector<RayHit> hits(k);
      const std::span<const vec3> o = as_vec3(origins), d = as_vec3(directions);
      for (size_t i = 0; i < k; ++i) rays[i] = Ray{o[i], d[i], tnear.data()[i], tfar.data()[i]};
      std::shared_lock lock(p.level_mutex);
      if (Status s = p.engine.trace_rays(where, rays, options, hits); !s.ok()) return s;
      for (size_t i = 0; i < k; ++i) {
        const RayHit& h = hits[i];
        hit[i] = h.hit;
        t[i] = h.t;
        for (int a = 0; a < 3; ++a) {
          position[3 * i + a] = h.position[a];
          normal[3 * i + a] = h.normal[a];
        }
        kind[i] = uint8_t(h.kind);
        triangle[i] = h.triangle;
        steps[i] = h.steps;
        crossings[i] = h.crossings;
        capped[i] = h.capped;
        invalid[i] = h.invalid;
      }
      return Status::Ok();
    });
  }));
  return out;
}

// The C++ batch as a C++ program calls it (results in a PointResult array allocated once, outside
// the timing), `repeats` times: the baseline of the Python benchmark (bench/bench_python.py).
std::vector<double> cxx_batch_seconds(const PythonModel& p, const py::handle& points_obj,
                                      const std::vector<std::string>& fields, const std::string& method, int64_t order,
                                      float beta, int repeats, Threads threads) {
  QueryRequest request = query_request(fields, method, order, beta, 32, 1e-4f);
  const FloatArray points = float_rows(points_obj, "points", 3);
  std::vector<double> seconds;
  std::vector<PointResult> results(size_t(points.shape(0)));
  for (int r = 0; r < repeats; ++r) {
    const auto start = std::chrono::steady_clock::now();
    check(run_released(threads, [&] {
      std::shared_lock lock(p.level_mutex);
      request.level = level_or_default(p, std::nullopt);
      return evaluate_points(p.model(), as_vec3(points), request, results);
    }));
    seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return seconds;
}

}  // namespace

void bind_queries(py::module_& m) {
  m.def("query", &query, py::arg("model"), py::arg("points"), py::arg("fields"), py::arg("method") = "auto",
        py::arg("order") = 2, py::arg("beta") = 2.0f, py::arg("level") = py::none(),
        py::arg("newton_iterations") = int64_t(32), py::arg("newton_tolerance") = 1e-4f,
        py::arg("threads") = py::none(), py::arg("device") = "cpu");
  m.def("trace", &trace, py::arg("model"), py::arg("origins"), py::arg("directions"), py::arg("tnear"), py::arg("tfar"),
        py::arg("mode") = "gwn", py::arg("level") = 0.5f, py::arg("epsilon") = 1e-5f,
        py::arg("max_steps") = int64_t(4096), py::arg("max_crossings") = int64_t(65536), py::arg("beta") = 2.0f,
        py::arg("exact") = false, py::arg("threads") = py::none(), py::arg("device") = "cpu");
  m.def("query_columns", &query_columns, py::arg("fields"));
  m.def("_cxx_batch_seconds", &cxx_batch_seconds, py::arg("model"), py::arg("points"), py::arg("fields"),
        py::arg("method") = "auto", py::arg("order") = 2, py::arg("beta") = 2.0f, py::arg("repeats") = 1,
        py::arg("threads") = py::none());
}

}  // namespace gwnrt::python
