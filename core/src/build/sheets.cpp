// Sheet classification: the other triangles' w at every triangle's centroid (sdf/sheets.h).
#include <tbb/parallel_for.h>

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
