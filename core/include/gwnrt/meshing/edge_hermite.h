// Where S crosses a grid edge: the Hermite data of dual contouring (a point of S on the edge and
// S's outward normal there), exact on sheet pieces and a bracketed root on smooth ones.
// Host-and-device.
#pragma once

#include "gwnrt/field/box_winding.h"
#include "gwnrt/field/evaluate_winding.h"
#include "gwnrt/geometry/model_view.h"
#include "gwnrt/geometry/ray.h"

namespace gwnrt {

// Crossings of M visited along one edge before giving up (an edge through a stack of hundreds
// of coincident triangles); the point found so far is kept and `capped` says so.
inline constexpr int kMaxEdgeCrossings = 256;
// Steps of the bracketed root search on a smooth piece: Illinois' regula falsi halves the
// bracket at least every third step, so 60 steps take any bracket below float round-off.
inline constexpr int kMaxRootSteps = 60;
// The root is found to this fraction of the edge, far below the 0.05 cell the output promises:
// the search stops once its bracket is this narrow or the secant through its ends puts the root
// this near its last point (regula falsi closes in from one side; on a scan that took 2.8
// values a root instead of 6.8, docs/performance.md).
inline constexpr float kRootTolerance = 1e-4f;
// The search also stops where |w − w*| is this small: a tenth of the error of its w (within 1e-4
// of the exact at kRootSearchConeBeta, below), which no further step could resolve. Where w's
// slope is small, the bracket's criterion above would otherwise take its steps by halving a
// bracket around noise: on a scan one root in fifteen took 5 to 60 values (docs/performance.md).
inline constexpr float kRootValueTolerance = 1e-5f;
// w is sampled this fraction of the edge before a crossing of M, for its value on the near
// side (continuous up to the crossing: the cone's field and the other triangles'); intervals
// between crossings shorter than twice this are taken as constant.
inline constexpr float kCrossingOffset = 1e-3f;

// The root search's w by crossings: the cone's clusters expanded beyond this many radii rather
// than kConeBeta's 5. It decides only where S crosses an edge, never which edges it crosses (the
// corners' signs, exact): within 1e-4 of the exact w (9.5e-5 the most seen, beside the scan's
// rim), a root moves by that over |∂w/∂t|, and the scan's edges took a quarter less time
// (docs/performance.md). An edge whose corners' signs its walk does not reproduce is walked again
// with the exact w.
inline constexpr float kRootSearchConeBeta = 3.0f;

// The cone's beta for a smooth Hermite point's normal, of which only the direction is read: the
// root search's. From 5 to 3 no vertex of the scan moved by 1e-3 of a cell for it (a QEF vertex
// moves by the normal's angle times its distance from the Hermite points; 8 to 5 moved none by
// 1e-4), and the scan's edges took a fifth less; the derivatives' own 16 made the normals a
// quarter of the mesher's time on a scan (docs/performance.md).
inline constexpr float kHermiteNormalBeta = kRootSearchConeBeta;

enum class HermiteKind : uint8_t { kSheet = 0, kSmooth = 1, kFallback = 2 };

struct HermitePoint {
  vec3 point{0.0f};
  vec3 normal{0.0f};                      // unit, out of {w > w*}
  uint32_t source_triangle = kEmptyLane;  // input index, for a sheet crossing
  HermiteKind kind = HermiteKind::kFallback;
  bool capped = false;           // kMaxEdgeCrossings or kMaxRootSteps was reached
  bool normal_deferred = false;  // a smooth root whose normal is left to the caller (smooth_normal)
  // A smooth root whose search is left to the caller: until then point holds (ta, fa, tb) and
  // normal.x fb of its bracket (deferred_bracket).
  bool root_deferred = false;
  // A walk that stopped for w − w* at `point` (before a crossing of M): the caller sums it and
  // walks the edge again with it (EdgeValues).
  bool value_deferred = false;
};

// The values of w − w* that an edge's walk asked for before its crossings of M, in the order
// asked, for a caller that sums them in batches: the walk takes these and stops at the next it
// needs (value_deferred); once kDeferredEdgeValues are taken it sums the rest itself.
inline constexpr int kDeferredEdgeValues = 8;
struct EdgeValues {
  float value[kDeferredEdgeValues];
  int count = 0;
};

// ∇w at a smooth root, whose direction gives its normal: by crossings, the cone's clusters
// expanded beyond kHermiteNormalBeta radii rather than the derivatives' 16.
GWNRT_HD inline vec3 smooth_root_gradient(const ModelView& m, const WindingOptions& winding, const vec3& x) {
  return resolve_winding_method(m, winding.method) == WindingMethod::kCrossing
             ? winding_number_crossing<true, false>(m, x, kHermiteNormalBeta).gradient
             : evaluate_winding(m, x, winding, true, false).gradient;
}

// A smooth root's normal from ∇w there: out of {w > w*}, or `fallback` (along the edge, out of
// the inside end) where ∇w vanishes.
GWNRT_HD inline vec3 smooth_normal(const vec3& gradient, const vec3& fallback) {
  const float length = glm::length(gradient);
  return length > 0.0f && is_finite(length) ? -gradient / length : fallback;
}

// f = w − w* on the bracket [ta, tb] of one smooth interval (fa, fb of different signs, inside
// meaning f > 0), searched with w alone (a Newton step needs ∇w, which the crossing method
// evaluates at a finer cone beta: several times w's cost): each point the secant through the
// last two values (the first: a given guess and its slope, else the bracket's ends) where it
// falls inside the bracket, else Illinois' regula falsi point; stopped when the local secant
// puts the root within kRootTolerance of the edge (h) from the last point, the bracket is that
// narrow, |f| is within kRootValueTolerance, or after kMaxRootSteps. One step at a time (next, then take f there), so
// that the mesher can step many brackets together.
struct IllinoisBracket {
  float ta = 0, fa = 0, tb = 0, fb = 0, h = 0;
  float t = 0, ft = 0;                     // the last point asked for, and f there once taken
  float first_guess = __builtin_nanf("");  // the first point, where inside the bracket
  float slope = __builtin_nanf("");        // df/dt near t: the guess's, then the last two values' secant
  int side = 0;                            // which end was kept last (Illinois halves the kept end's value)
  int steps = 0;
  bool a_inside = false, converged = false;

