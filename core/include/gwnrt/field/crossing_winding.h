// Exact w by signed crossings plus the boundary cone (docs/design.md §3): M − C is closed, so
// off M ∪ C, w − w_C is a whole number, 0 at infinity, that changes by a crossing's jump of M
// minus that of C. Along one ray from x to beyond the box
//     w(x) = w_C(x) − Σ jumps of M + Σ jumps of C,        ∇w = ∇w_C,  H_w = H_{w_C},
// and w_C, ∇w_C, H_{w_C} (the Biot–Savart field of ∂M) come from one traversal of the cone's
// tree. The cost follows the number of crossings and |∂M|, not |M|; a closed mesh is its
// crossing count alone, with ∇w = 0. Host-and-device.
#pragma once

#include "gwnrt/field/winding_number.h"
#include "gwnrt/geometry/model_view.h"
#include "gwnrt/geometry/ray.h"

namespace gwnrt {

// The cone's clusters are expanded (order 2) only beyond this multiple of their radius. The
// crossing method promises |Δw| <= 1e-5 and ∇w to a relative 1e-4, where the tree's beta = 2
// gives 1e-3: 5 keeps a margin of about 4 on w and sums fewer cone triangles exactly than 6
// (docs/performance.md, exact w by crossings).
inline constexpr float kConeBeta = 5.0f;
// ∇w and H_w (relative 1e-4 promised) need more: 16 is the smallest tried that holds it.
inline constexpr float kConeDerivativeBeta = 16.0f;

struct CrossingStats {
  uint32_t mesh_crossings = 0;  // crossings of M met by the ray
  uint32_t cone_crossings = 0;
  uint32_t cone_near = 0;  // cone triangles summed exactly
  uint32_t cone_far = 0;   // cone clusters taken by their expansion
};

namespace detail {

// The jumps of the cone's triangles below one lane of a node that the axis ray crosses ahead.
GWNRT_HD GWNRT_FORCEINLINE void add_crossings_below(const TriangleTreeView& cone, const RayFrame& frame,
                                                    const WideNode& node, int lane, int& jumps, CrossingStats* stats) {
  const auto add = [&](uint32_t, float, int jump) {
    jumps += jump;
    if (stats) ++stats->cone_crossings;
  };
  if (node.count[lane] == 0)
    visit_axis_crossings(cone.bvh, cone.vertices, frame, 0.0f, add, node.child[lane]);
  else
    visit_axis_leaf(cone.vertices, node.child[lane], node.count[lane], frame, 0.0f, add);
}

// Whether the axis ray's line misses a triangle for certain: all its corners (relative to x,
// exact in double) strictly on one side of x in the ray's kx or in its ky. T is double, or d4
// for four triangles (a lane mask).
template <class T>
GWNRT_HD GWNRT_FORCEINLINE auto beside_axis_line(T a_kx, T b_kx, T c_kx, T a_ky, T b_ky, T c_ky) {
  const T zero{};
  return ((a_kx > zero) & (b_kx > zero) & (c_kx > zero)) | ((a_kx < zero) & (b_kx < zero) & (c_kx < zero)) |
         ((a_ky > zero) & (b_ky > zero) & (c_ky > zero)) | ((a_ky < zero) & (b_ky < zero) & (c_ky < zero));
}

// Whether a near cone triangle's plane, crossed by the ray at all, lies ahead: numerator =
// n·(apex − x) and n·direction (the opposite sign of jump) agree. The same numerator puts x on
// one side of the triangle for its solid angle, so the two always agree.
GWNRT_HD GWNRT_FORCEINLINE bool crossing_is_ahead(double numerator, int jump) {
  return numerator >= 0.0 ? jump < 0 : jump > 0;
}

// The cone's part: w_C, ∇w_C, H_{w_C} and the jumps of C along the ray, in one traversal. A
// cluster far from x is taken by its expansion; when the ray passes through its box its
// triangles are still tested for crossings (a crossing test is cheap; its solid angle is not).
// Near triangles are summed exactly, their differences from x and van Oosterom's numerator and
// denominator in double: the cone's inner edges (apex to ∂M) are singular lines of the two
// triangles that share them, whose terms cancel, and in float the rounding of x relative to
// such an edge leaves errors of 1e-4 (phase.h). Whether the ray ahead crosses a near triangle
// is decided by the sign of the same numerator that decides on which side of it the solid angle
// puts x, so that the two always agree, even for x within round-off of the cone.
template <bool WantGradient, bool WantHessian>
struct ConeCrossingSum {
  const TriangleTreeView& cone;
  const RayFrame& frame;
  const vec3& x;
  float beta;
  CrossingStats* stats;
  FieldAccumulator<float> far_field;
  UnwrappedAngleSum near_half_angles;  // Σ atan2 of the near triangles
  FanGradientSum near_gradient;        // with the Hessian, its sum alone (the edges evaluated anyway)
  Sym3<double> near_hessian;
  int jumps = 0;         // Σ jumps of C ahead
  bool on_cone = false;  // x lies exactly on a near cone triangle (its plane, inside or on its edges)

