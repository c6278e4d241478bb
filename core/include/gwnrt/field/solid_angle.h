// Exact per-triangle terms of the winding number: the signed solid angle of one triangle seen
// from a point, its gradient and its Hessian. These are the near field of every query and the
// brute-force reference. Host-and-device.
#pragma once

#include "gwnrt/base/hd.h"
#include "gwnrt/base/lanes.h"

namespace gwnrt {

// Signed solid angle Ω of triangle (p0, p1, p2) seen from x, in (-2π, 2π); positive when x is
// on the side opposite to the normal (p1-p0)×(p2-p0) (van Oosterom–Strackee).
// T = float for the fast path, double for the reference.
// The two arguments of its atan2: Ω = 2 atan2(numerator, denominator). Kept apart for sums
// wanted only modulo 4π (HalfAngleSum).
template <class T>
struct SolidAngleTangent {
  T numerator, denominator;
};

// Van Oosterom–Strackee's denominator from the corners' lengths and their dot products a·b, b·c,
// c·a: for any T, a scalar or a lane vector (the host's multipole traversal, winding_number.h).
template <class T>
GWNRT_HD GWNRT_FORCEINLINE T solid_angle_denominator(T la, T lb, T lc, T ab, T bc, T ca) {
  return la * lb * lc + ab * lc + bc * la + ca * lb;
}

// From the corners relative to x (a, b, c), their lengths, b × c and b·c: the pieces a caller
// may already have (the tracer shares them with its bound on the edge b -> c, phase.h).
template <class T>
GWNRT_HD GWNRT_FORCEINLINE SolidAngleTangent<T> solid_angle_tangent(const glm::vec<3, T>& a, const glm::vec<3, T>& b,
                                                                    const glm::vec<3, T>& c, T la, T lb, T lc,
                                                                    const glm::vec<3, T>& b_cross_c, T b_dot_c) {
  return {glm::dot(a, b_cross_c), solid_angle_denominator(la, lb, lc, glm::dot(a, b), b_dot_c, glm::dot(c, a))};
}

// x on the triangle itself: in its plane up to the round-off of the numerator a·(b × c), which
// is that of |a||b||c| (`relative` of it: kOnTriangleRoundOff for double, as the cone's test in
// crossing_winding.h), and not beside it (the denominator is > 0 at points of the plane outside
// the triangle, <= 0 only on it). There Ω's one-sided limits are ±2π, and which one the signs
// give is round-off (following them could put w at -0.5 on a cube's face diagonal). On M, w
// is the mean of its limits, the average of w over a small sphere about x (1/2 on a face of a
// closed mesh, the dihedral angle over 2π on an edge, the corner's solid angle over 4π at a
// vertex): the triangles that x lies on count 0. The float near field decides it in double
// (winding_number.h, near_solid_angle: float is ill-conditioned there). T is a scalar or a lane
// vector (then a mask).
inline constexpr double kOnTriangleRoundOff = 1e-12;
template <class T, class R>
GWNRT_HD GWNRT_FORCEINLINE auto point_on_triangle(T numerator, T denominator, T length_product, R relative) {
  const T round_off = length_product * relative;
  return (numerator <= round_off) & (-numerator <= round_off) & (denominator <= round_off);
}

// With mean_on_triangle, x on the triangle gives 0 (point_on_triangle; M's trees ask for it).
// The tangent of triangle (p0, p1, p2) seen from x, and |a||b||c| (the scale of its round-off).
template <class T>
GWNRT_HD GWNRT_FORCEINLINE SolidAngleTangent<T> triangle_solid_angle_tangent(const glm::vec<3, T>& p0,
                                                                             const glm::vec<3, T>& p1,
                                                                             const glm::vec<3, T>& p2,
                                                                             const glm::vec<3, T>& x,
                                                                             T& length_product) {
  const glm::vec<3, T> a = p0 - x, b = p1 - x, c = p2 - x;
  const T la = glm::length(a), lb = glm::length(b), lc = glm::length(c);
  length_product = la * lb * lc;
  return solid_angle_tangent(a, b, c, la, lb, lc, glm::cross(b, c), glm::dot(b, c));
}

template <class T>
GWNRT_HD inline T triangle_solid_angle(const glm::vec<3, T>& p0, const glm::vec<3, T>& p1, const glm::vec<3, T>& p2,
                                       const glm::vec<3, T>& x, bool mean_on_triangle = false) {
  T length_product;
  const SolidAngleTangent<T> tangent = triangle_solid_angle_tangent(p0, p1, p2, x, length_product);
  // atan2(0, 0) = 0 covers x on a vertex and zero-area triangles: they contribute nothing.
  if (mean_on_triangle &&
      point_on_triangle(tangent.numerator, tangent.denominator, length_product, T(kOnTriangleRoundOff)))
    return T(0);
  return T(2) * arctan2(tangent.numerator, tangent.denominator);
}

// Σ atan2(numerator_i, denominator_i) modulo 2π, as the argument of the product of the complex
// numbers denominator_i + i·numerator_i: one atan2 at the end instead of one per term. Only the
// product's direction matters, so factors are rescaled by exact powers of two (no division on
// the chain of multiplications, which would set its pace) and the products every 16 factors,
// which keeps them far from overflow and underflow. A zero factor (x on a vertex, a zero-area
// triangle) has no angle and is skipped.
struct HalfAngleSum {
  // Two products, alternated and multiplied together at the end: each multiplication then waits
  // on the one two factors back, which halves the latency of the chain.
  float re = 1.0f, im = 0.0f, other_re = 1.0f, other_im = 0.0f;
  uint32_t unscaled = 0;
  GWNRT_HD void add(const SolidAngleTangent<float>& t) {
    if (t.numerator == 0.0f && t.denominator == 0.0f) return;
    const float s = power_of_two_scale(max_of(fabsf(t.numerator), fabsf(t.denominator)));
    const float zr = t.denominator * s, zi = t.numerator * s;  // |z| in [1, 2√2)
    const float r = re * zr - im * zi, i = re * zi + im * zr;
    re = other_re;
    im = other_im;
    other_re = r;
    other_im = i;
    if (++unscaled == 16) {  // each product has taken 8 factors: at most 2^12 larger
      const float p = power_of_two_scale(max_of(fabsf(re), fabsf(im)));
      const float q = power_of_two_scale(max_of(fabsf(other_re), fabsf(other_im)));
      re *= p;
      im *= p;
      other_re *= q;
      other_im *= q;
      unscaled = 0;
    }
  }
  GWNRT_HD float angle() const {  // in (-π, π]
    return arctan2(re * other_im + im * other_re, re * other_re - im * other_im);
  }
};

// Σ atan2(numerator_i, denominator_i) exactly, not modulo 2π: the argument of the product of
// the complex numbers denominator_i + i·numerator_i plus 2π for each time the running argument
// wrapped past ±π. A wrap is read off the signs of the imaginary parts: two factors with
// arguments in [0, π] whose product has a negative imaginary part went past π, two in (−π, 0)
// whose product has a non-negative one went past −π; near ±π round-off may move the argument
// across and the count with it, so the total stays continuous. In double: one multiplication
// per term instead of one atan2 (which the crossing method's near cone triangles spent most of
// their time in), the product rescaled by an exact power of two every 4 factors (a factor is at
// most 4|a||b||c|: no overflow or underflow for coordinates within 1e15 of each other).
// T = double with W = int, or on the host d4 with l4 (lanes.h): four independent products, a
// lane each, which the caller adds together at the end (add_lanes_to). A factor 0 (x on a
// vertex, a zero-area triangle) has no angle: it is taken as 1.
template <class T, class W>
struct UnwrappedAngleSumT {
  T re = T{} + 1.0, im = T{};
  W wraps = W{};
  uint32_t unscaled = 0;
  GWNRT_HD GWNRT_FORCEINLINE void add(T numerator, T denominator) {
    const T zero{};
    denominator = lane_select((numerator == zero) & (denominator == zero), zero + 1.0, denominator);
    const T r = re * denominator - im * numerator, i = re * numerator + im * denominator;
    const auto up = (im >= zero) & (numerator >= zero), down = (im < zero) & (numerator < zero);
    wraps += lane_select(up & (i < zero), W{} + 1, W{}) - lane_select(down & (i >= zero), W{} + 1, W{});
    re = r;
    im = i;
    if (++unscaled == 4) {
      const T abs_re = lane_abs(re), abs_im = lane_abs(im);
      const T scale = power_of_two_scale(lane_select(abs_re > abs_im, abs_re, abs_im));
      re *= scale;
      im *= scale;
      unscaled = 0;
    }
  }
};

struct UnwrappedAngleSum : UnwrappedAngleSumT<double, int> {
  GWNRT_HD double angle() const { return atan2(im, re) + 2.0 * kPi * double(wraps); }
};

#if GWNRT_HOST_LANES && defined(__AVX__)
// The four lanes' products as factors of one scalar sum (each lane's argument is in (−π, π],
// its wraps counted apart).
GWNRT_FORCEINLINE void add_lanes_to(const UnwrappedAngleSumT<d4, l4>& lanes, UnwrappedAngleSum& sum) {
  for (int l = 0; l < 4; ++l) {
    sum.add(lanes.im[l], lanes.re[l]);
    sum.wraps += int(lanes.wraps[l]);
  }
}
#endif

// The corners of a fan's triangles (apex, a, b) relative to x, in double, visited in order:
// consecutive triangles of the cone C share their apex (one per boundary loop) and usually a
// vertex (b of one is a of the next in leaf order), so those lengths are reused, not recomputed.
struct FanCorners {
  dvec3 g0{0.0}, g1{0.0}, g2{0.0};  // apex, a, b relative to x
  double l0 = 0.0, l1 = 0.0, l2 = 0.0;
  vec3 last_apex{__builtin_huge_valf()}, last_b{__builtin_huge_valf()};

