// The scene reader's refusals, in-process through parse_scene,
// load_scene and default_scene: each class of hostile input is refused with the JSON location
// of the problem, and what is accepted makes a camera and geometry whose rays are finite. Also
// the two guards behind the reader: RenderScene drops a ray Embree would abort on, and the
// tone curve keeps huge radiances white.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "cli_util.h"
#include "mesh_files.h"
#include "render/image_output.h"
#include "render/integrators/path.h"
#include "render/render_scene.h"
#include "render/scene.h"
#include "test_util.h"

namespace gwnrt::render {
namespace {

// Parses `text` as a scene file in data/ (relative mesh paths name the bundled meshes).
Status parse(const std::string& text, SceneDesc& out) { return parse_scene(text, test::data_path("inline.json"), out); }

// `text` is refused, and the message names `location` (a JSON pointer) as the place.
void expect_refused(const std::string& text, const std::string& location, const std::string& words = "") {
  SCOPED_TRACE(text);
  SceneDesc s;
  const Status st = parse(text, s);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.message().find("inline.json: " + location + ": "), std::string::npos) << st.message();
  if (!words.empty()) {
    EXPECT_NE(st.message().find(words), std::string::npos) << st.message();
  }
}

using test::all_finite;

// Every corner and the centre ray of an accepted camera are finite and unit.
void expect_finite_rays(const render::PinholeCamera& cam) {
  for (const auto& [x, y] : {std::pair{0, 0}, std::pair{cam.width - 1, 0}, std::pair{0, cam.height - 1},
                             std::pair{cam.width - 1, cam.height - 1}, std::pair{cam.width / 2, cam.height / 2}}) {
    const Ray r = cam.ray(x, y);
    EXPECT_TRUE(all_finite(r.origin) && all_finite(r.direction));
    EXPECT_NEAR(glm::length(r.direction), 1.0f, 1e-5f);
  }
}

void expect_accepted(const std::string& text, SceneDesc* out = nullptr) {
  SCOPED_TRACE(text);
  SceneDesc s;
  const Status st = parse(text, s);
  ASSERT_TRUE(st.ok()) << st.message();
  expect_finite_rays(s.camera);
  if (out) *out = std::move(s);
}

// A camera over a unit plane (a scene needs something to render).
std::string camera(const std::string& eye, const std::string& target, const std::string& up) {
  return R"({"meshes": [{"plane": 1}], "camera": {"eye": )" + eye + R"(, "target": )" + target + R"(, "up": )" + up +
         R"(}})";
}

// Item 1: a camera that would make non-finite or meaningless rays (Embree's ray.valid() aborted).
TEST(SceneChecks, DegenerateCameraIsRefused) {
  // "up" zero, along the view direction either way, or within 0.06 degrees of it.
  expect_refused(camera("[0, 1, 5]", "[0, 0, 0]", "[0, 0, 0]"), "/camera/up", "zero");
  expect_refused(camera("[0, 5, 0]", "[0, 0, 0]", "[0, 1, 0]"), "/camera/up", "parallel");
  expect_refused(camera("[0, 5, 0]", "[0, 0, 0]", "[0, -3, 0]"), "/camera/up", "parallel");
  expect_refused(camera("[1, 2, 3]", "[0, 0, 0]", "[1e-20, 2e-20, 3.00001e-20]"), "/camera/up", "parallel");
  // Eye and target the same point (also after rounding to float).
  expect_refused(camera("[1, 2, 3]", "[1, 2, 3]", "[0, 1, 0]"), "/camera", "coincide");
  expect_refused(camera("[1e12, 0, 0]", "[1000000000000.0001, 0, 0]", "[0, 1, 0]"), "/camera", "coincide");
  // An eye or a target far out: Embree's triangle test overflows beyond ~2e12, its ray check
  // aborts beyond 1.8e18.
  for (const char* far : {"1.1e12", "-5e13", "1e18", "1e19", "1e37", "-3.4e38"}) {
    expect_refused(camera(std::string("[0, ") + far + ", 5]", "[0, 0, 0]", "[1, 0, 0]"), "/camera/eye", "1e12");
    expect_refused(camera("[0, 0, 5]", std::string("[0, ") + far + ", 0]", "[1, 0, 0]"), "/camera/target", "1e12");
  }
  // fov that rounds to 180 in float.
  expect_refused(R"({"camera": {"fov": 179.999999999}})", "/camera/fov");
  // Accepted: tiny but nonzero differences and "up" vectors are normalised in double; 1 degree
  // from the view direction is enough; the eye at the limit.
  expect_accepted(camera("[0, 0, 1e-30]", "[0, 0, 0]", "[0, 1e-30, 0]"));
  expect_accepted(camera("[0, 5, 0]", "[0, 0, 0]", "[0.01745, 1, 0]"));
  expect_accepted(camera("[0, 1e12, 5]", "[0, 0, 0]", "[1, 0, 0]"));
  expect_accepted(R"({"meshes": [{"plane": 1}], "camera": {"fov": 1e-30}})");
  expect_accepted(R"({"meshes": [{"plane": 1}], "camera": {"fov": 179.99}})");
}

// Item 1: geometry whose world-space coordinates float cannot carry through Embree.
TEST(SceneChecks, GeometryBeyondFloatIsRefused) {
  for (const char* size : {"2.1e12", "1e20", "3e38"})
    expect_refused(std::string(R"({"meshes": [{"plane": 1}, {"plane": )") + size + "}]}", "/meshes/1", "1e12");
  expect_refused(R"({"meshes": [{"plane": 0}]})", "/meshes/0/plane", "positive");
  expect_refused(R"({"meshes": [{"plane": -2}]})", "/meshes/0/plane", "positive");
  expect_refused(R"({"meshes": [{"plane": 2, "transform": {"translate": [0, 2e12, 0]}}]})", "/meshes/0", "1e12");
  // A transform that overflows float: refused as a transform (its scale) before the vertices.
  expect_refused(R"({"meshes": [{"plane": 2, "transform": {"scale": 1e30}}]})", "/meshes/0/transform", "1e12");
  expect_refused(R"({"meshes": [{"file": "bunny_holes.obj", "transform": {"scale": 5e11}}]})", "/meshes/0", "1e12");
  expect_refused(R"({"gwn_objects": [{"file": "bunny_holes.obj", "transform": {"translate": [1e13, 0, 0]}}]})",
                 "/gwn_objects/0/transform", "1e12");
  // Nothing but tiny geometry: below what float resolves.
  expect_refused(R"({"meshes": [{"plane": 1e-13}]})", "/", "1e-12");
  expect_accepted(R"({"meshes": [{"plane": 1.9e12}]})");
  expect_accepted(R"({"meshes": [{"plane": 1e-9}]})");
}

// Item 1: transforms that are singular, nearly so, or scale beyond what float can invert.
TEST(SceneChecks, BadTransformsAreRefused) {
  const std::string object = R"({"gwn_objects": [{"file": "bunny_holes.obj", "instances": [)";
  const std::string where = "/gwn_objects/0/instances/1";
  auto instance = [&](const std::string& t) { return object + R"({"scale": 1}, )" + t + "]}]}"; };
  expect_refused(instance(R"({"matrix": [0,0,0,0, 0,0,0,0, 0,0,0,0, 0,0,0,1]})"), where, "singular");
  expect_refused(instance(R"({"matrix": [0,0,0,0, 0,0,0,0, 0,0,0,0, 0,0,0,0]})"), where, "affine");
  expect_refused(instance(R"({"matrix": [1,0,0,0, 0,1,0,0, 1,1,0,0, 0,0,0,1]})"), where, "singular");
  expect_refused(instance(R"({"matrix": [1,2,3,0, 2,4,6,0, 0,0,1,0, 0,0,0,1]})"), where, "singular");
  expect_refused(instance(R"({"matrix": [1,0,0,0, 0,1,0,0, 0,0,1e-7,0, 0,0,0,1]})"), where, "nearly singular");
  expect_refused(instance(R"({"matrix": [1,1,0,0, 1,1.0000001,0,0, 0,0,1,0, 0,0,0,1]})"), where);
  expect_refused(instance(R"({"scale": [1, 1, 0]})"), where + "/scale", "zero");
  expect_refused(instance(R"({"scale": 1e-30})"), where, "1e-12");
  for (const char* s : {"1e13", "1e30", "3e38", "[1, 1e20, 1]"})
    expect_refused(instance(std::string(R"({"scale": )") + s + "}"), where);
  expect_refused(instance(R"({"rotate": [0, 0, 0, 30]})"), where + "/rotate", "zero");
  // Accepted: a flattening by 1e-3, a huge angle (reduced in double), a tiny rotation axis.
  SceneDesc s;
  expect_accepted(instance(R"({"scale": [1, 1, 1e-3]})"));
  expect_accepted(instance(R"({"rotate": [0, 1, 0, 1e30]})"));
  // A last row that float reads as 0 0 0 1 (as it always was read).
  expect_accepted(instance(R"({"matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,1e-50,1.0000000001]})"));
  expect_accepted(instance(R"({"rotate": [0, 1e-30, 0, 90], "translate": [1, 0, 0]})"), &s);
  ASSERT_EQ(s.gwn_objects[0].instances.size(), 2u);
  // The rotation of 90 degrees about y maps x to -z.
  const glm::mat4& t = s.gwn_objects[0].instances[1];
  EXPECT_NEAR((t * glm::vec4(1, 0, 0, 0)).z, -1.0f, 1e-6f);
}

