// The attribute transfer's driver (meshing/attribute_transfer.h): the per-vertex and per-face
// passes over the TBB backend, then the seam split on the host. The split touches only the faces
// that straddle a seam (a band one face wide along each seam: a small share of the faces), so it
// is a sort of their corners rather than a pass.
#include "gwnrt/meshing/attribute_transfer.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>
#include <tuple>

#include <tbb/parallel_sort.h>

#include "gwnrt/meshing/extract_surface.h"
#include "meshing/disjoint_sets.h"
#include "meshing/host_backend.h"

namespace gwnrt {
namespace {

constexpr uint32_t kDropped = 0xffffffffu;

// The bits of an edge's two ends (position, UV), lower end first, and its triangle: edges with
// equal keys join their triangles' charts.
struct ChartEdge {
  std::array<uint32_t, 10> key;
  uint32_t triangle;
};

std::array<uint32_t, 5> end_bits(const vec3& p, const glm::vec2& uv) {
  // +0.0f for -0.0f, so that the two zeros compare equal as bits.
  auto bits = [](float x) { return std::bit_cast<uint32_t>(x == 0.0f ? 0.0f : x); };
  return {bits(p.x), bits(p.y), bits(p.z), bits(uv.x), bits(uv.y)};
}

}  // namespace

std::vector<uint32_t> uv_charts(const Mesh& mesh) {
  if (mesh.uv_triangles.size() != mesh.triangles.size()) return {};
  const size_t n = mesh.triangles.size();
  std::vector<ChartEdge> edges(3 * n);
  tbb::parallel_for(size_t(0), n, [&](size_t t) {
    const uvec3 tri = mesh.triangles[t], uv = mesh.uv_triangles[t];
    for (int k = 0; k < 3; ++k) {
      const int l = (k + 1) % 3;
      std::array<uint32_t, 5> a = end_bits(mesh.positions[tri[k]], mesh.uvs[uv[k]]);
      std::array<uint32_t, 5> b = end_bits(mesh.positions[tri[l]], mesh.uvs[uv[l]]);
      // Ordered by position only, so that the two sides of an edge (which run it in opposite
      // directions) build the same key when their UVs agree.
      if (std::lexicographical_compare(b.begin(), b.begin() + 3, a.begin(), a.begin() + 3)) std::swap(a, b);
      ChartEdge& e = edges[3 * t + size_t(k)];
      std::copy(a.begin(), a.end(), e.key.begin());
      std::copy(b.begin(), b.end(), e.key.begin() + 5);
      e.triangle = uint32_t(t);
    }
  });
  tbb::parallel_sort(edges.begin(), edges.end(), [](const ChartEdge& a, const ChartEdge& b) { return a.key < b.key; });
  DisjointSets sets(n);
  for (size_t i = 1; i < edges.size(); ++i)
    if (edges[i].key == edges[i - 1].key) sets.unite(edges[i].triangle, edges[i - 1].triangle);
  std::vector<uint32_t> chart(n);
  uint32_t charts = 0;
  for (size_t t = 0; t < n; ++t) {
    const uint32_t root = sets.find(uint32_t(t));
    chart[t] = root == t ? charts++ : chart[root];  // the root is the chart's lowest triangle
  }
  return chart;
}

namespace {

// The corners of faces straddling a seam whose own chart is not their face's dominant one: each
// (vertex, chart) pair gets a copy of the vertex with the UV that chart gives it, shared by all
// the faces that ask for it, so each chart's side of the seam stays connected.
struct SeamCorner {
  uint32_t vertex, chart, face, corner;
  bool operator<(const SeamCorner& o) const {
    return std::tie(vertex, chart, face, corner) < std::tie(o.vertex, o.chart, o.face, o.corner);
  }
};

void split_seams(HostBackend& backend, const TriangleTreeView& tree, const SourceAttributesView& src,
                 SurfaceMesh& out) {
  const uint64_t face_count = out.triangles.size();
  std::vector<uint32_t> dominant(face_count);
  backend.parallel_for(face_count,
                       FaceChartPass{tree, src, out.positions.data(), out.triangles.data(), out.source_triangles.data(),
                                     dominant.data()},
                       256);
  std::vector<SeamCorner> corners;
  for (uint64_t f = 0; f < face_count; ++f) {
    if (dominant[f] == kSingleChart) continue;
    const uint32_t chart = src.charts[dominant[f]];
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t v = out.triangles[f][k];
      if (src.charts[out.source_triangles[v]] != chart) corners.push_back({v, chart, uint32_t(f), k});
    }
  }
  if (corners.empty()) return;
  std::sort(corners.begin(), corners.end());
  for (size_t i = 0; i < corners.size();) {
    const SeamCorner& first = corners[i];
    const uint32_t copy = uint32_t(out.positions.size());
    for_each_vertex_array(out, [&](auto& a) {
      if (!a.empty()) a.push_back(a[first.vertex]);
    });
    out.uvs[copy] = uv_from_triangle(src, dominant[first.face], out.positions[first.vertex]);
    for (; i < corners.size() && corners[i].vertex == first.vertex && corners[i].chart == first.chart; ++i)
      out.triangles[corners[i].face][corners[i].corner] = copy;
  }
  // A vertex all of whose faces took another chart is left without faces: drop it.
  std::vector<uint32_t> index(out.positions.size(), 0);
  for (const uvec3& t : out.triangles)
    for (int k = 0; k < 3; ++k) index[t[k]] = 1;
  if (std::find(index.begin(), index.end(), 0u) == index.end()) return;
  uint32_t kept = 0;
  for (uint32_t& x : index) x = x ? kept++ : kDropped;
  for_each_vertex_array(out, [&](auto& a) {
    if (a.empty()) return;
    for (size_t v = 0; v < a.size(); ++v)
      if (index[v] != kDropped) a[index[v]] = a[v];
    a.resize(kept);
  });
  for (uvec3& t : out.triangles) t = uvec3(index[t.x], index[t.y], index[t.z]);
}

}  // namespace

