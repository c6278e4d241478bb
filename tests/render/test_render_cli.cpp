// gwnrt-render run as a subprocess: the bundled scene, a mesh's default scene and the first-hit
// integrator produce images of the asked size; bad input ends in a message and exit code 1.
#include <OpenImageIO/imageio.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "cli_util.h"
#include "gwnrt/base/memory.h"
#include "mesh_files.h"
#include "test_util.h"

namespace gwnrt {
namespace {

class RenderCli : public ::testing::Test {
 protected:
  void SetUp() override {
    binary_ = test::program_binary("gwnrt-render");
    if (binary_.empty()) GTEST_SKIP() << "gwnrt-render not built next to the tests (expected <build>/bin/gwnrt-render)";
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

// --frames renders N times and prints the rate; --device cuda renders on the GPU
// or fails saying why; --frames 0 is refused.
TEST_F(RenderCli, FirstHitFramesAndDevice) {
  const std::string base = test::quote(test::data_path("bunny_holes.obj")) +
                           " --integrator first-hit --width 32 --height 24 -o " + test::quote(test::temp_path("f.png"));
  const test::RunResult frames = test::run_program(binary_, base + " --frames 3");
  ASSERT_TRUE(frames.exited);
  ASSERT_EQ(frames.exit_code, 0) << frames.err;
  EXPECT_NE(frames.out.find("3 frames, "), std::string::npos) << frames.out;
  EXPECT_NE(frames.out.find(" frames/s ("), std::string::npos) << frames.out;
  const test::RunResult cuda = test::run_program(binary_, base + " --device cuda --frames 2");
  ASSERT_TRUE(cuda.exited);
  if (cuda.exit_code != 0) {
    EXPECT_EQ(cuda.exit_code, 1);
    EXPECT_NE(cuda.err.find("--device cuda: "), std::string::npos) << cuda.err;
  } else {
    EXPECT_NE(cuda.out.find("on the GPU"), std::string::npos) << cuda.out;
  }
  for (const char* bad : {" --frames 0", " --frames -2", " --device gpu"}) {
    const test::RunResult r = test::run_program(binary_, base + bad);
    ASSERT_TRUE(r.exited);
    EXPECT_EQ(r.exit_code, 1) << bad;
  }
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

// --spp 0, --max-depth 0 and a negative --seed are refused (they used to mean
// "the scene's value", like leaving the option out, while --spp -1 was refused).
TEST_F(RenderCli, ZeroOrNegativeCountsAreRefused) {
  // And, as in a scene file, counts past their range (2^20 samples per pixel ran for days).
  for (const std::string args : {" --spp 0", " --spp -1", " --max-depth 0", " --seed -5", " --spp 1048577",
                                 " --spp 2000000000", " --max-depth 1001", " --seed 1073741825"}) {
    SCOPED_TRACE(args);
    const test::RunResult r = test::run_program(
        binary_, test::quote(kScene) + " --width 8 --height 8 -o " + test::quote(test::temp_path("z.png")) + args);
    ASSERT_TRUE(r.exited);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("must lie in ["), std::string::npos) << r.err;
  }
}

TEST_F(RenderCli, FirstHitOptionsAreRefusedForThePathTracer) {
  // `--level 1e39` and `--eps 0` exited 0 with the path tracer, which ignored them.
  // Values the first hit would take are refused as its options; values it would not (those two)
  // are refused by their flags' checks first, for either integrator (LimitsCli in
  // test_fuzz_inputs.cpp).
  for (const std::string args : {" --level 1e30", " --eps 1e-3", " --level 0.3", " --mode solid-angle", " --beta 3",
                                 " --max-steps 10", " --device cpu", " --frames 2"}) {
    SCOPED_TRACE(args);
    const test::RunResult r = test::run_program(
        binary_, test::quote(kScene) + " --width 8 --height 8 -o " + test::quote(test::temp_path("p.png")) + args);
    ASSERT_TRUE(r.exited);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("is an option of --integrator first-hit"), std::string::npos) << r.err;
  }
}

// Writes `text` to a new temporary file named after `name`; returns its path.
std::string write_temp(const std::string& name, const std::string& text) {
  const std::string path = test::temp_path(name);
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

// Runs gwnrt-render on `args` (a tiny image, one sample) expecting a refusal: exit status 1, not a
// signal, and a message naming `words`.
void expect_refusal(const std::string& binary, const std::string& args, const std::string& words) {
  SCOPED_TRACE(args);
  const test::RunResult r = test::run_program(binary, args + " --spp 1 --width 8 --height 6");
  ASSERT_TRUE(r.exited) << "killed by a signal: " << r.err;
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("gwnrt-render: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(words), std::string::npos) << r.err;
}

// Scenes whose rays used to abort inside Embree (its ray.valid() assertion)
// end in a message naming the JSON location (scene_checks covers each class in-process).
TEST_F(RenderCli, DegenerateScenesExitWithAMessage) {
  const std::string bunny = test::data_path("bunny_holes.obj");
  const std::string out = " -o " + test::quote(test::temp_path("degenerate.png"));
  for (const auto& [scene, where] : {
           std::pair{std::string(R"({"camera": {"eye": [0, 0, 5], "up": [0, 0, 0]}})"), "/camera/up"},
           std::pair{std::string(R"({"camera": {"eye": [0, 5, 0], "up": [0, 1, 0]}})"), "/camera/up"},
           std::pair{std::string(R"({"camera": {"eye": [0, 1e37, 5]}})"), "/camera/eye"},
           std::pair{std::string(R"({"meshes": [{"plane": 3e38}]})"), "/meshes/0"},
           std::pair{std::string(R"({"gwn_objects": [{"file": ")") + bunny +
                         R"(", "instances": [{"matrix": [0,0,0,0, 0,0,0,0, 0,0,0,0, 0,0,0,1]}]}]})",
                     "/gwn_objects/0/instances/0"},
           std::pair{std::string(R"({"gwn_objects": [{"file": ")") + bunny + R"(", "instances": [{"scale": 1e30}]}]})",
                     "/gwn_objects/0/instances/0"},
       }) {
    const std::string path = write_temp("degenerate.json", scene);
    expect_refusal(binary_, test::quote(path) + out, path + ": " + where + ": ");
    std::remove(path.c_str());
  }
  // The default scene of a mesh 1e-30 across: its framing used to underflow to a NaN camera.
  const std::string tiny = write_temp("tiny.obj",
                                      "v 0 0 0\nv 1e-30 0 0\nv 0 1e-30 0\nv 0 0 1e-30\n"
                                      "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  expect_refusal(binary_, test::quote(tiny) + out, tiny + ": the default scene for a mesh 1e-30 across");
  std::remove(tiny.c_str());
}

// A number beyond double's range and a scene path that is a directory used to
// throw through main (std::terminate); now errors naming the file (and the line).
TEST_F(RenderCli, UnreadableScenesExitWithAMessage) {
  const std::string out = " -o " + test::quote(test::temp_path("unreadable.png"));
  const std::string big = write_temp("big.json", "{\n  \"camera\": {\"fov\": 1e400}\n}\n");
  expect_refusal(binary_, test::quote(big) + out, big + ": not valid JSON: at line 2");
  std::remove(big.c_str());
  const std::string dir = test::temp_path("dir.json");
  std::filesystem::create_directories(dir);
  expect_refusal(binary_, test::quote(dir) + out, dir + ": cannot read: it is a directory");
  std::filesystem::remove(dir);
}

// Sections of the wrong type and unknown keys used to be ignored (defaults
// rendered); now refused, naming the location.
TEST_F(RenderCli, WrongSectionsAndUnknownKeysAreRefused) {
  const std::string out = " -o " + test::quote(test::temp_path("sections.png"));
  for (const auto& [scene, where] :
       {std::pair{R"({"camera": 5})", "/camera: expected an object"},
        std::pair{R"({"render": []})", "/render: expected an object"},
        std::pair{R"({"environment": 5})", "/environment: expected an object"},
        std::pair{R"({"sun": 5})", "/sun: expected an object"},
        std::pair{R"({"sun": {"radiance": [1, 1, 1], "angle": 0.1}})", "/sun/angle: unknown key"}}) {
    const std::string path = write_temp("sections.json", scene);
    expect_refusal(binary_, test::quote(path) + out, path + ": " + where);
    std::remove(path.c_str());
  }
}

// A key given twice and a scene without geometry used to render (exit 0), the one
// with a value silently dropped, the other an empty sky; a GWN object whose level w never reaches
// rendered nothing of it without a word. Now two refusals naming the location, and a warning.
TEST_F(RenderCli, DuplicateKeysEmptyScenesAndUnreachableLevels) {
  const std::string out = " -o " + test::quote(test::temp_path("f9.png"));
  const std::string bunny = test::data_path("bunny_holes.obj");
  for (const auto& [scene, where] :
       {std::pair{std::string("{}"), std::string("/: the scene has nothing to render")},
        std::pair{R"({"camera": {"eye": [0, 1, 5]}, "gwn_objects": [{"file": ")" + bunny + R"("}], "camera": {}})",
                  std::string("/camera: duplicate key")}}) {
    const std::string path = write_temp("f9.json", scene);
    expect_refusal(binary_, test::quote(path) + out, path + ": " + where);
    std::remove(path.c_str());
  }
  const std::string path = write_temp("f9.json", R"({"gwn_objects": [{"file": ")" + bunny + R"(", "level": 1e30}]})");
  const test::RunResult r = test::run_program(binary_, test::quote(path) + out + " --spp 1 --width 8 --height 6");
  ASSERT_TRUE(r.exited) << r.err;
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("gwnrt-render: warning: " + path +
                       ": /gwn_objects/0/level: level 1e+30 lies outside every value w takes on this mesh (|w| < "
                       "3524/2): S is empty\n"),
            std::string::npos)
      << r.err;
  std::remove(path.c_str());
}

// An emission above 1.8e19 used to render black in PNG (the tone curve's
// v² overflowed to inf / inf), and 3e38 also overflowed the pixel's sum of samples. Now the
// largest radiance allowed (1e20) renders white, and 3e38 is refused.
TEST_F(RenderCli, BrightestEmissionRendersWhite) {
  // The camera looks straight down at an emissive plane that fills the view.
  const std::string scene = R"({"camera": {"eye": [0, 1, 0], "target": [0, 0, 0], "up": [0, 0, 1], "fov": 30},
      "materials": {"lamp": {"type": "emissive", "emission": [EMISSION]}}, "meshes": [{"plane": 10, "material": "lamp"}]})";
  auto with = [&](const std::string& emission) {
    std::string s = scene;
    s.replace(s.find("EMISSION"), 8, emission);
    return write_temp("bright.json", s);
  };
  const std::string bright = with("1e20, 1e20, 1e20");
  const std::string out = test::temp_path("bright.png");
  const test::RunResult r =
      test::run_program(binary_, test::quote(bright) + " --spp 2 --width 6 --height 4 -o " + test::quote(out));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto in = OIIO::ImageInput::open(out);
  ASSERT_TRUE(in);
  std::vector<unsigned char> pixels(6 * 4 * 3);
  ASSERT_TRUE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, pixels.data()));
  in->close();
  for (unsigned char p : pixels) EXPECT_EQ(p, 255);
  std::remove(out.c_str());
  std::remove(bright.c_str());
  const std::string over = with("3e38, 3e38, 3e38");
  expect_refusal(binary_, test::quote(over) + " -o " + test::quote(out), "/materials/lamp/emission/0: 3e+38 is above");
  std::remove(over.c_str());
}