  // Whether this triangle continues the last one's fan: the same apex, and its a the last b.
  GWNRT_HD bool next(const dvec3& x, const vec3& apex, const vec3& a, const vec3& b) {
    const bool continues = apex == last_apex && a == last_b;
    if (!(apex == last_apex)) {
      last_apex = apex;
      g0 = dvec3(apex) - x;
      l0 = glm::length(g0);
    }
    g1 = dvec3(a) - x;
    g2 = dvec3(b) - x;
    l1 = a == last_b ? l2 : glm::length(g1);
    l2 = glm::length(g2);
    last_b = b;
    return continues;
  }
};

namespace detail {

// One edge's Biot–Savart term of ∇Ω for the edge g_i → g_j (g = vertex - x). Zero when x lies
// on the edge's line, which is the limit of the field on the line outside the segment.
template <class T>
struct EdgeField {
  glm::vec<3, T> e;  // g_j - g_i, constant in x
  glm::vec<3, T> c;  // g_i × g_j
  T c2;              // |c|²
  T f;               // e·(ĝ_j - ĝ_i)
  glm::vec<3, T> gi_hat, gj_hat;
  T inv_li, inv_lj;
  bool degenerate;

  GWNRT_HD EdgeField(const glm::vec<3, T>& gi, const glm::vec<3, T>& gj)
      : EdgeField(gi, gj, glm::length(gi), glm::length(gj)) {}
  // Inlined everywhere: out of line in some translation units only, its products would be fused
  // into FMAs differently there, and the same query would give results an ulp apart.
  GWNRT_HD GWNRT_FORCEINLINE EdgeField(const glm::vec<3, T>& gi, const glm::vec<3, T>& gj, T li, T lj) {
    e = gj - gi;
    c = glm::cross(gi, gj);
    c2 = glm::dot(c, c);
    degenerate = !(c2 > T(0)) || !(li > T(0)) || !(lj > T(0));
    inv_li = degenerate ? T(0) : T(1) / li;
    inv_lj = degenerate ? T(0) : T(1) / lj;
    gi_hat = gi * inv_li;
    gj_hat = gj * inv_lj;
    f = glm::dot(e, gj_hat - gi_hat);
  }
  GWNRT_HD glm::vec<3, T> gradient() const { return degenerate ? glm::vec<3, T>(0) : c * (f / c2); }
  // In float: x so near the edge's line that |c|² is near the denormals (1e-20 from a unit
  // mesh's vertex: |c|² ~ 1e-40, where 0·inf makes the gradient and the Hessian NaN). Such a
  // triangle is evaluated in double (below), as is one whose float terms overflow. On the line
  // itself (c = 0) the term is 0, as above. The bound is absolute, well above FLT_MIN (1.2e-38),
  // and below the |c|² of every point at ordinary distances from a mesh of the smallest size
  // served (1e-8 across: |c|² ~ 1e-32).
  GWNRT_HD bool float_underflows() const { return c2 < T(1e-36f) && (c.x != T(0) || c.y != T(0) || c.z != T(0)); }
};

// Whether every component is finite (a sum of them is not when one is inf or NaN, or when
// finite ones overflow it, which as well as any is a reason to take the double path).
GWNRT_HD inline bool finite(const vec3& v) { return is_finite(v.x + v.y + v.z); }
GWNRT_HD inline bool finite(const Sym3<float>& h) { return is_finite(h.xx + h.xy + h.xz + h.yy + h.yz + h.zz); }

// A double result in float, held within ±1e37: the terms of a triangle evaluated in double
// because float underflowed, where the Hessian's reach 1e40 (1/|c|²). They are large only by the
// edge whose line x nearly lies on, and that edge's terms in the two triangles that share it are
// exact negatives, so held at the same bound they still cancel (to 0 on a closed mesh), and a sum
// of up to 30 of them stays finite (at float's own limit two would make inf and then NaN). The
// bound is far above any term that is not on its way to infinity: a lower one (1e30) would cut
// the Hessians of the smallest meshes served, whose neighbouring triangles' terms cancel there.
GWNRT_HD inline float saturated_float(double v) {
  constexpr double kMax = 1e37;
  return float(v > kMax ? kMax : (v < -kMax ? -kMax : v));
}
GWNRT_HD inline vec3 saturated_float(const dvec3& v) {
  return {saturated_float(v.x), saturated_float(v.y), saturated_float(v.z)};
}
GWNRT_HD inline Sym3<float> saturated_float(const Sym3<double>& h) {
  return {saturated_float(h.xx), saturated_float(h.xy), saturated_float(h.xz),
          saturated_float(h.yy), saturated_float(h.yz), saturated_float(h.zz)};
}

}  // namespace detail

// ∇Ω with respect to x: the field of the triangle's boundary loop (Biot–Savart), summed over
// its three edges. Only valid off the triangle itself, where Ω is smooth.
template <class T>
GWNRT_HD inline glm::vec<3, T> triangle_solid_angle_gradient(const glm::vec<3, T>& p0, const glm::vec<3, T>& p1,
                                                             const glm::vec<3, T>& p2, const glm::vec<3, T>& x) {
  const glm::vec<3, T> g0 = p0 - x, g1 = p1 - x, g2 = p2 - x;
  const detail::EdgeField<T> e01(g0, g1), e12(g1, g2), e20(g2, g0);
  const glm::vec<3, T> sum = e01.gradient() + e12.gradient() + e20.gradient();
  if constexpr (sizeof(T) == sizeof(float)) {
    if (e01.float_underflows() || e12.float_underflows() || e20.float_underflows() || !detail::finite(sum))
      return detail::saturated_float(triangle_solid_angle_gradient(dvec3(p0), dvec3(p1), dvec3(p2), dvec3(x)));
  }
  return sum;
}

// ∇Ω summed over the triangles (apex, a, b) of fans visited in FanCorners' order. Where a
// triangle continues the last one's fan, the last one's edge b → apex and this one's apex → a are
// the same edge both ways, whose terms cancel: neither is evaluated, one edge in three for a run
// of the cone's triangles instead of three. They are also the large terms near the cone's inner
// edges (singular lines of both), so leaving them out removes their rounding as well.
struct FanGradientSum {
  dvec3 sum{0.0};
  dvec3 open_edge{0.0};  // the last triangle's b → apex, until the next one shows whether it cancels

