// Generated hostile scene files ("every hostile input gets a clear error or a right
// answer"). From valid scenes (the bundled data/*.json and a small one that uses every key), a
// fixed generator makes a few thousand mutations: every node replaced by values of every wrong
// type, by huge, tiny, denormal and out-of-range numbers and by degenerate vectors and matrices;
// every key removed; an unknown key added to every object; deep nesting; truncated text; bytes
// flipped or inserted; random bytes. Each goes through parse_scene in-process and must come back
// either as a scene the renderer can carry (finite unit camera rays, geometry within the
// documented limits, invertible affine instances, radiances within the limit; built in Embree
// and rendered at 4 x 3 without a ray refused and without a non-finite pixel) or as an error that
// names the file and a JSON location (or the line of the JSON error); never an exception. A
// handful also run through the gwnrt-render binary end to end. Deterministic: std::mt19937's
// sequence is fixed by the standard, and only its raw output is used.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_util.h"
#include "render/integrators/path.h"
#include "render/render_scene.h"
#include "render/scene.h"
#include "test_util.h"

namespace gwnrt::render {
namespace {

using json = nlohmann::json;

// A scene using every section and key, small and quick to build.
const char* const kSmallScene = R"({
  "camera": {"eye": [0, 1.5, 4], "target": [0, 0.5, 0], "up": [0, 1, 0], "fov": 40, "width": 8, "height": 6},
  "render": {"spp": 1, "max_depth": 3, "seed": 3},
  "materials": {
    "white": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]},
    "metal": {"type": "conductor", "albedo": [0.9, 0.8, 0.7], "roughness": 0.2},
    "glass": {"type": "dielectric", "ior": 1.5},
    "lamp": {"type": "emissive", "emission": [4, 4, 4]}
  },
  "meshes": [
    {"plane": 6, "material": "white"},
    {"plane": 1, "material": "lamp", "transform": {"translate": [0, 3, 0], "rotate": [1, 0, 0, 180]}},
    {"file": "bunny_holes.obj", "material": "metal",
     "transform": {"matrix": [1, 0, 0, 1, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}}
  ],
  "gwn_objects": [
    {"file": "bunny_holes.obj", "material": "glass", "mode": "gwn", "level": 0.5, "epsilon": 1e-4,
     "max_steps": 64, "beta": 2, "instances": [{"translate": [-1, 0, 0], "rotate": [0, 1, 0, 30], "scale": [1, 2, 1]}]},
    {"file": "bunny_holes.obj", "mode": "solid-angle", "transform": {"scale": 0.5}}
  ],
  "environment": {"radiance": [0.2, 0.3, 0.4]},
  "sun": {"direction": [0.3, 1, 0.2], "radiance": [20, 20, 20], "angular_radius": 0.05}
})";

// What replaces a node: every JSON type, numbers at float's and double's edges, degenerate
// vectors and matrices.
std::vector<json> replacements() {
  std::vector<json> v = {
      json(5),
      json(-1),
      json(0),
      json(-0.0),
      json(0.5),
      json("x"),
      json("NaN"),
      json(true),
      json(nullptr),
      json::array(),
      json::object(),
      json::object({{"zz", 1}}),
      json::array({1, 2}),
      json::array({1, 2, 3, 4}),
      json::array({"a", "b", "c"}),
      json(1e39),
      json(-1e39),
      json(3.4e38),
      json(1.7976931348623157e308),
      json(1e-45),
      json(4.9e-324),
      json(1e-30),
      json(1e12),
      json(2e12),
      json(1e19),
      json(uint64_t(18446744073709551615ull)),
      json(int64_t(-9223372036854775807ll - 1)),
      json(2147483648ll),
      json(1e21),
      json::array({0, 0, 0}),
      json::array({1e38, 1e38, 1e38}),
      json::array({1e-40, 0, 0}),
      json::array({-1, -1, -1}),
      json::array({1e13, 0, 0}),
      json::array({0, 1e-30, 0}),
      json::array({0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1}),
      json::array({1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1, 1}),
      json::object({{"scale", 1e30}}),
      json::object({{"scale", 1e-30}}),
      json::object({{"matrix", json::array({1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1e-7, 0, 0, 0, 0, 1})}}),
      json::object({{"type", "emissive"}, {"emission", json::array({3e38, 3e38, 3e38})}}),
  };
  return v;
}