// Item 1: an instance so small that, in its object space, the rest of the scene (where its rays
// start) lies beyond the coordinate limit.
TEST(SceneChecks, InstanceObjectSpaceIsBounded) {
  const std::string tiny = R"("gwn_objects": [{"file": "bunny_holes.obj", "instances": [{"scale": 1e-6}]}])";
  expect_refused("{" + tiny + R"(, "meshes": [{"plane": 1e8}]})", "/gwn_objects/0/instances/0", "object space");
  expect_refused("{" + tiny + R"(, "camera": {"eye": [0, 0, 1e7]}})", "/gwn_objects/0/instances/0", "object space");
  expect_accepted("{" + tiny + R"(, "meshes": [{"plane": 100}]})");
}

// Writes an OBJ tetrahedron of edge `size` with a corner at `offset` (on every axis).
std::string write_tetrahedron(double size, double offset, const std::string& name) {
  const std::string path = test::temp_path(name);
  std::ofstream f(path);
  f.precision(17);
  const double o = offset, s = size;
  f << "v " << o << " " << o << " " << o << "\nv " << o + s << " " << o << " " << o << "\nv " << o << " " << o + s
    << " " << o << "\nv " << o << " " << o << " " << o + s << "\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
  return path;
}

// Item 1: the default scene made for a bare mesh, whose camera and ground are computed from the
// mesh's box: meshes too small or too large (or too far out) for it are refused, naming the mesh.
TEST(SceneChecks, DefaultSceneOfExtremeMeshesIsRefused) {
  for (const auto& [size, offset] :
       {std::pair{1e-30, 0.0}, std::pair{1e-13, 0.0}, std::pair{1e11, 0.0}, std::pair{1e20, 0.0}}) {
    const std::string path = write_tetrahedron(size, offset, "extreme.obj");
    SCOPED_TRACE(path + " size " + std::to_string(size) + " offset " + std::to_string(offset));
    SceneDesc s;
    const Status st = default_scene(path, s);
    EXPECT_FALSE(st.ok());
    EXPECT_NE(st.message().find(path + ": the default scene for a mesh"), std::string::npos) << st.message();
    std::remove(path.c_str());
  }
  // Far out for its size (1e3 at 1e15, where float steps by 6.7e7): recentred, then stood on the
  // ground like any other.
  for (const auto& [size, offset] :
       {std::pair{1e-9, 0.0}, std::pair{1.0, 0.0}, std::pair{1e9, 0.0}, std::pair{1e3, 1e15}, std::pair{1.0, -3e13}}) {
    const std::string path = write_tetrahedron(size, offset, "fine.obj");
    SCOPED_TRACE(path + " size " + std::to_string(size) + " offset " + std::to_string(offset));
    SceneDesc s;
    const Status st = default_scene(path, s);
    ASSERT_TRUE(st.ok()) << st.message();
    expect_finite_rays(s.camera);
    // The camera looks at the middle of the mesh standing on the ground, (0, size/2, 0): the ray
    // through the image's middle passes it within half a pixel (the distance is 3.6 sizes, a
    // pixel 1/240 of tan 17.5°), far less than 1% of the size.
    const Ray r = s.camera.ray(s.camera.width / 2, s.camera.height / 2);
    const glm::dvec3 middle(0.0, 0.5 * size, 0.0), o(r.origin), d(r.direction);
    EXPECT_LT(glm::length(glm::cross(middle - o, d)), 0.01 * size);
    std::remove(path.c_str());
  }
}

