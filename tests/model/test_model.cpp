// What a model serves: levels w never reaches (no surface to trace or mesh, and a message that
// says so), and the scales of meshes and points (every answer right across the scales it serves,
// refused beyond them, far from the origin while float resolves the mesh, far points up to the
// query limit and refused beyond it).
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "gwnrt/field/winding_number.h"
#include "gwnrt/meshing/extract_surface.h"
#include "gwnrt/query/batch.h"
#include "test_util.h"

namespace gwnrt {
namespace {

using test::build_model;
using test::load_test_mesh;
// Item 4: |w| < n/2 for n triangles, so a level at or beyond it has no surface: no hit, no sheet
// with a flipped normal (a level of 3e9 overflowed the tracer's integer band), an empty
// mesh that says why; levels within reach still trace.
TEST(UnreachableLevel, TracesNoSurfaceAndMeshesNothing) {
  const GwnModel model = build_model(load_test_mesh("bunny_holes.obj"));
  const float n_half = 0.5f * float(model.view().triangles.triangle_count);
  const Aabb box = model.bounds();
  test::Random random(3);
  std::vector<Ray> rays;
  for (int i = 0; i < 64; ++i) {
    Ray ray;
    ray.origin = box.centre() + 2.0f * (box.hi - box.lo) * random.unit();
    ray.direction = random.in_box(box) - ray.origin;
    rays.push_back(ray);
  }
  std::vector<RayHit> hits(rays.size());
  TraceOptions options;
  ASSERT_TRUE(trace_rays(model, rays, options, hits).ok());
  int reference_hits = 0;
  for (const RayHit& h : hits) reference_hits += h.hit;
  EXPECT_GT(reference_hits, 32);  // the rays aim at the bunny: most hit S at 1/2
  for (float level : {3e9f, -3e9f, 1e30f, -1e30f, 2.2e9f, n_half, -n_half, std::nextafter(n_half, 1e30f)}) {
    options.level = level;
    ASSERT_TRUE(trace_rays(model, rays, options, hits).ok()) << level;
    for (size_t i = 0; i < hits.size(); ++i) {
      EXPECT_FALSE(hits[i].hit) << "level " << level << " ray " << i;
      EXPECT_FALSE(hits[i].invalid) << "level " << level << " ray " << i;
    }
    MeshingOptions meshing;
    meshing.level = level;
    meshing.resolution = 16;
    SurfaceMesh out;
    MeshingStats stats;
    ASSERT_TRUE(extract_surface(model, meshing, out, &stats).ok()) << level;
    EXPECT_TRUE(out.positions.empty()) << level;
    EXPECT_NE(stats.message.find("outside every value w takes"), std::string::npos) << stats.message;
  }
  // Solid-angle mode takes the level modulo one turn: any finite level is a surface.
  options.mode = TraceMode::kSolidAngle;
  options.level = 3e9f + 0.5f;  // a whole number in float: the level set Ω ≡ 0
  ASSERT_TRUE(trace_rays(model, rays, options, hits).ok());
  for (const RayHit& h : hits) EXPECT_FALSE(h.invalid);
}

// Item 6: scales. The tetrahedron with corners 0, s·e_x, s·e_y, s·e_z (outward), across the
// scales a model serves, against its closed forms: w = 1 inside and 0 outside by every method;
// the distance from (-k s, s/4, s/4) is k s (its foot lies inside the face x = 0), the signed
// distance the same, positive; the ray along +x from there hits the face at t = k s with normal
// -x. A tetrahedron at 1e13 gave w = 0.938, at 1e20 NaN, its distances were 1.4-3x too
// large beyond 1e10 and below 1e-11, its trace normals 0 or NaN.
// The fields asked for at every point, by one method (ASSERTs that the batch ran).
std::vector<PointResult> evaluated(const GwnModel& model, const std::vector<vec3>& points, WindingMethod method,
                                   uint32_t fields) {
  QueryRequest request;
  request.method = method;
  request.fields = fields;
  std::vector<PointResult> r(points.size());
  const Status s = evaluate_points(model, points, request, r);
  EXPECT_TRUE(s.ok()) << s.message();
  return r;
}

Mesh scaled_tetrahedron(float s) {
  Mesh tet;
  tet.positions = {{0, 0, 0}, {s, 0, 0}, {0, s, 0}, {0, 0, s}};
  tet.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return tet;
}

TEST(Scale, EveryAnswerIsRightAcrossTheServedScales) {
  for (const float s : {kMinMeshExtent, 1e-6f, 1e-3f, 1.0f, 1e3f, 1e6f, kMaxMeshCoordinate}) {
    const GwnModel model = build_model(scaled_tetrahedron(s));
    for (const float k : {0.1f, 3.0f, 1e3f, 1e6f}) {
      const vec3 outside(-k * s, 0.25f * s, 0.25f * s);
      const vec3 inside(0.2f * s, 0.2f * s, 0.2f * s);
      for (const WindingMethod method : {WindingMethod::kCrossing, WindingMethod::kTaylor, WindingMethod::kBrute}) {
        const std::vector<PointResult> r = evaluated(model, {outside, inside}, method,
                                                     kFieldW | kFieldGradient | kFieldHessian | kFieldUnsignedDistance |
                                                         kFieldSignedDistance | kFieldHarnackBound);
        const std::string where =
            "scale " + std::to_string(s) + " k " + std::to_string(k) + " method " + std::to_string(int(method));
        EXPECT_NEAR(r[0].w, 0.0f, 2e-3f) << where;  // the tree's promised accuracy
        EXPECT_NEAR(r[1].w, 1.0f, 2e-3f) << where;
        EXPECT_NEAR(r[0].unsigned_distance / (k * s), 1.0f, 1e-5f) << where;
        EXPECT_NEAR(r[0].sdf.distance / (k * s), 1.0f, 1e-5f) << where;
        EXPECT_GT(r[1].sdf.distance, -0.3f * s) << where;  // inside: negative, at most the inradius
        EXPECT_LT(r[1].sdf.distance, 0.0f) << where;
        EXPECT_LE(r[0].harnack_bound, r[0].unsigned_distance * (1 + 1e-6f)) << where;
        for (int i = 0; i < 2; ++i) {
          EXPECT_TRUE(std::isfinite(r[i].gradient.x) && std::isfinite(r[i].gradient.y) &&
                      std::isfinite(r[i].gradient.z))
              << where;
          EXPECT_TRUE(std::isfinite(r[i].hessian.xx) && std::isfinite(r[i].hessian.xy)) << where;
        }
      }
      Ray ray;
      ray.origin = outside;
      ray.direction = vec3(1, 0, 0);
      const std::vector<Ray> rays = {ray};
      std::vector<RayHit> hits(1);
      ASSERT_TRUE(trace_rays(model, rays, TraceOptions{}, hits).ok());
      ASSERT_TRUE(hits[0].hit) << s;
      EXPECT_NEAR(hits[0].t / (k * s), 1.0f, 1e-5f) << s;
      EXPECT_EQ(hits[0].normal, vec3(-1, 0, 0)) << s;
    }
  }
}

TEST(Scale, MeshesBeyondTheServedScalesAreRefusedSayingSo) {
  for (const float s : {1e9f, 1e13f, 1e20f, 1e30f, 1e-9f, 1e-14f, 1e-30f}) {
    GwnModel model;
    const Status status = GwnModel::build(scaled_tetrahedron(s), model);
    ASSERT_FALSE(status.ok()) << s;
    EXPECT_NE(status.message().find("scale the mesh"), std::string::npos) << status.message();
  }
  // Only the triangles' corners count: a far vertex no triangle uses is no scale of the mesh.
  Mesh unused = scaled_tetrahedron(1.0f);
  unused.positions.push_back({1e30f, 0, 0});
  GwnModel model;
  EXPECT_TRUE(GwnModel::build(std::move(unused), model).ok());
}

TEST(Scale, MeshesFarFromTheOriginAreServedWhileFloatResolvesThem) {
  // The unit tetrahedron moved by o along (1,1,1). Served (box diagonal >= 1e-4 of o): w, the
  // distance and the sdf from a point 2 in front of the face x = o, and the ray from it, right to
  // the points' own rounding (a step of 2^-10 at 1e4). Beyond, refused: at 1e6 S was empty (the
  // sheets' probe step spanned the mesh) and the sdf infinite.
  for (const float o : {1e3f, 1e4f}) {
    Mesh tet = scaled_tetrahedron(1.0f);
    for (vec3& p : tet.positions) p += vec3(o);
    const GwnModel model = build_model(tet);
    const vec3 outside(o - 2.0f, o + 0.25f, o + 0.25f), inside(o + 0.2f, o + 0.2f, o + 0.2f);
    const std::vector<PointResult> r = evaluated(model, {outside, inside}, WindingMethod::kAuto,
                                                 kFieldW | kFieldUnsignedDistance | kFieldSignedDistance);
    EXPECT_NEAR(r[0].w, 0.0f, 2e-3f) << o;
    EXPECT_NEAR(r[1].w, 1.0f, 2e-3f) << o;
    EXPECT_NEAR(r[0].sdf.distance, 2.0f, 2e-3f) << o;
    EXPECT_NEAR(r[1].sdf.distance, -(inside.x - o), 2e-3f) << o;  // nearest: the face x = o
    Ray ray;
    ray.origin = outside;
    ray.direction = vec3(1, 0, 0);
    std::vector<RayHit> hits(1);
    ASSERT_TRUE(trace_rays(model, std::vector<Ray>{ray}, TraceOptions{}, hits).ok());
    ASSERT_TRUE(hits[0].hit) << o;
    EXPECT_NEAR(hits[0].t, 2.0f, 2e-3f) << o;
  }
  for (const float o : {1e5f, 1e6f, 1e7f, -3e7f}) {
    Mesh tet = scaled_tetrahedron(1.0f);
    for (vec3& p : tet.positions) p += vec3(o);
    GwnModel model;
    const Status status = GwnModel::build(std::move(tet), model);
    ASSERT_FALSE(status.ok()) << o;
    EXPECT_NE(status.message().find("translate the mesh near the origin"), std::string::npos) << status.message();
  }
}

TEST(Scale, RaysFromFarAwayHitWhereRaysFromNearbyDo) {
  // Lines through the unit tetrahedron along the axes (so that the far origins and directions are
  // exact in float and the far and near rays share their line), started 3 units before the mesh
  // and 1e4 to 1e30 units before: the same hit point and normal, t the distance to within float's
  // step there. From 1e8 the ray's own t stepped by 8 and the tetrahedron was missed.
  const GwnModel model = build_model(scaled_tetrahedron(1.0f));
  test::Random rng(7);
  for (int line = 0; line < 60; ++line) {
    const int axis = line % 3;
    const float sign = (line / 3) % 2 ? 1.0f : -1.0f;
    vec3 across(rng.uniform(0.05f, 0.4f), rng.uniform(0.05f, 0.4f), rng.uniform(0.05f, 0.4f));
    vec3 d(0.0f);
    d[axis] = sign;
    std::vector<Ray> rays;
    std::vector<double> backs;
    for (const float back : {3.0f, 1e4f, 1e8f, 1e18f, 1e30f}) {
      Ray r;
      r.origin = across;
      r.origin[axis] = -sign * back;
      r.direction = d;
      rays.push_back(r);
      backs.push_back(back);
    }
    std::vector<RayHit> hits(rays.size());
    ASSERT_TRUE(trace_rays(model, rays, TraceOptions{}, hits).ok());
    ASSERT_TRUE(hits[0].hit) << line;
    for (size_t k = 1; k < rays.size(); ++k) {
      const std::string where = "line " + std::to_string(line) + " from " + std::to_string(backs[k]);
      ASSERT_TRUE(hits[k].hit) << where;
      EXPECT_LT(glm::length(hits[k].position - hits[0].position), 1e-5f) << where;
      EXPECT_LT(glm::length(hits[k].normal - hits[0].normal), 1e-5f) << where;
      const double distance = backs[k] + double(sign * hits[0].position[axis]);
      EXPECT_NEAR(hits[k].t, distance, 1.2e-7 * distance) << where;
    }
  }
  // A far ray's tnear and tfar are where they say: from -1e8 along +x, the tetrahedron moved to
  // x in [2, 3] (its centre 1e8 + 2.5 ahead: a float shift rounded that by 2.5, and the ray
  // started inside the mesh, hitting its far side, or ended past its first face).
  {
    Mesh moved = scaled_tetrahedron(1.0f);
    for (vec3& p : moved.positions) p.x += 2.0f;
    const GwnModel moved_model = build_model(moved);
    std::vector<Ray> rays(2);
    for (Ray& r : rays) {
      r.origin = vec3(-1e8f, 0.1f, 0.2f);
      r.direction = vec3(1, 0, 0);
    }
    rays[0].tnear = 1e8f;  // starts at x = 0
    rays[1].tfar = 1e8f;   // ends at x = 0
    std::vector<RayHit> hits(rays.size());
    ASSERT_TRUE(trace_rays(moved_model, rays, TraceOptions{}, hits).ok());
    ASSERT_TRUE(hits[0].hit);
    EXPECT_NEAR(hits[0].position.x, 2.0f, 1e-5f);  // the face x = 2, entered
    EXPECT_FALSE(hits[1].hit);
  }
  // Along a general direction from 1e4 (the far origin's rounding moves the line by 1e-3 there).
  for (int line = 0; line < 40; ++line) {
    const vec3 target(rng.uniform(0.05f, 0.3f), rng.uniform(0.05f, 0.3f), rng.uniform(0.05f, 0.3f));
    const vec3 d = rng.unit();
    std::vector<Ray> rays(2);
    rays[0].origin = vec3(dvec3(target) - 3.0 * dvec3(d));
    rays[1].origin = vec3(dvec3(target) - 1e4 * dvec3(d));
    rays[0].direction = rays[1].direction = d;
    std::vector<RayHit> hits(rays.size());
    ASSERT_TRUE(trace_rays(model, rays, TraceOptions{}, hits).ok());
    ASSERT_TRUE(hits[0].hit && hits[1].hit) << line;
    EXPECT_LT(glm::length(hits[1].position - hits[0].position), 1e-2f) << line;
  }
}

TEST(Scale, GradientWithinRoundingOfAVertexOrAnEdgeIsFinite) {
  // Points 1e-20 from a vertex and from an edge's line of the unit tetrahedron: |g_i × g_j|² is
  // denormal in float there, and f/|c|² · c gave 0·inf = NaN in ∇w, H_w and the sdf's first
  // order. ∇w (about 1/(4π) a component here, each edge's term ~1e20) as the double brute force;
  // H_w's per-triangle terms reach 1e40, beyond float, and cancel between triangles: not NaN.
  const GwnModel model = build_model(scaled_tetrahedron(1.0f));
  const std::vector<vec3> points = {{0.0f, 1e-20f, 1e-20f},
                                    {1e-20f, 1e-20f, 0.0f},
                                    {0.5f, 1e-20f, 1e-20f},
                                    {0.3f, 1e-25f, 0.0f},
                                    {0.0f, 0.4f, 3e-21f}};
  for (const WindingMethod method : {WindingMethod::kCrossing, WindingMethod::kTaylor}) {
    const std::vector<PointResult> r =
        evaluated(model, points, method, kFieldW | kFieldGradient | kFieldHessian | kFieldPseudoDistance);
    for (size_t i = 0; i < points.size(); ++i) {
      const std::string where = "point " + std::to_string(i) + " method " + winding_method_name(method);
      const WindingSampleExact e = winding_number_exact(model.triangle_view(), points[i], true);
      EXPECT_LE(glm::length(dvec3(r[i].gradient) - e.gradient), 1e-4 * (1.0 + glm::length(e.gradient))) << where;
      const Sym3<float>& h = r[i].hessian;
      for (const float v : {h.xx, h.xy, h.xz, h.yy, h.yz, h.zz}) EXPECT_FALSE(std::isnan(v)) << where;
      EXPECT_TRUE(std::isfinite(r[i].sdf.first_order)) << where;
    }
  }
}

TEST(Scale, FarPointsAreAnsweredUpToTheLimitAndRefusedBeyond) {
  // bunny_holes at 10^k from its box's centre: w within A/(4π d²) of 0 (the bound the plugin's
  // box rests on: no NaN, where far points gave NaN from 3e12), the distance d up to the
  // box's half diagonal, the sdf positive; beyond kMaxQueryCoordinate, or not finite, refused
  // naming the point.
  const GwnModel model = build_model(load_test_mesh("bunny_holes.obj"));
  const Aabb box = model.bounds();
  const float half_diagonal = 0.5f * glm::length(box.hi - box.lo);
  double area = 0;
  for (const uvec3& t : model.mesh().triangles) {
    const dvec3 a(model.mesh().positions[t[0]]), b(model.mesh().positions[t[1]]), c(model.mesh().positions[t[2]]);
    area += 0.5 * glm::length(glm::cross(b - a, c - a));
  }
  std::vector<vec3> points;
  for (float d = 1e2f; d <= 0.5f * kMaxQueryCoordinate; d *= 10.0f)
    points.push_back(box.centre() + vec3(d, 0.3f * d, -0.2f * d));
  for (const WindingMethod method : {WindingMethod::kCrossing, WindingMethod::kTaylor, WindingMethod::kBrute}) {
    const std::vector<PointResult> r =
        evaluated(model, points, method, kFieldW | kFieldGradient | kFieldUnsignedDistance | kFieldSignedDistance);
    for (size_t i = 0; i < points.size(); ++i) {
      const double d = glm::length(dvec3(points[i]) - dvec3(box.centre()));
      const double near = d - half_diagonal;
      EXPECT_LE(std::fabs(r[i].w), area / (4 * kPi * near * near) + 1e-12) << i;
      EXPECT_NEAR(r[i].unsigned_distance, d, half_diagonal * 1.01 + 4e-7 * d) << i;  // and float round-off
      EXPECT_GT(r[i].sdf.distance, 0.0f) << i;
      EXPECT_TRUE(std::isfinite(r[i].gradient.x)) << i;
    }
  }
  for (const vec3& bad : {vec3(2e18f, 0, 0), vec3(0, -1e30f, 0), vec3(0, 0, std::numeric_limits<float>::quiet_NaN()),
                          vec3(kInfinity, 0, 0)}) {
    std::vector<vec3> batch = points;
    batch.insert(batch.begin() + 3, bad);
    std::vector<PointResult> r(batch.size());
    const Status status = evaluate_points(model, batch, QueryRequest{}, r);
    ASSERT_FALSE(status.ok());
    EXPECT_NE(status.message().find("point 3 "), std::string::npos) << status.message();
  }
}

}  // namespace
}  // namespace gwnrt
