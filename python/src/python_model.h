// The model the Python module holds: a GwnModel, the lock that keeps set_sheet_level apart from
// running batches (GwnModel::set_sheet_level is not thread-safe with queries, and Python threads
// may call both), and, with the CUDA backend, the device copy made on the first device="cuda" call.
#pragma once

#include <memory>
#include <mutex>
#include <shared_mutex>
#include <string>

#include "gwnrt/model/model.h"
#include "numpy_arrays.h"

#if defined(GWNRT_HAVE_CUDA)
#include "gwnrt/cuda.h"
#endif

namespace gwnrt::python {

struct PythonModel {
  GwnModel model;
  mutable std::shared_mutex level_mutex;
#if defined(GWNRT_HAVE_CUDA)
  mutable std::mutex device_mutex;
  mutable std::unique_ptr<cuda::DeviceModel> device;
  // The device copy, uploaded once (every part built first); call without the GIL.
  Status device_model(const cuda::DeviceModel*& out) const;
#endif
};

// Whether the CUDA backend is built in and a GPU usable; `why` says what is missing otherwise.
bool cuda_usable(std::string& why);

// Whether `device` ("cpu", "cuda" or "auto") runs on the GPU; ValueError for another name,
// RuntimeError for "cuda" without a usable GPU (saying why). "auto" takes the GPU when usable.
bool use_cuda(const std::string& device);

// `level`, or for a request without one the sheets' level, else 1/2. Call holding level_mutex
// (shared) for as long as the level is used.
float level_or_default(const PythonModel& p, std::optional<float> level);

// WindingMethod by winding_method_name; ValueError for another name.
WindingMethod winding_method_argument(const std::string& name);

void bind_model(py::module_& m);
void bind_queries(py::module_& m);
void bind_meshing(py::module_& m);

}  // namespace gwnrt::python
