// Exact w by crossings of M alone: the spanning surface of ∂M taken as each segment's ribbon,
// swept from the segment to infinity opposite the axis ray that counts M's jumps. The ray runs
// parallel to every ribbon and crosses none, so no cone and no cone crossings are needed, and
// no inner triangles pass by points near the rim (docs/performance.md, the scan's near cone work).
// This is the scalar O(|∂M|) form, in double, that a clustered form must reproduce.
#pragma once

#include "gwnrt/base/hd.h"
#include "gwnrt/field/crossing_winding.h"
#include "gwnrt/field/solid_angle.h"
#include "gwnrt/geometry/model_view.h"
#include "gwnrt/geometry/ray.h"

namespace gwnrt {

// The ribbon of a segment a -> b (relative to x), swept to infinity along the unit direction c,
// subtends from x the spherical triangle (a, b, c): van Oosterom and Strackee with |c| = 1. Its
// boundary holds a -> b as a cone triangle (z, a, b) holds it, so the ribbons of ∂M's segments
// span ∂M as the cone does.
GWNRT_HD inline SolidAngleTangent<double> ribbon_tangent(const dvec3& a, const dvec3& b, const dvec3& c) {
  return solid_angle_tangent(a, b, c, glm::length(a), glm::length(b), 1.0, glm::cross(b, c), glm::dot(b, c));
}

// The direction ribbons are swept in for rays along `axis` with `sign`: opposite the ray, so that
// it crosses none.
GWNRT_HD inline dvec3 ribbon_direction(int axis, float sign) {
  dvec3 c(0.0);
  c[axis] = -double(sign);
  return c;
}

// The ribbon's Ω, ∇Ω and H Ω at x: its boundary a -> b, b -> ∞ and ∞ -> a (solid_angle.h's edge
// terms and their half-line limits).
GWNRT_HD inline void ribbon_derivatives(const dvec3& a, const dvec3& b, const dvec3& c, double& omega, dvec3& gradient,
                                        Sym3<double>& hessian) {
  const SolidAngleTangent<double> t = ribbon_tangent(a, b, c);
  omega = 2.0 * atan2(t.numerator, t.denominator);
  gradient = dvec3(0.0);
  hessian = Sym3<double>{};
  detail::add_edge_derivatives(detail::EdgeField<double>(a, b), gradient, hessian);
  detail::add_half_line_derivatives(b, c, gradient, hessian);
  dvec3 into_a(0.0);
  Sym3<double> into_a_hessian;
  detail::add_half_line_derivatives(a, c, into_a, into_a_hessian);
  gradient -= into_a;
  hessian += into_a_hessian * -1.0;
}

// w at x: the ribbons' solid angles over 4π (swept along −d) less M's jumps ahead of x along the
// axis ray d that leaves M's box soonest. Exact up to round-off where x is off M. Where x lies on
// a ribbon (the ray runs into ∂M: a query point in the plane of a planar hole, the ray in that
// plane), the term is ±2π by round-off and M's faces lie along the ray: x is moved as the cone's
// crossing method moves it (ConeNudge), w being continuous there.
GWNRT_HD inline double winding_number_by_ribbons(const ModelView& m, const vec3& x_in) {
  vec3 x = x_in;
  ConeNudge nudge(m.bounds, x_in);
  for (;;) {
    const RayFrame frame = shortest_exit_axis_ray(m.bounds, x);
    const dvec3 behind = ribbon_direction(frame.kz, frame.sz);  // sz = 1 / d[kz] = ±1
    const dvec3 xd(x);
    double omega = 0;
    bool on_ribbon = false;
    for (uint32_t s = 0; s < m.boundary.segment_count; ++s) {
      const dvec3 a = dvec3(m.boundary.endpoints[2 * s]) - xd, b = dvec3(m.boundary.endpoints[2 * s + 1]) - xd;
      const SolidAngleTangent<double> t = ribbon_tangent(a, b, behind);
      on_ribbon = on_ribbon || (t.numerator == 0.0 && t.denominator <= 0.0);
      omega += 2.0 * atan2(t.numerator, t.denominator);
    }
    if (on_ribbon && nudge.left()) {
      x = nudge.next();
      continue;
    }
    int mesh_jumps = 0;
    visit_axis_crossings(m.triangles.bvh, m.triangles.vertices, frame, 0.0f,
                         [&](uint32_t, float, int jump) { mesh_jumps += jump; });
    return omega * (0.25 / kPi) - double(mesh_jumps);
  }
}

#if GWNRT_HOST_LANES && defined(__AVX__)
// A far fan is summed once for the whole batch, by the second-order Taylor expansion of its
// multipole about the batch's box centre c, where it lies beyond beta times its radius plus this
// many box half-diagonals from c: the expansion's remainder is then of the order of the
// multipole's own truncation (both a cube of the distance ratio). So are the ribbons of its loose
// ends that pass far enough from the box.
inline constexpr float kLocalExpansionReach = 2.0f;

// w at many points at once from the ribbons (the meshing passes' points): one traversal of the
// ribbon tree for all of them, M's jumps left to the caller. A lane is expanded only where it is
// beyond beta radii of the points' box and the beam of the points' rays (their box swept along
// +d) misses it: then no ray meets its fan, and its ribbons sum to the fan (its multipole) plus
// k_v · ribbon(z → v) at each loose end v (R(a→b) = T(z,a,b) + R(z→b) − R(z→a), the prism they
// bound holding no point). Every other lane is opened; segments are ribbon terms. ∇w is the
// Biot–Savart sum over ∂M's segments, taken the same way (the fan's expansion and its spokes
// z → v at the loose ends), with no ray. Eight points at a time in float, a term where float is
// ill-conditioned in double (kNearConditioning, as the near triangles); a point on a ribbon is
// unsure.
template <int Capacity, bool WantGradient = false>
struct RibbonWindingBatch : WindingBatchPoints<Capacity, WantGradient> {
  using Points = WindingBatchPoints<Capacity, WantGradient>;
  using Points::count, Points::x, Points::y, Points::z, Points::omega, Points::unsure, Points::gradient,
      Points::winding, Points::add_edge_field;

