// The native part of the Python module (gwnrt._gwnrt): the model, its I/O, and what the other
// files share. The Python-facing API (named results, keyword defaults, objects with .vertices and
// .faces) is python/gwnrt/__init__.py.
#include <cmath>
#include <cstring>
#include <string>

#include "gwnrt/io/mesh_io.h"
#include "python_model.h"

namespace gwnrt::python {

void raise_status(const Status& status) {
  switch (status.code()) {
    case StatusCode::kInvalidArgument:
    case StatusCode::kParseError:
    case StatusCode::kInvalidMesh:
      throw py::value_error(status.message());
    case StatusCode::kIoError:
      PyErr_SetString(PyExc_OSError, status.message().c_str());
      throw py::error_already_set();
    case StatusCode::kOutOfMemory:
      PyErr_SetString(PyExc_MemoryError, status.message().c_str());
      throw py::error_already_set();
    default:
      throw std::runtime_error(status.message());
  }
}

namespace {

std::string shape_text(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t d = 0; d < a.ndim(); ++d) s += (d ? ", " : "") + std::to_string(a.shape(d));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

std::string rows_text(py::ssize_t width) { return width == 1 ? "(k,)" : "(k, " + std::to_string(width) + ")"; }

}  // namespace

FloatArray float_rows(const py::handle& obj, const char* name, py::ssize_t width) {
  py::array any = py::array::ensure(obj);
  if (!any) throw py::value_error(std::string(name) + " must be an array of numbers of shape " + rows_text(width));
  const char kind = any.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u' && kind != 'b')
    throw py::value_error(std::string(name) + " must hold real numbers, got dtype " +
                          std::string(py::str(any.dtype())));
  // No rows: (0, width), or (0,) as an empty list converts.
  if (any.ndim() == 1 && any.shape(0) == 0)
    return FloatArray(width == 1 ? std::vector<py::ssize_t>{0} : std::vector<py::ssize_t>{0, width});
  const bool shaped = width == 1 ? any.ndim() == 1 : any.ndim() == 2 && any.shape(1) == width;
  if (!shaped)
    throw py::value_error(std::string(name) + " must have shape " + rows_text(width) + ", got " + shape_text(any));
  // Not aligned (np.frombuffer at an odd offset): copied, so that the rows read as vec3s.
  if (!(any.flags() & py::detail::npy_api::NPY_ARRAY_ALIGNED_)) any = any.attr("copy")();
  return FloatArray(any);  // converts (float64, strides, byte order) or raises, MemoryError included
}

Device device_argument(const std::string& device) {
  Device asked = Device::kCpu;
  if (!device_named(device, asked))
    throw py::value_error("device must be 'cpu', 'cuda' or 'auto', got '" + device + "'");
  DeviceChoice chosen;
  if (Status s = choose_device(asked, chosen); !s.ok()) throw std::runtime_error("device='cuda': " + s.message());
  return chosen.device;
}

WindingMethod winding_method_argument(const std::string& name) {
  WindingMethod method;
  if (gwnrt::winding_method_named(name, method)) return method;
  throw py::value_error("method must be 'auto', 'crossing', 'taylor' or 'brute', got '" + name + "'");
}

namespace {

// `obj` as rows of indices, each below `limit`: shape (m, width) for a Row of `width` uint32s,
// (m,) for one. `name` is the argument, `row` and `index` name a row and what an index points at
// in the message ("face 2 has vertex index -1, outside [0, 4)").
template <class Row>
std::vector<Row> index_rows(const py::handle& obj, const char* name, uint64_t limit, const char* row,
                            const char* index) {
  constexpr py::ssize_t width = sizeof(Row) / sizeof(uint32_t);
  static_assert(sizeof(Row) == width * sizeof(uint32_t));
  const std::string shape = width == 1 ? "(m,)" : "(m, " + std::to_string(width) + ")";
  py::array any = py::array::ensure(obj);
  if (!any) throw py::value_error(std::string(name) + " must be an integer array of shape " + shape);
  if (any.ndim() == 1 && any.shape(0) == 0) return {};
  if (any.dtype().kind() != 'i' && any.dtype().kind() != 'u')
    throw py::value_error(std::string(name) + " must be an integer array of shape " + shape + ", got dtype " +
                          std::string(py::str(any.dtype())));
  if (width == 1 ? any.ndim() != 1 : any.ndim() != 2 || any.shape(1) != width)
    throw py::value_error(std::string(name) + " must have shape " + shape + ", got " + shape_text(any));
  // Signed and unsigned indices each in a 64-bit type of their own kind, so that neither wraps.
  const auto convert = [&]<class Index>(Index) {
    const py::array_t<Index, py::array::c_style | py::array::forcecast> indices(any);
    std::vector<Row> rows(size_t(indices.shape(0)));
    uint32_t* out = reinterpret_cast<uint32_t*>(rows.data());
    const Index* v = indices.data();
    for (size_t i = 0; i < rows.size() * width; ++i) {
      if (v[i] < 0 || uint64_t(v[i]) >= limit)
        throw py::value_error(std::string(row) + " " + std::to_string(i / width) + " has " + index + " index " +
                              std::to_string(v[i]) + ", outside [0, " + std::to_string(limit) + ")");
      out[i] = uint32_t(v[i]);
    }
    return rows;
  };
  return any.dtype().kind() == 'u' ? convert(uint64_t()) : convert(int64_t());
}

}  // namespace

std::vector<uvec3> face_rows(const py::handle& obj, size_t vertex_count) {
  return index_rows<uvec3>(obj, "faces", vertex_count, "face", "vertex");
}

std::vector<uint32_t> source_triangle_rows(const py::handle& obj) {
  return index_rows<uint32_t>(obj, "source_triangles", uint64_t(UINT32_MAX) + 1, "source_triangles entry", "triangle");
}

float level_or_default(const PythonModel& p, std::optional<float> level) {
  if (level) return *level;
  const float sheets = p.model().requested_sheet_level();
  return std::isnan(sheets) ? 0.5f : sheets;
}

namespace {

BuildOptions build_options(bool classify_sheets, float level, const std::string& sheet_method) {
  BuildOptions options;
  options.classify_sheets = classify_sheets;
  options.sheet_level = level;
  options.sheet_method = winding_method_argument(sheet_method);
  if (options.sheet_method == WindingMethod::kBrute)
    throw py::value_error("sheet_method must be 'auto', 'crossing' or 'taylor' (brute would sum n^2 terms)");
  if (!std::isfinite(level)) throw py::value_error("level must be a finite number");
  // The tree now, the boundary, cone and sheets on first need (a distance query never pays for them).
  options.defer_parts = true;
  return options;
}

std::unique_ptr<PythonModel> build_model(Mesh mesh, const BuildOptions& options, Threads threads) {
  auto out = std::make_unique<PythonModel>();
  GwnModel model;
  check(run_released(threads, [&] { return GwnModel::build(std::move(mesh), model, options); }));
  out->engine = Engine(std::move(model));
  return out;
}

py::array vec3_copy(std::span<const vec3> v) {
  auto out = new_rows<float>(v.size(), {3});
  if (!v.empty()) std::memcpy(out.mutable_data(), v.data(), v.size() * sizeof(vec3));
  return out;
}

}  // namespace

void bind_model(py::module_& m) {
  py::class_<PythonModel>(m, "Model")
      .def(py::init([](const py::handle& vertices, const py::handle& faces, bool classify_sheets, float level,
                       const std::string& sheet_method, Threads threads) {
             const BuildOptions options = build_options(classify_sheets, level, sheet_method);
             const FloatArray positions = float_rows(vertices, "vertices", 3);
             Mesh mesh;
             mesh.positions.assign(as_vec3(positions).begin(), as_vec3(positions).end());
             mesh.triangles = face_rows(faces, mesh.positions.size());
             return build_model(std::move(mesh), options, threads);
           }),
           py::arg("vertices"), py::arg("faces"), py::kw_only(), py::arg("classify_sheets") = true,
           py::arg("level") = 0.5f, py::arg("sheet_method") = "auto", py::arg("threads") = py::none())
      .def_static(
          "load",
          [](const std::string& path, bool classify_sheets, float level, const std::string& sheet_method,
             Threads threads, bool recentre, double weld_tolerance) {
            const BuildOptions options = build_options(classify_sheets, level, sheet_method);
            Mesh mesh;
            MeshLoadReport report;
            MeshLoadOptions load_options;
            load_options.recentre = recentre;
            load_options.weld_tolerance = weld_tolerance;
            check(run_released(std::nullopt, [&] { return load_mesh(path, mesh, &report, load_options); }));
            std::string notes = report.warnings;
            if (!report.attributes_dropped.empty())
              notes += (notes.empty() ? "" : "; ") + std::string("dropped: ") + report.attributes_dropped;
            const std::array<double, 3> origin = {report.origin.x, report.origin.y, report.origin.z};
            py::dict loaded;
            loaded["format"] = report.format;
            loaded["file_vertices"] = report.file_vertices;
            loaded["tolerance_welded"] = report.tolerance_welded;
            loaded["degenerate_triangles"] = report.degenerate_triangles;
            return py::make_tuple(build_model(std::move(mesh), options, threads), notes, origin, loaded);
          },
          py::arg("path"), py::kw_only(), py::arg("classify_sheets") = true, py::arg("level") = 0.5f,
          py::arg("sheet_method") = "auto", py::arg("threads") = py::none(), py::arg("recentre") = false,
          py::arg("weld_tolerance") = 0.0)
      .def("weld_summary",
           [](const PythonModel& p) {
             // On first need (gwnrt.Model.load_report): on a large mesh it costs more than parsing.
             const WeldSummary w = run_released(std::nullopt, [&] { return summarize_weld(p.model().mesh()); });
             py::dict d;
             d["vertices_used"] = w.vertices_used;
             d["positions_used"] = w.positions_used;
             d["boundary_edges_by_index"] = w.boundary_by_index;
             d["boundary_edges"] = w.boundary_by_position;
             d["boundary_loops"] = w.boundary_loops;
             return d;
           })
      .def_property_readonly("vertex_count", [](const PythonModel& p) { return p.model().mesh().positions.size(); })
      .def_property_readonly("triangle_count", [](const PythonModel& p) { return p.model().mesh().triangles.size(); })
      .def_property_readonly("vertices", [](const PythonModel& p) { return vec3_copy(p.model().mesh().positions); })
      .def_property_readonly("faces",
                             [](const PythonModel& p) {
                               const auto& t = p.model().mesh().triangles;
                               auto out = new_rows<int64_t>(t.size(), {3});
                               int64_t* o = out.mutable_data();
                               for (size_t f = 0; f < t.size(); ++f)
                                 for (int c = 0; c < 3; ++c) o[3 * f + c] = t[f][c];
                               return out;
                             })
      .def_property_readonly("bounds",
                             [](const PythonModel& p) {
                               const vec3 corners[2] = {p.model().bounds().lo, p.model().bounds().hi};
                               return vec3_copy(corners);
                             })
      .def_property_readonly("sheet_level",
                             [](const PythonModel& p) -> std::optional<float> {
                               const float level = run_released(std::nullopt, [&] {
                                 std::shared_lock lock(p.level_mutex);  // a classification may be running
                                 return p.model().requested_sheet_level();
                               });
                               if (std::isnan(level)) return std::nullopt;
                               return level;
                             })
      .def_property_readonly("boundary_segment_count",
                             [](const PythonModel& p) {
                               check(run_released(std::nullopt, [&] { return p.model().prepare(kPartBoundary); }));
                               return p.model().boundary_tree().view().segment_count;
                             })
      .def(
          "set_sheet_level",
          [](PythonModel& p, float level) {
            check(run_released(std::nullopt, [&] {
              std::unique_lock lock(p.level_mutex);
              return p.engine.set_sheet_level(level);  // the GPU's copy is made again when next asked
            }));
          },
          py::arg("level"));
}

}  // namespace gwnrt::python

PYBIND11_MODULE(_gwnrt, m) {
  namespace py = pybind11;
  m.doc() = "gwnrt's native module; use the gwnrt package";
  gwnrt::python::bind_model(m);
  gwnrt::python::bind_queries(m);
  gwnrt::python::bind_meshing(m);
  m.def("device_available", []() -> py::tuple {
    std::string why;
    const bool usable = gwnrt::cuda_usable(&why);
    return py::make_tuple(usable, why);
  });
  m.attr("has_cuda_backend") = gwnrt::cuda_backend_built();
}
