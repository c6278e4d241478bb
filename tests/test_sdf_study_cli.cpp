// The accuracy study (examples/sdf_study) as the check that the Harnack lower bound never
// exceeds the distance to S on the study's points: the program computes an independent
// reference (exact sheet distances; points of the smooth pieces confirmed by exact sums) and
// exits with status 3 if ρ lies above it anywhere. Small runs here (a few thousand points, a
// few seconds each); the README's tables come from the default sizes.
#include <string>

#include <gtest/gtest.h>

#include "cli_util.h"
#include "test_util.h"

namespace gwnrt {
namespace {

class SdfStudyCli : public ::testing::TestWithParam<const char*> {
 protected:
  void SetUp() override {
    binary_ = test::example_binary("gwnrt-sdf-study");
    if (binary_.empty()) GTEST_SKIP() << "gwnrt-sdf-study not built next to the tests";
  }
  std::string binary_;
};

TEST_P(SdfStudyCli, HarnackBoundNeverExceedsTheReference) {
  const test::RunResult r = test::run_program(
      binary_, test::quote(test::data_path(GetParam())) + " --points 3000 --cloud 8000 --threads 2 --seed 7");
  ASSERT_TRUE(r.exited) << r.err;
  EXPECT_EQ(r.exit_code, 0) << r.err << "\n" << r.out;
  // The table is there, with all three bands, and the reference says what it is.
  for (const char* band : {"< 1%", "< 5%", "< 20%"}) EXPECT_NE(r.out.find(band), std::string::npos) << band;
  EXPECT_NE(r.out.find("Harnack lower bound"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("sdf2"), std::string::npos) << r.out;
}

INSTANTIATE_TEST_SUITE_P(Meshes, SdfStudyCli, ::testing::Values("bunny_holes.obj", "teapot.obj"));

}  // namespace
}  // namespace gwnrt
