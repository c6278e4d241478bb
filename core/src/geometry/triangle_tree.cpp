// The multipole tree: the wide BVH over the triangles plus, per lane, the expansion centre,
// radius and moments (docs/design.md §2), computed bottom-up in double and stored compressed in float.
#include <algorithm>
#include <cmath>
#include <string>

#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include "gwnrt/geometry/triangle_tree.h"

#include "geometry/raw_moments.h"

namespace gwnrt {
namespace {

class MomentBuilder {
 public:
  explicit MomentBuilder(TriangleTree& tree) : tree_(tree) {}

  void run() {
    const size_t n = tree_.bvh.nodes.size();
    tree_.expansion.assign(n, WideNodeExpansion{});
    tree_.order1.assign(n, WideNodeOrder1{});
    tree_.order2.assign(n, WideNodeOrder2{});
    node_moments(0, 0);
  }

 private:
  RawMoments leaf_moments(uint32_t first, uint32_t count) const {
    RawMoments m;
    dvec3 weighted{0.0}, plain{0.0};
    for (uint32_t t = first; t < first + count; ++t) {
      const dvec3 p[3] = {dvec3(tree_.vertices[3 * t]), dvec3(tree_.vertices[3 * t + 1]),
                          dvec3(tree_.vertices[3 * t + 2])};
      const double area = 0.5 * glm::length(glm::cross(p[1] - p[0], p[2] - p[0]));
      const dvec3 centroid = (p[0] + p[1] + p[2]) / 3.0;
      weighted += area * centroid;
      plain += centroid;
      m.area += area;
    }
    m.centre = m.area > 0 ? weighted / m.area : plain / double(count);
    m.area = 0;
    for (uint32_t t = first; t < first + count; ++t) {
      const dvec3 p[3] = {dvec3(tree_.vertices[3 * t]), dvec3(tree_.vertices[3 * t + 1]),
                          dvec3(tree_.vertices[3 * t + 2])};
      add_triangle_moments(p, m.centre, m);
    }
    return m;
  }

  // Computes every lane of node `index` and returns the moments of the whole node.
  RawMoments node_moments(uint32_t index, int depth) {
    const WideNode& node = tree_.bvh.nodes[index];
    RawMoments lanes[kBvhWidth];
    auto lane_work = [&](int i) {
      if (node.child[i] == kEmptyLane) return;
      lanes[i] =
          node.count[i] > 0 ? leaf_moments(node.child[i], node.count[i]) : node_moments(node.child[i], depth + 1);
    };
    if (depth < 4) {
      tbb::task_group tasks;
      for (int i = 0; i < kBvhWidth; ++i) tasks.run([&, i] { lane_work(i); });
      tasks.wait();
    } else {
      for (int i = 0; i < kBvhWidth; ++i) lane_work(i);
    }

    WideNodeExpansion& ex = tree_.expansion[index];
    WideNodeOrder1& o1 = tree_.order1[index];
    WideNodeOrder2& o2 = tree_.order2[index];
    RawMoments total;
    dvec3 weighted{0.0}, plain{0.0};
    int used = 0;
    double corner[kBvhWidth] = {};  // farthest corner of each lane's box from the lane's centre
    for (int i = 0; i < kBvhWidth; ++i) {
      if (node.child[i] == kEmptyLane) {
        // An empty lane is never far (NaN centre) and is skipped when near.
        for (int a = 0; a < 3; ++a) ex.centre[a][i] = NAN;
        continue;
      }
      // A leaf's ball passes through the farthest corner of its box; an inner lane's radius
      // was set by node_moments from its children.
      corner[i] = farthest_corner(node, i, lanes[i].centre);
      if (node.count[i] > 0) lanes[i].radius = corner[i];
      store_lane_moments(lanes[i], i, ex, o1, o2);
      weighted += lanes[i].area * lanes[i].centre;
      plain += lanes[i].centre;
      total.area += lanes[i].area;
      ++used;
    }
    total.centre = total.area > 0 ? weighted / total.area : plain / double(std::max(used, 1));
    const double area = total.area;
    total.area = 0;
    // The node's ball (what beta is measured against) is the smallest about its centre that
    // holds the balls through the farthest box corner of each of its lanes. It bounds every
    // triangle below, and is a little looser than the farthest corner of the node's own box
    // where the lanes sit unevenly about p̄, which is where the truncation error is largest.
    // It beats the node's box corner (HDK's choice) and balls of balls at every level for the
    // same work (docs/performance.md, queries).
    for (int i = 0; i < kBvhWidth; ++i) {
      if (node.child[i] == kEmptyLane) continue;
      total.radius = std::max(total.radius, glm::length(lanes[i].centre - total.centre) + corner[i]);
      lanes[i].shift_to(total.centre);
      total.add(lanes[i]);
    }
    total.area = area;
    return total;
  }

