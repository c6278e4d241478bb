// Where w is evaluated: the multipole traversal of the triangle tree (Taylor orders 0-2, with
// ∇w and H_w from the same traversal) and the brute-force reference. Host-and-device.
#pragma once

#include <array>
#include <type_traits>

#include "gwnrt/base/lanes.h"
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
// (docs/performance.md, queries).
inline constexpr float kLeafExpansionScale = 1.5f;

// Whether a lane's cluster is far enough to be expanded (scale2 = beta² for inner lanes, and
// kLeafExpansionScale² beta² for leaves). T is float (one lane) or f4 (a node's four lanes);
// empty lanes have a NaN centre, so they never pass.
template <class T, class M>
GWNRT_HD GWNRT_FORCEINLINE auto lane_is_far(T dx, T dy, T dz, T radius, M is_inner, float inner_scale2,
                                            float leaf_scale2) {
  const T r2 = dx * dx + dy * dy + dz * dz;
  const T scale2 = lane_select(is_inner, T{} + inner_scale2, T{} + leaf_scale2);
  return r2 > scale2 * radius * radius;
}

#if GWNRT_HOST_LANES
// A visitor that takes a node's far lanes at once: far_lanes(node, mask, dx, dy, dz), mask and
// d = p̄ - x per lane (and near triangles in any order).
template <class Visitor>
concept FarLanesVisitor = requires(Visitor& v, uint32_t node, i4 mask, f4 d) {
  v.far_lanes(node, mask, d, d, d);
};

// One that also takes a near leaf's triangles [first, first + count) at once.
template <class Visitor>
concept NearLeafVisitor = requires(Visitor& v, uint32_t first) {
  v.near_leaf(first, first);
};

namespace detail {

// visit_multipole for a FarLanesVisitor: the four lanes' tests and expansions at once, and the
// near lanes sorted out by bit masks rather than a branch per lane. A large mesh's moments do not
// stay in cache, so each opened child is prefetched when pushed, and its parent summed after the
// pushes to give the prefetches time; only the child's node and the first line of its expansion
// (its moments too cost more than they save in Morton order). Timings: docs/performance.md.
//
// A visitor with far_lane_pair (Taylor w) is visited two nodes at a time where the CPU has AVX2:
// both nodes' lanes tested and expanded as one 8-wide vector, and the opened children pushed
// without a branch (compacted by a permutation).
//
// Pairs are visited only while sp <= PairsBelow, so a pair leaves at most PairsBelow + 6 entries
// (and its push writes 8 lanes from sp - 2); from there single steps go depth-first, adding at
// most kTraversalStackSize - 1 (3 a level), so the stack never holds more than
// PairsBelow + kTraversalStackSize + 5. (PairsBelow is a parameter so that tests reach that branch.)
#if defined(__AVX2__)
// For each 8-bit mask, the indices of its set bits, lowest first, a nibble each.
inline constexpr std::array<uint32_t, 256> kSetLaneNibbles = [] {
  std::array<uint32_t, 256> table{};
  for (uint32_t m = 0; m < 256; ++m)
    for (uint32_t l = 0, k = 0; l < 8; ++l)
      if (m >> l & 1) table[m] |= l << (4 * k++);
  return table;
}();
#endif

template <class Visitor, int PairsBelow = kTraversalStackSize>
struct LaneTraversal {
  static_assert(PairsBelow >= 2);
  const TriangleTreeView& tree;
  const vec3 x;
  float inner_scale2, leaf_scale2;
  Visitor& visitor;
  uint32_t stack[PairsBelow + kTraversalStackSize + 8];
  int sp = 0;

  GWNRT_FORCEINLINE LaneTraversal(const TriangleTreeView& t, const vec3& p, float inner, float leaf, Visitor& v)
      : tree(t), x(p), inner_scale2(inner), leaf_scale2(leaf), visitor(v) {
    stack[sp++] = 0;
  }

