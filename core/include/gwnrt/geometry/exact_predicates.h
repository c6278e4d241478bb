// Exact predicates on float coordinates, host and device: a double evaluation with a forward
// error bound decides almost every call; the rest are decided by expansion arithmetic (numbers as
// sums of non-overlapping doubles, after Shewchuk 1997), which is exact for every finite float
// input (products of three float differences neither overflow nor underflow in double). The
// self-intersection count (meshing/mesh_quality.h) and the mesher's repair of intersecting
// triangles (meshing/dual_contouring.h) are built on them.
//
// Only when the filter's result is within its bound of 0 (coplanar neighbours of a flat region:
// every call there) is the determinant computed as an expansion, whose sign is that of its
// largest component (Shewchuk, "Adaptive precision floating-point arithmetic and fast robust
// geometric predicates", 1997, §2). A float difference is a two-component expansion, and
// products of three of them lie between 2^-447 and 2^387, far from double's underflow and
// overflow, so every error term below is itself a double.
//
// The expansion sum relies on round-to-nearest-even (the default everywhere gwnrt runs).
// Compilers contract a * b + c into one fma (GCC in C++, nvcc by default): the expansions
// multiply only inside two_product, whose error term is an explicit fma, and in the filters a
// contraction drops a rounding, which the bounds (one relative error ε per operation, at most)
// still cover. The expansion buffers take about 10 KB of stack; device code reaches them only
// for nearly coplanar inputs.
#pragma once

#include <array>
#include <cmath>

#include "gwnrt/base/hd.h"