  GWNRT_HD ConeCrossingSum(const TriangleTreeView& cone_tree, const RayFrame& ray, const vec3& point,
                           float cone_beta = kConeBeta, CrossingStats* counters = nullptr)
      : cone(cone_tree), frame(ray), x(point), beta(cone_beta), stats(counters) {}

  GWNRT_HD float winding() const {  // w_C
    return float(double(far_field.omega) * (0.25 / kPi) + near_half_angles.angle() * (0.5 / kPi));
  }

  FanCorners corners;  // reuses the apex's and the shared vertex's lengths

  // A far cluster: its expansion, and when the ray passes through its box, its crossings.
  GWNRT_HD void far(uint32_t node, int lane, const vec3& d) {
    add_cluster_far_field<2, WantGradient, WantHessian>(cone, node, lane, d, far_field);
    if (stats) ++stats->cone_far;
    const WideNode& n = cone.bvh.nodes[node];
    if (axis_ray_meets_lane(n, lane, frame, 0.0f)) add_crossings_below(cone, frame, n, lane, jumps, stats);
  }

  // A near cone triangle, summed exactly.
  GWNRT_HD void near(uint32_t, const vec3& apex, const vec3& a, const vec3& b) {
    const dvec3 xd(x);
    const bool continues = corners.next(xd, apex, a, b);
    const SolidAngleTangent<double> tangent =
        solid_angle_tangent(corners.g0, corners.g1, corners.g2, corners.l0, corners.l1, corners.l2,
                            glm::cross(corners.g1, corners.g2), glm::dot(corners.g1, corners.g2));
    // -0 + 0 = +0: x on the triangle's plane counts as on its positive side, for the angle and
    // the crossing alike.
    const double numerator = tangent.numerator + 0.0;
    // On the triangle (in its plane, not outside it), up to double round-off relative to its
    // corners' distances: w_C jumps there and the side is not defined, so the caller moves x off
    // C (w is continuous there, C is not part of M). On an edge the denominator is 0 only up to
    // that round-off (a point on an inner edge of an axis-aligned cap).
    const double round_off = 1e-12 * corners.l0 * corners.l1 * corners.l2;
    on_cone |= fabs(numerator) <= round_off && tangent.denominator <= round_off;
    near_half_angles.add(numerator, tangent.denominator);
    // The crossing test only where the ray's line passes within the triangle's bounds across it
    // (most near triangles are beside the ray: comparisons instead of the test).
    const int kx = frame.kx, ky = frame.ky;
    const bool beside = beside_axis_line(corners.g0[kx], corners.g1[kx], corners.g2[kx], corners.g0[ky], corners.g1[ky],
                                         corners.g2[ky]);
    float t;
    int jump;
    if (!beside && triangle_crossing<true>(frame, apex, a, b, t, jump) && crossing_is_ahead(numerator, jump)) {
      jumps += jump;
      if (stats) ++stats->cone_crossings;
    }
    if constexpr (WantHessian) {
      dvec3 g;
      Sym3<double> h;
      triangle_solid_angle_derivatives(dvec3(apex), dvec3(a), dvec3(b), xd, g, h);
      near_gradient.sum += g;
      near_hessian += h;
    } else if constexpr (WantGradient) {
      near_gradient.add(corners, continues);
    }
    if (stats) ++stats->cone_near;
  }

  GWNRT_HD void traverse() {
    if (cone.bvh.node_count > 0) visit_multipole(cone, x, beta, *this);
  }
};

// The visitor winding_number_crossing runs: ConeCrossingSum, or on the host for w alone
// ConeCrossingLanes.
template <bool WantGradient, bool WantHessian>
struct ConeCrossingVisitor {
  using type = ConeCrossingSum<WantGradient, WantHessian>;
};

#if GWNRT_HOST_LANES && defined(__AVX__)
// The far lanes `far_bits` of a node, counted, and the crossings below those the axis ray meets.
GWNRT_FORCEINLINE void add_far_lane_crossings(const TriangleTreeView& cone, const RayFrame& frame, uint32_t node,
                                              uint32_t far_bits, int& jumps, CrossingStats* stats) {
  if (stats) stats->cone_far += uint32_t(__builtin_popcount(far_bits));
  const WideNode& n = cone.bvh.nodes[node];
  for (uint32_t meets = far_bits & axis_ray_lane_mask(n, frame, 0.0f); meets != 0; meets &= meets - 1)
    add_crossings_below(cone, frame, n, lowest_set_bit(meets), jumps, stats);
}

// w_C and C's jumps on the host: ConeCrossingSum<false, false>'s terms and decisions with a
// node's far lanes expanded together and the near triangles four at a time in double, four angle
// products side by side: the near cone triangles are most of a crossing query's time, and the
// lanes give the same w to the last bit of the sums compared.
struct ConeCrossingLanes {
  const TriangleTreeView& cone;
  const RayFrame& frame;
  const dvec3 x;
  float beta;
  CrossingStats* stats;
  f4 far_omega{};
  UnwrappedAngleSumT<d4, l4> near_half_angles;
  int jumps = 0;
  bool on_cone = false;

