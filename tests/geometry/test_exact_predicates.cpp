// The exact predicates (geometry/exact_predicates.h): orient3d and orient2d on nearly coplanar
// and collinear floats against integer arithmetic, the expansion path against the filter, and the
// triangle-pair test against a separating-axis reference in integers.
#include "gwnrt/geometry/exact_predicates.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace gwnrt {
namespace {

// ---------------------------------------------------------------------------------------------
// Exact predicates

using I3 = std::array<int64_t, 3>;

I3 isub(const I3& a, const I3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
I3 icross(const I3& a, const I3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
int64_t idot(const I3& a, const I3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

vec3 to_float(const I3& p, float scale) { return vec3(float(p[0]), float(p[1]), float(p[2])) * scale; }

// The sign of det[b − a, c − a, d − a] for integer a, b, c and d = D / 2^shift, in 128-bit
// integers: with N = (b − a) × (c − a) it is that of N · D − 2^shift N · a (|N| < 2^47, so
// every term stays below 2^112).
int orient3d_int(const I3& a, const I3& b, const I3& c, const I3& d, int shift = 0) {
  const I3 n = icross(isub(b, a), isub(c, a));
  __int128 nd = 0, na = 0;
  for (int k = 0; k < 3; ++k) {
    nd += __int128(n[k]) * d[k];
    na += __int128(n[k]) * a[k];
  }
  const __int128 det = nd - na * (__int128(1) << shift);
  return det > 0 ? 1 : (det < 0 ? -1 : 0);
}

int sign_of(double x) { return x > 0 ? 1 : (x < 0 ? -1 : 0); }

TEST(ExactPredicate, Orient3dOnNearlyCoplanarFloats) {
  // Points on the plane z = n1 x + n2 y + c, then d moved off it by -1, 0 or +1 in z. Two kinds:
  //  - a, b, c, d all integers up to 2^23 (an ulp of 1 at the top): the plain double
  //    determinant rounds terms of 2^69, so for the coplanar ones its sign is noise;
  //  - the plane through the origin, a, b, c as large, d tiny (integers / 2^40) and up to an ulp
  //    off the plane: det / permanent ~ 2^-63 is beyond any double filter, so these are decided
  //    by the expansions, and nonzero.
  // Scaling every point by one power of two keeps the inputs exact and the sign.
  std::mt19937_64 g(7);
  auto uni = [&](int64_t lo, int64_t hi) { return std::uniform_int_distribution<int64_t>(lo, hi)(g); };
  int mismatched_naive[2] = {0, 0}, nonzero[2] = {0, 0};
  for (int it = 0; it < 40000; ++it) {
    const int kind = it % 2, shift = kind == 0 ? 0 : 40;
    const int64_t n1 = uni(-3, 3), n2 = uni(-3, 3), c = kind == 0 ? uni(-(1 << 20), 1 << 20) : 0;
    auto on_plane = [&](int64_t range) {
      const int64_t x = uni(-range, range), y = uni(-range, range);
      return I3{x, y, n1 * x + n2 * y + c};
    };
    const I3 a = on_plane(1 << 21), b = on_plane(1 << 21), cc = on_plane(1 << 21);
    I3 d = on_plane(kind == 0 ? 1 << 21 : 1 << 10);
    d[2] += uni(-1, 1);
    const float scale = std::ldexp(1.0f, int(uni(-40, 40)));
    const vec3 fa = to_float(a, scale), fb = to_float(b, scale), fc = to_float(cc, scale),
               fd = to_float(d, std::ldexp(scale, -shift));
    const int expected = orient3d_int(a, b, cc, d, shift);
    ASSERT_EQ(exact::orient3d(fa, fb, fc, fd), expected) << it;
    ASSERT_EQ(exact::orient3d_expansion(fa, fb, fc, fd), expected) << it;
    ASSERT_EQ(exact::orient3d(fb, fa, fc, fd), -expected) << it;
    ASSERT_EQ(exact::orient3d(fd, fa, fb, fc), -expected) << it;  // det[a − d, b − d, c − d]
    nonzero[kind] += expected != 0;
    const dvec3 u = dvec3(fb) - dvec3(fa), v = dvec3(fc) - dvec3(fa), w = dvec3(fd) - dvec3(fa);
    mismatched_naive[kind] += sign_of(glm::dot(u, glm::cross(v, w))) != expected;
  }
  for (int kind = 0; kind < 2; ++kind) {
    EXPECT_GT(nonzero[kind], 10000) << kind;
    EXPECT_GT(mismatched_naive[kind], 500) << kind;  // hard inputs: plain double gets these wrong
  }
}

TEST(ExactPredicate, Orient2dOnNearlyCollinearFloats) {
  // The same two kinds in the plane: y = n x + c; the second with c = 0, p tiny and up to an ulp
  // off the line. Reference: det·2^s = (b − a) × P − 2^s (b − a) × a in 128-bit integers.
  std::mt19937_64 g(11);
  auto uni = [&](int64_t lo, int64_t hi) { return std::uniform_int_distribution<int64_t>(lo, hi)(g); };
  int mismatched_naive = 0;
  for (int it = 0; it < 40000; ++it) {
    const int kind = it % 2, shift = kind == 0 ? 0 : 40;
    const int64_t n = uni(-5, 5), c = kind == 0 ? uni(-(1 << 20), 1 << 20) : 0;
    auto on_line = [&](int64_t range) {
      const int64_t x = uni(-range, range);
      return std::array<int64_t, 2>{x, n * x + c};
    };
    const auto a = on_line(1 << 21), b = on_line(1 << 21);
    auto p = on_line(kind == 0 ? 1 << 21 : 1 << 10);
    p[1] += uni(-1, 1);
    const int64_t ux = b[0] - a[0], uy = b[1] - a[1];
    const __int128 det = (__int128(ux) * p[1] - __int128(uy) * p[0]) -
                         (__int128(ux) * a[1] - __int128(uy) * a[0]) * (__int128(1) << shift);
    const int expected = det > 0 ? 1 : (det < 0 ? -1 : 0);
    const float s = std::ldexp(1.0f, int(uni(-40, 40))), sp = std::ldexp(s, -shift);
    const glm::vec2 fa(float(a[0]) * s, float(a[1]) * s), fb(float(b[0]) * s, float(b[1]) * s),
        fp(float(p[0]) * sp, float(p[1]) * sp);
    ASSERT_EQ(exact::orient2d(fa, fb, fp), expected) << it;
    ASSERT_EQ(exact::orient2d_expansion(fa, fb, fp), expected) << it;
    ASSERT_EQ(exact::orient2d(fb, fa, fp), -expected) << it;
    ASSERT_EQ(exact::orient2d(fp, fa, fb), expected) << it;  // an even permutation
    const double naive = (double(fb.x) - fa.x) * (double(fp.y) - fa.y) - (double(fb.y) - fa.y) * (double(fp.x) - fa.x);
    mismatched_naive += sign_of(naive) != expected;
  }
  EXPECT_GT(mismatched_naive, 1000);
}

TEST(ExactPredicate, ExpansionPathAgreesWithFilterOnWideRanges) {
  // Coordinates over many magnitudes (differences that double cannot hold: tails in the
  // expansion), where the filter decides: both paths agree.
  std::mt19937_64 g(3);
  std::uniform_real_distribution<float> mant(-1.0f, 1.0f);
  std::uniform_int_distribution<int> expo(-40, 40);
  auto rnd = [&] {
    return vec3(std::ldexp(mant(g), expo(g)), std::ldexp(mant(g), expo(g)), std::ldexp(mant(g), expo(g)));
  };
  for (int it = 0; it < 20000; ++it) {
    const vec3 a = rnd(), b = rnd(), c = rnd(), d = rnd();
    ASSERT_EQ(exact::orient3d(a, b, c, d), exact::orient3d_expansion(a, b, c, d)) << it;
    ASSERT_EQ(exact::orient3d(a, b, c, c), 0);  // repeated points
    ASSERT_EQ(exact::orient3d(a, b, a, d), 0);
  }
  // Extreme spread, exactly coplanar: all in z = 0.
  const vec3 p(3e30f, 0, 0), q(0, 1e-30f, 0), r(-1e-38f, 7e20f, 0), s(5e-20f, -3e10f, 0);
  EXPECT_EQ(exact::orient3d(p, q, r, s), 0);
  EXPECT_EQ(exact::orient3d(p, q, r, s + vec3(0, 0, 1e-45f)), exact::orient3d(p, q, r, vec3(0, 0, 1)));
  EXPECT_TRUE(exact::collinear(vec3(0), vec3(1e30f, 1e-30f, 0), vec3(2e30f, 2e-30f, 0)));
  EXPECT_FALSE(exact::collinear(vec3(0), vec3(1e30f, 1e-30f, 0), vec3(2e30f, 2e-30f, 1e-45f)));
}

// Separating-axis reference with integer coordinates: two closed convex sets given by their
// points are disjoint exactly when their projections on one of the axes are.
bool separated(const std::vector<I3>& a, const std::vector<I3>& b, const std::vector<I3>& axes) {
  for (const I3& n : axes) {
    if (n == I3{0, 0, 0}) continue;
    int64_t alo = INT64_MAX, ahi = INT64_MIN, blo = INT64_MAX, bhi = INT64_MIN;
    for (const I3& p : a) alo = std::min(alo, idot(n, p)), ahi = std::max(ahi, idot(n, p));
    for (const I3& p : b) blo = std::min(blo, idot(n, p)), bhi = std::max(bhi, idot(n, p));
    if (ahi < blo || bhi < alo) return true;
  }
  return false;
}

// Closed triangle (or segment, two points) a meets closed triangle b. The axes: the facet
// normals of a − b (the triangle normals and the edge-pair cross products) and, for a − b flat,
// the in-plane normals of its edges.
bool convex_meet(const std::vector<I3>& a, const std::array<I3, 3>& b) {
  std::vector<I3> ea, eb;
  for (size_t i = 0; i < a.size(); ++i)
    if (a.size() == 3 || i == 0) ea.push_back(isub(a[(i + 1) % a.size()], a[i]));
  for (int i = 0; i < 3; ++i) eb.push_back(isub(b[(i + 1) % 3], b[i]));
  const I3 nb = icross(eb[0], eb[1]);
  std::vector<I3> axes = {nb};
  if (a.size() == 3) axes.push_back(icross(ea[0], ea[1]));
  for (const I3& e : ea) {
    axes.push_back(icross(nb, e));
    for (const I3& f : eb) axes.push_back(icross(e, f));
  }
  for (const I3& f : eb) axes.push_back(icross(nb, f));
  return !separated(a, std::vector<I3>(b.begin(), b.end()), axes);
}

bool reference_intersect(const std::array<I3, 3>& p, const std::array<I3, 3>& q) {
  int match[3] = {-1, -1, -1}, shared = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (p[i] == q[j]) match[i] = j, ++shared;
  if (shared == 3) return true;
  if (shared == 0) return convex_meet({p[0], p[1], p[2]}, q);
  if (shared == 1) {
    const int i0 = match[0] >= 0 ? 0 : (match[1] >= 0 ? 1 : 2), j0 = match[i0];
    return convex_meet({p[(i0 + 1) % 3], p[(i0 + 2) % 3]}, q) || convex_meet({q[(j0 + 1) % 3], q[(j0 + 2) % 3]}, p);
  }
  const int i2 = match[0] < 0 ? 0 : (match[1] < 0 ? 1 : 2);
  const int j2 = 3 - match[(i2 + 1) % 3] - match[(i2 + 2) % 3];
  const I3 e = isub(p[(i2 + 2) % 3], p[(i2 + 1) % 3]);
  const I3 np = icross(e, isub(p[i2], p[(i2 + 1) % 3])), nq = icross(e, isub(q[j2], p[(i2 + 1) % 3]));
  return icross(np, nq) == I3{0, 0, 0} && idot(np, nq) > 0;  // coplanar, third vertices on one side
}

TEST(ExactPredicate, TrianglePairsMatchSeparatingAxisReference) {
  // Triangles on a small grid share vertices, edges and planes all the time; an offset of 2^22
  // keeps the coordinates float-exact and the double differences exact.
  std::mt19937_64 g(5);
  std::uniform_int_distribution<int64_t> coord(0, 2);
  const float offset = 4194304.0f;
  int checked = 0, met = 0;
  int by_shared[4] = {0, 0, 0, 0};
  for (int it = 0; it < 40000; ++it) {
    std::array<I3, 3> p, q;
    for (auto& v : p) v = {coord(g), coord(g), coord(g)};
    for (auto& v : q) v = {coord(g), coord(g), coord(g)};
    if (g() % 2) q[0] = p[g() % 3];  // shared vertices more often
    if (g() % 3 == 0) q[1] = p[1 + g() % 2];
    if (icross(isub(p[1], p[0]), isub(p[2], p[0])) == I3{0, 0, 0}) continue;
    if (icross(isub(q[1], q[0]), isub(q[2], q[0])) == I3{0, 0, 0}) continue;
    exact::Triangle fp, fq;
    for (int k = 0; k < 3; ++k) {
      fp[k] = to_float(p[k], 1.0f) + vec3(offset);
      fq[k] = to_float(q[k], 1.0f) + vec3(offset);
    }
    const bool expected = reference_intersect(p, q);
    int shared = 0;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) shared += p[i] == q[j];
    ++by_shared[shared];
    ASSERT_EQ(exact::triangles_intersect(fp, fq), expected) << it << " shared " << shared;
    // Whatever order the vertices and the triangles come in.
    exact::Triangle rp = {fp[1], fp[2], fp[0]}, rq = {fq[2], fq[1], fq[0]};
    ASSERT_EQ(exact::triangles_intersect(rq, rp), expected) << it;
    ++checked;
    met += expected;
  }
  EXPECT_GT(checked, 20000);
  EXPECT_GT(met, 2000);
  EXPECT_GT(checked - met, 2000);
  for (int s = 0; s < 4; ++s) EXPECT_GT(by_shared[s], 100) << s;
}

// The quick filter before the pair test: whenever it says apart, the exact test agrees, on
// exactly coplanar grids and on the same grids with every coordinate nudged by a few ulps (the
// nearly coplanar pairs of a flat region, which the filter decides in projection); and it decides
// most of the pairs that do not meet.
TEST(ExactPredicate, ApartFilterNeverHidesAnIntersection) {
  std::mt19937_64 g(11);
  std::uniform_int_distribution<int64_t> coord(0, 2);
  std::uniform_int_distribution<int> nudge(-3, 3);
  int apart = 0, disjoint = 0, met = 0;
  for (int it = 0; it < 40000; ++it) {
    std::array<I3, 3> p, q;
    for (auto& v : p) v = {coord(g), coord(g), coord(g)};
    for (auto& v : q) v = {coord(g), coord(g), coord(g)};
    if (g() % 2) q[0] = p[g() % 3];
    if (g() % 3 == 0) q[1] = p[1 + g() % 2];
    exact::Triangle fp, fq;
    const bool nudged = it % 2 == 1;
    for (int k = 0; k < 3; ++k) {
      fp[k] = to_float(p[k], 0.25f) + vec3(3.0f);
      fq[k] = to_float(q[k], 0.25f) + vec3(3.0f);
    }
    if (nudged)  // shared positions stay shared: nudge each distinct position once
      for (int k = 0; k < 3; ++k) {
        const vec3 before = fp[k];
        for (int a = 0; a < 3; ++a) fp[k][a] = std::nextafter(fp[k][a], nudge(g) > 0 ? 10.0f : 0.0f);
        for (int j = 0; j < 3; ++j)
          if (fq[j] == before) fq[j] = fp[k];
      }
    if (exact::collinear(fp[0], fp[1], fp[2]) || exact::collinear(fq[0], fq[1], fq[2])) continue;
    const bool meet = exact::triangles_of_nonzero_area_intersect(fp, fq);
    const bool filtered = exact::apart_beyond_shared(fp, exact::PlaneFilter(fp), fq, exact::PlaneFilter(fq));
    ASSERT_FALSE(filtered && meet) << it;
    met += meet;
    disjoint += !meet;
    apart += filtered;
  }
  EXPECT_GT(met, 2000);
  EXPECT_GT(apart, disjoint / 2) << "of " << disjoint << " pairs that do not meet";
}

// PlaneFilter::side, where it decides, is orient3d: on random points, and on points of the
// triangle's plane (integer combinations of its edges: exactly coplanar) and an ulp off it, which
// it leaves undecided (orient3d decides them by expansion).
TEST(ExactPredicate, PlaneFilterSideIsOrient3dWhereDecided) {
  std::mt19937_64 g(13);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::uniform_int_distribution<int> small(-20, 20);
  int decided = 0, undecided = 0;
  for (int it = 0; it < 20000; ++it) {
    const auto grid_point = [&] { return vec3(float(small(g)), float(small(g)), float(small(g))); };
    exact::Triangle t;
    vec3 x;
    if (it % 2 == 0) {
      t = {vec3(u(g), u(g), u(g)), vec3(u(g), u(g), u(g)), vec3(u(g), u(g), u(g))};
      x = vec3(u(g), u(g), u(g));
    } else {
      t = {grid_point(), grid_point(), grid_point()};
      const float a = float(small(g)), b = float(small(g));
      x = t[0] + a * (t[1] - t[0]) + b * (t[2] - t[0]);  // exact: small integers
      if (it % 4 == 1) x.x = std::nextafter(x.x, 1e9f);
    }
    const int side = exact::PlaneFilter(t).side(x);
    if (side == exact::kUndecided) {
      ++undecided;
      continue;
    }
    ++decided;
    ASSERT_EQ(side, exact::orient3d(t[0], t[1], t[2], x)) << it;
  }
  EXPECT_GT(decided, 10000);
  EXPECT_GT(undecided, 1000);
}
}  // namespace
}  // namespace gwnrt
