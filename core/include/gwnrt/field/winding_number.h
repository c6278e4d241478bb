// Where w is evaluated: the multipole traversal of the triangle tree (Taylor orders 0-2, with
// ∇w and H_w from the same traversal) and the brute-force reference. Host-and-device.
#pragma once

#include "gwnrt/field/multipole.h"
#include "gwnrt/field/solid_angle.h"
#include "gwnrt/geometry/bvh.h"

namespace gwnrt {

struct TaylorOptions {
  int order = 2;      // 0, 1 or 2
  float beta = 2.0f;  // a cluster is expanded when |x - p̄| > beta · radius
};

template <class T>
struct WindingSampleT {
  T w = 0;
  glm::vec<3, T> gradient{0};
  Sym3<T> hessian;
};
using WindingSample = WindingSampleT<float>;
using WindingSampleExact = WindingSampleT<double>;

namespace detail {

GWNRT_HD GWNRT_FORCEINLINE void load_lane_moments(const TriangleTreeView& tree, uint32_t node, int lane, int order,
                                                  float n[3], float s[6], float p[10], float e[3]) {
  const WideNodeExpansion& ex = tree.expansion[node];
  for (int a = 0; a < 3; ++a) n[a] = ex.n[a][lane];
  if (order >= 1) {
    const WideNodeOrder1& o1 = tree.order1[node];
    for (int k = 0; k < 6; ++k) s[k] = o1.s[k][lane];
  }
  if (order >= 2) {
    const WideNodeOrder2& o2 = tree.order2[node];
    for (int k = 0; k < 10; ++k) p[k] = o2.p[k][lane];
    for (int a = 0; a < 3; ++a) e[a] = o2.e[a][lane];
  }
}

}  // namespace detail

// A leaf (a few triangles) is expanded only from farther away than an inner cluster: summing
// it exactly costs about what its expansion does, so the margin buys accuracy almost for free
// (measured at beta = 2 on the bundled meshes and the full dragon: the same max error as never
// expanding leaves, with 40-70% fewer exact triangle terms and 15-30% less time).
inline constexpr float kLeafExpansionScale = 1.5f;

// The multipole traversal shared by every evaluation of a triangle tree. A cluster whose ball
// (centre p̄, radius r) has |x - p̄| > beta·r (leaves: kLeafExpansionScale·beta·r) is handed to
// visitor.far(node, lane, d = p̄ - x); the triangles of nearer leaves to
// visitor.near(t, p0, p1, p2), t its leaf-order index; nearer inner clusters are opened.
template <class Visitor>
GWNRT_HD GWNRT_FORCEINLINE void visit_multipole(const TriangleTreeView& tree, const vec3& x, float beta,
                                                Visitor& visitor) {
  uint32_t stack[kTraversalStackSize];
  int sp = 0;
  stack[sp++] = 0;
  const float inner_scale2 = beta * beta;
  const float leaf_scale2 = inner_scale2 * (kLeafExpansionScale * kLeafExpansionScale);
  while (sp > 0) {
    const uint32_t ni = stack[--sp];
    const WideNode& node = tree.bvh.nodes[ni];
    const WideNodeExpansion& ex = tree.expansion[ni];
    for (int l = 0; l < kBvhWidth; ++l) {
      const vec3 d(ex.centre[0][l] - x.x, ex.centre[1][l] - x.y, ex.centre[2][l] - x.z);
      const float r2 = glm::dot(d, d);
      // Empty lanes have a NaN centre, so they never pass this test.
      const float scale2 = node.count[l] == 0 ? inner_scale2 : leaf_scale2;
      if (r2 > scale2 * ex.radius[l] * ex.radius[l]) {
        visitor.far(ni, l, d);
        continue;
      }
      const uint32_t child = node.child[l];
      if (child == kEmptyLane) continue;
      if (node.count[l] == 0) {
        stack[sp++] = child;
        continue;
      }
      for (uint32_t t = child; t < child + node.count[l]; ++t)
        visitor.near(t, tree.vertices[3 * t], tree.vertices[3 * t + 1], tree.vertices[3 * t + 2]);
    }
  }
}

// The far-field part every visitor shares: the expansion of one cluster added to `acc`.
template <int Order, bool WantGradient, bool WantHessian>
GWNRT_HD GWNRT_FORCEINLINE void add_cluster_far_field(const TriangleTreeView& tree, uint32_t node, int lane,
                                                      const vec3& d, FieldAccumulator<float>& acc) {
  float n[3], s[6], p[10], e[3];
  detail::load_lane_moments(tree, node, lane, Order, n, s, p, e);
  add_far_field<Order, WantGradient, WantHessian>(n, s, p, e, d, acc);
}

namespace detail {

template <int Order, bool WantGradient, bool WantHessian>
struct TaylorSum {
  const TriangleTreeView& tree;
  const vec3& x;
  FieldAccumulator<float> acc;
  GWNRT_HD void far(uint32_t node, int lane, const vec3& d) {
    add_cluster_far_field<Order, WantGradient, WantHessian>(tree, node, lane, d, acc);
  }
  GWNRT_HD void near(uint32_t, const vec3& p0, const vec3& p1, const vec3& p2) {
    acc.omega += triangle_solid_angle(p0, p1, p2, x);
    if constexpr (WantHessian) {
      vec3 g;
      sym3 h;
      triangle_solid_angle_derivatives(p0, p1, p2, x, g, h);
      if constexpr (WantGradient) acc.gradient += g;
      acc.hessian += h;
    } else if constexpr (WantGradient) {
      acc.gradient += triangle_solid_angle_gradient(p0, p1, p2, x);
    }
  }
};

}  // namespace detail

// w (and optionally ∇w, H_w) at x by the multipole tree: far clusters by their expansion of
// the given order, near triangles exactly.
template <int Order, bool WantGradient, bool WantHessian>
GWNRT_HD WindingSample winding_number_taylor(const TriangleTreeView& tree, const vec3& x, float beta) {
  detail::TaylorSum<Order, WantGradient, WantHessian> sum{tree, x, {}};
  visit_multipole(tree, x, beta, sum);
  WindingSample out;
  out.w = sum.acc.omega * kInv4Pi;
  out.gradient = sum.acc.gradient * kInv4Pi;
  out.hessian = sum.acc.hessian * kInv4Pi;
  return out;
}

// Runtime choice of order and derivatives; each combination is its own specialisation, so
// asking for w alone costs what w alone costs.
GWNRT_HD inline WindingSample winding_number(const TriangleTreeView& tree, const vec3& x, const TaylorOptions& options,
                                             bool want_gradient = false, bool want_hessian = false) {
#define GWNRT_DISPATCH_ORDER(O)                                                          \
  if (want_hessian)                                                                      \
    return want_gradient ? winding_number_taylor<O, true, true>(tree, x, options.beta)   \
                         : winding_number_taylor<O, false, true>(tree, x, options.beta); \
  return want_gradient ? winding_number_taylor<O, true, false>(tree, x, options.beta)    \
                       : winding_number_taylor<O, false, false>(tree, x, options.beta);
  switch (options.order) {
    case 0:
      GWNRT_DISPATCH_ORDER(0)
    case 1:
      GWNRT_DISPATCH_ORDER(1)
    default:
      GWNRT_DISPATCH_ORDER(2)
  }
#undef GWNRT_DISPATCH_ORDER
}

// The reference: every triangle's exact term, accumulated in double.
GWNRT_HD inline WindingSampleExact winding_number_exact(const TriangleTreeView& tree, const vec3& xf,
                                                        bool want_gradient = false, bool want_hessian = false) {
  WindingSampleExact out;
  const dvec3 x(xf);
  double omega = 0;
  for (uint32_t t = 0; t < tree.triangle_count; ++t) {
    const dvec3 p0(tree.vertices[3 * t]), p1(tree.vertices[3 * t + 1]), p2(tree.vertices[3 * t + 2]);
    omega += triangle_solid_angle(p0, p1, p2, x);
    if (want_hessian) {
      dvec3 g;
      Sym3<double> h;
      triangle_solid_angle_derivatives(p0, p1, p2, x, g, h);
      out.gradient += g;
      out.hessian += h;
    } else if (want_gradient) {
      out.gradient += triangle_solid_angle_gradient(p0, p1, p2, x);
    }
  }
  const double inv4pi = 0.25 / kPi;
  out.w = omega * inv4pi;
  out.gradient *= inv4pi;
  out.hessian = out.hessian * inv4pi;
  return out;
}

}  // namespace gwnrt
