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

// A fan's apex: the mean of its segments' endpoints, moved off the line of every one of them so
// that none of its triangles has zero area (the tree leaves those out, and the tracer reads ∂M
// off the tree's triangles, phase.h): by 1e-3 of the segments' box diagonal, up to 8 times, in
// directions far from any axis (grid-aligned loops cannot keep it on a line). A whole loop on one
// line (`whole_loop`) cancels (its field is zero, nothing is lost with it): its apex stays the
// mean; a group of a spanned loop on one line does not, and is moved off it.
vec3 fan_apex(const Segment* segments, size_t count, bool whole_loop) {
  dvec3 sum(0.0);
  for (size_t s = 0; s < count; ++s) sum += dvec3(segments[s].a) + dvec3(segments[s].b);
  const vec3 mean(sum / double(2 * count));
  auto collinear = [&](const vec3& z) {
    for (size_t s = 0; s < count; ++s)
      if (is_degenerate_triangle(z, segments[s].a, segments[s].b)) return true;
    return false;
  };
  if (!collinear(mean)) return mean;
  Aabb box;
  bool on_one_line = true;
  for (size_t s = 0; s < count; ++s)
    for (const vec3& p : {segments[s].a, segments[s].b}) {
      box.extend(p);
      on_one_line = on_one_line && is_degenerate_triangle(segments[0].a, segments[0].b, p);
    }
  if (on_one_line && whole_loop) return mean;
  const float size = glm::length(box.hi - box.lo);
  vec3 apex = mean;
  for (int attempt = 1; attempt <= 8 && collinear(apex); ++attempt) {
    const vec3 direction = glm::normalize(vec3(0.5773f, 0.6172f + 0.1f * attempt, 0.5345f - 0.07f * attempt));
    apex = mean + (1e-3f * float(attempt) * size) * direction;
  }
  return apex;
}

// Triangles (apex, a, b) for segments [begin, end) into the soup `mesh` (sized already), segment s
// as triangle first + s.
void fan_into(Mesh& mesh, size_t first, const std::vector<Segment>& segments, const vec3& apex, size_t begin,
              size_t end) {
  for (size_t s = begin; s < end; ++s) {
    const size_t t = first + s;
    mesh.positions[3 * t] = apex;
    mesh.positions[3 * t + 1] = segments[s].a;
    mesh.positions[3 * t + 2] = segments[s].b;
    mesh.triangles[t] = {uint32_t(3 * t), uint32_t(3 * t + 1), uint32_t(3 * t + 2)};
  }
}

}  // namespace