  IllinoisBracket() = default;
  GWNRT_HD IllinoisBracket(float ta_, float fa_, float tb_, float fb_, float h_)
      : ta(ta_), fa(fa_), tb(tb_), fb(fb_), h(h_), a_inside(fa_ > 0.0f) {}
  GWNRT_HD bool active() const { return !converged && steps < kMaxRootSteps && tb - ta > kRootTolerance * h; }
  // The next point to evaluate f at.
  GWNRT_HD float next() {
    float u = steps == 0 ? first_guess : t - ft / slope;
    if (!(u > ta && u < tb)) {
      u = fb != fa ? tb - fb * (tb - ta) / (fb - fa) : 0.5f * (ta + tb);
      if (!(u > ta && u < tb)) u = 0.5f * (ta + tb);
    }
    if (steps > 0) previous = t, f_previous = ft;
    return t = u;
  }
  // f at t, and df/dt there where known (∂w along the edge: then the next point is Newton's).
  GWNRT_HD void take(float f, float df = __builtin_nanf("")) {
    ft = f;
    // The local slope: df, else the secant through the last two values, or the guess's.
    if (df == df && df != 0.0f)
      slope = df;
    else if (steps > 0 && t != previous)
      slope = (f - f_previous) / (t - previous);
    const float local = slope == slope && slope != 0.0f ? fabsf(slope) : fabsf(fb - fa) / (tb - ta);
    if (fabsf(f) <= kRootTolerance * h * local || fabsf(f) <= kRootValueTolerance) {
      ta = tb = t;
      converged = true;
      return;
    }
    if ((f > 0.0f) == a_inside) {
      ta = t;
      fa = f;
      if (side == -1) fb *= 0.5f;
      side = -1;
    } else {
      tb = t;
      fb = f;
      if (side == 1) fa *= 0.5f;
      side = 1;
    }
    ++steps;
  }
  GWNRT_HD float root() const { return 0.5f * (ta + tb); }
  GWNRT_HD bool capped() const { return steps == kMaxRootSteps; }

