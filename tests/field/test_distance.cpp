// Closest-point primitives against dense sampling, and the BVH distance queries against brute force.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "gwnrt/field/distance.h"
#include "reference/exact_distance.h"
#include "test_util.h"

namespace gwnrt {
namespace {

using test::build_model;
using test::load_test_mesh;
using test::make_cube;
using test::make_sphere;
using test::mesh_bounds;
using test::sample_points;
// The brute-force references of the distance queries (zero-area triangles as their three edges,
// where ClosestPointOnTriangle.ZeroArea* shows closest_point_on_triangle to be unreliable).
using reference::boundary_distance;
using reference::mesh_distance;
using reference::triangle_distance;

using test::kInf;

struct Tri {
  dvec3 p0, p1, p2;
  const char* kind;
};

// Triangles with positive area, down to slivers and needles, to reach every Voronoi region.
std::vector<Tri> proper_triangles(std::mt19937& rng, int count) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_real_distribution<double> t01(0.0, 1.0);
  auto rp = [&] { return dvec3(u(rng), u(rng), u(rng)); };
  std::vector<Tri> tris;
  for (int i = 0; i < count; ++i) {
    const dvec3 a = rp(), b = rp(), c = rp();
    tris.push_back({a, b, c, "generic"});
    // Sliver: the third corner lies just off the opposite edge.
    const dvec3 off = glm::normalize(glm::cross(b - a, rp())) * 1e-4;
    tris.push_back({a, b, a + t01(rng) * (b - a) + off, "sliver"});
    // Needle: two corners almost coincide.
    tris.push_back({a, b, b + 1e-5 * rp(), "needle"});
  }
  return tris;
}

// Zero-area triangles: collinear corners (the middle one in each slot) and repeated corners.
std::vector<Tri> zero_area_triangles(std::mt19937& rng, int count) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_real_distribution<double> t01(0.0, 1.0);
  auto rp = [&] { return dvec3(u(rng), u(rng), u(rng)); };
  std::vector<Tri> tris;
  for (int i = 0; i < count; ++i) {
    const dvec3 a = rp(), b = rp();
    const dvec3 m = a + t01(rng) * (b - a);
    tris.push_back({a, b, m, "collinear (m last)"});
    tris.push_back({a, m, b, "collinear (m middle)"});
    tris.push_back({m, a, b, "collinear (m first)"});
    tris.push_back({a, b, a + 1.7 * (b - a), "collinear (third beyond b)"});
    tris.push_back({a, a, b, "repeated p0=p1"});
    tris.push_back({a, b, b, "repeated p1=p2"});
    tris.push_back({b, a, b, "repeated p0=p2"});
    tris.push_back({a, a, a, "point"});
  }
  return tris;
}

double longest_edge(const Tri& t) {
  return std::max({glm::length(t.p1 - t.p0), glm::length(t.p2 - t.p1), glm::length(t.p0 - t.p2)});
}