SpanningSurface spanning_surface(const BoundaryCurve& curve) {
  SpanningSurface out;
  std::vector<Segment> level(curve.segment_count());
  for (size_t s = 0; s < level.size(); ++s) level[s] = {curve.endpoints[2 * s], curve.endpoints[2 * s + 1]};
  auto fan = [&](const std::vector<Segment>& segments, size_t first, const vec3& apex, size_t begin, size_t end) {
    fan_into(out.mesh, first, segments, apex, begin, end);
  };
  auto grow = [&](size_t more) {
    out.mesh.positions.resize(out.mesh.positions.size() + 3 * more);
    out.mesh.triangles.resize(out.mesh.triangles.size() + more);
  };
  auto mean = [](const std::vector<Segment>& segments, size_t begin, size_t end) {
    return fan_apex(segments.data() + begin, end - begin, false);
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

namespace {

// Whether the loop is mostly a curve: at most a quarter of its segments start where another does.
// A scan's rim pinches at a few points (the birdBath scan's: 105 of 1,304); the boundary of
// flipped faces repeats every segment, and a soup's branches at every point.
bool mostly_a_curve(const BoundaryCurve& loop) {
  std::vector<std::array<float, 3>> starts(loop.segment_count());
  for (size_t s = 0; s < starts.size(); ++s) {
    const vec3 a = loop.endpoints[2 * s] + 0.0f;  // -0 as +0, as position welding does
    starts[s] = {a.x, a.y, a.z};
  }
  std::sort(starts.begin(), starts.end());
  size_t repeated = 0;
  for (size_t s = 1; s < starts.size(); ++s) repeated += starts[s] == starts[s - 1];
  return 4 * repeated <= starts.size();
}

// The loop's segments fanned from one apex (fan_apex): a spanning surface of one level.
SpanningSurface fan_surface(const BoundaryCurve& loop) {
  std::vector<Segment> segments(loop.segment_count());
  for (size_t s = 0; s < segments.size(); ++s) segments[s] = {loop.endpoints[2 * s], loop.endpoints[2 * s + 1]};
  SpanningSurface out;
  out.mesh.positions.resize(3 * segments.size());
  out.mesh.triangles.resize(segments.size());
  fan_into(out.mesh, 0, segments, fan_apex(segments.data(), segments.size(), true), 0, segments.size());
  return out;
}

}  // namespace

Cone boundary_cone(const BoundaryCurve& curve, std::span<const uint32_t> loop_of_segment, uint32_t loop_count) {
  Cone cone;
  const size_t n = curve.segment_count();
  std::vector<std::vector<uint32_t>> segments_of(loop_count);
  for (uint32_t s = 0; s < n; ++s) segments_of[loop_of_segment[s]].push_back(s);
  // Each loop's surface apart (its first segment_count triangles carry its segments), then the
  // carrying triangles of all loops ahead of the inner ones.
  std::vector<SpanningSurface> surfaces(loop_count);
  tbb::parallel_for(uint32_t(0), loop_count, [&](uint32_t l) {
    BoundaryCurve loop;
    loop.endpoints.reserve(2 * segments_of[l].size());
    for (uint32_t s : segments_of[l]) {
      loop.endpoints.push_back(curve.endpoints[2 * s]);
      loop.endpoints.push_back(curve.endpoints[2 * s + 1]);
    }
    surfaces[l] = segments_of[l].size() > kFannedLoopSegments && mostly_a_curve(loop) ? spanning_surface(loop)
                                                                                      : fan_surface(loop);
  });
  auto append = [&](uint32_t l, size_t begin, size_t end) {
    const Mesh& from = surfaces[l].mesh;
    for (size_t t = begin; t < end; ++t) {
      const uint32_t first = uint32_t(cone.mesh.positions.size());
      for (int k = 0; k < 3; ++k) cone.mesh.positions.push_back(from.positions[from.triangles[t][k]]);
      cone.mesh.triangles.push_back({first, first + 1, first + 2});
      cone.loop_of_triangle.push_back(l);
    }
  };
  for (uint32_t l = 0; l < loop_count; ++l) append(l, 0, segments_of[l].size());
  cone.segment_triangles = cone.mesh.triangles.size();
  for (uint32_t l = 0; l < loop_count; ++l) append(l, segments_of[l].size(), surfaces[l].mesh.triangles.size());
  return cone;
}

namespace {

// The length of the segment of ∂M that leaf-order cone triangle t carries (its edge 1 -> 2), or 0
// for an inner triangle.
double carried_length(const TriangleTree& cone, size_t segment_triangles, size_t t) {
  if (cone.triangle_ids[t] >= segment_triangles) return 0.0;
  return glm::length(dvec3(cone.vertices[3 * t + 2]) - dvec3(cone.vertices[3 * t + 1]));
}

}  // namespace

std::vector<ConeSegment> cone_segments(const TriangleTree& cone, size_t segment_triangles) {
  std::vector<ConeSegment> segments(cone.triangle_ids.size());
  for (size_t t = 0; t < segments.size(); ++t) {
    const double length = carried_length(cone, segment_triangles, t);
    // The length rounded up: the bound it enters must not shrink.
    if (length > 0.0) segments[t] = {std::nextafter(float(length), kInfinity), float(1.0 / (length * length))};
  }
  return segments;
}

std::vector<WideNodeLength> cone_boundary_lengths(const TriangleTree& cone, size_t segment_triangles) {
  struct Context {
    const TriangleTree* cone;
    size_t segment_triangles;
  } context{&cone, segment_triangles};
  return lane_lengths(
      cone.bvh,
      [](const void* c, uint32_t t) {
        const Context& x = *static_cast<const Context*>(c);
        return carried_length(*x.cone, x.segment_triangles, t);
      },
      &context);
}

}  // namespace gwnrt
