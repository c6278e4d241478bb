// The dense sums of brute_force_winding.h, out of line: this file is built without the
// sanitizers and optimised even in a sanitizer build (reference/CMakeLists.txt). They are
// the checking builds' slowest code and check nothing of gwnrt's own.
#include <cmath>
#if defined(__AVX__)
#include <immintrin.h>
#endif

#include "reference/brute_force_winding.h"

namespace gwnrt::reference {

// w(x) = Σ Ω_i / 4π; Ω of one triangle is 2·atan2(a·(b×c), |a||b||c| + (a·b)|c| + (b·c)|a| + (c·a)|b|)
// with a, b, c its corners relative to x: positive behind the normal (b-a)×(c-a), so w = 1 inside
// a closed outward-oriented mesh.
double reference_w(const ReferenceMesh& r, const dvec3& x) {
#if defined(__AVX__)
  // libm's atan2 is SSE code, which runs many times slower while the upper halves of the vector
  // registers are dirty; ASan's allocator leaves them so (its 0xbe fill of each new block, in
  // zmm16 by gdb), and this loop's VEX code never clears them. Cleared here: TraceFilter's
  // bunny_holes test (7.8e8 atan2) took 227 s in the ASan build, 13.5 s with this, as in Release.
  _mm256_zeroupper();
#endif
  double omega = 0;
  for (size_t i = 0; i < r.corners.size(); i += 3) {
    const dvec3 a = r.corners[i] - x, b = r.corners[i + 1] - x, c = r.corners[i + 2] - x;
    const double la = glm::length(a), lb = glm::length(b), lc = glm::length(c);
    const double num = glm::dot(a, glm::cross(b, c));
    const double den = la * lb * lc + glm::dot(a, b) * lc + glm::dot(b, c) * la + glm::dot(c, a) * lb;
    omega += 2.0 * std::atan2(num, den);
  }
  return omega / (4.0 * kPi);
}

// ∇w(x) off the mesh: each directed edge a→b of each triangle (relative to x) contributes
// (a×b)(|a|+|b|) / (|a||b|(|a||b| + a·b)) to ∇Ω (the Biot–Savart field of the boundary loop).
dvec3 reference_gradient(const ReferenceMesh& r, const dvec3& x) {
  dvec3 g(0.0);
  auto edge = [&](const dvec3& a, const dvec3& b) {
    const double la = glm::length(a), lb = glm::length(b);
    const double den = la * lb * (la * lb + glm::dot(a, b));
    if (!(den > 0)) return;  // x on the edge's line, outside the segment: no contribution in the limit
    g += glm::cross(a, b) * ((la + lb) / den);
  };
  for (size_t i = 0; i < r.corners.size(); i += 3) {
    const dvec3 a = r.corners[i] - x, b = r.corners[i + 1] - x, c = r.corners[i + 2] - x;
    edge(a, b);
    edge(b, c);
    edge(c, a);
  }
  return g / (4.0 * kPi);
}

}  // namespace gwnrt::reference
