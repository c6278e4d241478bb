// ∂M, its loops, the cone C over it and the spanning surface (gwnrt/geometry/boundary.h).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <span>

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_sort.h>

#include "gwnrt/geometry/boundary.h"
#include "gwnrt/geometry/weld.h"

namespace gwnrt {

BoundaryCurve extract_boundary(const Mesh& mesh) {
  return extract_boundary(mesh, vertices_by_position(mesh.positions));
}

BoundaryCurve extract_boundary(const Mesh& mesh, std::span<const uint32_t> canonical) {
  struct HalfEdge {
    uint64_t key;  // (min << 32) | max of the welded endpoints
    int32_t sign;  // +1 when the triangle walks min -> max
  };
  const size_t nt = mesh.triangles.size();
  std::vector<HalfEdge> half_edges(3 * nt, HalfEdge{~uint64_t(0), 0});
  tbb::parallel_for(size_t(0), nt, [&](size_t t) {
    const uvec3 tri = mesh.triangles[t];
    if (is_degenerate_triangle(mesh.positions[tri[0]], mesh.positions[tri[1]], mesh.positions[tri[2]])) return;
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = canonical[tri[k]], b = canonical[tri[(k + 1) % 3]];
      if (a == b) continue;
      half_edges[3 * t + k] = {(uint64_t(std::min(a, b)) << 32) | std::max(a, b), a < b ? 1 : -1};
    }
  });
  tbb::parallel_sort(half_edges.begin(), half_edges.end(),
                     [](const HalfEdge& x, const HalfEdge& y) { return x.key < y.key; });

  BoundaryCurve curve;
  for (size_t i = 0; i < half_edges.size();) {
    size_t j = i;
    int sum = 0;
    while (j < half_edges.size() && half_edges[j].key == half_edges[i].key) sum += half_edges[j++].sign;
    if (half_edges[i].sign != 0 && sum != 0) {
      const vec3 lo = mesh.positions[uint32_t(half_edges[i].key >> 32)];
      const vec3 hi = mesh.positions[uint32_t(half_edges[i].key & 0xFFFFFFFFu)];
      for (int m = 0; m < std::abs(sum); ++m) {
        curve.endpoints.push_back(sum > 0 ? lo : hi);
        curve.endpoints.push_back(sum > 0 ? hi : lo);
      }
    }
    i = j;
  }
  return curve;
}

std::vector<uint32_t> boundary_loops(const BoundaryCurve& curve, uint32_t& loop_count) {
  // Union-find over endpoints matched by exact position (the curve's endpoints are copies of
  // welded vertices, so equal positions are the same vertex).
  const size_t n = curve.segment_count();
  std::vector<uint32_t> parent(2 * n);
  for (uint32_t i = 0; i < parent.size(); ++i) parent[i] = i;
  auto find = [&](uint32_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  std::vector<uint32_t> order(2 * n);
  for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  auto key = [&](uint32_t i) {
    const vec3 p = curve.endpoints[i] + vec3(0.0f);  // -0 + 0 = +0
    return std::array<float, 3>{p.x, p.y, p.z};
  };
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return key(a) < key(b); });
  auto unite = [&](uint32_t a, uint32_t b) { parent[find(a)] = find(b); };
  for (size_t i = 1; i < order.size(); ++i)
    if (key(order[i]) == key(order[i - 1])) unite(order[i], order[i - 1]);
  for (uint32_t s = 0; s < n; ++s) unite(2 * s, 2 * s + 1);
  std::vector<uint32_t> loop(n), id(2 * n, kEmptyLane);
  loop_count = 0;
  for (uint32_t s = 0; s < n; ++s) {
    uint32_t& r = id[find(2 * s)];
    if (r == kEmptyLane) r = loop_count++;
    loop[s] = r;
  }
  return loop;
}

