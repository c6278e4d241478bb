// load_mesh (gwnrt/io/mesh_io.h): the reader chosen by the extension, then validate_mesh.
#include <filesystem>

#include "gwnrt/io/mesh_io.h"
#include "gwnrt/io/read_file.h"
#include "io/readers.h"
#include "io/text.h"

namespace gwnrt {
namespace {

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) {
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  return ext;
}

Status load_mesh_unguarded(const std::string& path, Mesh& mesh, MeshLoadReport* report) {
  const std::string ext = lower_extension(path);
  const bool is_obj = ext == ".obj";
  if (!is_obj && ext != ".ply") {
    return {StatusCode::kInvalidArgument,
            cat(path, ": unsupported mesh file extension '", ext, "' (expected .obj or .ply)")};
  }
  std::string data;
  ReadLimits limits;
  if (!is_obj) limits.text_end = io::ply_text_end;  // lines are checked in the header and an ASCII body
  if (Status s = read_file(path, data, limits); !s.ok()) return s;
  // A UTF-8 byte-order mark (some Windows editors write one) is not content: left in, it glued
  // itself to the first keyword and the OBJ reader skipped that line.
  std::string_view content = data;
  if (content.substr(0, 3) == "\xEF\xBB\xBF") content.remove_prefix(3);

  Mesh m;
  MeshLoadReport rep;
  Status s = is_obj ? io::read_obj(path, content, m, rep) : io::read_ply(path, content, m, rep);
  if (!s.ok()) return s;
  if (s = validate_mesh(m, path); !s.ok()) return s;

  rep.vertex_count = m.positions.size();
  rep.triangle_count = m.triangles.size();
  rep.uv_count = m.uvs.size();
  rep.has_colors = !m.colors.empty();
  for (const uvec3& t : m.triangles) {
    rep.degenerate_triangles += is_degenerate_triangle(m.positions[t.x], m.positions[t.y], m.positions[t.z]);
  }
  mesh = std::move(m);
  if (report) *report = std::move(rep);
  return Status::Ok();
}

}  // namespace

Status load_mesh(const std::string& path, Mesh& mesh, MeshLoadReport* report) {
  return guard_status(path.c_str(), [&] { return load_mesh_unguarded(path, mesh, report); });
}

}  // namespace gwnrt
