// A brute-force Harnack tracer of S = ∂{w > level}, the reference the tracing benchmark
// (gwnrt-bench-trace) checks gwnrt's trace_surface against. Host-only.
//
// What it computes. Along the ray it marches with the paper's Algorithm 2 (Gillespie, Yang,
// Botsch, Crane 2024) on φ = w mod 1, where at every step
//  - w (and, for the stopping test, ∇w) is the exact double sum over ALL triangles of M
//    (winding_number_exact: O(n) per step, no multipole tree, no cone);
//  - R is the distance to every edge of every triangle of M, by brute force over the edges.
//    φ is harmonic off ∂M, and a ball that meets no edge at all meets no part of ∂M, so R is a
//    valid (pessimistic) Harnack radius; it does not need ∂M to be known.
// The step, the level bracket, the gradient stopping test |gap| <= ε|∇w| and over-stepping are
// harnack.h's (bracket_levels, angle_valued_step, harnack_gradient_bound, kPaperOverstepFactor).
// A smooth hit is a stop at the level of φ where w itself reaches `level` (not level ± k),
// moving into the other side; other levels are stepped across as in the core.
//
// Sheets. R counts every edge but not triangle interiors, so a step may pass through a
// triangle, where w jumps by ±1 while φ stays continuous. Between two accepted points no level
// of φ is reached (that is what the Harnack step guarantees), so a change of the sign of
// w − level between them can only come from such jumps: the tracer then bisects on the sign of
// w − level (40 halvings, each an exact O(n) sum) and reports a sheet hit there, with the
// normal of the triangle the line crosses nearest to that point (found by brute force too).
// Known blind spot, shared with every tracer of this kind: two sheets inside one step whose
// jumps cancel (a wall thinner than the step, crossed in and out) are not seen, and when
// several sign changes lie in one step the bisection finds one of them, not necessarily the
// first.
//
// Why it is a reference: nothing in it comes from gwnrt's acceleration structures. It uses no
// BVH (neither the triangle tree's traversal nor its moments), no cone over ∂M, no boundary
// extraction, no crossing walk and no symbolic tie-breaks; only the triangle soup (the model's
// vertices, in any order), the exact per-triangle solid angle, and the bound on where S can lie
// (the model's box grown by its surface margin, a function of the mesh alone: docs/design.md §5).
// It is O(n) per step and meant for a few hundred rays.
//
// Units and conventions follow trace_surface: t in units of the ray's own direction, the hit
// normal unit and outward (from {w > level} toward {w < level}), `steps` the number of Harnack
// evaluations (the bisection's evaluations not included), `crossings` the number of sheets
// (jumps of floor(w − level)) detected between steps, `capped` when max_steps ended the trace.
// Only TraceMode::kWindingNumber is supported (other modes return an invalid hit).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "gwnrt/field/distance.h"
#include "gwnrt/field/winding_number.h"
#include "gwnrt/geometry/model_view.h"
#include "gwnrt/trace/harnack.h"
#include "gwnrt/trace/surface_trace.h"

namespace gwnrt::reference {

class BruteForceTracer {
 public:
  // Keeps a reference to the model's triangle soup (the view must outlive the tracer) and
  // copies its edges, each undirected edge once (matched by bit-identical endpoints).
  explicit BruteForceTracer(const ModelView& model) : model_(model) {
    const TriangleTreeView& tris = model.triangles;
    std::vector<Edge> edges;
    edges.reserve(size_t(tris.triangle_count) * 3);
    for (uint32_t t = 0; t < tris.triangle_count; ++t)
      for (int k = 0; k < 3; ++k) {
        vec3 a = tris.vertices[3 * t + k], b = tris.vertices[3 * t + (k + 1) % 3];
        if (less(b, a)) std::swap(a, b);
        edges.push_back({a, b});
      }
    std::sort(edges.begin(), edges.end(),
              [](const Edge& x, const Edge& y) { return less(x.a, y.a) || (x.a == y.a && less(x.b, y.b)); });
    edges.erase(
        std::unique(edges.begin(), edges.end(), [](const Edge& x, const Edge& y) { return x.a == y.a && x.b == y.b; }),
        edges.end());
    edges_.reserve(edges.size() * 2);
    for (const Edge& e : edges) {
      edges_.push_back(dvec3(e.a));
      edges_.push_back(dvec3(e.b));
    }
  }

