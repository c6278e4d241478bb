// The mesh quality report (gwnrt/meshing/mesh_quality.h): topology from the corners around each
// vertex and a concurrent union-find, self-intersections by a grid of cells over the triangles
// and the exact pair test (exact_predicates.cpp), distances to S by the model's signed distance one way and the
// tracer's hits and the same grid over the output the other.
#include "gwnrt/meshing/mesh_quality.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include "base/message.h"
#include "gwnrt/base/host_blocks.h"
#include "gwnrt/field/distance.h"
#include "gwnrt/geometry/bvh.h"
#include "gwnrt/geometry/exact_predicates.h"
#include "gwnrt/geometry/triangle_tree.h"
#include "gwnrt/query/batch.h"
#include "gwnrt/sdf/signed_distance.h"
#include "meshing/disjoint_sets.h"

namespace gwnrt {
namespace {

// The checks every entry point makes: coordinates finite (the exact predicates and the weld's
// order need numbers) and indices in range, each failure naming its element.
Status validate_surface_mesh(const SurfaceMesh& mesh, const char* where) {
  const std::vector<vec3>& pos = mesh.positions;
  for (size_t i = 0; i < pos.size(); ++i) {
    const vec3& p = pos[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      return {StatusCode::kInvalidMesh, cat(where, ": vertex ", i, " ", non_finite_coordinate(p.x, p.y, p.z))};
  }
  for (size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = mesh.triangles[t][k];
      if (v >= pos.size())
        return {StatusCode::kInvalidMesh,
                cat(where, ": triangle ", t, " refers to vertex ", v, " but there are ", pos.size(), " vertices")};
    }
  // Corners are numbered 3t + k in 32 bits, and triangle indices are reported in 32 bits.
  if (mesh.triangles.size() > size_t(0xffffffffu) / 3)
    return {StatusCode::kInvalidArgument, cat(where, ": more than 1431655765 triangles")};
  return Status::Ok();
}

// Vertex ids after welding: equal positions (by value, so 0.0 == -0.0) get one id, numbered in
// the order of their first vertex; count is the number of distinct positions.
struct WeldedPositions {
  HostVector<uint32_t> id;
  uint32_t count = 0;
};

// Equal positions hash equally: -0.0 is read as 0.0 (the coordinates are finite).
inline uint64_t position_hash(const vec3& p) {
  uint64_t h = 0x9e3779b97f4a7c15ull;
  for (const float c : {p.x, p.y, p.z}) {
    uint32_t bits;
    const float plus = c + 0.0f;
    std::memcpy(&bits, &plus, sizeof bits);
    h = (h ^ bits) * 0xff51afd7ed558ccdull;
    h ^= h >> 32;
  }
  return h;
}

// By an open-addressing table of the vertices, filled in parallel: a slot holds the smallest
// vertex at its position (the sort of the positions it replaced cost about three times as much).
void weld_positions(const std::vector<vec3>& pos, WeldedPositions& out) {
  const size_t n = pos.size();
  constexpr uint32_t kEmpty = ~uint32_t(0);
  size_t size = 16;
  while (size < 2 * n) size *= 2;  // at most half full: a probe ends within a few slots
  const size_t mask = size - 1;
  HostVector<uint32_t> table(size, kEmpty);
  HostVector<size_t> slot_of(n);  // the table has up to 2^33 slots
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 2048), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      size_t slot = position_hash(pos[i]) & mask;
      for (size_t probe = 0; probe < size; ++probe, slot = (slot + 1) & mask) {
        std::atomic_ref<uint32_t> entry(table[slot]);
        uint32_t held = entry.load(std::memory_order_relaxed);
        if (held == kEmpty && entry.compare_exchange_strong(held, uint32_t(i), std::memory_order_relaxed)) break;
        if (pos[held] != pos[i]) continue;  // held: the slot's vertex, whether found or just set by another thread
        while (i < held && !entry.compare_exchange_weak(held, uint32_t(i), std::memory_order_relaxed)) {
        }
        break;
      }
      slot_of[i] = slot;
    }
  });
  // A position's first vertex numbers it; the others take its number.
  HostVector<uint32_t>& id = out.id;
  id.resize(n);
  uint32_t next = 0;
  for (size_t i = 0; i < n; ++i)
    if (table[slot_of[i]] == i) id[i] = next++;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i)
      if (const uint32_t first = table[slot_of[i]]; first != i) id[i] = id[first];
  });
  out.count = next;
}

// `items` reordered by bucket_of(item), in [0, buckets), keeping their order within a bucket: by
// counting, O(n + buckets). Returns where each bucket starts (buckets + 1 entries).
template <class T, class BucketOf>
HostVector<uint32_t> order_by_bucket(HostVector<T>& items, size_t buckets, BucketOf bucket_of) {
  HostVector<uint32_t> start(buckets + 1, 0);
  for (const T& x : items) ++start[bucket_of(x) + 1];
  for (size_t b = 1; b <= buckets; ++b) start[b] += start[b - 1];
  HostVector<T> ordered(items.size());
  HostVector<uint32_t> next(start.begin(), start.end() - 1);
  for (const T& x : items) ordered[next[bucket_of(x)]++] = x;
  items.swap(ordered);
  return start;
}