Mesh boundary_cone(const BoundaryCurve& curve, std::span<const uint32_t> loop_of_segment, uint32_t loop_count) {
  Mesh cone;
  const size_t n = curve.segment_count();
  if (n == 0) return cone;
  // One apex per loop, the mean of its endpoints: the fan then stays inside the loop's box
  // (its convex hull), which is what bounds where smooth pieces can be.
  std::vector<dvec3> sum(loop_count, dvec3(0.0));
  std::vector<double> count(loop_count, 0.0);
  for (size_t s = 0; s < n; ++s) {
    sum[loop_of_segment[s]] += dvec3(curve.endpoints[2 * s]) + dvec3(curve.endpoints[2 * s + 1]);
    count[loop_of_segment[s]] += 2;
  }
  std::vector<vec3> apex(loop_count);
  for (uint32_t l = 0; l < loop_count; ++l) apex[l] = vec3(sum[l] / count[l]);
  // A cone triangle whose apex lies on its segment's line has zero area and is left out of the
  // tree, and the tracer reads ∂M off the tree's triangles (phase.h): the apex is moved off
  // every such line. A loop lying on one line is the exception: its segments cancel (their
  // field is zero), so nothing is lost with them.
  std::vector<std::vector<uint32_t>> segments_of(loop_count);
  for (uint32_t s = 0; s < n; ++s) segments_of[loop_of_segment[s]].push_back(s);
  for (uint32_t l = 0; l < loop_count; ++l) {
    const std::vector<uint32_t>& seg = segments_of[l];
    const vec3 a0 = curve.endpoints[2 * seg[0]], b0 = curve.endpoints[2 * seg[0] + 1];
    Aabb box;
    bool on_one_line = true;
    for (uint32_t s : seg)
      for (int k = 0; k < 2; ++k) {
        box.extend(curve.endpoints[2 * s + k]);
        on_one_line = on_one_line && is_degenerate_triangle(a0, b0, curve.endpoints[2 * s + k]);
      }
    if (on_one_line) continue;
    auto collinear = [&](const vec3& z) {
      for (uint32_t s : seg)
        if (is_degenerate_triangle(z, curve.endpoints[2 * s], curve.endpoints[2 * s + 1])) return true;
      return false;
    };
    const float size = glm::length(box.hi - box.lo);
    for (int attempt = 1; attempt <= 8 && collinear(apex[l]); ++attempt) {
      // Directions far from any axis, so that grid-aligned loops cannot keep the apex on a line.
      const vec3 direction = glm::normalize(vec3(0.5773f, 0.6172f + 0.1f * attempt, 0.5345f - 0.07f * attempt));
      apex[l] = vec3(sum[l] / count[l]) + (1e-3f * float(attempt) * size) * direction;
    }
  }
  cone.positions.reserve(2 * n + loop_count);
  cone.positions.insert(cone.positions.end(), curve.endpoints.begin(), curve.endpoints.end());
  cone.positions.insert(cone.positions.end(), apex.begin(), apex.end());
  cone.triangles.reserve(n);
  for (uint32_t s = 0; s < n; ++s) cone.triangles.push_back({uint32_t(2 * n) + loop_of_segment[s], 2 * s, 2 * s + 1});
  return cone;
}

namespace {

struct Segment {
  vec3 a, b;  // a -> b
};

// Reorders segments[begin, end) so that every run of kSpanningGroup (from begin) is compact: the
// midpoints split at a multiple of the group size along their box's longest axis, recursively.
void order_into_groups(std::vector<Segment>& segments, size_t begin, size_t end) {
  const size_t count = end - begin;
  if (count <= kSpanningGroup) return;
  Aabb box;
  for (size_t i = begin; i < end; ++i) box.extend(0.5f * (segments[i].a + segments[i].b));
  const vec3 extent = box.hi - box.lo;
  const int axis = extent.x >= extent.y ? (extent.x >= extent.z ? 0 : 2) : (extent.y >= extent.z ? 1 : 2);
  const size_t half = (count / 2 + kSpanningGroup - 1) / kSpanningGroup * kSpanningGroup;  // < count
  std::nth_element(segments.begin() + ptrdiff_t(begin), segments.begin() + ptrdiff_t(begin + half),
                   segments.begin() + ptrdiff_t(end), [axis](const Segment& x, const Segment& y) {
                     return x.a[axis] + x.b[axis] < y.a[axis] + y.b[axis];
                   });
  if (count < 4096) {
    order_into_groups(segments, begin, begin + half);
    order_into_groups(segments, begin + half, end);
  } else {
    tbb::parallel_invoke([&] { order_into_groups(segments, begin, begin + half); },
                         [&] { order_into_groups(segments, begin + half, end); });
  }
}

}  // namespace

