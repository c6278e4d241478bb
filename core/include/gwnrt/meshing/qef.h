// Where a cell's vertex is solved: the quadratic error function of dual contouring, Σ (n_i ·
// (x − p_i))² over a component's Hermite points p_i and unit normals n_i, minimised robustly.
// Host-and-device.
#pragma once

#include "gwnrt/base/hd.h"
#include "gwnrt/base/symmetric_eigen.h"

namespace gwnrt {

// Directions whose eigenvalue of AᵀA is below this fraction of the largest are left to the
// mass point (a truncated pseudo-inverse): near-parallel normals (a flat or gently curved
// patch) then put the vertex on the plane at the points' centre instead of far along the
// nearly free direction. 0.1 is the usual truncation of dual contouring's SVD (Ju et al.;
// Lindstrom's QEF): a crease whose two planes meet at 18° or more keeps its sharp direction.
inline constexpr double kQefTruncation = 0.1;
struct Qef {
  Sym3<double> ata;       // Σ n nᵀ
  dvec3 atb{0.0};         // Σ n (n · p)
  dvec3 point_sum{0.0};   // Σ p
  dvec3 normal_sum{0.0};  // Σ n
  int count = 0;

  GWNRT_HD void add(const dvec3& p, const dvec3& n) {
    ata += Sym3<double>{n.x * n.x, n.x * n.y, n.x * n.z, n.y * n.y, n.y * n.z, n.z * n.z};
    atb += n * glm::dot(n, p);
    point_sum += p;
    normal_sum += n;
    ++count;
  }
  GWNRT_HD dvec3 mass_point() const { return count > 0 ? point_sum / double(count) : dvec3(0.0); }
};

namespace detail {

// The parameters [t0, t1] for which x + t d lies in [lo, hi]; false when the line misses it.
GWNRT_HD inline bool clip_line_to_box(const dvec3& x, const dvec3& d, const dvec3& lo, const dvec3& hi, double& t0,
                                      double& t1) {
  t0 = -1e300;
  t1 = 1e300;
  for (int a = 0; a < 3; ++a) {
    if (fabs(d[a]) < 1e-12) {
      if (x[a] < lo[a] || x[a] > hi[a]) return false;
      continue;
    }
    double ta = (lo[a] - x[a]) / d[a], tb = (hi[a] - x[a]) / d[a];
    if (ta > tb) {
      const double t = ta;
      ta = tb;
      tb = t;
    }
    t0 = fmax(t0, ta);
    t1 = fmin(t1, tb);
  }
  return t0 <= t1;
}

}  // namespace detail

// The minimiser nearest the mass point m̄ in the retained directions: x = m̄ + Σ_i v_i (v_iᵀ(b −
// A m̄)) / λ_i over the eigenvalues λ_i >= kQefTruncation · λ_max, kept in [lo, hi] (the cell).
// A component of one Hermite point (or parallel normals) stays at its mass point along the
// free directions. When x leaves the cell, a crease is kept before the cell's box is: with two
// retained directions x slides along the crease line (where the error stays minimal) to the
// nearest point inside; with three (a corner outside the cell), the crease of the two strongest
// planes is taken, at its point nearest the corner. Only a line that misses the cell is clamped.
// This puts the vertex of every cell a sharp edge passes through on the edge, where clamping
// leaves it off. Letting the vertex follow the crease out of its cell would also bring the cells
// the edge passes just outside of onto it, but makes the output self-intersect, so the cell
// bounds the vertex (docs/performance.md, meshing).
GWNRT_HD inline dvec3 solve_qef(const Qef& q, const dvec3& lo, const dvec3& hi) {
  const dvec3 mass = q.mass_point();
  double lambda[3];
  dvec3 v[3];
  symmetric_eigen(q.ata, lambda, v);
  const double largest = fmax(lambda[0], fmax(lambda[1], lambda[2]));
  const dvec3 residual = q.atb - q.ata.apply(mass);
  dvec3 step[3] = {dvec3(0.0), dvec3(0.0), dvec3(0.0)};
  int retained = 0, weakest = -1, free_direction = -1;
  for (int i = 0; i < 3; ++i) {
    if (largest > 0 && lambda[i] >= kQefTruncation * largest) {
      step[i] = v[i] * (glm::dot(v[i], residual) / lambda[i]);
      ++retained;
      if (weakest < 0 || lambda[i] < lambda[weakest]) weakest = i;
    } else {
      free_direction = i;
    }
  }
  const dvec3 x = mass + step[0] + step[1] + step[2];
  const auto inside = [&](const dvec3& p) {
    return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z && p.z <= hi.z;
  };
  if (inside(x) || retained < 2) return glm::clamp(x, lo, hi);
  // The crease line: through x along the free direction (two retained), or through the point of
  // the two strongest planes along the weakest one's direction (three retained).
  const int along = retained == 2 ? free_direction : weakest;
  const dvec3 base = retained == 2 ? x : x - step[weakest];
  const double wanted = retained == 2 ? 0.0 : glm::dot(x - base, v[along]);
  double t0, t1;
  if (!detail::clip_line_to_box(base, v[along], lo, hi, t0, t1)) return glm::clamp(x, lo, hi);
  return glm::clamp(base + v[along] * fmin(fmax(wanted, t0), t1), lo, hi);
}

}  // namespace gwnrt