// `welded`: weld_positions' result when the caller has it.
Status mesh_topology_unguarded(const SurfaceMesh& mesh, MeshTopology& out, bool weld,
                               const WeldedPositions* welded = nullptr) {
  if (Status s = validate_surface_mesh(mesh, "mesh_topology"); !s.ok()) return s;
  MeshTopology topo;
  const size_t n = mesh.triangles.size();
  topo.triangles = n;
  HostVector<uvec3> tris(mesh.triangles.begin(), mesh.triangles.end());
  size_t vertex_count = mesh.positions.size();
  if (weld) {
    WeldedPositions own;
    if (!welded) weld_positions(mesh.positions, own);
    const WeldedPositions& w = welded ? *welded : own;
    vertex_count = w.count;
    const HostVector<uint32_t>& id = w.id;
    tbb::parallel_for(size_t(0), n, [&](size_t t) {
      for (int k = 0; k < 3; ++k) tris[t][k] = id[tris[t][k]];
    });
  }
  topo.vertices = vertex_count;

  // Per triangle: 0 sound, 1 zero area (still in the edge counts), 2 repeated index (left out).
  HostVector<uint8_t> kind(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t t = r.begin(); t != r.end(); ++t) {
      const uvec3 v = tris[t];
      const uvec3 o = mesh.triangles[t];
      if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0])
        kind[t] = 2;
      else
        kind[t] = exact::collinear(mesh.positions[o[0]], mesh.positions[o[1]], mesh.positions[o[2]]) ? 1 : 0;
    }
  });

  for (size_t t = 0; t < n; ++t) topo.degenerate_triangles += kind[t] != 0 ? 1 : 0;

  // The corners at each vertex (of the triangles with three distinct vertices), grouped by
  // vertex: everything below but the components is local to one vertex.
  HostVector<uint32_t> start(vertex_count + 1, 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t t = r.begin(); t != r.end(); ++t)
      if (kind[t] != 2)
        for (int k = 0; k < 3; ++k)
          std::atomic_ref<uint32_t>(start[tris[t][k] + 1]).fetch_add(1, std::memory_order_relaxed);
  });
  for (size_t v = 1; v <= vertex_count; ++v) start[v] += start[v - 1];
  HostVector<uint32_t> corners(start[vertex_count]);
  {
    HostVector<uint32_t> next(start.begin(), start.end() - 1);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t t = r.begin(); t != r.end(); ++t)
        if (kind[t] != 2)
          for (int k = 0; k < 3; ++k)
            corners[std::atomic_ref<uint32_t>(next[tris[t][k]]).fetch_add(1, std::memory_order_relaxed)] =
                uint32_t(3 * t + k);
    });
  }

  // Around vertex v each edge {v, u} is one group of the corners' neighbours u: its size is the
  // edge's count of triangles (counted at its smaller end), the corners in it are one fan, and
  // the triangles of an edge with two or more are one component.
  struct Counts {
    uint64_t boundary = 0, non_manifold = 0, inconsistent = 0, non_manifold_vertices = 0, unreferenced = 0;
  };
  struct Neighbour {
    uint32_t vertex, corner;  // corner: its index among v's corners
    bool leaving;             // the corner's triangle runs v -> vertex
    bool operator<(const Neighbour& o) const { return vertex < o.vertex; }
  };
  ConcurrentDisjointSets components(n);
  tbb::enumerable_thread_specific<Counts> counts;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, vertex_count, 1024), [&](const tbb::blocked_range<size_t>& r) {
    Counts& c = counts.local();
    std::vector<Neighbour> around;
    DisjointSets fan(0);
    for (size_t v = r.begin(); v != r.end(); ++v) {
      const uint32_t first = start[v], count = start[v + 1] - first;
      if (count == 0) {
        ++c.unreferenced;
        continue;
      }
      around.clear();
      fan.reset(count);
      for (uint32_t j = 0; j < count; ++j) {
        const uint32_t corner = corners[first + j], t = corner / 3, k = corner % 3;
        around.push_back({tris[t][(k + 1) % 3], j, true});
        around.push_back({tris[t][(k + 2) % 3], j, false});
      }
      std::sort(around.begin(), around.end());
      for (size_t g = 0; g < around.size();) {
        size_t e = g + 1;
        while (e < around.size() && around[e].vertex == around[g].vertex) ++e;
        for (size_t m = g + 1; m < e; ++m) fan.unite(around[g].corner, around[m].corner);
        if (around[g].vertex > v) {
          const size_t on_edge = e - g;
          if (on_edge == 1) ++c.boundary;
          if (on_edge > 2) ++c.non_manifold;
          if (on_edge == 2 && around[g].leaving == around[g + 1].leaving) ++c.inconsistent;
          for (size_t m = g + 1; m < e; ++m)
            components.unite(corners[first + around[g].corner] / 3, corners[first + around[m].corner] / 3);
        }
        g = e;
      }
      uint32_t fans = 0;
      for (uint32_t j = 0; j < count; ++j) fans += fan.find(j) == j ? 1 : 0;
      if (fans > 1) ++c.non_manifold_vertices;
    }
  });
  counts.combine_each([&](const Counts& c) {
    topo.boundary_edges += c.boundary;
    topo.non_manifold_edges += c.non_manifold;
    topo.inconsistent_edges += c.inconsistent;
    topo.non_manifold_vertices += c.non_manifold_vertices;
    topo.unreferenced_vertices += c.unreferenced;
  });
  topo.components = tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, n, 4096), uint64_t(0),
      [&](const tbb::blocked_range<size_t>& r, uint64_t roots) {
        for (size_t t = r.begin(); t != r.end(); ++t)
          roots += kind[t] != 2 && components.find(uint32_t(t)) == t ? 1 : 0;
        return roots;
      },
      std::plus<>());
  out = topo;
  return Status::Ok();
}

// The lanes of a node whose boxes overlap b, as bits (empty lanes have inverted boxes and fail):
// all four compared as one vector.
inline unsigned overlapping_lanes(const WideNode& node, const Aabb& b) {
#if GWNRT_HOST_LANES
  i4 in = i4{} - 1;
  for (int a = 0; a < 3; ++a) in &= (load4(node.lo[a]) <= b.hi[a]) & (splat<f4>(b.lo[a]) <= load4(node.hi[a]));
  return lane_bits(in);
#else
  unsigned mask = 0;
  for (int l = 0; l < kBvhWidth; ++l) {
    bool in = true;
    for (int a = 0; a < 3; ++a) in &= (node.lo[a][l] <= b.hi[a]) & (b.lo[a] <= node.hi[a][l]);
    mask |= unsigned(in) << l;
  }
  return mask;
#endif
}

// Which of the kBoxLanes boxes from j on (in box_column: lo x, y, z, hi x, y, z) overlap b, as bits.
#if GWNRT_HOST_LANES
inline constexpr int kBoxLanes = kNearWidth;
inline fnear load_lanes(const float* p) {
  fnear v;
  __builtin_memcpy(&v, p, sizeof v);
  return v;
}
inline uint32_t overlapping_boxes(const std::array<HostVector<float>, 6>& column, size_t j, const Aabb& b) {
  inear in = inear{} - 1;
  for (int a = 0; a < 3; ++a)
    in &=
        (load_lanes(column[a].data() + j) <= b.hi[a]) & (splat<fnear>(b.lo[a]) <= load_lanes(column[3 + a].data() + j));
  return lane_bits(in);
}
#else
inline constexpr int kBoxLanes = 4;
inline uint32_t overlapping_boxes(const std::array<HostVector<float>, 6>& column, size_t j, const Aabb& b) {
  uint32_t mask = 0;
  for (int l = 0; l < kBoxLanes; ++l) {
    bool in = true;
    for (int a = 0; a < 3; ++a) in &= (column[a][j + l] <= b.hi[a]) & (b.lo[a] <= column[3 + a][j + l]);
    mask |= uint32_t(in) << l;
  }
  return mask;
}
#endif
// The lanes of the first `left` (all kBoxLanes when more are left).
inline uint32_t lanes_before(size_t left) {
  return left >= size_t(kBoxLanes) ? (1u << kBoxLanes) - 1u : (1u << left) - 1u;
}

