// write_surface_mesh (gwnrt/io/mesh_writer.h). Records are formatted straight into one fixed
// buffer that is flushed with fwrite: a soup is written without building it, and a
// million-triangle mesh costs a few hundred fwrite calls rather than an iostream call per number.
#include <algorithm>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "base/message.h"
#include "gwnrt/io/mesh_writer.h"
#include "gwnrt/io/output_file.h"
#include "io/text.h"

namespace gwnrt {
namespace {

// Output file

class OutFile {
 public:
  // The longest record one room() call may hold: an OBJ face line with three v/vt/vn corners of
  // 10-digit indices, or a vertex line of three 24-character doubles and three 15-character floats,
  // with margin.
  static constexpr size_t kMaxRecord = 256;

  explicit OutFile(std::string path) : out_(std::move(path)) {}
  OutFile(const OutFile&) = delete;
  OutFile& operator=(const OutFile&) = delete;

  // Beside the destination until close() (ReplacingFile): a failed or interrupted write, or one
  // never closed (an exception unwinding), leaves an existing file as it was, and a truncated OBJ
  // never passes for a smaller mesh.
  Status open() {
    if (Status s = out_.open(); !s.ok()) return s;
    f_ = out_.file();
    buf_.resize(size_t(1) << 20);
    return Status::Ok();
  }

  // Space for up to kMaxRecord bytes; the caller writes there and hands the end to commit().
  char* room() {
    if (buf_.size() - used_ < kMaxRecord) flush();
    return buf_.data() + used_;
  }
  void commit(char* end) { used_ = static_cast<size_t>(end - buf_.data()); }

  void write(std::string_view s) {
    while (!s.empty()) {
      const size_t n = std::min(s.size(), kMaxRecord);
      char* p = room();
      std::copy_n(s.data(), n, p);
      commit(p + n);
      s.remove_prefix(n);
    }
  }

  // Flushes, closes and puts the file in place, checking each step.
  Status close() {
    flush();
    f_ = nullptr;
    return out_.commit(failed_ ? (err_ ? err_ : EIO) : 0);
  }

 private:
  void flush() {
    if (used_ > 0 && !failed_) {
      errno = 0;
      if (std::fwrite(buf_.data(), 1, used_, f_) != used_) {
        failed_ = true;
        err_ = errno;
      }
    }
    used_ = 0;  // after a failure the rest is dropped; close() reports it
  }

