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

// Adds the far-field contribution of one cluster at offset d = p̄ - x.
template <int Order, bool WantGradient, bool WantHessian>
GWNRT_HD GWNRT_FORCEINLINE void add_far_field(const float* n, const float* s, const float* p, const float* e,
                                              const vec3& d, FieldAccumulator<float>& acc) {
  const float r2 = glm::dot(d, d);
  const float inv_r2 = 1.0f / r2;
  const float inv_r = sqrtf(inv_r2);
  const float inv_r3 = inv_r * inv_r2;
  const float inv_r5 = inv_r3 * inv_r2;
  const float inv_r7 = inv_r5 * inv_r2;
  const float inv_r9 = inv_r7 * inv_r2;

  const vec3 N(n[0], n[1], n[2]);
  const float n_dot_d = glm::dot(N, d);
  float omega = n_dot_d * inv_r3;

  // Order-1 quantities.
  vec3 sd(0.0f);
  float half_trace_s = 0.0f, dsd = 0.0f;
  if constexpr (Order >= 1) {
    sd = vec3(s[0] * d.x + s[1] * d.y + s[2] * d.z, s[1] * d.x + s[3] * d.y + s[4] * d.z,
              s[2] * d.x + s[4] * d.y + s[5] * d.z);
    half_trace_s = 0.5f * (s[0] + s[3] + s[5]);
    dsd = glm::dot(d, sd);
    omega += half_trace_s * inv_r3 - 1.5f * dsd * inv_r5;
  }
  // Order-2 quantities: Q = P(d,·,·), so P(d,d,·) = Q d and P(d,d,d) = d·Q d.
  Sym3<float> q;
  vec3 qd(0.0f), E(0.0f);
  float c3 = 0.0f, e_dot_d = 0.0f;
  if constexpr (Order >= 2) {
    q.xx = p[0] * d.x + p[1] * d.y + p[2] * d.z;
    q.xy = p[1] * d.x + p[3] * d.y + p[4] * d.z;
    q.xz = p[2] * d.x + p[4] * d.y + p[5] * d.z;
    q.yy = p[3] * d.x + p[6] * d.y + p[7] * d.z;
    q.yz = p[4] * d.x + p[7] * d.y + p[8] * d.z;
    q.zz = p[5] * d.x + p[8] * d.y + p[9] * d.z;
    qd = vec3(q.xx * d.x + q.xy * d.y + q.xz * d.z, q.xy * d.x + q.yy * d.y + q.yz * d.z,
              q.xz * d.x + q.yz * d.y + q.zz * d.z);
    c3 = glm::dot(d, qd);
    E = vec3(e[0], e[1], e[2]);
    e_dot_d = glm::dot(E, d);
    omega += 7.5f * c3 * inv_r7 - 1.5f * e_dot_d * inv_r5;
  }
  acc.omega += omega;

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
