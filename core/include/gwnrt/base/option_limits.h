// The ranges of numeric options that the programs, the Python module and the C API share,
// checked where each is given (docs/programs.md lists them with the others').
#pragma once

#include <cstdint>
#include <limits>

namespace gwnrt {

// Worker threads: 0 (or none given) for all cores, else at most this many. TBB makes a thread
// and a stack for each worker it is allowed: ten million asked for took 1.3 GB, and 2^31 − 1
// crashed inside TBB.
inline constexpr int64_t kMaxThreads = 1024;

// The multipole accuracy scale beta: a cluster is expanded only beyond beta times its radius,
// where its series converges; below 1 that is inside its own ball (beta 0.1 gave w 0.35 where the
// exact is −0.019, and traced the wrong hit). Finite, as a float.
inline constexpr float kMinBeta = 1.0f;
inline bool beta_valid(float beta) { return beta >= kMinBeta && beta <= std::numeric_limits<float>::max(); }

}  // namespace gwnrt
