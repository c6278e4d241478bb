// Meshing S into numpy arrays (the SurfaceMesh's buffers handed over, not copied), writing a mesh
// to PLY/OBJ and the topology report.
#include <array>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "gwnrt/io/mesh_writer.h"
#include "gwnrt/meshing/extract_surface.h"
#include "gwnrt/meshing/mesh_quality.h"
#include "python_model.h"

namespace gwnrt::python {
namespace {

uint32_t attributes_named(const std::vector<std::string>& names) {
  uint32_t attributes = 0;
  for (const std::string& name : names) {
    const uint32_t attribute = mesh_attribute_named(name);
    if (attribute == 0) throw py::value_error("unknown attribute '" + name + "' (" + kMeshAttributeNames + ")");
    attributes |= attribute;
  }
  return attributes;
}

py::dict stats_dict(const MeshingStats& s) {
  py::dict d;
  d["grid"] = py::make_tuple(s.grid[0], s.grid[1], s.grid[2]);
  d["cell_size"] = s.cell_size;
  d["origin"] = py::make_tuple(s.origin[0], s.origin[1], s.origin[2]);
  d["active_blocks"] = s.active_blocks;
  d["corners"] = s.corners;
  d["crossing_edges"] = s.crossing_edges;
  d["sheet_edges"] = s.sheet_edges;
  d["smooth_edges"] = s.smooth_edges;
  d["fallback_edges"] = s.fallback_edges;
  d["capped_edges"] = s.capped_edges;
  d["multi_component_cells"] = s.multi_component_cells;
  d["open_edges"] = s.open_edges;
  d["rescouted_open_edges"] = s.rescouted_open_edges;
  d["self_intersections_repaired"] = s.self_intersections_repaired;
  d["repair_rounds"] = s.repair_rounds;
  d["repaired_vertex_moves"] = s.repaired_vertex_moves;
  d["self_intersections_left"] = s.self_intersections_left;
  d["bytes"] = s.bytes;
  d["seconds"] = s.seconds.total();
  d["message"] = s.message;
  return d;
}

// Every non-empty array of the mesh, under the names gwnrt.MeshResult uses.
py::dict mesh_dict(SurfaceMesh&& mesh) {
  py::dict d;
  d["vertices"] = adopt_rows<float>(std::move(mesh.positions), 3);
  d["faces"] = adopt_rows<int32_t>(std::move(mesh.triangles), 3);
  if (!mesh.normals.empty()) d["normals"] = adopt_rows<float>(std::move(mesh.normals), 3);
  if (!mesh.source_triangles.empty()) d["source_triangles"] = adopt_rows<int32_t>(std::move(mesh.source_triangles), 1);
  if (!mesh.source_barycentrics.empty())
    d["source_barycentrics"] = adopt_rows<float>(std::move(mesh.source_barycentrics), 2);
  if (!mesh.uvs.empty()) d["uvs"] = adopt_rows<float>(std::move(mesh.uvs), 2);
  if (!mesh.colors.empty()) d["colors"] = adopt_rows<float>(std::move(mesh.colors), 4);
  return d;
}

py::dict extract(const PythonModel& p, int64_t resolution, float cell_size, const std::string& method,
                 std::optional<float> level, float smooth_angle, bool soup, const std::vector<std::string>& attributes,
                 const std::string& winding_method, int64_t order, float beta, int64_t memory_budget, Threads threads,
                 const std::string& device) {
  MeshingOptions options;
  options.resolution = checked_integer<uint32_t>(resolution, "resolution (cells along the box's longest side)", 1);
  options.cell_size = cell_size;
  if (!meshing_method_named(method, options.method))
    throw py::value_error("method must be 'dc' (dual contouring) or 'mc' (marching cubes), got '" + method + "'");
  options.smooth_angle = smooth_angle;
  options.soup = soup;
  options.attributes = attributes_named(attributes);
  options.winding.method = winding_method_argument(winding_method);
  options.winding.taylor.order = checked_integer<int>(order, "order");
  options.winding.taylor.beta = beta;
  options.memory_budget = checked_integer<uint64_t>(memory_budget, "memory_budget (bytes)", 0, INT64_MAX);
  const Device where = device_argument(device);
  SurfaceMesh mesh;
  MeshingStats stats;
  check(run_released(threads, [&] {
    std::shared_lock lock(p.level_mutex);
    options.level = level_or_default(p, level);
    return p.engine.extract_surface(where, options, mesh, &stats);
  }));
  py::dict out = mesh_dict(std::move(mesh));
  out["stats"] = stats_dict(stats);
  return out;
}

// Rows of `obj` into a vector of V (width floats each); None or an empty array leaves it empty.
template <class V>
void rows_into(const py::handle& obj, const char* name, py::ssize_t width, std::vector<V>& out) {
  if (obj.is_none()) return;
  const FloatArray rows = float_rows(obj, name, width);
  out.resize(size_t(rows.shape(0)));
  if (!out.empty()) std::memcpy(out.data(), rows.data(), out.size() * sizeof(V));
}

SurfaceMesh surface_mesh(const py::handle& vertices, const py::handle& faces, const py::handle& normals = py::none(),
                         const py::handle& uvs = py::none(), const py::handle& colors = py::none(),
                         const py::handle& source_triangles = py::none(),
                         const py::handle& source_barycentrics = py::none()) {
  SurfaceMesh mesh;
  rows_into(vertices, "vertices", 3, mesh.positions);
  rows_into(normals, "normals", 3, mesh.normals);
  rows_into(uvs, "uvs", 2, mesh.uvs);
  rows_into(colors, "colors", 4, mesh.colors);
  rows_into(source_barycentrics, "source_barycentrics", 2, mesh.source_barycentrics);
  if (!source_triangles.is_none()) mesh.source_triangles = source_triangle_rows(source_triangles);
  mesh.triangles = face_rows(faces, mesh.positions.size());
  return mesh;
}

void write_mesh(const std::string& path, const py::handle& vertices, const py::handle& faces, const py::handle& normals,
                const py::handle& uvs, const py::handle& colors, const py::handle& source_triangles,
                const py::handle& source_barycentrics, const std::string& format, bool soup,
                const std::array<double, 3>& origin) {
  MeshWriteOptions options;
  options.origin = dvec3(origin[0], origin[1], origin[2]);
  if (format == "auto")
    options.format = MeshFileFormat::kAuto;
  else if (format == "ply")
    options.format = MeshFileFormat::kPly;
  else if (format == "obj")
    options.format = MeshFileFormat::kObj;
  else if (format == "stl")
    options.format = MeshFileFormat::kStl;
  else
    throw py::value_error("format must be 'auto', 'ply', 'obj' or 'stl', got '" + format + "'");
  options.soup = soup;
  const SurfaceMesh mesh = surface_mesh(vertices, faces, normals, uvs, colors, source_triangles, source_barycentrics);
  check(run_released(std::nullopt, [&] { return write_surface_mesh(path, mesh, options); }));
}

py::dict topology(const py::handle& vertices, const py::handle& faces, bool weld) {
  const SurfaceMesh mesh = surface_mesh(vertices, faces);
  MeshTopology t;
  check(run_released(std::nullopt, [&] { return mesh_topology(mesh, t, weld); }));
  py::dict d;
  d["vertices"] = t.vertices;
  d["unreferenced_vertices"] = t.unreferenced_vertices;
  d["triangles"] = t.triangles;
  d["degenerate_triangles"] = t.degenerate_triangles;
  d["boundary_edges"] = t.boundary_edges;
  d["non_manifold_edges"] = t.non_manifold_edges;
  d["non_manifold_vertices"] = t.non_manifold_vertices;
  d["inconsistent_edges"] = t.inconsistent_edges;
  d["components"] = t.components;
  d["watertight"] = t.watertight();
  d["manifold"] = t.manifold();
  d["closed_manifold"] = t.closed_manifold();
  return d;
}

}  // namespace

void bind_meshing(py::module_& m) {
  m.def("extract_surface", &extract, py::arg("model"), py::arg("resolution") = int64_t(256),
        py::arg("cell_size") = 0.0f, py::arg("method") = "dc", py::arg("level") = py::none(),
        py::arg("smooth_angle") = 30.0f, py::arg("soup") = false, py::arg("attributes") = std::vector<std::string>{},
        py::arg("winding_method") = "auto", py::arg("order") = 2, py::arg("beta") = 2.0f,
        py::arg("memory_budget") = int64_t(8) << 30, py::arg("threads") = py::none(), py::arg("device") = "cpu");
  m.def("write_mesh", &write_mesh, py::arg("path"), py::arg("vertices"), py::arg("faces"),
        py::arg("normals") = py::none(), py::arg("uvs") = py::none(), py::arg("colors") = py::none(),
        py::arg("source_triangles") = py::none(), py::arg("source_barycentrics") = py::none(),
        py::arg("format") = "auto", py::arg("soup") = false, py::arg("origin") = std::array<double, 3>{0.0, 0.0, 0.0});
  m.def("mesh_topology", &topology, py::arg("vertices"), py::arg("faces"), py::arg("weld") = false);
}

}  // namespace gwnrt::python