// Every node's JSON pointer, the root first.
void pointers(const json& j, const std::string& at, std::vector<std::string>& out) {
  out.push_back(at);
  if (j.is_object()) {
    for (const auto& item : j.items()) {
      std::string token;
      for (char c : item.key())
        token += c == '~' ? std::string("~0") : c == '/' ? std::string("~1") : std::string(1, c);
      pointers(item.value(), at + "/" + token, out);
    }
  } else if (j.is_array()) {
    for (size_t i = 0; i < j.size(); ++i) pointers(j[i], at + "/" + std::to_string(i), out);
  }
}

struct Mutation {
  std::string name;
  std::string text;
};

std::vector<Mutation> mutations(const std::vector<std::pair<std::string, std::string>>& seeds) {
  std::vector<Mutation> out;
  const std::vector<json> values = replacements();
  std::mt19937 random(20240615u);
  for (const auto& [seed_name, seed_text] : seeds) {
    const json seed = json::parse(seed_text);
    std::vector<std::string> nodes;
    pointers(seed, "", nodes);
    for (size_t n = 0; n < nodes.size(); ++n) {
      const json::json_pointer p(nodes[n]);
      // Replacements: all of them for leaves (where the numbers matter), a rotating third for
      // objects and arrays (whose wrong types the leaves' parents already see).
      const bool leaf = !seed.at(p).is_structured();
      for (size_t k = 0; k < values.size(); ++k) {
        if (!leaf && (k + n) % 3 != 0) continue;
        json m = seed;
        m[p] = values[k];
        out.push_back({seed_name + " " + nodes[n] + " = " + values[k].dump(), m.dump()});
      }
      if (nodes[n].empty()) continue;
      // The node removed (a missing key or a shorter list).
      json m = seed;
      const json::json_pointer parent = p.parent_pointer();
      if (m.at(parent).is_object())
        m.at(parent).erase(p.back());
      else
        m.at(parent).erase(size_t(std::stoul(p.back())));
      out.push_back({seed_name + " remove " + nodes[n], m.dump()});
      // An unknown key beside each object's own.
      if (seed.at(p).is_object()) {
        json u = seed;
        u.at(p)["zz_unknown"] = 1;
        out.push_back({seed_name + " unknown key in " + nodes[n], u.dump()});
      }
    }
    const std::string text = seed.dump();
    // Numbers beyond double's range and the words JSON does not have, spliced in as text for the
    // camera's fov.
    json with_fov = seed;
    with_fov["camera"]["fov"] = 40;
    const std::string fov_text = with_fov.dump();
    for (const char* token : {"1e400", "-1e400", "1e-400", "NaN", "Infinity", "-inf", "0x10", "1.e5", "01",
                              "100000000000000000000000000000000000000000000000000"}) {
      std::string t = fov_text;
      t.replace(t.find("\"fov\":40") + 6, 2, token);
      out.push_back({seed_name + " number " + token, t});
    }
    // Deep nesting in place of the camera's eye.
    for (const size_t depth : {size_t(1000), size_t(100000)}) {
      json m = seed;
      m["camera"] = json::object({{"eye", 0}});
      std::string t = m.dump();
      t.replace(t.find("\"eye\":0") + 6, 1, std::string(depth, '[') + std::string(depth, ']'));
      out.push_back({seed_name + " nesting " + std::to_string(depth), t});
    }
    // Truncations at 40 places.
    for (size_t k = 0; k < 40; ++k) {
      const size_t at = text.size() * k / 40;
      out.push_back({seed_name + " truncated at " + std::to_string(at), text.substr(0, at)});
    }
    // 1 to 3 bytes replaced, or inserted, by any byte value.
    for (int k = 0; k < 60; ++k) {
      std::string t = text;
      const int count = 1 + int(random() % 3);
      for (int c = 0; c < count; ++c) {
        const size_t at = random() % t.size();
        const char byte = char(random() % 256);
        if (k % 2)
          t[at] = byte;
        else
          t.insert(t.begin() + std::ptrdiff_t(at), byte);
      }
      out.push_back({seed_name + " bytes changed #" + std::to_string(k), t});
    }
    // A long material name and a long string value.
    json m = seed;
    m["materials"][std::string(100000, 'm')] = json::object({{"type", "diffuse"}});
    out.push_back({seed_name + " long name", m.dump()});
  }
  // Random bytes.
  for (int k = 0; k < 40; ++k) {
    std::string t(random() % 300, '\0');
    for (char& c : t) c = char(random() % 256);
    out.push_back({"random bytes #" + std::to_string(k), t});
  }
  return out;
}

