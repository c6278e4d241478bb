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

// out[i] = fn(in[i]) on the device, one thread per item, on `stream`: copies `in` up into the
// model's scratch, runs, copies `out` down, and waits for the stream. Fn is a trivially
// copyable functor with a __device__ call operator.
template <class In, class Out, class Fn>
Status map_on_device(DeviceAccess::Buffers& buffers, std::span<const In> in, std::span<Out> out, int block, Fn fn,
                     cudaStream_t stream, BatchTimings* timings) {
  if (in.empty()) return Status::Ok();
  const std::lock_guard<std::mutex> lock(buffers.scratch_mutex);
  if (Status s = buffers.inputs.reserve(in.size_bytes()); !s.ok()) return s;
  if (Status s = buffers.results.reserve(out.size_bytes()); !s.ok()) return s;
  In* d_in = static_cast<In*>(buffers.inputs.get());
  Out* d_out = static_cast<Out*>(buffers.results.get());
  BatchEvents events(timings, stream);
  events.record(0);
  if (Status s = cuda_status(cudaMemcpyAsync(d_in, in.data(), in.size_bytes(), cudaMemcpyHostToDevice, stream),
                             "cudaMemcpy of " + std::to_string(in.size_bytes()) + " bytes to the device");
      !s.ok())
    return s;
  events.record(1);
  const unsigned grid = unsigned((in.size() + block - 1) / block);
  map_kernel<<<grid, block, 0, stream>>>(d_in, in.size(), fn, d_out);
  if (Status s = cuda_status(cudaGetLastError(), "kernel launch"); !s.ok()) return s;
  events.record(2);
  if (Status s = cuda_status(cudaMemcpyAsync(out.data(), d_out, out.size_bytes(), cudaMemcpyDeviceToHost, stream),
                             "cudaMemcpy of " + std::to_string(out.size_bytes()) + " bytes to the host");
      !s.ok())
    return s;
  events.record(3);
  if (Status s = cuda_status(cudaStreamSynchronize(stream), "kernel execution"); !s.ok()) return s;
  events.report();
  return Status::Ok();
}

// What the batch entry points share (as the CPU drivers do, batch.cpp): `name` fails when in and
// out differ in size, then on validate(), then on a model never uploaded; else map_on_device.
template <class In, class Out, class Validate, class Fn>
Status map_batch_on_device(const char* name, const DeviceModel& model, std::span<const In> in, std::span<Out> out,
                           int block, Validate validate, Fn fn, cudaStream_t stream, BatchTimings* timings) {
  if (in.size() != out.size())
    return {StatusCode::kInvalidArgument, std::string(name) + ": inputs and outputs differ in size"};
  if (Status s = validate(); !s.ok()) return s;
  if (in.empty()) return Status::Ok();
  DeviceAccess::Buffers* buffers = DeviceAccess::buffers(model);
  if (!buffers) return {StatusCode::kInvalidArgument, std::string(name) + ": model not uploaded"};
  return guard_status(name, [&] { return map_on_device(*buffers, in, out, block, fn, stream, timings); });
}

}  // namespace gwnrt::cuda