void check_against_sampling(const std::vector<Tri>& tris, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  constexpr int kGrid = 400;
  constexpr int kPointsPerTriangle = 12;
  std::vector<dvec3> samples;
  samples.reserve((kGrid + 1) * (kGrid + 2) / 2);
  for (size_t ti = 0; ti < tris.size(); ++ti) {
    const Tri& t = tris[ti];
    samples.clear();
    for (int i = 0; i <= kGrid; ++i)
      for (int j = 0; i + j <= kGrid; ++j) {
        const double a = double(i) / kGrid, b = double(j) / kGrid;
        samples.push_back((1 - a - b) * t.p0 + a * t.p1 + b * t.p2);
      }
    // Every point of the triangle lies in a grid cell whose corners are samples and whose edges
    // are the triangle's edges divided by kGrid (h = 1/kGrid), so some sample is within
    // h * longest_edge of it.
    const double grid_bound = longest_edge(t) / kGrid;
    for (int k = 0; k < kPointsPerTriangle; ++k) {
      // Half the queries near the triangle, where the regions are finely interleaved.
      const dvec3 x =
          k % 2 ? dvec3(u(rng), u(rng), u(rng)) : (t.p0 + t.p1 + t.p2) / 3.0 + 0.05 * dvec3(u(rng), u(rng), u(rng));
      double sampled2 = kInf;
      for (const dvec3& s : samples) sampled2 = std::min(sampled2, glm::dot(s - x, s - x));
      const double sampled = std::sqrt(sampled2);
      const ClosestPoint<double> c = closest_point_on_triangle(t.p0, t.p1, t.p2, x);
      const double d = glm::length(c.point - x);
      SCOPED_TRACE(std::string(t.kind) + " #" + std::to_string(ti) + ", query " + std::to_string(k));
      // Coordinates are O(1): 1e-12 leaves room for double rounding only.
      EXPECT_LE(d, sampled + 1e-12);
      EXPECT_GE(d, sampled - grid_bound - 1e-12);
      // Barycentrics must describe a point of the (closed) triangle; 1e-12 is rounding slack.
      EXPECT_GE(c.u, -1e-12);
      EXPECT_GE(c.v, -1e-12);
      EXPECT_LE(c.u + c.v, 1 + 1e-12);
      // The returned point and the barycentrics agree up to O(1) coordinates' double rounding.
      const dvec3 from_bary = (1 - c.u - c.v) * t.p0 + c.u * t.p1 + c.v * t.p2;
      EXPECT_LT(glm::length(from_bary - c.point), 1e-12);
    }
  }
}

TEST(ClosestPointOnTriangle, MatchesDenseBarycentricSampling) {
  std::mt19937 rng(7);
  check_against_sampling(proper_triangles(rng, 20), rng);
}

TEST(ClosestPointOnTriangle, ZeroAreaTrianglesMatchDenseSampling) {
  std::mt19937 rng(8);
  check_against_sampling(zero_area_triangles(rng, 6), rng);
}

TEST(ClosestPointOnTriangle, RepeatedCornerMinimalCase) {
  // p0 == p1: the triangle is the segment p0-p2, whose nearest point to x is (0.5, 0, 0).
  const dvec3 p(0, 0, 0), q(1, 0, 0), x(0.5, 1, 0);
  EXPECT_EQ(closest_point_on_triangle(p, p, q, x).point, dvec3(0.5, 0, 0));
  EXPECT_EQ(closest_point_on_triangle(p, q, q, x).point, dvec3(0.5, 0, 0));
  EXPECT_EQ(closest_point_on_triangle(q, p, q, x).point, dvec3(0.5, 0, 0));
}

TEST(ClosestPointOnTriangle, VertexEdgeAndFaceRegionsExactly) {
  const dvec3 p0(0, 0, 0), p1(1, 0, 0), p2(0, 1, 0);
  auto cp = [&](dvec3 x) { return closest_point_on_triangle(p0, p1, p2, x); };
  EXPECT_EQ(cp({-1, -1, 3}).point, p0);
  EXPECT_EQ(cp({2, -0.5, 0}).point, p1);
  EXPECT_EQ(cp({-0.5, 2, 0}).point, p2);
  EXPECT_EQ(cp({0.5, -1, 1}).point, dvec3(0.5, 0, 0));
  EXPECT_EQ(cp({-1, 0.25, 0}).point, dvec3(0, 0.25, 0));
  EXPECT_EQ(cp({1, 1, -2}).point, dvec3(0.5, 0.5, 0));
  const ClosestPoint<double> face = cp({0.25, 0.5, 7});
  EXPECT_EQ(face.point, dvec3(0.25, 0.5, 0));
  EXPECT_EQ(face.u, 0.25);
  EXPECT_EQ(face.v, 0.5);
}