  GWNRT_HD GWNRT_FORCEINLINE void add(const FanCorners& c, bool continues) {  // inlined: see EdgeField
    sum += detail::EdgeField<double>(c.g1, c.g2, c.l1, c.l2).gradient();      // a → b, a segment of ∂M
    if (!continues) sum += open_edge + detail::EdgeField<double>(c.g0, c.g1, c.l0, c.l1).gradient();
    open_edge = detail::EdgeField<double>(c.g2, c.g0, c.l2, c.l0).gradient();
  }
  GWNRT_HD dvec3 total() const { return sum + open_edge; }
};

// ∇Ω and the Hessian of Ω together. The Hessian is the x-derivative of each edge term,
// ∂(c f/|c|²)/∂x = c ⊗ v + (f/|c|²) E with v = ∇f/|c|² − 2f/|c|⁴ (c × e) and E the matrix of
// x ↦ e × x. Per edge that is not symmetric; the sum over the closed loop is. E is
// antisymmetric, so it drops out of the symmetric part, and each edge adds only
// ½(c vᵀ + v cᵀ): six entries instead of nine, and the round-off asymmetry is gone too.
namespace detail {

// The symmetric part of c ⊗ v, added to h.
template <class T>
GWNRT_HD GWNRT_FORCEINLINE void add_symmetric_product(const glm::vec<3, T>& c, const glm::vec<3, T>& v, Sym3<T>& h) {
  h.xx += c.x * v.x;
  h.yy += c.y * v.y;
  h.zz += c.z * v.z;
  h.xy += T(0.5) * (c.x * v.y + v.x * c.y);
  h.xz += T(0.5) * (c.x * v.z + v.x * c.z);
  h.yz += T(0.5) * (c.y * v.z + v.y * c.z);
}

// One edge's term of ∇Ω and its share of the Hessian, added.
template <class T>
GWNRT_HD GWNRT_FORCEINLINE void add_edge_derivatives(const EdgeField<T>& edge, glm::vec<3, T>& gradient,
                                                     Sym3<T>& hessian) {
  if (edge.degenerate) return;
  const T inv_c2 = T(1) / edge.c2;
  const T s = edge.f * inv_c2;
  gradient += edge.c * s;
  // ∂ĝ/∂x = -(I - ĝĝᵀ)/|g|, so ∇f = (I - ĝ_iĝ_iᵀ)e/|g_i| - (I - ĝ_jĝ_jᵀ)e/|g_j|;
  // c(x) = const + e × x, so ∇(|c|²)/2 = c × e.
  const glm::vec<3, T> grad_f = (edge.e - edge.gi_hat * glm::dot(edge.gi_hat, edge.e)) * edge.inv_li -
                                (edge.e - edge.gj_hat * glm::dot(edge.gj_hat, edge.e)) * edge.inv_lj;
  add_symmetric_product(edge.c, (grad_f - glm::cross(edge.c, edge.e) * (T(2) * s)) * inv_c2, hessian);
}

// The same for the half-line from g (relative to x) to infinity along the unit u: the edge term's
// limit, (g × u) / (|g| (|g| + g·u)) (a ribbon's side, ribbon_winding.h). Its c = g × u moves
// with x as u × x, antisymmetric, so again only c ⊗ ∇s counts.
template <class T>
GWNRT_HD GWNRT_FORCEINLINE void add_half_line_derivatives(const glm::vec<3, T>& g, const glm::vec<3, T>& u,
                                                          glm::vec<3, T>& gradient, Sym3<T>& hessian) {
  const T l = glm::length(g), along = glm::dot(g, u), d = l * (l + along);
  if (!(d > T(0))) return;  // x on the half-line
  const T s = T(1) / d;
  const glm::vec<3, T> c = glm::cross(g, u);
  gradient += c * s;
  add_symmetric_product(c, (g * (T(2) + along / l) + u * l) * (s * s), hessian);
}

}  // namespace detail

template <class T>
GWNRT_HD inline void triangle_solid_angle_derivatives(const glm::vec<3, T>& p0, const glm::vec<3, T>& p1,
                                                      const glm::vec<3, T>& p2, const glm::vec<3, T>& x,
                                                      glm::vec<3, T>& gradient, Sym3<T>& hessian) {
  const glm::vec<3, T> g[3] = {p0 - x, p1 - x, p2 - x};
  const detail::EdgeField<T> edges[3] = {{g[0], g[1]}, {g[1], g[2]}, {g[2], g[0]}};
  gradient = glm::vec<3, T>(0);
  hessian = Sym3<T>{};
  for (const detail::EdgeField<T>& edge : edges) detail::add_edge_derivatives(edge, gradient, hessian);
  if constexpr (sizeof(T) == sizeof(float)) {
    if (edges[0].float_underflows() || edges[1].float_underflows() || edges[2].float_underflows() ||
        !detail::finite(gradient) || !detail::finite(hessian)) {
      dvec3 gd;
      Sym3<double> hd;
      triangle_solid_angle_derivatives(dvec3(p0), dvec3(p1), dvec3(p2), dvec3(x), gd, hd);
      gradient = detail::saturated_float(gd);
      hessian = detail::saturated_float(hd);
    }
  }
}

}  // namespace gwnrt