// The pairs whose boxes overlap are found on a uniform grid: each triangle no wider than a cell
// (twice the median triangle's extent, so nearly all of them) is filed under the cell of its box's
// low corner, and two such boxes that overlap have their low corners within a cell of each other
// along every axis, so in the same cell or neighbouring ones; the few wider triangles are tested
// against every triangle by a BVH over them alone. Sorting by cell costs a fraction of a BVH over
// all of them, and a triangle meets only its neighbours' few (docs/performance.md).
inline constexpr double kGridCellOverMedianExtent = 2.0;
inline constexpr double kMaxGridCellsPerAxis = double(1u << 20);  // keys of 60 bits at most
// A map from every cell to its run (16 MiB at most) where the grid has this many cells or fewer,
// so that a point's rings of cells are looked up directly, out to kMaxRings.
inline constexpr double kMaxDenseGridCells = double(1u << 22);
inline constexpr int64_t kMaxRings = 8;

// The mesh's triangles of non-zero area on the uniform grid above, in cell order.
struct TriangleGrid {
  HostVector<uint32_t> input;  // grid order -> mesh triangle
  HostVector<Aabb> box;        // in grid order
  size_t narrow = 0;           // [0, narrow) filed under their cells, [narrow, size) wider than a cell
  dvec3 origin{0.0};
  double cell = 1.0;
  uint64_t dims[3] = {1, 1, 1};
  HostVector<uint64_t> run_key;    // the occupied cells, ascending
  HostVector<uint32_t> run_begin;  // cell run_key[r] holds [run_begin[r], run_begin[r + 1])
  HostVector<int32_t> dense_run;   // per cell its run or -1, where the cells are few enough

  uint64_t key(uint64_t x, uint64_t y, uint64_t z) const { return x + dims[0] * (y + dims[1] * z); }
  // The run of cell q (any coordinates), or -1 when it holds none; from: where to start looking.
  int64_t run_of(const int64_t (&q)[3], size_t from = 0) const {
    for (int a = 0; a < 3; ++a)
      if (q[a] < 0 || q[a] >= int64_t(dims[a])) return -1;
    const uint64_t k = key(uint64_t(q[0]), uint64_t(q[1]), uint64_t(q[2]));
    if (!dense_run.empty()) return dense_run[k];
    const auto it = std::lower_bound(run_key.begin() + ptrdiff_t(from), run_key.end(), k);
    return it == run_key.end() || *it != k ? -1 : int64_t(it - run_key.begin());
  }
};

void build_triangle_grid(const SurfaceMesh& mesh, TriangleGrid& g) {
  const size_t n_all = mesh.triangles.size();
  const std::vector<vec3>& pos = mesh.positions;
  HostVector<uint8_t> keep(n_all);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n_all, 1024), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t t = r.begin(); t != r.end(); ++t) {
      const uvec3 v = mesh.triangles[t];
      keep[t] = !exact::collinear(pos[v[0]], pos[v[1]], pos[v[2]]);
    }
  });
  HostVector<uint32_t> ids;
  for (size_t t = 0; t < n_all; ++t)
    if (keep[t]) ids.push_back(uint32_t(t));
  const size_t n = ids.size();
  g = TriangleGrid{};
  if (n == 0) {
    g.run_begin.push_back(0);
    return;
  }
  // Boxes and extents (in double: the classification below must not round a width down).
  HostVector<Aabb> bounds(n);
  HostVector<double> extent(n);
  tbb::parallel_for(size_t(0), n, [&](size_t i) {
    for (int k = 0; k < 3; ++k) bounds[i].extend(pos[mesh.triangles[ids[i]][k]]);
    const dvec3 e = dvec3(bounds[i].hi) - dvec3(bounds[i].lo);
    extent[i] = std::max(e.x, std::max(e.y, e.z));
  });
  Aabb all;
  for (const Aabb& b : bounds) {
    all.extend(b.lo);
    all.extend(b.hi);
  }
  g.origin = dvec3(all.lo);
  const dvec3 size = dvec3(all.hi) - dvec3(all.lo);
  HostVector<double> sorted_extent(extent);
  std::nth_element(sorted_extent.begin(), sorted_extent.begin() + ptrdiff_t(n / 2), sorted_extent.end());
  g.cell = kGridCellOverMedianExtent * sorted_extent[n / 2];
  g.cell = std::max(g.cell, std::max(size.x, std::max(size.y, size.z)) / kMaxGridCellsPerAxis);
  if (!(g.cell > 0.0)) g.cell = 1.0;  // every triangle a point's box: nothing overlaps but at points
  for (int a = 0; a < 3; ++a) g.dims[a] = uint64_t(size[a] / g.cell) + 1;
  const auto cell_of = [&](const vec3& lo, int a) {
    return std::min(uint64_t((double(lo[a]) - g.origin[a]) / g.cell), g.dims[a] - 1);
  };
  // Wide: more than a cell (less a margin for the rounding of the cells' coordinates, so that
  // narrower ones' low corners stay within one cell of each other's).
  const double narrow = g.cell * (1.0 - 1e-6);
  constexpr uint64_t kWide = ~uint64_t(0);
  HostVector<std::pair<uint64_t, uint32_t>> order(n);
  tbb::parallel_for(size_t(0), n, [&](size_t i) {
    const vec3& lo = bounds[i].lo;
    order[i] = {extent[i] <= narrow ? g.key(cell_of(lo, 0), cell_of(lo, 1), cell_of(lo, 2)) : kWide, uint32_t(i)};
  });
  const double cells = double(g.dims[0]) * double(g.dims[1]) * double(g.dims[2]);
  if (cells <= kMaxDenseGridCells) {
    // By counting (keys below 2^22, the wide ones last), in index order within a key as the
    // comparison sort leaves them.
    order_by_bucket(order, size_t(cells) + 1, [&](const std::pair<uint64_t, uint32_t>& o) {
      return o.first == kWide ? size_t(cells) : size_t(o.first);
    });
  } else {
    tbb::parallel_sort(order.begin(), order.end());
  }
  g.narrow = n;
  while (g.narrow > 0 && order[g.narrow - 1].first == kWide) --g.narrow;
  g.input.resize(n);
  g.box.resize(n);
  tbb::parallel_for(size_t(0), n, [&](size_t i) {
    g.input[i] = ids[order[i].second];
    g.box[i] = bounds[order[i].second];
  });
  for (size_t i = 0; i < g.narrow; ++i)
    if (i == 0 || order[i].first != order[i - 1].first) {
      g.run_key.push_back(order[i].first);
      g.run_begin.push_back(uint32_t(i));
    }
  g.run_begin.push_back(uint32_t(g.narrow));
  if (cells <= kMaxDenseGridCells) {
    g.dense_run.assign(size_t(cells), -1);
    for (size_t r = 0; r < g.run_key.size(); ++r) g.dense_run[g.run_key[r]] = int32_t(r);
  }
}

// Whether box b lies within r of x, in double (the grid's triangles' boxes, for the nearest ones).
inline bool box_within(const Aabb& b, const dvec3& x, double r) {
  const dvec3 gap = glm::max(glm::max(dvec3(b.lo) - x, x - dvec3(b.hi)), dvec3(0.0));
  return glm::dot(gap, gap) <= r * r;
}