  TriangleTree& tree_;
};

}  // namespace

TriangleTreeView TriangleTree::view() const {
  const uint32_t count = uint32_t(triangle_ids.size());
  return {bvh.view(),
          expansion.data(),
          order1.data(),
          order2.data(),
          vertices.data(),
          triangle_ids.data(),
          count,
          corner_columns.empty() ? nullptr : corner_columns.data(),
          corner_columns.empty() ? 0u : count + kCornerColumnPadding};
}

void add_corner_columns(TriangleTree& tree) {
  const size_t count = tree.triangle_ids.size(), stride = count + kCornerColumnPadding;
  tree.corner_columns.clear();
  if (count == 0) return;
  tree.corner_columns.resize(9 * stride);
  for (size_t t = 0; t < stride; ++t) {
    const size_t from = std::min(t, count - 1);
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) tree.corner_columns[(3 * j + k) * stride + t] = tree.vertices[3 * from + j][k];
  }
}

Status build_triangle_tree(const Mesh& mesh, uint32_t max_leaf_size, TriangleTree& out) {
  // Zero-area triangles contribute nothing to w, but evaluated in float near their line their
  // solid angle is noise of up to ±2π; so they are not part of the tree (nor of M for distances).
  std::vector<uint32_t> kept;
  kept.reserve(mesh.triangles.size());
  for (uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    const uvec3 tri = mesh.triangles[t];
    if (!is_degenerate_triangle(mesh.positions[tri[0]], mesh.positions[tri[1]], mesh.positions[tri[2]]))
      kept.push_back(t);
  }
  return build_triangle_tree(mesh, kept, max_leaf_size, out);
}

Status build_triangle_tree(const Mesh& mesh, std::span<const uint32_t> selection, uint32_t max_leaf_size,
                           TriangleTree& out, TreeMoments moments) {
  const size_t n = selection.size();
  std::vector<Aabb> bounds(n);
  tbb::parallel_for(size_t(0), n, [&](size_t i) {
    for (int k = 0; k < 3; ++k) bounds[i].extend(mesh.positions[mesh.triangles[selection[i]][k]]);
  });
  TriangleTree tree;
  if (Status s = build_wide_bvh(bounds, max_leaf_size, tree.bvh); !s.ok()) return s;
  tree.triangle_ids.resize(n);
  for (size_t i = 0; i < n; ++i) tree.triangle_ids[i] = selection[tree.bvh.primitive_order[i]];
  tree.vertices.resize(3 * n);
  tbb::parallel_for(size_t(0), n, [&](size_t i) {
    const uvec3 tri = mesh.triangles[tree.triangle_ids[i]];
    for (int k = 0; k < 3; ++k) tree.vertices[3 * i + k] = mesh.positions[tri[k]];
  });
  if (n > 0 && moments == TreeMoments::kWith) MomentBuilder(tree).run();  // an empty tree has no root for them
  out = std::move(tree);
  return Status::Ok();
}

