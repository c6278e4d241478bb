// First-hit rendering on the GPU (gwnrt-render --integrator first-hit --device cuda): one thread
// per pixel running first_hit_pixel, the CPU's per-pixel function. Plain C++ header; in a build
// without the CUDA backend the function is there and says so (first_hit_no_cuda.cpp).
#pragma once

#include <vector>

#include "gwnrt/base/status.h"
#include "render/integrators/first_hit_pixel.h"

namespace gwnrt::cuda {
class DeviceModel;
}

namespace gwnrt::render {

// Renders camera.width × camera.height pixels `frames` times (the same image each time, for a
// frame rate); `pixels` gets them row-major. `seconds_per_frame`: the mean of one frame's kernel
// and the copy of its pixels to the host, the model's upload not included. The trace options must
// have passed validate_trace_options. `model` comes from Engine::device_model.
Status render_first_hit_cuda(const cuda::DeviceModel& model, const render::PinholeCamera& camera,
                             const FirstHitSettings& settings, int frames, std::vector<FirstHitSample>& pixels,
                             double& seconds_per_frame);

}  // namespace gwnrt::render
