// The multipole triangle tree: a wide BVH over triangles with the Taylor moments of every lane
// (built in core/src/geometry/triangle_tree.cpp). The same tree serves M, the cone over ∂M and the
// sheets.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "gwnrt/geometry/bvh.h"
#include "gwnrt/geometry/mesh.h"
#include "gwnrt/geometry/model_view.h"

namespace gwnrt {

struct TriangleTree {
  WideBvh bvh;
  std::vector<WideNodeExpansion> expansion;
  std::vector<WideNodeOrder1> order1;
  std::vector<WideNodeOrder2> order2;
  std::vector<vec3> vertices;          // 3 per triangle, leaf order
  std::vector<uint32_t> triangle_ids;  // leaf order -> input triangle
  std::vector<float> corner_columns;   // empty, or TriangleTreeView::corner_columns
  TriangleTreeView view() const;
};

// Fills tree.corner_columns from its vertices: for the host's lanes over a tree whose near
// triangles are summed four at a time in double (the cone's: gathering them from the vertices
// was a third of the exact sweep of φ).
void add_corner_columns(TriangleTree& tree);

Status build_triangle_tree(const Mesh& mesh, uint32_t max_leaf_size, TriangleTree& out);
// Whether a tree gets the moments of the multipole expansion, or only what distances need (the
// BVH, the vertices and ids: the sheet tree, sdf/sheets.h; its expansion arrays stay empty).
enum class TreeMoments { kWith, kWithout };

// The tree over the triangles `selection` of the mesh (input indices, none of zero area); its
// triangle_ids are those input indices.
Status build_triangle_tree(const Mesh& mesh, std::span<const uint32_t> selection, uint32_t max_leaf_size,
                           TriangleTree& out, TreeMoments moments = TreeMoments::kWith);
// The tree over base's triangles whose input index t has keep[t] != 0, with base's topology:
// every leaf keeps its selected triangles in leaf order, lanes with none left below are
// emptied, and boxes and moments are those of what is kept. No splits, so far cheaper than a
// build; where at least a quarter of the triangles are kept it is at most a level deeper than a
// build over them would be (log4 of the ratio).
Status filter_triangle_tree(const TriangleTree& base, std::span<const uint8_t> keep, TriangleTree& out,
                            TreeMoments moments = TreeMoments::kWith);

}  // namespace gwnrt