Status filter_triangle_tree(const TriangleTree& base, std::span<const uint8_t> keep, TriangleTree& out,
                            TreeMoments moments) {
  const size_t n = base.triangle_ids.size();
  for (const uint32_t id : base.triangle_ids)
    if (id >= keep.size())
      return {StatusCode::kInvalidArgument, "filter_triangle_tree: triangle " + std::to_string(id) +
                                                " of the tree is beyond the " + std::to_string(keep.size()) +
                                                " flags given"};
  // kept_before[i]: how many of the base's leaf-order triangles before i are kept, their new
  // leaf-order index.
  std::vector<uint32_t> kept_before(n + 1, 0);
  for (size_t i = 0; i < n; ++i) kept_before[i + 1] = kept_before[i] + (keep[base.triangle_ids[i]] != 0 ? 1u : 0u);
  const uint32_t kept = kept_before[n];
  TriangleTree tree;
  if (kept == 0) {  // an empty tree, as a build over no triangles makes it
    if (Status s = build_wide_bvh({}, 1, tree.bvh); !s.ok()) return s;
    out = std::move(tree);
    return Status::Ok();
  }
  tree.triangle_ids.resize(kept);
  tree.vertices.resize(3 * size_t(kept));
  tbb::parallel_for(size_t(0), n, [&](size_t i) {
    if (kept_before[i + 1] == kept_before[i]) return;
    const uint32_t j = kept_before[i];
    tree.triangle_ids[j] = base.triangle_ids[i];
    for (int k = 0; k < 3; ++k) tree.vertices[3 * size_t(j) + k] = base.vertices[3 * i + k];
  });
  tree.bvh.nodes = base.bvh.nodes;
  tree.bvh.depth = base.bvh.depth;
  tree.bvh.primitive_order.resize(kept);
  for (uint32_t j = 0; j < kept; ++j) tree.bvh.primitive_order[j] = j;
  // Bottom up: the builder numbers every child after its parent. Lanes left with nothing below
  // are emptied (an inverted box, as the builder leaves unused lanes); nodes only they reached
  // stay in the array, unreached.
  std::vector<uint32_t> kept_below(tree.bvh.nodes.size(), 0);
  for (size_t k = tree.bvh.nodes.size(); k-- > 0;) {
    WideNode& node = tree.bvh.nodes[k];
    uint32_t total = 0;
    for (int l = 0; l < kBvhWidth; ++l) {
      if (node.child[l] == kEmptyLane) continue;
      Aabb box;
      if (node.count[l] > 0) {
        if (size_t(node.child[l]) + node.count[l] > n)
          return {StatusCode::kInvalidArgument, "filter_triangle_tree: node " + std::to_string(k) +
                                                    " holds triangles beyond the tree's " + std::to_string(n)};
        const uint32_t first = kept_before[node.child[l]], count = kept_before[node.child[l] + node.count[l]] - first;
        for (uint32_t t = first; t < first + count; ++t)
          for (int c = 0; c < 3; ++c) box.extend(tree.vertices[3 * size_t(t) + c]);
        node.child[l] = count > 0 ? first : kEmptyLane;
        node.count[l] = count;
        total += count;
      } else if (node.child[l] <= k || node.child[l] >= tree.bvh.nodes.size()) {
        return {StatusCode::kInvalidArgument, "filter_triangle_tree: node " + std::to_string(k) + " has child " +
                                                  std::to_string(node.child[l]) +
                                                  ", not after it (the tree was not made by build_wide_bvh)"};
      } else if (kept_below[node.child[l]] > 0) {
        const WideNode& child = tree.bvh.nodes[node.child[l]];
        for (int m = 0; m < kBvhWidth; ++m)
          if (child.child[m] != kEmptyLane)
            for (int a = 0; a < 3; ++a) {
              box.lo[a] = std::min(box.lo[a], child.lo[a][m]);
              box.hi[a] = std::max(box.hi[a], child.hi[a][m]);
            }
        total += kept_below[node.child[l]];
      } else {
        node.child[l] = kEmptyLane;
      }
      for (int a = 0; a < 3; ++a) {
        node.lo[a][l] = box.lo[a];
        node.hi[a][l] = box.hi[a];
      }
    }
    kept_below[k] = total;
  }
  if (moments == TreeMoments::kWith) MomentBuilder(tree).run();
  out = std::move(tree);
  return Status::Ok();
}

}  // namespace gwnrt