  ConeCrossingLanes(const TriangleTreeView& cone_tree, const RayFrame& ray, const vec3& point, float cone_beta,
                    CrossingStats* counters)
      : cone(cone_tree), frame(ray), x(point), beta(cone_beta), stats(counters) {}

  GWNRT_FORCEINLINE void far_lanes(uint32_t node, i4 mask, f4 dx, f4 dy, f4 dz) {
    far_omega += lane_select(mask, far_lanes_omega<2>(cone, node, dx, dy, dz), f4{});
    add_far_lane_crossings(cone, frame, node, lane_bits(mask), jumps, stats);
  }
  // A leaf's triangles four at a time (BuildOptions allows leaves of up to kMaxLeafSize).
  GWNRT_FORCEINLINE void near_leaf(uint32_t first, uint32_t count) {
    for (uint32_t done = 0; done < count; done += 4) near_quad(first + done, count - done < 4 ? count - done : 4);
  }
  GWNRT_FORCEINLINE void near_quad(uint32_t first, uint32_t count) {
    const vec3* v = cone.vertices + 3 * first;
    d4 g[3][3];
    lane_triangle_corners(cone, first, count, x, g);
    const LaneTangent<d4> tangent = lane_solid_angle_tangent(g[0], g[1], g[2]);
    const l4 lane{0, 1, 2, 3};
    const l4 used = lane < int64_t(count);
    const d4 zero{};
    // Unused lanes: the factor 0, which has no angle. -0 + 0 = +0 as in ConeCrossingSum::near.
    const d4 numerator = lane_select(used, tangent.numerator + 0.0, zero);
    const d4 denominator = lane_select(used, tangent.denominator, zero);
    const d4 round_off = 1e-12 * tangent.length_product;
    on_cone |= lane_bits64(used & (lane_abs(numerator) <= round_off) & (denominator <= round_off)) != 0;
    near_half_angles.add(numerator, denominator);
    const int kx = frame.kx, ky = frame.ky;
    uint32_t maybe = lane_bits64(used & ~beside_axis_line(g[0][kx], g[1][kx], g[2][kx], g[0][ky], g[1][ky], g[2][ky]));
    for (; maybe != 0; maybe &= maybe - 1) {
      const int l = lowest_set_bit(maybe);
      float t;
      int jump;
      if (triangle_crossing<true>(frame, v[3 * l], v[3 * l + 1], v[3 * l + 2], t, jump) &&
          crossing_is_ahead(numerator[l], jump)) {
        jumps += jump;
        if (stats) ++stats->cone_crossings;
      }
    }
    if (stats) stats->cone_near += count;
  }
  GWNRT_FORCEINLINE void traverse() {
    if (cone.bvh.node_count > 0) visit_multipole(cone, vec3(x), beta, *this);
  }
  GWNRT_FORCEINLINE float winding() const {  // w_C
    UnwrappedAngleSum near;
    add_lanes_to(near_half_angles, near);
    return float(double(lane_sum(far_omega)) * (0.25 / kPi) + near.angle() * (0.5 / kPi));
  }
};

template <>
struct ConeCrossingVisitor<false, false> {
  using type = ConeCrossingLanes;
};

// w_C and ∇w_C on the host: ConeCrossingSum<true, false> with a node's far lanes expanded together
// (their expansion and its gradient were a third of a scan's meshing, at the box bounds' centres
// and the smooth roots' normals); the near triangles stay scalar (their fans' shared edges).
struct ConeCrossingGradientLanes : ConeCrossingSum<true, false> {
  f4 far_omega{};
  f4 far_gradient[3] = {};

  ConeCrossingGradientLanes(const TriangleTreeView& cone_tree, const RayFrame& ray, const vec3& point, float cone_beta,
                            CrossingStats* counters)
      : ConeCrossingSum<true, false>(cone_tree, ray, point, cone_beta, counters) {}

