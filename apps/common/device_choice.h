// --device auto|cpu|cuda, the same in every program (issue 17): `cuda` needs the CUDA backend
// built into the program (GWNRT_HAVE_CUDA) and a usable device, and fails with the reason
// otherwise; `auto` takes the GPU when both hold and the CPU otherwise, saying on stderr which it
// chose and why.
#pragma once

#include <cstdio>
#include <string>

#include "gwnrt/base/status.h"

#if defined(GWNRT_HAVE_CUDA)
#include "gwnrt/cuda.h"
#endif

namespace gwnrt::apps {

inline constexpr const char* kDeviceHelp =
    "Where to compute: cpu, cuda (fails when no GPU is usable) or auto (the GPU when one is usable, "
    "else the CPU; says which)";

// Whether the program runs on the GPU for `--device asked` (already checked to be one of the
// three names); Status says why `cuda` cannot.
inline Status choose_device(const char* program, const std::string& asked, bool& use_cuda) {
  use_cuda = false;
  if (asked == "cpu") return Status::Ok();
  std::string why;
#if defined(GWNRT_HAVE_CUDA)
  const bool usable = cuda::device_available(&why);
#else
  const bool usable = false;
  why = std::string("this ") + program +
        " was built without the CUDA backend (reconfigure with -DGWNRT_WITH_CUDA=ON on a machine with the CUDA "
        "toolkit)";
#endif
  if (asked == "cuda") {
    if (!usable) return {StatusCode::kUnavailable, "--device cuda: " + why};
    use_cuda = true;
    return Status::Ok();
  }
  use_cuda = usable;
  if (usable)
    std::fprintf(stderr, "%s: --device auto: the GPU\n", program);
  else
    std::fprintf(stderr, "%s: --device auto: the CPU (%s)\n", program, why.c_str());
  return Status::Ok();
}

}  // namespace gwnrt::apps
