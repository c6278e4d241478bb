// Writing a SurfaceMesh (the mesher's output) to binary PLY, OBJ or binary STL
// (core/src/io/mesh_writer.cpp).
//
// PLY is the complete format: it keeps every per-vertex array SurfaceMesh has, in binary so
// that a file read back holds the very floats that were written. OBJ is for tools that read
// nothing else; it keeps positions, normals, texture coordinates and (as the common `v x y z r g b`
// extension) colours, with the shortest decimal text that reads back to the same float.
//
// PLY layout (binary_little_endian 1.0, "comment written by gwnrt"): element vertex with
//   float x y z (double with an origin, MeshWriteOptions::origin); float nx ny nz (normals); uchar red green blue alpha
//   (colours, round(clamp(c, 0, 1)
//   * 255)); float u v (uvs); uint source_triangle (source_triangles); float source_u source_v
//   (source_barycentrics), each group only when its array is non-empty; element face with
//   `property list uchar int vertex_indices`.
// OBJ layout: `v x y z [r g b]`, `vn`, `vt`, then `f` with 1-based indices in the form that what
//   is present implies (v, v//vn, v/vt/vn, v/vt). Alpha and the source arrays have no place in
//   OBJ and are left out.
// STL layout: binary, an 80-byte header that does not begin "solid", the count, then per triangle
//   its normal from the corners, the corners in float and a zero attribute; no other array. A mesh
//   with an origin is refused (STL's float would round it where it lies).
#pragma once

#include <string>

#include "gwnrt/base/status.h"
#include "gwnrt/geometry/surface_mesh.h"

namespace gwnrt {

enum class MeshFileFormat {
  kAuto,  // by the path's extension, case-insensitive: .ply, .obj or .stl; any other is refused
  kPly,
  kObj,
  kStl  // binary STL: positions only, a soup by the format's nature
};

struct MeshWriteOptions {
  MeshFileFormat format = MeshFileFormat::kAuto;
  // Every triangle gets three vertices of its own (attributes duplicated): for tools that want
  // flat, unshared corners.
  bool soup = false;
  // Added to every position as it is written, in double: the MeshLoadReport::origin of a
  // recentred input (MeshLoadOptions::recentre), so that the output lies where the input did.
  // When it is not zero the positions are written in double (PLY `double x y z`; OBJ the
  // shortest text that reads back to the same double), since float would round them again.
  dvec3 origin{0.0};
};

// Writes `mesh` to `path` (replacing it). The mesh is checked before the file is opened, so an
// invalid mesh leaves an existing file untouched: each per-vertex array must be empty or as
// long as positions, every triangle index in range, and every float attribute finite (a NaN
// written out is unreadable to most tools). Failures name the file and the triangle, vertex or
// array; a write that fails part-way removes the partial file. A non-finite origin is refused.
// Nothing throws.
[[nodiscard]] Status write_surface_mesh(const std::string& path, const SurfaceMesh& mesh,
                                        const MeshWriteOptions& options = {});

}  // namespace gwnrt