  GWNRT_FORCEINLINE void far_lanes(uint32_t node, i4 mask, f4 dx, f4 dy, f4 dz) {
    add_far_lanes_with_gradient<2>(
        cone, [&](auto field) { return load4(field(node)); }, mask, dx, dy, dz, far_omega, far_gradient);
    add_far_lane_crossings(cone, frame, node, lane_bits(mask), jumps, stats);
  }
  // The lanes folded into far_field, which winding() and cone_gradient() read.
  GWNRT_FORCEINLINE void traverse() {
    if (cone.bvh.node_count == 0) return;
    visit_multipole(cone, x, beta, *this);
    far_field.omega += lane_sum(far_omega);
    for (int k = 0; k < 3; ++k) far_field.gradient[k] += lane_sum(far_gradient[k]);
  }
};

template <>
struct ConeCrossingVisitor<true, false> {
  using type = ConeCrossingGradientLanes;
};

#endif

// w from the cone's traversal along a ray and the jumps of M met ahead on that ray.
template <class Cone>
GWNRT_HD GWNRT_FORCEINLINE float crossing_winding(const Cone& cone, int mesh_jumps) {
  return float(cone.jumps - mesh_jumps) + cone.winding();
}

// ∇w = ∇w_C from a traversal that summed the gradient: far clusters' expansions and the near
// triangles' Biot–Savart sum.
template <class Cone>
GWNRT_HD GWNRT_FORCEINLINE vec3 cone_gradient(const Cone& cone) {
  return cone.far_field.gradient * kInv4Pi + saturated_float(cone.near_gradient.total() * (0.25 * kInvPi));
}

}  // namespace detail

#if GWNRT_HOST_LANES && defined(__AVX__)
// w_C at many points at once (the sheets' side points, sdf/sheets.cpp, over their spanning
// surfaces' tree): one traversal of the cone's tree for all of them, a cluster expanded where it
// is beyond beta radii of the points' whole box (so of each point), each far cluster and near
// triangle evaluated at eight points at a time in float. The cone's jumps are left to a walk of
// their own (jumps_along_axis_lattice), so a point is unsure, and gets no value, wherever that
// walk and the solid angle might put it on different sides of a near triangle or float is
// ill-conditioned: within kConeBatchPlaneTolerance of the triangle's plane (relative to the
// distances involved, far above either's round-off), or near the triangle itself
// (kNearConditioning, as the Taylor lanes). Elsewhere the float error is a few ε /
// kNearConditioning a near triangle, far below the tree's own at the betas used.
inline constexpr float kConeBatchPlaneTolerance = 1e-4f;
// With ∇w (the Biot–Savart field of edges, no jumps needed), an edge whose |g_i × g_j| is below
// this share of |g_i||g_j| (x near its line, where float loses the terms that cancel between its
// neighbours) is taken in double.
inline constexpr float kBatchGradientConditioning = 1e-2f;

// The points of a batch (ConeWindingBatch, RibbonWindingBatch), eight to a chunk, and what is
// summed at them: Ω (w_C, or the ribbons' w before M's jumps), ∇Ω when asked, and whether each is
// unsure.
template <int Capacity, bool WantGradient>
struct WindingBatchPoints {
  static constexpr int kChunks = (Capacity + 7) / 8;
  f8 x[kChunks], y[kChunks], z[kChunks];
  f8 omega[kChunks];
  i8 unsure[kChunks];
  f8 gradient[WantGradient ? 3 : 1][kChunks];
  int count = 0;

  GWNRT_FORCEINLINE void add(const vec3& p) {
    const int c = count / 8, l = count % 8;
    if (l == 0) {
      x[c] = y[c] = z[c] = omega[c] = f8{};
      unsure[c] = i8{};
      if constexpr (WantGradient) gradient[0][c] = gradient[1][c] = gradient[2][c] = f8{};
    }
    x[c][l] = p.x;
    y[c][l] = p.y;
    z[c][l] = p.z;
    ++count;
  }

  // Whether point i has a value.
  GWNRT_FORCEINLINE bool sure(int i) const { return !unsure[i / 8][i % 8]; }

  // Ω / 4π at point i, or NaN where it is unsure.
  GWNRT_FORCEINLINE float winding(int i) const {
    return sure(i) ? omega[i / 8][i % 8] * float(0.25 * kInvPi) : __builtin_nanf("");
  }

  // ∇Ω / 4π at point i (WantGradient), or NaN where it is unsure.
  GWNRT_FORCEINLINE vec3 winding_gradient(int i) const requires WantGradient {
    if (!sure(i)) return vec3(__builtin_nanf(""));
    return vec3(gradient[0][i / 8][i % 8], gradient[1][i / 8][i % 8], gradient[2][i / 8][i % 8]) * float(0.25 * kInvPi);
  }

  // Before a traversal: the last chunk's unused lanes repeat its first point (finite; never
  // read), and the points' box. Returns the number of chunks.
  GWNRT_FORCEINLINE int prepare(vec3& lo, vec3& hi) {
    const int chunks = (count + 7) / 8;
    for (int l = count % 8; l != 0 && l < 8; ++l) {
      x[chunks - 1][l] = x[chunks - 1][0];
      y[chunks - 1][l] = y[chunks - 1][0];
      z[chunks - 1][l] = z[chunks - 1][0];
    }
    lo = vec3(kInfinity);
    hi = vec3(-kInfinity);
    for (int c = 0; c < chunks; ++c)
      for (int l = 0; l < 8; ++l) {
        lo = glm::min(lo, vec3(x[c][l], y[c][l], z[c][l]));
        hi = glm::max(hi, vec3(x[c][l], y[c][l], z[c][l]));
      }
    return chunks;
  }

  // Whether lane `lane` of a node is beyond beta radii of the points' box [lo, hi]
  // (inner_scale2 = beta², leaf_scale2 for leaves); its expansion centre in `centre`.
  static GWNRT_FORCEINLINE bool lane_far(const WideNode& node, const WideNodeExpansion& ex, int lane, const vec3& lo,
                                         const vec3& hi, float inner_scale2, float leaf_scale2, vec3& centre) {
    centre = vec3(ex.centre[0][lane], ex.centre[1][lane], ex.centre[2][lane]);
    const vec3 gap = glm::max(glm::max(lo - centre, centre - hi), vec3(0.0f));
    const float scale2 = node.count[lane] == 0 ? inner_scale2 : leaf_scale2;
    return glm::dot(gap, gap) > scale2 * ex.radius[lane] * ex.radius[lane];
  }