  std::size_t edge_count() const { return edges_.size() / 2; }

  // Distance from x to the nearest edge of any triangle of M (+inf for an empty mesh).
  double edge_distance(const dvec3& x) const {
    double best2 = INFINITY;
    for (std::size_t i = 0; i < edges_.size(); i += 2) {
      const ClosestPoint<double> c = closest_point_on_segment(edges_[i], edges_[i + 1], x);
      const dvec3 d = c.point - x;
      best2 = std::min(best2, glm::dot(d, d));
    }
    return std::sqrt(best2);
  }

  RayHit trace(const Ray& ray, const TraceOptions& o) const {
    RayHit hit;
    const double len = glm::length(dvec3(ray.direction));
    if (o.mode != TraceMode::kWindingNumber || !finite(ray.origin) || !finite(ray.direction) || !(len > 0) ||
        !std::isfinite(len) || std::isnan(ray.tnear) || std::isnan(ray.tfar)) {
      hit.invalid = true;
      return hit;
    }
    const dvec3 origin(ray.origin), dir = dvec3(ray.direction) / len;
    // The interval where S can be: the box of M grown by the surface margin.
    double t0 = double(ray.tnear) * len, t1 = double(ray.tfar) * len;
    for (int k = 0; k < 3; ++k) {
      const double lo = double(model_.bounds.lo[k]) - model_.surface_margin;
      const double hi = double(model_.bounds.hi[k]) + model_.surface_margin;
      if (dir[k] == 0) {
        if (origin[k] < lo || origin[k] > hi) return hit;
        continue;
      }
      double a = (lo - origin[k]) / dir[k], b = (hi - origin[k]) / dir[k];
      if (a > b) std::swap(a, b);
      t0 = std::max(t0, a);
      t1 = std::min(t1, b);
    }
    if (!(t0 <= t1)) return hit;

    const double level = o.level;
    const float phase = o.level - std::floor(o.level);
    const double eps = double(o.epsilon) * glm::length(dvec3(model_.bounds.hi - model_.bounds.lo));
    const auto point = [&](double t) { return vec3(origin + t * dir); };
    const auto band_at = [&](double t) {
      return std::floor(winding_number_exact(model_.triangles, point(t)).w - level);
    };

    double t = t0, t_prev = t0, rho_prev = 0;  // t_prev, rho_prev: the last accepted point and its safe step
    bool overstepped = false;
    bool have_accepted = false;
    double t_accepted = t0, band_accepted = 0;
    for (;;) {
      if (hit.steps >= o.max_steps) {
        hit.capped = true;
        return hit;
      }
      ++hit.steps;
      const vec3 x = point(t);
      const double w = winding_number_exact(model_.triangles, x).w;
      const float phi = float(w - std::floor(w));
      const float radius = float(edge_distance(dvec3(x)));
      const LevelBracket levels = bracket_levels(phi, phase);
      const float rho = angle_valued_step(radius, phi, levels);
      if (overstepped && t - t_prev > double(rho_prev) + double(rho)) {  // the long step was not covered
        t = t_prev + rho_prev;
        overstepped = false;
        continue;
      }
      overstepped = false;

      // An accepted point: the sign of w − level can only have changed since the last one by
      // jumps across triangles (no level of φ lies in between).
      const double band = std::floor(w - level);
      if (have_accepted && band != band_accepted) {
        hit.crossings += uint32_t(std::fabs(band - band_accepted));
        if ((band_accepted < 0) != (band < 0)) {
          sheet_hit(origin, dir, len, t_accepted, band_accepted < 0, t, band_at, hit);
          return hit;
        }
      }
      have_accepted = true;
      t_accepted = t;
      band_accepted = band;

      const float gap_below = phi - levels.below, gap_above = levels.above - phi;
      const float gap = std::min(gap_below, gap_above);
      if (gap <= float(eps) * harnack_gradient_bound(radius, phi)) {
        const dvec3 g = winding_number_exact(model_.triangles, x, true).gradient;
        const double gn = glm::length(g);
        if (gap <= eps * gn) {
          const bool at_above = gap_above <= gap_below;
          const double rate = glm::dot(g, dir);  // dw/dt
          // The level of w being approached, and whether it is w* itself.
          const double w_level = std::floor(w) + double(at_above ? levels.above : levels.below);
          const bool target = std::round(w_level - level) == 0.0;
          if (at_above ? rate > 0 : rate < 0) {
            if (target) {
              hit.hit = true;
              hit.kind = HitKind::kSmooth;
              hit.t = float(t / len);
              hit.position = x;
              hit.normal = vec3(-g / gn);
              return hit;
            }
            t += std::min(2.0 * gap / std::fabs(rate) + eps, 10.0 * eps);  // across another level
          } else {
            t += std::max(double(rho), eps);  // moving away from the level (or grazing it)
          }
          if (t_accepted >= t1) break;
          t = std::min(t, t1);
          t_prev = t;
          rho_prev = 0;
          continue;
        }
      }
      if (t >= t1) break;
      const double safe = std::max(double(rho), 0.5 * eps);  // R -> 0 on an edge: keep moving
      t_prev = t;
      rho_prev = safe;
      if (t + safe >= t1) {
        t = t1;  // the last piece: evaluate the end for the sheet test
      } else if (o.overstep) {
        t = std::min(t + double(kPaperOverstepFactor) * safe, t1);
        overstepped = true;
      } else {
        t += safe;
      }
    }
    return hit;
  }

