#include "scene.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>

#include <glm/gtc/matrix_transform.hpp>
#include <nlohmann/json.hpp>

#include "gwnrt/batch.h"
#include "gwnrt/io/mesh_io.h"

namespace gwnrt::render {
namespace {

using json = nlohmann::json;

// A problem at a place in the file: thrown while reading, turned into a Status at the top.
struct SceneError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

[[noreturn]] void fail(const std::string& where, const std::string& what) { throw SceneError(where + ": " + what); }

float number(const json& j, const std::string& where) {
  if (!j.is_number()) fail(where, "expected a number");
  const double v = j.get<double>();
  if (!std::isfinite(v)) fail(where, "expected a finite number");
  return float(v);
}

vec3 vector3(const json& j, const std::string& where) {
  if (!j.is_array() || j.size() != 3) fail(where, "expected an array of 3 numbers");
  return {number(j[0], where + "/0"), number(j[1], where + "/1"), number(j[2], where + "/2")};
}

int integer(const json& j, const std::string& where, int lo, int hi) {
  if (!j.is_number_integer()) fail(where, "expected an integer");
  const long long v = j.get<long long>();
  if (v < lo || v > hi) fail(where, "must lie in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return int(v);
}

glm::mat4 transform(const json& j, const std::string& where) {
  if (!j.is_object()) fail(where, "expected a transform object");
  if (j.contains("matrix")) {
    const json& m = j["matrix"];
    if (!m.is_array() || m.size() != 16) fail(where + "/matrix", "expected 16 numbers (row-major)");
    glm::mat4 out(1.0f);
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) out[c][r] = number(m[4 * r + c], where + "/matrix/" + std::to_string(4 * r + c));
    return out;
  }
  glm::mat4 out(1.0f);
  if (j.contains("translate")) out = glm::translate(out, vector3(j["translate"], where + "/translate"));
  if (j.contains("rotate")) {
    const json& r = j["rotate"];
    if (!r.is_array() || r.size() != 4) fail(where + "/rotate", "expected [axis_x, axis_y, axis_z, degrees]");
    const vec3 axis(number(r[0], where + "/rotate/0"), number(r[1], where + "/rotate/1"),
                    number(r[2], where + "/rotate/2"));
    if (!(glm::length(axis) > 0.0f)) fail(where + "/rotate", "the axis must not be zero");
    out = glm::rotate(out, glm::radians(number(r[3], where + "/rotate/3")), glm::normalize(axis));
  }
  if (j.contains("scale")) {
    const json& s = j["scale"];
    const vec3 v = s.is_array() ? vector3(s, where + "/scale") : vec3(number(s, where + "/scale"));
    if (!(v.x != 0.0f && v.y != 0.0f && v.z != 0.0f)) fail(where + "/scale", "a scale factor is zero");
    out = glm::scale(out, v);
  }
  return out;
}

Material material(const json& j, const std::string& where) {
  if (!j.is_object() || !j.contains("type") || !j["type"].is_string()) fail(where, "expected {\"type\": ...}");
  const std::string type = j["type"].get<std::string>();
  Material m;
  if (type == "diffuse")
    m.kind = MaterialKind::kDiffuse;
  else if (type == "conductor")
    m.kind = MaterialKind::kConductor;
  else if (type == "dielectric")
    m.kind = MaterialKind::kDielectric;
  else if (type == "emissive")
    m.kind = MaterialKind::kEmissive;
  else
    fail(where + "/type", "unknown material type \"" + type + "\" (diffuse, conductor, dielectric, emissive)");
  if (j.contains("albedo")) m.albedo = vector3(j["albedo"], where + "/albedo");
  if (j.contains("roughness")) m.roughness = number(j["roughness"], where + "/roughness");
  if (j.contains("ior")) m.ior = number(j["ior"], where + "/ior");
  if (j.contains("emission")) m.emission = vector3(j["emission"], where + "/emission");
  if (m.albedo.x < 0 || m.albedo.y < 0 || m.albedo.z < 0 || m.albedo.x > 1 || m.albedo.y > 1 || m.albedo.z > 1)
    fail(where + "/albedo", "components must lie in [0, 1]");
  if (m.roughness < 0 || m.roughness > 1) fail(where + "/roughness", "must lie in [0, 1]");
  if (!(m.ior > 0.0f)) fail(where + "/ior", "must be positive");
  if (m.emission.x < 0 || m.emission.y < 0 || m.emission.z < 0) fail(where + "/emission", "must not be negative");
  return m;
}

Mesh plane_mesh(float size) {
  const float h = 0.5f * size;
  Mesh m;
  m.positions = {{-h, 0.0f, -h}, {h, 0.0f, -h}, {h, 0.0f, h}, {-h, 0.0f, h}};
  m.triangles = {{0, 2, 1}, {0, 3, 2}};  // normal +y
  return m;
}

Mesh read_mesh(const std::string& file, const std::filesystem::path& base, const std::string& where) {
  const std::filesystem::path p = std::filesystem::path(file).is_absolute() ? std::filesystem::path(file) : base / file;
  Mesh m;
  if (Status s = load_mesh(p.string(), m); !s.ok()) fail(where, s.message());
  return m;
}

void apply(const glm::mat4& t, Mesh& m) {
  for (vec3& p : m.positions) p = vec3(t * glm::vec4(p, 1.0f));
}

int material_index(const json& j, const std::string& where, const SceneDesc& scene) {
  if (!j.is_string()) fail(where, "expected a material name");
  const std::string name = j.get<std::string>();
  for (size_t i = 0; i < scene.material_names.size(); ++i)
    if (scene.material_names[i] == name) return int(i);
  fail(where, "no material named \"" + name + "\"");
}

// Calls read(entry, where) for each entry of the array j[key] (none when there is no key), where
// is the entry's JSON location for messages.
template <class Read>
void for_each_entry(const json& j, const std::string& key, Read read) {
  if (!j.contains(key)) return;
  const json& list = j[key];
  if (!list.is_array()) fail("/" + key, "expected an array");
  for (size_t i = 0; i < list.size(); ++i) read(list[i], "/" + key + "/" + std::to_string(i));
}

void read_scene(const json& j, const std::filesystem::path& base, SceneDesc& s) {
  if (!j.is_object()) fail("/", "expected a JSON object");
  {
    // What a missing "camera" block or key means.
    vec3 eye(0.0f, 0.0f, 5.0f), target(0.0f), up(0.0f, 1.0f, 0.0f);
    float fov_degrees = 40.0f;  // vertical
    int width = 640, height = 480;
    if (j.contains("camera")) {
      const json& c = j["camera"];
      if (c.contains("eye")) eye = vector3(c["eye"], "/camera/eye");
      if (c.contains("target")) target = vector3(c["target"], "/camera/target");
      if (c.contains("up")) up = vector3(c["up"], "/camera/up");
      if (c.contains("fov")) fov_degrees = number(c["fov"], "/camera/fov");
      if (c.contains("width")) width = integer(c["width"], "/camera/width", 1, 1 << 15);
      if (c.contains("height")) height = integer(c["height"], "/camera/height", 1, 1 << 15);
      if (!(fov_degrees > 0.0f && fov_degrees < 180.0f)) fail("/camera/fov", "must lie in (0, 180)");
      if (!(glm::length(target - eye) > 0.0f)) fail("/camera", "eye and target coincide");
    }
    s.camera = examples::look_at(eye, target, up, fov_degrees, width, height);
  }
  if (j.contains("render")) {
    const json& r = j["render"];
    if (r.contains("spp")) s.render.spp = integer(r["spp"], "/render/spp", 1, 1 << 20);
    if (r.contains("max_depth")) s.render.max_depth = integer(r["max_depth"], "/render/max_depth", 1, 1000);
    if (r.contains("seed")) s.render.seed = uint64_t(integer(r["seed"], "/render/seed", 0, 1 << 30));
  }
  if (j.contains("materials")) {
    if (!j["materials"].is_object()) fail("/materials", "expected an object of named materials");
    for (const auto& [name, m] : j["materials"].items()) {
      s.materials.push_back(material(m, "/materials/" + name));
      s.material_names.push_back(name);
    }
  }
  if (s.materials.empty()) {
    s.materials.push_back(Material{});
    s.material_names.push_back("default");
  }
  for_each_entry(j, "meshes", [&](const json& e, const std::string& where) {
    MeshDesc d;
    if (e.contains("plane")) {
      d.mesh = plane_mesh(number(e["plane"], where + "/plane"));
      d.source = "plane";
    } else if (e.contains("file") && e["file"].is_string()) {
      d.source = e["file"].get<std::string>();
      d.mesh = read_mesh(d.source, base, where + "/file");
    } else {
      fail(where, "expected \"file\" or \"plane\"");
    }
    if (e.contains("transform")) apply(transform(e["transform"], where + "/transform"), d.mesh);
    d.material = e.contains("material") ? material_index(e["material"], where + "/material", s) : 0;
    s.meshes.push_back(std::move(d));
  });
  for_each_entry(j, "gwn_objects", [&](const json& e, const std::string& where) {
    GwnObjectDesc d;
    if (!e.contains("file") || !e["file"].is_string()) fail(where, "expected \"file\"");
    d.source = e["file"].get<std::string>();
    d.mesh = read_mesh(d.source, base, where + "/file");
    if (e.contains("mode")) {
      const std::string mode = e["mode"].is_string() ? e["mode"].get<std::string>() : "";
      if (mode == "gwn")
        d.options.mode = TraceMode::kWindingNumber;
      else if (mode == "solid-angle")
        d.options.mode = TraceMode::kSolidAngle;
      else
        fail(where + "/mode", "expected \"gwn\" or \"solid-angle\"");
    }
    if (e.contains("level")) d.options.level = number(e["level"], where + "/level");
    if (e.contains("epsilon")) d.options.epsilon = number(e["epsilon"], where + "/epsilon");
    if (e.contains("max_steps"))
      d.options.max_steps = uint32_t(integer(e["max_steps"], where + "/max_steps", 1, 1 << 30));
    if (e.contains("beta")) d.options.beta = number(e["beta"], where + "/beta");
    if (e.contains("instances")) {
      if (!e["instances"].is_array()) fail(where + "/instances", "expected an array of transforms");
      for (size_t k = 0; k < e["instances"].size(); ++k)
        d.instances.push_back(transform(e["instances"][k], where + "/instances/" + std::to_string(k)));
    } else {
      d.instances.push_back(e.contains("transform") ? transform(e["transform"], where + "/transform")
                                                    : glm::mat4(1.0f));
    }
    d.material = e.contains("material") ? material_index(e["material"], where + "/material", s) : 0;
    s.gwn_objects.push_back(std::move(d));
  });
  if (j.contains("environment")) {
    const json& e = j["environment"];
    if (e.contains("file")) {
      if (!e["file"].is_string()) fail("/environment/file", "expected a path");
      const std::filesystem::path p(e["file"].get<std::string>());
      s.environment.file = (p.is_absolute() ? p : base / p).string();
    }
    if (e.contains("radiance")) s.environment.radiance = vector3(e["radiance"], "/environment/radiance");
    if (e.contains("scale")) s.environment.scale = number(e["scale"], "/environment/scale");
  }
  if (j.contains("sun")) {
    const json& e = j["sun"];
    if (e.contains("direction")) {
      const vec3 d = vector3(e["direction"], "/sun/direction");
      if (!(glm::length(d) > 0.0f)) fail("/sun/direction", "must not be zero");
      s.sun.direction = glm::normalize(d);
    }
    if (e.contains("radiance")) s.sun.radiance = vector3(e["radiance"], "/sun/radiance");
    if (e.contains("angular_radius")) s.sun.angular_radius = number(e["angular_radius"], "/sun/angular_radius");
    if (!(s.sun.angular_radius > 0.0f && s.sun.angular_radius < 1.0f))
      fail("/sun/angular_radius", "must lie in (0, 1) radians");
  }
  for (const GwnObjectDesc& g : s.gwn_objects)
    if (Status st = validate_trace_options(g.options); !st.ok()) fail("/gwn_objects", st.message());
}

}  // namespace

Status load_scene(const std::string& path, SceneDesc& out) {
  std::ifstream in(path);
  if (!in) return {StatusCode::kIoError, path + ": cannot open the scene file"};
  json j;
  try {
    j = json::parse(in);
  } catch (const json::parse_error& e) {
    return {StatusCode::kParseError, path + ": not valid JSON (" + std::string(e.what()) + ")"};
  }
  SceneDesc scene;
  try {
    read_scene(j, std::filesystem::path(path).parent_path(), scene);
  } catch (const SceneError& e) {
    return {StatusCode::kInvalidArgument, path + ": " + e.what()};
  }
  out = std::move(scene);
  return Status::Ok();
}

Aabb scene_bounds(const SceneDesc& scene) {
  Aabb box;
  for (const MeshDesc& m : scene.meshes)
    for (const vec3& p : m.mesh.positions) box.extend(p);
  for (const GwnObjectDesc& g : scene.gwn_objects)
    for (const glm::mat4& t : g.instances)
      for (const vec3& p : g.mesh.positions) box.extend(vec3(t * glm::vec4(p, 1.0f)));
  return box;
}

Status default_scene(const std::string& mesh_path, SceneDesc& out) {
  SceneDesc s;
  GwnObjectDesc object;
  object.source = mesh_path;
  if (Status st = load_mesh(mesh_path, object.mesh); !st.ok()) return st;
  if (object.mesh.positions.empty()) return {StatusCode::kInvalidMesh, mesh_path + ": the mesh has no vertices"};
  Aabb box;
  for (const vec3& p : object.mesh.positions) box.extend(p);
  // Stand the mesh on the ground (y = 0), centred, whatever its units.
  const vec3 centre = box.centre();
  object.instances.push_back(glm::translate(glm::mat4(1.0f), vec3(-centre.x, -box.lo.y, -centre.z)));
  object.material = 0;
  s.materials = {Material{MaterialKind::kDiffuse, Spectrum(0.8f)}, Material{MaterialKind::kDiffuse, Spectrum(0.5f)}};
  s.material_names = {"object", "ground"};
  s.gwn_objects.push_back(std::move(object));
  const vec3 extent = box.hi - box.lo;
  const float size = std::max(extent.x, std::max(extent.y, extent.z));
  MeshDesc ground;
  ground.source = "plane";
  ground.mesh = plane_mesh(20.0f * size);
  ground.material = 1;
  s.meshes.push_back(std::move(ground));
  s.environment.radiance = Spectrum(0.45f, 0.55f, 0.7f);
  s.sun.direction = glm::normalize(vec3(0.4f, 0.8f, 0.45f));
  // The disc subtends π·r² ≈ 6.8e-5 sr: irradiance about 1.3, like the sky's π · 0.55.
  s.sun.radiance = Spectrum(2.0e4f, 1.9e4f, 1.7e4f);
  // Frame the object's bounding sphere from the front-right, slightly above.
  const float radius = 0.5f * glm::length(extent);
  const vec3 look = vec3(0.0f, 0.5f * extent.y, 0.0f);
  const float fov_degrees = 35.0f;
  const float distance = 1.3f * radius / std::tan(0.5f * glm::radians(fov_degrees));
  s.camera = examples::look_at(look + distance * glm::normalize(vec3(0.55f, 0.35f, 0.9f)), look, vec3(0.0f, 1.0f, 0.0f),
                               fov_degrees, 640, 480);
  out = std::move(s);
  return Status::Ok();
}

}  // namespace gwnrt::render
