// w at points exactly on M (a face, an edge, a corner): the mean of its one-sided limits, by every
// method the queries offer, against analytic values; and the near field's solid angle of a
// triangle through its own points.
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "gwnrt/field/solid_angle.h"
#include "gwnrt/field/winding_number.h"
#include "gwnrt/query/batch.h"
#include "test_util.h"

namespace gwnrt {
namespace {

using test::build_model;

// w at x by each method the queries offer (and the tree at each order), by name.
struct MethodValue {
  std::string name;
  float w;
};
std::vector<MethodValue> w_by_every_method(const GwnModel& model, const vec3& x) {
  std::vector<MethodValue> out;
  const std::pair<WindingMethod, const char*> methods[] = {{WindingMethod::kAuto, "auto"},
                                                           {WindingMethod::kCrossing, "crossing"},
                                                           {WindingMethod::kTaylor, "taylor"},
                                                           {WindingMethod::kBrute, "brute"}};
  for (const auto& [method, name] : methods)
    for (int order = 0; order <= (method == WindingMethod::kTaylor ? 2 : 0); ++order) {
      QueryRequest request;
      request.method = method;
      request.taylor.order = method == WindingMethod::kTaylor ? order : 2;
      const PointResult r = evaluate_point(model.view(), x, request);
      out.push_back({std::string(name) + (method == WindingMethod::kTaylor ? std::to_string(order) : ""), r.w});
    }
  return out;
}

// Item 7: on M, w is the mean of its one-sided limits, the average of w over a small sphere
// about x: for a closed mesh 1/2 on a face, the interior dihedral angle over 2π on an edge, the
// corner's solid angle over 4π at a vertex (solid_angle.h, point_on_triangle). Analytic values;
// every method must give them (the tree's far clusters within its 2e-3, the others within 1e-5).
void expect_on_mesh_values(const GwnModel& model, const std::vector<std::pair<vec3, double>>& cases) {
  for (const auto& [x, expected] : cases)
    for (const MethodValue& v : w_by_every_method(model, x)) {
      const double tolerance = v.name.rfind("taylor", 0) == 0 ? 2e-3 : 1e-5;
      EXPECT_NEAR(v.w, expected, tolerance) << v.name << " at (" << x.x << ", " << x.y << ", " << x.z << ")";
    }
}

TEST(OnMesh, CubeFacesEdgesAndCornersTakeTheMeanOfBothSides) {
  const GwnModel model = build_model(test::make_cube());  // [-1, 1]³
  std::vector<std::pair<vec3, double>> cases = {
      {{0, 0, -1}, 0.5},         // the bottom face's diagonal, where a reported cube gave -0.5
      {{0.25f, 0.5f, 1}, 0.5},   // inside a top triangle
      {{-1, 0.3f, 0.1f}, 0.5},   // a side face
      {{1, 0, -1}, 0.25},        // an edge: the dihedral angle π/2 over 2π
      {{0, -1, 1}, 0.25},        //
      {{1, 1, 1}, 0.125},        // a corner: an octant
      {{-1, -1, -1}, 0.125},     //
      {{-1, 1, -0.75f}, 0.25}};  // an edge, off its midpoint
  // Random points of the faces (coordinates exactly ±1 on one axis).
  test::Random random(7);
  for (int i = 0; i < 40; ++i) {
    vec3 x(random.uniform(-1, 1), random.uniform(-1, 1), random.uniform(-1, 1));
    x[i % 3] = i % 2 ? 1.0f : -1.0f;
    cases.push_back({x, 0.5});
  }
  expect_on_mesh_values(model, cases);
}

TEST(OnMesh, TetrahedronEdgesAndCornersTakeTheMeanOfBothSides) {
  Mesh tet;
  tet.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  tet.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};  // outward
  const GwnModel model = build_model(std::move(tet));
  // The slanted face's dihedral angle with each axis face: acos(1/√3), 1.152 rad.
  const double slanted = std::acos(1.0 / std::sqrt(3.0)) / (2.0 * kPi);
  // The corner (1, 0, 0) by Girard: its dihedral angles π/2, acos(1/√3) twice, less π.
  const double corner = (kPi / 2 + 2 * std::acos(1.0 / std::sqrt(3.0)) - kPi) / (4.0 * kPi);
  expect_on_mesh_values(model, {{{0.5f, 0.5f, 0}, slanted},
                                {{0, 0.5f, 0.5f}, slanted},
                                {{0.5f, 0, 0}, 0.25},
                                {{0, 0, 0.25f}, 0.25},
                                {{0, 0, 0}, 0.125},
                                {{1, 0, 0}, corner},
                                {{0, 0, 1}, corner},
                                {{0.25f, 0.25f, 0}, 0.5},
                                {{0.25f, 0.25f, 0.5f}, 0.5}});
}

// One near triangle's Ω as the tree's near field takes it (TaylorSum::near): in float where
// that is well-conditioned, else in double.
float near_solid_angle(const vec3& a, const vec3& b, const vec3& c, const vec3& x) {
  float omega;
  if (near_solid_angle_float(a, b, c, x, omega)) return omega;
  return float(triangle_solid_angle(dvec3(a), dvec3(b), dvec3(c), dvec3(x), true));
}

TEST(OnMesh, NearFieldCountsTrianglesThroughTheirPointsAsZero) {
  // x on the triangle (inside, on an edge, on a corner) counts 0, in the float near field (which
  // decides it in double) and in double; beside it in its plane, and off its plane, the solid
  // angle is its own (the octant triangle's π/2 from the origin; ±2π at 1e-3 of its face).
  const vec3 a(2, 0, 0), b(0, 2, 0), c(0, 0, 2);
  for (const vec3& x : {vec3(1, 1, 0), vec3(0.5f, 0.5f, 1), vec3(2, 0, 0), vec3(0.25f, 0.75f, 1.0f)}) {
    EXPECT_EQ(near_solid_angle(a, b, c, x), 0.0f);
    EXPECT_EQ(triangle_solid_angle(dvec3(a), dvec3(b), dvec3(c), dvec3(x), true), 0.0);
  }
  EXPECT_NEAR(near_solid_angle(a, b, c, vec3(2, 2, -2)), 0.0f, 1e-6f);  // in its plane, beside it
  EXPECT_NEAR(near_solid_angle(a, b, c, vec3(0.0f)), float(kPi / 2), 1e-6f);
  const vec3 n = glm::normalize(vec3(1, 1, 1));
  const vec3 centre(2.0f / 3.0f);
  EXPECT_NEAR(near_solid_angle(a, b, c, centre - 1e-3f * n), 2 * kPi, 0.01);
  EXPECT_NEAR(near_solid_angle(a, b, c, centre + 1e-3f * n), -2 * kPi, 0.01);
}

}  // namespace
}  // namespace gwnrt