// A 32768 x 32768 image used to end in std::bad_alloc (or the OOM killer) after
// the scene was built; now refused before anything is allocated, saying what it would need.
TEST_F(RenderCli, ImageBeyondMemoryIsRefusedUpFront) {
  // Per pixel: with AOVs to EXR, 10 float channels and their encoding, 80 bytes (80 GiB); for
  // first-hit, RGB (12), the per-pixel trace (16), its PNG (3 + 3), the 7-channel statistics
  // image (28) and its EXR encoding (28): 90. Machines with that much free memory would render
  // them: skipped there.
  const uint64_t pixels = uint64_t(32768) * 32768;
  if (available_memory_bytes() != kUnknownMemory && available_memory_bytes() >= 90 * pixels)
    GTEST_SKIP() << "this machine has memory for a 32768 x 32768 image";
  const std::string side = " --width 32768 --height 32768 --spp 1";
  for (const auto& [args, needed] :
       {std::pair{test::quote(kScene) + " --aovs -o " + test::quote(test::temp_path("huge.exr")) + side, "80.0 GiB"},
        std::pair{test::quote(test::data_path("bunny_holes.obj")) + " --integrator first-hit -o " +
                      test::quote(test::temp_path("huge.png")) + " --stats-image " +
                      test::quote(test::temp_path("s.exr")) + side,
                  "90.0 GiB"}}) {
    SCOPED_TRACE(args);
    const test::RunResult r = test::run_program(binary_, args);
    ASSERT_TRUE(r.exited) << r.err;
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("32768 x 32768"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(needed), std::string::npos) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;  // refused before loading or building anything
  }
}

