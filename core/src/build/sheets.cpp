// Sheet classification: the other triangles' w at every triangle's centroid (sdf/sheets.h).
#include <tbb/parallel_for.h>

#include "gwnrt/field/crossing_winding.h"
#include "gwnrt/field/solid_angle.h"
#include "gwnrt/field/winding_number.h"
#include "gwnrt/geometry/triangle_tree.h"
#include "gwnrt/sdf/sheets.h"

namespace gwnrt {
namespace {

// The multipole sum with the triangle and any triangle coincident with it at its centroid left
// out. The centroid lies on those, where a solid angle is ±2π by which side round-off puts the
// point, so they must not be summed; they are never in a far cluster (the centroid lies inside
// every ball holding them). Instead they are counted: a stack of coincident triangles (a soup
// that lists a face twice) makes w jump by its net orientation, not by one.
struct SumWithoutStack {
  detail::TaylorSum<2, false, false> sum;
  uint32_t left_out;
  vec3 normal;  // of the left-out triangle
  int jump = 1;
  void far(uint32_t node, int lane, const vec3& d) { sum.far(node, lane, d); }
  void near(uint32_t t, const vec3& p0, const vec3& p1, const vec3& p2) {
    if (t == left_out) return;
    // In the plane of t (relative volume below float round-off) and inside it (van Oosterom's
    // denominator < 0: the solid angle's ±2π branch).
    const vec3 a = p0 - sum.x, b = p1 - sum.x, c = p2 - sum.x;
    const float la = glm::length(a), lb = glm::length(b), lc = glm::length(c);
    const SolidAngleTangent<float> tangent = solid_angle_tangent(a, b, c, la, lb, lc, glm::cross(b, c), glm::dot(b, c));
    if (fabsf(tangent.numerator) <= 1e-5f * la * lb * lc && tangent.denominator < 0.0f) {
      jump += glm::dot(glm::cross(p1 - p0, p2 - p0), normal) > 0.0f ? 1 : -1;
      return;
    }
    sum.near(t, p0, p1, p2);
  }
};
}  // namespace

void other_triangles_winding_by_crossings(const ModelView& view, std::span<float> out, std::span<int8_t> jump) {
  const TriangleTreeView& tree = view.triangles;
  const vec3 extent = view.bounds.hi - view.bounds.lo;
  const float diagonal = glm::length(extent);
  tbb::parallel_for(uint32_t(0), tree.triangle_count, [&](uint32_t i) {
    const vec3 &p0 = tree.vertices[3 * i], &p1 = tree.vertices[3 * i + 1], &p2 = tree.vertices[3 * i + 2];
    const vec3 centroid = (p0 + p1 + p2) / 3.0f;
    const vec3 normal = glm::cross(p1 - p0, p2 - p0);
    // The ray crosses the triangle at a slope of at most √3 (some axis has |n_k| >= |n|/√3), so
    // that it leaves the triangle's plane at once.
    const vec3 an = glm::abs(normal);
    const float largest = max_of(an.x, max_of(an.y, an.z));
    const uint32_t axes =
        (an.x >= 0.5f * largest ? 1u : 0u) | (an.y >= 0.5f * largest ? 2u : 0u) | (an.z >= 0.5f * largest ? 4u : 0u);
    // Two points on the ray d through the centroid c, behind = c − δd and front = c + δd, on either
    // side of the triangle's stack (it and any triangle coincident with it at c): the crossings
    // within δ/2 of c seen from behind are the stack, their jumps k. δ is far above the rounding
    // of the centroid and of the vertices relative to it (a few ulps of the coordinates), and far
    // below any feature a mesh resolves. (Not c itself: a stacked copy that is a loop of ∂M on
    // its own has c as its cone's apex, where w_C is undefined.)
    const float delta = 2e-6f * (diagonal + max_of(fabsf(centroid.x), max_of(fabsf(centroid.y), fabsf(centroid.z))));
    const RayFrame axis = shortest_exit_axis_ray(view.bounds, centroid, axes);
    vec3 direction(0.0f), behind = centroid, front = centroid;
    direction[axis.kz] = axis.sz;  // ±1
    behind[axis.kz] -= axis.sz * delta;
    front[axis.kz] += axis.sz * delta;
    const RayFrame frame = make_ray_frame(behind, direction);
    int ahead = 0, stack = 0;
    visit_axis_crossings(tree.bvh, tree.vertices, frame, 0.0f, [&](uint32_t, float t, int k) {
      ahead += k;
      if (fabsf(t - delta) <= 0.5f * delta) stack += k;
    });
    // w at behind and at front (where the M crossings ahead are those of behind but the stack).
    // Their mean is w_o at c to second order in δ: the stack's own terms are ±(2π − h·A) at
    // heights ∓h over its plane, with A varying along the plane only at second order. Either side
    // alone, less its own terms, is off by δ·|∇w_o|, which beside the neighbouring triangles is
    // of the order δ / edge length (up to 9e-4 on the bundled meshes). A closed mesh has
    // whole-number sides, so its w_o is an exact half-integer.
    double w_behind = -double(ahead), w_front = double(stack - ahead);
    if (view.cone.triangle_count > 0) {
      using ConeSum = detail::ConeCrossingVisitor<false, false>::type;
      ConeSum cone_behind(view.cone, frame, behind, kConeBeta, nullptr);
      cone_behind.traverse();
      w_behind += double(cone_behind.jumps) + double(cone_behind.winding());
      const RayFrame front_frame = make_ray_frame(front, direction);
      ConeSum cone_front(view.cone, front_frame, front, kConeBeta, nullptr);
      cone_front.traverse();
      w_front += double(cone_front.jumps) + double(cone_front.winding());
    }
    // k relative to the triangle's own normal: its own jump along d is +1 when d runs from the
    // side its normal points to onto the other (normal·d < 0).
    const int own_count = normal[axis.kz] * axis.sz < 0.0f ? stack : -stack;
    out[tree.triangle_ids[i]] = float(0.5 * (w_behind + w_front));
    jump[tree.triangle_ids[i]] = int8_t(own_count < -127 ? -127 : (own_count > 127 ? 127 : own_count));
  });
}

void other_triangles_winding(const TriangleTree& tree, std::span<const uint32_t> leaves, float beta,
                             std::span<float> out, std::span<int8_t> jump) {
  const TriangleTreeView view = tree.view();
  tbb::parallel_for(size_t(0), leaves.size(), [&](size_t k) {
    const uint32_t i = leaves[k];
    const vec3 &p0 = view.vertices[3 * i], &p1 = view.vertices[3 * i + 1], &p2 = view.vertices[3 * i + 2];
    const vec3 centroid = (p0 + p1 + p2) / 3.0f;
    SumWithoutStack visitor{{view, centroid, {}}, i, glm::cross(p1 - p0, p2 - p0)};
    visit_multipole(view, centroid, beta, visitor);
    out[view.triangle_ids[i]] = visitor.sum.acc.omega * kInv4Pi;
    jump[view.triangle_ids[i]] = int8_t(visitor.jump < -127 ? -127 : (visitor.jump > 127 ? 127 : visitor.jump));
  });
}

}  // namespace gwnrt