  // Visits the node on top of the stack; false once there is none.
  GWNRT_FORCEINLINE bool step() {
    if (sp == 0) return false;
    const uint32_t ni = stack[--sp];
    const WideNode& node = tree.bvh.nodes[ni];
    const WideNodeExpansion& ex = tree.expansion[ni];
    const f4 dx = load4(ex.centre[0]) - x.x, dy = load4(ex.centre[1]) - x.y, dz = load4(ex.centre[2]) - x.z;
    const u4 count = load4(node.count);
    const i4 far = lane_is_far(dx, dy, dz, load4(ex.radius), count == 0u, inner_scale2, leaf_scale2);
    const uint32_t near_bits = ~lane_bits(far) & lane_bits(load4(node.child) != kEmptyLane);
    const uint32_t inner_bits = lane_bits(count == 0u);
    for (uint32_t rest = near_bits & inner_bits; rest != 0; rest &= rest - 1) {
      const uint32_t child = node.child[lowest_set_bit(rest)];
      stack[sp++] = child;
      __builtin_prefetch(&tree.bvh.nodes[child].child);
      __builtin_prefetch(&tree.expansion[child]);
    }
    // Whether or not a lane is far: most visited nodes have one, and the empty mask costs less
    // than a mispredicted branch.
    visitor.far_lanes(ni, far, dx, dy, dz);
    for (uint32_t leaves = near_bits & ~inner_bits; leaves != 0; leaves &= leaves - 1) {
      const int l = lowest_set_bit(leaves);
      near_leaf(node.child[l], node.count[l]);
    }
    return true;
  }

#if defined(__AVX2__)
  // Visits the two nodes on top of the stack (there are at least two, and sp <= PairsBelow).
  GWNRT_FORCEINLINE void step_pair() {
    const uint32_t na = stack[sp - 1], nb = stack[sp - 2];
    sp -= 2;
    const WideNode& a = tree.bvh.nodes[na];
    const WideNode& b = tree.bvh.nodes[nb];
    const WideNodeExpansion& ea = tree.expansion[na];
    const WideNodeExpansion& eb = tree.expansion[nb];
    const f8 dx = load8(ea.centre[0], eb.centre[0]) - x.x;
    const f8 dy = load8(ea.centre[1], eb.centre[1]) - x.y;
    const f8 dz = load8(ea.centre[2], eb.centre[2]) - x.z;
    const u8 count = load8(a.count, b.count), child = load8(a.child, b.child);
    const i8 far = lane_is_far(dx, dy, dz, load8(ea.radius, eb.radius), count == 0u, inner_scale2, leaf_scale2);
    const uint32_t near_bits = ~lane_bits(far) & lane_bits(child != kEmptyLane);
    const uint32_t inner_bits = lane_bits(count == 0u);
    const uint32_t open = near_bits & inner_bits;
    // The opened children, lowest lane first, moved to the front of one vector and stored at
    // once. Nothing is prefetched: prefetching the next two nodes to visit costs more than it
    // saves.
    const u8 nibbles = (u8{} + kSetLaneNibbles[open]) >> u8{0, 4, 8, 12, 16, 20, 24, 28};
    const u8 pushed = u8(_mm256_permutevar8x32_epi32(__m256i(child), __m256i(nibbles & 15u)));
    __builtin_memcpy(&stack[sp], &pushed, sizeof pushed);
    sp += __builtin_popcount(open);
    visitor.far_lane_pair(na, nb, far, dx, dy, dz);
    for (uint32_t leaves = near_bits & ~inner_bits; leaves != 0; leaves &= leaves - 1) {
      const int l = lowest_set_bit(leaves);
      near_leaf(child[l], count[l]);
    }
  }
#endif

  GWNRT_FORCEINLINE void near_leaf(uint32_t first, uint32_t count) {
    if constexpr (NearLeafVisitor<Visitor>) {
      visitor.near_leaf(first, count);
    } else {
      for (uint32_t t = first; t < first + count; ++t)
        visitor.near(t, tree.vertices[3 * t], tree.vertices[3 * t + 1], tree.vertices[3 * t + 2]);
    }
  }
};

template <int PairsBelow = kTraversalStackSize, class Visitor>
GWNRT_FORCEINLINE void visit_multipole_lanes(const TriangleTreeView& tree, const vec3& x, float inner_scale2,
                                             float leaf_scale2, Visitor& visitor) {
  LaneTraversal<Visitor, PairsBelow> traversal(tree, x, inner_scale2, leaf_scale2, visitor);
#if defined(__AVX2__)
  if constexpr (requires(f8 d, i8 m) { visitor.far_lane_pair(0u, 0u, m, d, d, d); }) {
    while (true) {
      if (traversal.sp >= 2 && traversal.sp <= PairsBelow)
        traversal.step_pair();
      else if (!traversal.step())
        break;
    }
    return;
  }
#endif
  while (traversal.step()) {
  }
}

}  // namespace detail
#endif