// A write that fails (a full disk) used to print "wrote" and exit 0; an
// output that cannot be created (/proc/x.png) was found only after the render.
TEST_F(RenderCli, FailedWritesExitNonZero) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full here";
  const std::string bunny = test::quote(test::data_path("bunny_holes.obj"));
  const std::string png = test::temp_path("full.png"), exr = test::temp_path("full.exr");
  const std::string fine = test::temp_path("fine.png");
  std::filesystem::create_symlink("/dev/full", png);
  std::filesystem::create_symlink("/dev/full", exr);
  const std::string scene = test::quote(kScene) + " --width 8 --height 6 --spp 1";
  const std::string first_hit = bunny + " --integrator first-hit --width 8 --height 6";
  for (const auto& [args, failed] : {
           std::pair{scene + " -o " + test::quote(png), png},
           std::pair{scene + " -o " + test::quote(exr), exr},
           std::pair{first_hit + " -o " + test::quote(png), png},
           std::pair{first_hit + " -o " + test::quote(fine) + " --stats-image " + test::quote(exr), exr},
       }) {
    SCOPED_TRACE(args);
    const test::RunResult r = test::run_program(binary_, args);
    ASSERT_TRUE(r.exited) << r.err;
    EXPECT_EQ(r.exit_code, 1) << r.out;
    EXPECT_NE(r.err.find(failed + ": write failed: "), std::string::npos) << r.err;
    EXPECT_EQ(r.out.find("wrote " + failed), std::string::npos) << r.out;
  }
  EXPECT_TRUE(std::filesystem::is_symlink(png));  // the link itself left alone
  std::filesystem::remove(png);
  std::filesystem::remove(fine);
  std::filesystem::remove(exr);
  // Paths that cannot be created fail before the scene is read or built.
  const std::string dir_png = test::temp_path("a_directory.png");
  std::filesystem::create_directories(dir_png);
  for (const std::string& bad : {std::string("/proc/x.png"), dir_png}) {
    for (const std::string& args : {scene + " -o " + test::quote(bad), first_hit + " -o " + test::quote(bad)}) {
      SCOPED_TRACE(args);
      const test::RunResult r = test::run_program(binary_, args);
      ASSERT_TRUE(r.exited) << r.err;
      EXPECT_EQ(r.exit_code, 1);
      EXPECT_NE(r.err.find(bad + ": cannot be written: "), std::string::npos) << r.err;
      EXPECT_TRUE(r.out.empty()) << r.out;  // nothing loaded, built or rendered
    }
  }
  std::filesystem::remove(dir_png);
  // The up-front check leaves nothing behind when the job fails later.
  const std::string later = test::temp_path("never.png");
  const std::string bad_scene = write_temp("bad.json", R"({"camera": 5})");
  const test::RunResult r = test::run_program(binary_, test::quote(bad_scene) + " -o " + test::quote(later));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_FALSE(std::filesystem::exists(later));
  std::remove(bad_scene.c_str());
}

