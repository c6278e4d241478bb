// Sheet classification: the other triangles' w at every triangle's centroid (model.h).
#include <limits>

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

std::vector<float> other_triangles_winding(const TriangleTree& tree, size_t triangle_count, float beta) {
  std::vector<float> out(triangle_count, std::numeric_limits<float>::quiet_NaN());
  const TriangleTreeView view = tree.view();
  tbb::parallel_for(uint32_t(0), view.triangle_count, [&](uint32_t i) {
    const vec3 centroid = (view.vertices[3 * i] + view.vertices[3 * i + 1] + view.vertices[3 * i + 2]) / 3.0f;
    SumWithoutOne visitor{{view, centroid, {}}, i};
    visit_multipole(view, centroid, beta, visitor);
    out[view.triangle_ids[i]] = visitor.sum.acc.omega * kInv4Pi;
  });
  return out;
}

}  // namespace gwnrt