// A georeferenced scan (bunny_holes moved to UTM metres, where float steps by 0.25-0.5) is read
// in double and recentred: a scene file's transform applies to the file's coordinates, composed
// with the mesh's origin in double, so a scan placed back near the origin lands where the bunny
// itself is, as a triangle mesh and as a GWN object. Error budget: the file's 17 digits (1e-10),
// float rounding of positions about the mesh's centre and of the small composed translation
// (each about 1e-8 here), and the float product instance · position; 1e-6 of the diagonal is
// ample, and far below the 0.25 that rounding the file's coordinates to float would cost.
TEST(SceneChecks, FarOffMeshesArePlacedInDouble) {
  const Mesh bunny = test::load_test_mesh("bunny_holes.obj");
  const std::string utm = test::temp_path("utm_bunny_holes.obj");
  test::write_translated(test::data_path("bunny_holes.obj"), utm, test::kUtm, true);
  dvec3 lo(bunny.positions[0]), hi = lo;
  for (const vec3& p : bunny.positions) {
    lo = glm::min(lo, dvec3(p));
    hi = glm::max(hi, dvec3(p));
  }
  const double tolerance = 1e-6 * glm::length(hi - lo);
  const auto worst_distance = [&](const glm::mat4& placement, const Mesh& placed, const dvec3& shift) {
    EXPECT_EQ(placed.positions.size(), bunny.positions.size());
    double worst = 0;
    for (size_t i = 0; i < std::min(placed.positions.size(), bunny.positions.size()); ++i) {
      const dvec3 world(glm::dmat4(placement) * glm::dvec4(dvec3(placed.positions[i]), 1.0));
      worst = std::max(worst, glm::length(world - (dvec3(bunny.positions[i]) + shift)));
    }
    return worst;
  };
  const std::string back = R"({"translate": [)" + test::num(-test::kUtm[0]) + ", " + test::num(-test::kUtm[1]) + ", " +
                           test::num(-test::kUtm[2]) + "]}";
  SceneDesc s;
  expect_accepted(R"({"meshes": [{"file": ")" + utm + R"(", "transform": )" + back +
                      R"(}], "gwn_objects": [{"file": ")" + utm + R"(", "instances": [)" + back +
                      R"(, {"scale": 1}]}]})",
                  &s);
  ASSERT_EQ(s.loaded_meshes.size(), 2u);
  EXPECT_NE(s.loaded_meshes[0].report.origin, dvec3(0.0));
  ASSERT_EQ(s.meshes.size(), 1u);
  EXPECT_LE(worst_distance(glm::mat4(1.0f), s.meshes[0].mesh, dvec3(0.0)), tolerance);
  ASSERT_EQ(s.gwn_objects.size(), 1u);
  ASSERT_EQ(s.gwn_objects[0].instances.size(), 2u);
  EXPECT_LE(worst_distance(s.gwn_objects[0].instances[0], s.gwn_objects[0].mesh, dvec3(0.0)), tolerance);
  // The identity leaves the scan where the file puts it (float's step there is 0.5 at most).
  const dvec3 utm_offset(test::kUtm[0], test::kUtm[1], test::kUtm[2]);
  EXPECT_LE(worst_distance(s.gwn_objects[0].instances[1], s.gwn_objects[0].mesh, utm_offset), 0.5);
  // The default scene stands the scan on the ground exactly as it does the bunny, framing what is
  // drawn: a vertex no triangle uses (here at the file's origin, 4e6 away) is not framed.
  const std::string with_unused = test::temp_path("utm_unused.obj");
  std::filesystem::copy_file(utm, with_unused, std::filesystem::copy_options::overwrite_existing);
  std::ofstream(with_unused, std::ios::app) << "v 0 0 0\n";
  SceneDesc far_scene, near_scene;
  ASSERT_TRUE(default_scene(with_unused, far_scene).ok());
  ASSERT_TRUE(default_scene(test::data_path("bunny_holes.obj"), near_scene).ok());
  EXPECT_LE(glm::length(dvec3(far_scene.camera.eye) - dvec3(near_scene.camera.eye)), tolerance);
  const glm::dmat4 near_placement(near_scene.gwn_objects[0].instances[0]);
  double worst = 0;
  for (size_t i = 0; i < bunny.positions.size(); ++i) {
    const dvec3 far_world(glm::dmat4(far_scene.gwn_objects[0].instances[0]) *
                          glm::dvec4(dvec3(far_scene.gwn_objects[0].mesh.positions[i]), 1.0));
    const dvec3 near_world(near_placement * glm::dvec4(dvec3(bunny.positions[i]), 1.0));
    worst = std::max(worst, glm::length(far_world - near_world));
  }
  EXPECT_LE(worst, tolerance);
  // A scene of the scan with a camera at UTM is moved about its centre, camera and all; the
  // unused vertex at the file's 0 does not count (it would keep the scene where float steps by
  // 0.5).
  const auto utm_point = [](double x, double y, double z) {
    return "[" + test::num(test::kUtm[0] + x) + ", " + test::num(test::kUtm[1] + y) + ", " +
           test::num(test::kUtm[2] + z) + "]";
  };
  SceneDesc site;
  expect_accepted(R"({"gwn_objects": [{"file": ")" + with_unused + R"("}], "camera": {"eye": )" + utm_point(0, 1, 3) +
                      R"(, "target": )" + utm_point(0, 0, 0) + "}}",
                  &site);
  EXPECT_NE(site.origin, dvec3(0.0));
  EXPECT_LT(glm::length(dvec3(site.camera.eye)), 10.0);
  std::remove(utm.c_str());
  std::remove(with_unused.c_str());
}

