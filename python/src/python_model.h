// The model the Python module holds: an Engine (the GwnModel, and its GPU copy made on the first
// device="cuda" call), and the lock that keeps set_sheet_level apart from running batches
// (Engine::set_sheet_level is not thread-safe with them, and Python threads may call both).
#pragma once

#include <memory>
#include <shared_mutex>
#include <string>

#include "gwnrt/engine.h"
#include "numpy_arrays.h"

namespace gwnrt::python {

struct PythonModel {
  Engine engine;
  mutable std::shared_mutex level_mutex;

  const GwnModel& model() const { return engine.model(); }
};

// Where `device` ("cpu", "cuda" or "auto") runs: kCpu or kCuda; ValueError for another name,
// RuntimeError for "cuda" without a usable GPU (saying why). "auto" takes the GPU when usable.
Device device_argument(const std::string& device);

// `level`, or for a request without one the sheets' level, else 1/2. Call holding level_mutex
// (shared) for as long as the level is used.
float level_or_default(const PythonModel& p, std::optional<float> level);

// WindingMethod by winding_method_name; ValueError for another name.
WindingMethod winding_method_argument(const std::string& name);

void bind_model(py::module_& m);
void bind_queries(py::module_& m);
void bind_meshing(py::module_& m);

}  // namespace gwnrt::python
