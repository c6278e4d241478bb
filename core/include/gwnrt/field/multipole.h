// Far field of a cluster of triangles: the Taylor expansion of its solid angle about the
// cluster's centre p̄ (Barill et al. 2018), with its gradient and Hessian from the same
// moments. Host-and-device.
//
// With d = p̄ - x, r = |d|, K = 1/r and the raw moments N_α = Σ∫n_α, N_αj = Σ∫n_α s_j,
// N_αjk = Σ∫n_α s_j s_k (s = y - p̄), the expansion is
//     Ω(x) ≈ -(N_α ∂_α K + N_αj ∂_α∂_j K + ½ N_αjk ∂_α∂_j∂_k K)(d).
// Contracting the derivatives of K leaves only
//   order 0:  N                          Ω₀ = (N·d) / r³               = ρ² N·u
//   order 1:  S = N₁ + N₁ᵀ (symmetric)   Ω₁ = ½ tr S / r³ - (3/2) dᵀS d / r⁵
//                                            = ρ³ (½ tr S - (3/2) uᵀS u)
//   order 2:  P = N₂ fully symmetrised,  Ω₂ = (15/2) P(d,d,d) / r⁷ - (3/2) (e·d) / r⁵
//                                            = ρ⁴ ((15/2) P(u,u,u) - (3/2) e·u)
// (u = d/r, ρ = 1/r: the form computed, FarFieldOmega)
//             e_α = 2 Σ_β N_ββα + Σ_j N_αjj
// so that is what the tree stores. ∇ₓΩ = -∇_d Ω and Hₓ Ω = H_d Ω (d = p̄ - x).
#pragma once

#include "gwnrt/base/hd.h"
#include "gwnrt/base/lanes.h"

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
// Written in the unit direction u = d/r and ρ = 1/r, each order's term a form of u times a power
// of ρ, nested (Ω = ρ²·(order 0 + ρ·(order 1 + ρ·order 2))): each moment of order m scales as a
// length^(2+m), so each product stays near the size of its term whatever the mesh's scale (the
// forms in d and 1/r^k overflow: P(d,d,d) = inf against 1/r⁷ = 0 for a mesh 1e6 across). A point
// so far that r² overflows gets ρ = 0: no term.
template <int Order, class T>
struct FarFieldOmega {
  T inv_r, inv_r2;                   // ρ, ρ²
  T ux, uy, uz;                      // u = d/r
  T n_dot_u, half_trace_s{}, usu{};  // order 1: ½ tr S, uᵀS u
  T c3{}, e_dot_u{};                 // order 2: P(u,u,u), e·u
  T omega;

  GWNRT_HD GWNRT_FORCEINLINE FarFieldOmega(const T* n, const T* s, const T* p, const T* e, T dx, T dy, T dz) {
    inv_r2 = 1.0f / (dx * dx + dy * dy + dz * dz);
    inv_r = lane_sqrt(inv_r2);
    ux = dx * inv_r;
    uy = dy * inv_r;
    uz = dz * inv_r;
    n_dot_u = n[0] * ux + n[1] * uy + n[2] * uz;
    T inner{};
    if constexpr (Order >= 2) {
      c3 = cubic_form(p, ux, uy, uz);
      e_dot_u = e[0] * ux + e[1] * uy + e[2] * uz;
      inner = (7.5f * c3 - 1.5f * e_dot_u) * inv_r;
    }
    if constexpr (Order >= 1) {
      half_trace_s = 0.5f * (s[0] + s[3] + s[5]);
      usu = quadratic_form(s, ux, uy, uz);
      inner = (half_trace_s - 1.5f * usu + inner) * inv_r;
    }
    omega = (n_dot_u + inner) * inv_r2;
  }
};

// And the vectors the derivatives add: S u and, for order 2, Q = P(u,·,·) and Q u.
template <int Order, class T>
struct FarFieldTerms : FarFieldOmega<Order, T> {
  T su[3] = {};
  T q[6] = {}, qu[3] = {};

  GWNRT_HD GWNRT_FORCEINLINE FarFieldTerms(const T* n, const T* s, const T* p, const T* e, T dx, T dy, T dz)
      : FarFieldOmega<Order, T>(n, s, p, e, dx, dy, dz) {
    const T ux = this->ux, uy = this->uy, uz = this->uz;
    if constexpr (Order >= 1) {
      su[0] = s[0] * ux + s[1] * uy + s[2] * uz;
      su[1] = s[1] * ux + s[3] * uy + s[4] * uz;
      su[2] = s[2] * ux + s[4] * uy + s[5] * uz;
    }
    if constexpr (Order >= 2) {
      q[0] = p[0] * ux + p[1] * uy + p[2] * uz;  // xx
      q[1] = p[1] * ux + p[3] * uy + p[4] * uz;  // xy
      q[2] = p[2] * ux + p[4] * uy + p[5] * uz;  // xz
      q[3] = p[3] * ux + p[6] * uy + p[7] * uz;  // yy
      q[4] = p[4] * ux + p[7] * uy + p[8] * uz;  // yz
      q[5] = p[5] * ux + p[8] * uy + p[9] * uz;  // zz
      qu[0] = q[0] * ux + q[1] * uy + q[2] * uz;
      qu[1] = q[1] * ux + q[3] * uy + q[4] * uz;
      qu[2] = q[2] * ux + q[4] * uy + q[5] * uz;
    }
  }
};