// Item 1, the guard behind the reader: a ray Embree would abort on (non-finite, or beyond its
// FLT_LARGE) is dropped and counted by RenderScene, never handed to Embree.
TEST(SceneChecks, RenderSceneDropsInvalidRays) {
  for (const vec3 eye : {vec3(std::numeric_limits<float>::quiet_NaN()), vec3(0.0f, 0.0f, 1e19f),
                         vec3(std::numeric_limits<float>::infinity())}) {
    SceneDesc s;
    s.materials = {Material{}};
    s.material_names = {"m"};
    MeshDesc plane;
    plane.source = "plane";
    plane.mesh.positions = {{-1, 0, -1}, {1, 0, -1}, {1, 0, 1}, {-1, 0, 1}};
    plane.mesh.triangles = {{0, 2, 1}, {0, 3, 2}};
    s.meshes.push_back(plane);
    s.environment.radiance = Spectrum(1.0f);
    // Built by hand, past the reader's checks.
    s.camera = render::look_along(eye, vec3(0, -1, 0), vec3(0, 0, 1), 40.0f, 4, 3);
    RenderScene scene;
    ASSERT_TRUE(scene.build(s).ok());
    RenderSettings settings;
    settings.spp = 1;
    const PathRender r = render_paths(scene, settings);
    EXPECT_EQ(scene.invalid_rays(), 12u);  // every camera ray; none went further
    for (float v : r.image.data()) EXPECT_TRUE(std::isfinite(v));
  }
}