Status check_attributes(const Mesh& source, uint32_t attributes) {
  if ((attributes & kAttributeUv) && source.uv_triangles.empty())
    return {StatusCode::kInvalidArgument, "meshing: UVs were asked for but the source mesh has no texture coordinates"};
  if ((attributes & kAttributeColor) && source.colors.empty())
    return {StatusCode::kInvalidArgument, "meshing: colours were asked for but the source mesh has no vertex colours"};
  return Status::Ok();
}

Status transfer_attributes(const Mesh& source, const TriangleTreeView& tree, uint32_t attributes, SurfaceMesh& out) {
  if (Status s = check_attributes(source, attributes); !s.ok()) return s;
  if (attributes == 0) return Status::Ok();
  const bool want_uv = attributes & kAttributeUv, want_color = attributes & kAttributeColor;
  const std::vector<uint32_t> charts = want_uv ? uv_charts(source) : std::vector<uint32_t>{};
  const SourceAttributesView src{source.positions.data(),
                                 source.triangles.data(),
                                 want_uv ? source.uvs.data() : nullptr,
                                 want_uv ? source.uv_triangles.data() : nullptr,
                                 want_uv ? charts.data() : nullptr,
                                 want_color ? source.colors.data() : nullptr};
  const size_t n = out.positions.size();
  out.source_triangles.resize(n);
  out.source_barycentrics.resize(n);
  if (want_color) out.colors.resize(n);
  if (want_uv) out.uvs.resize(n);
  HostBackend backend;
  backend.parallel_for(
      n,
      VertexAttributePass{tree, src, out.positions.data(), out.source_triangles.data(), out.source_barycentrics.data(),
                          want_color ? out.colors.data() : nullptr, want_uv ? out.uvs.data() : nullptr},
      256);
  if (want_uv) split_seams(backend, tree, src, out);
  if (!(attributes & kAttributeSource)) {
    out.source_triangles = {};
    out.source_barycentrics = {};
  }
  return Status::Ok();
}

}  // namespace gwnrt