  // Visits the lanes of a tree (its BVH and per-node expansions) depth first for the points' box
  // [lo, hi]: on_lane(node index, node, lane, far, centre), far whether the lane is beyond beta
  // radii of the box (lane_far, centre its expansion's), returns whether to open an inner lane.
  template <class OnLane>
  static GWNRT_FORCEINLINE void visit_lanes(const BvhView& bvh, const WideNodeExpansion* expansion, float beta,
                                            const vec3& lo, const vec3& hi, OnLane&& on_lane) {
    const float inner_scale2 = beta * beta;
    const float leaf_scale2 = inner_scale2 * (kLeafExpansionScale * kLeafExpansionScale);
    uint32_t stack[kTraversalStackSize];
    int sp = 0;
    stack[sp++] = 0;
    while (sp > 0) {
      const uint32_t ni = stack[--sp];
      const WideNode& node = bvh.nodes[ni];
      for (int lane = 0; lane < kBvhWidth; ++lane) {
        if (node.child[lane] == kEmptyLane) continue;
        vec3 centre;
        const bool far = lane_far(node, expansion[ni], lane, lo, hi, inner_scale2, leaf_scale2, centre);
        if (on_lane(ni, node, lane, far, centre) && node.count[lane] == 0) stack[sp++] = node.child[lane];
      }
    }
  }

  // A far cluster of `tree`: its expansion (and ∇) at every point.
  GWNRT_FORCEINLINE void far(const TriangleTreeView& tree, uint32_t node, int lane, const vec3& centre, int chunks) {
    const auto lanes = [&](auto field) { return splat<f8>(field(node)[lane]); };
    const detail::FarLaneMoments<2, f8, decltype(lanes)> m(tree, lanes);
    for (int c = 0; c < chunks; ++c) {
      if constexpr (WantGradient) {
        const FarFieldTerms<2, f8> t(m.n, m.s, m.p, m.e, centre.x - x[c], centre.y - y[c], centre.z - z[c]);
        omega[c] += t.omega;
        f8 g[3];
        far_field_gradient(t, m.n, m.e, g);
        for (int k = 0; k < 3; ++k) gradient[k][c] -= g[k];  // ∇ₓ = -∇_d
      } else {
        omega[c] += FarFieldOmega<2, f8>(m.n, m.s, m.p, m.e, centre.x - x[c], centre.y - y[c], centre.z - z[c]).omega;
      }
    }
  }

  // One edge's Biot–Savart term of ∇Ω (solid_angle.h's EdgeField) at eight points, added to sum;
  // the lanes where it is ill-conditioned (kBatchGradientConditioning) returned.
  static GWNRT_FORCEINLINE i8 add_edge_field(const f8 (&gi)[3], const f8 (&gj)[3], f8 li, f8 lj, f8 (&sum)[3]) {
    const f8 c[3] = {gi[1] * gj[2] - gi[2] * gj[1], gi[2] * gj[0] - gi[0] * gj[2], gi[0] * gj[1] - gi[1] * gj[0]};
    const f8 c2 = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
    const f8 scale = kBatchGradientConditioning * li * lj;
    const i8 ill = c2 <= scale * scale;
    const f8 inv_li = 1.0f / li, inv_lj = 1.0f / lj;
    f8 f{};
    for (int k = 0; k < 3; ++k) f += (gj[k] - gi[k]) * (gj[k] * inv_lj - gi[k] * inv_li);
    const f8 s = lane_select(ill, f8{}, f / c2);
    for (int k = 0; k < 3; ++k) sum[k] += c[k] * s;
    return ill;
  }
};

template <int Capacity>
struct ConeWindingBatch : WindingBatchPoints<Capacity, false> {
  using Points = WindingBatchPoints<Capacity, false>;
  using Points::count, Points::x, Points::y, Points::z, Points::omega, Points::unsure, Points::winding;

  // w at point i from the jumps of the cone and of M ahead of it along the caller's ray
  // (detail::crossing_winding's sum), or NaN where it is unsure.
  GWNRT_FORCEINLINE float crossing_winding(int i, int cone_jumps, int mesh_jumps) const {
    return float(cone_jumps - mesh_jumps) + winding(i);
  }

  // axis: that of the rays along which the caller counts the cone's jumps.
  void evaluate(const TriangleTreeView& cone, float beta, int axis) {
    const int kx = (axis + 1) % 3, ky = (axis + 2) % 3;
    if (count == 0) return;
    vec3 lo, hi;
    const int chunks = this->prepare(lo, hi);
    const float diagonal = glm::length(hi - lo);
    if (cone.bvh.node_count == 0) return;
    Points::visit_lanes(
        cone.bvh, cone.expansion, beta, lo, hi,
        [&](uint32_t ni, const WideNode& node, int lane, bool far, const vec3& centre) {
          if (far) {
            this->far(cone, ni, lane, centre, chunks);
            return false;
          }
          for (uint32_t t = node.child[lane]; t < node.child[lane] + node.count[lane]; ++t)  // none when inner
            near(cone.vertices[3 * t], cone.vertices[3 * t + 1], cone.vertices[3 * t + 2], diagonal, kx, ky, chunks);
          return true;
        });
  }