// The grid's cells in blocks of kFarBlockCells along each axis, with a BVH over the blocks'
// boxes: the nearest narrow triangles to a point beyond the rings, without a tree over every
// triangle (building one took most of the report's distances where a few points of S lie far
// from the output).
inline constexpr uint64_t kFarBlockCells = 4;

struct GridBlocks {
  HostVector<uint32_t> runs;         // the grid's runs, block by block
  HostVector<uint32_t> block_begin;  // block b holds runs[block_begin[b], block_begin[b + 1])
  WideBvh bvh;                       // over the blocks' boxes
};

Status build_grid_blocks(const TriangleGrid& g, GridBlocks& out) {
  const size_t run_count = g.run_key.size();
  uint64_t blocks_along[3];
  for (int a = 0; a < 3; ++a) blocks_along[a] = (g.dims[a] + kFarBlockCells - 1) / kFarBlockCells;
  HostVector<std::pair<uint64_t, uint32_t>> order(run_count);
  tbb::parallel_for(size_t(0), run_count, [&](size_t r) {
    const uint64_t key = g.run_key[r];
    const uint64_t c[3] = {key % g.dims[0], key / g.dims[0] % g.dims[1], key / g.dims[0] / g.dims[1]};
    const uint64_t block =
        c[0] / kFarBlockCells + blocks_along[0] * (c[1] / kFarBlockCells + blocks_along[1] * (c[2] / kFarBlockCells));
    order[r] = {block, uint32_t(r)};
  });
  tbb::parallel_sort(order.begin(), order.end());
  out = GridBlocks{};
  out.runs.resize(run_count);
  std::vector<Aabb> box;
  for (size_t i = 0; i < run_count; ++i) {
    if (i == 0 || order[i].first != order[i - 1].first) {
      out.block_begin.push_back(uint32_t(i));
      box.emplace_back();
    }
    const uint32_t run = order[i].second;
    out.runs[i] = run;
    for (uint32_t j = g.run_begin[run]; j < g.run_begin[run + 1]; ++j) {
      box.back().extend(g.box[j].lo);
      box.back().extend(g.box[j].hi);
    }
  }
  out.block_begin.push_back(uint32_t(run_count));
  return build_wide_bvh(box, 1, out.bvh);
}

// fn(grid index) for every narrow triangle whose box lies within reach() of x (read before each
// block and triangle, so that a nearest search can shrink it), nearer blocks first.
template <class Reach, class Fn>
void for_each_narrow_near(const TriangleGrid& g, const GridBlocks& blocks, const vec3& x, Reach reach, Fn fn) {
  if (blocks.block_begin.size() < 2) return;
  const dvec3 xd(x);
  const auto within = [&](float d2) {
    const float r = float(reach()) * (1 + 1e-6f);  // float boxes and x: past their round-off
    return d2 <= r * r;
  };
  const auto visit_block = [&](uint32_t b) {
    for (uint32_t i = blocks.block_begin[b]; i < blocks.block_begin[b + 1]; ++i) {
      const uint32_t run = blocks.runs[i];
      for (uint32_t j = g.run_begin[run]; j < g.run_begin[run + 1]; ++j)
        if (box_within(g.box[j], xd, reach())) fn(j);
    }
  };
  uint32_t stack[kTraversalStackSize];
  int sp = 0;
  stack[sp++] = 0;
  while (sp > 0) {
    const WideNode& node = blocks.bvh.nodes[stack[--sp]];
    float d2[kBvhWidth];
    int lanes[kBvhWidth], count = 0;
    for (int l = 0; l < kBvhWidth; ++l) {
      d2[l] = detail::box_distance2(node, l, x);
      if (node.child[l] != kEmptyLane && within(d2[l])) lanes[count++] = l;
    }
    for (int i = 1; i < count; ++i)  // by distance (std::sort on four trips GCC's -Warray-bounds)
      for (int k = i; k > 0 && d2[lanes[k]] < d2[lanes[k - 1]]; --k) std::swap(lanes[k], lanes[k - 1]);
    for (int k = count; k-- > 0;)  // the nearer popped first
      if (node.count[lanes[k]] == 0) stack[sp++] = node.child[lanes[k]];
    for (int k = 0; k < count; ++k) {
      const int l = lanes[k];
      if (node.count[l] == 0 || !within(d2[l])) continue;
      for (uint32_t p = node.child[l]; p < node.child[l] + node.count[l]; ++p)
        visit_block(blocks.bvh.primitive_order[p]);
    }
  }
}