 private:
  struct Edge {
    vec3 a, b;
  };
  static bool less(const vec3& p, const vec3& q) {
    return p.x < q.x || (p.x == q.x && (p.y < q.y || (p.y == q.y && p.z < q.z)));
  }
  static bool finite(const vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

  // The sign of w − level flips in (ta, tb]: bisect on it, then take the normal of the triangle
  // the line crosses nearest to that point.
  template <class BandAt>
  void sheet_hit(const dvec3& origin, const dvec3& dir, double len, double ta, bool outside_at_a, double tb,
                 const BandAt& band_at, RayHit& hit) const {
    double lo = ta, hi = tb;
    for (int i = 0; i < 40; ++i) {
      const double mid = 0.5 * (lo + hi);
      if (!(mid > lo && mid < hi)) break;
      ((band_at(mid) < 0) == outside_at_a ? lo : hi) = mid;
    }
    const double t = 0.5 * (lo + hi);
    const bool entering = outside_at_a;  // into {w > level}: the outside is behind the ray
    hit.hit = true;
    hit.kind = HitKind::kSheet;
    hit.t = float(t / len);
    hit.position = vec3(origin + t * dir);
    // Möller–Trumbore in double over every triangle: the crossing nearest to t.
    const TriangleTreeView& tris = model_.triangles;
    double best = INFINITY;
    for (uint32_t i = 0; i < tris.triangle_count; ++i) {
      const dvec3 p0(tris.vertices[3 * i]), p1(tris.vertices[3 * i + 1]), p2(tris.vertices[3 * i + 2]);
      const dvec3 e1 = p1 - p0, e2 = p2 - p0, p = glm::cross(dir, e2);
      const double det = glm::dot(e1, p);
      if (det == 0) continue;
      const dvec3 s = origin - p0;
      const double u = glm::dot(s, p) / det;
      const dvec3 q = glm::cross(s, e1);
      const double v = glm::dot(dir, q) / det;
      if (u < 0 || v < 0 || u + v > 1) continue;
      const double tc = glm::dot(e2, q) / det;
      if (std::fabs(tc - t) < best) {
        best = std::fabs(tc - t);
        dvec3 n = glm::normalize(glm::cross(e1, e2));
        if ((glm::dot(n, dir) > 0) == entering) n = -n;
        hit.normal = vec3(n);
        hit.triangle = tris.triangle_ids[i];
      }
    }
  }

  ModelView model_;
  std::vector<dvec3> edges_;  // 2 per edge
};

}  // namespace gwnrt::reference