TEST(ClosestPointOnSegment, MatchesDenseSampling) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  constexpr int kSamples = 100000;
  for (int s = 0; s < 60; ++s) {
    const dvec3 a(u(rng), u(rng), u(rng));
    const dvec3 b =
        s % 6 == 0 ? a : (s % 6 == 1 ? a + 1e-6 * dvec3(u(rng), u(rng), u(rng)) : dvec3(u(rng), u(rng), u(rng)));
    // Any point of the segment is within half a sample spacing (length / kSamples) of a sample.
    const double grid_bound = glm::length(b - a) / kSamples;
    for (int k = 0; k < 10; ++k) {
      const dvec3 x = 2.0 * dvec3(u(rng), u(rng), u(rng));
      double sampled2 = kInf;
      for (int i = 0; i <= kSamples; ++i) {
        const dvec3 p = a + (double(i) / kSamples) * (b - a);
        sampled2 = std::min(sampled2, glm::dot(p - x, p - x));
      }
      const double sampled = std::sqrt(sampled2);
      const ClosestPoint<double> c = closest_point_on_segment(a, b, x);
      const double d = glm::length(c.point - x);
      SCOPED_TRACE("segment " + std::to_string(s) + ", query " + std::to_string(k));
      // O(1) coordinates: double rounding only.
      EXPECT_LE(d, sampled + 1e-12);
      EXPECT_GE(d, sampled - grid_bound - 1e-12);
      EXPECT_GE(c.u, 0.0);
      EXPECT_LE(c.u, 1.0);
      EXPECT_EQ(c.v, 0.0);
      EXPECT_LT(glm::length((1 - c.u) * a + c.u * b - c.point), 1e-12);
    }
  }
  // A zero-length segment is its point.
  const dvec3 p(0.3, -0.2, 0.9);
  const ClosestPoint<double> c = closest_point_on_segment(p, p, dvec3(4, 5, 6));
  EXPECT_EQ(c.point, p);
  EXPECT_EQ(c.u, 0.0);
}

// The branch-free squared distance the traversal ranks a leaf's triangles by (triangle_distance2),
// scalar and four lanes at once, against the double brute force of the same float corners, on
// proper triangles down to slivers and needles and on zero-area ones (collinear, repeated
// corners, a point), from points near and far. Float corners and points of O(1) coordinates:
// the distance is within a few ulps of them, 1e-6.
TEST(TriangleDistance2, MatchesBruteForceOnEveryKindOfTriangle) {
  std::mt19937 rng(21);
  std::vector<Tri> tris = proper_triangles(rng, 40);
  for (const Tri& t : zero_area_triangles(rng, 20)) tris.push_back(t);
  std::uniform_real_distribution<float> u(-2.0f, 2.0f);
  double worst = 0;
  for (size_t ti = 0; ti < tris.size(); ++ti) {
    const vec3 c[3] = {vec3(tris[ti].p0), vec3(tris[ti].p1), vec3(tris[ti].p2)};
    for (int k = 0; k < 40; ++k) {
      const vec3 centre = (c[0] + c[1] + c[2]) / 3.0f;
      const vec3 x = k % 4 == 0
                         ? c[k / 4 % 3]  // on a corner
                         : (k % 2 ? vec3(u(rng), u(rng), u(rng)) : centre + 0.05f * vec3(u(rng), u(rng), u(rng)));
      const double ref = reference::triangle_distance(c[0], c[1], c[2], dvec3(x));
      const float p[3][3] = {{c[0].x, c[0].y, c[0].z}, {c[1].x, c[1].y, c[1].z}, {c[2].x, c[2].y, c[2].z}};
      const float xs[3] = {x.x, x.y, x.z};
      const double scalar = std::sqrt(double(triangle_distance2(p, xs)));
      SCOPED_TRACE(std::string(tris[ti].kind) + " #" + std::to_string(ti) + ", query " + std::to_string(k));
      EXPECT_NEAR(scalar, ref, 1e-6);
      // A corner is on its triangle: its edge's t is 1 but for rounding (fused multiply-adds may
      // round x's dot product and the edge's own differently), two ulps of the coordinates.
      if (k % 4 == 0) {
        EXPECT_LE(scalar, 2.4e-7 * 2.0) << "a corner is on its triangle";
      }
      worst = std::max(worst, std::abs(scalar - ref));
#if GWNRT_HOST_LANES
      // The same triangle in every lane but one, which holds another: lanes do not mix.
      const Tri& other = tris[(ti + 1) % tris.size()];
      const vec3 o[3] = {vec3(other.p0), vec3(other.p1), vec3(other.p2)};
      f4 pl[3][3], xl[3];
      for (int a = 0; a < 3; ++a) {
        for (int q = 0; q < 3; ++q) pl[q][a] = f4{c[q][a], o[q][a], c[q][a], c[q][a]};
        xl[a] = splat<f4>(x[a]);
      }
      const f4 lanes = triangle_distance2(pl, xl);
      for (int l : {0, 2, 3}) EXPECT_NEAR(std::sqrt(double(lanes[l])), ref, 1e-6) << "lane " << l;
      EXPECT_NEAR(std::sqrt(double(lanes[1])), reference::triangle_distance(o[0], o[1], o[2], dvec3(x)), 1e-6);
#endif
    }
  }
  std::printf("[ triangle_distance2 ] %zu triangles: max |d - brute force| %.2e\n", tris.size(), worst);
}