using test::all_finite;
bool within(const vec3& v, float limit) {
  return std::fabs(v.x) <= limit && std::fabs(v.y) <= limit && std::fabs(v.z) <= limit;
}
bool radiance_ok(const Spectrum& s) {
  return all_finite(s) && s.x >= 0 && s.y >= 0 && s.z >= 0 && within(s, kMaxRadiance);
}

// Why an accepted scene is not one the renderer can carry, or empty. The limits are those
// scene.h documents.
std::string scene_problem(const SceneDesc& s) {
  const render::PinholeCamera& c = s.camera;
  if (!(c.width >= 1 && c.width <= 32768 && c.height >= 1 && c.height <= 32768)) return "image size";
  if (!within(c.eye, 1e12f) || !all_finite(c.eye)) return "eye";
  for (const auto& [x, y] : {std::pair{0, 0}, std::pair{c.width - 1, c.height - 1}, std::pair{c.width / 2, 0}}) {
    const Ray r = c.ray(x, y);
    if (!all_finite(r.direction) || std::fabs(glm::length(r.direction) - 1.0f) > 1e-4f) return "camera ray";
  }
  if (s.render.spp < 1 || s.render.max_depth < 1) return "render settings";
  if (s.materials.size() != s.material_names.size() || s.materials.empty()) return "materials";
  for (const Material& m : s.materials)
    if (!radiance_ok(m.emission) || !all_finite(m.albedo) || !(m.ior > 0.0f) || !std::isfinite(m.roughness))
      return "material";
  for (const MeshDesc& m : s.meshes) {
    if (m.material < 0 || size_t(m.material) >= s.materials.size()) return "mesh material";
    for (const vec3& p : m.mesh.positions)
      if (!all_finite(p) || !within(p, 1e12f)) return "mesh vertex";
  }
  for (const GwnObjectDesc& g : s.gwn_objects) {
    if (g.material < 0 || size_t(g.material) >= s.materials.size()) return "object material";
    for (const glm::mat4& t : g.instances) {
      for (int col = 0; col < 4; ++col)
        if (!std::isfinite(t[col].x + t[col].y + t[col].z + t[col].w)) return "instance not finite";
      if (t[0][3] != 0 || t[1][3] != 0 || t[2][3] != 0 || t[3][3] != 1) return "instance not affine";
      if (!(std::fabs(glm::determinant(glm::dmat3(glm::mat3(t)))) > 0.0)) return "instance singular";
    }
  }
  if (!radiance_ok(s.environment.radiance) || !radiance_ok(s.sun.radiance)) return "light";
  if (!all_finite(s.sun.direction) || std::fabs(glm::length(s.sun.direction) - 1.0f) > 1e-4f) return "sun direction";
  return {};
}

// Renders an accepted scene at 4 x 3, one sample, depth 3, the tracer's steps capped at 64 (a
// mutated epsilon or cap would otherwise only cost time): empty, or what went wrong.
std::string render_problem(SceneDesc s) {
  s.camera.width = 4;
  s.camera.height = 3;
  for (GwnObjectDesc& g : s.gwn_objects) g.options.max_steps = std::min<uint32_t>(g.options.max_steps, 64);
  RenderScene scene;
  if (Status st = scene.build(s); !st.ok()) return "build: " + st.message();
  RenderSettings settings;
  settings.spp = 1;
  settings.max_depth = 3;
  const PathRender r = render_paths(scene, settings);
  if (scene.invalid_rays() != 0) return std::to_string(scene.invalid_rays()) + " invalid rays";
  for (float v : r.image.data())
    if (!std::isfinite(v)) return "a non-finite pixel";
  return {};
}

