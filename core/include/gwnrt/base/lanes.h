// Lane vectors for the host's multipole traversal: a node's four lanes (and batches of near
// triangles) evaluated at once with GCC's vector extensions. The formulas they run are templates
// over the lane type, shared with the scalar code (multipole.h: float, the device and every
// other visitor), so only this vocabulary is host-only. nvcc (either pass) never sees the
// vector types: GWNRT_HOST_LANES is 0 under __CUDACC__.
#pragma once

#include <cstdint>

#include "gwnrt/base/hd.h"

#if !defined(__CUDACC__) && defined(__GNUC__)
#define GWNRT_HOST_LANES 1
#else
#define GWNRT_HOST_LANES 0
#endif

#if GWNRT_HOST_LANES && (defined(__x86_64__) || defined(__i386__))
#include <immintrin.h>
#endif

namespace gwnrt {

// Square root of a scalar: the lane-type templates call it unqualified, so the vector overloads
// below are found the same way.
GWNRT_HD GWNRT_FORCEINLINE float lane_sqrt(float x) { return sqrtf(x); }
GWNRT_HD GWNRT_FORCEINLINE double lane_abs(double x) { return fabs(x); }

// Whether any lane of a comparison holds (a scalar comparison: whether it holds).
GWNRT_HD GWNRT_FORCEINLINE bool lane_any(bool m) { return m; }

// a·b − c·d to an ulp or two of the result, however much the products cancel (Kahan's: the
// rounding error of c·d, recovered by a fused multiply-add, added back).
GWNRT_HD GWNRT_FORCEINLINE float difference_of_products(float a, float b, float c, float d) {
  const float cd = c * d;
  return fmaf(a, b, -cd) + fmaf(-c, d, cd);
}
GWNRT_HD GWNRT_FORCEINLINE double difference_of_products(double a, double b, double c, double d) {
  const double cd = c * d;
  return fma(a, b, -cd) + fma(-c, d, cd);
}

// m ? a : b, lane by lane for lane vectors (GCC's vector conditional) and plainly for scalars.
template <class M, class V>
GWNRT_HD GWNRT_FORCEINLINE V lane_select(M m, V a, V b) {
  return m ? a : b;
}

#if GWNRT_HOST_LANES

typedef float f4 __attribute__((vector_size(16)));
typedef int32_t i4 __attribute__((vector_size(16)));
typedef uint32_t u4 __attribute__((vector_size(16)));
// Near triangles go 8 at a time where the CPU has 256-bit registers (AVX), else 4: a 256-bit
// vector without AVX would change the calling convention (GCC's -Wpsabi).
#if defined(__AVX__)
typedef float fnear __attribute__((vector_size(32)));
typedef int32_t inear __attribute__((vector_size(32)));
inline constexpr int kNearWidth = 8;
typedef fnear f8;
typedef inear i8;
typedef uint32_t u8 __attribute__((vector_size(32)));
// Four lanes at lo and four at hi as one 8-lane vector, lo's first: a load and a vinsertf128
// from memory (GCC 12 builds __builtin_shufflevector of two loaded f4s through the stack).
GWNRT_FORCEINLINE f8 load8(const float* lo, const float* hi) { return f8(_mm256_loadu2_m128(hi, lo)); }
GWNRT_FORCEINLINE u8 load8(const uint32_t* lo, const uint32_t* hi) {
  return u8(_mm256_loadu2_m128i(reinterpret_cast<const __m128i*>(hi), reinterpret_cast<const __m128i*>(lo)));
}
#else
typedef f4 fnear;
typedef i4 inear;
inline constexpr int kNearWidth = 4;
#endif

GWNRT_FORCEINLINE f4 load4(const float* p) {
  f4 v;
  __builtin_memcpy(&v, p, sizeof v);
  return v;
}
GWNRT_FORCEINLINE u4 load4(const uint32_t* p) {
  u4 v;
  __builtin_memcpy(&v, p, sizeof v);
  return v;
}

// Every lane x (but not -0: 0 + -0 is +0).
template <class V>
GWNRT_FORCEINLINE V splat(float x) {
  return V{} + x;
}

// Correctly rounded, as sqrtf is: the lanes give the scalar path's results bit for bit.
template <class V>
GWNRT_FORCEINLINE V lane_sqrt(V x) {
#if defined(__x86_64__) || defined(__i386__)
  if constexpr (sizeof(V) == 16) return V(_mm_sqrt_ps(__m128(x)));
#if defined(__AVX__)
  if constexpr (sizeof(V) == 32) return V(_mm256_sqrt_ps(__m256(x)));
#endif
#endif
  V r;
  for (int i = 0; i < int(sizeof(V) / sizeof(float)); ++i) r[i] = sqrtf(x[i]);
  return r;
}

// Bit i set when lane i of the comparison mask is true.
template <class M>
GWNRT_FORCEINLINE uint32_t lane_bits(M m) {
#if defined(__x86_64__) || defined(__i386__)
  if constexpr (sizeof(M) == 16) return uint32_t(_mm_movemask_ps(__m128(m)));
#if defined(__AVX__)
  if constexpr (sizeof(M) == 32) return uint32_t(_mm256_movemask_ps(__m256(m)));
#endif
#endif
  uint32_t bits = 0;
  for (int i = 0; i < int(sizeof(M) / sizeof(int32_t)); ++i) bits |= (m[i] != 0 ? 1u : 0u) << i;
  return bits;
}

GWNRT_FORCEINLINE f4 difference_of_products(f4 a, f4 b, f4 c, f4 d) {
#if defined(__FMA__)
  const __m128 cd = _mm_mul_ps(__m128(c), __m128(d));
  return f4(_mm_add_ps(_mm_fmsub_ps(__m128(a), __m128(b), cd), _mm_fnmadd_ps(__m128(c), __m128(d), cd)));
#else
  f4 r;
  for (int i = 0; i < 4; ++i) r[i] = difference_of_products(a[i], b[i], c[i], d[i]);
  return r;
#endif
}

template <class M>
GWNRT_FORCEINLINE bool lane_any(M m) {
  return lane_bits(m) != 0;
}

// Four doubles, where the CPU has 256-bit registers: exact products of floats (the ray's edge
// functions, geometry/ray.h) four at a time. Without AVX the callers keep their scalar loops.
#if defined(__AVX__)
typedef double d4 __attribute__((vector_size(32)));
typedef int64_t l4 __attribute__((vector_size(32)));

// Bit i set when lane i of a comparison of d4s is true.
GWNRT_FORCEINLINE uint32_t lane_bits64(l4 m) {
#if defined(__x86_64__) || defined(__i386__)
  return uint32_t(_mm256_movemask_pd(__m256d(m)));
#else
  uint32_t bits = 0;
  for (int i = 0; i < 4; ++i) bits |= (m[i] != 0 ? 1u : 0u) << i;
  return bits;
#endif
}

// Correctly rounded, as sqrt is (a non-template overload: preferred to lane_sqrt<V> above).
GWNRT_FORCEINLINE d4 lane_sqrt(d4 x) {
#if defined(__x86_64__) || defined(__i386__)
  return d4(_mm256_sqrt_pd(__m256d(x)));
#else
  d4 r;
  for (int i = 0; i < 4; ++i) r[i] = sqrt(x[i]);
  return r;
#endif
}

GWNRT_FORCEINLINE d4 lane_abs(d4 x) {
  return __builtin_bit_cast(d4, __builtin_bit_cast(l4, x) & (l4{} + 0x7fffffffffffffffll));
}

GWNRT_FORCEINLINE d4 power_of_two_scale(d4 m) { return detail::power_of_two_scale_bits<d4, l4>(m); }
#endif

template <class V>
GWNRT_FORCEINLINE float lane_sum(V v) {
  float s = 0.0f;
  for (int i = 0; i < int(sizeof(V) / sizeof(float)); ++i) s += v[i];
  return s;
}

// atan2 of each lane, to 3 ulp of the result (against atan2f), with atan2f's signs and its
// atan2(±0, ±0). One division: the argument is reduced to [0, tan π/8] by swapping the legs and by
// atan t = π/4 + atan((t - 1)/(t + 1)) (Cephes' atanf).
template <class V>
GWNRT_FORCEINLINE V lane_atan2(V y, V x) {
  using M = decltype(y < x);
  const V zero{};
  const V ay = lane_select(y < zero, -y, y), ax = lane_select(x < zero, -x, x);
  const M swap = ay > ax;
  const V lo = lane_select(swap, ax, ay), hi = lane_select(swap, ay, ax);
  const M big = lo > splat<V>(0.41421356237f) * hi;
  const V num = lane_select(big, lo - hi, lo), den = lane_select(big, lo + hi, hi);
  const V t = lane_select(hi > zero, num / den, zero);
  const V z = t * t;
  V r = (((splat<V>(8.05374449538e-2f) * z - splat<V>(1.38776856032e-1f)) * z + splat<V>(1.99777106478e-1f)) * z -
         splat<V>(3.33329491539e-1f)) *
            z * t +
        t;
  r += lane_select(big, splat<V>(0.78539816340f), zero);
  r = lane_select(swap, splat<V>(1.57079632679f) - r, r);
  // x < 0, or x = -0 (atan2f(±0, -0) = ±π): the sign bit of x.
  const M sign_bit = M{} + int32_t(0x80000000u);
  r = lane_select((M(x) & sign_bit) != M{}, splat<V>(3.14159265359f) - r, r);
  return V(M(r) | (M(y) & sign_bit));  // the sign of y
}

#endif  // GWNRT_HOST_LANES

}  // namespace gwnrt
