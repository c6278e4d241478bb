// --device auto|cpu|cuda, the same in every program. The engine decides (gwnrt/engine.h); this
// names the flag when `cuda` cannot be had and, for `auto`, says on stderr which it took and why.
#pragma once

#include <cstdio>
#include <string>

#include "gwnrt/engine.h"

namespace gwnrt::apps {

inline constexpr const char* kDeviceHelp =
    "Where to compute: cpu, cuda (fails when no GPU is usable) or auto (the GPU when one is usable, "
    "else the CPU; says which)";

// The device `--device asked` runs on (kCpu or kCuda); `asked` is one of the three names (the
// flag's check took only these).
inline Status choose_device(const char* program, const std::string& asked, Device& device) {
  Device wanted = Device::kCpu;
  (void)device_named(asked, wanted);
  DeviceChoice chosen;
  if (Status s = gwnrt::choose_device(wanted, chosen); !s.ok()) return {s.code(), "--device cuda: " + s.message()};
  device = chosen.device;
  if (wanted == Device::kAuto) {
    if (device == Device::kCuda)
      std::fprintf(stderr, "%s: --device auto: the GPU\n", program);
    else
      std::fprintf(stderr, "%s: --device auto: the CPU (%s)\n", program, chosen.reason.c_str());
  }
  return Status::Ok();
}

}  // namespace gwnrt::apps
