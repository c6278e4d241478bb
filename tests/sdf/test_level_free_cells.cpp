// The level-free cells (sdf/level_free_cells.h) against exact w: no level of φ = w mod 1 at the
// cells' phase lies in a free cell. The free cells beside those that are not are checked, each
// sampled on a lattice of 5³ points (its
// corners and faces included) by w by crossings (exact up to float round-off); between lattice
// neighbours φ is continued by the nearest lift, and a level crossed between them by more than
// round-off is a level in the cell.

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "gwnrt/field/crossing_winding.h"
#include "gwnrt/model/model.h"
#include "gwnrt/trace/surface_trace.h"
#include "test_util.h"

namespace gwnrt {
namespace {

// Beyond the crossing method's float round-off of w (1e-5 in the tests of field/), a level
// crossed by both neighbours' values.
constexpr double kLevelMargin = 2e-5;

struct CellCheck {
  size_t free = 0, checked = 0, levels_found = 0;
  std::string first;
};

CellCheck check_free_cells(const GwnModel& model, size_t max_cells, uint32_t seed) {
  const ModelView view = model.view();
  const LevelFreeCells& c = view.level_free;
  CellCheck out;
  // The free cells beside a cell that is not: where a bound too loose would show first.
  const std::vector<uint8_t>& flags = model.level_free_cells().free;
  const auto is_free = [&](int64_t x, int64_t y, int64_t z) {
    if (x < 0 || y < 0 || z < 0 || x >= c.dims[0] || y >= c.dims[1] || z >= c.dims[2]) return true;
    return flags[size_t(x + int64_t(c.dims[0]) * (y + int64_t(c.dims[1]) * z))] != 0;
  };
  std::vector<uint32_t> free;
  for (uint32_t i = 0; i < flags.size(); ++i) {
    if (!flags[i]) continue;
    ++out.free;
    const int64_t x = i % c.dims[0], y = i / c.dims[0] % c.dims[1], z = i / (c.dims[0] * c.dims[1]);
    if (!is_free(x - 1, y, z) || !is_free(x + 1, y, z) || !is_free(x, y - 1, z) || !is_free(x, y + 1, z) ||
        !is_free(x, y, z - 1) || !is_free(x, y, z + 1))
      free.push_back(i);
  }
  test::Random random(seed);
  constexpr int n = 5;
  for (size_t k = 0; k < std::min(max_cells, free.size()); ++k) {
    const uint32_t i = free[size_t(random.index(int(free.size())))];
    const uint32_t index[3] = {i % c.dims[0], i / c.dims[0] % c.dims[1], i / (c.dims[0] * c.dims[1])};
    double phi[n][n][n];
    for (int z = 0; z < n; ++z)
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
          const int l[3] = {x, y, z};
          vec3 p;
          for (int a = 0; a < 3; ++a) p[a] = c.box.lo[a] + (float(index[a]) + float(l[a]) / float(n - 1)) * c.cell;
          const double w = winding_number_crossing<false, false>(view, p).w;
          phi[z][y][x] = w - std::floor(w);
        }
    ++out.checked;
    // Every lattice edge: the level phase + m crossed between its ends by the nearest lift.
    for (int z = 0; z < n; ++z)
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
          for (int a = 0; a < 3; ++a) {
            const int q[3] = {x + (a == 0), y + (a == 1), z + (a == 2)};
            if (q[0] >= n || q[1] >= n || q[2] >= n) continue;
            const double from = phi[z][y][x];
            double d = phi[q[2]][q[1]][q[0]] - from;
            d -= std::floor(d + 0.5);
            const double to = from + d;
            const double level = double(c.phase) + std::floor(std::max(from, to) - double(c.phase));
            if (std::min(from, to) < level - kLevelMargin && std::max(from, to) > level + kLevelMargin) {
              if (out.levels_found++ == 0)
                out.first = "cell " + std::to_string(i) + ": φ from " + std::to_string(from) + " to " +
                            std::to_string(to) + " across " + std::to_string(level);
            }
          }
  }
  return out;
}

struct Case {
  const char* name;
  float level;
};

class LevelFreeCellsProof : public ::testing::TestWithParam<Case> {};

TEST_P(LevelFreeCellsProof, NoLevelInAFreeCell) {
  const Case p = GetParam();
  const std::string name = p.name;
  Mesh mesh = name == "open_hemisphere" ? test::make_hemisphere(12, 200) : test::load_test_mesh(name);
  BuildOptions options;
  options.sheet_level = p.level;
  GwnModel model;
  ASSERT_TRUE(GwnModel::build(std::move(mesh), model, options).ok());
  EXPECT_FALSE(model.built_parts() & kPartLevelFreeCells);  // not without being asked
  ASSERT_TRUE(model.prepare(kPartLevelFreeCells).ok());
  ASSERT_TRUE(model.view().parts & kPartLevelFreeCells);
  EXPECT_EQ(model.view().level_free.phase, p.level - std::floor(p.level));
  const CellCheck c = check_free_cells(model, test::kAddressSanitizer ? 40 : 300, 11);
  std::printf("[ %s level %.2f ] %zu of %zu cells free, %zu checked\n", p.name, p.level, c.free,
              model.level_free_cells().free.size(), c.checked);
  EXPECT_GT(c.free, model.level_free_cells().free.size() / 2);  // the cells are worth their build
  EXPECT_LT(c.free, model.level_free_cells().free.size());      // S's smooth pieces lie in some
  EXPECT_GT(c.checked, 0u);
  EXPECT_EQ(c.levels_found, 0u) << c.first;
}

INSTANTIATE_TEST_SUITE_P(Meshes, LevelFreeCellsProof,
                         ::testing::Values(Case{"bunny_holes.obj", 0.5f}, Case{"teapot.obj", 0.5f},
                                           Case{"teapot.obj", 0.3f}, Case{"open_hemisphere", 0.5f},
                                           Case{"realworld/birdBath_ggg_photogrammetry.obj", 0.5f}),
                         [](const auto& info) {
                           std::string n = info.param.name;
                           n = n.substr(n.rfind('/') + 1);
                           n = n.substr(0, n.find('.'));
                           return n + "_level" + std::to_string(int(std::lround(info.param.level * 100)));
                         });

// A closed mesh has no levels off M: no cells, and the tracer takes none.
TEST(LevelFreeCells, ClosedMeshHasNone) {
  GwnModel model = test::build_model(test::load_test_mesh("bunny.obj"));
  ASSERT_TRUE(model.prepare(kPartLevelFreeCells).ok());
  EXPECT_EQ(model.view().level_free.free, nullptr);
}

// The tracer takes the cells: far fewer Harnack steps through the empty space around an open
// mesh (the hits are held to the dense reference with and without them in trace/).
TEST(LevelFreeCells, TheTracerStepsAcrossThem) {
  const GwnModel model = test::build_model(test::load_test_mesh("teapot.obj"));
  ASSERT_TRUE(model.prepare(kPartLevelFreeCells).ok());
  ModelView with = model.view(), without = with;
  without.level_free = {};
  test::Random random(5);
  const Aabb box = model.bounds();
  uint64_t steps_with = 0, steps_without = 0;
  for (int k = 0; k < 500; ++k) {
    Ray ray;
    ray.origin = box.centre() + 2.0f * glm::length(box.hi - box.lo) * random.unit();
    ray.direction = random.in_box(box) - ray.origin;
    steps_with += trace_surface(with, ray, TraceOptions{}).steps;
    steps_without += trace_surface(without, ray, TraceOptions{}).steps;
  }
  std::printf("[ teapot ] Harnack steps of 500 rays: %llu without the cells, %llu with\n",
              (unsigned long long)steps_without, (unsigned long long)steps_with);
  EXPECT_LT(steps_with, steps_without * 3 / 4);
}

}  // namespace
}  // namespace gwnrt
