// The quadric error function of dual contouring (meshing/qef.h) on configurations whose vertex is
// known: three planes, a crease, near-parallel normals, the clamp to the cell; and the symmetric
// eigendecomposition it rests on.
#include <cmath>
#include <random>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "gwnrt/base/symmetric_eigen.h"
#include "gwnrt/meshing/qef.h"

namespace gwnrt {
namespace {

// ---------------------------------------------------------------------------------------------
// The QEF on known configurations.

dvec3 solve_planes(const std::vector<std::pair<dvec3, dvec3>>& planes, const dvec3& lo = dvec3(0.0),
                   const dvec3& hi = dvec3(1.0)) {
  Qef q;
  for (const auto& [p, n] : planes) q.add(p, glm::normalize(n));
  return solve_qef(q, lo, hi);
}

TEST(MeshingQef, ThreePlanesMeetAtTheCorner) {
  const dvec3 corner(0.3, 0.6, 0.45);
  const dvec3 x = solve_planes({{corner + dvec3(0, 0.2, 0.1), {1, 0, 0}},
                                {corner + dvec3(0.3, 0, -0.2), {0, 1, 0}},
                                {corner + dvec3(-0.1, 0.3, 0), {0, 0, 1}},
                                {corner + dvec3(0, -0.3, 0.2), {1, 0, 0}}});
  EXPECT_NEAR(glm::length(x - corner), 0.0, 1e-9);
}

TEST(MeshingQef, TwoPlanesGiveTheCreaseNearestTheMassPoint) {
  // Planes x = 0.5 and y = 0.4 (crease along z); the points' mean z is 0.3.
  const dvec3 x = solve_planes({{{0.5, 0.1, 0.2}, {1, 0, 0}},
                                {{0.5, 0.9, 0.4}, {1, 0, 0}},
                                {{0.2, 0.4, 0.1}, {0, 1, 0}},
                                {{0.8, 0.4, 0.5}, {0, 1, 0}}});
  EXPECT_NEAR(x.x, 0.5, 1e-9);
  EXPECT_NEAR(x.y, 0.4, 1e-9);
  EXPECT_NEAR(x.z, 0.3, 1e-9);
}

TEST(MeshingQef, NearParallelNormalsStayNearTheMassPoint) {
  // A gently curved patch: two points at z = 0.5 with normals tilted 1 and 2 degrees. Their
  // planes meet at x = 1.4, far outside the cell; the full solve would go there (clamped to the
  // face x = 1). Truncated, the nearly free direction is left at the mass point: the vertex
  // moves only along the normals, by their planes' mean offset (about 0.003).
  const double a = 1.0 * kPi / 180.0, b = 2.0 * kPi / 180.0;
  const dvec3 x = solve_planes(
      {{{0.2, 0.5, 0.5}, {std::sin(a), 0, std::cos(a)}}, {{0.8, 0.5, 0.5}, {std::sin(b), 0, std::cos(b)}}});
  EXPECT_NEAR(x.x, 0.5, 1e-3);
  EXPECT_NEAR(x.y, 0.5, 1e-12);
  EXPECT_NEAR(x.z, 0.5, 5e-3);
}

TEST(MeshingQef, ParallelPlanesAndOnePointAndTheClamp) {
  // Two parallel planes z = 0.2 and z = 0.6 (one component cannot hold both, but the solve must
  // stay finite): between them, at the mass point's x, y.
  const dvec3 x = solve_planes({{{0.2, 0.3, 0.2}, {0, 0, 1}}, {{0.6, 0.5, 0.6}, {0, 0, 1}}});
  EXPECT_NEAR(x.x, 0.4, 1e-9);
  EXPECT_NEAR(x.y, 0.4, 1e-9);
  EXPECT_NEAR(x.z, 0.4, 1e-9);
  const dvec3 one = solve_planes({{{0.7, 0.1, 0.9}, {0, 1, 0}}});
  EXPECT_NEAR(glm::length(one - dvec3(0.7, 0.1, 0.9)), 0.0, 1e-12);
  // Planes meeting at (2, 0.5, 0.5), outside the cell: clamped into it.
  const dvec3 c =
      solve_planes({{{0.0, 0.5, 0.5}, {1, 1, 0}}, {{0.0, 0.5, 0.5}, {1, -1, 0}}, {{0.5, 0.5, 0.5}, {0, 0, 1}}});
  EXPECT_GE(c.x, 0.0);
  EXPECT_LE(c.x, 1.0);
}

TEST(MeshingQef, ACreaseLeavingTheCellIsFollowedInsideIt) {
  // Planes y = x + 0.9 and z = 0.5: their crease cuts the cell's corner near (0, 1), from (0, 0.9)
  // to (0.1, 1). The mass point (0.5, 0.85, 0.5) projects onto it at (0.275, 1.175), outside;
  // clamping would leave the vertex 0.25 off the crease; following the crease gives its end in
  // the cell nearest that projection.
  const double s = std::sqrt(0.5);
  const dvec3 x = solve_planes({{{0.05, 0.95, 0.3}, {s, -s, 0}},
                                {{0.05, 0.95, 0.7}, {s, -s, 0}},
                                {{1.0, 0.5, 0.5}, {0, 0, 1}},
                                {{0.9, 1.0, 0.5}, {0, 0, 1}}});
  EXPECT_NEAR(glm::length(x - dvec3(0.1, 1.0, 0.5)), 0.0, 1e-9);
}

TEST(MeshingQef, EigenDecompositionReconstructsTheMatrix) {
  std::mt19937 g(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int k = 0; k < 100; ++k) {
    const Sym3<double> a{u(g), u(g), u(g), u(g), u(g), u(g)};
    double lambda[3];
    dvec3 v[3];
    symmetric_eigen(a, lambda, v);
    for (int i = 0; i < 3; ++i) {
      const dvec3 av = a.apply(v[i]);
      EXPECT_NEAR(glm::length(av - lambda[i] * v[i]), 0.0, 1e-10);
      EXPECT_NEAR(glm::length(v[i]), 1.0, 1e-12);
    }
  }
}

}  // namespace
}  // namespace gwnrt
