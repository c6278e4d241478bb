// The mesher's CUDA backend (meshing/mesh_pipeline.h): arrays in device memory, parallel_for as
// one grid-stride kernel over the pass functors (the very GWNRT_HD structs and lambdas the TBB
// backend runs), scans and sums with CUB. The driver's calls return nothing, so a CUDA call that
// fails throws DeviceFailure, which the entry point turns back into its Status (guard_device).
#pragma once

#include <cub/device/device_reduce.cuh>
#include <cub/device/device_scan.cuh>

#include <atomic>
#include <cstdint>
#include <exception>
#include <string>
#include <utility>
#include <vector>

#include "device_buffer.h"

namespace gwnrt::cuda {

struct DeviceFailure : std::exception {
  Status status;
  explicit DeviceFailure(Status s) : status(std::move(s)) {}
  const char* what() const noexcept override { return status.message().c_str(); }
};

inline void check_device(cudaError_t err, const char* what) {
  if (err != cudaSuccess) throw DeviceFailure(cuda_status(err, what));
}

// guard_status, keeping a DeviceFailure's own code (out of memory, unavailable).
template <class Fn>
Status guard_device(const char* where, Fn&& fn) noexcept {
  try {
    return std::forward<Fn>(fn)();
  } catch (const DeviceFailure& e) {
    return {e.status.code(), std::string(where) + ": " + e.status.message()};
  } catch (...) {
    return guard_status(where, []() -> Status { throw; });
  }
}

// Zero-filled device array; resize does not keep the contents (the driver never needs them).
template <class T>
class DeviceArray {
 public:
  void resize(uint64_t n) {
    if (Status s = buffer_.allocate(n); !s.ok()) throw DeviceFailure(s);
    if (n == 0) return;
    check_device(cudaMemset(buffer_.get(), 0, n * sizeof(T)), "cudaMemset");
    // The fill runs on the legacy default stream, which a stream made non-blocking does not wait
    // for: the driver's next kernel, on the backend's stream, must not start before it ends.
    check_device(cudaStreamSynchronize(cudaStreamLegacy), "cudaMemset");
  }
  T* data() const { return buffer_.get(); }
  uint64_t size() const { return buffer_.size(); }

 private:
  DeviceBuffer<T> buffer_;
};

template <class Fn>
__global__ void for_each_item(uint64_t n, Fn fn) {
  const uint64_t stride = uint64_t(gridDim.x) * blockDim.x;
  for (uint64_t i = uint64_t(blockIdx.x) * blockDim.x + threadIdx.x; i < n; i += stride) fn(i);
}

struct CudaBackend {
  template <class T>
  using Array = DeviceArray<T>;

  cudaStream_t stream = nullptr;

  // fn(i) for i in [0, n): one thread an item (the grain is the CPU's); `progress` counts the
  // items once the kernel has finished.
  template <class Fn>
  void parallel_for(uint64_t n, const Fn& fn, uint64_t = 0, std::atomic<size_t>* progress = nullptr) const {
    if (n == 0) return;
    constexpr unsigned kBlock = 128;
    const uint64_t blocks = (n + kBlock - 1) / kBlock;
    for_each_item<<<unsigned(blocks < (1u << 20) ? blocks : (1u << 20)), kBlock, 0, stream>>>(n, fn);
    check_device(cudaGetLastError(), "kernel launch");
    if (progress) {
      check_device(cudaStreamSynchronize(stream), "kernel execution");
      progress->fetch_add(size_t(n), std::memory_order_relaxed);
    }
  }

  // out[i] = Σ in[0..i) (32-bit, as on the host), returning the 64-bit total; out may be in (CUB
  // scans in place), so the total is summed first.
  uint64_t exclusive_scan(const uint32_t* in, uint64_t n, uint32_t* out) const {
    if (n == 0) return 0;
    if (!scan_total.get())
      if (Status s = scan_total.allocate(1); !s.ok()) throw DeviceFailure(s);
    size_t scan_bytes = 0, sum_bytes = 0;
    check_device(cub::DeviceScan::ExclusiveSum(nullptr, scan_bytes, in, out, int64_t(n), stream), "cub scan");
    check_device(cub::DeviceReduce::Sum(nullptr, sum_bytes, in, scan_total.get(), int64_t(n), stream), "cub sum");
    const size_t needed = scan_bytes > sum_bytes ? scan_bytes : sum_bytes;
    if (scan_temp.size() < needed)
      if (Status s = scan_temp.allocate(needed); !s.ok()) throw DeviceFailure(s);
    size_t bytes = scan_temp.size();
    check_device(cub::DeviceReduce::Sum(scan_temp.get(), bytes, in, scan_total.get(), int64_t(n), stream), "cub sum");
    bytes = scan_temp.size();
    check_device(cub::DeviceScan::ExclusiveSum(scan_temp.get(), bytes, in, out, int64_t(n), stream), "cub scan");
    uint64_t total = 0;
    check_device(cudaMemcpyAsync(&total, scan_total.get(), sizeof(total), cudaMemcpyDeviceToHost, stream),
                 "cudaMemcpy to host");
    check_device(cudaStreamSynchronize(stream), "cudaMemcpy to host");
    return total;
  }

  // CUB's temporary storage and the scans' total, kept from scan to scan (grown when one needs
  // more): a scan costs no cudaMalloc, cudaFree or fill (the driver scans about 15 times a mesh).
  mutable DeviceBuffer<uint8_t> scan_temp;
  mutable DeviceBuffer<uint64_t> scan_total;

  template <class T>
  T to_host(const Array<T>& a, uint64_t i) const {
    T value;
    check_device(cudaMemcpyAsync(&value, a.data() + i, sizeof(T), cudaMemcpyDeviceToHost, stream),
                 "cudaMemcpy to host");
    check_device(cudaStreamSynchronize(stream), "cudaMemcpy to host");
    return value;
  }

  template <class T>
  void move_out(Array<T>& a, std::vector<T>& dst) const {
    dst.resize(a.size());
    if (!dst.empty())
      check_device(cudaMemcpyAsync(dst.data(), a.data(), dst.size() * sizeof(T), cudaMemcpyDeviceToHost, stream),
                   "cudaMemcpy to host");
    check_device(cudaStreamSynchronize(stream), "cudaMemcpy to host");
    a = Array<T>{};
  }
};

}  // namespace gwnrt::cuda