// Item 2: numbers beyond double's range, and files that cannot be read as text: errors with
// the place, never an exception.
TEST(SceneChecks, UnreadableInputGivesAnError) {
  for (const char* number : {"1e400", "-1e400", "1E+999", "123456789e999"}) {
    SceneDesc s;
    const std::string text = std::string("{\n  \"camera\": {\n    \"fov\": ") + number + "\n  }\n}";
    SCOPED_TRACE(text);
    const Status st = parse(text, s);
    ASSERT_FALSE(st.ok());
    EXPECT_EQ(st.code(), StatusCode::kParseError);
    EXPECT_NE(st.message().find("inline.json: not valid JSON: at line 3"), std::string::npos) << st.message();
  }
  for (const std::string& text : {std::string(""), std::string("{"), std::string("{\"camera\": [1, 2,"),
                                  std::string("{\"a\": \"\xff\xfe\"}"), std::string("\0\0\0", 3), std::string("nul")}) {
    SceneDesc s;
    const Status st = parse(text, s);
    ASSERT_FALSE(st.ok());
    EXPECT_NE(st.message().find("inline.json: not valid JSON"), std::string::npos) << st.message();
  }
  // A directory, a missing file, a stream that never ends (stopped at the size limit).
  SceneDesc s;
  const std::string dir = test::temp_path("scene_dir.json");
  std::filesystem::create_directories(dir);
  Status st = load_scene(dir, s);
  EXPECT_FALSE(st.ok());
  EXPECT_NE(st.message().find(dir), std::string::npos) << st.message();
  EXPECT_NE(st.message().find("directory"), std::string::npos) << st.message();
  std::filesystem::remove(dir);
  st = load_scene(dir + "/missing.json", s);
  EXPECT_FALSE(st.ok());
  EXPECT_NE(st.message().find("missing.json"), std::string::npos) << st.message();
  if (std::filesystem::exists("/dev/zero")) {
    st = load_scene("/dev/zero", s);
    EXPECT_FALSE(st.ok());
    EXPECT_NE(st.message().find("/dev/zero"), std::string::npos) << st.message();
  }
}

// Item 12: every section and list entry of the wrong type is refused at its location.
TEST(SceneChecks, SectionsOfTheWrongTypeAreRefused) {
  const std::vector<std::string> not_objects = {"5", "[]", "\"x\"", "true", "null", "[{}]"};
  for (const char* section : {"camera", "render", "materials", "environment", "sun"})
    for (const std::string& v : not_objects)
      expect_refused(std::string("{\"") + section + "\": " + v + "}", std::string("/") + section, "expected an object");
  for (const char* list : {"meshes", "gwn_objects"}) {
    for (const std::string v : {"5", "{}", "\"x\"", "true", "null"})
      expect_refused(std::string("{\"") + list + "\": " + v + "}", std::string("/") + list, "expected an array");
    for (const std::string v : {"5", "[]", "\"x\"", "null"})
      expect_refused(std::string("{\"") + list + "\": [" + v + "]}", std::string("/") + list + "/0",
                     "expected an object");
  }
  expect_refused("[]", "/", "expected an object");
  expect_refused("5", "/", "expected an object");
  expect_refused(R"({"materials": {"m": 5}})", "/materials/m", "expected an object");
  expect_refused(R"({"materials": {"a/b~": []}})", "/materials/a~1b~0", "expected an object");
  expect_refused(R"({"meshes": [{"plane": 2, "transform": 5}]})", "/meshes/0/transform", "expected an object");
  expect_refused(R"({"meshes": [{"file": 5}]})", "/meshes/0/file", "expected a file name");
  expect_refused(R"({"gwn_objects": [{"file": "bunny_holes.obj", "instances": 5}]})", "/gwn_objects/0/instances");
  expect_refused(R"({"gwn_objects": [{"file": "bunny_holes.obj", "instances": [5]}]})", "/gwn_objects/0/instances/0");
  expect_refused(R"({"camera": {"eye": {"x": 1}}})", "/camera/eye", "3 numbers");
  expect_refused(R"({"camera": {"eye": [1, "2", 3]}})", "/camera/eye/1", "expected a number");
  expect_refused(R"({"camera": {"width": 64.5}})", "/camera/width", "integer");
  expect_refused(R"({"render": {"spp": "16"}})", "/render/spp", "integer");
  expect_refused(R"({"render": {"seed": 18446744073709551615}})", "/render/seed", "must lie in");
  // Found by test_scene_fuzz: a non-negative integer arrives as unsigned, and 0 passed [1, ...].
  expect_refused(R"({"render": {"spp": 0}})", "/render/spp", "must lie in");
  expect_refused(R"({"render": {"max_depth": 0}})", "/render/max_depth", "must lie in");
  expect_refused(R"({"camera": {"width": 0}})", "/camera/width", "must lie in");
  expect_refused(R"({"gwn_objects": [{"file": "bunny_holes.obj", "max_steps": 0}]})", "/gwn_objects/0/max_steps");
  expect_refused(R"({"meshes": [{"plane": 2, "material": 0}]})", "/meshes/0/material", "material name");
}

