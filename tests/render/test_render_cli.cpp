// gwnrt-render run as a subprocess: the bundled scene, a mesh's default scene and the first-hit
// integrator produce images of the asked size; bad input ends in a message and exit code 1.
#include <OpenImageIO/imageio.h>

#include <string>

#include "../cli_util.h"
#include "../test_util.h"

namespace gwnrt {
namespace {

class RenderCli : public ::testing::Test {
 protected:
  void SetUp() override {
    binary_ = test::example_binary("gwnrt-render");
    if (binary_.empty())
      GTEST_SKIP() << "gwnrt-render not built next to the tests (expected <tests>/../examples/gwnrt-render)";
  }
  // Runs with `args`, writing to a temporary image; checks it exists with the given size.
  void expect_image(const std::string& args, const std::string& extension, int width, int height) {
    const std::string out = test::temp_path("render" + extension);
    const test::RunResult r = test::run_program(binary_, args + " -o " + test::quote(out));
    ASSERT_TRUE(r.exited);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    auto in = OIIO::ImageInput::open(out);
    ASSERT_TRUE(in) << "no image at " << out;
    EXPECT_EQ(in->spec().width, width);
    EXPECT_EQ(in->spec().height, height);
    in->close();
    std::remove(out.c_str());
  }
  std::string binary_;
};

const std::string kScene = test::data_path("bunny_scene.json");

TEST_F(RenderCli, BundledSceneRenders) {
  expect_image(test::quote(kScene) + " --spp 1 --width 40 --height 24", ".png", 40, 24);
}

// Glass (a GWN object), rough metal, an emissive quad, a sun: every material and light kind.
TEST_F(RenderCli, MaterialsSceneRenders) {
  expect_image(test::quote(test::data_path("materials_scene.json")) + " --spp 2 --width 32 --height 18", ".exr", 32,
               18);
}

TEST_F(RenderCli, MeshGetsTheDefaultSceneWithAovs) {
  const std::string out = test::temp_path("aovs.exr");
  const test::RunResult r =
      test::run_program(binary_, test::quote(test::data_path("bunny_holes.obj")) +
                                     " --spp 1 --width 16 --height 12 --aovs -o " + test::quote(out));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto in = OIIO::ImageInput::open(out);
  ASSERT_TRUE(in);
  EXPECT_EQ(in->spec().nchannels, 10);  // R G B, albedo.R/G/B, N.X/Y/Z, Z
  in->close();
  std::remove(out.c_str());
}

TEST_F(RenderCli, FirstHitIntegratorRenders) {
  expect_image(test::quote(test::data_path("bunny_holes.obj")) + " --integrator first-hit --width 24 --height 16",
               ".png", 24, 16);
}

TEST_F(RenderCli, BadInputIsRefusedWithAMessage) {
  const std::string bad = test::temp_path("bad.json");
  {
    std::ofstream f(bad);
    f << R"({"materials": {"m": {"type": "diffuse", "albedo": [2, 0, 0]}}})";
  }
  for (const std::string& args : {test::quote(bad), std::string("/nonexistent/mesh.obj"),
                                  test::quote(kScene) + " --aovs -o x.png", test::quote(kScene) + " -o out.bmp"}) {
    SCOPED_TRACE(args);
    const test::RunResult r = test::run_program(binary_, args + " --spp 1 --width 8 --height 8");
    ASSERT_TRUE(r.exited);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("gwnrt-render: "), std::string::npos) << r.err;
  }
  std::remove(bad.c_str());
}

// Issue 15 item 15: --spp 0, --max-depth 0 and a negative --seed are refused (they used to mean
// "the scene's value", like leaving the option out, while --spp -1 was refused).
TEST_F(RenderCli, ZeroOrNegativeCountsAreRefused) {
  for (const std::string args : {" --spp 0", " --spp -1", " --max-depth 0", " --seed -5"}) {
    SCOPED_TRACE(args);
    const test::RunResult r = test::run_program(
        binary_, test::quote(kScene) + " --width 8 --height 8 -o " + test::quote(test::temp_path("z.png")) + args);
    ASSERT_TRUE(r.exited);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("must be"), std::string::npos) << r.err;
  }
}

}  // namespace
}  // namespace gwnrt