// What the mesh loader skipped (an OBJ line with an
// unknown statement) is said, as gwnrt-mesh says it, for meshes read by scene files, the default
// scene and the first-hit integrator.
TEST_F(RenderCli, MeshLoadWarningsArePrinted) {
  const std::string mesh = write_temp("odd.obj",
                                      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvv 1 1 1\n"
                                      "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  const std::string scene = write_temp("odd.json", R"({"gwn_objects": [{"file": ")" + mesh + R"("}]})");
  const std::string out = " -o " + test::quote(test::temp_path("odd.png")) + " --width 8 --height 6";
  for (const std::string& args : {test::quote(scene) + out + " --spp 1", test::quote(mesh) + out + " --spp 1",
                                  test::quote(mesh) + out + " --integrator first-hit"}) {
    SCOPED_TRACE(args);
    const test::RunResult r = test::run_program(binary_, args);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("gwnrt-render: " + mesh + ": warning: 1 line"), std::string::npos) << r.err;
  }
  std::remove(mesh.c_str());
  std::remove(scene.c_str());
}

// All channels of an image written by gwnrt-render, as floats, pixel by pixel.
std::vector<float> read_pixels(const std::string& path, int& channels) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) return {};
  channels = in->spec().nchannels;
  std::vector<float> pixels(size_t(in->spec().width) * size_t(in->spec().height) * size_t(channels));
  if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, pixels.data())) pixels.clear();
  in->close();
  return pixels;
}

