// Host-and-device foundation: the macro that marks a function as compiled for both the
// CPU and the GPU, and the small vector vocabulary every numeric kernel shares.
// This header (and every header it reaches) must stay free of TBB, Embree and OpenImageIO:
// nvcc compiles it.
#pragma once

#include <cstdint>

// GWNRT_PASS marks a lambda handed to a backend's parallel_for (meshing/mesh_pipeline.h). Under
// nvcc it is device code only: the CUDA backend only launches it, and a host copy (an extended
// __host__ __device__ lambda gets one) brings host copies of all it calls, compiled without the
// host's lanes (GWNRT_HOST_LANES is 0 under nvcc), which the linker may then pick for the CPU
// code of a binary that links both backends.
#if defined(__CUDACC__)
#define GWNRT_HD __host__ __device__
#define GWNRT_PASS __device__
#define GWNRT_FORCEINLINE __forceinline__
#define GWNRT_NOINLINE __noinline__
#else
#define GWNRT_HD
#define GWNRT_PASS
#define GWNRT_FORCEINLINE inline __attribute__((always_inline))
#define GWNRT_NOINLINE __attribute__((noinline))
#endif

// GLM recognises nvcc on its own and marks its functions __host__ __device__.
#include <glm/glm.hpp>

namespace gwnrt {

using vec3 = glm::vec3;
using dvec3 = glm::dvec3;
using uvec3 = glm::uvec3;

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr float kInvPi = float(1.0 / kPi);
inline constexpr float kInv4Pi = float(0.25 / kPi);
inline constexpr float kDegree = float(kPi / 180.0);       // one degree in radians
inline constexpr float kInfinity = __builtin_huge_valf();  // +inf, usable on the device

// Symmetric 3x3 matrix stored as its six independent entries (xx, xy, xz, yy, yz, zz).
template <class T>
struct Sym3 {
  T xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
  GWNRT_HD T trace() const { return xx + yy + zz; }
  GWNRT_HD Sym3& operator+=(const Sym3& o) {
    xx += o.xx;
    xy += o.xy;
    xz += o.xz;
    yy += o.yy;
    yz += o.yz;
    zz += o.zz;
    return *this;
  }
  GWNRT_HD Sym3 operator*(T s) const { return {xx * s, xy * s, xz * s, yy * s, yz * s, zz * s}; }
  GWNRT_HD glm::vec<3, T> apply(const glm::vec<3, T>& v) const {  // the matrix times v
    return {xx * v.x + xy * v.y + xz * v.z, xy * v.x + yy * v.y + yz * v.z, xz * v.x + yz * v.y + zz * v.z};
  }
};
using sym3 = Sym3<float>;

template <class T>
GWNRT_HD inline T sqr(T x) {
  return x * x;
}

// Minimum and maximum of numbers: fminf and fmaxf also order NaN, and for that GCC calls the
// library on x86 instead of emitting one instruction. Callers that rely on NaN being dropped
// keep fminf / fmaxf.
GWNRT_HD GWNRT_FORCEINLINE float min_of(float a, float b) { return b < a ? b : a; }
GWNRT_HD GWNRT_FORCEINLINE float max_of(float a, float b) { return a < b ? b : a; }

// atan2 by the type of its arguments: an unqualified atan2 of floats finds C's double version on
// the host (about twice the cost).
GWNRT_HD GWNRT_FORCEINLINE float arctan2(float y, float x) { return atan2f(y, x); }
GWNRT_HD GWNRT_FORCEINLINE double arctan2(double y, double x) { return atan2(y, x); }

// The bits of a float and back, the same on the host and the device.
GWNRT_HD inline uint32_t float_bits(float x) {
#if defined(__CUDA_ARCH__)
  return __float_as_uint(x);
#else
  return __builtin_bit_cast(uint32_t, x);
#endif
}
GWNRT_HD inline float bits_float(uint32_t u) {
#if defined(__CUDA_ARCH__)
  return __uint_as_float(u);
#else
  return __builtin_bit_cast(float, u);
#endif
}

// A bit test rather than std::isfinite: under -ffast-math the compiler may assume that no NaN
// or infinity exists and fold std::isfinite to true, which would disable input checks.
GWNRT_HD inline bool is_finite(float x) { return (float_bits(x) & 0x7f800000u) != 0x7f800000u; }

// 2^-e for the binary exponent e of m > 0, so that m·scale lies in [1, 2): an exact rescaling
// (no rounding) that costs no division. Huge m saturate at 2^-126, zero or subnormal m get 2^127 (and
// m·scale stays below 2).
GWNRT_HD inline float power_of_two_scale(float m) {
  uint32_t exponent = float_bits(m) & 0x7f800000u;
  exponent = exponent > 0x7e800000u ? 0x7e800000u : exponent;
  return bits_float(0x7f000000u - exponent);
}

namespace detail {
// 2^-e for the binary exponent e of m > 0 on the host, U the integer type of m's bits: a double,
// or each lane of a vector of doubles (lanes.h).
template <class D, class U>
inline D power_of_two_scale_bits(D m) {
  const U exponent = __builtin_bit_cast(U, m) & (U{} + 0x7ff0000000000000ll);
  const U largest = U{} + 0x7fd0000000000000ll;
  return __builtin_bit_cast(D, (U{} + 0x7fe0000000000000ll) - (exponent > largest ? largest : exponent));
}
}  // namespace detail

// The same for doubles: 2^-e for the binary exponent e of m > 0 (huge m saturate at 2^-1022,
// zero or subnormal m get 2^1023).
GWNRT_HD inline double power_of_two_scale(double m) {
#if defined(__CUDA_ARCH__)
  uint64_t exponent = uint64_t(__double_as_longlong(m)) & 0x7ff0000000000000ull;
  exponent = exponent > 0x7fd0000000000000ull ? 0x7fd0000000000000ull : exponent;
  return __longlong_as_double((long long)(0x7fe0000000000000ull - exponent));
#else
  return detail::power_of_two_scale_bits<double, uint64_t>(m);
#endif
}

// The index of the lowest set bit of a nonzero mask.
GWNRT_HD GWNRT_FORCEINLINE int lowest_set_bit(uint32_t mask) {
#if defined(__CUDA_ARCH__)
  return __ffs(int(mask)) - 1;
#else
  return __builtin_ctz(mask);
#endif
}

GWNRT_HD inline int bit_count(uint32_t v) {
#if defined(__CUDA_ARCH__)
  return __popc(v);
#else
  return __builtin_popcount(v);
#endif
}

GWNRT_HD inline bool is_nan(float x) { return !is_finite(x) && x != kInfinity && x != -kInfinity; }

}  // namespace gwnrt
