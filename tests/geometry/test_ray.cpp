// The watertight ray–triangle crossing test and its walks (ray.h): ties (a ray exactly through
// an edge or a vertex) are counted exactly once, crossing sums equal winding-number differences,
// and traced hits through a cube's edges and vertices are still reported.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "gwnrt/geometry/ray.h"
#include "gwnrt/trace/surface_trace.h"
#include "reference/brute_force_winding.h"
#include "test_util.h"

namespace gwnrt {
namespace {

using test::build_model;

std::string line_name(const vec3& o, const vec3& d) {
  char buf[200];
  std::snprintf(buf, sizeof buf, "line (%.9g, %.9g, %.9g) + t (%.9g, %.9g, %.9g)", o.x, o.y, o.z, d.x, d.y, d.z);
  return buf;
}

// Crossings of one line with a list of triangles, by the raw test.
struct Crossings {
  int count = 0, sum = 0;
  std::vector<float> t;
};

Crossings cross_all(const RayFrame& f, const std::vector<vec3>& corners) {
  Crossings c;
  for (size_t i = 0; i < corners.size(); i += 3) {
    float t;
    int jump;
    if (triangle_crossing(f, corners[i], corners[i + 1], corners[i + 2], t, jump)) {
      ++c.count;
      c.sum += jump;
      c.t.push_back(t);
    }
  }
  return c;
}

std::vector<vec3> corners_of(const Mesh& m) {
  std::vector<vec3> c;
  for (const uvec3& t : m.triangles) c.insert(c.end(), {m.positions[t[0]], m.positions[t[1]], m.positions[t[2]]});
  return c;
}

// Directions with small dyadic components: their shear factors are exact, so lines through
// dyadic points hit edges and vertices exactly (true ties, not near misses).
std::vector<vec3> dyadic_directions() {
  std::vector<vec3> out;
  const float c[] = {-1.0f, -0.5f, 0.0f, 0.25f, 0.5f, 1.0f};
  for (const float x : c)
    for (const float y : c)
      for (const float z : {0.0f, 0.5f, 1.0f, 2.0f})
        if (x != 0 || y != 0 || z != 0) out.push_back({x, y, z});
  return out;
}

TEST(RayCrossing, SharedEdgeOfTwoTrianglesIsCrossedOnce) {
  // The unit square as two consistently oriented triangles sharing the diagonal (0,0)-(1,1).
  const std::vector<vec3> square = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  size_t lines = 0;
  for (const float s : {0.125f, 0.25f, 0.5f, 0.75f, 0.875f}) {
    const vec3 on_edge(s, s, 0.0f);
    for (const vec3& d : dyadic_directions()) {
      if (d.z == 0) continue;  // within the plane: edge-on, never crossed
      for (const float dir : {1.0f, -1.0f}) {
        const vec3 dd = dir * d;
        const vec3 origin = on_edge - 2.0f * dd;  // exact: dyadic values
        const RayFrame f = make_ray_frame(origin, dd);
        const Crossings c = cross_all(f, square);
        SCOPED_TRACE(line_name(origin, dd));
        // Exactly once, with the jump of the side the line comes from: +1 from the normal's
        // side (z > 0, the normal is +z) to the other.
        ASSERT_EQ(c.count, 1);
        EXPECT_EQ(c.sum, dd.z < 0 ? 1 : -1);
        EXPECT_FLOAT_EQ(c.t[0], 2.0f);
        ++lines;
      }
    }
  }
  EXPECT_GT(lines, 300u);
}

TEST(RayCrossing, InteriorVertexOfAFanIsCrossedOnce) {
  // A planar fan of eight triangles around the origin (dyadic rim), and lines through the centre
  // vertex and through the midpoints of its spokes.
  std::vector<vec3> rim = {{1, 0, 0},  {1, 1, 0},   {0, 1, 0},  {-1, 1, 0},
                           {-1, 0, 0}, {-1, -1, 0}, {0, -1, 0}, {1, -1, 0}};
  std::vector<vec3> fan;
  for (size_t k = 0; k < rim.size(); ++k) fan.insert(fan.end(), {vec3(0.0f), rim[k], rim[(k + 1) % rim.size()]});
  std::vector<vec3> targets = {vec3(0.0f)};
  for (const vec3& p : rim) targets.push_back(0.5f * p);
  for (const vec3& target : targets) {
    for (const vec3& d : dyadic_directions()) {
      if (d.z == 0) continue;
      const vec3 origin = target + 3.0f * d;
      const vec3 dd = -d;
      const RayFrame f = make_ray_frame(origin, dd);
      const Crossings c = cross_all(f, fan);
      SCOPED_TRACE(line_name(origin, dd));
      ASSERT_EQ(c.count, 1);
      EXPECT_EQ(c.sum, 1);  // coming down from z > 0, the normals' side
      EXPECT_FLOAT_EQ(c.t[0], 3.0f);
    }
  }
}

TEST(RayCrossing, StackedCopiesAreEachVisitedOnce) {
  // Two copies of the same triangle (and one reversed): every copy is crossed at the same t and
  // next_crossing visits each exactly once, in leaf order.
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}, {0, 1, 2}, {0, 2, 1}};
  const GwnModel model = build_model(m);
  const TriangleTreeView tree = model.triangle_view();
  const RayFrame f = make_ray_frame(vec3(0.25f, 0.25f, 1.0f), vec3(0.0f, 0.0f, -1.0f));
  CrossingHit c;
  float t = -10.0f;
  uint32_t index = kEmptyLane;
  int visits = 0, sum = 0;
  while (next_crossing(tree.bvh, tree.vertices, f, t, index, 10.0f, c)) {
    EXPECT_FLOAT_EQ(c.t, 1.0f);
    ++visits;
    sum += c.jump;
    t = c.t;
    index = c.index;
    ASSERT_LE(visits, 3);
  }
  EXPECT_EQ(visits, 3);
  EXPECT_EQ(sum, 1);
  EXPECT_EQ(crossing_sum(tree.bvh, tree.vertices, f, -10.0f, 10.0f), 1);
  EXPECT_EQ(crossing_sum(tree.bvh, tree.vertices, f, -10.0f, 1.0f), 0);  // [t_lo, t_hi): 1 is out
}