// A georeferenced scan (bunny_holes moved to UTM metres; GwnModel::build refuses it where it lies)
// renders recentred, and as the bunny at the origin does: the camera frames the model's box and
// the image holds no positions. The two models differ by float rounding about the centre (1e-8
// of a 0.2 diagonal), far below the tracer's stopping distance, so the hit kinds agree on at least
// 99.9% of pixels (the CUDA image's criterion) and the shaded colours to 1e-3 (they depend on the
// normal, whose change over 1e-8 is below 1e-5).
TEST_F(RenderCli, FarOffScanRendersAsAtTheOrigin) {
  const std::string near_path = test::data_path("bunny_holes.obj"), far_path = test::temp_path("utm_render.obj");
  test::write_translated(near_path, far_path, test::kUtm, true);
  std::vector<float> colour[2], stats[2];
  int colour_channels = 0, stats_channels = 0;
  for (int k = 0; k < 2; ++k) {
    const std::string image = test::temp_path("utm_render.exr"), stats_image = test::temp_path("utm_stats.exr");
    const test::RunResult r = test::run_program(
        binary_, test::quote(k ? far_path : near_path) + " --integrator first-hit --width 64 --height 48 -o " +
                     test::quote(image) + " --stats-image " + test::quote(stats_image));
    ASSERT_TRUE(r.exited);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const bool said = r.err.find("far from the origin for its size: computed relative to (") != std::string::npos;
    EXPECT_EQ(said, k == 1) << r.err;
    EXPECT_EQ(r.err.find("written in double"), std::string::npos) << r.err;  // no positions are written
    colour[k] = read_pixels(image, colour_channels);
    stats[k] = read_pixels(stats_image, stats_channels);
    std::remove(image.c_str());
    std::remove(stats_image.c_str());
  }
  std::remove(far_path.c_str());
  ASSERT_EQ(stats_channels, 7);  // R G B steps crossings kind capped
  ASSERT_EQ(colour[0].size(), colour[1].size());
  ASSERT_EQ(stats[0].size(), stats[1].size());
  const size_t pixels = stats[0].size() / 7;
  ASSERT_EQ(pixels, size_t(64 * 48));
  size_t same_kind = 0, hits = 0;
  float worst = 0;
  for (size_t i = 0; i < pixels; ++i) {
    const bool same = stats[0][7 * i + 5] == stats[1][7 * i + 5];
    same_kind += same;
    hits += stats[0][7 * i + 5] != 0.0f;
    if (same)
      for (int c = 0; c < colour_channels; ++c)
        worst = std::max(
            worst, std::fabs(colour[0][size_t(colour_channels) * i + c] - colour[1][size_t(colour_channels) * i + c]));
  }
  EXPECT_GT(hits, pixels / 10);  // the bunny is in the picture
  EXPECT_GE(double(same_kind), 0.999 * double(pixels));
  EXPECT_LE(worst, 1e-3f);
}

