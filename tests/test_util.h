// Shared helpers for the tests: bundled meshes, analytic shapes and point sets. The independent
// references the tests compare against are in reference/ at the top.
#pragma once

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "gwnrt/geometry/mesh.h"
#include "gwnrt/io/mesh_io.h"
#include "gwnrt/model/model.h"
#include "gwnrt/query/batch.h"
#include "reference/point_mix.h"

namespace gwnrt::test {

// The bundled meshes, scenes and probe points (data/ at the top of the repository).
inline std::string data_path(const std::string& name) { return std::string(GWNRT_DATA_DIR) + "/" + name; }

// A whole file as bytes (empty when it cannot be read).
inline std::string read_bytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

inline constexpr double kInf = std::numeric_limits<double>::infinity();

// What the exact methods by crossings promise (README): |Δw| <= kCrossingTolerance wherever x is
// farther than kCrossingNearMesh of the box diagonal from M (nearer, the side of M that x is on
// is a matter of float round-off).
inline constexpr double kCrossingTolerance = 1e-5;
inline constexpr double kCrossingNearMesh = 1e-5;

inline bool all_finite(const vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

inline Mesh load_test_mesh(const std::string& name) {
  Mesh mesh;
  const Status s = load_mesh(data_path(name), mesh);
  EXPECT_TRUE(s.ok()) << s.message();
  return mesh;
}

inline GwnModel build_model(Mesh mesh) {
  GwnModel model;
  const Status s = GwnModel::build(std::move(mesh), model);
  EXPECT_TRUE(s.ok()) << s.message();
  return model;
}

// Clang names the sanitizers by __has_feature, GCC by __SANITIZE_ADDRESS__ and __SANITIZE_THREAD__.
#if defined(__has_feature)
#define GWNRT_TEST_HAS_FEATURE(name) __has_feature(name)
#else
#define GWNRT_TEST_HAS_FEATURE(name) 0
#endif

// Under AddressSanitizer (CI's sanitize job) the tests that need size to show a cost's growth
// run smaller: there they look for memory errors, and the Release suite for the growth.
#if defined(__SANITIZE_ADDRESS__) || GWNRT_TEST_HAS_FEATURE(address_sanitizer)
inline constexpr bool kAddressSanitizer = true;
#else
inline constexpr bool kAddressSanitizer = false;
#endif

// ThreadSanitizer runs the plugin tests' single-threaded ray loops ten times slower and more:
// there they look for races, which a quarter of the rays meets as well.
#if defined(__SANITIZE_THREAD__) || GWNRT_TEST_HAS_FEATURE(thread_sanitizer)
inline constexpr bool kThreadSanitizer = true;
#else
inline constexpr bool kThreadSanitizer = false;
#endif
// A side of a ray lattice (n² rays): half as many per side under ThreadSanitizer.
inline int lattice_side(int n) { return kThreadSanitizer ? (n + 1) / 2 : n; }

// Float random numbers for rays and points (a fixed seed: the tests are reproducible).
class Random {
 public:
  explicit Random(uint32_t seed) : g_(seed) {}
  float uniform(float a, float b) { return std::uniform_real_distribution<float>(a, b)(g_); }
  int index(int n) { return std::uniform_int_distribution<int>(0, n - 1)(g_); }
  vec3 in_box(const Aabb& b) { return {uniform(b.lo.x, b.hi.x), uniform(b.lo.y, b.hi.y), uniform(b.lo.z, b.hi.z)}; }
  vec3 unit() {
    for (;;) {
      const vec3 v(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
      const float l = glm::length(v);
      if (l > 0.1f && l <= 1.0f) return v / l;
    }
  }
  // A direction length between 1e-2 and 1e2: t is in units of it, whatever it is.
  float scale() { return std::pow(10.0f, uniform(-2.0f, 2.0f)); }

 private:
  std::mt19937 g_;
};

// Hexagon fan, slightly curved: centre raised by 0.15 above the unit rim, normals up.
inline Mesh make_hexagon_fan() {
  Mesh m;
  m.positions.push_back({0.0f, 0.0f, 0.15f});
  for (int k = 0; k < 6; ++k) {
    const double a = 2.0 * kPi * k / 6.0;
    m.positions.push_back({float(std::cos(a)), float(std::sin(a)), 0.0f});
  }
  for (uint32_t k = 0; k < 6; ++k) m.triangles.push_back({0u, 1 + k, 1 + (k + 1) % 6});
  return m;
}

// Unit sphere by subdividing an icosahedron `levels` times, outward-oriented, vertices on the sphere.
inline Mesh make_sphere(int levels, float radius = 1.0f) {
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  Mesh m;
  m.positions = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                 {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  m.triangles = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (auto& p : m.positions) p = glm::normalize(p);
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      m.positions.push_back(glm::normalize(m.positions[a] + m.positions[b]));
      return mid[key] = uint32_t(m.positions.size() - 1);
    };
    std::vector<uvec3> next;
    for (const uvec3& tri : m.triangles) {
      const uint32_t a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
      next.insert(next.end(), {{tri[0], a, c}, {tri[1], b, a}, {tri[2], c, b}, {a, b, c}});
    }
    m.triangles = std::move(next);
  }
  for (auto& p : m.positions) p *= radius;
  return m;
}

// The upper half (z >= 0) of the unit sphere, outward normals: a fan around the pole (0,0,1) and
// `rings` - 1 bands of quads down to the rim, a regular `segments`-gon at exactly z = 0 (so the
// mirror image of the cap closes it: sdf/sdf_fixtures.h's HemisphereReference). All vertices lie on the sphere.
inline Mesh make_hemisphere(int rings, int segments) {
  Mesh m;
  m.positions.push_back({0.0f, 0.0f, 1.0f});
  for (int i = 1; i <= rings; ++i) {
    const double theta = 0.5 * kPi * i / rings;
    const double r = i == rings ? 1.0 : std::sin(theta), z = i == rings ? 0.0 : std::cos(theta);
    for (int j = 0; j < segments; ++j) {
      const double phi = 2.0 * kPi * j / segments;
      m.positions.push_back({float(r * std::cos(phi)), float(r * std::sin(phi)), float(z)});
    }
  }
  auto ring = [&](int i, int j) { return uint32_t(1 + (i - 1) * segments + (j % segments)); };
  for (int j = 0; j < segments; ++j) m.triangles.push_back({0u, ring(1, j), ring(1, j + 1)});
  for (int i = 1; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      m.triangles.push_back({ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
      m.triangles.push_back({ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
    }
  return m;
}

// Axis-aligned cube [-1, 1]³, outward-oriented; `open_top` drops the two z = +1 triangles.
inline Mesh make_cube(bool open_top = false) {
  Mesh m;
  m.positions = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1}, {-1, -1, 1}, {1, -1, 1}, {1, 1, 1}, {-1, 1, 1}};
  m.triangles = {{0, 2, 1}, {0, 3, 2}, {0, 1, 5}, {0, 5, 4}, {1, 2, 6},
                 {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  if (!open_top) m.triangles.insert(m.triangles.end(), {{4, 5, 6}, {4, 6, 7}});
  return m;
}

// A regular n-gon of `radius` about `centre` in the plane spanned by the orthonormal u and v
// (z = 0 by default), fanned from vertex 0 as the mesh readers fan a polygon face: n - 2 long thin
// triangles that all meet at vertex 0, normals along u × v. With `star` != 1 every other vertex
// is at star · radius: a non-convex star, whose fan has triangles of both orientations overlapping
// (the polygon's inside is covered once net). Corners computed in double, rounded once to float.
inline Mesh make_fanned_polygon(int n, double radius = 0.5, dvec3 centre = {0.5, 0.5, 0.0}, double star = 1.0,
                                dvec3 u = {1, 0, 0}, dvec3 v = {0, 1, 0}) {
  Mesh m;
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * kPi * i / n, r = (i % 2 == 1 ? star : 1.0) * radius;
    m.positions.push_back(vec3(centre + r * std::cos(a) * u + r * std::sin(a) * v));
  }
  for (uint32_t i = 1; i + 1 < uint32_t(n); ++i) m.triangles.push_back({0u, i, i + 1});
  return m;
}

// An open cone: n triangles around the apex (0.5, 0.5, height) over a circle of radius 0.5 in
// z = 0, vertices 0 .. n-1 (not flat, so no plane leaves its clusters out: every one holds the
// apex and reaches across).
inline Mesh make_open_cone(int n, float height = 0.6f) {
  Mesh m = make_fanned_polygon(n);
  m.triangles.clear();
  const uint32_t apex = uint32_t(m.positions.size());
  m.positions.push_back({0.5f, 0.5f, height});
  for (uint32_t i = 0; i < uint32_t(n); ++i) m.triangles.push_back({apex, i, (i + 1) % uint32_t(n)});
  return m;
}

inline Aabb mesh_bounds(const Mesh& m) {
  Aabb box;
  for (const vec3& p : m.positions) box.extend(p);
  return box;
}

// The benchmark's point mix (reference/point_mix.h).
inline std::vector<vec3> sample_points(const Aabb& box, size_t count, uint32_t seed) {
  return point_mix(box, count, seed);
}

// Every column of a PointColumns, each of `rows` rows with its bytes set to `fill`: for tests that
// compare whole columns. `row_bytes` and `bytes` are in for_each_point_column's order.
struct AllPointColumns {
  PointColumns columns;
  std::vector<size_t> row_bytes;
  std::vector<std::vector<unsigned char>> bytes;

  AllPointColumns(size_t rows, unsigned char fill) {
    for_each_point_column(columns, [&](auto*& column, size_t values) {
      using T = std::remove_reference_t<decltype(*column)>;
      row_bytes.push_back(values * sizeof(T));
      bytes.emplace_back(rows * row_bytes.back(), fill);
      column = reinterpret_cast<T*>(bytes.back().data());  // vector storage: aligned for any T
    });
  }
  AllPointColumns(const AllPointColumns&) = delete;
  AllPointColumns& operator=(const AllPointColumns&) = delete;
};

}  // namespace gwnrt::test