Status count_self_intersections_unguarded(const SurfaceMesh& mesh, uint64_t& count, std::vector<glm::uvec2>* pairs,
                                          const TriangleGrid* shared_grid = nullptr,
                                          const WeldedPositions* welded = nullptr) {
  if (Status s = validate_surface_mesh(mesh, "count_self_intersections"); !s.ok()) return s;
  count = 0;
  if (pairs) pairs->clear();
  TriangleGrid own_grid;
  if (!shared_grid) build_triangle_grid(mesh, own_grid);
  const TriangleGrid& grid = shared_grid ? *shared_grid : own_grid;
  const size_t n = grid.input.size(), n_narrow = grid.narrow;
  if (n == 0) return Status::Ok();
  const std::vector<vec3>& pos = mesh.positions;
  const HostVector<Aabb>& box = grid.box;
  const HostVector<uint64_t>& run_key = grid.run_key;
  const HostVector<uint32_t>& run_begin = grid.run_begin;

  // Corners by position (a soup's copies of a vertex are one), so that a pair matches its shared
  // corners by their ids.
  WeldedPositions own;
  if (!welded) weld_positions(pos, own);
  const HostVector<uint32_t>& vertex_id = (welded ? *welded : own).id;
  // Triangles in cell order, so that a cell's are adjacent in memory.
  HostVector<exact::Triangle> tri(n);
  HostVector<exact::PlaneFilter> plane(n);
  HostVector<uvec3> corner_id(n);
  tbb::parallel_for(size_t(0), n, [&](size_t i) {
    const uvec3 v = mesh.triangles[grid.input[i]];
    for (int k = 0; k < 3; ++k) {
      tri[i][k] = pos[v[k]];
      corner_id[i][k] = vertex_id[v[k]];
    }
    plane[i].set(tri[i]);
  });
  // The boxes again by coordinate, padded by boxes that overlap nothing, for the lane test below.
  std::array<HostVector<float>, 6> box_column;
  for (int c = 0; c < 6; ++c) box_column[c].assign(n + kBoxLanes, c < 3 ? kInfinity : -kInfinity);
  tbb::parallel_for(size_t(0), n, [&](size_t i) {
    for (int a = 0; a < 3; ++a) {
      box_column[a][i] = box[i].lo[a];
      box_column[3 + a][i] = box[i].hi[a];
    }
  });

  tbb::combinable<uint64_t> counts([] { return uint64_t(0); });
  tbb::enumerable_thread_specific<std::vector<glm::uvec2>> found;
  // A pair whose boxes overlap.
  const auto test = [&](size_t i, size_t j, uint64_t& local, std::vector<glm::uvec2>* local_pairs) {
    if (exact::apart_beyond_shared(tri[i], plane[i], tri[j], plane[j], corner_id[i], corner_id[j]) ||
        !exact::triangles_of_nonzero_area_intersect(tri[i], tri[j]))
      return;
    ++local;
    if (local_pairs)
      local_pairs->push_back({std::min(grid.input[i], grid.input[j]), std::max(grid.input[i], grid.input[j])});
  };

  // Narrow against narrow: each cell against itself and its 13 neighbours that come later in key
  // order, so that each pair of cells is met once.
  tbb::parallel_for(tbb::blocked_range<size_t>(0, run_key.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
    uint64_t local = 0;
    std::vector<glm::uvec2>* local_pairs = pairs ? &found.local() : nullptr;
    for (size_t run = r.begin(); run != r.end(); ++run) {
      const uint64_t key = run_key[run];
      const uint64_t* dims = grid.dims;
      const int64_t c[3] = {int64_t(key % dims[0]), int64_t(key / dims[0] % dims[1]), int64_t(key / dims[0] / dims[1])};
      for (int d = 13; d < 27; ++d) {  // offsets (dx, dy, dz) = d's base-3 digits − 1; 13 is (0, 0, 0)
        const int64_t q[3] = {c[0] + d % 3 - 1, c[1] + d / 3 % 3 - 1, c[2] + d / 9 - 1};
        const int64_t found_run = grid.run_of(q, run);
        if (found_run < 0) continue;
        const size_t run2 = size_t(found_run);
        for (size_t i = run_begin[run]; i < run_begin[run + 1]; ++i) {
          const size_t end = run_begin[run2 + 1];
          for (size_t j = d == 13 ? i + 1 : run_begin[run2]; j < end; j += kBoxLanes)
            for (uint32_t m = overlapping_boxes(box_column, j, box[i]) & lanes_before(end - j); m != 0; m &= m - 1)
              test(i, j + size_t(__builtin_ctz(m)), local, local_pairs);
        }
      }
    }
    counts.local() += local;
  });

  // Wide against every other: each triangle against the wide ones after it.
  if (n_narrow < n) {
    HostVector<Aabb> wide_bounds(box.begin() + ptrdiff_t(n_narrow), box.end());
    WideBvh bvh;
    if (Status s = build_wide_bvh(wide_bounds, 4, bvh); !s.ok()) return s;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 256), [&](const tbb::blocked_range<size_t>& r) {
      uint64_t local = 0;
      std::vector<glm::uvec2>* local_pairs = pairs ? &found.local() : nullptr;
      uint32_t stack[kTraversalStackSize];
      for (size_t i = r.begin(); i != r.end(); ++i) {
        int sp = 0;
        stack[sp++] = 0;
        while (sp > 0) {
          const WideNode& node = bvh.nodes[stack[--sp]];
          for (unsigned mask = overlapping_lanes(node, box[i]); mask != 0; mask &= mask - 1) {
            const int l = __builtin_ctz(mask);
            if (node.count[l] == 0) {
              stack[sp++] = node.child[l];
              continue;
            }
            for (uint32_t p = node.child[l]; p < node.child[l] + node.count[l]; ++p) {
              const size_t j = n_narrow + bvh.primitive_order[p];
              if (j > i && box[i].overlaps(box[j])) test(i, j, local, local_pairs);
            }
          }
        }
      }
      counts.local() += local;
    });
  }
  count = counts.combine([](uint64_t a, uint64_t b) { return a + b; });
  if (pairs) {
    for (const auto& v : found) pairs->insert(pairs->end(), v.begin(), v.end());
    std::sort(pairs->begin(), pairs->end(),
              [](const glm::uvec2& a, const glm::uvec2& b) { return a.x != b.x ? a.x < b.x : a.y < b.y; });
  }
  return Status::Ok();
}

// Uniform doubles in [0, 1) from the generator's top 53 bits: the same sequence on every
// platform (std::uniform_real_distribution's algorithm is the library's).
inline double uniform01(std::mt19937_64& g) { return double(g() >> 11) * 0x1p-53; }

// Area-weighted random points of a list of triangles: the running total of their areas, then a
// triangle by one search and a uniform point in it (sqrt of one uniform folds the square onto the
// triangle without bias).
struct AreaSampler {
  HostVector<double> cumulative;
  double total = 0;
  void add(const dvec3& p0, const dvec3& p1, const dvec3& p2) {
    total += 0.5 * glm::length(glm::cross(p1 - p0, p2 - p0));
    cumulative.push_back(total);
  }
  size_t triangle(std::mt19937_64& rng) const {
    const double pick = uniform01(rng) * total;
    return std::min<size_t>(std::upper_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin(),
                            cumulative.size() - 1);
  }
  static dvec3 point(const dvec3& p0, const dvec3& p1, const dvec3& p2, std::mt19937_64& rng) {
    const double r1 = std::sqrt(uniform01(rng)), r2 = uniform01(rng);
    return (1 - r1) * p0 + r1 * (1 - r2) * p1 + r1 * r2 * p2;
  }
};

inline double angle_deg(const dvec3& a, const dvec3& b) {
  // atan2 of |a × b| and a · b keeps small angles accurate, where acos(a · b) loses half the digits.
  return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b)) * (180.0 / kPi);
}

// The output's unit normal at barycentrics (u, v) of its triangle t: the interpolated vertex
// normal where the mesh has normals (and they do not cancel there), else the face normal.
dvec3 output_normal(const SurfaceMesh& mesh, uint32_t t, double u, double v) {
  const uvec3 tri = mesh.triangles[t];
  if (!mesh.normals.empty()) {
    const dvec3 n =
        (1 - u - v) * dvec3(mesh.normals[tri[0]]) + u * dvec3(mesh.normals[tri[1]]) + v * dvec3(mesh.normals[tri[2]]);
    const double len = glm::length(n);
    if (len > 0 && std::isfinite(len)) return n / len;
  }
  const dvec3 p0(mesh.positions[tri[0]]);
  const dvec3 n = glm::cross(dvec3(mesh.positions[tri[1]]) - p0, dvec3(mesh.positions[tri[2]]) - p0);
  return n / glm::length(n);  // the tree holds no zero-area triangle
}