  // w at point i given M's jumps ahead of it along the ray of evaluate(), or NaN where unsure.
  GWNRT_FORCEINLINE float crossing_winding(int i, int mesh_jumps) const { return winding(i) - float(mesh_jumps); }

  // The ribbons swept opposite the ray along `axis` with `sign` (w; and ∇w when WantGradient), or
  // axis -1 for ∇w alone.
  void evaluate(const RibbonTreeView& ribbons, float beta, int axis, float sign) {
    if (count == 0) return;
    vec3 lo, hi;
    const int chunks = this->prepare(lo, hi);
    const BvhView& bvh = ribbons.fans.bvh;
    if (bvh.node_count == 0 || ribbons.segment_count == 0) return;
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    // Fans far from the whole box go into one local expansion about its centre (below).
    const vec3 box_centre = 0.5f * (lo + hi);
    const float box_reach = kLocalExpansionReach * 0.5f * glm::length(hi - lo);
    FieldAccumulator<float> local;
    bool any_local = false;
    const float beta2 = beta * beta;
    Points::visit_lanes(
        bvh, ribbons.fans.expansion, beta, lo, hi,
        [&](uint32_t ni, const WideNode& node, int lane, bool far, const vec3& centre) {
          const WideNodeFan& fan = ribbons.fan_ends[ni];
          far = far && fan.end_count[lane] != kOpenFan;
          if (far && axis >= 0) {  // and the beam misses the lane's box
            const bool ahead = sign > 0.0f ? node.hi[axis][lane] >= lo[axis] : node.lo[axis][lane] <= hi[axis];
            far = !(ahead && node.lo[u][lane] <= hi[u] && node.hi[u][lane] >= lo[u] && node.lo[v][lane] <= hi[v] &&
                    node.hi[v][lane] >= lo[v]);
          }
          if (!far) {
            for (uint32_t s = node.child[lane]; s < node.child[lane] + node.count[lane]; ++s)  // none when inner
              segment(ribbons.endpoints[2 * s], ribbons.endpoints[2 * s + 1], 1.0f, axis, sign, chunks);
            return true;
          }
          const vec3 d = centre - box_centre;
          const float reach = ribbons.fans.expansion[ni].radius[lane] + box_reach;
          const bool to_local = chunks > 1 && glm::dot(d, d) > beta2 * reach * reach;
          if (to_local) {
            add_cluster_far_field<2, true, true>(ribbons.fans, ni, lane, d, local);
            any_local = true;
          } else {
            this->far(ribbons.fans, ni, lane, centre, chunks);
          }
          const vec3 apex(fan.apex[0][lane], fan.apex[1][lane], fan.apex[2][lane]);
          for (uint32_t e = fan.first_end[lane]; e < fan.first_end[lane] + fan.end_count[lane]; ++e) {
            const LooseEnd& end = ribbons.loose_ends[e];
            // A loose end's ribbon too where it is twice as far from the box as a fan must be from
            // c (at the same distance the exact corners' error doubled on the scan). With ∇w asked,
            // the batch drops the ribbons' sides (they cancel over ∂M), which a ribbon's own
            // expansion cannot.
            if (!WantGradient && to_local &&
                ribbon_gap2(apex, end.position, lo, hi, axis, sign) > 4.0f * beta2 * box_reach * box_reach)
              add_local_ribbon(apex, end.position, end.multiplicity, box_centre, axis, sign, local);
            else
              segment(apex, end.position, end.multiplicity, axis, sign, chunks);
          }
          return false;
        });
    if (any_local) add_local(local, box_centre, chunks);
  }