// The multipole traversal shared by every evaluation of a triangle tree. A cluster whose ball
// (centre p̄, radius r) has |x - p̄| > beta·r (leaves: kLeafExpansionScale·beta·r) is handed to
// visitor.far(node, lane, d = p̄ - x) (on the host, a FarLanesVisitor gets all of a node's at
// once); the triangles of nearer leaves to visitor.near(t, p0, p1, p2), t its leaf-order index;
// nearer inner clusters are opened. A scalar visitor may leave out near clusters it knows add
// nothing (visitor.skip_near(node, lane) true: the sheet classification's clusters that lie in
// the plane of x and do not contain it, core/src/sdf/sheets.cpp).
template <class Visitor>
GWNRT_HD GWNRT_FORCEINLINE void visit_multipole(const TriangleTreeView& tree, const vec3& x, float beta,
                                                Visitor& visitor) {
  const float inner_scale2 = beta * beta;
  const float leaf_scale2 = inner_scale2 * (kLeafExpansionScale * kLeafExpansionScale);
#if GWNRT_HOST_LANES
  if constexpr (FarLanesVisitor<Visitor>) {
    detail::visit_multipole_lanes(tree, x, inner_scale2, leaf_scale2, visitor);
    return;
  } else
#endif
  {
    uint32_t stack[kTraversalStackSize];
    int sp = 0;
    stack[sp++] = 0;
    while (sp > 0) {
      const uint32_t ni = stack[--sp];
      const WideNode& node = tree.bvh.nodes[ni];
      const WideNodeExpansion& ex = tree.expansion[ni];
      for (int l = 0; l < kBvhWidth; ++l) {
        const vec3 d(ex.centre[0][l] - x.x, ex.centre[1][l] - x.y, ex.centre[2][l] - x.z);
        if (lane_is_far(d.x, d.y, d.z, ex.radius[l], node.count[l] == 0, inner_scale2, leaf_scale2)) {
          visitor.far(ni, l, d);
          continue;
        }
        const uint32_t child = node.child[l];
        if (child == kEmptyLane) continue;
        if constexpr (requires { visitor.skip_near(ni, l); })
          if (visitor.skip_near(ni, l)) continue;
        if (node.count[l] == 0) {
          stack[sp++] = child;
          continue;
        }
        for (uint32_t t = child; t < child + node.count[l]; ++t)
          visitor.near(t, tree.vertices[3 * t], tree.vertices[3 * t + 1], tree.vertices[3 * t + 2]);
      }
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

// The near field is summed in float, but beside a long edge float has no digits left: where x
// lies within a small fraction of an edge's length from that edge (or of the triangle's size from
// its interior), van Oosterom's numerator and denominator are both far below |a||b||c|, the scale
// of their round-off: beside a fanned polygon's slivers float's w is off by tenths while every far
// cluster is right. Such a triangle (both below kNearConditioning |a||b||c|: the shape of
// point_on_triangle, with this looser bound) is evaluated in double, as the reference is; the
// float error of any other is then at most a few ε / kNearConditioning (≈ 1.5e-5 rad).
inline constexpr float kNearConditioning = 1.0f / 64;

// Whether float is ill-conditioned for a near triangle (kNearConditioning): what is then decided
// in double, by the near field, the crossing method's on-M test and the sheets' stack test.
GWNRT_HD GWNRT_FORCEINLINE bool near_float_ill_conditioned(const SolidAngleTangent<float>& t, float length_product) {
  return point_on_triangle(t.numerator, t.denominator, length_product, kNearConditioning);
}

// Ω of one near triangle: in float where that is well-conditioned (true; its value in `omega`),
// else false (the caller takes it in double).
GWNRT_HD GWNRT_FORCEINLINE bool near_solid_angle_float(const vec3& p0, const vec3& p1, const vec3& p2, const vec3& x,
                                                       float& omega) {
  float length_product;
  const SolidAngleTangent<float> t = triangle_solid_angle_tangent(p0, p1, p2, x, length_product);
  if (near_float_ill_conditioned(t, length_product)) return false;
  omega = 2.0f * arctan2(t.numerator, t.denominator);
  return true;
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
    float omega;
    if (!near_solid_angle_float(p0, p1, p2, x, omega)) {
      // Ill-conditioned: the derivatives' edge terms lose their digits there too (each long
      // edge's Biot–Savart term is ~1/h, and the terms of shared edges cancel), so all in double.
      const dvec3 q0(p0), q1(p1), q2(p2), xd(x);
      acc.omega += float(triangle_solid_angle(q0, q1, q2, xd, tree.mean_on_triangles));
      if constexpr (WantHessian) {
        dvec3 g;
        Sym3<double> h;
        triangle_solid_angle_derivatives(q0, q1, q2, xd, g, h);
        if constexpr (WantGradient) acc.gradient += detail::saturated_float(g);
        acc.hessian += detail::saturated_float(h);
      } else if constexpr (WantGradient) {
        acc.gradient += detail::saturated_float(triangle_solid_angle_gradient(q0, q1, q2, xd));
      }
      return;
    }
    acc.omega += omega;
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

#if GWNRT_HOST_LANES
// Van Oosterom–Strackee's tangent (solid_angle.h) of triangles given by their corners relative
// to x, a lane per triangle, and the product of the corners' lengths (the scale of its round-off);
// with the terms of the edge b -> c it was made of (a cone triangle's segment of ∂M, phase.h):
// |b|, |c|, b·c and |b × c|² (unread, the compiler drops them).
template <class V>
struct LaneTangent {
  V numerator, denominator, length_product;
  V lb, lc, bc, cross2;
};
template <class V>
GWNRT_FORCEINLINE LaneTangent<V> lane_solid_angle_tangent(const V a[3], const V b[3], const V c[3]) {
  const V la = lane_sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  const V lb = lane_sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
  const V lc = lane_sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
  const V bc0 = b[1] * c[2] - b[2] * c[1], bc1 = b[2] * c[0] - b[0] * c[2], bc2 = b[0] * c[1] - b[1] * c[0];
  const V ab = a[0] * b[0] + a[1] * b[1] + a[2] * b[2], bc = b[0] * c[0] + b[1] * c[1] + b[2] * c[2],
          ca = c[0] * a[0] + c[1] * a[1] + c[2] * a[2];
  return {
      a[0] * bc0 + a[1] * bc1 + a[2] * bc2, solid_angle_denominator(la, lb, lc, ab, bc, ca), la * lb * lc, lb, lc, bc,
      bc0 * bc0 + bc1 * bc1 + bc2 * bc2};
}

#if defined(__AVX__)
// The corners of triangles [v, v + 3·count) (count 1 to 4, three corners each) relative to x,
// g[j][k] coordinate k of corner j, a lane per triangle: lanes past count repeat the last one.
GWNRT_FORCEINLINE void lane_triangle_corners(const vec3* v, uint32_t count, const dvec3& x, d4 g[3][3]) {
  const uint32_t last = count - 1;
  const uint32_t m1 = last < 1 ? last : 1, m2 = last < 2 ? last : 2, m3 = last < 3 ? last : 3;
  for (int j = 0; j < 3; ++j)
    for (int k = 0; k < 3; ++k) g[j][k] = d4{v[j][k], v[3 * m1 + j][k], v[3 * m2 + j][k], v[3 * m3 + j][k]} - x[k];
}
// The same for leaf-order triangles [first, first + count) of a tree, from its corner columns
// where it has them (one load a coordinate; lanes past count then hold the next triangles, which
// the callers mask as they mask the repeated ones).
GWNRT_FORCEINLINE void lane_triangle_corners(const TriangleTreeView& tree, uint32_t first, uint32_t count,
                                             const dvec3& x, d4 g[3][3]) {
  if (!tree.corner_columns) return lane_triangle_corners(tree.vertices + 3 * first, count, x, g);
  const float* column = tree.corner_columns + first;
  for (int c = 0; c < 9; ++c)
    g[c / 3][c % 3] = d4(_mm256_cvtps_pd(_mm_loadu_ps(column))) - x[c % 3], column += tree.column_stride;
}
#endif

// Near triangles collected until a lane vector of Width is full: corners[3 * j + k][lane] is
// coordinate k of corner j.
template <int Width>
struct PendingTriangles {
  float corners[9][Width] = {};
  int count = 0;
  // Adds one; true when all Width lanes are taken.
  GWNRT_FORCEINLINE bool push(const vec3& p0, const vec3& p1, const vec3& p2) {
    for (int k = 0; k < 3; ++k) {
      corners[k][count] = p0[k];
      corners[3 + k][count] = p1[k];
      corners[6 + k][count] = p2[k];
    }
    return ++count == Width;
  }
  // The corners relative to x as lanes of V; lanes from count on hold stale corners.
  template <class V>
  GWNRT_FORCEINLINE void relative_to(const vec3& x, V g[3][3]) const {
    typedef float Loaded __attribute__((vector_size(sizeof(float) * Width)));
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) {
        Loaded v;
        __builtin_memcpy(&v, corners[3 * j + k], sizeof v);
        g[j][k] = __builtin_convertvector(v, V) - x[k];
      }
  }
};

// The far lanes' expansion of one node (f4) or of two (f8, lanes 0-3 the first node's):
// lanes(field) loads field(node) of each node as one lane vector.
template <int Order, class V, class Lanes>
struct FarLaneMoments {
  V n[3], s[6], p[10], e[3];
  GWNRT_FORCEINLINE FarLaneMoments(const TriangleTreeView& tree, Lanes lanes) {
    for (int k = 0; k < 3; ++k) n[k] = lanes([&](uint32_t i) { return tree.expansion[i].n[k]; });
    if constexpr (Order >= 1)
      for (int k = 0; k < 6; ++k) s[k] = lanes([&](uint32_t i) { return tree.order1[i].s[k]; });
    if constexpr (Order >= 2) {
      for (int k = 0; k < 10; ++k) p[k] = lanes([&](uint32_t i) { return tree.order2[i].p[k]; });
      for (int k = 0; k < 3; ++k) e[k] = lanes([&](uint32_t i) { return tree.order2[i].e[k]; });
    }
  }
};
template <int Order, class V, class Lanes>
GWNRT_FORCEINLINE V expand_far_lanes(const TriangleTreeView& tree, Lanes lanes, V dx, V dy, V dz) {
  const FarLaneMoments<Order, V, Lanes> m(tree, lanes);
  return FarFieldOmega<Order, V>(m.n, m.s, m.p, m.e, dx, dy, dz).omega;
}
// The far lanes' Ω and ∇ₓΩ, added to omega and gradient where mask holds.
template <int Order, class V, class M, class Lanes>
GWNRT_FORCEINLINE void add_far_lanes_with_gradient(const TriangleTreeView& tree, Lanes lanes, M mask, V dx, V dy, V dz,
                                                   V& omega, V gradient[3]) {
  const FarLaneMoments<Order, V, Lanes> m(tree, lanes);
  const FarFieldTerms<Order, V> t(m.n, m.s, m.p, m.e, dx, dy, dz);
  omega += lane_select(mask, t.omega, V{});
  V g[3];
  far_field_gradient(t, m.n, m.e, g);
  for (int k = 0; k < 3; ++k) gradient[k] -= lane_select(mask, g[k], V{});  // ∇ₓ = -∇_d
}
template <int Order>
GWNRT_FORCEINLINE f4 far_lanes_omega(const TriangleTreeView& tree, uint32_t node, f4 dx, f4 dy, f4 dz) {
  return expand_far_lanes<Order>(
      tree, [&](auto field) { return load4(field(node)); }, dx, dy, dz);
}

// w (and ∇w) on the host: a node's far lanes expanded together (one f4 expansion per node), and
// the near triangles kNearWidth at a time with a vector atan2 (lanes.h): the scalar atan2f is a
// large share of a lane-by-lane query. ∇w comes from the same far lanes and, for
// each near triangle, from its edges in float, or in double where its lane found float
// ill-conditioned, as the scalar visitor decides. H_w keeps the scalar visitor.
template <int Order, bool WantGradient = false>
struct TaylorLanesSum {
  const TriangleTreeView& tree;
  const vec3 x;
  f4 far_omega{};
  fnear near_omega{};
  PendingTriangles<kNearWidth> pending{};
  // ∇Ω's sums, only when asked: with them always there (zeroed, unused), w alone runs slower.
  struct GradientSums {
    f4 far[3] = {};
#if defined(__AVX2__)
    f8 far8[3] = {};  // of node pairs
#endif
    vec3 near{0.0f};
  };
  struct NoGradient {};
  [[no_unique_address]] std::conditional_t<WantGradient, GradientSums, NoGradient> gradient_sums{};

#if defined(__AVX2__)
  f8 far_omega8{};  // lanes of node pairs (LaneTraversal::step_pair)
  GWNRT_FORCEINLINE void far_lane_pair(uint32_t a, uint32_t b, i8 mask, f8 dx, f8 dy, f8 dz) {
    const auto lanes = [&](auto field) { return load8(field(a), field(b)); };
    if constexpr (WantGradient)
      add_far_lanes_with_gradient<Order>(tree, lanes, mask, dx, dy, dz, far_omega8, gradient_sums.far8);
    else
      far_omega8 += lane_select(mask, expand_far_lanes<Order>(tree, lanes, dx, dy, dz), f8{});
  }
#endif
  GWNRT_FORCEINLINE void far_lanes(uint32_t node, i4 mask, f4 dx, f4 dy, f4 dz) {
    if constexpr (WantGradient) {
      const auto lanes = [&](auto field) { return load4(field(node)); };
      add_far_lanes_with_gradient<Order>(tree, lanes, mask, dx, dy, dz, far_omega, gradient_sums.far);
    } else {
      far_omega += lane_select(mask, far_lanes_omega<Order>(tree, node, dx, dy, dz), f4{});
    }
  }
  GWNRT_FORCEINLINE void near(uint32_t, const vec3& p0, const vec3& p1, const vec3& p2) {
    if (pending.push(p0, p1, p2)) flush();
  }
  // Corner j of the pending triangle in lane l.
  GWNRT_FORCEINLINE vec3 corner(int l, int j) const {
    return vec3(pending.corners[3 * j][l], pending.corners[3 * j + 1][l], pending.corners[3 * j + 2][l]);
  }
  GWNRT_FORCEINLINE void flush() {
    fnear g[3][3];
    pending.relative_to(x, g);
    const LaneTangent<fnear> tangent = lane_solid_angle_tangent(g[0], g[1], g[2]);
    fnear omega = 2.0f * lane_atan2(tangent.numerator, tangent.denominator);
    // Ill-conditioned lanes (near_solid_angle_float) again in double: rare, so a scalar loop.
    const uint32_t ill = lane_bits(point_on_triangle(tangent.numerator, tangent.denominator, tangent.length_product,
                                                     kNearConditioning)) &
                         ((1u << pending.count) - 1u);
    for (uint32_t rest = ill; rest != 0; rest &= rest - 1) {
      const int l = lowest_set_bit(rest);
      const dvec3 p0(corner(l, 0)), p1(corner(l, 1)), p2(corner(l, 2));
      omega[l] = float(triangle_solid_angle(p0, p1, p2, dvec3(x), tree.mean_on_triangles));
      if constexpr (WantGradient)
        gradient_sums.near += saturated_float(triangle_solid_angle_gradient(p0, p1, p2, dvec3(x)));
    }
    if constexpr (WantGradient)
      for (int l = 0; l < pending.count; ++l)
        if (!(ill >> l & 1))
          gradient_sums.near += triangle_solid_angle_gradient(corner(l, 0), corner(l, 1), corner(l, 2), x);
    if (pending.count < kNearWidth) {  // the unused lanes hold stale corners
      inear lane;
      for (int i = 0; i < kNearWidth; ++i) lane[i] = i;
      omega = lane_select(lane < pending.count, omega, fnear{});
    }
    near_omega += omega;
    pending.count = 0;
  }
  GWNRT_FORCEINLINE float omega() {
    if (pending.count > 0) flush();
#if defined(__AVX2__)
    return lane_sum(far_omega) + lane_sum(far_omega8) + lane_sum(near_omega);
#else
    return lane_sum(far_omega) + lane_sum(near_omega);
#endif
  }
  GWNRT_FORCEINLINE vec3 gradient() requires WantGradient {
    if (pending.count > 0) flush();
    vec3 sum = gradient_sums.near;
    for (int k = 0; k < 3; ++k) {
      sum[k] += lane_sum(gradient_sums.far[k]);
#if defined(__AVX2__)
      sum[k] += lane_sum(gradient_sums.far8[k]);
#endif
    }
    return sum;
  }
};
#endif

}  // namespace detail

// w (and optionally ∇w, H_w) at x by the multipole tree: far clusters by their expansion of
// the given order, near triangles exactly.
template <int Order, bool WantGradient, bool WantHessian>
GWNRT_HD WindingSample winding_number_taylor(const TriangleTreeView& tree, const vec3& x, float beta) {
#if GWNRT_HOST_LANES
  if constexpr (!WantHessian) {
    detail::TaylorLanesSum<Order, WantGradient> sum{tree, x};
    visit_multipole(tree, x, beta, sum);
    WindingSample out;
    out.w = sum.omega() * kInv4Pi;
    if constexpr (WantGradient) out.gradient = sum.gradient() * kInv4Pi;
    return out;
  }
#endif
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
    omega += triangle_solid_angle(p0, p1, p2, x, tree.mean_on_triangles);
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