// Calls fn(leaf-order index) for every triangle of the tree whose box is within r of x.
template <class Fn>
void for_each_near(const TriangleTreeView& tree, const vec3& x, float r, Fn fn) {
  if (tree.bvh.node_count == 0) return;
  const float r2 = r * r;
  uint32_t stack[kTraversalStackSize];
  int sp = 0;
  stack[sp++] = 0;
  while (sp > 0) {
    const WideNode& node = tree.bvh.nodes[stack[--sp]];
    for (int l = 0; l < kBvhWidth; ++l) {
      // An empty lane's inverted box is at distance +inf: within an infinite r all the same.
      if (node.child[l] == kEmptyLane || !(detail::box_distance2(node, l, x) <= r2)) continue;
      if (node.count[l] == 0) {
        stack[sp++] = node.child[l];
        continue;
      }
      for (uint32_t i = node.child[l]; i < node.child[l] + node.count[l]; ++i) fn(i);
    }
  }
}

struct SurfacePoint {
  vec3 position, normal;
};

Status surface_distances_unguarded(const GwnModel& model, const SurfaceMesh& mesh,
                                   const SurfaceDistanceOptions& options, SurfaceDistances& out,
                                   const TriangleGrid* shared_grid = nullptr) {
  if (Status s = validate_surface_mesh(mesh, "surface_distances"); !s.ok()) return s;
  if (!mesh.normals.empty() && mesh.normals.size() != mesh.positions.size())
    return {StatusCode::kInvalidMesh, cat("surface_distances: ", mesh.normals.size(), " normals for ",
                                          mesh.positions.size(), " vertices (one per vertex, or none)")};
  if (!(options.trace_epsilon > 0.0f && options.trace_epsilon < 1.0f))
    return {StatusCode::kInvalidArgument, "surface_distances: trace_epsilon must lie in (0, 1)"};
  QueryRequest request;
  request.fields = kFieldSignedDistance;
  request.level = options.level;
  // Not the tracer's level-free cells, unless already built: a few thousand rays saved less than
  // the cells took to build (the scan: 4 ms of steps for 29 ms of cells).
  if (Status s = model.prepare(parts_read_by(request)); !s.ok()) return s;
  const ModelView view = model.view();
  if (Status s = validate_request(request, &view); !s.ok()) return s;
  TraceOptions trace;
  trace.level = options.level;
  trace.epsilon = options.trace_epsilon;
  if (Status s = validate_trace_options(trace); !s.ok()) return s;

  SurfaceDistances result;
  std::mt19937_64 rng(options.seed);
  const auto t_to = std::chrono::steady_clock::now();

  // Output -> S.
  const std::vector<vec3>& pos = mesh.positions;
  HostVector<vec3> samples;
  {
    AreaSampler area;
    for (const uvec3& v : mesh.triangles) area.add(dvec3(pos[v[0]]), dvec3(pos[v[1]]), dvec3(pos[v[2]]));
    if (area.total > 0) {
      samples.reserve(options.output_samples);
      for (uint32_t s = 0; s < options.output_samples; ++s) {
        const uvec3 v = mesh.triangles[area.triangle(rng)];
        samples.push_back(vec3(AreaSampler::point(dvec3(pos[v[0]]), dvec3(pos[v[1]]), dvec3(pos[v[2]]), rng)));
      }
    }
    if (options.vertex_samples > 0) {
      HostVector<uint8_t> used(pos.size(), 0);
      for (const uvec3& v : mesh.triangles) used[v[0]] = used[v[1]] = used[v[2]] = 1;
      HostVector<uint32_t> vertices;
      for (size_t i = 0; i < pos.size(); ++i)
        if (used[i]) vertices.push_back(uint32_t(i));
      if (vertices.size() > options.vertex_samples) {
        // A partial Fisher-Yates shuffle: vertex_samples distinct vertices, reproducibly.
        for (size_t i = 0; i < options.vertex_samples; ++i)
          std::swap(vertices[i], vertices[i + size_t(rng() % (vertices.size() - i))]);
        vertices.resize(options.vertex_samples);
      }
      for (const uint32_t i : vertices) samples.push_back(pos[i]);
    }
  }
  // |sdf| at each sample, its sign never read: without w where the sheet distance is the answer.
  HostVector<float> to_surface(samples.size());
  {
    const WindingOptions winding{resolve_point_method(view, request.method), request.taylor};
    tbb::parallel_for(tbb::blocked_range<size_t>(0, samples.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i != r.end(); ++i)
        to_surface[i] = signed_distance(view, samples[i], request.level, winding, nullptr, false).distance;
    });
  }
  result.output_samples = samples.size();
  for (const float d : to_surface) {
    result.mean_to_surface += d;
    result.hausdorff_to_surface = std::max(result.hausdorff_to_surface, double(d));
  }
  if (!to_surface.empty()) result.mean_to_surface /= double(to_surface.size());
  result.seconds_to_surface = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_to).count();
  const auto t_from = std::chrono::steady_clock::now();

  // Points of S: every hit along rays through the model's box.
  const Aabb& bounds = model.bounds();
  const dvec3 centre(bounds.centre());
  const double half_diagonal = 0.5 * glm::length(dvec3(bounds.hi) - dvec3(bounds.lo));
  const double radius = 1.5 * std::max(half_diagonal, 1e-30);
  HostVector<Ray> rays(options.surface_rays);
  for (Ray& ray : rays) {
    const double z = 2 * uniform01(rng) - 1, phi = 2 * kPi * uniform01(rng), s = std::sqrt(std::max(0.0, 1 - z * z));
    const dvec3 origin = centre + radius * dvec3(s * std::cos(phi), s * std::sin(phi), z);
    dvec3 target;
    for (int a = 0; a < 3; ++a) target[a] = bounds.lo[a] + uniform01(rng) * (double(bounds.hi[a]) - bounds.lo[a]);
    ray.origin = vec3(origin);
    ray.direction = vec3(target - origin);
  }
  const uint32_t max_hits = std::max<uint32_t>(1, options.max_hits_per_ray);
  std::vector<std::vector<SurfacePoint>> ray_points(rays.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), 16), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t k = r.begin(); k != r.end(); ++k) {
      std::vector<SurfacePoint>& found = ray_points[k];
      // Every candidate is recorded and turned down, so the trace goes on to the next, until the
      // cap (that one is accepted, ending the trace).
      trace_surface(view, rays[k], trace, [&](const RayHit& h) {
        found.push_back({h.position, h.normal});
        return found.size() >= max_hits;
      });
    }
  });
  HostVector<SurfacePoint> surface_points;
  for (const auto& v : ray_points) surface_points.insert(surface_points.end(), v.begin(), v.end());
  ray_points = {};
  // Points of S's sheets: M's sheet triangles for the level (the model's classification, which its
  // signed distance measures the sheets by), area-weighted, outward toward the side below w*.
  {
    const TriangleTreeView& sheets = view.sheets;
    const std::span<const int8_t> jump = model.sheet_jump();
    AreaSampler area;
    for (uint32_t t = 0; t < sheets.triangle_count; ++t)
      area.add(dvec3(sheets.vertices[3 * t]), dvec3(sheets.vertices[3 * t + 1]), dvec3(sheets.vertices[3 * t + 2]));
    if (area.total > 0) {
      for (uint32_t s = 0; s < options.sheet_samples; ++s) {
        const size_t t = area.triangle(rng);
        const dvec3 p0(sheets.vertices[3 * t]), p1(sheets.vertices[3 * t + 1]), p2(sheets.vertices[3 * t + 2]);
        const dvec3 p = AreaSampler::point(p0, p1, p2, rng);
        const dvec3 n = glm::cross(p1 - p0, p2 - p0);
        const double length = glm::length(n);
        if (!(length > 0)) continue;  // zero area: picked with probability 0
        // w is higher behind the normal by the triangle's jump: {w > w*} lies behind for k > 0.
        const double sign = jump[sheets.triangle_ids[t]] > 0 ? 1.0 : -1.0;
        surface_points.push_back({vec3(p), vec3(sign * n / length)});
        ++result.sheet_points;
      }
    }
  }
  result.surface_points = surface_points.size();

  // S -> output: the output's triangles of non-zero area in rings of the grid's cells around each
  // point, and the wide ones near it by a tree over them. Where the nearest is not nearer than
  // anything beyond the rings can be (a point far from the output), blocks of cells by a tree.
  TriangleGrid own_grid;
  if (!shared_grid) build_triangle_grid(mesh, own_grid);
  const TriangleGrid& grid = shared_grid ? *shared_grid : own_grid;
  Aabb output_box;
  for (const Aabb& b : grid.box) {
    output_box.extend(b.lo);
    output_box.extend(b.hi);
  }
  // Triangles this much nearer or farther than the nearest are equally near to float round-off.
  const double tie = grid.input.empty() ? 0.0 : 1e-6 * glm::length(dvec3(output_box.hi) - dvec3(output_box.lo));
  TriangleTree wide_tree;
  if (grid.narrow < grid.input.size()) {
    const HostVector<uint32_t> wide(grid.input.begin() + ptrdiff_t(grid.narrow), grid.input.end());
    Mesh output;
    output.positions = mesh.positions;
    output.triangles = mesh.triangles;
    if (Status s = build_triangle_tree(output, wide, 4, wide_tree, TreeMoments::kWithout); !s.ok()) return s;
  }
  const TriangleTreeView wide_view = wide_tree.view();
  // fn(output triangle) for every wide triangle whose box lies within r of x (searched in float,
  // widened past its round-off).
  const auto each_wide_near = [&](const vec3& x, double r, auto&& fn) {
    for_each_near(wide_view, x, float(r) * (1 + 1e-6f), [&](uint32_t i) { fn(wide_view.triangle_ids[i]); });
  };
  const auto closest = [&](uint32_t t, const dvec3& xd) {
    const uvec3 v = mesh.triangles[t];
    return closest_point_on_triangle(dvec3(pos[v[0]]), dvec3(pos[v[1]]), dvec3(pos[v[2]]), xd);
  };
  // The nearest distance `best` found (in double, over every triangle), among the triangles as
  // near to round-off the normal that agrees best with S's. each_near(reach, wide_reach, fn):
  // fn(triangle) for every triangle of the output within reach() or wide_reach, and maybe others.
  const auto measure = [&](const dvec3& xd, const dvec3& ns, auto&& each_near, double best, double& from,
                           double& angle) {
    const double near = best + 2 * tie;
    angle = std::numeric_limits<double>::infinity();
    each_near([&] { return near; }, near,
              [&](uint32_t t) {
                const ClosestPoint<double> c = closest(t, xd);
                if (glm::length(c.point - xd) <= best + tie)
                  angle = std::min(angle, angle_deg(ns, output_normal(mesh, t, c.u, c.v)));
              });
    from = best;
  };
  HostVector<double> from_surface(surface_points.size()), deviation(surface_points.size());
  HostVector<uint8_t> far(surface_points.size(), 0);  // beyond the rings searched: by a tree
  tbb::enumerable_thread_specific<HostVector<int64_t>> ring_runs;
  // Out to kMaxRings rings where the grid has a dense map, else 2 (each cell a search).
  const int64_t max_ring = grid.dense_run.empty() ? 2 : kMaxRings;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, surface_points.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t k = r.begin(); k != r.end(); ++k) {
      const vec3 x = surface_points[k].position;
      const dvec3 xd(x);
      HostVector<int64_t>& runs = ring_runs.local();
      runs.clear();
      int64_t c[3];
      for (int a = 0; a < 3; ++a)
        c[a] = int64_t(std::clamp(std::floor((xd[a] - grid.origin[a]) / grid.cell), -2.0, double(grid.dims[a]) + 1));
      // The occupied cells at Chebyshev distance `ring` from x's.
      const auto add_ring = [&](int64_t ring) {
        for (int64_t dz = -ring; dz <= ring; ++dz)
          for (int64_t dy = -ring; dy <= ring; ++dy)
            for (int64_t dx = -ring; dx <= ring; dx += std::abs(dz) == ring || std::abs(dy) == ring ? 1 : 2 * ring) {
              const int64_t q[3] = {c[0] + dx, c[1] + dy, c[2] + dz};
              const int64_t run = grid.run_of(q);
              if (run >= 0) runs.push_back(run);
            }
      };
      // fn(triangle) for the narrow ones in the cells of `runs` from `first` on whose boxes lie
      // within reach(), read before each, and the wide ones within wide_reach (none when negative).
      const auto each_near_from = [&](size_t first, auto&& reach, double wide_reach, auto&& fn) {
        for (size_t i = first; i < runs.size(); ++i)
          for (uint32_t j = grid.run_begin[size_t(runs[i])]; j < grid.run_begin[size_t(runs[i]) + 1]; ++j)
            if (box_within(grid.box[j], xd, reach())) fn(grid.input[j]);
        if (wide_reach >= 0.0) each_wide_near(x, wide_reach, fn);
      };
      const auto each_near = [&](auto&& reach, double wide_reach, auto&& fn) {
        each_near_from(0, reach, wide_reach, fn);
      };
      // How near a narrow triangle filed beyond ring r of x's cell can be: its box starts beyond
      // cell c + r + 1 along some axis, or, being narrower than a cell, ends before cell
      // c − r + 1 starts; less a margin for the rounding of the cells' coordinates. Once the
      // nearest is nearer, the rings up to r hold all that matters. x's own cell first: the
      // nearest found early prunes the rest.
      const auto beyond = [&](int64_t r) {
        double gap = std::numeric_limits<double>::infinity();
        for (int a = 0; a < 3; ++a) {
          const double at = xd[a] - grid.origin[a];
          gap = std::min(gap, std::min(double(c[a] + r + 1) * grid.cell - at, at - double(c[a] - r + 1) * grid.cell));
        }
        return gap - 1e-3 * grid.cell;
      };
      double best = std::numeric_limits<double>::infinity();
      const auto nearer = [&](uint32_t t) { best = std::min(best, glm::length(closest(t, xd).point - xd)); };
      add_ring(0);
      int64_t ring = 0;
      for (size_t first = 0; !(best + 2 * tie < beyond(ring)) && ring < max_ring;) {
        add_ring(++ring);
        each_near_from(
            first, [&] { return best; }, -1.0, nearer);
        first = runs.size();
      }
      if (!(best + 2 * tie < beyond(ring))) {
        far[k] = 1;
        continue;
      }
      // The wide triangles as near as the narrow ones' nearest, or nearer.
      each_wide_near(x, best + 2 * tie, nearer);
      measure(xd, dvec3(surface_points[k].normal), each_near, best, from_surface[k], deviation[k]);
    }
  });
  if (std::find(far.begin(), far.end(), uint8_t(1)) != far.end()) {
    GridBlocks blocks;
    if (Status s = build_grid_blocks(grid, blocks); !s.ok()) return s;
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, surface_points.size(), 16), [&](const tbb::blocked_range<size_t>& r) {
          for (size_t k = r.begin(); k != r.end(); ++k) {
            if (!far[k]) continue;
            const vec3 x = surface_points[k].position;
            const dvec3 xd(x);
            // The nearest: the narrow triangles' by the blocks, then the wide ones as near or nearer
            // (all of them where no narrow one is).
            double best = std::numeric_limits<double>::infinity();
            const auto nearer = [&](uint32_t t) { best = std::min(best, glm::length(closest(t, xd).point - xd)); };
            for_each_narrow_near(
                grid, blocks, x, [&] { return best; }, [&](uint32_t j) { nearer(grid.input[j]); });
            each_wide_near(x, best + 2 * tie, nearer);
            if (!(best < std::numeric_limits<double>::infinity())) {  // no output triangle of non-zero area
              from_surface[k] = std::numeric_limits<double>::infinity();
              deviation[k] = -1;  // no output: no normal to compare
              continue;
            }
            const auto each_near = [&](auto&& reach, double wide_reach, auto&& fn) {
              for_each_narrow_near(grid, blocks, x, reach, [&](uint32_t j) { fn(grid.input[j]); });
              each_wide_near(x, wide_reach, fn);
            };
            measure(xd, dvec3(surface_points[k].normal), each_near, best, from_surface[k], deviation[k]);
          }
        });
  }
  uint64_t normals = 0;
  for (size_t k = 0; k < surface_points.size(); ++k) {
    result.mean_from_surface += from_surface[k];
    result.hausdorff_from_surface = std::max(result.hausdorff_from_surface, from_surface[k]);
    if (deviation[k] >= 0) {
      result.normal_deviation_mean_deg += deviation[k];
      result.normal_deviation_max_deg = std::max(result.normal_deviation_max_deg, deviation[k]);
      ++normals;
    }
  }
  if (!surface_points.empty()) result.mean_from_surface /= double(surface_points.size());
  if (normals > 0) result.normal_deviation_mean_deg /= double(normals);
  result.chamfer = 0.5 * (result.mean_to_surface + result.mean_from_surface);
  result.seconds_from_surface = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_from).count();
  out = result;
  return Status::Ok();
}

