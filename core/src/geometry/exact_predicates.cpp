// Exact orientation predicates on float coordinates, and the triangle-pair test of the
// self-intersection count built on them (gwnrt/geometry/exact_predicates.h).
//
// Each predicate is first evaluated in double with a forward error bound (Shewchuk's bounds for
// the plain evaluation, rounded up); only when the result is within the bound of 0 (coplanar
// neighbours of a flat region: every call there) is the determinant computed exactly, as an
// expansion: a sum of doubles in increasing magnitude that do not overlap, whose sign is that of
// its largest component (Shewchuk, "Adaptive precision floating-point arithmetic and fast robust
// geometric predicates", 1997, §2). Float inputs keep that exact: a float difference is a
// two-component expansion, and products of three of them lie between 2^-447 and 2^387, far from
// double's underflow and overflow, so every error term below is itself a double.
//
// The expansion sum below relies on round-to-nearest-even (the default everywhere gwnrt runs).
// GCC contracts a * b + c into one fma by default in C++: the expansions multiply only inside
// two_product, whose error term is an explicit fma, and in the filters a contraction drops a
// rounding, which the bounds (one relative error ε per operation, at most) still cover.
#include <cmath>

#include "gwnrt/geometry/exact_predicates.h"

namespace gwnrt::exact {
namespace {

constexpr double kEpsilon = 0x1p-53;  // the relative error of one rounding
// |computed − exact| <= bound × permanent for the plain evaluations below. Shewchuk's bounds are
// (3 + 16ε)ε (orient2d) and (7 + 56ε)ε (orient3d); these round them up, which also covers the
// rounding of the permanent itself (at most 5 roundings, (1 − ε)^5 > 7/8).
constexpr double kOrient2dBound = 4.0 * kEpsilon;
constexpr double kOrient3dBound = 8.0 * kEpsilon;

// ---- Error-free transformations: a op b = x + y exactly, x the rounded result.

inline void two_sum(double a, double b, double& x, double& y) {
  x = a + b;
  const double bv = x - a, av = x - bv;
  y = (a - av) + (b - bv);
}

inline void fast_two_sum(double a, double b, double& x, double& y) {  // |a| >= |b| (or a == 0)
  x = a + b;
  y = b - (x - a);
}

inline void two_diff(double a, double b, double& x, double& y) {
  x = a - b;
  const double bv = a - x, av = x + bv;
  y = (a - av) + (bv - b);
}

inline void two_product(double a, double b, double& x, double& y) {
  x = a * b;
  y = std::fma(a, b, -x);
}

// ---- Expansions: components in increasing magnitude, non-overlapping, zeros dropped (the
// zero expansion has no components). Sizes are bounded by the determinants below, so buffers
// are fixed arrays on the stack.

constexpr int kMaxComponents = 192;  // orient3d: 3 terms × 2 × (2 × (2 × 2 × 2 + 2 × 2 × 2))

// h = e + f (Shewchuk's fast expansion sum: merge by magnitude, then one chain of two-sums).
int sum(const double* e, int ne, const double* f, int nf, double* h) {
  double g[kMaxComponents];
  int m = 0, i = 0, j = 0;
  while (i < ne && j < nf) g[m++] = std::fabs(e[i]) <= std::fabs(f[j]) ? e[i++] : f[j++];
  while (i < ne) g[m++] = e[i++];
  while (j < nf) g[m++] = f[j++];
  if (m == 0) return 0;
  if (m == 1) {
    h[0] = g[0];
    return 1;
  }
  int k = 0;
  double q, t;
  fast_two_sum(g[1], g[0], q, t);
  if (t != 0) h[k++] = t;
  for (int n = 2; n < m; ++n) {
    two_sum(q, g[n], q, t);
    if (t != 0) h[k++] = t;
  }
  if (q != 0) h[k++] = q;
  return k;
}

// h = e × b (Shewchuk's scale expansion).
int scale(const double* e, int ne, double b, double* h) {
  if (ne == 0 || b == 0) return 0;
  int k = 0;
  double q, t;
  two_product(e[0], b, q, t);
  if (t != 0) h[k++] = t;
  for (int i = 1; i < ne; ++i) {
    double p, pt, s;
    two_product(e[i], b, p, pt);
    two_sum(q, pt, s, t);
    if (t != 0) h[k++] = t;
    fast_two_sum(p, s, q, t);
    if (t != 0) h[k++] = t;
  }
  if (q != 0) h[k++] = q;
  return k;
}

// h = e × f: one scaled copy of e per component of f, summed.
int product(const double* e, int ne, const double* f, int nf, double* h) {
  double acc[kMaxComponents], part[kMaxComponents], next[kMaxComponents];
  int n = 0;
  for (int j = 0; j < nf; ++j) {
    const int np = scale(e, ne, f[j], part);
    n = sum(acc, n, part, np, next);
    for (int i = 0; i < n; ++i) acc[i] = next[i];
  }
  for (int i = 0; i < n; ++i) h[i] = acc[i];
  return n;
}

// h = e − f.
int difference(const double* e, int ne, const double* f, int nf, double* h) {
  double neg[kMaxComponents];
  for (int i = 0; i < nf; ++i) neg[i] = -f[i];
  return sum(e, ne, neg, nf, h);
}

int sign_of(const double* e, int n) { return n == 0 ? 0 : (e[n - 1] > 0 ? 1 : -1); }

// A float difference as an expansion of at most two components.
struct Diff {
  double c[2];
  int n;
};

inline Diff diff(float a, float b) {
  Diff d;
  double x, y;
  two_diff(double(a), double(b), x, y);
  d.n = 0;
  if (y != 0) d.c[d.n++] = y;
  if (x != 0) d.c[d.n++] = x;
  return d;
}

// a·b − c·d, exactly.
int cross_term(const Diff& a, const Diff& b, const Diff& c, const Diff& d, double* h) {
  double ab[8], cd[8];
  const int nab = product(a.c, a.n, b.c, b.n, ab), ncd = product(c.c, c.n, d.c, d.n, cd);
  return difference(ab, nab, cd, ncd, h);
}

}  // namespace

int orient2d_expansion(const glm::vec2& a, const glm::vec2& b, const glm::vec2& c) {
  const Diff ux = diff(b.x, a.x), uy = diff(b.y, a.y), vx = diff(c.x, a.x), vy = diff(c.y, a.y);
  double det[16];
  return sign_of(det, cross_term(ux, vy, uy, vx, det));
}

int orient2d(const glm::vec2& a, const glm::vec2& b, const glm::vec2& c) {
  const double ux = double(b.x) - a.x, uy = double(b.y) - a.y, vx = double(c.x) - a.x, vy = double(c.y) - a.y;
  const double l = ux * vy, r = uy * vx;
  const double det = l - r, bound = kOrient2dBound * (std::fabs(l) + std::fabs(r));
  if (det > bound) return 1;
  if (det < -bound) return -1;
  if (bound == 0) return 0;  // both products exactly zero (float differences never round to 0)
  return orient2d_expansion(a, b, c);
}

int orient3d_expansion(const vec3& a, const vec3& b, const vec3& c, const vec3& d) {
  const Diff ux = diff(b.x, a.x), uy = diff(b.y, a.y), uz = diff(b.z, a.z);
  const Diff vx = diff(c.x, a.x), vy = diff(c.y, a.y), vz = diff(c.z, a.z);
  const Diff wx = diff(d.x, a.x), wy = diff(d.y, a.y), wz = diff(d.z, a.z);
  // u · (v × w), cofactor by cofactor.
  double cx[16], cy[16], cz[16];
  const int ncx = cross_term(vy, wz, vz, wy, cx), ncy = cross_term(vz, wx, vx, wz, cy),
            ncz = cross_term(vx, wy, vy, wx, cz);
  double tx[64], ty[64], tz[64], txy[128], det[kMaxComponents];
  const int ntx = product(cx, ncx, ux.c, ux.n, tx), nty = product(cy, ncy, uy.c, uy.n, ty),
            ntz = product(cz, ncz, uz.c, uz.n, tz);
  const int nxy = sum(tx, ntx, ty, nty, txy);
  return sign_of(det, sum(txy, nxy, tz, ntz, det));
}

int orient3d(const vec3& a, const vec3& b, const vec3& c, const vec3& d) {
  const double ux = double(b.x) - a.x, uy = double(b.y) - a.y, uz = double(b.z) - a.z;
  const double vx = double(c.x) - a.x, vy = double(c.y) - a.y, vz = double(c.z) - a.z;
  const double wx = double(d.x) - a.x, wy = double(d.y) - a.y, wz = double(d.z) - a.z;
  const double p1 = vy * wz, p2 = vz * wy, p3 = vz * wx, p4 = vx * wz, p5 = vx * wy, p6 = vy * wx;
  const double det = ux * (p1 - p2) + uy * (p3 - p4) + uz * (p5 - p6);
  const double permanent = std::fabs(ux) * (std::fabs(p1) + std::fabs(p2)) +
                           std::fabs(uy) * (std::fabs(p3) + std::fabs(p4)) +
                           std::fabs(uz) * (std::fabs(p5) + std::fabs(p6));
  const double bound = kOrient3dBound * permanent;
  if (det > bound) return 1;
  if (det < -bound) return -1;
  if (bound == 0) return 0;  // every product exactly zero
  return orient3d_expansion(a, b, c, d);
}

namespace {

// The coordinate-plane projections: drop axis k (k = 0: (y, z), 1: (z, x), 2: (x, y)). Each
// keeps orientation up to one sign for the whole plane, which is all the tests below compare.
inline glm::vec2 project(const vec3& p, int k) {
  return k == 0 ? glm::vec2(p.y, p.z) : (k == 1 ? glm::vec2(p.z, p.x) : glm::vec2(p.x, p.y));
}

// The first projection in which a triangle of non-zero area keeps non-zero area: a bijection of
// its plane onto the coordinate plane, so everything coplanar with it can be decided there.
int projection_axis(const Triangle& t) {
  for (int k = 0; k < 3; ++k)
    if (orient2d(project(t[0], k), project(t[1], k), project(t[2], k)) != 0) return k;
  return 2;  // unreachable for a triangle of non-zero area
}

// Signs s[0..2] admit a common point: none positive with another negative.
inline bool not_mixed(int s0, int s1, int s2) {
  const bool pos = s0 > 0 || s1 > 0 || s2 > 0, neg = s0 < 0 || s1 < 0 || s2 < 0;
  return !(pos && neg);
}

inline bool lex_less(const glm::vec2& a, const glm::vec2& b) { return a.x < b.x || (a.x == b.x && a.y < b.y); }

// Closed point in closed triangle (t of non-zero area), in the plane.
bool point_in_triangle_2d(const glm::vec2& a, const glm::vec2& t0, const glm::vec2& t1, const glm::vec2& t2) {
  return not_mixed(orient2d(t0, t1, a), orient2d(t1, t2, a), orient2d(t2, t0, a));
}

// Closed segments ab and cd meet, in the plane.
bool segments_meet_2d(const glm::vec2& a, const glm::vec2& b, const glm::vec2& c, const glm::vec2& d) {
  const int o1 = orient2d(a, b, c), o2 = orient2d(a, b, d);
  if (o1 * o2 > 0) return false;
  const int o3 = orient2d(c, d, a), o4 = orient2d(c, d, b);
  if (o3 * o4 > 0) return false;
  if (o1 != 0 || o2 != 0 || o3 != 0 || o4 != 0) return true;
  // All four on one line: points on a line are ordered by their lexicographic order, so the
  // segments meet when their intervals in that order do.
  const glm::vec2 lo1 = lex_less(b, a) ? b : a, hi1 = lex_less(b, a) ? a : b;
  const glm::vec2 lo2 = lex_less(d, c) ? d : c, hi2 = lex_less(d, c) ? c : d;
  return !lex_less(hi1, lo2) && !lex_less(hi2, lo1);
}

// Closed segment ab meets closed triangle t (of non-zero area), all in the plane.
bool segment_meets_triangle_2d(const glm::vec2& a, const glm::vec2& b, const glm::vec2 (&t)[3]) {
  if (point_in_triangle_2d(a, t[0], t[1], t[2]) || point_in_triangle_2d(b, t[0], t[1], t[2])) return true;
  for (int e = 0; e < 3; ++e)
    if (segments_meet_2d(a, b, t[e], t[(e + 1) % 3])) return true;
  return false;
}

// Closed segment ab meets closed triangle t (of non-zero area) in space; oa and ob are the sides
// of a and b of t's plane (orient3d(t0, t1, t2, ·)).
bool segment_meets_triangle(const vec3& a, const vec3& b, int oa, int ob, const Triangle& t) {
  if (oa * ob > 0) return false;  // strictly on one side
  if (oa == 0 && ob == 0) {       // in the plane
    const int k = projection_axis(t);
    const glm::vec2 pt[3] = {project(t[0], k), project(t[1], k), project(t[2], k)};
    return segment_meets_triangle_2d(project(a, k), project(b, k), pt);
  }
  // The segment meets the plane in one point, which lies in the closed triangle exactly when the
  // line ab passes on no two opposite sides of its edges.
  return not_mixed(orient3d(a, b, t[0], t[1]), orient3d(a, b, t[1], t[2]), orient3d(a, b, t[2], t[0]));
}

inline bool same_point(const vec3& a, const vec3& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

// Coplanar triangles of non-zero area meet: an edge of one meets an edge of the other, or one
// lies inside the other (then its first vertex does).
bool coplanar_triangles_meet(const Triangle& p, const Triangle& q) {
  const int k = projection_axis(p);
  const glm::vec2 a[3] = {project(p[0], k), project(p[1], k), project(p[2], k)};
  const glm::vec2 b[3] = {project(q[0], k), project(q[1], k), project(q[2], k)};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (segments_meet_2d(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3])) return true;
  return point_in_triangle_2d(a[0], b[0], b[1], b[2]) || point_in_triangle_2d(b[0], a[0], a[1], a[2]);
}

}  // namespace

bool collinear(const vec3& a, const vec3& b, const vec3& c) {
  for (int k = 0; k < 3; ++k)
    if (orient2d(project(a, k), project(b, k), project(c, k)) != 0) return false;
  return true;
}

bool triangles_intersect(const Triangle& p, const Triangle& q) {
  if (collinear(p[0], p[1], p[2]) || collinear(q[0], q[1], q[2])) return false;
  return triangles_of_nonzero_area_intersect(p, q);
}

bool triangles_of_nonzero_area_intersect(const Triangle& p, const Triangle& q) {
  // Which vertices are shared (a triangle of non-zero area has three distinct positions, so
  // each vertex of p matches at most one of q).
  int match[3] = {-1, -1, -1}, shared = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (same_point(p[i], q[j])) {
        match[i] = j;
        ++shared;
      }
  if (shared == 3) return true;  // the same triangle twice
  if (shared == 2) {
    // Off their common plane the two meet only in the line of the shared edge, which meets each
    // of them in that edge alone. In it they overlap when the third vertices lie on the same
    // side of the edge (folded onto each other), and touch along the edge otherwise.
    const int i2 = match[0] < 0 ? 0 : (match[1] < 0 ? 1 : 2);
    const int i0 = (i2 + 1) % 3, i1 = (i2 + 2) % 3;
    const int j2 = 3 - match[i0] - match[i1];
    if (orient3d(p[0], p[1], p[2], q[j2]) != 0) return false;
    const int k = projection_axis(p);
    const glm::vec2 a = project(p[i0], k), b = project(p[i1], k);
    return orient2d(a, b, project(p[i2], k)) == orient2d(a, b, project(q[j2], k));
  }
  if (shared == 1) {
    // Sharing v, their intersection is convex and holds v; if it holds another point, its point
    // farthest from v along that direction is where the ray from v leaves p or q, which is on the
    // edge opposite v: so they meet beyond v exactly when an opposite edge meets the other one.
    const int i0 = match[0] >= 0 ? 0 : (match[1] >= 0 ? 1 : 2), j0 = match[i0];
    const vec3 &pa = p[(i0 + 1) % 3], &pb = p[(i0 + 2) % 3], &qa = q[(j0 + 1) % 3], &qb = q[(j0 + 2) % 3];
    return segment_meets_triangle(pa, pb, orient3d(q[0], q[1], q[2], pa), orient3d(q[0], q[1], q[2], pb), q) ||
           segment_meets_triangle(qa, qb, orient3d(p[0], p[1], p[2], qa), orient3d(p[0], p[1], p[2], qb), p);
  }
  // Nothing shared: they meet exactly when an edge of one meets the other (the extreme points of
  // their intersection lie on the boundary of one of them).
  int op[3], oq[3];
  for (int i = 0; i < 3; ++i) op[i] = orient3d(q[0], q[1], q[2], p[i]);
  if ((op[0] > 0 && op[1] > 0 && op[2] > 0) || (op[0] < 0 && op[1] < 0 && op[2] < 0)) return false;
  for (int i = 0; i < 3; ++i) oq[i] = orient3d(p[0], p[1], p[2], q[i]);
  if ((oq[0] > 0 && oq[1] > 0 && oq[2] > 0) || (oq[0] < 0 && oq[1] < 0 && oq[2] < 0)) return false;
  if (op[0] == 0 && op[1] == 0 && op[2] == 0) return coplanar_triangles_meet(p, q);
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    if (segment_meets_triangle(p[i], p[j], op[i], op[j], q)) return true;
    if (segment_meets_triangle(q[i], q[j], oq[i], oq[j], p)) return true;
  }
  return false;
}

}  // namespace gwnrt::exact
