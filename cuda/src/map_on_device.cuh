// The CUDA backend's one launch: out[i] = fn(in[i]), one thread per item. Point queries and ray
// tracing both go through it with a functor that calls the core's GWNRT_HD function.
#pragma once

#include <span>
#include <string>

#include "device_model.cuh"

namespace gwnrt::cuda {

template <class In, class Out, class Fn>
__global__ void map_kernel(const In* in, size_t count, Fn fn, Out* out) {
  const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
  if (i < count) out[i] = fn(in[i]);
}

// out[i] = fn(in[i]) on the device, one thread per item, on `stream`: copies `in` up into the
// model's scratch, runs, copies `out` down, and waits for the stream. Fn is a trivially
// copyable functor with a __device__ call operator.
template <class In, class Out, class Fn>
Status map_on_device(DeviceAccess::Buffers& buffers, std::span<const In> in, std::span<Out> out, int block, Fn fn,
                     cudaStream_t stream) {
  if (in.empty()) return Status::Ok();
  const std::lock_guard<std::mutex> lock(buffers.scratch_mutex);
  if (Status s = buffers.inputs.reserve(in.size_bytes()); !s.ok()) return s;
  if (Status s = buffers.results.reserve(out.size_bytes()); !s.ok()) return s;
  In* d_in = static_cast<In*>(buffers.inputs.get());
  Out* d_out = static_cast<Out*>(buffers.results.get());
  if (Status s = cuda_status(cudaMemcpyAsync(d_in, in.data(), in.size_bytes(), cudaMemcpyHostToDevice, stream),
                             "cudaMemcpy of " + std::to_string(in.size_bytes()) + " bytes to the device");
      !s.ok())
    return s;
  const unsigned grid = unsigned((in.size() + block - 1) / block);
  map_kernel<<<grid, block, 0, stream>>>(d_in, in.size(), fn, d_out);
  if (Status s = cuda_status(cudaGetLastError(), "kernel launch"); !s.ok()) return s;
  if (Status s = cuda_status(cudaMemcpyAsync(out.data(), d_out, out.size_bytes(), cudaMemcpyDeviceToHost, stream),
                             "cudaMemcpy of " + std::to_string(out.size_bytes()) + " bytes to the host");
      !s.ok())
    return s;
  return cuda_status(cudaStreamSynchronize(stream), "kernel execution");
}

// What the batch entry points share (as the CPU drivers do, batch.cpp): `name` fails when in and
// out differ in size, then on validate(), then on a model never uploaded; else map_on_device.
template <class In, class Out, class Validate, class Fn>
Status map_batch_on_device(const char* name, const DeviceModel& model, std::span<const In> in, std::span<Out> out,
                           int block, Validate validate, Fn fn, cudaStream_t stream) {
  if (in.size() != out.size())
    return {StatusCode::kInvalidArgument, std::string(name) + ": inputs and outputs differ in size"};
  if (Status s = validate(); !s.ok()) return s;
  if (in.empty()) return Status::Ok();
  DeviceAccess::Buffers* buffers = DeviceAccess::buffers(model);
  if (!buffers) return {StatusCode::kInvalidArgument, std::string(name) + ": model not uploaded"};
  return guard_status(name, [&] { return map_on_device(*buffers, in, out, block, fn, stream); });
}

}  // namespace gwnrt::cuda
