// The CUDA backend's one launch: out[i] = fn(in[i]), one thread per item. Point queries and ray
// tracing both go through it with a functor that calls the core's GWNRT_HD function.
#pragma once

#include <span>

#include "device_buffer.h"
#include "gwnrt/geometry/model_view.h"

namespace gwnrt::cuda {

template <class In, class Out, class Fn>
__global__ void map_kernel(const In* in, size_t count, Fn fn, Out* out) {
  const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
  if (i < count) out[i] = fn(in[i]);
}

// out[i] = fn(in[i]) on the device, one thread per item: copies `in` up, runs, copies `out`
// down. Fn is a trivially copyable functor with a __device__ call operator.
template <class In, class Out, class Fn>
Status map_on_device(std::span<const In> in, std::span<Out> out, int block, Fn fn) {
  if (in.empty()) return Status::Ok();
  DeviceBuffer<In> d_in;
  DeviceBuffer<Out> d_out;
  if (Status s = d_in.upload(in.data(), in.size()); !s.ok()) return s;
  if (Status s = d_out.allocate(in.size()); !s.ok()) return s;
  const unsigned grid = unsigned((in.size() + block - 1) / block);
  map_kernel<<<grid, block>>>(d_in.get(), in.size(), fn, d_out.get());
  if (Status s = cuda_status(cudaGetLastError(), "kernel launch"); !s.ok()) return s;
  if (Status s = cuda_status(cudaDeviceSynchronize(), "kernel execution"); !s.ok()) return s;
  return d_out.download(out.data(), out.size());
}

// What the batch entry points share (as the CPU drivers do, batch.cpp): `name` fails when in and
// out differ in size, then on validate(), then on a model never uploaded; else map_on_device.
template <class In, class Out, class Validate, class Fn>
Status map_batch_on_device(const char* name, const ModelView& model, std::span<const In> in, std::span<Out> out,
                           int block, Validate validate, Fn fn) {
  if (in.size() != out.size())
    return {StatusCode::kInvalidArgument, std::string(name) + ": inputs and outputs differ in size"};
  if (Status s = validate(); !s.ok()) return s;
  if (in.empty()) return Status::Ok();
  if (!model.triangles.bvh.nodes) return {StatusCode::kInvalidArgument, std::string(name) + ": model not uploaded"};
  return map_on_device(in, out, block, fn);
}

}  // namespace gwnrt::cuda
