// The mesher's sparse grid: blocks of kBlockCells³ cells, kept only where a proven bound says S
// may meet them; a block's slot holds its corners' values, its edges' offsets and its cells'
// vertex offsets. Host-and-device.
#pragma once

#include <cmath>
#include <cstdint>

#include "gwnrt/base/hd.h"
#include "gwnrt/geometry/bvh.h"
#include "gwnrt/meshing/cell_topology.h"

namespace gwnrt {

inline constexpr int kBlockCells = 8;  // cells (and owned corners) per block along each axis
inline constexpr uint32_t kBlockItems = kBlockCells * kBlockCells * kBlockCells;

struct GridCoord {
  int32_t x = 0, y = 0, z = 0;
  GWNRT_HD int32_t operator[](int a) const { return a == 0 ? x : (a == 1 ? y : z); }
  GWNRT_HD int32_t& operator[](int a) { return a == 0 ? x : (a == 1 ? y : z); }
};

// The grid: corner (i, j, k) at origin + cell · (i, j, k), cells [0, cells) per axis, corners
// [0, cells]; blocks cover the corners.
struct MeshGrid {
  vec3 origin{0.0f};
  float cell = 0;
  int32_t cells[3] = {0, 0, 0};
  int32_t blocks[3] = {0, 0, 0};

  // One rounding (an explicit fma), so that every caller gets the same floats whether or not the
  // compiler contracts: the repair's cell containment compares positions with them.
  GWNRT_HD vec3 corner_position(const GridCoord& c) const {
    return {fmaf(cell, float(c.x), origin.x), fmaf(cell, float(c.y), origin.y), fmaf(cell, float(c.z), origin.z)};
  }
  GWNRT_HD uint64_t block_count() const { return uint64_t(blocks[0]) * uint64_t(blocks[1]) * uint64_t(blocks[2]); }
  GWNRT_HD uint64_t block_index(int32_t bx, int32_t by, int32_t bz) const {
    return uint64_t(bx) + uint64_t(blocks[0]) * (uint64_t(by) + uint64_t(blocks[1]) * uint64_t(bz));
  }
  GWNRT_HD GridCoord block_of_index(uint64_t i) const {
    GridCoord b;
    b.x = int32_t(i % uint64_t(blocks[0]));
    i /= uint64_t(blocks[0]);
    b.y = int32_t(i % uint64_t(blocks[1]));
    b.z = int32_t(i / uint64_t(blocks[1]));
    return b;
  }
};

// Corner k of the cell whose lowest corner is c: offset (k & 1, (k >> 1) & 1, k >> 2).
GWNRT_HD inline GridCoord cell_corner(const GridCoord& c, int k) {
  return {c.x + (k & 1), c.y + ((k >> 1) & 1), c.z + ((k >> 2) & 1)};
}

GWNRT_HD inline uint32_t local_index(const GridCoord& c) {
  return uint32_t(c.x % kBlockCells) +
         kBlockCells * (uint32_t(c.y % kBlockCells) + kBlockCells * uint32_t(c.z % kBlockCells));
}
GWNRT_HD inline GridCoord local_coord(uint32_t local) {
  return {int32_t(local % kBlockCells), int32_t((local / kBlockCells) % kBlockCells),
          int32_t(local / (kBlockCells * kBlockCells))};
}

// The sparse grid's arrays, per slot (a kept block or a neighbour whose corners it reads).
struct SparseGridView {
  MeshGrid grid;
  const uint32_t* slot_of_block = nullptr;  // dense over the blocks; kEmptyLane: no slot
  const uint32_t* block_of_slot = nullptr;  // block index
  const uint32_t* needed_from = nullptr;    // per slot: bit d set when block − d (d ∈ {0,1}³) is active
  const float* corner_value = nullptr;      // per slot × kBlockItems: w − w*; NaN: not evaluated
  const uint8_t* edge_mask = nullptr;       // per corner: axes of its sign-changing edges
  // A corner's first edge and a cell's first vertex: the slot's first plus the item's within the
  // slot (16 bits: a slot has at most 3 edges and 4 vertices an item; SlotOffsetsPass).
  const uint16_t* edge_in_slot = nullptr;
  const uint32_t* slot_first_edge = nullptr;
  const uint32_t* cell_parts = nullptr;  // per cell: pack_components of its pattern (0: no vertex)
  const uint16_t* vertex_in_slot = nullptr;
  const uint32_t* slot_first_vertex = nullptr;

