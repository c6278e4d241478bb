// Available memory and the size checks (gwnrt/base/memory.h). Linux only reads what /proc and
// /sys say; elsewhere the memory is unknown and every check passes (std::bad_alloc, caught by
// guard_status, is then the only guard).
#include "gwnrt/base/memory.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <limits>
#include <string>

namespace gwnrt {
namespace {

// The number after `key` on its line of a "key value" file (/proc/meminfo, memory.stat), or false.
bool read_keyed_value(const char* path, const std::string& key, uint64_t& value) {
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.compare(0, key.size(), key) != 0) continue;
    unsigned long long v = 0;
    if (std::sscanf(line.c_str() + key.size(), "%llu", &v) != 1) return false;
    value = v;
    return true;
  }
  return false;
}

// The first number in a one-value file (memory.max, memory.current); false for "max" or none.
bool read_single_value(const char* path, uint64_t& value) {
  std::ifstream in(path);
  unsigned long long v = 0;
  if (!(in >> v)) return false;
  value = v;
  return true;
}

// MemAvailable + SwapFree, in bytes.
uint64_t system_available() {
  uint64_t available_kib = 0, swap_kib = 0;
  if (!read_keyed_value("/proc/meminfo", "MemAvailable:", available_kib)) return kUnknownMemory;
  if (!read_keyed_value("/proc/meminfo", "SwapFree:", swap_kib)) swap_kib = 0;
  return saturating_product(saturating_sum(available_kib, swap_kib), 1024);
}

// The container's room: its limit less its usage, where the usage's inactive file cache counts
// as free (the kernel reclaims it before refusing), as container runtimes count it. cgroup v2
// first, then v1; the process sees its own cgroup at these paths in a container.
uint64_t cgroup_available() {
  struct Layout {
    const char *limit, *usage, *stat, *inactive_key;
  };
  static constexpr Layout kLayouts[] = {
      {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current", "/sys/fs/cgroup/memory.stat", "inactive_file "},
      {"/sys/fs/cgroup/memory/memory.limit_in_bytes", "/sys/fs/cgroup/memory/memory.usage_in_bytes",
       "/sys/fs/cgroup/memory/memory.stat", "total_inactive_file "},
  };
  for (const Layout& l : kLayouts) {
    uint64_t limit = 0, usage = 0, inactive = 0;
    if (!read_single_value(l.limit, limit) || !read_single_value(l.usage, usage)) continue;
    if (!read_keyed_value(l.stat, l.inactive_key, inactive)) inactive = 0;
    const uint64_t used = usage - std::min(usage, inactive);
    return limit > used ? limit - used : 0;
  }
  return kUnknownMemory;
}

// RLIMIT_AS less the address space already mapped (/proc/self/statm's first field, in pages).
uint64_t address_space_available() {
  rlimit lim{};
  if (getrlimit(RLIMIT_AS, &lim) != 0 || lim.rlim_cur == RLIM_INFINITY) return kUnknownMemory;
  uint64_t pages = 0;
  if (!read_single_value("/proc/self/statm", pages)) return kUnknownMemory;
  const long page = sysconf(_SC_PAGESIZE);
  const uint64_t mapped = saturating_product(pages, page > 0 ? uint64_t(page) : 4096);
  return lim.rlim_cur > mapped ? uint64_t(lim.rlim_cur) - mapped : 0;
}

}  // namespace

uint64_t available_memory_bytes() {
  return std::min({system_available(), cgroup_available(), address_space_available()});
}

std::string memory_size_text(uint64_t bytes) {
  static constexpr const char* kUnits[] = {"KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  if (bytes < 1024) return std::to_string(bytes) + " B";
  if (bytes == std::numeric_limits<uint64_t>::max()) return "16 EiB or more";  // a saturated product
  double v = double(bytes) / 1024.0;
  int unit = 0;
  while (v >= 1024.0 && unit + 1 < int(std::size(kUnits))) {
    v /= 1024.0;
    ++unit;
  }
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f %s", v, kUnits[unit]);
  return buf;
}

Status check_memory(uint64_t bytes, const std::string& what) {
  const uint64_t available = available_memory_bytes();
  if (available == kUnknownMemory || bytes <= available) return Status::Ok();
  return {StatusCode::kOutOfMemory, what + " would need " + memory_size_text(bytes) + " of memory, more than the " +
                                        memory_size_text(available) + " available"};
}

}  // namespace gwnrt