// w of the closed cube [-1, 1]³ at x: 1 inside, 0 outside, -1 on its surface (undefined there).
int cube_w(const vec3& x) {
  const float m = std::max(std::fabs(x.x), std::max(std::fabs(x.y), std::fabs(x.z)));
  return m < 1.0f ? 1 : (m > 1.0f ? 0 : -1);
}

TEST(RayCrossing, ClosedCubeCrossingSumsAreWindingNumbers) {
  // Lines through the cube's vertices, edges and faces (dyadic origins and directions: exact
  // ties), including lines lying in its face planes and along its edges. Over the whole line the
  // crossings cancel; from the far start to any point off the surface they sum to w there.
  const GwnModel model = build_model(test::make_cube());
  const TriangleTreeView tree = model.triangle_view();
  const std::vector<vec3> corners = corners_of(test::make_cube());
  const float c[] = {-1.0f, -0.5f, 0.0f, 0.5f, 1.0f};
  size_t lines = 0, points = 0, inside_points = 0;
  for (const float a : c) {
    for (const float b : c) {
      for (const vec3& d : dyadic_directions()) {
        for (int axis = 0; axis < 3; ++axis) {
          // A point on the cube's surface or inside it (a, b on the lattice), the line through it.
          vec3 p(0.0f);
          p[axis] = -1.0f;
          p[(axis + 1) % 3] = a;
          p[(axis + 2) % 3] = b;
          const RayFrame f = make_ray_frame(p - 8.0f * d, d);
          SCOPED_TRACE(line_name(p - 8.0f * d, d));
          const Crossings all = cross_all(f, corners);
          ASSERT_EQ(all.sum, 0);
          ASSERT_EQ(all.count % 2, 0);
          ASSERT_EQ(crossing_sum(tree.bvh, tree.vertices, f, -100.0f, 100.0f), 0);
          ++lines;
          // The walk meets each crossing once, in (t, index) order; between distinct t the
          // running sum is w of the (perturbed) line: 0 or 1. Crossings at one t (a line that
          // touches the cube at a vertex or along an edge enters and leaves there) may come in
          // either order.
          CrossingHit h;
          float t = -100.0f;
          uint32_t index = kEmptyLane;
          int visits = 0, running = 0;
          while (next_crossing(tree.bvh, tree.vertices, f, t, index, 100.0f, h)) {
            ASSERT_GE(h.t, t);
            if (h.t > t) {
              ASSERT_GE(running, 0);
              ASSERT_LE(running, 1);
            }
            running += h.jump;
            t = h.t;
            index = h.index;
            ASSERT_LE(++visits, all.count);
          }
          EXPECT_EQ(running, 0);
          EXPECT_EQ(visits, all.count);
          for (float s = 0.0f; s <= 16.0f; s += 0.25f) {
            const vec3 x = p - 8.0f * d + s * d;  // exact
            const int w = cube_w(x);
            if (w < 0) continue;  // on the surface
            ASSERT_EQ(crossing_sum(tree.bvh, tree.vertices, f, -100.0f, s), w) << "at s = " << s;
            ++points;
            inside_points += w;
          }
        }
      }
    }
  }
  EXPECT_GT(lines, 5000u);
  EXPECT_GT(points, 50000u);
  EXPECT_GT(inside_points, 5000u);
}