Status mesh_quality_report_unguarded(const GwnModel& model, const SurfaceMesh& mesh,
                                     const SurfaceDistanceOptions& options, MeshQualityReport& out,
                                     bool weld_equal_positions) {
  out = MeshQualityReport{};
  const auto t0 = std::chrono::steady_clock::now();
  const auto since = [](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  };
  if (Status s = validate_surface_mesh(mesh, "mesh_quality_report"); !s.ok()) return s;
  // One weld of the positions for the topology and the pairs (the topology beside the pairs, on
  // two threads, took a third more memory at the peak for a few hundredths of a second).
  WeldedPositions welded;
  if (Status s = guard_status("mesh_topology",
                              [&] {
                                weld_positions(mesh.positions, welded);
                                return mesh_topology_unguarded(mesh, out.topology, weld_equal_positions, &welded);
                              });
      !s.ok())
    return s;
  out.seconds_topology = since(t0);
  const auto t1 = std::chrono::steady_clock::now();
  // One grid of the output's triangles for the pairs and the distances.
  TriangleGrid grid;
  if (Status s = guard_status("mesh_quality_report",
                              [&] {
                                build_triangle_grid(mesh, grid);
                                return Status::Ok();
                              });
      !s.ok())
    return s;
  if (Status s = guard_status(
          "count_self_intersections",
          [&] { return count_self_intersections_unguarded(mesh, out.self_intersections, nullptr, &grid, &welded); });
      !s.ok())
    return s;
  out.seconds_self_intersections = since(t1);
  if (Status s = guard_status("surface_distances",
                              [&] { return surface_distances_unguarded(model, mesh, options, out.distances, &grid); });
      !s.ok())
    return s;
  out.seconds = since(t0);
  return Status::Ok();
}

}  // namespace