  // The squared gap between the points' box [lo, hi] and the box of segment p -> q swept
  // opposite the ray (axis, sign) to infinity, which holds its ribbon.
  static GWNRT_FORCEINLINE float ribbon_gap2(const vec3& p, const vec3& q, const vec3& lo, const vec3& hi, int axis,
                                             float sign) {
    vec3 ribbon_lo = glm::min(p, q), ribbon_hi = glm::max(p, q);
    if (sign > 0.0f)
      ribbon_lo[axis] = -kInfinity;
    else
      ribbon_hi[axis] = kInfinity;
    const vec3 gap = glm::max(glm::max(ribbon_lo - hi, lo - ribbon_hi), vec3(0.0f));
    return glm::dot(gap, gap);
  }

  // `multiplicity` times segment p -> q's ribbon, by its derivatives at c into the local expansion.
  static void add_local_ribbon(const vec3& p, const vec3& q, float multiplicity, const vec3& c, int axis, float sign,
                               FieldAccumulator<float>& local) {
    double omega;
    dvec3 g;
    Sym3<double> h;
    ribbon_derivatives(dvec3(p) - dvec3(c), dvec3(q) - dvec3(c), ribbon_direction(axis, sign), omega, g, h);
    local.omega += float(omega * multiplicity);
    local.gradient += detail::saturated_float(g * double(multiplicity));
    local.hessian += detail::saturated_float(h * double(multiplicity));
  }

  // The local expansion (Ω, ∇Ω and H Ω at c) at every point: second order in x − c.
  GWNRT_FORCEINLINE void add_local(const FieldAccumulator<float>& l, const vec3& c, int chunks) {
    const Sym3<float>& h = l.hessian;
    for (int k = 0; k < chunks; ++k) {
      const f8 dx = x[k] - c.x, dy = y[k] - c.y, dz = z[k] - c.z;
      const f8 hx = h.xx * dx + h.xy * dy + h.xz * dz, hy = h.xy * dx + h.yy * dy + h.yz * dz,
               hz = h.xz * dx + h.yz * dy + h.zz * dz;
      omega[k] +=
          l.omega + (l.gradient.x + 0.5f * hx) * dx + (l.gradient.y + 0.5f * hy) * dy + (l.gradient.z + 0.5f * hz) * dz;
      if constexpr (WantGradient) {
        gradient[0][k] += l.gradient.x + hx;
        gradient[1][k] += l.gradient.y + hy;
        gradient[2][k] += l.gradient.z + hz;
      }
    }
  }

  // `multiplicity` times segment p -> q's ribbon (axis >= 0) and its Biot–Savart term (WantGradient).
  GWNRT_FORCEINLINE void segment(const vec3& p, const vec3& q, float multiplicity, int axis, float sign, int chunks) {
    for (int c = 0; c < chunks; ++c) {
      const f8 a[3] = {p.x - x[c], p.y - y[c], p.z - z[c]}, b[3] = {q.x - x[c], q.y - y[c], q.z - z[c]};
      const f8 la = lane_sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
      const f8 lb = lane_sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
      if (axis >= 0) {
        // Van Oosterom–Strackee for (a, b, c), c = −sign · e_axis: a·(b × c) = c·(a × b).
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        const float c_axis = -sign;
        const f8 numerator = c_axis * (a[u] * b[v] - a[v] * b[u]);
        const f8 ab = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        const f8 denominator = solid_angle_denominator(la, lb, f8{} + 1.0f, ab, c_axis * b[axis], c_axis * a[axis]);
        f8 angle = lane_atan2(numerator, denominator);
        // Where float is ill-conditioned (the ray passes near the segment or an endpoint), the
        // term in double; x on the ribbon itself is unsure (Ω jumps by 4π there).
        const uint32_t ill = lane_bits(point_on_triangle(numerator, denominator, la * lb, kNearConditioning));
        for (uint32_t rest = ill; rest != 0; rest &= rest - 1) {
          const int l = lowest_set_bit(rest);
          const dvec3 xd(x[c][l], y[c][l], z[c][l]), pd = dvec3(p) - xd, qd = dvec3(q) - xd;
          const SolidAngleTangent<double> exact = ribbon_tangent(pd, qd, ribbon_direction(axis, sign));
          unsure[c][l] |= point_on_triangle(exact.numerator, exact.denominator, glm::length(pd) * glm::length(qd),
                                            kOnTriangleRoundOff)
                              ? -1
                              : 0;
          angle[l] = float(atan2(exact.numerator, exact.denominator));
        }
        omega[c] += (2.0f * multiplicity) * angle;
      }
      if constexpr (WantGradient) {
        f8 edge[3] = {};
        const uint32_t ill = lane_bits(add_edge_field(a, b, la, lb, edge));
        for (int k = 0; k < 3; ++k) gradient[k][c] += multiplicity * edge[k];
        for (uint32_t rest = ill; rest != 0; rest &= rest - 1) {  // near the segment's line: in double
          const int l = lowest_set_bit(rest);
          const dvec3 xd(x[c][l], y[c][l], z[c][l]);
          const vec3 exact = detail::saturated_float(
              detail::EdgeField<double>(dvec3(p) - xd, dvec3(q) - xd).gradient() * double(multiplicity));
          for (int k = 0; k < 3; ++k) gradient[k][c][l] += exact[k];
        }
      }
    }
  }
};
#endif

}  // namespace gwnrt