namespace gwnrt::exact {

// What the public functions below answer:
// orient3d(a, b, c, d): the sign of det[b − a, c − a, d − a]: +1 when d lies on the side of the
// plane through a, b, c that (b − a) × (c − a) points to (a, b, c counter-clockwise seen from d),
// −1 on the other, 0 when the four points are coplanar. orient2d(a, b, c): the sign of
// det[b − a, c − a], +1 when a, b, c turn counter-clockwise. The *_expansion forms always take
// the exact path (no filter), for tests of it. collinear: every coordinate-plane projection has
// orientation 0 (the triangle has zero area). triangles_intersect(p, q): the pair test of
// count_self_intersections, whether p and q intersect other than in the vertices and edge they
// share (by equal positions), false when either has zero area; triangles_of_nonzero_area_
// intersect: the same for triangles known to have non-zero area.
using Triangle = std::array<vec3, 3>;

constexpr double kEpsilon = 0x1p-53;  // the relative error of one rounding
// |computed − exact| <= bound × permanent for the plain evaluations below. Shewchuk's bounds are
// (3 + 16ε)ε (orient2d) and (7 + 56ε)ε (orient3d); these round them up, which also covers the
// rounding of the permanent itself (at most 5 roundings, (1 − ε)^5 > 7/8).
constexpr double kOrient2dBound = 4.0 * kEpsilon;
constexpr double kOrient3dBound = 8.0 * kEpsilon;

namespace detail {

// ---- Error-free transformations: a op b = x + y exactly, x the rounded result.

GWNRT_HD inline void two_sum(double a, double b, double& x, double& y) {
  x = a + b;
  const double bv = x - a, av = x - bv;
  y = (a - av) + (b - bv);
}

GWNRT_HD inline void fast_two_sum(double a, double b, double& x, double& y) {  // |a| >= |b| (or a == 0)
  x = a + b;
  y = b - (x - a);
}

GWNRT_HD inline void two_diff(double a, double b, double& x, double& y) {
  x = a - b;
  const double bv = a - x, av = x + bv;
  y = (a - av) + (bv - b);
}

GWNRT_HD inline void two_product(double a, double b, double& x, double& y) {
  x = a * b;
  y = fma(a, b, -x);
}

// ---- Expansions: components in increasing magnitude, non-overlapping, zeros dropped (the
// zero expansion has no components). Sizes are bounded by the determinants below, so buffers
// are fixed arrays on the stack.

constexpr int kMaxComponents = 192;  // orient3d: 3 terms × 2 × (2 × (2 × 2 × 2 + 2 × 2 × 2))

// h = e + f_sign·f, f_sign ±1 (Shewchuk's fast expansion sum: merge by magnitude, then one
// chain of two-sums).
GWNRT_HD inline int sum(const double* e, int ne, const double* f, int nf, double* h, double f_sign = 1.0) {
  double g[kMaxComponents];
  int m = 0, i = 0, j = 0;
  while (i < ne && j < nf) g[m++] = fabs(e[i]) <= fabs(f[j]) ? e[i++] : f_sign * f[j++];
  while (i < ne) g[m++] = e[i++];
  while (j < nf) g[m++] = f_sign * f[j++];
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
GWNRT_HD inline int scale(const double* e, int ne, double b, double* h) {
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
GWNRT_HD inline int product(const double* e, int ne, const double* f, int nf, double* h) {
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
GWNRT_HD inline int difference(const double* e, int ne, const double* f, int nf, double* h) {
  return sum(e, ne, f, nf, h, -1.0);
}

GWNRT_HD inline int sign_of(const double* e, int n) { return n == 0 ? 0 : (e[n - 1] > 0 ? 1 : -1); }

// A float difference as an expansion of at most two components.
struct Diff {
  double c[2];
  int n;
};

GWNRT_HD inline Diff diff(float a, float b) {
  Diff d{};
  double x, y;
  two_diff(double(a), double(b), x, y);
  d.n = 0;
  if (y != 0) d.c[d.n++] = y;
  if (x != 0) d.c[d.n++] = x;
  return d;
}

// a·b − c·d, exactly.
GWNRT_HD inline int cross_term(const Diff& a, const Diff& b, const Diff& c, const Diff& d, double* h) {
  // Zeroed: GCC cannot follow the counts through the products and, depending on what it inlines,
  // warns that the parts past them may be read (they are not).
  double ab[8] = {}, cd[8] = {};
  const int nab = product(a.c, a.n, b.c, b.n, ab), ncd = product(c.c, c.n, d.c, d.n, cd);
  return difference(ab, nab, cd, ncd, h);
}

}  // namespace detail

// Out of line: the rare exact path keeps its kilobytes of buffers out of its callers' frames.
GWNRT_HD GWNRT_NOINLINE inline int orient2d_expansion(const glm::vec2& a, const glm::vec2& b, const glm::vec2& c) {
  const detail::Diff ux = detail::diff(b.x, a.x), uy = detail::diff(b.y, a.y), vx = detail::diff(c.x, a.x),
                     vy = detail::diff(c.y, a.y);
  double det[16];
  return detail::sign_of(det, detail::cross_term(ux, vy, uy, vx, det));
}

GWNRT_HD inline int orient2d(const glm::vec2& a, const glm::vec2& b, const glm::vec2& c) {
  const double ux = double(b.x) - a.x, uy = double(b.y) - a.y, vx = double(c.x) - a.x, vy = double(c.y) - a.y;
  const double l = ux * vy, r = uy * vx;
  const double det = l - r, bound = kOrient2dBound * (fabs(l) + fabs(r));
  if (det > bound) return 1;
  if (det < -bound) return -1;
  if (bound == 0) return 0;  // both products exactly zero (float differences never round to 0)
  return orient2d_expansion(a, b, c);
}

GWNRT_HD GWNRT_NOINLINE inline int orient3d_expansion(const vec3& a, const vec3& b, const vec3& c, const vec3& d) {
  const detail::Diff ux = detail::diff(b.x, a.x), uy = detail::diff(b.y, a.y), uz = detail::diff(b.z, a.z);
  const detail::Diff vx = detail::diff(c.x, a.x), vy = detail::diff(c.y, a.y), vz = detail::diff(c.z, a.z);
  const detail::Diff wx = detail::diff(d.x, a.x), wy = detail::diff(d.y, a.y), wz = detail::diff(d.z, a.z);
  // u · (v × w), cofactor by cofactor.
  double cx[16], cy[16], cz[16];
  const int ncx = detail::cross_term(vy, wz, vz, wy, cx), ncy = detail::cross_term(vz, wx, vx, wz, cy),
            ncz = detail::cross_term(vx, wy, vy, wx, cz);
  double tx[64], ty[64], tz[64], txy[128], det[detail::kMaxComponents];
  const int ntx = detail::product(cx, ncx, ux.c, ux.n, tx), nty = detail::product(cy, ncy, uy.c, uy.n, ty),
            ntz = detail::product(cz, ncz, uz.c, uz.n, tz);
  const int nxy = detail::sum(tx, ntx, ty, nty, txy);
  return detail::sign_of(det, detail::sum(txy, nxy, tz, ntz, det));
}

GWNRT_HD inline int orient3d(const vec3& a, const vec3& b, const vec3& c, const vec3& d) {
  const double ux = double(b.x) - a.x, uy = double(b.y) - a.y, uz = double(b.z) - a.z;
  const double vx = double(c.x) - a.x, vy = double(c.y) - a.y, vz = double(c.z) - a.z;
  const double wx = double(d.x) - a.x, wy = double(d.y) - a.y, wz = double(d.z) - a.z;
  const double p1 = vy * wz, p2 = vz * wy, p3 = vz * wx, p4 = vx * wz, p5 = vx * wy, p6 = vy * wx;
  const double det = ux * (p1 - p2) + uy * (p3 - p4) + uz * (p5 - p6);
  const double permanent =
      fabs(ux) * (fabs(p1) + fabs(p2)) + fabs(uy) * (fabs(p3) + fabs(p4)) + fabs(uz) * (fabs(p5) + fabs(p6));
  const double bound = kOrient3dBound * permanent;
  if (det > bound) return 1;
  if (det < -bound) return -1;
  if (bound == 0) return 0;  // every product exactly zero
  return orient3d_expansion(a, b, c, d);
}

namespace detail {

// The coordinate-plane projections: drop axis k (k = 0: (y, z), 1: (z, x), 2: (x, y)). Each
// keeps orientation up to one sign for the whole plane, which is all the tests below compare.
GWNRT_HD inline glm::vec2 project(const vec3& p, int k) {
  return k == 0 ? glm::vec2(p.y, p.z) : (k == 1 ? glm::vec2(p.z, p.x) : glm::vec2(p.x, p.y));
}

// The first projection in which a triangle of non-zero area keeps non-zero area: a bijection of
// its plane onto the coordinate plane, so everything coplanar with it can be decided there.
GWNRT_HD inline int projection_axis(const Triangle& t) {
  for (int k = 0; k < 3; ++k)
    if (orient2d(project(t[0], k), project(t[1], k), project(t[2], k)) != 0) return k;
  return 2;  // unreachable for a triangle of non-zero area
}

// Signs s[0..2] admit a common point: none positive with another negative.
GWNRT_HD inline bool not_mixed(int s0, int s1, int s2) {
  const bool pos = s0 > 0 || s1 > 0 || s2 > 0, neg = s0 < 0 || s1 < 0 || s2 < 0;
  return !(pos && neg);
}

GWNRT_HD inline bool lex_less(const glm::vec2& a, const glm::vec2& b) { return a.x < b.x || (a.x == b.x && a.y < b.y); }

// Closed point in closed triangle (t of non-zero area), in the plane.
GWNRT_HD inline bool point_in_triangle_2d(const glm::vec2& a, const glm::vec2& t0, const glm::vec2& t1,
                                          const glm::vec2& t2) {
  return not_mixed(orient2d(t0, t1, a), orient2d(t1, t2, a), orient2d(t2, t0, a));
}

// Closed segments ab and cd meet, in the plane.
GWNRT_HD inline bool segments_meet_2d(const glm::vec2& a, const glm::vec2& b, const glm::vec2& c, const glm::vec2& d) {
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
GWNRT_HD inline bool segment_meets_triangle_2d(const glm::vec2& a, const glm::vec2& b, const glm::vec2 (&t)[3]) {
  if (point_in_triangle_2d(a, t[0], t[1], t[2]) || point_in_triangle_2d(b, t[0], t[1], t[2])) return true;
  for (int e = 0; e < 3; ++e)
    if (segments_meet_2d(a, b, t[e], t[(e + 1) % 3])) return true;
  return false;
}

// Closed segment ab meets closed triangle t (of non-zero area) in space; oa and ob are the sides
// of a and b of t's plane (orient3d(t0, t1, t2, ·)).
GWNRT_HD inline bool segment_meets_triangle(const vec3& a, const vec3& b, int oa, int ob, const Triangle& t) {
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

GWNRT_HD inline bool same_point(const vec3& a, const vec3& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

// Coplanar triangles of non-zero area meet: an edge of one meets an edge of the other, or one
// lies inside the other (then its first vertex does).
GWNRT_HD inline bool coplanar_triangles_meet(const Triangle& p, const Triangle& q) {
  const int k = projection_axis(p);
  const glm::vec2 a[3] = {project(p[0], k), project(p[1], k), project(p[2], k)};
  const glm::vec2 b[3] = {project(q[0], k), project(q[1], k), project(q[2], k)};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (segments_meet_2d(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3])) return true;
  return point_in_triangle_2d(a[0], b[0], b[1], b[2]) || point_in_triangle_2d(b[0], a[0], a[1], a[2]);
}

}  // namespace detail

// A triangle's plane, for many orientation tests against it: orient3d(t0, t1, t2, x) is the sign
// of n · (x − t0) with n = (t1 − t0) × (t2 − t0), here with n computed once in double and a bound
// on the error of the evaluation (the same terms as orient3d's permanent; the order of the
// operations differs, so the bound is taken larger). side() answers only what the bound decides.
inline constexpr int kUndecided = 2;
struct PlaneFilter {
  vec3 origin;
  dvec3 normal, magnitude;  // magnitude: per component, the sum of |products| it was made of

  PlaneFilter() = default;
  GWNRT_HD explicit PlaneFilter(const Triangle& t) { set(t); }
  // In place: an array of them filled without a temporary's copy (whose wide load waits on the
  // narrow stores just made).
  GWNRT_HD void set(const Triangle& t) {
    origin = t[0];
    const dvec3 u = dvec3(t[1]) - dvec3(t[0]), v = dvec3(t[2]) - dvec3(t[0]);
    normal = dvec3(u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x);
    magnitude =
        dvec3(fabs(u.y * v.z) + fabs(u.z * v.y), fabs(u.z * v.x) + fabs(u.x * v.z), fabs(u.x * v.y) + fabs(u.y * v.x));
  }
  // orient3d(t0, t1, t2, x) where the double evaluation decides it, else kUndecided.
  GWNRT_HD int side(const vec3& x) const {
    const dvec3 w = dvec3(x) - dvec3(origin);
    const double det = normal.x * w.x + normal.y * w.y + normal.z * w.z;
    const double bound =
        16.0 * kEpsilon * (magnitude.x * fabs(w.x) + magnitude.y * fabs(w.y) + magnitude.z * fabs(w.z));
    if (det > bound) return 1;
    if (det < -bound) return -1;
    return bound == 0 ? 0 : kUndecided;
  }
  // Whether component k of n (the orientation of the projection dropping axis k) is certainly
  // non-zero, its sign then certain: beyond its error bound.
  GWNRT_HD bool certain_component(int k) const { return fabs(normal[k]) > 8.0 * kEpsilon * magnitude[k]; }
  // Whether the triangle certainly has non-zero area: some component of n certainly non-zero.
  GWNRT_HD bool certainly_nonzero_area() const {
    return certain_component(0) || certain_component(1) || certain_component(2);
  }
};

namespace detail {

// orient2d(a, b, c) in projection k where the double evaluation decides it, else kUndecided.
GWNRT_HD inline int orient2d_filtered(const vec3& a, const vec3& b, const vec3& c, int k) {
  const glm::vec2 pa = project(a, k), pb = project(b, k), pc = project(c, k);
  const double ux = double(pb.x) - pa.x, uy = double(pb.y) - pa.y, vx = double(pc.x) - pa.x, vy = double(pc.y) - pa.y;
  const double l = ux * vy, r = uy * vx;
  const double det = l - r, bound = 2.0 * kOrient2dBound * (fabs(l) + fabs(r));
  if (det > bound) return 1;
  if (det < -bound) return -1;
  return bound == 0 ? 0 : kUndecided;
}

// The unshared vertices of u strictly on one side of t's plane.
GWNRT_HD inline bool off_plane(const Triangle& u, const bool* u_shared, const PlaneFilter& t_plane) {
  int side = 0;
  for (int k = 0; k < 3; ++k) {
    if (u_shared[k]) continue;
    const int s = t_plane.side(u[k]);
    if ((s != 1 && s != -1) || (side != 0 && s != side)) return false;
    side = s;
  }
  return side != 0;
}

// Whether x, exactly on the line of t's edge (e, f) in projection k, lies beyond the end at
// `shared` away from the other end: the line is not perpendicular to some projected axis, and
// along it x and the other end lie strictly on opposite sides of the shared one.
GWNRT_HD inline bool beyond_edge_end(const Triangle& t, int e, int f, int shared, const vec3& x, int k) {
  if (orient2d(project(t[e], k), project(t[f], k), project(x, k)) != 0) return false;
  const glm::vec2 p = project(t[shared], k), q = project(t[shared == e ? f : e], k), y = project(x, k);
  const int a = q.x != p.x ? 0 : 1;
  return q[a] != p[a] && y[a] != p[a] && (y[a] < p[a]) == (q[a] > p[a]);
}

// An edge line of t separates t from u in t's dominant projection (injective on t's plane): t's
// third vertex strictly on one side, u's vertices strictly on the other but for those shared
// with the edge's ends (u_match[j]: the vertex of t that u's vertex j is, or −1), or, where u
// shares one end alone, on the line beyond that end (flat regions of a lattice's vertices). Then
// whatever t and u share lies on that edge's ends: u meets the line's vertical plane, where t has
// only its edge, in a segment from the shared end away from the edge.
GWNRT_HD inline bool edge_line_separates(const Triangle& t, const PlaneFilter& t_plane, const Triangle& u,
                                         const int* u_match) {
  const dvec3 n = glm::abs(t_plane.normal);
  const int k = n.x >= n.y && n.x >= n.z ? 0 : (n.y >= n.z ? 1 : 2);
  if (!t_plane.certain_component(k)) return false;  // not surely injective
  // The projection's orientation (the normal's component, whose sign is certain) puts each
  // third vertex on this side of its edge.
  const int s = t_plane.normal[k] > 0.0 ? 1 : -1;
  for (int e = 0; e < 3; ++e) {
    const int f = (e + 1) % 3;
    const bool shares_e = u_match[0] == e || u_match[1] == e || u_match[2] == e;
    const bool shares_f = u_match[0] == f || u_match[1] == f || u_match[2] == f;
    bool separated = true;
    for (int j = 0; j < 3 && separated; ++j) {
      if (u_match[j] == e || u_match[j] == f) continue;
      const int side = orient2d_filtered(t[e], t[f], u[j], k);
      separated =
          side == -s || (side != s && shares_e != shares_f && beyond_edge_end(t, e, f, shares_e ? e : f, u[j], k));
    }
    if (separated) return true;
  }
  return false;
}

}  // namespace detail

// True only when p and q (of non-zero area, with their planes fp and fq) certainly meet in
// nothing beyond the vertices they share, decided in double with error bounds: a quick filter
// before triangles_of_nonzero_area_intersect, which decides the rest. Either the unshared
// vertices of one lie strictly on one side of the other's plane, or an edge line separates them
// in a projection (which decides the nearly coplanar pairs of flat regions without expansions).
// q_match[j] is the vertex of p that q's vertex j is, or −1: by equal positions, or by any rule
// that matches only vertices at equal positions (a mesh's indices): a vertex left unmatched that
// does coincide lies on the other's plane and edge lines, which the filter never calls strictly
// off them, so the answer stays safe.
GWNRT_HD inline bool apart_beyond_shared(const Triangle& p, const PlaneFilter& fp, const Triangle& q,
                                         const PlaneFilter& fq, const int* q_match) {
  int p_match[3] = {-1, -1, -1};
  bool p_shared[3] = {false, false, false}, q_shared[3] = {false, false, false};
  int shared = 0;
  for (int j = 0; j < 3; ++j)
    if (q_match[j] >= 0) {
      p_match[q_match[j]] = j;
      p_shared[q_match[j]] = q_shared[j] = true;
      ++shared;
    }
  if (shared == 3) return false;
  // Sharing an edge, one unshared vertex off the other's plane is enough (they then meet only in
  // the line of the edge).
  if (detail::off_plane(q, q_shared, fp) || detail::edge_line_separates(p, fp, q, q_match)) return true;
  return (shared < 2 && detail::off_plane(p, p_shared, fq)) || detail::edge_line_separates(q, fq, p, p_match);
}

// The same, matching vertices by equal positions.
GWNRT_HD inline bool apart_beyond_shared(const Triangle& p, const PlaneFilter& fp, const Triangle& q,
                                         const PlaneFilter& fq) {
  int q_match[3] = {-1, -1, -1};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (detail::same_point(p[i], q[j])) q_match[j] = i;
  return apart_beyond_shared(p, fp, q, fq, q_match);
}

// The same, matching vertices by ids that are equal only at equal positions (a mesh's indices, or
// the ids of welded positions): three integer compares a vertex instead of three of floats.
GWNRT_HD inline bool apart_beyond_shared(const Triangle& p, const PlaneFilter& fp, const Triangle& q,
                                         const PlaneFilter& fq, const uvec3& p_ids, const uvec3& q_ids) {
  int q_match[3];
  for (int k = 0; k < 3; ++k)
    q_match[k] = q_ids[k] == p_ids[0] ? 0 : (q_ids[k] == p_ids[1] ? 1 : (q_ids[k] == p_ids[2] ? 2 : -1));
  return apart_beyond_shared(p, fp, q, fq, q_match);
}

GWNRT_HD inline bool collinear(const vec3& a, const vec3& b, const vec3& c) {
  for (int k = 0; k < 3; ++k)
    if (orient2d(detail::project(a, k), detail::project(b, k), detail::project(c, k)) != 0) return false;
  return true;
}

GWNRT_HD inline bool triangles_of_nonzero_area_intersect(const Triangle& p, const Triangle& q);

GWNRT_HD inline bool triangles_intersect(const Triangle& p, const Triangle& q) {
  if (collinear(p[0], p[1], p[2]) || collinear(q[0], q[1], q[2])) return false;
  return triangles_of_nonzero_area_intersect(p, q);
}

GWNRT_HD inline bool triangles_of_nonzero_area_intersect(const Triangle& p, const Triangle& q) {
  // Which vertices are shared (a triangle of non-zero area has three distinct positions, so
  // each vertex of p matches at most one of q).
  int match[3] = {-1, -1, -1}, shared = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (detail::same_point(p[i], q[j])) {
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
    const int k = detail::projection_axis(p);
    const glm::vec2 a = detail::project(p[i0], k), b = detail::project(p[i1], k);
    return orient2d(a, b, detail::project(p[i2], k)) == orient2d(a, b, detail::project(q[j2], k));
  }
  if (shared == 1) {
    // Sharing v, their intersection is convex and holds v; if it holds another point, its point
    // farthest from v along that direction is where the ray from v leaves p or q, which is on the
    // edge opposite v: so they meet beyond v exactly when an opposite edge meets the other one.
    const int i0 = match[0] >= 0 ? 0 : (match[1] >= 0 ? 1 : 2), j0 = match[i0];
    const vec3 &pa = p[(i0 + 1) % 3], &pb = p[(i0 + 2) % 3], &qa = q[(j0 + 1) % 3], &qb = q[(j0 + 2) % 3];
    return detail::segment_meets_triangle(pa, pb, orient3d(q[0], q[1], q[2], pa), orient3d(q[0], q[1], q[2], pb), q) ||
           detail::segment_meets_triangle(qa, qb, orient3d(p[0], p[1], p[2], qa), orient3d(p[0], p[1], p[2], qb), p);
  }
  // Nothing shared: they meet exactly when an edge of one meets the other (the extreme points of
  // their intersection lie on the boundary of one of them).
  int op[3], oq[3];
  for (int i = 0; i < 3; ++i) op[i] = orient3d(q[0], q[1], q[2], p[i]);
  if ((op[0] > 0 && op[1] > 0 && op[2] > 0) || (op[0] < 0 && op[1] < 0 && op[2] < 0)) return false;
  for (int i = 0; i < 3; ++i) oq[i] = orient3d(p[0], p[1], p[2], q[i]);
  if ((oq[0] > 0 && oq[1] > 0 && oq[2] > 0) || (oq[0] < 0 && oq[1] < 0 && oq[2] < 0)) return false;
  if (op[0] == 0 && op[1] == 0 && op[2] == 0) return detail::coplanar_triangles_meet(p, q);
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    if (detail::segment_meets_triangle(p[i], p[j], op[i], op[j], q)) return true;
    if (detail::segment_meets_triangle(q[i], q[j], oq[i], oq[j], p)) return true;
  }
  return false;
}

}  // namespace gwnrt::exact
