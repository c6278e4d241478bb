// A build without the CUDA backend: no GPU, and the reason (device_copy.h).
#include "device_copy.h"

namespace gwnrt::detail {
namespace {

constexpr const char* kNoBackend =
    "this build has no CUDA backend (reconfigure with -DGWNRT_WITH_CUDA=ON on a machine with the CUDA toolkit)";

}  // namespace

bool device_backend_built() { return false; }

bool device_usable(std::string* why) {
  if (why) *why = kNoBackend;
  return false;
}

uint64_t device_free_memory() { return 0; }

Status upload_device_copy(const GwnModel&, std::unique_ptr<DeviceCopy>& out) {
  out.reset();
  return {StatusCode::kUnavailable, kNoBackend};
}

}  // namespace gwnrt::detail
