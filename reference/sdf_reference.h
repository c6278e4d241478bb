// The independent reference signed distance to S = ∂{w > w*} of the accuracy study
// (gwnrt-sdf-study), min over the two kinds of piece:
//  - sheet pieces: the exact distance to the sheet triangles (the caller's, from the model);
//  - smooth pieces: a cloud of points on S. Random lines are traced with trace_surface and every
//    smooth crossing is kept (the accept filter turns all hits down, so the trace goes on to the
//    end of the line); each crossing is moved onto the exact level (φ = w_C mod 1 by the double
//    sum over the cone C, docs/design.md §3) and kept only when the exact w of the whole mesh is w* there,
//    i.e. it is a point of S and not of w* ± 1. For a query point the nearest cloud point seeds a
//    refinement (project onto its tangent plane, back onto the exact level along the normal,
//    repeat: the fixed point is a foot of the perpendicular), whose points are confirmed the same
//    way.
// Every candidate is a point of S up to the level tolerance, so the reference is an upper bound
// of the true distance. The sign is that of w* − w with w the exact double sum over M.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "gwnrt/geometry/bvh.h"
#include "gwnrt/model/model.h"
#include "reference/kd_tree.h"

namespace gwnrt::reference {

// What the exact levels are computed from: φ by the double sum over the cone, w by the double
// sum over M, distances to M through its BVH.
struct ExactLevel {
  TriangleTreeView mesh, cone;
  TriangleTreeView triangles;  // M through its BVH, for distances
  double level;
  double diagonal;
};

// wrap(w_C − w*) in (−1/2, 1/2]: φ − w* on the nearest lift (w − w_C is a whole number off M ∪ C).
struct LevelGap {
  double gap;
  dvec3 gradient;  // ∇w = ∇w_C
};

LevelGap level_gap(const ExactLevel& e, const dvec3& x);

// Accepted as on the level: |φ − w*| below this (float positions cannot do much better where
// |∇w| is large), and then the whole-mesh w must be w* to within kBandTolerance (not w* ± 1).
inline constexpr double kGapTolerance = 1e-5;
inline constexpr double kBandTolerance = 1e-3;

// From q, the point q + t·n on the exact level, |t| <= limit (1D Newton along the unit n).
// `slack` gets |gap| / |∇w| there: how far the true level may be from the returned point.
bool onto_level(const ExactLevel& e, const dvec3& q, const dvec3& n, double limit, dvec3& out, dvec3& gradient,
                double& slack);

// Whether the whole-mesh w at y is w* (not w* ± 1), to within kBandTolerance.
bool on_surface_band(const ExactLevel& e, const dvec3& y);

struct CloudPoint {
  dvec3 p;
  dvec3 n;  // unit ∇w
};

struct CloudStats {
  size_t lines = 0, crossings = 0, capped = 0, moved_off = 0, wrong_band = 0;
  double seconds = 0;
  double max_slack = 0;
};

// Traces lines until the cloud has `target` points (or `max_lines` lines were shot); every
// smooth crossing is moved onto the exact level and kept when the whole-mesh w confirms it.
// Lines, a third each: through uniform points of the march boxes (where the tracer says smooth
// pieces can be), through uniform points of each boundary loop's box (the caps span the loops),
// and through points near ∂M (the rims, where the caps curve most); each runs across the whole
// box that holds S.
std::vector<CloudPoint> build_cloud(const GwnModel& model, const ExactLevel& exact, float level, size_t target,
                                    size_t max_lines, uint64_t seed, CloudStats& stats);

// The reference at one point.
struct Reference {
  double sheet = kInfinity;       // unsigned distance to the sheet triangles
  double smooth = kInfinity;      // unsigned, to the confirmed smooth points (refined)
  double smooth_raw = kInfinity;  // to the nearest cloud point alone
  double tangent_gap = 0;         // |x − y| − |(x − y)·n| at the final refined point: ~0 at a foot
  double slack = 0;               // how far the level may be from the winning smooth point
  double w = 0;                   // exact w at x
  double sign = 1;                // sign(w* − w)
  double distance() const { return sign * std::min(sheet, smooth); }
  bool smooth_nearest() const { return smooth < sheet; }
};

inline constexpr int kRefineSteps = 32;

// Nearest cloud point, then: foot of x on the tangent plane at y, back onto the level along the
// normal, repeat. Each step stays within half the distance from y to M (no sheet in between, the
// level a graph over the plane there); the points are confirmed by the whole-mesh w, newest
// first, and the nearest confirmed one wins.
// `skip_margin`: no refinement when the sheets are nearer than the raw distance minus this (the
// cloud's gaps are far smaller, so the smooth pieces cannot win there).
void smooth_reference(const ExactLevel& e, const std::vector<CloudPoint>& cloud, const KdTree& tree, const dvec3& x,
                      double skip_margin, Reference& ref);

}  // namespace gwnrt::reference