TEST(RayCrossing, DiagonalThroughTwoCubeVerticesCountsOnceInAndOnceOut) {
  // The line through (-1,-1,-1) and (1,1,1) meets the cube at two vertices only.
  const GwnModel model = build_model(test::make_cube());
  const TriangleTreeView tree = model.triangle_view();
  const RayFrame f = make_ray_frame(vec3(-2.0f), vec3(1.0f));
  EXPECT_EQ(crossing_sum(tree.bvh, tree.vertices, f, 0.0f, 2.0f), 1);  // ends inside
  EXPECT_EQ(crossing_sum(tree.bvh, tree.vertices, f, 0.0f, 4.0f), 0);  // passes through
  EXPECT_EQ(crossing_sum(tree.bvh, tree.vertices, f, 2.0f, 4.0f), -1);
  // Through the midpoints of two opposite edges.
  const RayFrame g = make_ray_frame(vec3(-2.0f, 0.0f, -2.0f), vec3(1.0f, 0.0f, 1.0f));
  EXPECT_EQ(crossing_sum(tree.bvh, tree.vertices, g, 0.0f, 2.0f), 1);
  EXPECT_EQ(crossing_sum(tree.bvh, tree.vertices, g, 0.0f, 4.0f), 0);
}

TEST(RayCrossing, ClosedMeshCrossingSumsAreWindingNumbers) {
  // The bunny (closed), lines aimed exactly at its vertices from random points: from where the
  // line enters the box, the crossings sum to w at points off the surface.
  const Mesh mesh = test::load_test_mesh("bunny.obj");
  const GwnModel model = build_model(mesh);
  ASSERT_EQ(model.boundary().segment_count(), 0u);
  const TriangleTreeView tree = model.triangle_view();
  const reference::ReferenceMesh ref = reference::reference_mesh(mesh);
  const Aabb box = model.bounds();
  const float diag = glm::length(box.hi - box.lo);
  std::mt19937 rng(601);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  size_t checked = 0, inside = 0;
  for (int i = 0; i < 150; ++i) {
    const vec3 o = box.lo - 0.5f * diag + 2.0f * diag * vec3(u(rng), u(rng), u(rng));
    const vec3 target = mesh.positions[std::uniform_int_distribution<size_t>(0, mesh.positions.size() - 1)(rng)];
    const vec3 d = target - o;
    const RayFrame f = make_ray_frame(o, d);
    float t0, t1;
    clip_to_box(f, box, t0, t1);
    if (!(t0 < t1)) continue;
    SCOPED_TRACE(line_name(o, d));
    EXPECT_EQ(crossing_sum(tree.bvh, tree.vertices, f, t0 - 1.0f, t1 + 1.0f), 0);
    for (int k = 0; k < 10; ++k) {
      const float s = t0 + (t1 - t0) * (float(k) + 0.5f) / 10.0f;
      const double w = reference::reference_w(ref, dvec3(o) + double(s) * dvec3(d));
      if (std::fabs(w - std::round(w)) > 1e-3) continue;
      EXPECT_EQ(crossing_sum(tree.bvh, tree.vertices, f, t0 - 1.0f, s), int(std::round(w))) << "at t = " << s;
      ++checked;
      inside += w > 0.5;
    }
  }
  EXPECT_GT(checked, 1000u);
  EXPECT_GT(inside, 100u);
}

