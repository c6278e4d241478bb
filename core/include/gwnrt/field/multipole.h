// Far field of a cluster of triangles: the Taylor expansion of its solid angle about the
// cluster's centre p̄ (Barill et al. 2018), with its gradient and Hessian from the same
// moments. Host-and-device.
//
// With d = p̄ - x, r = |d|, K = 1/r and the raw moments N_α = Σ∫n_α, N_αj = Σ∫n_α s_j,
// N_αjk = Σ∫n_α s_j s_k (s = y - p̄), the expansion is
//     Ω(x) ≈ -(N_α ∂_α K + N_αj ∂_α∂_j K + ½ N_αjk ∂_α∂_j∂_k K)(d).
// Contracting the derivatives of K leaves only
//   order 0:  N                          Ω₀ = (N·d) / r³
//   order 1:  S = N₁ + N₁ᵀ (symmetric)   Ω₁ = ½ tr S / r³ - (3/2) dᵀS d / r⁵
//   order 2:  P = N₂ fully symmetrised,  Ω₂ = (15/2) P(d,d,d) / r⁷ - (3/2) (e·d) / r⁵
//             e_α = 2 Σ_β N_ββα + Σ_j N_αjj
// so that is what the tree stores. ∇ₓΩ = -∇_d Ω and Hₓ Ω = H_d Ω (d = p̄ - x).
#pragma once

#include "gwnrt/field/lanes.h"
#include "gwnrt/hd.h"

namespace gwnrt {

// Compressed moments of one cluster, as stored per BVH lane.
struct Moments {
  float n[3];   // order 0: area-weighted normal N
  float s[6];   // order 1: S = N₁ + N₁ᵀ as (xx, xy, xz, yy, yz, zz)
  float p[10];  // order 2: symmetric P as (xxx, xxy, xxz, xyy, xyz, xzz, yyy, yyz, yzz, zzz)
  float e[3];   // order 2: trace vector e
};

// Derivative request of one evaluation; the template flags let the compiler drop unused work.
template <class T>
struct FieldAccumulator {
  T omega = 0;
  glm::vec<3, T> gradient{0};
  Sym3<T> hessian;
};

// dᵀS d for S stored as (xx, xy, xz, yy, yz, zz), and P(d,d,d) for P stored as in Moments, as
// polynomials grouped by the square of a coordinate: fewer operations and a shorter dependency
// chain than contracting through S d and P(d,·,·) d, which only the derivatives need.
template <class T>
GWNRT_HD GWNRT_FORCEINLINE T quadratic_form(const T* s, T dx, T dy, T dz) {
  const T y2 = dy + dy, z2 = dz + dz;
  return dx * (s[0] * dx + s[1] * y2 + s[2] * z2) + dy * (s[3] * dy + s[4] * z2) + s[5] * (dz * dz);
}
template <class T>
GWNRT_HD GWNRT_FORCEINLINE T cubic_form(const T* p, T dx, T dy, T dz) {
  const T x3 = 3.0f * dx, y3 = 3.0f * dy, z3 = 3.0f * dz;
  return dx * dx * (p[0] * dx + p[1] * y3 + p[2] * z3) + dy * dy * (p[3] * x3 + p[6] * dy + p[7] * z3) +
         dz * dz * (p[5] * x3 + p[8] * y3 + p[9] * dz) + p[4] * (6.0f * dx * dy * dz);
}

// One cluster's Ω at d = p̄ - x and the scalars it is made of, which ∇Ω and H Ω share. T is
// float (one lane) or a lane vector (lanes.h: a node's lanes at once); the moments are indexed
// as in Moments.
template <int Order, class T>
struct FarFieldOmega {
  T inv_r2, inv_r3, inv_r5, inv_r7;  // all of them: the derivatives need higher powers than Ω
  T n_dot_d, half_trace_s{}, dsd{};  // order 1: ½ tr S, dᵀS d
  T c3{}, e_dot_d{};                 // order 2: P(d,d,d), e·d
  T omega;

  GWNRT_HD GWNRT_FORCEINLINE FarFieldOmega(const T* n, const T* s, const T* p, const T* e, T dx, T dy, T dz) {
    inv_r2 = 1.0f / (dx * dx + dy * dy + dz * dz);
    inv_r3 = lane_sqrt(inv_r2) * inv_r2;
    inv_r5 = inv_r3 * inv_r2;
    inv_r7 = inv_r5 * inv_r2;
    n_dot_d = n[0] * dx + n[1] * dy + n[2] * dz;
    omega = n_dot_d * inv_r3;
    if constexpr (Order >= 1) {
      half_trace_s = 0.5f * (s[0] + s[3] + s[5]);
      dsd = quadratic_form(s, dx, dy, dz);
      omega += half_trace_s * inv_r3 - 1.5f * dsd * inv_r5;
    }
    if constexpr (Order >= 2) {
      c3 = cubic_form(p, dx, dy, dz);
      e_dot_d = e[0] * dx + e[1] * dy + e[2] * dz;
      omega += 7.5f * c3 * inv_r7 - 1.5f * e_dot_d * inv_r5;
    }
  }
};

// And the vectors the derivatives add: S d and, for order 2, Q = P(d,·,·) and Q d.
template <int Order, class T>
struct FarFieldTerms : FarFieldOmega<Order, T> {
  T inv_r9;
  T sd[3] = {};
  T q[6] = {}, qd[3] = {};