// A scene file in georeferenced coordinates (bunny_scene without its rotations, camera, ground and
// both bunnies moved to UTM metres, where float steps by 0.25-0.5) is rendered about its own
// centre and gives the picture the scene gives at the origin: before, float's steps there showed
// as banding on ~20% of pixels. The two renders differ only by float rounding of where things
// lie (1e-7 of the scene), which may turn a sample's path at an edge: at most 0.2% of pixels may
// differ by more than 2 of 255 levels (measured at 240 x 135: 1 pixel, by 1 level).
TEST_F(RenderCli, SceneFarFromTheOriginRendersAsAtTheOrigin) {
  const std::string near_mesh = test::data_path("bunny_holes.obj"), far_mesh = test::temp_path("utm_scene.obj");
  test::write_translated(near_mesh, far_mesh, test::kUtm, true);
  const auto scene = [](const std::string& mesh, const double(&t)[3]) {
    const auto moved = [&](double x, double y, double z) {
      return "[" + test::num(x + t[0]) + ", " + test::num(y + t[1]) + ", " + test::num(z + t[2]) + "]";
    };
    return R"({"camera": {"eye": )" + moved(4, 7, 34) + R"(, "target": )" + moved(0, 4.5, 0) +
           R"(, "up": [0, 1, 0], "fov": 34},
  "render": {"spp": 4, "max_depth": 4, "seed": 7},
  "materials": {"clay": {"type": "diffuse", "albedo": [0.8, 0.62, 0.45]}, "ground": {"type": "diffuse"}},
  "meshes": [{"plane": 200, "material": "ground", "transform": {"translate": )" +
           moved(0, 0, 0) + R"(}},
             {"file": ")" +
           mesh + R"(", "material": "clay", "transform": {"translate": [6.5, 0, 0]}}],
  "gwn_objects": [{"file": ")" +
           mesh + R"(", "material": "clay", "instances": [{"translate": [-6.5, 0, 0]}]}],
  "sun": {"direction": [0.35, 0.85, 0.4], "radiance": [20000, 19000, 17000]}})";
  };
  const double zero[3] = {0, 0, 0};
  std::vector<float> pixels[2];
  for (int k = 0; k < 2; ++k) {
    const std::string path =
        write_temp(k ? "far_scene.json" : "near_scene.json", k ? scene(far_mesh, test::kUtm) : scene(near_mesh, zero));
    const std::string image = test::temp_path("scene_far.png");
    const test::RunResult r =
        test::run_program(binary_, test::quote(path) + " --width 96 --height 54 -o " + test::quote(image));
    ASSERT_TRUE(r.exited);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const bool said = r.err.find(": far from the origin for its size: rendered relative to (") != std::string::npos;
    EXPECT_EQ(said, k == 1) << r.err;
    int channels = 0;
    pixels[k] = read_pixels(image, channels);
    EXPECT_EQ(channels, 3);
    std::remove(image.c_str());
    std::remove(path.c_str());
  }
  std::remove(far_mesh.c_str());
  ASSERT_EQ(pixels[0].size(), size_t(96 * 54 * 3));
  ASSERT_EQ(pixels[1].size(), pixels[0].size());
  size_t differing = 0;
  for (size_t i = 0; i < pixels[0].size(); i += 3) {
    float d = 0;
    for (int c = 0; c < 3; ++c) d = std::max(d, std::fabs(pixels[0][i + c] - pixels[1][i + c]));
    differing += d > 2.0f / 255.0f;
  }
  EXPECT_LE(differing, 96 * 54 / 500) << differing << " pixels differ by more than 2 levels";
}

}  // namespace
}  // namespace gwnrt
