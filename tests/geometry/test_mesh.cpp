// The checks of a mesh in memory (geometry/mesh.h): the exact test for zero-area triangles, and
// validate_mesh on non-finite coordinates, indices out of range and the attribute arrays.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "gwnrt/geometry/mesh.h"

namespace gwnrt {
namespace {

TEST(MeshIoDegenerate, ExactTest) {
  EXPECT_FALSE(is_degenerate_triangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}));
  EXPECT_TRUE(is_degenerate_triangle({0, 0, 0}, {1, 2, 3}, {2, 4, 6}));
  EXPECT_TRUE(is_degenerate_triangle({1, 2, 3}, {1, 2, 3}, {4, 5, 7}));
  EXPECT_TRUE(is_degenerate_triangle({1, 2, 3}, {1, 2, 3}, {1, 2, 3}));
  // The product of the edges underflows in float but not in double.
  EXPECT_FALSE(is_degenerate_triangle({0, 0, 0}, {1e-30f, 0, 0}, {0, 1e-30f, 0}));
  // Nearly but not exactly collinear.
  EXPECT_FALSE(is_degenerate_triangle({0, 0, 0}, {1, 1, 1}, {2, 2, std::nextafter(2.0f, 3.0f)}));
}

// ---------------------------------------------------------------------------------------
// validate_mesh

Mesh tetrahedron() {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return m;
}

TEST(MeshIoValidate, InMemory) {
  EXPECT_TRUE(validate_mesh(tetrahedron()).ok());

  Mesh m = tetrahedron();
  m.positions[1] = {std::numeric_limits<float>::quiet_NaN(), 0, 1};
  Status s = validate_mesh(m, "src");
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
  EXPECT_EQ(s.message(), "src: vertex 1 has a non-finite coordinate (nan, 0, 1)");

  m = tetrahedron();
  m.positions[3].z = -std::numeric_limits<float>::infinity();
  s = validate_mesh(m);
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
  EXPECT_EQ(s.message(),
            "mesh: vertex 3 has a non-finite coordinate (0, 0, -inf): infinite, or beyond float's range (+-3.4e38)");

  m = tetrahedron();
  m.triangles[2] = {0, 7, 2};
  s = validate_mesh(m, "src");
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
  EXPECT_EQ(s.message(), "src: triangle 2 refers to vertex 7 but there are 4 vertices");

  m = tetrahedron();
  m.triangles.clear();
  s = validate_mesh(m, "src");
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
  EXPECT_EQ(s.message(), "src: the mesh has no triangles");

  s = validate_mesh(Mesh{}, "src");
  EXPECT_FALSE(s.ok());

  // Degenerate triangles are valid.
  m = tetrahedron();
  m.triangles.push_back({1, 1, 2});
  EXPECT_TRUE(validate_mesh(m).ok());
}

TEST(MeshIoValidate, Attributes) {
  Mesh m = tetrahedron();
  ASSERT_TRUE(validate_mesh(m).ok());
  Mesh bad = m;
  bad.uv_triangles = {{0, 0, 0}};
  bad.uvs = {{0, 0}};
  EXPECT_NE(validate_mesh(bad).message().find("UV triangles for"), std::string::npos);
  bad = m;
  bad.uvs = {{0, 0}};
  EXPECT_NE(validate_mesh(bad).message().find("no UV triangles"), std::string::npos);
  bad = m;
  bad.uvs = {{0, 0}, {1, 0}};
  bad.uv_triangles.assign(m.triangles.size(), uvec3(0, 1, 2));
  EXPECT_NE(validate_mesh(bad).message().find("refers to texture coordinate 2"), std::string::npos)
      << validate_mesh(bad).message();
  bad.uvs.push_back({std::numeric_limits<float>::infinity(), 0});
  EXPECT_NE(validate_mesh(bad).message().find("texture coordinate 2 is not finite"), std::string::npos);
  bad = m;
  bad.colors = {{1, 1, 1, 1}};
  EXPECT_NE(validate_mesh(bad).message().find("vertex colours for"), std::string::npos);
  bad.colors.assign(m.positions.size(), glm::vec4(1));
  EXPECT_TRUE(validate_mesh(bad).ok());
  bad.colors[1].g = std::numeric_limits<float>::quiet_NaN();
  EXPECT_NE(validate_mesh(bad).message().find("vertex 1 has a non-finite colour"), std::string::npos);
}

}  // namespace
}  // namespace gwnrt
