// Sheet classification: the other triangles' w at every triangle's centroid (sdf/sheets.h).
#include <algorithm>
#include <cmath>
#include <vector>

#include <tbb/parallel_for.h>

#include "gwnrt/base/symmetric_eigen.h"
#include "gwnrt/field/crossing_winding.h"
#include "gwnrt/field/solid_angle.h"
#include "gwnrt/field/winding_number.h"
#include "gwnrt/geometry/triangle_tree.h"
#include "gwnrt/sdf/sheets.h"

namespace gwnrt {
namespace {

// Lanes as oriented boxes, and which lie in one plane. A polygon fanned from one vertex is n
// slivers that all meet there: every cluster of them holds that vertex and reaches across the
// polygon, so its ball holds most of the polygon's centroids and the multipole sum opens it at
// each, as a crossing ray from each meets most of their axis-aligned boxes: O(n) a triangle, O(n²)
// the classification. But a triangle adds nothing to w at a
// point of its own plane that it does not contain, and a box along a cluster's own axes is as
// thin as its slivers: a centroid, or a ray, meets O(1) of them a level.
//
// In the plane: within 4·2^-24 of the largest coordinate (rounding a planar polygon's corners to
// float moves them at most √3·2^-24 of it off the plane).
constexpr double kFlatUlps = 4.0 * 0x1p-24;

struct LaneFrame {
  dvec3 normal{0.0};                              // unit
  vec3 u{0.0f}, v{0.0f};                          // unit, in the plane: with the normal, the box's axes
  double offset = 0;                              // normal · y for y in the plane
  double thickness = -1;                          // every triangle lies within this of the plane; < 0: not flat
  double scale = 0;                               // the largest |coordinate|
  float lo[3] = {0, 0, 0}, hi[3] = {-1, -1, -1};  // the box along u, v, normal (none: empty), rounded out
  bool flat() const { return thickness >= 0; }
  // Within round-off of the plane; and of the box in it (within `slack` more).
  double round_off(const dvec3& y) const {
    return std::max(thickness, 0.0) + kFlatUlps * std::max({scale, std::abs(y.x), std::abs(y.y), std::abs(y.z)});
  }
  bool in_plane(const dvec3& y) const { return std::abs(glm::dot(normal, y) - offset) <= round_off(y); }
  bool in_box(const dvec3& y, double slack) const {
    const double pad = round_off(y) + slack, a = glm::dot(dvec3(u), y), b = glm::dot(dvec3(v), y);
    return a >= lo[0] - pad && a <= hi[0] + pad && b >= lo[1] - pad && b <= hi[1] + pad;
  }
  // Whether the line through y along axis k misses the box (grown by round-off).
  bool line_misses(const dvec3& y, int k) const {
    if (!(hi[0] >= lo[0])) return false;  // no box
    const double pad = kFlatUlps * std::max({scale, std::abs(y.x), std::abs(y.y), std::abs(y.z)});
    const dvec3 axes[3] = {dvec3(u), dvec3(v), normal};
    double t0 = -INFINITY, t1 = INFINITY;
    for (int a = 0; a < 3; ++a) {
      const double along = axes[a][k], at = glm::dot(axes[a], y);
      if (std::abs(along) < 1e-12) {
        if (at < lo[a] - pad || at > hi[a] + pad) return true;
        continue;
      }
      double ta = (lo[a] - pad - at) / along, tb = (hi[a] + pad - at) / along;
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
    }
    return t0 > t1;
  }
};

// The mean and scatter Σ (p - mean)(p - mean)ᵀ of a lane's vertices, merged up the tree
// (Chan et al.'s pairwise update: no cancellation far from the origin).
struct PointStats {
  double count = 0;
  dvec3 mean{0.0};
  Sym3<double> scatter;
  void add(const PointStats& o) {
    if (o.count == 0) return;
    const double n = count + o.count;
    const dvec3 d = o.mean - mean, w = d * (count * o.count / n);
    scatter += o.scatter;
    scatter += Sym3<double>{w.x * d.x, w.x * d.y, w.x * d.z, w.y * d.y, w.y * d.z, w.z * d.z};
    mean += d * (o.count / n);
    count = n;
  }
};

// Whether the frames pay. A centroid lies within beta radii of about beta² Σ r² / A leaf lanes
// (r their radii, A the area of the triangles they hold): Σ r² / A is about 1.5 on ordinary
// meshes and grows with a fan's n. Below kLongClusters the classification runs without frames:
// on an ordinary mesh their arrays' first touch alone costs about what the classification does.
constexpr double kLongClusters = 32.0;
}  // namespace

bool clusters_are_long(const TriangleTreeView& tree) {
  double radii = 0, area = 0;
  for (uint32_t k = 0; k < tree.bvh.node_count; ++k) {
    const WideNode& n = tree.bvh.nodes[k];
    for (int l = 0; l < kBvhWidth; ++l) {
      if (n.child[l] == kEmptyLane || n.count[l] == 0) continue;
      radii += sqr(double(tree.expansion[k].radius[l]));
      for (uint32_t t = n.child[l]; t < n.child[l] + n.count[l]; ++t) {
        const dvec3 p0(tree.vertices[3 * t]), p1(tree.vertices[3 * t + 1]), p2(tree.vertices[3 * t + 2]);
        area += 0.5 * glm::length(glm::cross(p1 - p0, p2 - p0));
      }
    }
  }
  return radii > kLongClusters * area;
}

namespace {

// Every lane's LaneFrame (none where the clusters are not long), in three walks of the tree (the
// root's four subtrees as tasks): up, the mean and scatter of each node's vertices; down, each
// lane's axes and whether it is flat; up again, its box along them. A lane is flat in its
// least-scatter plane when every vertex lies within kFlatUlps of the largest coordinate of it:
// tested on the vertices only where the scatter allows it (its RMS distance from the plane within
// that), so at O(1) a lane on a curved mesh. The lanes below a flat one take its plane (not each
// its own: the plane of a few slivers is tilted by the rounding of their corners over their
// width, far more than that rounding at the far side of the polygon). A box is the box of its
// children's boxes (exact for a leaf): looser than the vertices', never smaller.
std::vector<LaneFrame> lane_frames(const TriangleTreeView& tree) {
  if (tree.bvh.node_count == 0 || !clusters_are_long(tree)) return {};
  const size_t nodes = tree.bvh.node_count;
  std::vector<LaneFrame> out(nodes * kBvhWidth);
  std::vector<PointStats> stats(nodes);                   // of each node's vertices
  std::vector<uint32_t> first(nodes, 0), last(nodes, 0);  // its triangles, in leaf order
  std::vector<int32_t> parent_lane(nodes, -1);            // the lane that holds it
  // Runs visit(node, lane) over every lane below `node`, the root's four subtrees as tasks:
  // children before their parent (post) or after it (pre).
  auto walk = [&](auto& self, uint32_t node, bool post, const auto& visit) -> void {
    const WideNode& n = tree.bvh.nodes[node];
    auto lane = [&](int l) {
      if (n.child[l] == kEmptyLane) return;
      if (!post) visit(node, l);
      if (n.count[l] == 0) self(self, n.child[l], post, visit);
      if (post) visit(node, l);
    };
    if (node == 0) {
      tbb::parallel_for(0, kBvhWidth, lane);
    } else {
      for (int l = 0; l < kBvhWidth; ++l) lane(l);
    }
  };
  auto vertex = [&](uint32_t t, int c) { return dvec3(tree.vertices[3 * t + c]); };
  // A lane's triangles and statistics: a leaf's from its triangles, an inner lane's its node's.
  auto lane_range = [&](const WideNode& n, int l, uint32_t& begin, uint32_t& end) {
    begin = n.count[l] > 0 ? n.child[l] : first[n.child[l]];
    end = n.count[l] > 0 ? n.child[l] + n.count[l] : last[n.child[l]];
  };
  auto lane_stats = [&](const WideNode& n, int l) {
    if (n.count[l] == 0) return stats[n.child[l]];
    PointStats st;
    for (uint32_t t = n.child[l]; t < n.child[l] + n.count[l]; ++t)
      for (int c = 0; c < 3; ++c) st.mean += vertex(t, c);
    st.count = 3.0 * n.count[l];
    st.mean /= st.count;
    for (uint32_t t = n.child[l]; t < n.child[l] + n.count[l]; ++t)
      for (int c = 0; c < 3; ++c) {
        const dvec3 d = vertex(t, c) - st.mean;
        st.scatter += Sym3<double>{d.x * d.x, d.x * d.y, d.x * d.z, d.y * d.y, d.y * d.z, d.z * d.z};
      }
    return st;
  };
  // Up: each node's statistics and triangles, from its lanes'.
  auto up = [&](auto& self, uint32_t node) -> void {
    const WideNode& n = tree.bvh.nodes[node];
    auto below = [&](int l) {
      if (n.child[l] == kEmptyLane || n.count[l] > 0) return;
      parent_lane[n.child[l]] = int32_t(size_t(node) * kBvhWidth + l);
      self(self, n.child[l]);
    };
    if (node == 0) {
      tbb::parallel_for(0, kBvhWidth, below);
    } else {
      for (int l = 0; l < kBvhWidth; ++l) below(l);
    }
    first[node] = UINT32_MAX;
    for (int l = 0; l < kBvhWidth; ++l) {
      if (n.child[l] == kEmptyLane) continue;
      uint32_t begin, end;
      lane_range(n, l, begin, end);
      first[node] = std::min(first[node], begin);
      last[node] = std::max(last[node], end);
      stats[node].add(lane_stats(n, l));
    }
  };
  up(up, 0);
  // Down: each lane's axes, and whether it is flat (its parent lane before it).
  walk(walk, 0, false, [&](uint32_t node, int l) {
    const WideNode& n = tree.bvh.nodes[node];
    LaneFrame& f = out[size_t(node) * kBvhWidth + l];
    const LaneFrame* parent = parent_lane[node] >= 0 ? &out[size_t(parent_lane[node])] : nullptr;
    if (parent && !parent->flat()) parent = nullptr;
    const PointStats st = lane_stats(n, l);
    uint32_t begin, end;
    lane_range(n, l, begin, end);
    // Axes: of an inner lane the scatter's principal axes, the least one its plane's normal; of a
    // leaf (three in four lanes: the eigen-decomposition cost as much as the rest) its triangles'
    // normal (each turned to agree with the first) and its longest edge.
    dvec3 normal(0.0), u(0.0);
    double lambda[3];
    if (n.count[l] == 0) {
      dvec3 axes[3];
      symmetric_eigen(st.scatter, lambda, axes);
      const int smallest = lambda[0] <= lambda[1] ? (lambda[0] <= lambda[2] ? 0 : 2) : (lambda[1] <= lambda[2] ? 1 : 2);
      const int a = (smallest + 1) % 3, b = (smallest + 2) % 3;
      normal = axes[smallest];
      u = axes[lambda[a] >= lambda[b] ? a : b];
      lambda[0] = lambda[smallest];
    } else {
      double longest = -1;
      for (uint32_t t = begin; t < end; ++t) {
        const dvec3 tn = glm::cross(vertex(t, 1) - vertex(t, 0), vertex(t, 2) - vertex(t, 0));
        normal += glm::dot(tn, normal) >= 0 ? tn : -tn;
        for (int c = 0; c < 3; ++c) {
          const dvec3 e = vertex(t, (c + 1) % 3) - vertex(t, c);
          if (glm::dot(e, e) > longest) {
            longest = glm::dot(e, e);
            u = e;
          }
        }
      }
      lambda[0] = 0;  // the flatness test below sees only a few vertices
    }
    f.normal = parent ? parent->normal : glm::normalize(normal);
    f.offset = parent ? parent->offset : glm::dot(f.normal, st.mean);
    // The in-plane axis, flattened into the plane.
    u -= f.normal * glm::dot(f.normal, u);
    if (!(glm::length(u) > 1e-3)) u = std::abs(f.normal.x) < 0.6 ? dvec3(1, 0, 0) : dvec3(0, 1, 0);
    u -= f.normal * glm::dot(f.normal, u);
    f.u = vec3(glm::normalize(u));
    f.v = vec3(glm::cross(f.normal, dvec3(f.u)));
    const dvec3 mean = st.mean;
    const Sym3<double>& scatter = st.scatter;
    // A bound on |coordinate|: the mean plus the spread.
    f.scale = std::max({std::abs(mean.x), std::abs(mean.y), std::abs(mean.z)}) + std::sqrt(scatter.trace());
    const double tolerance = kFlatUlps * f.scale;
    if (parent) {
      f.thickness = parent->thickness;
    } else if (lambda[0] <= sqr(tolerance) * st.count) {
      double thickness = 0;
      for (uint32_t t = begin; t < end; ++t)
        for (int c = 0; c < 3; ++c)
          thickness = std::max(thickness, std::abs(glm::dot(f.normal, vertex(t, c)) - f.offset));
      f.thickness = thickness <= tolerance ? thickness : -1.0;  // also NaN: not flat
    }
  });
  // Up again: the boxes.
  walk(walk, 0, true, [&](uint32_t node, int l) {
    const WideNode& n = tree.bvh.nodes[node];
    LaneFrame& f = out[size_t(node) * kBvhWidth + l];
    const dvec3 axis[3] = {dvec3(f.u), dvec3(f.v), f.normal};
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    auto extend = [&](const dvec3& p) {
      for (int a = 0; a < 3; ++a) {
        const double x = glm::dot(axis[a], p);
        lo[a] = std::min(lo[a], x);
        hi[a] = std::max(hi[a], x);
      }
    };
    auto store = [&] {
      for (int a = 0; a < 3; ++a) {
        f.lo[a] = std::nextafter(float(lo[a]), -INFINITY);
        f.hi[a] = std::nextafter(float(hi[a]), INFINITY);
      }
    };
    if (n.count[l] > 0) {
      for (uint32_t t = n.child[l]; t < n.child[l] + n.count[l]; ++t)
        for (int c = 0; c < 3; ++c) extend(vertex(t, c));
      store();
      return;
    }
    const WideNode& below = tree.bvh.nodes[n.child[l]];
    for (int m = 0; m < kBvhWidth; ++m) {
      if (below.child[m] == kEmptyLane) continue;
      const LaneFrame& c = out[size_t(n.child[l]) * kBvhWidth + m];
      for (int corner = 0; corner < 8; ++corner)
        extend(double(corner & 1 ? c.hi[0] : c.lo[0]) * dvec3(c.u) +
               double(corner & 2 ? c.hi[1] : c.lo[1]) * dvec3(c.v) + double(corner & 4 ? c.hi[2] : c.lo[2]) * c.normal);
    }
    store();
  });
  return out;
}

// The multipole sum with the triangle and any triangle coincident with it at its centroid left
// out. The centroid lies on those, where a solid angle is ±2π by which side round-off puts the
// point, so they must not be summed; they are never in a far cluster (the centroid lies inside
// every ball holding them). Instead they are counted: a stack of coincident triangles (a soup
// that lists a face twice) makes w jump by its net orientation, not by one.
struct SumWithoutStack {
  detail::TaylorSum<2, false, false> sum;
  uint32_t left_out;
  vec3 normal;  // of the left-out triangle
  const LaneFrame* frames;
  int jump = 1;
  void far(uint32_t node, int lane, const vec3& d) { sum.far(node, lane, d); }
  // A flat cluster in the plane of x adds nothing unless it contains x; its expansion, taken where
  // it is far, is zero there too (every term is odd in the normal direction).
  bool skip_near(uint32_t node, int lane) const {
    if (frames == nullptr) return false;
    const LaneFrame& f = frames[size_t(node) * kBvhWidth + lane];
    const dvec3 x(sum.x);
    return f.flat() && f.in_plane(x) && !f.in_box(x, 0.0);
  }
  void near(uint32_t t, const vec3& p0, const vec3& p1, const vec3& p2) {
    if (t == left_out) return;
    if (contains_x(p0, p1, p2)) {
      jump += glm::dot(glm::cross(p1 - p0, p2 - p0), normal) > 0.0f ? 1 : -1;
      return;
    }
    sum.near(t, p0, p1, p2);
  }
  // x in the triangle's plane (within round-off of the coordinates) and inside it (van
  // Oosterom's denominator < 0: the solid angle's ±2π branch). Float cannot tell either beside a
  // long edge (winding_number.h, kNearConditioning): only triangles it finds near enough to being
  // on are decided, in double.
  bool contains_x(const vec3& p0, const vec3& p1, const vec3& p2) const {
    float length_product;
    const SolidAngleTangent<float> near = triangle_solid_angle_tangent(p0, p1, p2, sum.x, length_product);
    if (!near_float_ill_conditioned(near, length_product)) return false;
    const dvec3 x(sum.x), q0(p0), q1(p1), q2(p2);
    double exact_length_product;
    const SolidAngleTangent<double> exact = triangle_solid_angle_tangent(q0, q1, q2, x, exact_length_product);
    const double scale =
        std::max({std::abs(x.x), std::abs(x.y), std::abs(x.z), std::abs(q0.x), std::abs(q0.y), std::abs(q0.z),
                  std::abs(q1.x), std::abs(q1.y), std::abs(q1.z), std::abs(q2.x), std::abs(q2.y), std::abs(q2.z)});
    return std::abs(exact.numerator) <= kFlatUlps * scale * glm::length(glm::cross(q1 - q0, q2 - q0)) &&
           exact.denominator < 0.0;
  }
};
}  // namespace

void other_triangles_winding_by_crossings(const ModelView& view, const TriangleTreeView& spanning, std::span<float> out,
                                          std::span<int8_t> jump) {
  const TriangleTreeView& tree = view.triangles;
  const vec3 extent = view.bounds.hi - view.bounds.lo;
  const float diagonal = glm::length(extent);
  const std::vector<LaneFrame> frames = lane_frames(tree);
  // M's jumps ahead of x along `frame`, less the lanes whose oriented box the ray's line misses,
  // where the clusters are long: the axis-aligned box of a cluster of slivers reaches across the
  // whole fan (a crossing ray of the classification met most of them), its oriented box is as
  // thin as the cluster.
  const auto mesh_ahead = [&](const RayFrame& frame) {
    int ahead = 0;
    auto crossing = [&](uint32_t, float, int k) { ahead += k; };
    const dvec3 origin(frame.origin);
    visit_axis_crossings(tree.bvh, tree.vertices, frame, 0.0f, crossing, 0, [&](uint32_t ni, const WideNode&, int l) {
      return frames.empty() || !frames[size_t(ni) * kBvhWidth + l].line_misses(origin, frame.kz);
    });
    return ahead;
  };
  // w at x, exactly: w_S(x) less M's jumps ahead of x plus S's, along the axis ray that leaves the
  // box soonest (field/crossing_winding.h).
  const auto winding_at = [&](const vec3& x) {
    const RayFrame frame = shortest_exit_axis_ray(view.bounds, x);
    double w = -double(mesh_ahead(frame));
    if (spanning.triangle_count > 0) {
      using ConeSum = detail::ConeCrossingVisitor<false, false>::type;
      ConeSum cone(spanning, frame, x, kConeBeta, nullptr);
      cone.traverse();
      w += double(cone.jumps) + double(cone.winding());
    }
    return w;
  };
  // The two points of triangle i (tree order): its centroid c ∓ δu along the unit normal u, on
  // either side of the triangle's stack (it and any triangle coincident with it at c): the
  // difference of w there is the stack's jump k, their mean w_o at c to second order in δ. Along
  // the normal, not along the ray's axis: a tilted offset moves the two points apart across the
  // plane too, and beside a sliver's neighbours w_o then errs by that shift times δ over the
  // squared width. δ is far above the rounding of the centroid and of the vertices relative to it
  // (a few ulps of the coordinates), and far below any feature a mesh resolves. (Not c itself: a
  // stacked copy that is a loop of ∂M on its own has c as its cone's apex, where w_C is
  // undefined.) A zero-area triangle has no side of its own: both points are c.
  const auto sides = [&](uint32_t i, vec3(&point)[2], bool& has_area) {
    const dvec3 p0(tree.vertices[3 * i]), p1(tree.vertices[3 * i + 1]), p2(tree.vertices[3 * i + 2]);
    const dvec3 centroid = (p0 + p1 + p2) / 3.0;
    const dvec3 normal = glm::cross(p1 - p0, p2 - p0);  // in double: a sliver's is exact, not float noise
    const double area2 = glm::length(normal);
    const double delta =
        2e-6 * (double(diagonal) + std::max({std::abs(centroid.x), std::abs(centroid.y), std::abs(centroid.z)}));
    const dvec3 u = area2 > 0.0 ? normal / area2 : dvec3(0.0, 0.0, 1.0);
    point[0] = vec3(centroid - delta * u);
    point[1] = vec3(centroid + delta * u);
    has_area = area2 > 0.0;
  };
  // A closed mesh has whole-number sides, so its w_o is an exact half-integer.
  const auto store = [&](uint32_t i, double w_behind, double w_front, bool has_area) {
    const long own = has_area ? std::lround(w_behind - w_front) : 0;
    out[tree.triangle_ids[i]] = float(0.5 * (w_behind + w_front));
    jump[tree.triangle_ids[i]] = int8_t(own < -127 ? -127 : (own > 127 ? 127 : own));
  };
  const auto classify_one = [&](uint32_t i) {
    vec3 point[2];
    bool has_area;
    sides(i, point, has_area);
    store(i, winding_at(point[0]), winding_at(point[1]), has_area);
  };
#if GWNRT_HOST_LANES && defined(__AVX__)
  // Four neighbouring triangles (tree order) at once: w_S at their eight points from one batched
  // traversal of S's tree, each point's jumps (S's and M's) from walks along the first point's
  // axis (the batch needs one axis; each point's sign is the side of the box it leaves sooner).
  // A point the batch is unsure of takes winding_at. Returns how many it was unsure of.
  constexpr uint32_t kGroup = 4;
  const auto classify_group = [&](uint32_t first, uint32_t count) {
    vec3 point[kGroup][2];
    bool has_area[kGroup];
    for (uint32_t k = 0; k < count; ++k) sides(first + k, point[k], has_area[k]);
    const int axis = shortest_exit_axis_ray(view.bounds, point[0][0]).kz;
    int mesh_jumps[kGroup][2], cone_jumps[kGroup][2];
    ConeWindingBatch<2 * kGroup> batch;
    for (uint32_t k = 0; k < count; ++k)
      for (int side = 0; side < 2; ++side) {
        const vec3& x = point[k][side];
        const RayFrame frame = shortest_exit_axis_ray(view.bounds, x, 1u << axis);
        mesh_jumps[k][side] = mesh_ahead(frame);
        int ahead = 0;
        visit_axis_crossings(spanning.bvh, spanning.vertices, frame, 0.0f,
                             [&](uint32_t, float, int jump) { ahead += jump; });
        cone_jumps[k][side] = ahead;
        batch.add(x);
      }
    batch.evaluate(spanning, kConeBeta, axis);
    uint32_t unsure = 0;
    for (uint32_t k = 0; k < count; ++k) {
      double w[2];
      for (int side = 0; side < 2; ++side) {
        const float f = batch.crossing_winding(int(2 * k + side), cone_jumps[k][side], mesh_jumps[k][side]);
        unsure += !(f == f);
        w[side] = f == f ? double(f) : winding_at(point[k][side]);
      }
      store(first + k, w[0], w[1], has_area[k]);
    }
    return unsure;
  };
  // Runs of kRunGroups groups: once a group leaves half its points unsure (a flat fan, whose
  // spanning surface lies in M's plane: every side point is within the batch's plane tolerance),
  // the rest of its run goes one by one. Fixed runs, so the result does not depend on the threads.
  constexpr uint32_t kRunGroups = 16;
  if (spanning.triangle_count > 0) {
    constexpr uint32_t kRun = kGroup * kRunGroups;
    tbb::parallel_for(uint32_t(0), (tree.triangle_count + kRun - 1) / kRun, [&](uint32_t run) {
      const uint32_t end = std::min(tree.triangle_count, (run + 1) * kRun);
      bool batching = true;
      for (uint32_t first = run * kRun; first < end; first += kGroup) {
        const uint32_t count = std::min(kGroup, end - first);
        if (batching)
          batching = classify_group(first, count) <= count;  // half its 2 · count points
        else
          for (uint32_t i = first; i < first + count; ++i) classify_one(i);
      }
    });
    return;
  }
#endif
  tbb::parallel_for(uint32_t(0), tree.triangle_count, classify_one);
}

void other_triangles_winding(const TriangleTree& tree, std::span<const uint32_t> leaves, float beta,
                             std::span<float> out, std::span<int8_t> jump) {
  const TriangleTreeView view = tree.view();
  const std::vector<LaneFrame> frames = lane_frames(view);
  tbb::parallel_for(size_t(0), leaves.size(), [&](size_t k) {
    const uint32_t i = leaves[k];
    const vec3 &p0 = view.vertices[3 * i], &p1 = view.vertices[3 * i + 1], &p2 = view.vertices[3 * i + 2];
    const vec3 centroid = (p0 + p1 + p2) / 3.0f;
    SumWithoutStack visitor{
        {view, centroid, {}}, i, glm::cross(p1 - p0, p2 - p0), frames.empty() ? nullptr : frames.data()};
    visit_multipole(view, centroid, beta, visitor);
    out[view.triangle_ids[i]] = visitor.sum.acc.omega * kInv4Pi;
    jump[view.triangle_ids[i]] = int8_t(visitor.jump < -127 ? -127 : (visitor.jump > 127 ? 127 : visitor.jump));
  });
}

}  // namespace gwnrt
