// The cell topology of dual contouring (meshing/cell_topology.h): each cell's patch components and
// loops against a flood fill over the cube's surface, for all 256 corner patterns, and the
// numbering of corners and edges.
#include <cstdint>
#include <map>
#include <utility>

#include <gtest/gtest.h>

#include "gwnrt/meshing/cell_topology.h"

namespace gwnrt {
namespace {

// ---------------------------------------------------------------------------------------------
// Cell components against a flood fill over the cube's surface: the patch's loops are the
// boundaries between the inside regions (inside corners joined along cube edges) and the
// outside regions (outside corners joined along cube edges and across the ambiguous faces, where
// the rule keeps the inside corners apart); on the cube's surface, a sphere, two adjacent
// regions share exactly one loop, so an edge's loop is named by the pair of regions it joins.

struct Regions {
  int of_corner[8];
};

Regions flood_regions(uint32_t inside) {
  int parent[8];
  for (int c = 0; c < 8; ++c) parent[c] = c;
  const auto find = [&](int c) {
    while (parent[c] != c) c = parent[c];
    return c;
  };
  const auto join = [&](int a, int b) { parent[find(a)] = find(b); };
  const auto in = [&](int c) { return (inside >> c) & 1u; };
  for (int c = 0; c < 8; ++c)
    for (int a = 0; a < 3; ++a) {
      const int d = c ^ (1 << a);
      if (in(c) == in(d)) join(c, d);
    }
  for (int a = 0; a < 3; ++a)
    for (int side = 0; side < 2; ++side) {
      const int b = (a + 1) % 3, c = (a + 2) % 3, base = side << a;
      const int p = base, q = base | (1 << b), r = base | (1 << b) | (1 << c), s = base | (1 << c);
      const bool ambiguous = in(p) == in(r) && in(q) == in(s) && in(p) != in(q);
      if (ambiguous) {  // the outside diagonal is joined across the face
        if (in(p))
          join(q, s);
        else
          join(p, r);
      }
    }
  Regions out;
  for (int c = 0; c < 8; ++c) out.of_corner[c] = find(c);
  return out;
}

TEST(MeshingCell, ComponentsMatchFloodFillForAll256Patterns) {
  for (uint32_t mask = 0; mask < 256; ++mask) {
    const CellComponents parts = cell_components(mask);
    const Regions regions = flood_regions(mask);
    std::map<std::pair<int, int>, int> loop_of_pair;
    std::map<int, std::pair<int, int>> pair_of_loop;
    for (int e = 0; e < kCellEdges; ++e) {
      const int c0 = edge_corner(e), c1 = c0 | (1 << edge_axis(e));
      const bool changes = ((mask >> c0) & 1u) != ((mask >> c1) & 1u);
      ASSERT_EQ(parts.of_edge[e] >= 0, changes) << "pattern " << mask << " edge " << e;
      if (!changes) continue;
      const int inside = (mask >> c0) & 1u ? c0 : c1, outside = inside == c0 ? c1 : c0;
      const std::pair<int, int> key{regions.of_corner[inside], regions.of_corner[outside]};
      const auto [it, fresh] = loop_of_pair.emplace(key, parts.of_edge[e]);
      EXPECT_EQ(it->second, parts.of_edge[e]) << "pattern " << mask << " edge " << e << ": two loops for one pair";
      const auto [jt, fresh2] = pair_of_loop.emplace(parts.of_edge[e], key);
      EXPECT_EQ(jt->second, key) << "pattern " << mask << " edge " << e << ": one loop for two pairs";
    }
    EXPECT_EQ(int(loop_of_pair.size()), parts.count) << "pattern " << mask;
  }
}

// Whether some face of the cell holds both edges.
bool share_a_face(int a, int b) {
  for (int face = 0; face < 6; ++face) {
    const CellFace f = cell_face(face);
    bool has_a = false, has_b = false;
    for (int k = 0; k < 4; ++k) {
      has_a |= f.edge[k] == a;
      has_b |= f.edge[k] == b;
    }
    if (has_a && has_b) return true;
  }
  return false;
}

// Every pair of cells sharing an ambiguous face (the face's 4 signs, the two cells' other 4 each):
// where both have a tunnel through it, all four of the face's crossed edges are one component
// in both cells under the default pairing (their two vertices would be joined by four triangles),
// and after the flip in neither.
TEST(MeshingCell, FlippingAFaceWithTunnelsOnBothSidesSeparatesItsSegments) {
  const auto one_component = [](uint32_t inside, int face, uint32_t flipped) {
    const CellComponents parts = cell_components(inside, flipped);
    const CellFace f = cell_face(face);
    for (int k = 1; k < 4; ++k)
      if (parts.of_edge[f.edge[k]] != parts.of_edge[f.edge[0]]) return false;
    return true;
  };
  int both_tunnels = 0;
  for (int face = 0; face < 6; ++face) {
    const CellFace f = cell_face(face), g = cell_face(face ^ 1);  // g: the same corners, one cell over
    for (uint32_t a = 0; a < 256; ++a)
      for (uint32_t far = 0; far < 16; ++far) {
        // The cell across: its face g holds a's face f corners; its other four corners from `far`.
        uint32_t b = 0;
        for (int k = 0; k < 4; ++k) b |= ((a >> f.corner[k]) & 1u) << g.corner[k];
        for (int k = 0; k < 4; ++k) b |= ((far >> k) & 1u) << cell_face(face).corner[k];
        if (!tunnel_through_face(a, face) || !tunnel_through_face(b, face ^ 1)) continue;
        ++both_tunnels;
        ASSERT_TRUE(one_component(a, face, 0) && one_component(b, face ^ 1, 0)) << a << " " << b;
        EXPECT_FALSE(one_component(a, face, 1u << face)) << "pattern " << a << " face " << face;
        EXPECT_FALSE(one_component(b, face ^ 1, 1u << (face ^ 1))) << "pattern " << b << " face " << (face ^ 1);
      }
  }
  EXPECT_GT(both_tunnels, 0);
}

TEST(MeshingCell, LoopsAreTheComponentsInOrder) {
  for (uint32_t mask = 0; mask < 256; ++mask) {
    const CellComponents parts = cell_components(mask);
    const CellLoops loops = cell_loops(mask);
    ASSERT_EQ(loops.count, parts.count) << "pattern " << mask;
    int first = 0, seen = 0;
    for (int l = 0; l < loops.count; ++l) {
      const int n = loops.length[l];
      ASSERT_GE(n, 3) << "pattern " << mask;
      const int component = parts.of_edge[loops.edge[first]];
      for (int k = 0; k < n; ++k) {
        const int e = loops.edge[first + k], next = loops.edge[first + (k + 1) % n];
        EXPECT_EQ(parts.of_edge[e], component) << "pattern " << mask << ": a loop crosses components";
        EXPECT_TRUE(share_a_face(e, next)) << "pattern " << mask << ": consecutive edges " << e << ", " << next;
      }
      first += n;
      seen += n;
    }
    int crossed = 0;
    for (int e = 0; e < kCellEdges; ++e) crossed += parts.of_edge[e] >= 0;
    EXPECT_EQ(seen, crossed) << "pattern " << mask;
  }
}

TEST(MeshingCell, EdgeNumberingIsConsistent) {
  for (int e = 0; e < kCellEdges; ++e) {
    const int c = edge_corner(e);
    EXPECT_EQ((c >> edge_axis(e)) & 1, 0);
    EXPECT_EQ(corner_edge(c, edge_axis(e)), e);
  }
}

}  // namespace
}  // namespace gwnrt
