// What an allocation sized by input (a file, a header's count, an image or point count) would
// need, against what the system can give now (definitions: core/src/base/memory.cpp). Checked
// before allocating: with Linux's overcommit a huge allocation often succeeds and the process is
// killed later, when its pages are touched, and elsewhere it ends in std::bad_alloc; either way
// the user learns nothing about the size they asked for (docs/design.md §8).
#pragma once

#include <cstdint>
#include <limits>
#include <string>

#include "gwnrt/base/status.h"

namespace gwnrt {

inline constexpr uint64_t kUnknownMemory = std::numeric_limits<uint64_t>::max();

// Bytes this process can still allocate: the system's available memory (MemAvailable, which
// counts reclaimable caches, plus free swap), capped by the cgroup's limit (containers) and by
// RLIMIT_AS (`ulimit -v`) less what the process already maps. kUnknownMemory where none of these
// can be read.
uint64_t available_memory_bytes();

// a · b, or UINT64_MAX when that overflows: sizes computed from untrusted counts.
constexpr uint64_t saturating_product(uint64_t a, uint64_t b) {
  return a != 0 && b > std::numeric_limits<uint64_t>::max() / a ? std::numeric_limits<uint64_t>::max() : a * b;
}

// a + b, or UINT64_MAX when that overflows.
constexpr uint64_t saturating_sum(uint64_t a, uint64_t b) {
  return b > std::numeric_limits<uint64_t>::max() - a ? std::numeric_limits<uint64_t>::max() : a + b;
}

// "512 B", "12.0 KiB", "312.5 MiB", "1.5 GiB", "2.0 TiB", ... (any size, no overflow).
std::string memory_size_text(uint64_t bytes);

// Ok when `bytes` fit in available_memory_bytes() (always when that is unknown); else
// kOutOfMemory: "<what> would need <size> of memory, more than the <size> available".
Status check_memory(uint64_t bytes, const std::string& what);

}  // namespace gwnrt