  ReplacingFile out_;
  std::FILE* f_ = nullptr;
  std::vector<char> buf_;
  size_t used_ = 0;
  bool failed_ = false;
  int err_ = 0;
};

// Checks

template <glm::length_t N>
bool all_finite(const glm::vec<N, float>& v) {
  for (int k = 0; k < N; ++k) {
    if (!is_finite(v[k])) return false;
  }
  return true;
}

template <glm::length_t N>
std::string text(const glm::vec<N, float>& v) {
  std::string s = "(";
  for (int k = 0; k < N; ++k) s += cat(k ? ", " : "", v[k]);
  return s + ")";
}

template <class T>
Status check_size(const std::string& path, const std::vector<T>& a, const char* name, size_t n) {
  if (a.empty() || a.size() == n) return Status::Ok();
  return {StatusCode::kInvalidMesh, cat(path, ": inconsistent mesh: ", a.size(), " ", name, " for ", n,
                                        " positions (a per-vertex array is empty or as long as positions)")};
}

template <glm::length_t N>
Status check_finite(const std::string& path, const std::vector<glm::vec<N, float>>& a, const char* name) {
  for (size_t i = 0; i < a.size(); ++i) {
    if (!all_finite(a[i])) {
      return {StatusCode::kInvalidMesh, cat(path, ": vertex ", i, " has a non-finite ", name, " ", text(a[i]))};
    }
  }
  return Status::Ok();
}

Status check_mesh(const std::string& path, const SurfaceMesh& m) {
  const size_t n = m.positions.size();
  for (Status s : {check_size(path, m.normals, "normals", n), check_size(path, m.uvs, "uvs", n),
                   check_size(path, m.colors, "colors", n), check_size(path, m.source_triangles, "source_triangles", n),
                   check_size(path, m.source_barycentrics, "source_barycentrics", n)}) {
    if (!s.ok()) return s;
  }
  for (size_t t = 0; t < m.triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      if (m.triangles[t][k] >= n) {
        return {StatusCode::kInvalidMesh, cat(path, ": triangle ", t, " refers to vertex ", m.triangles[t][k],
                                              " but the mesh has ", n, " vertices")};
      }
    }
  }
  for (Status s : {check_finite(path, m.positions, "position"), check_finite(path, m.normals, "normal"),
                   check_finite(path, m.uvs, "uv"), check_finite(path, m.colors, "color"),
                   check_finite(path, m.source_barycentrics, "source barycentric")}) {
    if (!s.ok()) return s;
  }
  return Status::Ok();
}

// Calls fn(i) for the mesh vertex behind each output vertex: each vertex once, or each
// triangle corner in a soup.
template <class Fn>
void for_each_output_vertex(const SurfaceMesh& m, bool soup, Fn&& fn) {
  if (soup) {
    for (const uvec3& t : m.triangles) {
      fn(t.x);
      fn(t.y);
      fn(t.z);
    }
  } else {
    for (size_t i = 0; i < m.positions.size(); ++i) fn(i);
  }
}

// The output triangle t: its own corners in a soup.
uvec3 output_triangle(const SurfaceMesh& m, bool soup, size_t t) {
  if (!soup) return m.triangles[t];
  const auto b = static_cast<uint32_t>(3 * t);
  return {b, b + 1, b + 2};
}

// PLY

// Little-endian bytes by shifts, whatever the host's order (GCC merges them into one store on
// a little-endian host).
inline char* put_u32(char* p, uint32_t v) {
  p[0] = static_cast<char>(v & 0xff);
  p[1] = static_cast<char>((v >> 8) & 0xff);
  p[2] = static_cast<char>((v >> 16) & 0xff);
  p[3] = static_cast<char>(v >> 24);
  return p + 4;
}

inline char* put_f32(char* p, float v) { return put_u32(p, std::bit_cast<uint32_t>(v)); }

inline char* put_f64(char* p, double v) {
  const uint64_t bits = std::bit_cast<uint64_t>(v);
  p = put_u32(p, static_cast<uint32_t>(bits));
  return put_u32(p, static_cast<uint32_t>(bits >> 32));
}

template <glm::length_t N>
inline char* put_f32(char* p, const glm::vec<N, float>& v) {
  for (int k = 0; k < N; ++k) p = put_f32(p, v[k]);
  return p;
}

inline char to_u8(float c) { return static_cast<char>(std::lround(std::clamp(c, 0.0f, 1.0f) * 255.0f)); }

// A position as written: in the input's coordinates (MeshWriteOptions::origin).
inline dvec3 world_position(const SurfaceMesh& m, const dvec3& origin, size_t i) {
  return origin + dvec3(m.positions[i]);
}

void write_ply(OutFile& out, const SurfaceMesh& m, bool soup, size_t nverts, const dvec3& origin) {
  const bool wide = origin != dvec3(0.0);
  const bool has_n = !m.normals.empty();
  const bool has_c = !m.colors.empty();
  const bool has_uv = !m.uvs.empty();
  const bool has_st = !m.source_triangles.empty();
  const bool has_sb = !m.source_barycentrics.empty();

  const char* const xyz = wide ? "property double x\nproperty double y\nproperty double z\n"
                               : "property float x\nproperty float y\nproperty float z\n";
  std::string h =
      cat("ply\nformat binary_little_endian 1.0\ncomment written by gwnrt\nelement vertex ", nverts, "\n", xyz);
  if (has_n) h += "property float nx\nproperty float ny\nproperty float nz\n";
  if (has_c) h += "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n";
  // `u v`: the names the project's PLY conventions and most readers (Assimp, Blender) accept.
  if (has_uv) h += "property float u\nproperty float v\n";
  if (has_st) h += "property uint source_triangle\n";
  if (has_sb) h += "property float source_u\nproperty float source_v\n";
  h += cat("element face ", m.triangles.size(), "\nproperty list uchar int vertex_indices\nend_header\n");
  out.write(h);

  for_each_output_vertex(m, soup, [&](size_t i) {
    char* p = out.room();
    if (wide) {
      const dvec3 x = world_position(m, origin, i);
      for (int k = 0; k < 3; ++k) p = put_f64(p, x[k]);
    } else {
      p = put_f32(p, m.positions[i]);
    }
    if (has_n) p = put_f32(p, m.normals[i]);
    if (has_c) {
      for (int k = 0; k < 4; ++k) *p++ = to_u8(m.colors[i][k]);
    }
    if (has_uv) p = put_f32(p, m.uvs[i]);
    if (has_st) p = put_u32(p, m.source_triangles[i]);
    if (has_sb) p = put_f32(p, m.source_barycentrics[i]);
    out.commit(p);
  });
  for (size_t t = 0; t < m.triangles.size(); ++t) {
    const uvec3 tri = output_triangle(m, soup, t);
    char* p = out.room();
    *p++ = 3;
    // Indices are below 2^31 (checked), so the uint bits are those of the declared int.
    p = put_u32(p, tri.x);
    p = put_u32(p, tri.y);
    p = put_u32(p, tri.z);
    out.commit(p);
  }
}

// OBJ

// The shortest text that reads back to the same float (at most 9 significant digits).
inline char* put_float(char* p, float v) { return std::to_chars(p, p + 32, v).ptr; }

inline char* put_index(char* p, uint64_t v) { return std::to_chars(p, p + 24, v).ptr; }

template <glm::length_t N>
inline char* put_floats(char* p, const glm::vec<N, float>& v) {
  for (int k = 0; k < N; ++k) {
    *p++ = ' ';
    p = put_float(p, v[k]);
  }
  return p;
}

void write_obj(OutFile& out, const SurfaceMesh& m, bool soup, size_t nverts, const dvec3& origin) {
  const bool wide = origin != dvec3(0.0);
  const bool has_n = !m.normals.empty();
  const bool has_c = !m.colors.empty();
  const bool has_uv = !m.uvs.empty();

  out.write(cat("# written by gwnrt: ", nverts, " vertices, ", m.triangles.size(), " triangles\n"));
  for_each_output_vertex(m, soup, [&](size_t i) {
    char* p = out.room();
    *p++ = 'v';
    if (wide) {
      const dvec3 x = world_position(m, origin, i);
      for (int k = 0; k < 3; ++k) {
        *p++ = ' ';
        p = std::to_chars(p, p + 32, x[k]).ptr;  // the shortest text that reads back to the same double
      }
    } else {
      p = put_floats(p, m.positions[i]);
    }
    if (has_c) p = put_floats(p, glm::clamp(glm::vec3(m.colors[i]), 0.0f, 1.0f));
    *p++ = '\n';
    out.commit(p);
  });
  if (has_n) {
    for_each_output_vertex(m, soup, [&](size_t i) {
      char* p = out.room();
      *p++ = 'v';
      *p++ = 'n';
      p = put_floats(p, m.normals[i]);
      *p++ = '\n';
      out.commit(p);
    });
  }
  if (has_uv) {
    for_each_output_vertex(m, soup, [&](size_t i) {
      char* p = out.room();
      *p++ = 'v';
      *p++ = 't';
      p = put_floats(p, m.uvs[i]);
      *p++ = '\n';
      out.commit(p);
    });
  }
  // Every attribute is per vertex, so a corner's v, vt and vn indices are the same number.
  for (size_t t = 0; t < m.triangles.size(); ++t) {
    const uvec3 tri = output_triangle(m, soup, t);
    char* p = out.room();
    *p++ = 'f';
    for (int k = 0; k < 3; ++k) {
      const uint64_t i = uint64_t(tri[k]) + 1;
      *p++ = ' ';
      p = put_index(p, i);
      if (has_uv || has_n) {
        *p++ = '/';
        if (has_uv) p = put_index(p, i);
        if (has_n) {
          *p++ = '/';
          p = put_index(p, i);
        }
      }
    }
    *p++ = '\n';
    out.commit(p);
  }
}

// STL (binary): per facet its unit normal (from the corners, in double; 0 for a zero-area facet),
// the three corners and a zero attribute. The header does not begin with "solid", which some
// readers take for ASCII.
void write_stl(OutFile& out, const SurfaceMesh& m) {
  std::string header = "binary STL written by gwnrt";
  header.resize(80, ' ');
  out.write(header);
  char count[4];
  put_u32(count, static_cast<uint32_t>(m.triangles.size()));
  out.write(std::string_view(count, 4));
  for (const uvec3& t : m.triangles) {
    const dvec3 a(m.positions[t.x]), b(m.positions[t.y]), c(m.positions[t.z]);
    const dvec3 n = glm::cross(b - a, c - a);
    const double len = glm::length(n);
    char* p = out.room();
    p = put_f32(p, len > 0 ? vec3(n / len) : vec3(0.0f));
    for (int k = 0; k < 3; ++k) p = put_f32(p, m.positions[t[k]]);
    *p++ = 0;
    *p++ = 0;
    out.commit(p);
  }
}

Status write_unguarded(const std::string& path, const SurfaceMesh& mesh, const MeshWriteOptions& options) {
  MeshFileFormat format = options.format;
  if (format == MeshFileFormat::kAuto) {
    const std::string ext = io::lower_extension(path);
    if (ext == ".ply") {
      format = MeshFileFormat::kPly;
    } else if (ext == ".obj") {
      format = MeshFileFormat::kObj;
    } else if (ext == ".stl") {
      format = MeshFileFormat::kStl;
    } else {
      return {StatusCode::kInvalidArgument,
              cat(path, ": unknown mesh file extension '", ext, "' (expected .ply, .obj or .stl, or give the format)")};
    }
  }
  if (Status s = check_mesh(path, mesh); !s.ok()) return s;
  const dvec3& origin = options.origin;
  if (!std::isfinite(origin.x) || !std::isfinite(origin.y) || !std::isfinite(origin.z))
    return {StatusCode::kInvalidArgument, cat(path, ": the origin added to the positions is not finite (", origin.x,
                                              ", ", origin.y, ", ", origin.z, ")")};

  if (format == MeshFileFormat::kStl) {
    // STL holds float coordinates and nothing else: a recentred mesh would be rounded where it lies.
    if (origin != dvec3(0.0)) {
      return {StatusCode::kInvalidArgument,
              cat(path, ": STL holds float coordinates, which would round this mesh's positions where it lies (it was ",
                  "recentred about (", origin.x, ", ", origin.y, ", ", origin.z, ")); write .ply or .obj")};
    }
    if (mesh.triangles.size() > std::numeric_limits<uint32_t>::max())
      return {StatusCode::kInvalidMesh, cat(path, ": too many triangles for STL (", mesh.triangles.size(), ")")};
    OutFile out(path);
    if (Status s = out.open(); !s.ok()) return s;
    write_stl(out, mesh);
    return out.close();
  }
  // PLY indices are declared int; OBJ readers (ours included) index with 32 bits.
  const bool ply = format == MeshFileFormat::kPly;
  const uint64_t limit = ply ? uint64_t(1) << 31 : uint64_t(1) << 32;
  const uint64_t nverts = options.soup ? 3 * uint64_t(mesh.triangles.size()) : uint64_t(mesh.positions.size());
  if (nverts > limit) {
    return {StatusCode::kInvalidMesh,
            cat(path, ": too many vertices to write (", nverts, ", at most ", limit, " in ", ply ? "PLY" : "OBJ", ")")};
  }

  OutFile out(path);
  if (Status s = out.open(); !s.ok()) return s;
  if (ply) {
    write_ply(out, mesh, options.soup, nverts, origin);
  } else {
    write_obj(out, mesh, options.soup, nverts, origin);
  }
  return out.close();
}

}  // namespace

Status write_surface_mesh(const std::string& path, const SurfaceMesh& mesh, const MeshWriteOptions& options) {
  return guard_status(path.c_str(), [&] { return write_unguarded(path, mesh, options); });
}

}  // namespace gwnrt
