// Where a cell's sign pattern is split into surface components: the numbering of a cube's
// corners, edges and faces, and the connected components of the surface patch inside one cell
// (one dual-contouring vertex each, as in Nielson's dual marching cubes and manifold DC).
// Host-and-device: computed from the 8 corner signs each time (about a hundred operations), no
// table to copy to the device.
#pragma once

#include <array>
#include <cstdint>

#include "gwnrt/base/hd.h"

namespace gwnrt {

// Corner c of a cell sits at offset (c & 1, (c >> 1) & 1, (c >> 2) & 1) cells from its lowest
// corner. Edge e runs along axis a = e / 4 from the corner with bit a clear; its other two
// coordinates are the bits of e % 4: the axis (a + 1) % 3 in bit 0, (a + 2) % 3 in bit 1.
inline constexpr int kCellCorners = 8;
inline constexpr int kCellEdges = 12;

GWNRT_HD constexpr int edge_axis(int edge) { return edge >> 2; }

// The corner at the edge's lower end.
GWNRT_HD constexpr int edge_corner(int edge) {
  const int a = edge >> 2, u = edge & 1, v = (edge >> 1) & 1;
  return (u << ((a + 1) % 3)) | (v << ((a + 2) % 3));
}

// The edge along axis a from corner c (whose bit a is clear).
GWNRT_HD constexpr int corner_edge(int corner, int axis) {
  return 4 * axis + ((corner >> ((axis + 1) % 3)) & 1) + 2 * ((corner >> ((axis + 2) % 3)) & 1);
}

// The surface components of one cell: which sign-changing edges belong to which closed loop of
// the patch. A corner is inside when w > w*; `inside` has bit c set for inside corner c.
struct CellComponents {
  int count = 0;                 // 0 to 4
  int8_t of_edge[kCellEdges]{};  // component of each sign-changing edge, -1 for the others
};

// The cube's faces: face f = 2 · axis + side holds the corners whose bit `axis` equals `side`.
// Its corners in cyclic order, and edge k of the face joining corner k to corner k + 1.
struct CellFace {
  int corner[4];
  int edge[4];
};
GWNRT_HD constexpr CellFace cell_face(int face) {
  const int axis = face >> 1, b = (axis + 1) % 3, c = (axis + 2) % 3, base = (face & 1) << axis;
  CellFace f{};
  f.corner[0] = base;
  f.corner[1] = base | (1 << b);
  f.corner[2] = base | (1 << b) | (1 << c);
  f.corner[3] = base | (1 << c);
  f.edge[0] = corner_edge(f.corner[0], b);
  f.edge[1] = corner_edge(f.corner[1], c);
  f.edge[2] = corner_edge(f.corner[3], b);
  f.edge[3] = corner_edge(f.corner[0], c);
  return f;
}

// Whether edge e of the cell has a sign change.
GWNRT_HD constexpr bool edge_crossed(uint32_t inside, int e) {
  const int c = edge_corner(e);
  return ((inside >> c) & 1u) != ((inside >> (c | (1 << edge_axis(e)))) & 1u);
}

// Whether `face` is ambiguous (its diagonal corners alike, four crossed edges) and its two inside
// corners are joined inside the cell, through inside corners along the cell's edges. The patch's
// loop around them then passes through the face twice (a tunnel). When the cells on both sides
// of a face have such a tunnel through it, their two vertices are joined by all four of the
// face's quads, an edge of four triangles: so that face's pairing is flipped (both cells read the
// same two patterns, so they agree). After the flip neither cell's loop passes the face twice:
// the inside corners' path and an outside corners' path could not both cross the rest of the
// cube's surface.
GWNRT_HD constexpr bool tunnel_through_face(uint32_t inside, int face) {
  const CellFace f = cell_face(face);
  const uint32_t a = (inside >> f.corner[0]) & 1u, b = (inside >> f.corner[1]) & 1u;
  if (a == b || ((inside >> f.corner[2]) & 1u) != a || ((inside >> f.corner[3]) & 1u) != b) return false;
  const int from = a ? f.corner[0] : f.corner[1], to = a ? f.corner[2] : f.corner[3];
  uint32_t reached = 1u << from;
  for (int step = 0; step < kCellCorners; ++step)  // a flood fill over at most 8 corners
    for (int c = 0; c < kCellCorners; ++c)
      if ((reached >> c) & 1u)
        for (int axis = 0; axis < 3; ++axis) {
          const int d = c ^ (1 << axis);
          if ((inside >> d) & 1u) reached |= 1u << d;
        }
  return (reached >> to) & 1u;
}

// The patch's segments on the cell's faces, as join(edge a, edge b). On each face the patch
// crosses two or four of its edges. Two are joined by one segment. Four (diagonal corners alike:
// the ambiguous face) are joined so that each inside corner is cut off by its own segment, the
// two inside corners of the face apart: a rule that reads only the face's four signs, so the two
// cells sharing the face join its crossings the same way and the patches meet edge to edge
// (watertight). Faces with bit f of `flipped` set take the other pairing, each outside corner
// cut off (see tunnel_through_face: the two cells sharing the face decide it alike). Every
// sign-changing edge lies on two faces, so the segments close into loops.
template <class Join>
GWNRT_HD constexpr void visit_face_segments(uint32_t inside, Join&& join, uint32_t flipped = 0) {
  for (int face = 0; face < 6; ++face) {
    const CellFace f = cell_face(face);
    int crossed[4]{}, n = 0;
    for (int k = 0; k < 4; ++k)
      if (edge_crossed(inside, f.edge[k])) crossed[n++] = k;
    if (n == 2) {
      join(f.edge[crossed[0]], f.edge[crossed[1]]);
    } else if (n == 4) {
      // Corner k lies between edges k - 1 and k: cut off corners 0 and 2, or 1 and 3.
      if (((inside >> f.corner[0]) & 1u) != ((flipped >> face) & 1u)) {
        join(f.edge[3], f.edge[0]);
        join(f.edge[1], f.edge[2]);
      } else {
        join(f.edge[0], f.edge[1]);
        join(f.edge[2], f.edge[3]);
      }
    }
  }
}

// The components: a loop of segments is a component.
GWNRT_HD constexpr CellComponents cell_components(uint32_t inside, uint32_t flipped = 0) {
  CellComponents out;
  int8_t parent[kCellEdges]{};
  for (int e = 0; e < kCellEdges; ++e) parent[e] = int8_t(edge_crossed(inside, e) ? e : -1);
  const auto find = [&](int e) {
    while (parent[e] != e) e = parent[e];
    return e;
  };
  visit_face_segments(
      inside,
      [&](int a, int b) {
        const int ra = find(a), rb = find(b);
        if (ra < rb) parent[rb] = int8_t(ra);
        if (rb < ra) parent[ra] = int8_t(rb);
      },
      flipped);
  int8_t label[kCellEdges]{};
  for (int e = 0; e < kCellEdges; ++e) {
    label[e] = -1;
    out.of_edge[e] = -1;
  }
  for (int e = 0; e < kCellEdges; ++e) {
    if (parent[e] < 0) continue;
    const int r = find(e);
    if (label[r] < 0) label[r] = int8_t(out.count++);
    out.of_edge[e] = label[r];
  }
  return out;
}

// A cell's components packed in 32 bits: the component of edge e in bits 2e, 2e + 1 (0 for the
// edges without a crossing), the count in bits 24-26. What the passes keep per cell.
GWNRT_HD constexpr uint32_t pack_components(const CellComponents& parts) {
  uint32_t packed = uint32_t(parts.count) << 24;
  for (int e = 0; e < kCellEdges; ++e)
    if (parts.of_edge[e] > 0) packed |= uint32_t(parts.of_edge[e]) << (2 * e);
  return packed;
}
GWNRT_HD constexpr int packed_count(uint32_t packed) { return int(packed >> 24); }
GWNRT_HD constexpr int packed_component(uint32_t packed, int edge) { return int((packed >> (2 * edge)) & 3u); }

#if !defined(__CUDACC__)
// On the host the 256 patterns are tabulated at compile time: the cell passes read them for every
// cell S crosses, several times, and tracing the loops each time would be a large share of the
// mesher's time. The device computes them (a table there would have to be copied to constant
// memory).
inline constexpr std::array<uint32_t, 256> kPackedCellComponents = [] {
  std::array<uint32_t, 256> table{};
  for (uint32_t mask = 0; mask < 256; ++mask) table[mask] = pack_components(cell_components(mask));
  return table;
}();
#endif

GWNRT_HD inline uint32_t packed_cell_components(uint32_t inside, uint32_t flipped = 0) {
#if defined(__CUDACC__)
  return pack_components(cell_components(inside, flipped));
#else
  return flipped ? pack_components(cell_components(inside, flipped)) : kPackedCellComponents[inside];
#endif
}

// The same components as closed loops of edges in order, for marching cubes (one polygon per
// component, its corners on the loop's edges). Each loop runs counter-clockwise seen from
// outside {w > w*}: its polygon's normal (Newell's, over the edges' midpoints) points from the
// component's inside corners toward its outside ones.
struct CellLoops {
  int count = 0;
  int length[4]{};
  int8_t edge[kCellEdges]{};  // loop 0's edges, then loop 1's, ...
};

GWNRT_HD constexpr CellLoops cell_loops(uint32_t inside) {
  // Each crossed edge's two neighbours along the patch: its partners on its two faces.
  int8_t next[kCellEdges][2]{};
  int8_t degree[kCellEdges]{};
  visit_face_segments(inside, [&](int a, int b) {
    next[a][degree[a]++] = int8_t(b);
    next[b][degree[b]++] = int8_t(a);
  });
  CellLoops out;
  bool used[kCellEdges]{};
  int written = 0;
  for (int start = 0; start < kCellEdges; ++start) {
    if (!edge_crossed(inside, start) || used[start]) continue;
    const int first = written;
    int previous = -1, e = start;
    for (int guard = 0; guard < kCellEdges && !used[e]; ++guard) {
      used[e] = true;
      out.edge[written++] = int8_t(e);
      const int a = next[e][0], b = next[e][1];
      const int step = a != previous ? a : b;
      previous = e;
      e = step;
    }
    const int length = written - first;
    // Orientation: Newell's normal of the edges' midpoints against inside -> outside.
    double nx = 0, ny = 0, nz = 0, gx = 0, gy = 0, gz = 0;
    for (int k = 0; k < length; ++k) {
      const int e0 = out.edge[first + k], e1 = out.edge[first + (k + 1) % length];
      double p[3] = {}, q[3] = {};
      for (int a = 0; a < 3; ++a) {
        p[a] = a == edge_axis(e0) ? 0.5 : double((edge_corner(e0) >> a) & 1);
        q[a] = a == edge_axis(e1) ? 0.5 : double((edge_corner(e1) >> a) & 1);
      }
      nx += (p[1] - q[1]) * (p[2] + q[2]);
      ny += (p[2] - q[2]) * (p[0] + q[0]);
      nz += (p[0] - q[0]) * (p[1] + q[1]);
      const double sign = ((inside >> edge_corner(e0)) & 1u) ? 1.0 : -1.0;  // inside -> outside along the edge
      (edge_axis(e0) == 0 ? gx : (edge_axis(e0) == 1 ? gy : gz)) += sign;
    }
    if (nx * gx + ny * gy + nz * gz < 0)
      for (int i = first, j = written - 1; i < j; ++i, --j) {
        const int8_t t = out.edge[i];
        out.edge[i] = out.edge[j];
        out.edge[j] = t;
      }
    out.length[out.count++] = length;
  }
  return out;
}

#if !defined(__CUDACC__)
inline constexpr std::array<CellLoops, 256> kCellLoops = [] {
  std::array<CellLoops, 256> table{};
  for (uint32_t mask = 0; mask < 256; ++mask) table[mask] = cell_loops(mask);
  return table;
}();
#endif

GWNRT_HD inline CellLoops cell_loops_of(uint32_t inside) {
#if defined(__CUDACC__)
  return cell_loops(inside);
#else
  return kCellLoops[inside];
#endif
}

}  // namespace gwnrt
