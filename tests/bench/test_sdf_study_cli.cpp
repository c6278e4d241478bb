// The accuracy study (bench/sdf_study.cpp) as the check that the Harnack lower bound never
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
    binary_ = test::program_binary("gwnrt-sdf-study");
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

// --smooth-share nan was accepted (CLI11's Range lets nan through), and a
// positive count of 0 answered with a 300-digit range.
TEST(SdfStudyCliArguments, OutOfRangeValuesAreRefusedPlainly) {
  const std::string binary = test::program_binary("gwnrt-sdf-study");
  if (binary.empty()) GTEST_SKIP() << "gwnrt-sdf-study not built next to the tests";
  for (const std::string args : {" --smooth-share nan", " --smooth-share 1.5", " --points 0", " --beta nan"}) {
    const test::RunResult r = test::run_program(binary, test::quote(test::data_path("bunny_holes.obj")) + args);
    ASSERT_TRUE(r.exited) << args;
    EXPECT_NE(r.exit_code, 0) << args;
    EXPECT_NE(r.err.find("must be"), std::string::npos) << args << ": " << r.err;
    EXPECT_EQ(r.err.find("17976931"), std::string::npos) << args << ": " << r.err;
  }
}

}  // namespace
}  // namespace gwnrt
