// Sheet classification: the other triangles' w at every triangle's centroid (model.h).
#include <tbb/parallel_for.h>

#include "gwnrt/model.h"
#include "gwnrt/winding_number.h"

namespace gwnrt {
namespace {

// The multipole sum with one triangle left out. The centroid lies on that triangle, where its
// own solid angle is ±2π by which side round-off puts the point, so it must not be summed; it
// is never in a far cluster (the centroid lies inside every ball holding the triangle).
struct SumWithoutOne {
  detail::TaylorSum<2, false, false> sum;
  uint32_t left_out;
  void far(uint32_t node, int lane, const vec3& d) { sum.far(node, lane, d); }
  void near(uint32_t t, const vec3& p0, const vec3& p1, const vec3& p2) {
    if (t != left_out) sum.near(t, p0, p1, p2);
  }
};

}  // namespace

void other_triangles_winding(const TriangleTree& tree, std::span<const uint32_t> leaves, float beta,
                             std::span<float> out) {
  const TriangleTreeView view = tree.view();
  tbb::parallel_for(size_t(0), leaves.size(), [&](size_t k) {
    const uint32_t i = leaves[k];
    const vec3 centroid = (view.vertices[3 * i] + view.vertices[3 * i + 1] + view.vertices[3 * i + 2]) / 3.0f;
    SumWithoutOne visitor{{view, centroid, {}}, i};
    visit_multipole(view, centroid, beta, visitor);
    out[view.triangle_ids[i]] = visitor.sum.acc.omega * kInv4Pi;
  });
}

}  // namespace gwnrt