// Item 12: an unknown (misspelt) key anywhere is refused at its location, as are keys that
// would be ignored (a scale without an image, an ior on a diffuse material).
TEST(SceneChecks, UnknownKeysAreRefused) {
  expect_refused(R"({"camra": {}})", "/camra", "unknown key");
  expect_refused(R"({"camera": {"fovv": 30}})", "/camera/fovv", "unknown key");
  expect_refused(R"({"render": {"sppp": 4}})", "/render/sppp", "unknown key");
  expect_refused(R"({"materials": {"m": {"type": "diffuse", "albdo": [1, 1, 1]}}})", "/materials/m/albdo");
  expect_refused(R"({"materials": {"m": {"type": "diffuse", "ior": 1.5}}})", "/materials/m/ior", "unknown key");
  expect_refused(R"({"materials": {"m": {"type": "dielectric", "albedo": [1, 1, 1]}}})", "/materials/m/albedo");
  expect_refused(R"({"materials": {"m": {"type": "emissive", "roughness": 0}}})", "/materials/m/roughness");
  expect_refused(R"({"meshes": [{"plane": 2, "materal": "m"}]})", "/meshes/0/materal", "unknown key");
  expect_refused(R"({"meshes": [{"plane": 2, "file": "bunny_holes.obj"}]})", "/meshes/0", "not both");
  expect_refused(R"({"meshes": [{"plane": 2, "transform": {"translat": [1, 0, 0]}}]})", "/meshes/0/transform/translat",
                 "unknown key");
  expect_refused(
      R"({"meshes": [{"plane": 2, "transform": {"matrix": [1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1], "scale": 2}}]})",
      "/meshes/0/transform", "alone");
  expect_refused(R"({"gwn_objects": [{"file": "bunny_holes.obj", "levl": 0.4}]})", "/gwn_objects/0/levl");
  expect_refused(R"({"gwn_objects": [{"file": "bunny_holes.obj", "transform": {}, "instances": []}]})",
                 "/gwn_objects/0", "not both");
  expect_refused(R"({"environment": {"radiancee": [1, 1, 1]}})", "/environment/radiancee", "unknown key");
  expect_refused(R"({"environment": {"radiance": [1, 1, 1], "scale": 2}})", "/environment/scale", "image");
  expect_refused(R"({"environment": {"radiance": [1, 1, 1], "file": "sky.exr"}})", "/environment", "not both");
  expect_refused(R"({"sun": {"dirction": [0, 1, 0]}})", "/sun/dirction", "unknown key");
}

