// Relaxed atomic updates that compile for the host (GCC builtins) and the device (CUDA's
// atomics), for the passes that count or flag from many items at once.
#pragma once

#include <cstdint>

#include "gwnrt/base/hd.h"

namespace gwnrt {

GWNRT_HD inline void atomic_or(uint32_t* p, uint32_t bits) {
#if defined(__CUDA_ARCH__)
  atomicOr(p, bits);
#else
  __atomic_fetch_or(p, bits, __ATOMIC_RELAXED);
#endif
}

GWNRT_HD inline void atomic_add(unsigned long long* p, unsigned long long v) {
#if defined(__CUDA_ARCH__)
  atomicAdd(p, v);
#else
  __atomic_fetch_add(p, v, __ATOMIC_RELAXED);
#endif
}

}  // namespace gwnrt