  GWNRT_FORCEINLINE void near(const vec3& p0, const vec3& p1, const vec3& p2, float diagonal, int kx, int ky,
                              int chunks) {
    // The distance to the plane from (p0 − x)·n with n in double first: the solid angle's own
    // numerator carries an error of a few ε |a||b||c|, far more than this across a sliver.
    const vec3 n(glm::cross(dvec3(p1) - dvec3(p0), dvec3(p2) - dvec3(p0)));
    const float longest = max_of(glm::length(p1 - p0), max_of(glm::length(p2 - p1), glm::length(p0 - p2)));
    const float reach = kConeBatchPlaneTolerance * glm::length(n);
    for (int c = 0; c < chunks; ++c) {
      const f8 g[3][3] = {{p0.x - x[c], p0.y - y[c], p0.z - z[c]},
                          {p1.x - x[c], p1.y - y[c], p1.z - z[c]},
                          {p2.x - x[c], p2.y - y[c], p2.z - z[c]}};
      const detail::LaneTangent<f8> t = detail::lane_solid_angle_tangent(g[0], g[1], g[2]);
      f8 angle = 2.0f * lane_atan2(t.numerator, t.denominator);
      // Where float is ill-conditioned, the triangle again in double (as the Taylor lanes do).
      const uint32_t ill =
          lane_bits(point_on_triangle(t.numerator, t.denominator, t.length_product, kNearConditioning));
      for (uint32_t rest = ill; rest != 0; rest &= rest - 1) {
        const int l = lowest_set_bit(rest);
        double length_product;
        const SolidAngleTangent<double> exact = triangle_solid_angle_tangent(
            dvec3(p0), dvec3(p1), dvec3(p2), dvec3(x[c][l], y[c][l], z[c][l]), length_product);
        unsure[c][l] |=
            point_on_triangle(exact.numerator, exact.denominator, length_product, kOnTriangleRoundOff) ? -1 : 0;
        angle[l] = float(2.0 * atan2(exact.numerator, exact.denominator));
      }
      omega[c] += angle;
      // Whether the line along the axis through x might cross the triangle near x: the corners'
      // distances from x are at most the longer of |b|, |c| plus the longest edge. (A sign of a
      // difference of floats is exact, so the test beside the line is.)
      const f8 farthest = lane_select(t.lb > t.lc, t.lb, t.lc) + (longest + diagonal);
      const f8 height = g[0][0] * n.x + g[0][1] * n.y + g[0][2] * n.z;
      const i8 beside = detail::beside_axis_line(g[0][kx], g[1][kx], g[2][kx], g[0][ky], g[1][ky], g[2][ky]);
      unsure[c] |= (height <= reach * farthest) & (-height <= reach * farthest) & ~beside;
    }
  }
};
#endif

// w, and ∇w and H_w when asked, by crossings and the cone. Exact up to float round-off (the
// cone's expansion is held to 1e-5 by kConeBeta) wherever x is not within round-off of M; on M
// (within round-off) the tree's sum, which gives there the mean of w's one-sided limits.
// Whether x lies on one of the triangles of a leaf lane whose box, grown by `pad`, holds x: as
// the tree's near field decides it (winding_number.h: in double, point_on_triangle, where float
// is ill-conditioned), so that the tree's sum taken there gives these triangles 0. The crossing
// walk asks it of every leaf its axis ray meets, so that finding x on M costs a box test per leaf,
// not a traversal of its own (which would double a query on a closed mesh).
GWNRT_HD inline bool point_on_leaf(const TriangleTreeView& tree, const WideNode& node, int lane, const vec3& x,
                                   float pad) {
  for (int k = 0; k < 3; ++k)
    if (!(node.lo[k][lane] - pad <= x[k] && x[k] <= node.hi[k][lane] + pad)) return false;
  for (uint32_t i = node.child[lane]; i < node.child[lane] + node.count[lane]; ++i) {
    const vec3 &p0 = tree.vertices[3 * i], &p1 = tree.vertices[3 * i + 1], &p2 = tree.vertices[3 * i + 2];
    float length_product;
    const SolidAngleTangent<float> near = triangle_solid_angle_tangent(p0, p1, p2, x, length_product);
    if (!near_float_ill_conditioned(near, length_product)) continue;  // well off the triangle
    double exact_length_product;
    const SolidAngleTangent<double> t =
        triangle_solid_angle_tangent(dvec3(p0), dvec3(p1), dvec3(p2), dvec3(x), exact_length_product);
    if (point_on_triangle(t.numerator, t.denominator, exact_length_product, kOnTriangleRoundOff)) return true;
  }
  return false;
}

// x exactly on a cone triangle (found in the traversal: the tangent's numerator 0 and its
// denominator <= 0) is moved along a fixed direction by this many ulps of its largest coordinate,
// or, near the origin, by 2^-40 of the model's box (the least that moves the corners relative to
// x in double), up to kConeNudgeTries times (each 8x farther): w is continuous there, so the
// moved point has the same w up to the move times |∇w|, far within the 1e-5 promised. It happens
// where x and a cap of ∂M share exact coordinates (an axis-aligned hole and a grid of query
// points in its plane; the hole's centre, its cone's apex, at the origin).
inline constexpr float kConeNudgeUlps = 2.0f;
inline constexpr int kConeNudgeTries = 4;

// The moves above, one after another: next() gives x_in moved kConeNudgeUlps ulps (or 2^-40 of
// the box), then 8x farther each time, while tries are left.
struct ConeNudge {
  vec3 x_in;
  float step;
  int tries = 0;
  GWNRT_HD ConeNudge(const Aabb& bounds, const vec3& x) : x_in(x) {
    const vec3 extent = bounds.hi - bounds.lo;
    const float largest = max_of(fabsf(x.x), max_of(fabsf(x.y), fabsf(x.z)));
    // 1.2e-7: about one ulp; 9.1e-13: 2^-40.
    step = max_of(kConeNudgeUlps * 1.2e-7f * largest, 9.1e-13f * max_of(extent.x, max_of(extent.y, extent.z)));
  }
  GWNRT_HD bool left() const { return tries < kConeNudgeTries; }
  GWNRT_HD vec3 next() {
    const vec3 moved = x_in + step * vec3(0.5345225f, -0.2672612f, 0.8017837f);  // a generic unit direction
    step *= 8.0f;
    ++tries;
    return moved;
  }
};

template <bool WantGradient, bool WantHessian>
GWNRT_HD WindingSample winding_number_crossing(const ModelView& m, const vec3& x_in,
                                               float cone_beta = (WantGradient || WantHessian) ? kConeDerivativeBeta
                                                                                               : kConeBeta,
                                               CrossingStats* stats = nullptr) {
  vec3 x = x_in;
  const float largest = max_of(fabsf(x.x), max_of(fabsf(x.y), fabsf(x.z)));
  ConeNudge nudge(m.bounds, x_in);
  for (;;) {
    const RayFrame frame = shortest_exit_axis_ray(m.bounds, x);
    typename detail::ConeCrossingVisitor<WantGradient, WantHessian>::type cone(m.cone, frame, x, cone_beta, stats);
    cone.traverse();
    if (cone.on_cone && nudge.left()) {
      x = nudge.next();
      continue;
    }
    // On M the crossings ahead give the side behind x along the ray, where w is the mean of its
    // one-sided limits (solid_angle.h): the tree's sum gives that, its triangles through x
    // counting 0. (Crossings within round-off of x do not find x on M: a ray from a cube's edge
    // runs in one face's plane and leaves the other by the tie-break.) Every leaf whose box holds
    // x is met by the axis ray from x, so the walk looks for x on M in those.
    const float pad = 4.0f * 1.2e-7f * largest;
    int mesh_jumps = 0;
    bool x_on_mesh = false;
    visit_axis_crossings(
        m.triangles.bvh, m.triangles.vertices, frame, 0.0f,
        [&](uint32_t, float, int jump) {
          mesh_jumps += jump;
          if (stats) ++stats->mesh_crossings;
        },
        0,
        [&](uint32_t, const WideNode& node, int lane) {
          if (node.count[lane] > 0) x_on_mesh = x_on_mesh || point_on_leaf(m.triangles, node, lane, x, pad);
          return true;
        });
    if (x_on_mesh) return winding_number_taylor<2, WantGradient, WantHessian>(m.triangles, x_in, cone_beta);
    WindingSample out;
    out.w = detail::crossing_winding(cone, mesh_jumps);
    if constexpr (WantGradient) out.gradient = detail::cone_gradient(cone);
    if constexpr (WantHessian) {
      out.hessian = cone.far_field.hessian * kInv4Pi;
      out.hessian += detail::saturated_float(cone.near_hessian * (0.25 * kInvPi));
    }
    return out;
  }
}

GWNRT_HD inline WindingSample winding_number_crossing(const ModelView& m, const vec3& x, bool want_gradient,
                                                      bool want_hessian, CrossingStats* stats = nullptr) {
  if (want_hessian)
    return want_gradient ? winding_number_crossing<true, true>(m, x, kConeDerivativeBeta, stats)
                         : winding_number_crossing<false, true>(m, x, kConeDerivativeBeta, stats);
  return want_gradient ? winding_number_crossing<true, false>(m, x, kConeDerivativeBeta, stats)
                       : winding_number_crossing<false, false>(m, x, kConeBeta, stats);
}

// M's jumps ahead of each of Count points along one line parallel to axis `axis`, in ascending
// order along the direction sign · e_axis (grid corners: meshing/): the ray from the first point
// meets, at t >= the offset of point k, every crossing ahead of point k, so M is walked once.
template <int Count>
GWNRT_HD void mesh_jumps_along_axis(const ModelView& m, const vec3 (&points)[Count], int axis, float sign,
                                    int (&mesh_jumps)[Count]) {
  vec3 direction(0.0f);
  direction[axis] = sign;
  const RayFrame line = make_ray_frame(points[0], direction);
  float offset[Count];
  for (int k = 0; k < Count; ++k) {
    offset[k] = (points[k][axis] - points[0][axis]) * sign;
    mesh_jumps[k] = 0;
  }
  visit_axis_crossings(m.triangles.bvh, m.triangles.vertices, line, 0.0f, [&](uint32_t, float t, int jump) {
    for (int k = 0; k < Count; ++k) mesh_jumps[k] += t >= offset[k] ? jump : 0;
  });
}

// The same for the N × N lines of a lattice at once (a block's columns), for the triangles of
// `tree` (M's, or the cone's): line i + N·j runs through the points at u[i] along axis
// (axis + 1) % 3, v[j] along (axis + 2) % 3 and along[k] along `axis` (ascending along
// sign · e_axis; the lines share them, as a grid's corners do). Each line's jumps are exactly
// mesh_jumps_along_axis's for its points: its crossings are tested by its own frame, in every
// leaf its walk would open, but the tree is walked once for the lattice.
template <int N, int Count>
GWNRT_HD void jumps_along_axis_lattice(const TriangleTreeView& tree, const float (&u)[N], const float (&v)[N],
                                       const float (&along)[Count], int axis, float sign,
                                       int (&mesh_jumps)[N * N][Count]) {
  const int au = (axis + 1) % 3, av = (axis + 2) % 3;
  vec3 direction(0.0f), lo, hi;
  direction[axis] = sign;
  lo[axis] = hi[axis] = along[0];
  lo[au] = u[0];
  hi[au] = u[N - 1];
  lo[av] = v[0];
  hi[av] = v[N - 1];
  const RayFrame beam = make_ray_frame(lo, direction);
  RayFrame line = beam;  // its origin moved to each line's in turn
  float offset[Count];
  for (int k = 0; k < Count; ++k) offset[k] = (along[k] - along[0]) * sign;
  for (int c = 0; c < N * N; ++c)
    for (int k = 0; k < Count; ++k) mesh_jumps[c][k] = 0;
  const vec3* vertices = tree.vertices;
  visit_axis_beam_leaves(tree.bvh, beam, lo, hi, [&](uint32_t first, uint32_t count) {
    for (uint32_t t = first; t < first + count; ++t) {
      const vec3 &p0 = vertices[3 * t], &p1 = vertices[3 * t + 1], &p2 = vertices[3 * t + 2];
      // A line whose origin lies outside the triangle's range along u or v misses it (ray.h).
      const float u0 = min_of(p0[au], min_of(p1[au], p2[au])), u1 = max_of(p0[au], max_of(p1[au], p2[au]));
      const float v0 = min_of(p0[av], min_of(p1[av], p2[av])), v1 = max_of(p0[av], max_of(p1[av], p2[av]));
      uint32_t in_u = 0, in_v = 0;
      for (int i = 0; i < N; ++i) {
        in_u |= uint32_t(u0 <= u[i] && u[i] <= u1) << i;
        in_v |= uint32_t(v0 <= v[i] && v[i] <= v1) << i;
      }
      if (in_u == 0) continue;
      for (uint32_t jm = in_v; jm != 0; jm &= jm - 1) {
        const int j = lowest_set_bit(jm);
        line.origin[av] = v[j];
        for (uint32_t im = in_u; im != 0; im &= im - 1) {
          const int i = lowest_set_bit(im);
          line.origin[au] = u[i];
          float tc;
          int jump;
          if (!triangle_crossing<true>(line, p0, p1, p2, tc, jump) || !(tc >= 0.0f)) continue;
          for (int k = 0; k < Count; ++k) mesh_jumps[i + N * j][k] += tc >= offset[k] ? jump : 0;
        }
      }
    }
  });
}

// w at x given M's jumps ahead of it along (axis, sign): the cone traversed along the same
// direction, its clusters expanded beyond cone_beta radii. A point exactly on C takes
// winding_number_crossing's nudged evaluation.
GWNRT_HD inline float winding_from_mesh_jumps(const ModelView& m, const vec3& x, int axis, float sign, int mesh_jumps,
                                              float cone_beta = kConeBeta) {
  vec3 direction(0.0f);
  direction[axis] = sign;
  const RayFrame frame = make_ray_frame(x, direction);  // the visitor keeps a reference
  typename detail::ConeCrossingVisitor<false, false>::type cone(m.cone, frame, x, cone_beta, nullptr);
  cone.traverse();
  return cone.on_cone ? winding_number_crossing<false, false>(m, x).w : detail::crossing_winding(cone, mesh_jumps);
}

// w at Count points along one line (mesh_jumps_along_axis), each exactly as winding_number_crossing
// gives it but with M's crossings found once.
template <int Count>
GWNRT_HD void winding_numbers_along_axis(const ModelView& m, const vec3 (&points)[Count], int axis, float sign,
                                         float (&out)[Count], float cone_beta = kConeBeta) {
  int mesh_jumps[Count];
  mesh_jumps_along_axis(m, points, axis, sign, mesh_jumps);
  for (int k = 0; k < Count; ++k) out[k] = winding_from_mesh_jumps(m, points[k], axis, sign, mesh_jumps[k], cone_beta);
}

}  // namespace gwnrt
