// render_first_hit_cuda (first_hit_cuda.h): the per-pixel function in a kernel.
#include <chrono>
#include <memory>
#include <string>

#include <cuda_runtime.h>

#include "gwnrt/cuda.h"
#include "gwnrt/query/validation.h"
#include "render/integrators/first_hit_cuda.h"

namespace gwnrt::render {
namespace {

__global__ void first_hit_kernel(ModelView model, render::PinholeCamera camera, FirstHitSettings settings,
                                 FirstHitSample* pixels) {
  const int x = int(blockIdx.x * blockDim.x + threadIdx.x), y = int(blockIdx.y * blockDim.y + threadIdx.y);
  if (x < camera.width && y < camera.height)
    pixels[size_t(y) * size_t(camera.width) + size_t(x)] = first_hit_pixel(model, camera, settings, x, y);
}

Status cuda_error(cudaError_t err, const std::string& what) {
  if (err == cudaSuccess) return Status::Ok();
  cudaGetLastError();
  return {err == cudaErrorMemoryAllocation ? StatusCode::kOutOfMemory : StatusCode::kUnavailable,
          "first-hit on the GPU: " + what + ": " + cudaGetErrorString(err)};
}

}  // namespace

Status render_first_hit_cuda(const cuda::DeviceModel& model, const render::PinholeCamera& camera,
                             const FirstHitSettings& settings, int frames, std::vector<FirstHitSample>& pixels,
                             double& seconds_per_frame) {
  return guard_status("render_first_hit_cuda", [&]() -> Status {
    const ModelView view = model.view();
    if (!view.triangles.bvh.nodes) return {StatusCode::kInvalidArgument, "first-hit on the GPU: model not uploaded"};
    if (Status s = validate_trace_view(view); !s.ok()) return s;
    const size_t count = size_t(camera.width) * size_t(camera.height);
    pixels.resize(count);
    FirstHitSample* device = nullptr;
    const size_t bytes = count * sizeof(FirstHitSample);
    if (Status s = cuda_error(cudaMalloc(&device, bytes), "cudaMalloc of " + std::to_string(bytes) + " bytes"); !s.ok())
      return s;
    const dim3 block(16, 8);
    const dim3 grid(unsigned((camera.width + 15) / 16), unsigned((camera.height + 7) / 8));
    // Freed on every way out.
    const auto free_device = [](FirstHitSample* p) { cudaFree(p); };
    const std::unique_ptr<FirstHitSample, decltype(free_device)> owner(device, free_device);
    const auto frame = [&]() -> Status {
      first_hit_kernel<<<grid, block>>>(view, camera, settings, device);
      if (Status s = cuda_error(cudaGetLastError(), "kernel launch"); !s.ok()) return s;
      return cuda_error(cudaMemcpy(pixels.data(), device, bytes, cudaMemcpyDeviceToHost),
                        "the kernel, or the copy of " + std::to_string(bytes) + " bytes to the host");
    };
    const auto t0 = std::chrono::steady_clock::now();
    for (int f = 0; f < frames; ++f)
      if (Status s = frame(); !s.ok()) return s;
    seconds_per_frame = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / frames;
    return Status::Ok();
  });
}

}  // namespace gwnrt::render
