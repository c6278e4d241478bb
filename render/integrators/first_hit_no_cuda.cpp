// render_first_hit_cuda in a build without the CUDA backend (first_hit_cuda.h): no GPU to render
// on. The engine never hands out a device model there, so this only answers a direct call.
#include "render/integrators/first_hit_cuda.h"

namespace gwnrt::render {

Status render_first_hit_cuda(const cuda::DeviceModel&, const render::PinholeCamera&, const FirstHitSettings&, int,
                             std::vector<FirstHitSample>& pixels, double& seconds_per_frame) {
  pixels.clear();
  seconds_per_frame = 0;
  return {StatusCode::kUnavailable, "first-hit on the GPU: this build has no CUDA backend"};
}

}  // namespace gwnrt::render