// Points where the traversal's choices are close calls, against the brute force and between the
// host's four-wide path and the scalar one (the device's): every vertex and edge midpoint of a
// mesh, points just off the slivers of a fanned polygon and on them, points exactly between two
// parallel squares (either square is right), and points far away (10^3 and 10^6 diagonals).
TEST(UnsignedDistance, VerticesEdgesSliversTiesAndFarPoints) {
  struct Case {
    const char* name;
    Mesh mesh;
  };
  Mesh squares;
  squares.positions = {{0, 0, -1}, {1, 0, -1}, {1, 1, -1}, {0, 1, -1}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  squares.triangles = {{0, 1, 2}, {0, 2, 3}, {4, 6, 5}, {4, 7, 6}};
  std::vector<Case> cases;
  cases.push_back({"bunny_holes", load_test_mesh("bunny_holes.obj")});
  cases.push_back({"fanned 2000-gon", test::make_fanned_polygon(2000)});
  cases.push_back({"two parallel squares", squares});
  for (Case& c : cases) {
    const Mesh mesh = c.mesh;
    const GwnModel model = build_model(std::move(c.mesh));
    const Aabb box = mesh_bounds(mesh);
    const double diag = glm::length(dvec3(box.hi - box.lo));
    std::vector<vec3> points;
    for (const vec3& p : mesh.positions) points.push_back(p);
    for (size_t t = 0; t < mesh.triangles.size(); t += std::max<size_t>(1, mesh.triangles.size() / 2000)) {
      const vec3 a = mesh.positions[mesh.triangles[t][0]], b = mesh.positions[mesh.triangles[t][1]],
                 d = mesh.positions[mesh.triangles[t][2]];
      const vec3 n = glm::cross(b - a, d - a), centroid = (a + b + d) / 3.0f;
      points.push_back(0.5f * (a + b));
      points.push_back(centroid);
      if (glm::length(n) > 0) points.push_back(centroid + 1e-4f * float(diag) * glm::normalize(n));
    }
    test::Random rng(31);
    for (int k = 0; k < 200; ++k) {
      const vec3 dir = glm::normalize(vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)));
      points.push_back(box.centre() + (k % 2 ? 1e3f : 1e6f) * float(diag) * dir);
    }
    if (&c == &cases[2])
      for (int k = 0; k < 100; ++k) points.push_back({rng.uniform(0, 1), rng.uniform(0, 1), 0.0f});
    const TriangleTreeView view = model.triangle_view();
    size_t checked = 0;
    for (const vec3& x : points) {
      const NearestPrimitive lanes = unsigned_distance(view, x);
      const NearestPrimitive scalar =
          detail::nearest_primitive<detail::TriangleLeaves, false>(view.bvh, view.triangle_ids, x, {view.vertices});
      const double ref = mesh_distance(mesh, dvec3(x));
      SCOPED_TRACE(std::string(c.name) + ": x = (" + std::to_string(x.x) + ", " + std::to_string(x.y) + ", " +
                   std::to_string(x.z) + ")");
      // Float coordinates of x and of M: a few ulps of the larger of |x| and the box.
      const double tol = 1e-6 * std::max(diag, double(glm::length(x)));
      ASSERT_LT(lanes.primitive, mesh.triangles.size());
      EXPECT_NEAR(lanes.distance, ref, tol);
      EXPECT_NEAR(triangle_distance(mesh, lanes.primitive, dvec3(x)), ref, tol);
      // The two paths rank by the same formula, which the compiler may fuse differently in each
      // (x - t e rounds to an ulp of the coordinates, 1.2e-7 of them): four ulps. A tie may go
      // either way, at the same distance.
      EXPECT_NEAR(scalar.distance, lanes.distance, 4.8e-7 * std::max(diag, double(glm::length(x))));
      if (scalar.primitive != lanes.primitive) {
        EXPECT_NEAR(triangle_distance(mesh, scalar.primitive, dvec3(x)), ref, tol);
      }
      ++checked;
    }
    std::printf("[ %-20s ] %zu points: vertices, edge midpoints, centroids, just off, far\n", c.name, checked);
  }
}