class SceneFuzz : public ::testing::Test {
 protected:
  void SetUp() override {
    // The scenes' meshes, bunny_holes.obj, are a tetrahedron here: quick to load and build.
    dir_ = test::temp_path("scene_fuzz");
    std::filesystem::create_directories(dir_);
    std::ofstream(dir_ + "/bunny_holes.obj")
        << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
    scene_path_ = dir_ + "/fuzz.json";
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string dir_, scene_path_;
};

TEST_F(SceneFuzz, HostileScenesGiveASceneOrALocatedError) {
  std::vector<std::pair<std::string, std::string>> seeds = {{"small", kSmallScene}};
  for (const char* name : {"bunny_scene.json", "materials_scene.json"})
    seeds.push_back({name, test::read_file(test::data_path(name))});
  for (const auto& [name, text] : seeds) {
    SceneDesc s;
    const Status st = parse_scene(text, scene_path_, s);
    ASSERT_TRUE(st.ok()) << name << ": " << st.message();  // the seeds themselves are valid
  }
  const auto start = std::chrono::steady_clock::now();
  const std::vector<Mutation> all = mutations(seeds);
  size_t accepted = 0, refused = 0, failures = 0;
  for (const Mutation& m : all) {
    SceneDesc s;
    Status st;
    std::string problem;
    try {
      st = parse_scene(m.text, scene_path_, s);
      if (st.ok()) {
        problem = scene_problem(s);
        if (problem.empty()) problem = render_problem(std::move(s));
      } else {
        const std::string& msg = st.message();
        // "<file>: /json/pointer: ..." or "<file>: not valid JSON: ... line L ...".
        const bool located =
            msg.rfind(scene_path_ + ": /", 0) == 0 ||
            (msg.rfind(scene_path_ + ": not valid JSON: ", 0) == 0 && msg.find("line ") != std::string::npos);
        if (!located) problem = "an error without a location: " + msg;
      }
    } catch (const std::exception& e) {
      problem = std::string("threw: ") + e.what();
    } catch (...) {
      problem = "threw something";
    }
    (st.ok() ? accepted : refused) += 1;
    if (!problem.empty() && ++failures <= 20) ADD_FAILURE() << m.name << ": " << problem;
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("[ fuzz ] %zu mutations: %zu accepted (each built and rendered), %zu refused, in %.2f s\n", all.size(),
              accepted, refused, seconds);
  EXPECT_EQ(failures, 0u);
  // The generator reaches both outcomes in numbers.
  EXPECT_GT(accepted, 100u);
  EXPECT_GT(refused, 1000u);
}

// A handful through the binary: accepted ones render (exit 0, an image), refused ones exit 1 with
// a message; none ends in a signal.
TEST_F(SceneFuzz, HandfulRunEndToEndCli) {
  const std::string binary = test::program_binary("gwnrt-render");
  if (binary.empty()) GTEST_SKIP() << "gwnrt-render not built next to the tests";
  const std::vector<Mutation> all = mutations({{"small", kSmallScene}});
  // Accepted and refused mutations of different kinds, picked by their names.
  const std::vector<std::string> picks = {"small /camera/up/1 = 1e-30", "small remove /meshes/0",
                                          "small /camera/up/1 = 0", "small /meshes/0/plane = 3.4e+38",
                                          "small nesting 100000"};
  const std::string out = test::temp_path("fuzz.png");
  size_t ran = 0;
  for (const Mutation& m : all) {
    if (std::find(picks.begin(), picks.end(), m.name) == picks.end()) continue;
    ++ran;
    SCOPED_TRACE(m.name);
    std::ofstream(scene_path_, std::ios::binary | std::ios::trunc) << m.text;
    SceneDesc s;
    const bool valid = parse_scene(m.text, scene_path_, s).ok();
    const test::RunResult r =
        test::run_program(binary, test::quote(scene_path_) + " --width 8 --height 6 --spp 1 -o " + test::quote(out));
    ASSERT_TRUE(r.exited) << "killed by a signal: " << r.err;
    EXPECT_EQ(r.exit_code, valid ? 0 : 1) << r.err;
    if (valid) {
      EXPECT_TRUE(std::filesystem::exists(out));
    } else {
      EXPECT_NE(r.err.find("gwnrt-render: " + scene_path_ + ": "), std::string::npos) << r.err;
    }
    std::remove(out.c_str());
  }
  EXPECT_EQ(ran, picks.size());
}

}  // namespace
}  // namespace gwnrt::render
