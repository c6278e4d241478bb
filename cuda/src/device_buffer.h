// RAII device memory for the CUDA backend (the smallgwn pattern: an owning buffer on the host
// side, a raw pointer inside the trivially copyable view handed to kernels).
#pragma once

#include <cuda_runtime.h>

#include <span>
#include <string>
#include <vector>

#include "gwnrt/status.h"

namespace gwnrt::cuda {

inline Status cuda_status(cudaError_t err, const char* what) {
  if (err == cudaSuccess) return Status::Ok();
  return {StatusCode::kUnavailable, std::string(what) + ": " + cudaGetErrorString(err)};
}

template <class T>
class DeviceBuffer {
 public:
  DeviceBuffer() = default;
  DeviceBuffer(const DeviceBuffer&) = delete;
  DeviceBuffer& operator=(const DeviceBuffer&) = delete;
  DeviceBuffer(DeviceBuffer&& o) noexcept : ptr_(o.ptr_), size_(o.size_) { o.ptr_ = nullptr; o.size_ = 0; }
  DeviceBuffer& operator=(DeviceBuffer&& o) noexcept {
    if (this != &o) { release(); ptr_ = o.ptr_; size_ = o.size_; o.ptr_ = nullptr; o.size_ = 0; }
    return *this;
  }
  ~DeviceBuffer() { release(); }

  Status allocate(size_t count) {
    release();
    if (count == 0) return Status::Ok();
    if (Status s = cuda_status(cudaMalloc(&ptr_, count * sizeof(T)), "cudaMalloc"); !s.ok()) { ptr_ = nullptr; return s; }
    size_ = count;
    return Status::Ok();
  }
  Status upload(const T* data, size_t count) {
    if (Status s = allocate(count); !s.ok()) return s;
    if (count == 0) return Status::Ok();
    return cuda_status(cudaMemcpy(ptr_, data, count * sizeof(T), cudaMemcpyHostToDevice), "cudaMemcpy to device");
  }
  Status upload(const std::vector<T>& v) { return upload(v.data(), v.size()); }
  Status download(T* data, size_t count) const {
    if (count == 0) return Status::Ok();
    return cuda_status(cudaMemcpy(data, ptr_, count * sizeof(T), cudaMemcpyDeviceToHost), "cudaMemcpy to host");
  }

  T* get() const { return ptr_; }
  size_t size() const { return size_; }

 private:
  void release() {
    if (ptr_) cudaFree(ptr_);
    ptr_ = nullptr;
    size_ = 0;
  }
  T* ptr_ = nullptr;
  size_t size_ = 0;
};

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

}  // namespace gwnrt::cuda
