// fn(i) for every i in [0, n), in parallel over TBB (grain: indices per task).
#pragma once

#include <cstddef>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace gwnrt::reference {

template <class Fn>
void parallel_over(size_t n, Fn fn, size_t grain = 16) {
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, grain), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) fn(i);
  });
}

}  // namespace gwnrt::reference