  GWNRT_HD GWNRT_FORCEINLINE FarFieldTerms(const T* n, const T* s, const T* p, const T* e, T dx, T dy, T dz)
      : FarFieldOmega<Order, T>(n, s, p, e, dx, dy, dz) {
    inv_r9 = this->inv_r7 * this->inv_r2;
    if constexpr (Order >= 1) {
      sd[0] = s[0] * dx + s[1] * dy + s[2] * dz;
      sd[1] = s[1] * dx + s[3] * dy + s[4] * dz;
      sd[2] = s[2] * dx + s[4] * dy + s[5] * dz;
    }
    if constexpr (Order >= 2) {
      q[0] = p[0] * dx + p[1] * dy + p[2] * dz;  // xx
      q[1] = p[1] * dx + p[3] * dy + p[4] * dz;  // xy
      q[2] = p[2] * dx + p[4] * dy + p[5] * dz;  // xz
      q[3] = p[3] * dx + p[6] * dy + p[7] * dz;  // yy
      q[4] = p[4] * dx + p[7] * dy + p[8] * dz;  // yz
      q[5] = p[5] * dx + p[8] * dy + p[9] * dz;  // zz
      qd[0] = q[0] * dx + q[1] * dy + q[2] * dz;
      qd[1] = q[1] * dx + q[3] * dy + q[4] * dz;
      qd[2] = q[2] * dx + q[4] * dy + q[5] * dz;
    }
  }
};

// Adds the far-field contribution of one cluster at offset d = p̄ - x.
template <int Order, bool WantGradient, bool WantHessian>
GWNRT_HD GWNRT_FORCEINLINE void add_far_field(const float* n, const float* s, const float* p, const float* e,
                                              const vec3& d, FieldAccumulator<float>& acc) {
  const FarFieldTerms<Order, float> t(n, s, p, e, d.x, d.y, d.z);
  acc.omega += t.omega;
  const float inv_r2 = t.inv_r2, inv_r3 = t.inv_r3, inv_r5 = t.inv_r5, inv_r7 = t.inv_r7, inv_r9 = t.inv_r9;
  const float n_dot_d = t.n_dot_d, half_trace_s = t.half_trace_s, dsd = t.dsd, c3 = t.c3, e_dot_d = t.e_dot_d;
  const vec3 N(n[0], n[1], n[2]), sd(t.sd[0], t.sd[1], t.sd[2]), qd(t.qd[0], t.qd[1], t.qd[2]);
  vec3 E(0.0f);
  if constexpr (Order >= 2) E = vec3(e[0], e[1], e[2]);
  const Sym3<float> q{t.q[0], t.q[1], t.q[2], t.q[3], t.q[4], t.q[5]};
  (void)inv_r2;
  (void)inv_r9;

  if constexpr (WantGradient || WantHessian) {
    // ∇_d Ω written as (along_d)·d + rest.
    float along_d = -3.0f * n_dot_d * inv_r5;
    vec3 rest = N * inv_r3;
    if constexpr (Order >= 1) {
      along_d += -3.0f * half_trace_s * inv_r5 + 7.5f * dsd * inv_r7;
      rest -= sd * (3.0f * inv_r5);
    }
    if constexpr (Order >= 2) {
      along_d += -52.5f * c3 * inv_r9 + 7.5f * e_dot_d * inv_r7;
      rest += qd * (22.5f * inv_r7) - E * (1.5f * inv_r5);
    }
    if constexpr (WantGradient) acc.gradient -= d * along_d + rest;  // ∇ₓ = -∇_d

    if constexpr (WantHessian) {
      // H_d Ω = a I + b d dᵀ + (u dᵀ + d uᵀ) + M.
      float a = -3.0f * n_dot_d * inv_r5;
      float b = 15.0f * n_dot_d * inv_r7;
      vec3 u = N * (-3.0f * inv_r5);
      Sym3<float> m;
      if constexpr (Order >= 1) {
        a += -3.0f * half_trace_s * inv_r5 + 7.5f * dsd * inv_r7;
        b += 15.0f * half_trace_s * inv_r7 - 52.5f * dsd * inv_r9;
        u += sd * (15.0f * inv_r7);
        m += Sym3<float>{s[0], s[1], s[2], s[3], s[4], s[5]} * (-3.0f * inv_r5);
      }
      if constexpr (Order >= 2) {
        a += -52.5f * c3 * inv_r9 + 7.5f * e_dot_d * inv_r7;
        b += 472.5f * c3 * inv_r9 * inv_r2 - 52.5f * e_dot_d * inv_r9;
        u += qd * (-157.5f * inv_r9) + E * (7.5f * inv_r7);
        m += q * (45.0f * inv_r7);
      }
      Sym3<float>& h = acc.hessian;
      h.xx += a + b * d.x * d.x + 2.0f * u.x * d.x + m.xx;
      h.yy += a + b * d.y * d.y + 2.0f * u.y * d.y + m.yy;
      h.zz += a + b * d.z * d.z + 2.0f * u.z * d.z + m.zz;
      h.xy += b * d.x * d.y + u.x * d.y + d.x * u.y + m.xy;
      h.xz += b * d.x * d.z + u.x * d.z + d.x * u.z + m.xz;
      h.yz += b * d.y * d.z + u.y * d.z + d.y * u.z + m.yz;
    }
  }
}

}  // namespace gwnrt