// Item 13: numbers that are finite doubles but not floats (1e39 would become inf), wherever a
// number is read.
TEST(SceneChecks, NumbersBeyondFloatAreRefused) {
  for (const char* big : {"1e39", "-1e39", "3.5e38", "1.7976931348623157e308"}) {
    const std::string b = big;
    expect_refused(R"({"camera": {"eye": [0, )" + b + ", 5]}}", "/camera/eye/1", "float");
    expect_refused(R"({"camera": {"fov": )" + b + "}}", "/camera/fov", "float");
    expect_refused(R"({"materials": {"m": {"type": "emissive", "emission": [)" + b + ", 1, 1]}}}",
                   "/materials/m/emission/0", "float");
    expect_refused(R"({"materials": {"m": {"type": "conductor", "roughness": )" + b + "}}}", "/materials/m/roughness",
                   "float");
    expect_refused(R"({"meshes": [{"plane": )" + b + "}]}", "/meshes/0/plane", "float");
    expect_refused(R"({"meshes": [{"plane": 2, "transform": {"scale": )" + b + "}}]}", "/meshes/0/transform/scale",
                   "float");
    expect_refused(R"({"meshes": [{"plane": 2, "transform": {"matrix": [1,0,0,)" + b + ",0,1,0,0,0,0,1,0,0,0,0,1]}}]}",
                   "/meshes/0/transform/matrix/3", "float");
    expect_refused(R"({"gwn_objects": [{"file": "bunny_holes.obj", "level": )" + b + "}]}", "/gwn_objects/0/level",
                   "float");
    expect_refused(R"({"environment": {"radiance": [1, )" + b + ", 1]}}", "/environment/radiance/1", "float");
    expect_refused(R"({"sun": {"angular_radius": )" + b + "}}", "/sun/angular_radius", "float");
  }
}

// Item 13: radiances that are floats but overflow when a pixel sums its samples (an emission of
// 3e38 rendered black), and negative ones.
TEST(SceneChecks, RadiancesBeyondTheLimitOrNegativeAreRefused) {
  for (const char* v : {"3e38", "1e21", "-1", "-1e-30"}) {
    const std::string x = v;
    expect_refused(R"({"materials": {"m": {"type": "emissive", "emission": [1, 1, )" + x + "]}}}",
                   "/materials/m/emission/2", "radiance");
    expect_refused(R"({"environment": {"radiance": [)" + x + ", 1, 1]}}", "/environment/radiance/0", "radiance");
    expect_refused(R"({"sun": {"radiance": [1, )" + x + ", 1]}}", "/sun/radiance/1", "radiance");
  }
  expect_refused(R"({"environment": {"file": "sky.exr", "scale": 1e21}})", "/environment/scale");
  expect_refused(R"({"environment": {"file": "sky.exr", "scale": -1}})", "/environment/scale");
  expect_refused(R"({"materials": {"g": {"type": "dielectric", "ior": 1e30}}})", "/materials/g/ior");
  expect_refused(R"({"materials": {"g": {"type": "dielectric", "ior": 1e-30}}})", "/materials/g/ior");
  SceneDesc s;
  expect_accepted(R"({"materials": {"m": {"type": "emissive", "emission": [1e20, 0, 1e20]}}, "meshes": [{"plane": 1}],
                      "environment": {"radiance": [1e20, 1e20, 1e20]}, "sun": {"radiance": [1e20, 0, 0]}})",
                  &s);
  EXPECT_EQ(s.materials[0].emission.x, kMaxRadiance);
}

// A key given twice in one object was accepted, the later value silently replacing
// the earlier (a second "camera": {} dropped the first); it is refused, at its JSON location, at
// any depth and inside arrays, while the same key in different objects is fine.
TEST(SceneChecks, DuplicateKeysAreRefused) {
  expect_refused(R"({"camera": {"fov": 30}, "meshes": [{"plane": 1}], "camera": {}})", "/camera", "duplicate key");
  expect_refused(R"({"meshes": [{"plane": 1}, {"plane": 2, "material": "m", "plane": 3}]})", "/meshes/1/plane",
                 "duplicate key");
  // Behind an array of numbers (the matrix), in the second entry of an array of objects.
  expect_refused(R"({"gwn_objects": [{"file": "bunny_holes.obj", "instances": [
                      {"matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]},
                      {"translate": [1, 0, 0], "scale": 2, "translate": [2, 0, 0]}]}]})",
                 "/gwn_objects/0/instances/1/translate", "duplicate key");
  // Keys are compared as given and located as JSON pointers ("/" escaped).
  expect_refused(R"({"materials": {"a/b": {"type": "diffuse"}, "a/b": {"type": "diffuse"}}, "meshes": [{"plane": 1}]})",
                 "/materials/a~1b", "duplicate key");
  // Found while parsing: before anything else is checked (the unknown key after it).
  expect_refused(R"({"sun": {"radiance": [1, 1, 1], "radiance": [2, 2, 2]}, "zz": 1})", "/sun/radiance",
                 "duplicate key");
  expect_accepted(R"({"meshes": [{"plane": 1, "material": "m"}, {"plane": 2, "material": "m"}],
                      "materials": {"m": {"type": "diffuse"}, "n": {"type": "diffuse"}}})");
}

