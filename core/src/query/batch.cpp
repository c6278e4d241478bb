// The TBB batch drivers (gwnrt/query/batch.h).
#include "gwnrt/query/batch.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <type_traits>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "base/message.h"

namespace gwnrt {
namespace {

// What the drivers share: store(i, fn(in[i])) over TBB chunks of `grain`, counting finished
// items into `progress`, once validate() passes. `order`, when given, is the sequence in which
// items are visited (the low 32 bits of each entry are the item's index): results still land at
// their items' places.
template <class In, class Validate, class Fn, class Store, class Order>
Status parallel_map(const char* name, std::span<const In> in, size_t grain, std::atomic<size_t>* progress,
                    Validate validate, Fn fn, Store store, Order make_order) {
  using Out = std::invoke_result_t<Fn&, const In&>;
  if (Status s = validate(); !s.ok()) return s;
  return guard_status(name, [&] {
    const std::vector<uint64_t> order = make_order();
    // A small batch of costly items (the brute force's few points) still spreads over the
    // threads: at least 64 chunks where there are that many items.
    const size_t chunk = std::max<size_t>(1, std::min(grain, in.size() / 64));
    tbb::parallel_for(tbb::blocked_range<size_t>(0, in.size(), chunk), [&](const tbb::blocked_range<size_t>& range) {
      if (order.empty()) {
        for (size_t k = range.begin(); k != range.end(); ++k) store(k, fn(in[k]));
      } else {
        // The order scatters the items over the batch: each block's inputs are gathered and its
        // results scattered in loops of their own, whose misses overlap, instead of one miss
        // per item stalling the evaluation (docs/performance.md, batch order).
        constexpr size_t kBlock = 32;
        In block_in[kBlock];
        Out block_out[kBlock];
        for (size_t b = range.begin(); b < range.end(); b += kBlock) {
          const size_t m = std::min(kBlock, range.end() - b);
          for (size_t j = 0; j < m; ++j) block_in[j] = in[size_t(order[b + j] & 0xffffffffu)];
          for (size_t j = 0; j < m; ++j) block_out[j] = fn(block_in[j]);
          for (size_t j = 0; j < m; ++j) store(size_t(order[b + j] & 0xffffffffu), block_out[j]);
        }
      }
      if (progress) progress->fetch_add(range.size(), std::memory_order_relaxed);
    });
    return Status::Ok();
  });
}

// Points are evaluated in Morton order of a 2^10 grid over the model's box (points outside clamp
// to its faces), so that consecutive queries touch the same parts of the trees: a large mesh's
// trees do not stay in cache otherwise. Batches under 16384 points are visited in input order.
inline constexpr size_t kSpatialOrderMinPoints = 16384;
inline constexpr uint32_t kUnorderedSegments = 65536;

uint32_t spread_bits(uint32_t v) {  // 10 bits to every third of 30
  v = (v | (v << 16)) & 0x030000ffu;
  v = (v | (v << 8)) & 0x0300f00fu;
  v = (v | (v << 4)) & 0x030c30c3u;
  v = (v | (v << 2)) & 0x09249249u;
  return v;
}

std::vector<uint64_t> spatial_order(const Aabb& box, std::span<const vec3> points) {
  std::vector<uint64_t> order;
  if (points.size() < kSpatialOrderMinPoints || points.size() > 0xffffffffu || !box.valid()) return order;
  order.resize(points.size());
  const vec3 extent = glm::max(box.hi - box.lo, vec3(1e-30f));
  tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      uint32_t cell[3];
      for (int a = 0; a < 3; ++a) {
        const float u = (points[i][a] - box.lo[a]) / extent[a] * 1024.0f;  // NaN fails both tests: cell 0
        cell[a] = u > 0.0f ? (u < 1023.0f ? uint32_t(u) : 1023u) : 0u;
      }
      const uint64_t code = spread_bits(cell[0]) | (spread_bits(cell[1]) << 1) | (spread_bits(cell[2]) << 2);
      order[i] = (code << 32) | uint64_t(i);
    }
  });
  tbb::parallel_sort(order.begin(), order.end());
  return order;
}

}  // namespace

namespace {

// `name` fails when a batch's inputs and outputs differ in size, naming what they hold.
Status check_batch_sizes(const char* name, const char* items, size_t in, const char* slots, size_t out) {
  if (in == out) return Status::Ok();
  return {StatusCode::kInvalidArgument,
          std::string(name) + ": " + std::to_string(in) + " " + items + " but " + std::to_string(out) + " " + slots};
}

// evaluate_points with store(i, result) for each point.
template <class Store>
Status evaluate_points_with(const GwnModel& model, std::span<const vec3> points, const QueryRequest& request,
                            std::atomic<size_t>* progress, Store store) {
  ModelView view;
  return parallel_map(
      "evaluate_points", points, 256, progress,
      [&] {
        if (Status s = validate_points(points); !s.ok()) return s;
        if (Status s = validate_request(request); !s.ok()) return s;
        if (Status s = model.prepare(parts_read_by(request)); !s.ok()) return s;
        view = model.view();
        return validate_request(request, &view);
      },
      [&](const vec3& x) { return evaluate_point(view, x, request); }, store,
      [&] {
        // The boundary distance alone reads only ∂M's tree, which below kUnorderedSegments stays in
        // cache in any order: sorting would cost more than the queries.
        if (request.fields == kFieldBoundaryDistance && view.boundary.segment_count < kUnorderedSegments)
          return std::vector<uint64_t>();
        return spatial_order(view.bounds, points);
      });
}

}  // namespace

Status evaluate_points(const GwnModel& model, std::span<const vec3> points, const QueryRequest& request,
                       std::span<PointResult> results, std::atomic<size_t>* progress) {
  if (Status s = check_batch_sizes("evaluate_points", "points", points.size(), "result slots", results.size()); !s.ok())
    return s;
  return evaluate_points_with(model, points, request, progress,
                              [&](size_t i, const PointResult& r) { results[i] = r; });
}

Status evaluate_points_to_columns(const GwnModel& model, std::span<const vec3> points, const QueryRequest& request,
                                  const PointColumns& columns, std::atomic<size_t>* progress) {
  return evaluate_points_with(model, points, request, progress,
                              [&](size_t i, const PointResult& r) { store_point_result(columns, i, r); });
}

Status trace_rays(const GwnModel& model, std::span<const Ray> rays, const TraceOptions& options, std::span<RayHit> hits,
                  std::atomic<size_t>* progress) {
  if (Status s = check_batch_sizes("trace_rays", "rays", rays.size(), "hit slots", hits.size()); !s.ok()) return s;
  ModelView view;
  // Rays cost far more than points (and vary more), so chunks are smaller.
  return parallel_map(
      "trace_rays", rays, 64, progress,
      [&] {
        if (Status s = validate_trace_options(options); !s.ok()) return s;
        if (Status s = model.prepare(kPartBoundary | kPartLevelFreeCells); !s.ok()) return s;
        view = model.view();
        return validate_trace_view(view);
      },
      [&](const Ray& ray) { return trace_surface(view, ray, options); },
      [&](size_t i, const RayHit& hit) { hits[i] = hit; }, [] { return std::vector<uint64_t>(); });
}

}  // namespace gwnrt
