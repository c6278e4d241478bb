// The CUDA backend's one launch: fn(i, in[i]), one thread per item (a map out[i] = fn(in[i]) is
// one such functor). Point queries and ray tracing go through it with a functor that calls the
// core's GWNRT_HD function.
#pragma once

#include <span>
#include <string>

#include "device_model.cuh"

namespace gwnrt::cuda {

template <class In, class Fn>
__global__ void for_each_kernel(const In* in, size_t count, Fn fn) {
  const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
  if (i < count) fn(i, in[i]);
}

// fn(i, x) of for_each_kernel for a map: out[i] = map(x).
template <class In, class Out, class Map>
struct StoreMapped {
  Map map;
  Out* out;
  __device__ void operator()(size_t i, const In& x) const { out[i] = map(x); }
};

// Four events around a batch's copy up, kernel and copy down, when its timings are asked for.
class BatchEvents {
 public:
  BatchEvents(BatchTimings* timings, cudaStream_t stream) : timings_(timings), stream_(stream) {
    for (cudaEvent_t& e : events_)
      if (timings_ && cudaEventCreate(&e) != cudaSuccess) e = nullptr;
  }
  ~BatchEvents() {
    for (cudaEvent_t e : events_)
      if (e) cudaEventDestroy(e);
  }
  void record(int k) {
    if (events_[k]) cudaEventRecord(events_[k], stream_);
  }
  // After the stream has finished.
  void report() const {
    if (!timings_) return;
    float ms[3] = {0, 0, 0};
    for (int k = 0; k < 3; ++k)
      if (events_[k] && events_[k + 1]) cudaEventElapsedTime(&ms[k], events_[k], events_[k + 1]);
    *timings_ = {1e-3 * ms[0], 1e-3 * ms[1], 1e-3 * ms[2]};
  }

 private:
  BatchTimings* timings_;
  cudaStream_t stream_;
  cudaEvent_t events_[4] = {nullptr, nullptr, nullptr, nullptr};
};

// fn(i, in[i]) on the device, one thread per item, on `stream`: copies `in` up into the model's
// scratch, reserves `result_bytes` of result scratch, runs the functor make(results) returns (a
// trivially copyable functor with a __device__ call operator, writing its results there), queues
// download(results) (the copies down), and waits for the stream.
template <class In, class Make, class Download>
Status run_on_device(DeviceAccess::Buffers& buffers, std::span<const In> in, size_t result_bytes, int block, Make make,
                     Download download, cudaStream_t stream, BatchTimings* timings) {
  if (in.empty()) return Status::Ok();
  const std::lock_guard<std::mutex> lock(buffers.scratch_mutex);
  if (Status s = buffers.inputs.reserve(in.size_bytes()); !s.ok()) return s;
  if (Status s = buffers.results.reserve(result_bytes); !s.ok()) return s;
  In* d_in = static_cast<In*>(buffers.inputs.get());
  void* d_results = buffers.results.get();
  BatchEvents events(timings, stream);
  events.record(0);
  if (Status s = cuda_status(cudaMemcpyAsync(d_in, in.data(), in.size_bytes(), cudaMemcpyHostToDevice, stream),
                             "cudaMemcpy of " + std::to_string(in.size_bytes()) + " bytes to the device");
      !s.ok())
    return s;
  events.record(1);
  const unsigned grid = unsigned((in.size() + block - 1) / block);
  for_each_kernel<<<grid, block, 0, stream>>>(d_in, in.size(), make(d_results));
  if (Status s = cuda_status(cudaGetLastError(), "kernel launch"); !s.ok()) return s;
  events.record(2);
  if (Status s = download(d_results); !s.ok()) {
    cudaStreamSynchronize(stream);  // the kernel may still use the scratch the next batch gets
    return s;
  }
  events.record(3);
  if (Status s = cuda_status(cudaStreamSynchronize(stream), "kernel execution"); !s.ok()) return s;
  events.report();
  return Status::Ok();
}

// Copies `bytes` from the device to `host` on `stream`, naming the size when it fails.
inline Status copy_to_host(void* host, const void* device, size_t bytes, cudaStream_t stream) {
  return cuda_status(cudaMemcpyAsync(host, device, bytes, cudaMemcpyDeviceToHost, stream),
                     "cudaMemcpy of " + std::to_string(bytes) + " bytes to the host");
}

// out[i] = fn(in[i]) on the device (run_on_device with the results copied down whole).
template <class In, class Out, class Fn>
Status map_on_device(DeviceAccess::Buffers& buffers, std::span<const In> in, std::span<Out> out, int block, Fn fn,
                     cudaStream_t stream, BatchTimings* timings) {
  return run_on_device(
      buffers, in, out.size_bytes(), block,
      [&](void* d_out) {
        return StoreMapped<In, Out, Fn>{fn, static_cast<Out*>(d_out)};
      },
      [&](const void* d_out) { return copy_to_host(out.data(), d_out, out.size_bytes(), stream); }, stream, timings);
}

// What the batch entry points share (as the CPU drivers do, batch.cpp): `name` fails on
// validate(), then on a model never uploaded; else run(buffers), exceptions turned into Status.
template <class Validate, class Run>
Status batch_on_device(const char* name, const DeviceModel& model, size_t items, Validate validate, Run run) {
  if (Status s = validate(); !s.ok()) return s;
  if (items == 0) return Status::Ok();
  DeviceAccess::Buffers* buffers = DeviceAccess::buffers(model);
  if (!buffers) return {StatusCode::kInvalidArgument, std::string(name) + ": model not uploaded"};
  return guard_status(name, [&] { return run(*buffers); });
}

// A batch that maps: fails too when in and out differ in size; else map_on_device.
template <class In, class Out, class Validate, class Fn>
Status map_batch_on_device(const char* name, const DeviceModel& model, std::span<const In> in, std::span<Out> out,
                           int block, Validate validate, Fn fn, cudaStream_t stream, BatchTimings* timings) {
  if (in.size() != out.size())
    return {StatusCode::kInvalidArgument, std::string(name) + ": inputs and outputs differ in size"};
  return batch_on_device(name, model, in.size(), validate, [&](DeviceAccess::Buffers& buffers) {
    return map_on_device(buffers, in, out, block, fn, stream, timings);
  });
}

}  // namespace gwnrt::cuda