// A scene with nothing in it (`{}`) rendered the sky alone and exited 0.
TEST(SceneChecks, SceneWithoutGeometryIsRefused) {
  for (const char* text : {"{}", R"({"meshes": [], "gwn_objects": []})",
                           R"({"camera": {"eye": [0, 0, 5]}, "environment": {"radiance": [1, 1, 1]}})"})
    expect_refused(text, "/", "nothing to render");
  expect_accepted(R"({"meshes": [{"plane": 1}]})");
  expect_accepted(R"({"gwn_objects": [{"file": "bunny_holes.obj"}]})");
}

// A GWN object whose level w never reaches on its mesh (|level| >= half its
// triangle count) renders nothing; the scene is accepted with a warning naming the object's
// level, worded as gwnrt-trace's, and none for a level within reach or in solid-angle mode.
TEST(SceneChecks, UnreachableLevelIsWarnedAbout) {
  for (const char* level : {"1e30", "-1e30", "3.4e38"}) {
    SCOPED_TRACE(level);
    SceneDesc s;
    expect_accepted(
        std::string(R"({"gwn_objects": [{"file": "bunny_holes.obj"}, {"file": "bunny_holes.obj", "level": )") + level +
            "}]}",
        &s);
    ASSERT_EQ(s.warnings.size(), 1u);
    EXPECT_EQ(s.warnings[0].find(test::data_path("inline.json") + ": /gwn_objects/1/level: level "), 0u)
        << s.warnings[0];
    EXPECT_NE(s.warnings[0].find(" lies outside every value w takes on this mesh"), std::string::npos) << s.warnings[0];
  }
  for (const char* object :
       {R"({"file": "bunny_holes.obj", "level": 0.5})", R"({"file": "bunny_holes.obj", "level": -3})",
        R"({"file": "bunny_holes.obj", "mode": "solid-angle", "level": 1e30})"}) {
    SceneDesc s;
    expect_accepted(std::string(R"({"gwn_objects": [)") + object + "]}", &s);
    EXPECT_TRUE(s.warnings.empty()) << object << ": " << s.warnings[0];
  }
  // The default scene of a mesh says so too: one triangle has |w| < 1/2, so the default level 1/2
  // is out of reach.
  const std::string path = test::temp_path("one_triangle.obj");
  std::ofstream(path) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  SceneDesc s;
  const Status st = default_scene(path, s);
  ASSERT_TRUE(st.ok()) << st.message();
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_EQ(s.warnings[0], path + ": level 0.5 lies outside every value w takes on this mesh (|w| < 1/2): S is empty");
  std::remove(path.c_str());
}

// Item 13: a projective matrix (last row not 0 0 0 1) cannot place geometry.
TEST(SceneChecks, ProjectiveMatrixIsRefused) {
  for (const char* last : {"0, 0, 1, 1", "0, 0, 0, 2", "1e-3, 0, 0, 1", "0, 0, 0, 0", "0, 0, 0, -1"}) {
    const std::string m = std::string(R"({"matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, )") + last + "]}";
    expect_refused(R"({"meshes": [{"plane": 2, "transform": )" + m + "}]}", "/meshes/0/transform", "affine");
    expect_refused(R"({"gwn_objects": [{"file": "bunny_holes.obj", "instances": [)" + m + "]}]}",
                   "/gwn_objects/0/instances/0", "affine");
  }
  expect_accepted(R"({"meshes": [{"plane": 2, "transform": {"matrix": [2,0,0,1, 0,2,0,0, 0,0,2,0, 0,0,0,1]}}]})");
}

// Item 13: the tone curve for PNG. Its direct form v(2.51v + 0.03) / (v(2.43v + 0.59) + 0.14)
// overflowed to inf / inf = NaN (black) from v ≈ 1.8e19; every finite radiance must map into
// [0, 2.51/2.43] (the curve's limit), non-decreasing, and huge values near that limit.
TEST(SceneChecks, ToneCurveKeepsHugeRadiancesWhite) {
  const std::vector<float> values = {0.0f, 0.5f, 1.0f, 2.0f, 1e4f, 1e19f, 1e20f, 1e30f, 3.4e38f};
  Image im(int(values.size()), 1, {"R", "G", "B"});
  for (size_t i = 0; i < values.size(); ++i) im.set_rgb(int(i), 0, vec3(values[i]));
  const Image out = tone_mapped(im);
  const double limit = 2.51 / 2.43;
  float previous = -1.0f;
  for (size_t i = 0; i < values.size(); ++i) {
    const float q = out.pixel(int(i), 0)[0];
    const double v = values[i];
    // The curve in double, where none of these overflow.
    const double reference = v * (2.51 * v + 0.03) / (v * (2.43 * v + 0.59) + 0.14);
    EXPECT_NEAR(q, reference, 1e-6 * limit) << v;
    EXPECT_GE(q, previous) << v;
    previous = q;
  }
  EXPECT_NEAR(out.pixel(int(values.size()) - 1, 0)[0], limit, 1e-6);
}

}  // namespace
}  // namespace gwnrt::render
