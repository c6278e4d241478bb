// The raw moments of triangle clusters while a tree is built (in double), and their compressed
// form per lane (multipole.h): shared by the triangle trees and the ribbon tree's fans.
#pragma once

#include <algorithm>
#include <cmath>

#include "gwnrt/geometry/bvh.h"

namespace gwnrt {

// Raw moments of a cluster about its own centre, in double while the tree is built.
struct RawMoments {
  dvec3 centre{0.0};
  double area = 0;
  double radius = 0;
  dvec3 n{0.0};
  double n1[3][3] = {};     // N_αj
  double n2[3][3][3] = {};  // N_αjk

  // Moves the expansion centre to c (parallel-axis shift of the first and second moments).
  void shift_to(const dvec3& c) {
    const dvec3 delta = centre - c;
    for (int a = 0; a < 3; ++a)
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k)
          n2[a][j][k] += n1[a][j] * delta[k] + n1[a][k] * delta[j] + n[a] * delta[j] * delta[k];
    for (int a = 0; a < 3; ++a)
      for (int j = 0; j < 3; ++j) n1[a][j] += n[a] * delta[j];
    centre = c;
  }
  void add(const RawMoments& o) {  // o must already be about the same centre
    area += o.area;
    n += o.n;
    for (int a = 0; a < 3; ++a)
      for (int j = 0; j < 3; ++j) {
        n1[a][j] += o.n1[a][j];
        for (int k = 0; k < 3; ++k) n2[a][j][k] += o.n2[a][j][k];
      }
  }
};

// Exact moments of one triangle about centre c: ∫ s s dA = A (g gᵀ + Σ_i e_i e_iᵀ / 12),
// g = centroid - c, e_i = p_i - centroid.
inline void add_triangle_moments(const dvec3 p[3], const dvec3& c, RawMoments& m) {
  const dvec3 area_normal = 0.5 * glm::cross(p[1] - p[0], p[2] - p[0]);
  const double area = glm::length(area_normal);
  m.area += area;
  m.n += area_normal;
  if (area == 0) return;
  const dvec3 centroid = (p[0] + p[1] + p[2]) / 3.0;
  const dvec3 g = centroid - c;
  const dvec3 e[3] = {p[0] - centroid, p[1] - centroid, p[2] - centroid};
  for (int j = 0; j < 3; ++j)
    for (int k = 0; k < 3; ++k) {
      const double second = g[j] * g[k] + (e[0][j] * e[0][k] + e[1][j] * e[1][k] + e[2][j] * e[2][k]) / 12.0;
      for (int a = 0; a < 3; ++a) m.n2[a][j][k] += area_normal[a] * second;
    }
  for (int a = 0; a < 3; ++a)
    for (int j = 0; j < 3; ++j) m.n1[a][j] += area_normal[a] * g[j];
}

// Radii are computed about the exact (double) centre. The tree stores the centre in float,
// which moves it by at most half an ulp per coordinate; widening the ball by one ulp of the
// largest coordinate and rounding up keeps every point of the cluster inside the stored ball.
inline float stored_radius(double r, const dvec3& centre) {
  const float largest = float(std::max({std::abs(centre.x), std::abs(centre.y), std::abs(centre.z)}));
  const double centre_ulp = double(std::nextafter(largest, INFINITY)) - double(largest);
  return std::nextafter(float(r + centre_ulp), INFINITY);
}

// Farthest corner of a lane's box from c.
inline double farthest_corner(const WideNode& node, int lane, const dvec3& c) {
  double d2 = 0;
  for (int a = 0; a < 3; ++a) d2 += std::max(sqr(node.lo[a][lane] - c[a]), sqr(node.hi[a][lane] - c[a]));
  return std::sqrt(d2);
}

// Stores m compressed as lane i of a node's expansion (centre, radius, moments).
inline void store_lane_moments(const RawMoments& m, int i, WideNodeExpansion& ex, WideNodeOrder1& o1,
                               WideNodeOrder2& o2) {
  for (int a = 0; a < 3; ++a) {
    ex.centre[a][i] = float(m.centre[a]);
    ex.n[a][i] = float(m.n[a]);
  }
  ex.radius[i] = stored_radius(m.radius, m.centre);
  const auto& n1 = m.n1;
  const double s[6] = {2 * n1[0][0], n1[0][1] + n1[1][0], n1[0][2] + n1[2][0],
                       2 * n1[1][1], n1[1][2] + n1[2][1], 2 * n1[2][2]};
  for (int k = 0; k < 6; ++k) o1.s[k][i] = float(s[k]);
  const auto& n2 = m.n2;
  auto sym = [&](int a, int j, int k) { return (n2[a][j][k] + n2[j][a][k] + n2[k][a][j]) / 3.0; };
  const int idx[10][3] = {{0, 0, 0}, {0, 0, 1}, {0, 0, 2}, {0, 1, 1}, {0, 1, 2},
                          {0, 2, 2}, {1, 1, 1}, {1, 1, 2}, {1, 2, 2}, {2, 2, 2}};
  for (int k = 0; k < 10; ++k) o2.p[k][i] = float(sym(idx[k][0], idx[k][1], idx[k][2]));
  for (int a = 0; a < 3; ++a) {
    const double e = 2 * (n2[0][0][a] + n2[1][1][a] + n2[2][2][a]) + (n2[a][0][0] + n2[a][1][1] + n2[a][2][2]);
    o2.e[a][i] = float(e);
  }
}

}  // namespace gwnrt