SurfaceDistanceOptions samples_for_output(size_t output_triangles, const SurfaceDistanceOptions& full) {
  const double share = std::clamp(double(output_triangles) / double(kFullSampleTriangles), 0.1, 1.0);
  const auto scaled = [&](uint32_t count) { return uint32_t(std::ceil(share * double(count))); };
  SurfaceDistanceOptions out = full;
  out.output_samples = scaled(full.output_samples);
  out.vertex_samples = scaled(full.vertex_samples);
  out.surface_rays = scaled(full.surface_rays);
  out.sheet_samples = scaled(full.sheet_samples);
  return out;
}

// Each entry's arrays reuse their large blocks while it runs (base/host_blocks.h).
Status mesh_topology(const SurfaceMesh& mesh, MeshTopology& out, bool weld_equal_positions) {
  return guard_status("mesh_topology", [&] {
    const HostBlockScope blocks;
    return mesh_topology_unguarded(mesh, out, weld_equal_positions);
  });
}

Status count_self_intersections(const SurfaceMesh& mesh, uint64_t& count, std::vector<glm::uvec2>* pairs) {
  return guard_status("count_self_intersections", [&] {
    const HostBlockScope blocks;
    return count_self_intersections_unguarded(mesh, count, pairs);
  });
}

Status surface_distances(const GwnModel& model, const SurfaceMesh& mesh, const SurfaceDistanceOptions& options,
                         SurfaceDistances& out) {
  return guard_status("surface_distances", [&] {
    const HostBlockScope blocks;
    return surface_distances_unguarded(model, mesh, options, out);
  });
}

Status mesh_quality_report(const GwnModel& model, const SurfaceMesh& mesh, const SurfaceDistanceOptions& options,
                           MeshQualityReport& out, bool weld_equal_positions) {
  return guard_status("mesh_quality_report", [&] {
    const HostBlockScope blocks;
    return mesh_quality_report_unguarded(model, mesh, options, out, weld_equal_positions);
  });
}

}  // namespace gwnrt
