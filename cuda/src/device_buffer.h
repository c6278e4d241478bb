// RAII device memory for the CUDA backend (the smallgwn pattern: an owning buffer on the host
// side, a raw pointer inside the trivially copyable view handed to kernels).
#pragma once

#include <cuda_runtime.h>

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "gwnrt/base/status.h"

namespace gwnrt::cuda {

inline Status cuda_status(cudaError_t err, const std::string& what) {
  if (err == cudaSuccess) return Status::Ok();
  cudaGetLastError();  // clears a sticky error, so that the next call does not report it again
  return {err == cudaErrorMemoryAllocation ? StatusCode::kOutOfMemory : StatusCode::kUnavailable,
          what + ": " + cudaGetErrorString(err)};
}

template <class T>
class DeviceBuffer {
 public:
  DeviceBuffer() = default;
  DeviceBuffer(const DeviceBuffer&) = delete;
  DeviceBuffer& operator=(const DeviceBuffer&) = delete;
  DeviceBuffer(DeviceBuffer&& o) noexcept : ptr_(o.ptr_), size_(o.size_) {
    o.ptr_ = nullptr;
    o.size_ = 0;
  }
  DeviceBuffer& operator=(DeviceBuffer&& o) noexcept {
    if (this != &o) {
      release();
      ptr_ = o.ptr_;
      size_ = o.size_;
      o.ptr_ = nullptr;
      o.size_ = 0;
    }
    return *this;
  }
  ~DeviceBuffer() { release(); }

  Status allocate(size_t count) {
    release();
    if (count == 0) return Status::Ok();
    if (count > SIZE_MAX / sizeof(T))
      return {StatusCode::kOutOfMemory, "cudaMalloc of " + std::to_string(count) + " items of " +
                                            std::to_string(sizeof(T)) + " bytes: beyond the address space"};
    if (Status s = cuda_status(cudaMalloc(&ptr_, count * sizeof(T)),
                               "cudaMalloc of " + std::to_string(count * sizeof(T)) + " bytes");
        !s.ok()) {
      ptr_ = nullptr;
      return s;
    }
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

}  // namespace gwnrt::cuda
