// The tracer's walk through level-free cells (trace/level_free_cells.h): the run it returns
// against stepping along the ray in small increments and reading each point's cell.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "gwnrt/trace/level_free_cells.h"
#include "test_util.h"

namespace gwnrt {
namespace {

struct SyntheticCells {
  LevelFreeCells cells;
  std::vector<uint8_t> free;
};

// A 5 × 4 × 3 grid of cells of side 0.5 from (-1, 0, 2), each free with probability 3/4.
SyntheticCells synthetic_cells(test::Random& random) {
  SyntheticCells s;
  s.cells.box.lo = vec3(-1.0f, 0.0f, 2.0f);
  s.cells.cell = 0.5f;
  s.cells.dims[0] = 5;
  s.cells.dims[1] = 4;
  s.cells.dims[2] = 3;
  s.cells.box.hi = s.cells.box.lo + 0.5f * vec3(5.0f, 4.0f, 3.0f);
  s.cells.phase = 0.5f;
  s.free.resize(5 * 4 * 3);
  for (uint8_t& f : s.free) f = random.uniform(0.0f, 1.0f) < 0.75f ? 1 : 0;
  s.cells.free = s.free.data();
  return s;
}

// Whether the point lies in a free cell (outside the grid: not).
bool in_free_cell(const LevelFreeCells& c, const dvec3& x) {
  int index[3];
  for (int a = 0; a < 3; ++a) {
    const double u = (x[a] - double(c.box.lo[a])) / double(c.cell);
    if (!(u >= 0.0 && u < double(c.dims[a]))) return false;
    index[a] = int(std::floor(u));
  }
  return c.free[uint32_t(index[0]) + c.dims[0] * (uint32_t(index[1]) + c.dims[1] * uint32_t(index[2]))] != 0;
}

TEST(LevelFreeCells, RunEndsWhereSteppingLeavesTheFreeCells) {
  test::Random random(7);
  const SyntheticCells s = synthetic_cells(random);
  const double step = 1e-4;
  int nonzero = 0;
  for (int k = 0; k < 2000; ++k) {
    const vec3 x(random.uniform(-1.2f, 1.7f), random.uniform(-0.2f, 2.2f), random.uniform(1.8f, 3.7f));
    vec3 dir = random.unit();
    if (k % 5 == 0) {  // along an axis too
      dir = vec3(0.0f);
      dir[k % 3] = k % 2 ? 1.0f : -1.0f;
    }
    const float run = level_free_run(s.cells, x, dir);
    // Stepping from x until the first point outside a free cell.
    double s_exit = 0.0;
    while (in_free_cell(s.cells, dvec3(x) + s_exit * dvec3(dir)) && s_exit < 10.0) s_exit += step;
    const double expected = s_exit > 0.0 ? s_exit - step : 0.0;  // the last point still in a free cell
    EXPECT_NEAR(run, expected, 2 * step) << "ray " << k;
    nonzero += run > 0.0f;
  }
  EXPECT_GT(nonzero, 500);  // most starts lie in free cells: the runs were exercised
}

TEST(LevelFreeCells, AppliesOnlyToItsPhase) {
  test::Random random(8);
  const SyntheticCells s = synthetic_cells(random);
  EXPECT_TRUE(level_free_cells_apply(s.cells, 0.5f));
  EXPECT_FALSE(level_free_cells_apply(s.cells, 0.25f));
  EXPECT_FALSE(level_free_cells_apply(LevelFreeCells{}, 0.5f));
}

}  // namespace
}  // namespace gwnrt
