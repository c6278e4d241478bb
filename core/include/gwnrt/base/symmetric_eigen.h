// The eigen-decomposition of a symmetric 3x3 matrix (the mesher's QEF, the sheets' scatter).
// Host-and-device.
#pragma once

#include "gwnrt/base/hd.h"

namespace gwnrt {

// Jacobi sweeps for the 3x3 eigen-decomposition: it converges quadratically, 2-4 sweeps reach
// double precision; the cap keeps the loop bounded.
inline constexpr int kJacobiMaxSweeps = 12;

// Eigen-decomposition of a symmetric 3x3 matrix by cyclic Jacobi rotations: a = V diag(λ) Vᵀ,
// the eigenvectors in the columns of v.
GWNRT_HD inline void symmetric_eigen(const Sym3<double>& a, double lambda[3], dvec3 v[3]) {
  double m[3][3] = {{a.xx, a.xy, a.xz}, {a.xy, a.yy, a.yz}, {a.xz, a.yz, a.zz}};
  double r[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int sweep = 0; sweep < kJacobiMaxSweeps; ++sweep) {
    const double off = m[0][1] * m[0][1] + m[0][2] * m[0][2] + m[1][2] * m[1][2];
    const double diag = m[0][0] * m[0][0] + m[1][1] * m[1][1] + m[2][2] * m[2][2];
    if (!(off > 1e-30 * diag)) break;
    for (int p = 0; p < 2; ++p)
      for (int q = p + 1; q < 3; ++q) {
        if (m[p][q] == 0.0) continue;
        // The rotation that zeroes m[p][q] (the smaller angle: Numerical Recipes' choice of t).
        const double theta = (m[q][q] - m[p][p]) / (2.0 * m[p][q]);
        const double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
        const double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
        for (int k = 0; k < 3; ++k) {  // m <- m G
          const double mkp = m[k][p], mkq = m[k][q];
          m[k][p] = c * mkp - s * mkq;
          m[k][q] = s * mkp + c * mkq;
        }
        for (int k = 0; k < 3; ++k) {  // m <- Gᵀ m
          const double mpk = m[p][k], mqk = m[q][k];
          m[p][k] = c * mpk - s * mqk;
          m[q][k] = s * mpk + c * mqk;
        }
        for (int k = 0; k < 3; ++k) {  // r <- r G
          const double rkp = r[k][p], rkq = r[k][q];
          r[k][p] = c * rkp - s * rkq;
          r[k][q] = s * rkp + c * rkq;
        }
      }
  }
  for (int i = 0; i < 3; ++i) {
    lambda[i] = m[i][i];
    v[i] = dvec3(r[0][i], r[1][i], r[2][i]);
  }
}

}  // namespace gwnrt