// ∇_d Ω of one cluster from its terms (∇ₓ Ω is its negative): ρ³ times (along_u · u + rest),
// each an order-nested sum in ρ as FarFieldOmega's. T is float or a lane vector (the host's far
// lanes, winding_number.h); n and e are the cluster's moments as in Moments.
template <int Order, class T>
GWNRT_HD GWNRT_FORCEINLINE void far_field_gradient(const FarFieldTerms<Order, T>& t, const T* n, const T* e, T g[3]) {
  const T rho = t.inv_r;
  const T u[3] = {t.ux, t.uy, t.uz};
  T along_u{};
  T rest[3] = {};
  if constexpr (Order >= 2) {
    along_u = (-52.5f * t.c3 + 7.5f * t.e_dot_u) * rho;
    for (int k = 0; k < 3; ++k) rest[k] = (t.qu[k] * 22.5f - e[k] * 1.5f) * rho;
  }
  if constexpr (Order >= 1) {
    along_u = (-3.0f * t.half_trace_s + 7.5f * t.usu + along_u) * rho;
    for (int k = 0; k < 3; ++k) rest[k] = (rest[k] - t.su[k] * 3.0f) * rho;
  }
  along_u += -3.0f * t.n_dot_u;
  const T rho3 = rho * t.inv_r2;
  for (int k = 0; k < 3; ++k) g[k] = (u[k] * along_u + (rest[k] + n[k])) * rho3;
}

// Adds the far-field contribution of one cluster at offset d = p̄ - x. The derivatives of the
// forms in d (Ω₀ = N·d/r³, ...), rewritten in u and ρ as FarFieldOmega is: ∇_d Ω and H_d Ω are
// ρ³ and ρ⁴ times (order 0 + ρ·(order 1 + ρ·order 2)).
template <int Order, bool WantGradient, bool WantHessian>
GWNRT_HD GWNRT_FORCEINLINE void add_far_field(const float* n, const float* s, const float* p, const float* e,
                                              const vec3& d, FieldAccumulator<float>& acc) {
  const FarFieldTerms<Order, float> t(n, s, p, e, d.x, d.y, d.z);
  acc.omega += t.omega;
  if constexpr (WantGradient) {
    float g[3];
    far_field_gradient(t, n, e, g);
    acc.gradient -= vec3(g[0], g[1], g[2]);  // ∇ₓ = -∇_d
  }
  if constexpr (WantHessian) {
    const float rho = t.inv_r, n_dot_u = t.n_dot_u, half_trace_s = t.half_trace_s, usu = t.usu, c3 = t.c3,
                e_dot_u = t.e_dot_u;
    const vec3 u(t.ux, t.uy, t.uz), N(n[0], n[1], n[2]), su(t.su[0], t.su[1], t.su[2]), qu(t.qu[0], t.qu[1], t.qu[2]);
    vec3 E(0.0f);
    if constexpr (Order >= 2) E = vec3(e[0], e[1], e[2]);
    const Sym3<float> q{t.q[0], t.q[1], t.q[2], t.q[3], t.q[4], t.q[5]};
    // H_d Ω = a I + b u uᵀ + (v uᵀ + u vᵀ) + M.
    float a = 0.0f, b = 0.0f;
    vec3 v(0.0f);
    Sym3<float> m;
    if constexpr (Order >= 2) {
      a = (-52.5f * c3 + 7.5f * e_dot_u) * rho;
      b = (472.5f * c3 - 52.5f * e_dot_u) * rho;
      v = (qu * -157.5f + E * 7.5f) * rho;
      m = q * (45.0f * rho);
    }
    if constexpr (Order >= 1) {
      a = (-3.0f * half_trace_s + 7.5f * usu + a) * rho;
      b = (15.0f * half_trace_s - 52.5f * usu + b) * rho;
      v = (su * 15.0f + v) * rho;
      Sym3<float> order1 = Sym3<float>{s[0], s[1], s[2], s[3], s[4], s[5]} * -3.0f;
      order1 += m;
      m = order1 * rho;
    }
    a += -3.0f * n_dot_u;
    b += 15.0f * n_dot_u;
    v += N * -3.0f;
    const float rho4 = t.inv_r2 * t.inv_r2;
    a *= rho4;
    b *= rho4;
    v *= rho4;
    m = m * rho4;
    Sym3<float>& h = acc.hessian;
    h.xx += a + b * u.x * u.x + 2.0f * v.x * u.x + m.xx;
    h.yy += a + b * u.y * u.y + 2.0f * v.y * u.y + m.yy;
    h.zz += a + b * u.z * u.z + 2.0f * v.z * u.z + m.zz;
    h.xy += b * u.x * u.y + v.x * u.y + u.x * v.y + m.xy;
    h.xz += b * u.x * u.z + v.x * u.z + u.x * v.z + m.xz;
    h.yz += b * u.y * u.z + v.y * u.z + u.y * v.z + m.yz;
  }
}

}  // namespace gwnrt