  // The slot item (slot · kBlockItems + local) of a corner or cell, or kEmptyLane beyond the
  // grid or in a block without a slot.
  GWNRT_HD uint64_t item_of(const GridCoord& c, int32_t limit_extra) const {
    for (int a = 0; a < 3; ++a)
      if (c[a] < 0 || c[a] >= grid.cells[a] + limit_extra) return ~uint64_t(0);
    const uint32_t slot = slot_of_block[grid.block_index(c.x / kBlockCells, c.y / kBlockCells, c.z / kBlockCells)];
    return slot == kEmptyLane ? ~uint64_t(0) : uint64_t(slot) * kBlockItems + local_index(c);
  }
  GWNRT_HD uint32_t edge_offset(uint64_t item) const {
    return slot_first_edge[item / kBlockItems] + edge_in_slot[item];
  }
  GWNRT_HD uint32_t cell_vertex_offset(uint64_t item) const {
    return slot_first_vertex[item / kBlockItems] + vertex_in_slot[item];
  }
  // A cell item's vertices: one per surface component of its pattern.
  GWNRT_HD uint32_t cell_vertex_count(uint64_t item) const { return uint32_t(packed_count(cell_parts[item])); }
  GWNRT_HD float corner_value_at(const GridCoord& c) const {
    const uint64_t item = item_of(c, 1);
    return item == ~uint64_t(0) ? __builtin_nanf("") : corner_value[item];
  }
  GWNRT_HD GridCoord coord_of_item(uint64_t item) const {
    const GridCoord b = grid.block_of_index(block_of_slot[item / kBlockItems]);
    const GridCoord l = local_coord(uint32_t(item % kBlockItems));
    return {b.x * kBlockCells + l.x, b.y * kBlockCells + l.y, b.z * kBlockCells + l.z};
  }
  GWNRT_HD bool slot_active(uint32_t slot) const { return needed_from[slot] & 1u; }

  // The value at the corner one step along `axis` from corner `item`, whose coordinate in its
  // block is `local` (local_coord): in the same slot unless the corner is on the block's last
  // layer along that axis; only then is the grid coordinate found, through the block map.
  GWNRT_HD float next_corner_value(uint64_t item, const GridCoord& local, int axis) const {
    if (local[axis] + 1 < kBlockCells)
      return corner_value[item + (axis == 0 ? 1 : (axis == 1 ? kBlockCells : kBlockCells * kBlockCells))];
    GridCoord n = coord_of_item(item);
    ++n[axis];
    return corner_value_at(n);
  }

  // A cell's 8 corner values (corner k at offset (k & 1, (k >> 1) & 1, k >> 2)): from its own
  // slot for the 7³ of every 8³ cells that are not on the block's last layer (two thirds of the
  // lookups), through the block map for the others.
  GWNRT_HD void cell_corner_values(uint64_t item, const GridCoord& cell, float f[kCellCorners]) const {
    const GridCoord l = local_coord(uint32_t(item % kBlockItems));
    if (l.x + 1 < kBlockCells && l.y + 1 < kBlockCells && l.z + 1 < kBlockCells) {
      for (int k = 0; k < kCellCorners; ++k)
        f[k] = corner_value[item + (k & 1) + kBlockCells * ((k >> 1) & 1) + kBlockCells * kBlockCells * (k >> 2)];
      return;
    }
    for (int k = 0; k < kCellCorners; ++k) f[k] = corner_value_at(cell_corner(cell, k));
  }
};

}  // namespace gwnrt
