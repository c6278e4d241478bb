// What the bindings share: numpy arrays in (checked shapes; float32 C-contiguous used in place,
// others converted once) and out (allocated by numpy, or adopting a std::vector's buffer), Status
// turned into a Python exception, and a batch run with the GIL released on `threads` TBB workers.
#pragma once

#include <climits>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <tbb/task_arena.h>

#include "gwnrt/base/hd.h"
#include "gwnrt/base/option_limits.h"
#include "gwnrt/base/status.h"

namespace gwnrt::python {

namespace py = pybind11;

using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;

// The exception a failed Status becomes, with its message: ValueError for bad input (arguments,
// file contents, meshes), OSError for files that cannot be read or written, MemoryError for
// allocations, RuntimeError otherwise.
[[noreturn]] void raise_status(const Status& status);
inline void check(const Status& status) {
  if (!status.ok()) raise_status(status);
}

// `obj` as float32 rows of `width` values ((k, width); (k,) when width is 1): used in place when
// it is a C-contiguous float32 array, else converted once (a list, float64, a strided view). An
// empty sequence is 0 rows. `name` names the argument in the error.
FloatArray float_rows(const py::handle& obj, const char* name, py::ssize_t width);

// `obj` as triangles: an integer array of shape (m, 3) whose indices lie in [0, vertex_count)
// (ValueError naming the face otherwise).
std::vector<uvec3> face_rows(const py::handle& obj, size_t vertex_count);

// `obj` as the source triangle of each vertex: an integer array of shape (m,) of 32-bit indices
// (ValueError naming the entry otherwise).
std::vector<uint32_t> source_triangle_rows(const py::handle& obj);

inline std::span<const vec3> as_vec3(const FloatArray& rows) {
  return {reinterpret_cast<const vec3*>(rows.data()), size_t(rows.shape(0))};
}

// A new C-contiguous array of `rows` rows of the given trailing shape.
template <class T>
py::array_t<T> new_rows(size_t rows, std::vector<py::ssize_t> trailing = {}) {
  trailing.insert(trailing.begin(), py::ssize_t(rows));
  return py::array_t<T>(trailing);
}

// An array over v's buffer, which it takes over (no copy): rows of `width` values of type T.
template <class T, class V>
py::array adopt_rows(std::vector<V>&& v, py::ssize_t width) {
  static_assert(sizeof(V) % sizeof(T) == 0);
  auto* owner = new std::vector<V>(std::move(v));
  py::capsule base(owner, [](void* p) { delete static_cast<std::vector<V>*>(p); });
  const py::ssize_t rows = py::ssize_t(owner->size() * sizeof(V) / sizeof(T)) / width;
  std::vector<py::ssize_t> shape{rows};
  if (width > 1) shape.push_back(width);
  return py::array_t<T>(shape, reinterpret_cast<const T*>(owner->data()), base);
}

// An integer argument as T when it lies in [lo, hi], else ValueError naming it (taken as int64
// and checked here: pybind11 would answer a negative number for an unsigned parameter with a
// TypeError and its signatures).
template <class T>
T checked_integer(int64_t value, const char* name, T lo = std::numeric_limits<T>::lowest(),
                  T hi = std::numeric_limits<T>::max()) {
  if (value < int64_t(lo) || (value > 0 && uint64_t(value) > uint64_t(hi)))
    throw py::value_error(std::string(name) + " must lie in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                          "], got " + std::to_string(value));
  return T(value);
}

// TBB workers for a call: None or 0 for all cores.
using Threads = std::optional<int64_t>;

// Runs fn with the GIL released, on at most `threads` TBB workers when given (> 0; 0 or None:
// all cores). Throws ValueError for a count outside [0, kMaxThreads].
template <class Fn>
auto run_released(Threads threads, Fn&& fn) {
  const int workers = threads ? checked_integer<int>(*threads, "threads", 0, int(kMaxThreads)) : 0;
  py::gil_scoped_release release;
  if (workers > 0) {
    tbb::task_arena arena(workers);
    return arena.execute(std::forward<Fn>(fn));
  }
  return fn();
}

}  // namespace gwnrt::python