TEST(RayCrossing, TracedCubeHitsThroughEdgesAndVertices) {
  // Rays exactly through the cube's vertices and edges are hits at the analytic t, from outside
  // and from inside, with no Harnack steps.
  const GwnModel model = build_model(test::make_cube());
  const ModelView view = model.view();
  struct Case {
    vec3 origin, direction;
    float t;
    bool from_inside;
  };
  std::vector<Case> cases = {
      {vec3(-2.0f), vec3(1.0f), 1.0f, false},                           // vertex (-1,-1,-1)
      {vec3(-2.0f, 0.0f, -2.0f), vec3(1.0f, 0.0f, 1.0f), 1.0f, false},  // edge midpoint (-1,0,-1)
      {vec3(-2.0f, -2.0f, 0.5f), vec3(1.0f, 1.0f, 0.0f), 1.0f, false},  // edge x=y=-1
      {vec3(-3.0f, 0.0f, 0.0f), vec3(2.0f, 0.0f, 0.0f), 1.0f, false},   // face centre
      {vec3(0.0f), vec3(1.0f), 1.0f, true},                             // out through vertex (1,1,1)
      {vec3(0.0f), vec3(0.5f, 0.5f, 0.0f), 2.0f, true},                 // out through edge midpoint
      {vec3(0.0f, 0.0f, 0.25f), vec3(-1.0f, 1.0f, 0.0f), 1.0f, true},   // out through edge x=-1,y=1
  };
  // All 8 vertices and 12 edge midpoints, from outside along the diagonal through them.
  for (int x = -1; x <= 1; ++x)
    for (int y = -1; y <= 1; ++y)
      for (int z = -1; z <= 1; ++z) {
        const int nonzero = (x != 0) + (y != 0) + (z != 0);
        if (nonzero < 2) continue;
        const vec3 p{float(x), float(y), float(z)};
        cases.push_back({2.0f * p, -p, 1.0f, false});
        cases.push_back({vec3(0.0f), p, 1.0f, true});
      }
  for (const Case& c : cases) {
    for (const float scale : {1.0f, 0.37f, 3.0f}) {
      Ray r{c.origin, c.direction * scale};
      const RayHit h = trace_surface(view, r, TraceOptions{});
      SCOPED_TRACE(line_name(r.origin, r.direction));
      ASSERT_TRUE(h.hit);
      EXPECT_EQ(h.kind, HitKind::kSheet);
      EXPECT_EQ(h.steps, 0u);
      EXPECT_NEAR(h.t * scale, c.t, 1e-6f * 4.0f);  // float round-off of O(1) values
      // The normal is one of the touching faces' outward normals: against the ray coming in,
      // along it going out.
      const float facing = glm::dot(h.normal, r.direction);
      if (c.from_inside) {
        EXPECT_GT(facing, 0.0f);
      } else {
        EXPECT_LT(facing, 0.0f);
      }
    }
  }
}

}  // namespace
}  // namespace gwnrt