 private:
  float previous = 0, f_previous = 0;
};

// A first point for the root search on a whole edge between corners of values f0 and f1 (of
// different signs), from the values one corner before (fm1) and after (f2) on its line: the root
// in (0, 1), in edge lengths, of the cubic through the four (the quadratic through three where
// one is NaN or differs from the line through the edge's ends by half a jump or more, a crossing
// of M beside the edge), or NaN; `slope`: the polynomial's there. Its error falls as h⁴ rather than the secant's h², so
// the search often stops at its first value; a poor guess costs steps, never the bracket.
GWNRT_HD inline float interpolated_root_guess(float fm1, float f0, float f1, float f2, float& slope) {
  slope = __builtin_nanf("");
  const bool use_before = fabsf(fm1 - (2.0f * f0 - f1)) < 0.5f, use_after = fabsf(f2 - (2.0f * f1 - f0)) < 0.5f;
  if (!use_before && !use_after) return __builtin_nanf("");
  // p(t) = f0 + c1 t + c2 t² + c3 t³ through the points used (Newton's divided differences).
  const float d1 = f1 - f0;
  float c1, c2, c3 = 0.0f;
  if (use_before && use_after) {
    c2 = 0.5f * (f1 - 2.0f * f0 + fm1);
    c3 = (f2 - 3.0f * f1 + 3.0f * f0 - fm1) / 6.0f;
    c1 = d1 - c2 - c3;
  } else if (use_before) {
    c2 = 0.5f * (f1 - 2.0f * f0 + fm1);
    c1 = d1 - c2;
  } else {
    c2 = 0.5f * (f2 - 2.0f * f1 + f0);
    c1 = d1 - c2;
  }
  float t = f0 / (f0 - f1);  // Newton on p from the secant's root, kept inside (0, 1)
  for (int k = 0; k < 4; ++k) {
    const float p = f0 + t * (c1 + t * (c2 + t * c3)), dp = c1 + t * (2.0f * c2 + 3.0f * t * c3);
    if (!(dp != 0.0f)) return __builtin_nanf("");
    t -= p / dp;
    if (!(t > 0.0f && t < 1.0f)) return __builtin_nanf("");
  }
  slope = c1 + t * (2.0f * c2 + 3.0f * t * c3);
  return t;
}

// The smooth root of a finished search on the edge from p0 along `direction`, with its normal
// from ∇w there, or, deferred (normal_deferred), the fallback along the edge until then.
GWNRT_HD inline HermitePoint smooth_root_point(const ModelView& m, const WindingOptions& winding, const vec3& p0,
                                               const vec3& direction, const IllinoisBracket& bracket,
                                               bool defer_normal) {
  HermitePoint out;
  out.kind = HermiteKind::kSmooth;
  out.capped = bracket.capped();
  out.point = p0 + bracket.root() * direction;
  out.normal = bracket.a_inside ? direction : -direction;
  out.normal_deferred = defer_normal;
  if (!defer_normal) out.normal = smooth_normal(smooth_root_gradient(m, winding, out.point), out.normal);
  return out;
}

// The bracket of a root_deferred point, for an edge of length h.
GWNRT_HD inline IllinoisBracket deferred_bracket(const HermitePoint& p, float h) {
  return IllinoisBracket(p.point.x, p.point.y, p.point.z, p.normal.x, h);
}

namespace detail {

// A smooth root from its bracket, searched with `value` (f at a point of the edge).
template <class Value>
GWNRT_HD inline HermitePoint smooth_root(const ModelView& m, const WindingOptions& winding, const vec3& p0,
                                         const vec3& direction, IllinoisBracket bracket, Value value,
                                         bool defer_normal) {
  while (bracket.active()) bracket.take(value(bracket.next()));
  return smooth_root_point(m, winding, p0, direction, bracket, defer_normal);
}

}  // namespace detail

// A first-order estimate of w whose bounds hold on a box that holds the edge (field/box_winding.h):
// its centre, and J at the edge's start (along the ray the estimate's ŵ is taken along).
struct EdgeBound {
  TaylorPoint point;
  BoxFieldBounds bounds;
  vec3 centre{0.0f};
  int jumps = 0;
};

namespace detail {

// edge_hermite's walk, w by crossings at `cone_beta` where the method is crossing.
GWNRT_HD inline HermitePoint walk_edge(const ModelView& m, const WindingOptions& winding, float level, const vec3& p0,
                                       int axis, float h, float f0, float f1, const EdgeBound* bound, float cone_beta,
                                       bool defer_normal, bool defer_root, const EdgeValues* values = nullptr) {
  vec3 direction(0.0f);
  direction[axis] = 1.0f;
  const RayFrame frame = make_ray_frame(p0, direction);
  const bool by_crossing = resolve_winding_method(m, winding.method) == WindingMethod::kCrossing;
  const auto value = [&](float t) {
    const vec3 x = p0 + t * direction;
    return (by_crossing ? winding_number_crossing<false, false>(m, x, cone_beta).w
                        : evaluate_winding(m, x, winding).w) -
           level;
  };
  int jumps = bound ? bound->jumps : 0;  // J on the current interval: it falls by each crossing's jump
  const bool piecewise_constant = m.cone.triangle_count == 0 && by_crossing;
  const float offset = kCrossingOffset * h;
  float t_start = 0.0f, f_start = f0;
  uint32_t index_after = kEmptyLane;
  bool capped = true;
  int values_used = 0;
  for (int k = 0; k < kMaxEdgeCrossings; ++k) {
    CrossingHit hit;
    const bool found = next_crossing<true>(m.triangles.bvh, m.triangles.vertices, frame, t_start, index_after, h, hit);
    const float t_end = found ? hit.t : h;
    float f_end = f1, f_after_settled = __builtin_nanf("");
    if (found) {
      const bool constant = piecewise_constant || t_end - t_start < 2.0f * offset;
      if (!constant && bound &&
          taylor_settles_segment(bound->point, bound->bounds, jumps, p0 + t_start * direction - bound->centre,
                                 p0 + (t_end - offset) * direction - bound->centre, level, f_start > 0.0f))
        f_after_settled = taylor_estimate(bound->point, bound->bounds, jumps - hit.jump,
                                          p0 + t_end * direction - bound->centre, level);
      if (f_after_settled == f_after_settled || constant) {
        f_end = f_start;  // its sign, which is all that is read of it
      } else if (values && values_used < values->count) {
        f_end = values->value[values_used++];
      } else if (values && values_used < kDeferredEdgeValues) {
        HermitePoint out;
        out.value_deferred = true;
        out.point = p0 + (t_end - offset) * direction;
        return out;
      } else {
        f_end = value(t_end - offset);
      }
    }
    if ((f_start > 0.0f) != (f_end > 0.0f)) {
      const float ta = t_start + (k > 0 && t_end - t_start >= 2.0f * offset ? offset : 0.0f);
      const IllinoisBracket bracket(ta, f_start, found ? t_end - offset : h, f_end, h);
      if (defer_root) {  // the search left to the caller
        HermitePoint out;
        out.kind = HermiteKind::kSmooth;
        out.root_deferred = true;
        out.point = vec3(bracket.ta, bracket.fa, bracket.tb);
        out.normal = vec3(bracket.fb, 0.0f, 0.0f);
        return out;
      }
      return smooth_root(m, winding, p0, direction, bracket, value, defer_normal);
    }
    if (!found) {
      capped = false;
      break;
    }
    const float f_after = f_after_settled == f_after_settled ? f_after_settled : f_end + float(hit.jump);
    jumps -= hit.jump;
    if ((f_end > 0.0f) != (f_after > 0.0f)) {
      HermitePoint out;
      out.kind = HermiteKind::kSheet;
      out.point = p0 + hit.t * direction;
      const vec3* v = m.triangles.vertices + 3 * hit.index;
      vec3 n = glm::cross(v[1] - v[0], v[2] - v[0]);
      // Outward is where w is lower: against the edge where w jumps up along it.
      if ((n[axis] > 0.0f) == (hit.jump > 0)) n = -n;
      const float length = glm::length(n);
      out.normal = length > 0.0f && is_finite(length) ? n / length : (f_after > 0.0f ? -direction : direction);
      out.source_triangle = m.triangles.triangle_ids[hit.index];
      return out;
    }
    t_start = hit.t;
    index_after = hit.index;
    f_start = f_after;
  }
  // The signs along the edge did not reproduce f1's (round-off within a crossing's width), or the
  // cap was hit: the edge's midpoint, the normal along the edge.
  HermitePoint out;
  out.point = p0 + (0.5f * h) * direction;
  out.normal = f0 > 0.0f ? direction : -direction;
  out.capped = capped;
  return out;
}

}  // namespace detail

// The point where S crosses the edge from p0 to p0 + h·e_axis, f0 = w(p0) − w* and f1 = w(end)
// − w* of different signs (inside: f > 0). Along the edge w is continuous except at crossings
// of M, where it jumps by the crossing's jump; walking from p0, the first place where f changes
// sign is either within an interval between crossings (a smooth piece: a bracketed root) or at a
// crossing (a sheet: the exact ray–triangle point and the triangle's normal, turned outward).
// Off a cone (a closed mesh) and with exact w, w is constant between crossings and no w is
// evaluated at all. With a bound, an interval it settles to one sign, and the side after its
// crossing when settled too, take no evaluation either (J falls by each crossing's jump, ŵ being
// continuous). The values by crossings are taken at kRootSearchConeBeta. With defer_normal a
// smooth root's normal is left to the caller (normal_deferred; its normal the fallback); with
// defer_root its search too (root_deferred), except on the walk again at kConeBeta; with
// `values` the values before crossings of M beyond those given (value_deferred).
GWNRT_HD inline HermitePoint edge_hermite(const ModelView& m, const WindingOptions& winding, float level,
                                          const vec3& p0, int axis, float h, float f0, float f1,
                                          const EdgeBound* bound = nullptr, bool defer_normal = false,
                                          bool defer_root = false, const EdgeValues* values = nullptr) {
  const HermitePoint out = detail::walk_edge(m, winding, level, p0, axis, h, f0, f1, bound, kRootSearchConeBeta,
                                             defer_normal, defer_root, values);
  if (out.kind != HermiteKind::kFallback || out.value_deferred || out.capped ||
      resolve_winding_method(m, winding.method) != WindingMethod::kCrossing || m.cone.triangle_count == 0)
    return out;
  return detail::walk_edge(m, winding, level, p0, axis, h, f0, f1, bound, kConeBeta, defer_normal, false);
}

}  // namespace gwnrt
