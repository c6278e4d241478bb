// What the tests of the mesh readers share: a directory of their own for each test's files, the
// check of a mesh read back, and the text of small inputs.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include <gtest/gtest.h>

#include "gwnrt/geometry/mesh.h"
#include "mesh_files.h"

namespace gwnrt {
// Each test's files in a directory of its own (test::TempDirTest).
class TempFiles : public test::TempDirTest {};

inline void expect_mesh(const Mesh& m, const std::vector<vec3>& pos, const std::vector<uvec3>& tris) {
  ASSERT_EQ(m.positions.size(), pos.size());
  for (size_t i = 0; i < pos.size(); ++i) EXPECT_EQ(m.positions[i], pos[i]) << "vertex " << i;
  ASSERT_EQ(m.triangles.size(), tris.size());
  for (size_t i = 0; i < tris.size(); ++i) EXPECT_EQ(m.triangles[i], tris[i]) << "triangle " << i;
}

inline const std::string kTri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";  // lines 1-3

// Nine lines; counts are text so that a test can declare counts no real file could hold.
inline std::string ply_header(std::string_view format, const std::string& nv, const std::string& nf,
                              std::string_view index_type = "int") {
  return "ply\nformat " + std::string(format) + " 1.0\nelement vertex " + nv +
         "\nproperty float x\nproperty float y\nproperty float z\nelement face " + nf + "\nproperty list uchar " +
         std::string(index_type) + " vertex_indices\nend_header\n";
}

inline std::string ply_header(std::string_view format, int nv, int nf, std::string_view index_type = "int") {
  return ply_header(format, std::to_string(nv), std::to_string(nf), index_type);
}

}  // namespace gwnrt