// Whether triangle (a, b, c) meets box [lo, hi], in double by clipping it against the box's six
// planes (Sutherland–Hodgman): independent of the separating axes of triangle_meets_box.
bool clipped_triangle_meets_box(const dvec3& a, const dvec3& b, const dvec3& c, const dvec3& lo, const dvec3& hi) {
  std::vector<dvec3> polygon = {a, b, c};
  for (int axis = 0; axis < 3 && !polygon.empty(); ++axis)
    for (const int side : {-1, 1}) {
      const double bound = side < 0 ? lo[axis] : hi[axis];
      const auto inside = [&](const dvec3& p) { return side < 0 ? p[axis] >= bound : p[axis] <= bound; };
      std::vector<dvec3> kept;
      for (size_t i = 0; i < polygon.size(); ++i) {
        const dvec3 &p = polygon[i], &q = polygon[(i + 1) % polygon.size()];
        if (inside(p)) kept.push_back(p);
        if (inside(p) != inside(q)) kept.push_back(p + (q - p) * ((bound - p[axis]) / (q[axis] - p[axis])));
      }
      polygon = kept;
      if (polygon.empty()) break;
    }
  return !polygon.empty();
}

// Triangles against boxes (random, and touching, piercing or just missing them), as clipping
// in double decides where a box grown or shrunk by 1e-4 of its size gets the same answer.
TEST(TriangleMeetsBox, MatchesClippingInDouble) {
  test::Random rng(37);
  int meets = 0, misses = 0;
  for (int k = 0; k < 20000; ++k) {
    const vec3 centre(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    const vec3 half(rng.uniform(0.05f, 1), rng.uniform(0.05f, 1), rng.uniform(0.05f, 1));
    const float spread = k % 2 ? 0.3f : 2.0f;
    vec3 v[3];
    for (vec3& p : v)
      p = vec3(rng.uniform(-spread, spread), rng.uniform(-spread, spread), rng.uniform(-spread, spread));
    if (k % 5 == 0) v[2] = v[0] + 1e-3f * (v[1] - v[0]);  // nearly degenerate
    const dvec3 lo = dvec3(centre - half), hi = dvec3(centre + half), grow = 1e-4 * dvec3(half);
    const bool outer = clipped_triangle_meets_box(dvec3(v[0]), dvec3(v[1]), dvec3(v[2]), lo - grow, hi + grow);
    const bool inner = clipped_triangle_meets_box(dvec3(v[0]), dvec3(v[1]), dvec3(v[2]), lo + grow, hi - grow);
    if (outer != inner) continue;  // a touch: float's to call
    EXPECT_EQ(detail::triangle_meets_box(v[0], v[1], v[2], centre, half), outer) << "case " << k;
    ++(outer ? meets : misses);
  }
  EXPECT_GT(meets, 3000);
  EXPECT_GT(misses, 3000);
}

// The scout's test over a mesh's tree: every box some triangle meets is reported (by clipping
// each triangle), and a box reported is met by some triangle within its grown slack.
TEST(AnyMeetsBox, MatchesTheTrianglesOneByOne) {
  const Mesh mesh = load_test_mesh("bunny_holes.obj");
  const GwnModel model = build_model(Mesh(mesh));
  const TriangleTreeView view = model.triangle_view();
  const Aabb box = mesh_bounds(mesh);
  const vec3 size = box.hi - box.lo;
  test::Random rng(39);
  int met = 0, missed = 0;
  for (int k = 0; k < 300; ++k) {
    const vec3 lo =
        box.lo - 0.1f * size + vec3(rng.uniform(0, 1.1f), rng.uniform(0, 1.1f), rng.uniform(0, 1.1f)) * size;
    const vec3 hi = lo + rng.uniform(0.005f, 0.1f) * glm::length(size) * vec3(1.0f);
    const auto any_clipped = [&](double grow) {
      const dvec3 g = grow * dvec3(hi - lo);
      for (const uvec3& t : mesh.triangles)
        if (clipped_triangle_meets_box(dvec3(mesh.positions[t.x]), dvec3(mesh.positions[t.y]),
                                       dvec3(mesh.positions[t.z]), dvec3(lo) - g, dvec3(hi) + g))
          return true;
      return false;
    };
    const bool reported = any_meets_box(view, Aabb{lo, hi});
    if (any_clipped(0.0)) {
      EXPECT_TRUE(reported) << "box " << k;
    }
    if (reported) {
      EXPECT_TRUE(any_clipped(2e-3)) << "box " << k;
    }
    ++(reported ? met : missed);
  }
  EXPECT_GT(met, 30);
  EXPECT_GT(missed, 30);
}

// The boundary's segments by both paths, against the brute force.
TEST(BoundaryDistance, FourWideMatchesScalarPath) {
  const GwnModel model = build_model(load_test_mesh("bunny_holes.obj"));
  const SegmentTreeView view = model.boundary_view();
  const BoundaryCurve& curve = model.boundary();
  const Aabb box = mesh_bounds(model.mesh());
  const double diag = glm::length(dvec3(box.hi - box.lo));
  std::vector<vec3> points = sample_points(box, 1000, 17);
  for (const vec3& p : curve.endpoints) points.push_back(p);
  for (const vec3& x : points) {
    const NearestPrimitive lanes = boundary_distance(view, x);
    const NearestPrimitive scalar =
        detail::nearest_primitive<detail::SegmentLeaves, false>(view.bvh, view.segment_ids, x, {view.endpoints});
    const double ref = boundary_distance(curve, dvec3(x));
    // As for triangles: ulps of the larger of |x| and the box.
    const double scale = std::max(diag, double(glm::length(x)));
    EXPECT_NEAR(lanes.distance, ref, 1e-6 * scale);
    EXPECT_NEAR(scalar.distance, lanes.distance, 4.8e-7 * scale);
  }
}

class DistanceOnRealMeshes : public ::testing::TestWithParam<const char*> {};

TEST_P(DistanceOnRealMeshes, UnsignedDistanceMatchesBruteForce) {
  const GwnModel model = build_model(load_test_mesh(GetParam()));
  const Mesh& mesh = model.mesh();
  const Aabb box = mesh_bounds(mesh);
  const double diag = glm::length(dvec3(box.hi - box.lo));
  // Float vertices, float traversal and points up to 3 boxes away: errors are ~1e-7 of the
  // coordinates, so 1e-5 of the diagonal is loose but far below any wrong-triangle error.
  const double tol = 1e-5 * diag;
  const std::vector<vec3> points = sample_points(box, 2000, 3);
  const TriangleTreeView view = model.triangle_view();
  for (size_t i = 0; i < points.size(); ++i) {
    const dvec3 x(points[i]);
    const NearestPrimitive n = unsigned_distance(view, points[i]);
    const double ref = mesh_distance(mesh, x);
    SCOPED_TRACE("point " + std::to_string(i));
    ASSERT_LT(n.primitive, mesh.triangles.size());
    EXPECT_NEAR(n.distance, ref, tol);
    // Ties between triangles are legitimate, so the id is judged by its distance.
    EXPECT_NEAR(triangle_distance(mesh, n.primitive, x), ref, tol);
    // Float barycentrics: 1e-5 covers their rounding on O(1) values.
    EXPECT_GE(n.u, -1e-5f);
    EXPECT_GE(n.v, -1e-5f);
    EXPECT_LE(n.u, 1 + 1e-5f);
    EXPECT_LE(n.v, 1 + 1e-5f);
    EXPECT_LE(n.u + n.v, 1 + 1e-5f);
    // The barycentrics describe the returned point on the returned triangle.
    const uvec3 t = mesh.triangles[n.primitive];
    const dvec3 from_bary = (1.0 - n.u - n.v) * dvec3(mesh.positions[t[0]]) +
                            double(n.u) * dvec3(mesh.positions[t[1]]) + double(n.v) * dvec3(mesh.positions[t[2]]);
    EXPECT_LT(glm::length(from_bary - dvec3(n.point)), tol);
  }
}

TEST_P(DistanceOnRealMeshes, BoundaryDistanceMatchesBruteForce) {
  const GwnModel model = build_model(load_test_mesh(GetParam()));
  const BoundaryCurve& curve = model.boundary();
  const Aabb box = mesh_bounds(model.mesh());
  const double diag = glm::length(dvec3(box.hi - box.lo));
  const double tol = 1e-5 * diag;  // same float-rounding argument as for triangles
  const std::vector<vec3> points = sample_points(box, 2000, 5);
  for (size_t i = 0; i < points.size(); ++i) {
    const dvec3 x(points[i]);
    const NearestPrimitive n = boundary_distance(model.boundary_view(), points[i]);
    SCOPED_TRACE("point " + std::to_string(i));
    if (curve.segment_count() == 0) {
      EXPECT_EQ(n.distance, kInfinity);
      EXPECT_EQ(n.primitive, kEmptyLane);
      continue;
    }
    const double ref = boundary_distance(curve, x);
    EXPECT_NEAR(n.distance, ref, tol);
    ASSERT_LT(n.primitive, curve.segment_count());
    const double id_dist = glm::length(closest_point_on_segment(dvec3(curve.endpoints[2 * n.primitive]),
                                                                dvec3(curve.endpoints[2 * n.primitive + 1]), x)
                                           .point -
                                       x);
    EXPECT_NEAR(id_dist, ref, tol);
  }
}

INSTANTIATE_TEST_SUITE_P(Meshes, DistanceOnRealMeshes,
                         ::testing::Values("bunny.obj", "bunny_holes.obj", "teapot.obj", "dragon_vrip_res4.ply"),
                         [](const auto& info) {
                           std::string name = info.param;
                           return name.substr(0, name.find('.'));
                         });

TEST(BoundaryDistance, InfiniteForClosedMeshes) {
  for (const Mesh& mesh : {load_test_mesh("bunny.obj"), make_sphere(2), make_cube()}) {
    const GwnModel model = build_model(mesh);
    EXPECT_EQ(model.boundary().segment_count(), 0u);
    for (const vec3& x : sample_points(mesh_bounds(mesh), 50, 9)) {
      const NearestPrimitive n = boundary_distance(model.boundary_view(), x);
      EXPECT_EQ(n.distance, kInfinity);
      EXPECT_EQ(n.primitive, kEmptyLane);
    }
  }
}

TEST(BoundaryDistance, OpenCubeIsTheDistanceToItsRim) {
  const GwnModel model = build_model(make_cube(true));
  for (const vec3& x : sample_points(mesh_bounds(model.mesh()), 500, 13)) {
    const NearestPrimitive n = boundary_distance(model.boundary_view(), x);
    ASSERT_TRUE(std::isfinite(n.distance));
    // The rim is the square |x|,|y| <= 1 at z = 1; its distance has a closed form.
    const double dz = double(x.z) - 1.0;
    const double dx = std::max(std::abs(double(x.x)) - 1.0, 0.0), dy = std::max(std::abs(double(x.y)) - 1.0, 0.0);
    const double in_x = 1.0 - std::abs(double(x.x)), in_y = 1.0 - std::abs(double(x.y));
    double planar;  // distance within the plane z = 1 from (x, y) to the square's outline
    if (dx == 0 && dy == 0)
      planar = std::min(in_x, in_y);
    else
      planar = std::sqrt(dx * dx + dy * dy);
    // Float query with O(1) coordinates.
    EXPECT_NEAR(n.distance, std::sqrt(planar * planar + dz * dz), 1e-5);
    EXPECT_NEAR(n.distance, boundary_distance(model.boundary(), dvec3(x)), 1e-5);
  }
}

}  // namespace
}  // namespace gwnrt