SpanningSurface spanning_surface(const BoundaryCurve& curve) {
  SpanningSurface out;
  std::vector<Segment> level(curve.segment_count());
  for (size_t s = 0; s < level.size(); ++s) level[s] = {curve.endpoints[2 * s], curve.endpoints[2 * s + 1]};
  auto fan = [&](const std::vector<Segment>& segments, size_t first, const vec3& apex, size_t begin, size_t end) {
    for (size_t s = begin; s < end; ++s) {
      const size_t t = first + s;
      out.mesh.positions[3 * t] = apex;
      out.mesh.positions[3 * t + 1] = segments[s].a;
      out.mesh.positions[3 * t + 2] = segments[s].b;
      out.mesh.triangles[t] = {uint32_t(3 * t), uint32_t(3 * t + 1), uint32_t(3 * t + 2)};
    }
  };
  auto grow = [&](size_t more) {
    out.mesh.positions.resize(out.mesh.positions.size() + 3 * more);
    out.mesh.triangles.resize(out.mesh.triangles.size() + more);
  };
  auto mean = [](const std::vector<Segment>& segments, size_t begin, size_t end) {
    dvec3 sum(0.0);
    for (size_t s = begin; s < end; ++s) sum += dvec3(segments[s].a) + dvec3(segments[s].b);
    return vec3(sum / double(2 * (end - begin)));
  };
  // ∂M is closed, and so is every level's curve: a level needs at most log_4 of the segments
  // levels; the cap only guards against a curve that is not.
  for (int depth = 0; !level.empty(); ++depth) {
    const size_t first = out.mesh.triangles.size();
    grow(level.size());
    if (depth == 64) {
      fan(level, first, mean(level, 0, level.size()), 0, level.size());
      out.single_apex_segments = level.size();
      break;
    }
    order_into_groups(level, 0, level.size());
    const size_t groups = (level.size() + kSpanningGroup - 1) / kSpanningGroup;
    // Per group, the spokes of −∂(its fan) less its segments: for an end v met k times more as
    // a segment's end than as its start, k spokes v -> apex in ∂ of the fan, so k copies of
    // apex -> v here (reversed for k < 0).
    std::vector<std::array<Segment, 2 * kSpanningGroup>> spokes(groups);
    std::vector<uint32_t> spoke_count(groups, 0);
    tbb::parallel_for(size_t(0), groups, [&](size_t g) {
      const size_t begin = g * kSpanningGroup, end = std::min(begin + kSpanningGroup, level.size());
      const vec3 apex = mean(level, begin, end);
      fan(level, first, apex, begin, end);
      std::array<vec3, 2 * kSpanningGroup> ends;
      std::array<int, 2 * kSpanningGroup> net{};
      uint32_t distinct = 0;
      auto add = [&](const vec3& v, int k) {
        uint32_t i = 0;
        while (i < distinct && !(ends[i] == v)) ++i;
        if (i == distinct) ends[distinct++] = v;
        net[i] += k;
      };
      for (size_t s = begin; s < end; ++s) {
        add(level[s].b, 1);
        add(level[s].a, -1);
      }
      for (uint32_t i = 0; i < distinct; ++i) {
        if (ends[i] == apex) continue;  // a spoke of no length
        for (int c = 0; c < std::abs(net[i]); ++c)
          spokes[g][spoke_count[g]++] = net[i] > 0 ? Segment{apex, ends[i]} : Segment{ends[i], apex};
      }
    });
    std::vector<Segment> next;
    for (size_t g = 0; g < groups; ++g) next.insert(next.end(), spokes[g].begin(), spokes[g].begin() + spoke_count[g]);
    // Spokes that stop shrinking (loose ends in every group: small loops scattered) are fanned
    // from one apex, as C is.
    if (4 * next.size() > 3 * level.size() && next.size() > kSpanningGroup) {
      const size_t rest = out.mesh.triangles.size();
      grow(next.size());
      fan(next, rest, mean(next, 0, next.size()), 0, next.size());
      out.single_apex_segments = next.size();
      break;
    }
    level = std::move(next);
  }
  return out;
}

std::vector<ConeSegment> cone_segments(const TriangleTree& cone) {
  std::vector<ConeSegment> segments(cone.vertices.size() / 3);
  for (size_t t = 0; t < segments.size(); ++t) {
    const double length2 = glm::dot(dvec3(cone.vertices[3 * t + 2]) - dvec3(cone.vertices[3 * t + 1]),
                                    dvec3(cone.vertices[3 * t + 2]) - dvec3(cone.vertices[3 * t + 1]));
    // The length rounded up: the bound it enters must not shrink.
    segments[t] = {std::nextafter(float(std::sqrt(length2)), kInfinity), float(1.0 / length2)};
  }
  return segments;
}

std::vector<WideNodeLength> cone_boundary_lengths(const TriangleTree& cone) {
  // A cone triangle's edge 1 -> 2 is its segment of ∂M.
  return lane_lengths(
      cone.bvh,
      [](const void* c, uint32_t t) {
        const vec3* v = static_cast<const vec3*>(c);
        return glm::length(dvec3(v[3 * t + 2]) - dvec3(v[3 * t + 1]));
      },
      cone.vertices.data());
}

}  // namespace gwnrt
