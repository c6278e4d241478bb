#include "render/scene.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <initializer_list>
#include <limits>
#include <set>
#include <stdexcept>

#include <glm/gtc/matrix_transform.hpp>
#include <nlohmann/json.hpp>

#include "apps/common/trace_level.h"
#include "gwnrt/io/mesh_io.h"
#include "gwnrt/io/read_file.h"
#include "gwnrt/query/validation.h"

namespace gwnrt::render {
namespace {

using json = nlohmann::json;
using glm::dvec3;

// What float arithmetic carries through Embree, and so what a scene may hold.
//
// Coordinates: Embree takes a ray only if every component of its origin is within FLT_LARGE
// (1.8e18; beyond, its ray.valid() assertion aborts), and its triangle test multiplies three
// coordinate differences: with every coordinate within ±L, the distance term
// dot(v0 − origin, cross(e1, e2)) reaches 3 · 2L · 2(2L)² = 48 L³, which stays below float's
// largest value (3.4e38) for L up to 1.9e12. So the eye, the target and every vertex in world
// space must lie within ±1e12 (48e36 ≈ 5e37: a margin of 7). Every ray the path tracer shoots
// starts at the eye or at a hit point (moved by 1e-4 of the scene's radius), so this also bounds
// every ray origin.
constexpr double kMaxCoordinate = 1e12;
// At the other end the same cubic term must stay a normal float (above 1.2e-38): a scene
// smaller than 1e-12 across makes it 1e-36 or less, and Embree's triangles vanish (their normal,
// a product of two edges, underflows first).
constexpr double kMinSceneSize = 1e-12;
// Transforms: Embree inverts an instance's transform in float (the adjugate over the
// determinant, a product of three scale factors) and hands the tracer the ray in object space,
// its direction not normalised. Scale factors within [1e-12, 1e12] keep the determinant
// (1e±36) and the object-space direction's squared length (1e±24) normal floats; the factors are
// bounded here by the Frobenius norms of the 3×3 part and of its inverse (each within √3 of the
// largest factor, and of the inverse of the smallest).
constexpr double kMaxTransformScale = 1e12;
// The inverse computed in float has a relative error of about κ · 2⁻²⁴ for the condition number
// κ (the largest scale factor over the smallest; bounded here by the product of the two norms):
// at 1e6, a few percent in shape; a nearly singular transform (a zero scale, an all-zero or
// rank-deficient matrix) would give rays in object space that mean nothing.
constexpr double kMaxTransformCondition = 1e6;
// The image's horizontal is the normalised cross product of the view direction and "up": float
// rounding (about 1e-7 on unit vectors) tilts it by 1e-7 / sin(angle), so the two must be at
// least 1e-3 (0.06 degrees) apart for it to be good to 1e-4.
constexpr double kMinUpSine = 1e-3;
// Refraction scales a path's throughput by the square of the index ratio at each crossing:
// indices in [0.01, 100] keep that factor within 1e±4, where anything else is no known material.
constexpr double kMinIor = 0.01, kMaxIor = 100.0;
// A scene file is a few kilobytes; this stops a stream that never ends (/dev/zero) or a wrong
// file well before memory does.
constexpr uint64_t kMaxSceneFileBytes = uint64_t(64) << 20;

// A problem at a place in the file: thrown while reading, turned into a Status at the top.
struct SceneError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

[[noreturn]] void fail(const std::string& where, const std::string& what) {
  throw SceneError((where.empty() ? std::string("/") : where) + ": " + what);
}

std::string number_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// The JSON pointer (RFC 6901) of `key` inside `where`: "~" and "/" in keys are escaped.
std::string at(const std::string& where, const std::string& key) {
  std::string token;
  for (char c : key) token += c == '~' ? std::string("~0") : c == '/' ? std::string("~1") : std::string(1, c);
  return where + "/" + token;
}

std::string at(const std::string& where, size_t index) { return where + "/" + std::to_string(index); }

// JSON lets an object give a key twice, and nlohmann keeps the last: a second "camera" (a
// forgotten `{}`, say) silently replaced the first, and readers differ on which one they keep.
// Called by the parser at each event (json::parse's callback), this follows where in the text it
// is, and refuses a key its object already has, naming it by its JSON location.
class DuplicateKeyCheck {
 public:
  bool operator()(int /*depth*/, json::parse_event_t event, const json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
        levels_.emplace_back(true);
        break;
      case json::parse_event_t::array_start:
        levels_.emplace_back(false);
        break;
      case json::parse_event_t::key: {
        Level& object = levels_.back();
        object.key = parsed.get<std::string>();
        if (!object.keys.insert(object.key).second)
          fail(at(location_of_top(), object.key), "duplicate key (the object has it already; give each key once)");
        break;
      }
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        levels_.pop_back();
        element_done();
        break;
      case json::parse_event_t::value:
        element_done();
        break;
    }
    return true;  // keep everything: this only checks
  }

 private:
  // An object being read (its keys so far, the latest one) or an array (the index of the
  // element being read).
  struct Level {
    explicit Level(bool is_object) : object(is_object) {}
    bool object;
    std::set<std::string> keys;
    std::string key;
    size_t index = 0;
  };

  // A value ended (a number, a string, a whole object or array): in an array, the next one is
  // the next index.
  void element_done() {
    if (!levels_.empty() && !levels_.back().object) ++levels_.back().index;
  }

  // The JSON pointer of the innermost object or array: each enclosing level's current key or
  // index.
  std::string location_of_top() const {
    std::string where;
    for (size_t i = 0; i + 1 < levels_.size(); ++i)
      where = levels_[i].object ? at(where, levels_[i].key) : at(where, levels_[i].index);
    return where;
  }

  std::vector<Level> levels_;
};

// Refuses any key of the object `j` that is not in `allowed`: a misspelt key is an error, not a
// silently kept default.
void check_keys(const json& j, const std::string& where, std::initializer_list<const char*> allowed) {
  for (const auto& item : j.items()) {
    if (std::any_of(allowed.begin(), allowed.end(), [&](const char* a) { return item.key() == a; })) continue;
    std::string list;
    for (const char* a : allowed) list += (list.empty() ? "\"" : ", \"") + std::string(a) + "\"";
    fail(at(where, item.key()), "unknown key (expected " + list + ")");
  }
}

// `j`, which must be a JSON object (a section such as "camera", or a list's entry).
const json& object(const json& j, const std::string& where, const std::string& what) {
  if (!j.is_object()) fail(where, "expected an object (" + what + "), got " + j.type_name());
  return j;
}

// The member `key` of the object `j`, or nullptr.
const json* member(const json& j, const char* key) {
  const auto it = j.find(key);
  return it == j.end() ? nullptr : &*it;
}

// A finite number within float's range: the renderer computes in float, where a double such as
// 1e39 would become inf.
double real(const json& j, const std::string& where) {
  if (!j.is_number()) fail(where, std::string("expected a number, got ") + j.type_name());
  const double v = j.get<double>();
  if (!std::isfinite(v)) fail(where, "expected a finite number");
  if (std::fabs(v) > double(FLT_MAX)) fail(where, number_text(v) + " is beyond float's range (±3.4e38)");
  return v;
}

float number(const json& j, const std::string& where) { return float(real(j, where)); }

dvec3 vector3(const json& j, const std::string& where) {
  if (!j.is_array() || j.size() != 3) fail(where, "expected an array of 3 numbers");
  return {real(j[0], at(where, 0)), real(j[1], at(where, 1)), real(j[2], at(where, 2))};
}

int integer(const json& j, const std::string& where, int lo, int hi) {
  if (!j.is_number_integer()) fail(where, std::string("expected an integer, got ") + j.type_name());
  // Non-negative integers arrive as unsigned: compared as such, a value past int64's range
  // cannot wrap around into [lo, hi].
  const bool in_range = j.is_number_unsigned()
                            ? j.get<uint64_t>() <= uint64_t(hi) && (lo <= 0 || j.get<uint64_t>() >= uint64_t(lo))
                            : j.get<int64_t>() >= lo && j.get<int64_t>() <= hi;
  if (!in_range) fail(where, "must lie in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return int(j.get<int64_t>());
}

// A radiance (emission, environment, sun): not negative and at most kMaxRadiance.
Spectrum radiance(const json& j, const std::string& where) {
  const dvec3 v = vector3(j, where);
  for (int c = 0; c < 3; ++c) {
    if (v[c] < 0.0) fail(at(where, size_t(c)), "a radiance must not be negative");
    if (v[c] > double(kMaxRadiance)) {
      fail(at(where, size_t(c)), number_text(v[c]) + " is above " + number_text(double(kMaxRadiance)) +
                                     ", the largest radiance whose paths' sums stay finite in float");
    }
  }
  return Spectrum(v);
}

// A point of the world (the eye, the target, a vertex): within ±kMaxCoordinate.
bool within_coordinates(const dvec3& p) {
  return std::fabs(p.x) <= kMaxCoordinate && std::fabs(p.y) <= kMaxCoordinate && std::fabs(p.z) <= kMaxCoordinate;
}

double largest_magnitude(const dvec3& p) { return std::max({std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)}); }

const std::string kCoordinateLimit =
    "beyond the ±1e12 that ray tracing in float (Embree) can carry; scale the scene down or move it toward the "
    "origin";

// Boxes in double: bounds of what the float scene holds, without rounding on the way.
struct Box {
  dvec3 lo{std::numeric_limits<double>::infinity()}, hi{-std::numeric_limits<double>::infinity()};
  void extend(const dvec3& p) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  void extend(const Box& b) {
    if (b.valid()) {
      extend(b.lo);
      extend(b.hi);
    }
  }
  bool valid() const { return lo.x <= hi.x; }
  dvec3 corner(int k) const { return {k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z}; }
};

// The camera at `eye` looking at `target`, after checking that it makes finite rays that mean
// something: the eye and the target within the coordinate limit and apart, "up"
// neither zero nor (nearly) along the view direction. The direction and "up" are normalised in
// double from the floats the camera keeps, so that tiny differences and tiny "up" vectors
// (whose squares underflow float) are no trouble.
render::PinholeCamera make_camera(const vec3& eye, const vec3& target, const vec3& up, float fov_degrees, int width,
                                  int height, const std::string& where) {
  if (!within_coordinates(dvec3(eye)))
    fail(at(where, "eye"), "at " + number_text(largest_magnitude(dvec3(eye))) + ", " + kCoordinateLimit);
  if (!within_coordinates(dvec3(target)))
    fail(at(where, "target"), "at " + number_text(largest_magnitude(dvec3(target))) + ", " + kCoordinateLimit);
  if (!(fov_degrees > 0.0f && fov_degrees < 180.0f)) fail(at(where, "fov"), "must lie in (0, 180) degrees");
  const dvec3 view = dvec3(target) - dvec3(eye);
  const double distance = glm::length(view);
  if (!(distance > 0.0)) fail(where, "the eye and the target coincide: there is no view direction");
  const double up_length = glm::length(dvec3(up));
  if (!(up_length > 0.0)) fail(at(where, "up"), "must not be zero");
  const dvec3 forward = view / distance, up_unit = dvec3(up) / up_length;
  if (!(glm::length(glm::cross(forward, up_unit)) >= kMinUpSine)) {
    fail(at(where, "up"),
         "is parallel to the view direction (eye to target), within 0.06 degrees: the image's horizontal is "
         "undefined");
  }
  render::PinholeCamera cam = render::look_along(eye, vec3(forward), vec3(up_unit), fov_degrees, width, height);
  // fov just below 180 can round to a half angle at or past 90 degrees in float.
  if (!(cam.tan_half_fov > 0.0f && std::isfinite(cam.tan_half_fov)))
    fail(at(where, "fov"), "too close to 180 degrees for float");
  return cam;
}

Mesh plane_mesh(float size) {
  const float h = 0.5f * size;
  Mesh m;
  m.positions = {{-h, 0.0f, -h}, {h, 0.0f, -h}, {h, 0.0f, h}, {-h, 0.0f, h}};
  m.triangles = {{0, 2, 1}, {0, 3, 2}};  // normal +y
  return m;
}

// A transform the renderer can carry (see kMaxTransformScale and kMaxTransformCondition above):
// finite, affine, its scale factors within 1e±12 and not nearly singular.
void check_transform(const glm::dmat4& m, const std::string& where) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!(std::fabs(m[c][r]) <= double(FLT_MAX)))
        fail(where, "the transform overflows float (an entry is beyond float's range)");
  if (m[0][3] != 0.0 || m[1][3] != 0.0 || m[2][3] != 0.0 || m[3][3] != 1.0)
    fail(where, "not an affine transform: the last row must be 0 0 0 1 (a projective matrix cannot place geometry)");
  const glm::dmat3 a(m);
  const double det = glm::determinant(a);
  if (!(det != 0.0) || !std::isfinite(det))
    fail(where, "singular (its 3x3 part has determinant 0): it flattens the geometry to a plane, a line or a point");
  const auto norm = [](const glm::dmat3& x) {
    double s = 0.0;
    for (int c = 0; c < 3; ++c) s += glm::dot(x[c], x[c]);
    return std::sqrt(s);
  };
  const double scale = norm(a), inverse_scale = norm(glm::inverse(a));
  if (!(scale <= kMaxTransformScale))
    fail(where, "scales by about " + number_text(scale) + ", beyond the factor 1e12 that float can carry");
  if (!(inverse_scale <= kMaxTransformScale))
    fail(where,
         "scales by about " + number_text(1.0 / inverse_scale) + ", below the factor 1e-12 that float can carry");
  if (!(scale * inverse_scale <= kMaxTransformCondition)) {
    fail(where, "nearly singular: its scale factors differ by a factor of about " + number_text(scale * inverse_scale) +
                    ", beyond 1e6");
  }
}

// A scene file's transform, computed in double: a recentred mesh's origin is composed with it
// (placed) before float keeps the result for Embree; check_transform says whether float can.
glm::dmat4 transform(const json& j, const std::string& where) {
  object(j, where, "a transform");
  glm::dmat4 out(1.0);
  if (const json* m = member(j, "matrix")) {
    if (j.size() > 1) fail(where, "give \"matrix\" alone, or \"translate\", \"rotate\" and \"scale\"");
    const std::string mw = at(where, "matrix");
    if (!m->is_array() || m->size() != 16) fail(mw, "expected 16 numbers (row-major)");
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) out[c][r] = real((*m)[size_t(4 * r + c)], at(mw, size_t(4 * r + c)));
    // The last row as float reads it (as it was read before transforms were kept in double):
    // 1.0000000001 there is 1, and the matrix affine.
    for (int c = 0; c < 4; ++c) out[c][3] = double(float(out[c][3]));
  } else {
    check_keys(j, where, {"translate", "rotate", "scale", "matrix"});
    if (const json* t = member(j, "translate")) out = glm::translate(out, vector3(*t, at(where, "translate")));
    if (const json* r = member(j, "rotate")) {
      const std::string rw = at(where, "rotate");
      if (!r->is_array() || r->size() != 4) fail(rw, "expected [axis_x, axis_y, axis_z, degrees]");
      const dvec3 axis(real((*r)[0], at(rw, 0)), real((*r)[1], at(rw, 1)), real((*r)[2], at(rw, 2)));
      const double length = glm::length(axis);
      if (!(length > 0.0)) fail(rw, "the axis must not be zero");
      // The angle reduced first: the radians of a huge angle would lose the turn.
      const double degrees = std::fmod(real((*r)[3], at(rw, 3)), 360.0);
      out = glm::rotate(out, glm::radians(degrees), axis / length);
    }
    if (const json* s = member(j, "scale")) {
      const std::string sw = at(where, "scale");
      const dvec3 v = s->is_array() ? vector3(*s, sw) : dvec3(real(*s, sw));
      if (!(v.x != 0.0 && v.y != 0.0 && v.z != 0.0)) fail(sw, "a scale factor is zero");
      out = glm::scale(out, v);
    }
  }
  check_transform(out, where);
  return out;
}

// What a scene file places in its world, kept in double until the scene's own origin is known
// (read_scene): a mesh's coordinates, recentred when it was loaded, are positions + origin in the
// file's; a transform takes them to the file's world; the scene is then moved by -scene_origin
// (nonzero for a scene far from the origin for its size) before float keeps it for Embree.
struct Placement {
  glm::dmat4 transform{1.0};  // the file's transform, or the identity
  dvec3 origin{0.0};          // the mesh's MeshLoadReport::origin
  // Object (the mesh as loaded) to the file's world.
  glm::dmat4 world_from_object() const { return glm::translate(transform, origin); }
};

// The box of what `m` draws, its triangles' corners, placed by `t`: a vertex no triangle uses (a
// stray point in a scan, or the file's origin) would move a camera or a scene's origin away from
// the mesh. Invalid for a mesh without triangles.
Box drawn_box(const Mesh& m, const glm::dmat4& t = glm::dmat4(1.0)) {
  Box box;
  for (const uvec3& tri : m.triangles)
    for (int k = 0; k < 3; ++k) box.extend(dvec3(t * glm::dvec4(dvec3(m.positions[tri[k]]), 1.0)));
  return box;
}

// The float transform Embree gets for an instance: its placement moved by -scene_origin.
glm::mat4 instance_transform(const Placement& p, const dvec3& scene_origin, const std::string& where) {
  if (p.origin == dvec3(0.0) && scene_origin == dvec3(0.0)) return glm::mat4(p.transform);
  const glm::dmat4 out = glm::translate(glm::dmat4(1.0), -scene_origin) * p.world_from_object();
  check_transform(out, where);  // the translation may leave float's range
  return glm::mat4(out);
}

Material material(const json& j, const std::string& where) {
  object(j, where, "a material");
  const json* type_json = member(j, "type");
  if (!type_json || !type_json->is_string()) fail(where, "expected {\"type\": ...}");
  const std::string type = type_json->get<std::string>();
  Material m;
  if (type == "diffuse") {
    m.kind = MaterialKind::kDiffuse;
    check_keys(j, where, {"type", "albedo"});
  } else if (type == "conductor") {
    m.kind = MaterialKind::kConductor;
    check_keys(j, where, {"type", "albedo", "roughness"});
  } else if (type == "dielectric") {
    m.kind = MaterialKind::kDielectric;
    check_keys(j, where, {"type", "ior"});
  } else if (type == "emissive") {
    m.kind = MaterialKind::kEmissive;
    check_keys(j, where, {"type", "emission"});
  } else {
    fail(at(where, "type"), "unknown material type \"" + type + "\" (diffuse, conductor, dielectric, emissive)");
  }
  if (const json* a = member(j, "albedo")) {
    const dvec3 v = vector3(*a, at(where, "albedo"));
    if (v.x < 0 || v.y < 0 || v.z < 0 || v.x > 1 || v.y > 1 || v.z > 1)
      fail(at(where, "albedo"), "components must lie in [0, 1]");
    m.albedo = vec3(v);
  }
  if (const json* r = member(j, "roughness")) {
    m.roughness = number(*r, at(where, "roughness"));
    if (m.roughness < 0 || m.roughness > 1) fail(at(where, "roughness"), "must lie in [0, 1]");
  }
  if (const json* i = member(j, "ior")) {
    const double ior = real(*i, at(where, "ior"));
    if (!(ior >= kMinIor && ior <= kMaxIor)) fail(at(where, "ior"), "must lie in [0.01, 100]");
    m.ior = float(ior);
  }
  if (const json* e = member(j, "emission")) m.emission = radiance(*e, at(where, "emission"));
  return m;
}

// A mesh file of the scene, recentred when far from the origin for its size: the file's
// coordinates are then positions + origin, in double (see Placement); origin is 0 otherwise.
Mesh read_mesh(const json& file, const std::filesystem::path& base, const std::string& where, SceneDesc& scene,
               dvec3& origin) {
  if (!file.is_string()) fail(where, std::string("expected a file name, got ") + file.type_name());
  const std::string name = file.get<std::string>();
  const std::filesystem::path p = std::filesystem::path(name).is_absolute() ? std::filesystem::path(name) : base / name;
  Mesh m;
  MeshLoadReport report;
  if (Status s = load_mesh(p.string(), m, &report, MeshLoadOptions{.recentre = true}); !s.ok())
    fail(where, s.message());
  origin = report.origin;
  scene.loaded_meshes.push_back({p.string(), report});
  return m;
}

// Moves a triangle mesh's vertices into world space (where Embree takes them), less
// scene_origin: in double when either origin is nonzero; in float otherwise, as before.
void apply(const Placement& placement, const dvec3& scene_origin, Mesh& m) {
  if (placement.origin == dvec3(0.0) && scene_origin == dvec3(0.0)) {
    if (placement.transform == glm::dmat4(1.0)) return;
    const glm::mat4 tf(placement.transform);
    for (vec3& p : m.positions) p = vec3(tf * glm::vec4(p, 1.0f));
    return;
  }
  const glm::dmat4 t = glm::translate(glm::dmat4(1.0), -scene_origin) * placement.world_from_object();
  // A vertex beyond float's range rounds to infinity (IEEE), which check_geometry reports.
  for (vec3& p : m.positions) p = vec3(t * glm::dvec4(dvec3(p), 1.0));
}

int material_index(const json& j, const std::string& where, const SceneDesc& scene) {
  if (!j.is_string()) fail(where, std::string("expected a material name, got ") + j.type_name());
  const std::string name = j.get<std::string>();
  for (size_t i = 0; i < scene.material_names.size(); ++i)
    if (scene.material_names[i] == name) return int(i);
  fail(where, "no material named \"" + name + "\"");
}

// Calls read(entry, where) for each entry of the array j[key] (none when there is no key), where
// is the entry's JSON location for messages.
template <class Read>
void for_each_entry(const json& j, const char* key, Read read) {
  const json* list = member(j, key);
  if (!list) return;
  const std::string where = at("", key);
  if (!list->is_array()) fail(where, std::string("expected an array, got ") + list->type_name());
  for (size_t i = 0; i < list->size(); ++i) read((*list)[i], at(where, i));
}

// Where each part of a SceneDesc came from, for the messages of check_geometry.
struct Locations {
  std::string scene;                                // the whole scene
  std::string camera;                               // the camera (its eye)
  std::vector<std::string> meshes;                  // per SceneDesc::meshes
  std::vector<std::vector<std::string>> instances;  // per SceneDesc::gwn_objects, per instance
};

// The checks that need the whole scene: every vertex in world space within the
// coordinate limit, the scene not too small for float, and every instance's object space able to
// hold the rays it will be given: all start within the box of the geometry and the eye, so that
// box's corners, taken to object space, must be within the limit too.
void check_geometry(const SceneDesc& s, const Locations& where) {
  Box geometry;
  for (size_t i = 0; i < s.meshes.size(); ++i) {
    Box box;
    for (const vec3& p : s.meshes[i].mesh.positions) {
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        fail(where.meshes[i], "its transform overflows float: a vertex is not finite in world space");
      box.extend(dvec3(p));
    }
    if (box.valid() && !(within_coordinates(box.lo) && within_coordinates(box.hi))) {
      fail(where.meshes[i], "its vertices reach " +
                                number_text(std::max(largest_magnitude(box.lo), largest_magnitude(box.hi))) +
                                " in world space, " + kCoordinateLimit);
    }
    geometry.extend(box);
  }
  for (size_t i = 0; i < s.gwn_objects.size(); ++i) {
    const GwnObjectDesc& g = s.gwn_objects[i];
    Box object;
    for (const vec3& p : g.mesh.positions) object.extend(dvec3(p));
    if (!object.valid()) continue;  // no vertices: the plugin refuses the mesh, naming it
    for (size_t k = 0; k < g.instances.size(); ++k) {
      const glm::dmat4 t(g.instances[k]);
      Box world;
      for (int c = 0; c < 8; ++c) world.extend(dvec3(t * glm::dvec4(object.corner(c), 1.0)));
      if (!(within_coordinates(world.lo) && within_coordinates(world.hi))) {
        fail(where.instances[i][k],
             "places the object at coordinates up to " +
                 number_text(std::max(largest_magnitude(world.lo), largest_magnitude(world.hi))) + ", " +
                 kCoordinateLimit);
      }
      geometry.extend(world);
    }
  }
  if (geometry.valid() && !(glm::length(geometry.hi - geometry.lo) >= kMinSceneSize)) {
    fail(where.scene, "the scene's geometry is " + number_text(glm::length(geometry.hi - geometry.lo)) +
                          " across, below the 1e-12 that ray tracing in float can resolve; scale it up");
  }
  Box reach = geometry;  // where rays start: the eye and points on the geometry
  reach.extend(dvec3(s.camera.eye));
  for (size_t i = 0; i < s.gwn_objects.size(); ++i) {
    for (size_t k = 0; k < s.gwn_objects[i].instances.size(); ++k) {
      const glm::dmat4 inverse = glm::inverse(glm::dmat4(s.gwn_objects[i].instances[k]));
      double farthest = 0.0;
      for (int c = 0; c < 8; ++c)
        farthest = std::max(farthest, largest_magnitude(dvec3(inverse * glm::dvec4(reach.corner(c), 1.0))));
      if (!(farthest <= kMaxCoordinate)) {
        fail(where.instances[i][k], "in its object space (the inverse transform) the eye and the scene lie up to " +
                                        number_text(farthest) + " away, " + kCoordinateLimit +
                                        " (or give the object a larger scale)");
      }
    }
  }
}

// A GWN object whose level w never reaches renders nothing, which the image alone does not
// explain: the scene keeps a warning, worded as gwnrt-trace's (trace_level.h). The count is the
// mesh's own, zero-area triangles included (the plugin's model leaves them out): the bound still
// holds, so the warning is never wrong.
void note_level_out_of_reach(const GwnObjectDesc& object, const std::string& where, SceneDesc& s) {
  const uint32_t triangles = uint32_t(std::min<size_t>(object.mesh.triangles.size(), UINT32_MAX));
  if (const auto why = apps::level_out_of_reach(triangles, object.options)) s.warnings.push_back(where + ": " + *why);
}

// A scene file's "camera" block, its eye and target in double (the scene may be moved).
struct CameraDesc {
  // What a missing "camera" block or key means.
  dvec3 eye{0.0, 0.0, 5.0}, target{0.0}, up{0.0, 1.0, 0.0};
  float fov_degrees = 40.0f;  // vertical
  int width = 640, height = 480;

  // The camera, in the scene moved by -scene_origin.
  render::PinholeCamera make(const dvec3& scene_origin, const std::string& where) const {
    return make_camera(vec3(eye - scene_origin), vec3(target - scene_origin), vec3(up), fov_degrees, width, height,
                       where);
  }
};

CameraDesc read_camera(const json* c, Locations& where) {
  CameraDesc cam;
  where.camera = "/camera";
  if (c) {
    object(*c, where.camera, "the camera");
    check_keys(*c, where.camera, {"eye", "target", "up", "fov", "width", "height"});
    if (const json* v = member(*c, "eye")) cam.eye = vector3(*v, "/camera/eye");
    if (const json* v = member(*c, "target")) cam.target = vector3(*v, "/camera/target");
    if (const json* v = member(*c, "up")) cam.up = vector3(*v, "/camera/up");
    if (const json* v = member(*c, "fov")) cam.fov_degrees = number(*v, "/camera/fov");
    if (const json* v = member(*c, "width")) cam.width = integer(*v, "/camera/width", 1, 1 << 15);
    if (const json* v = member(*c, "height")) cam.height = integer(*v, "/camera/height", 1, 1 << 15);
  }
  // Checked as given, so that its errors come first (an eye beyond the coordinate limit is
  // refused even where the scene would be moved); made again once the scene's origin is known.
  cam.make(dvec3(0.0), where.camera);
  return cam;
}

void read_render(const json& r, RenderSettings& settings) {
  object(r, "/render", "the render settings");
  check_keys(r, "/render", {"spp", "max_depth", "seed"});
  if (const json* v = member(r, "spp")) settings.spp = integer(*v, "/render/spp", 1, kMaxSpp);
  if (const json* v = member(r, "max_depth")) settings.max_depth = integer(*v, "/render/max_depth", 1, kMaxPathDepth);
  if (const json* v = member(r, "seed")) settings.seed = uint64_t(integer(*v, "/render/seed", 0, kMaxSeed));
}

void read_environment(const json& e, const std::filesystem::path& base, EnvironmentDesc& env) {
  const std::string where = "/environment";
  object(e, where, "{\"radiance\": [r, g, b]} or {\"file\": ..., \"scale\": s}");
  if (member(e, "file") && member(e, "radiance"))
    fail(where, "give \"radiance\" (a constant sky) or \"file\" (an image), not both");
  if (member(e, "scale") && !member(e, "file")) fail(at(where, "scale"), "scales an image \"file\": there is none");
  if (member(e, "file")) {
    check_keys(e, where, {"file", "scale"});
    const json& f = e["file"];
    if (!f.is_string()) fail(at(where, "file"), std::string("expected a path, got ") + f.type_name());
    const std::filesystem::path p(f.get<std::string>());
    env.file = (p.is_absolute() ? p : base / p).string();
    if (const json* s = member(e, "scale")) {
      env.scale = number(*s, at(where, "scale"));
      if (!(env.scale >= 0.0f && env.scale <= kMaxRadiance))
        fail(at(where, "scale"), "must lie in [0, " + number_text(double(kMaxRadiance)) + "]");
    }
  } else {
    check_keys(e, where, {"radiance", "file", "scale"});
    if (const json* r = member(e, "radiance")) env.radiance = radiance(*r, at(where, "radiance"));
  }
}

void read_sun(const json& e, Sun& sun) {
  object(e, "/sun", "the sun");
  check_keys(e, "/sun", {"direction", "radiance", "angular_radius"});
  if (const json* d = member(e, "direction")) {
    const dvec3 v = vector3(*d, "/sun/direction");
    const double length = glm::length(v);
    if (!(length > 0.0)) fail("/sun/direction", "must not be zero");
    sun.direction = vec3(v / length);
  }
  if (const json* r = member(e, "radiance")) sun.radiance = radiance(*r, "/sun/radiance");
  if (const json* a = member(e, "angular_radius")) sun.angular_radius = number(*a, "/sun/angular_radius");
  if (!(sun.angular_radius > 0.0f && sun.angular_radius < 1.0f))
    fail("/sun/angular_radius", "must lie in (0, 1) radians");
}

void read_scene(const json& j, const std::filesystem::path& base, SceneDesc& s) {
  object(j, "", "a scene");
  check_keys(j, "", {"camera", "render", "materials", "meshes", "gwn_objects", "environment", "sun"});
  Locations where;
  where.scene = "/";
  const CameraDesc camera = read_camera(member(j, "camera"), where);
  std::vector<Placement> mesh_placements;                   // per SceneDesc::meshes
  std::vector<std::vector<Placement>> instance_placements;  // per SceneDesc::gwn_objects, per instance
  if (const json* r = member(j, "render")) read_render(*r, s.render);
  if (const json* materials = member(j, "materials")) {
    object(*materials, "/materials", "named materials");
    for (const auto& item : materials->items()) {
      s.materials.push_back(material(item.value(), at("/materials", item.key())));
      s.material_names.push_back(item.key());
    }
  }
  if (s.materials.empty()) {
    s.materials.push_back(Material{});
    s.material_names.push_back("default");
  }
  for_each_entry(j, "meshes", [&](const json& e, const std::string& w) {
    object(e, w, "a mesh: {\"file\": ...} or {\"plane\": size}");
    MeshDesc d;
    Placement placement;
    if (member(e, "plane") && member(e, "file")) fail(w, "give \"file\" or \"plane\", not both");
    if (const json* plane = member(e, "plane")) {
      check_keys(e, w, {"plane", "material", "transform"});
      const float size = number(*plane, at(w, "plane"));
      if (!(size > 0.0f)) fail(at(w, "plane"), "the size must be positive");
      d.mesh = plane_mesh(size);
      d.source = "plane";
    } else if (const json* file = member(e, "file")) {
      check_keys(e, w, {"file", "material", "transform"});
      d.mesh = read_mesh(*file, base, at(w, "file"), s, placement.origin);
      d.source = file->get<std::string>();
    } else {
      fail(w, "expected \"file\" or \"plane\"");
    }
    if (const json* t = member(e, "transform")) placement.transform = transform(*t, at(w, "transform"));
    mesh_placements.push_back(placement);
    d.material = member(e, "material") ? material_index(e["material"], at(w, "material"), s) : 0;
    s.meshes.push_back(std::move(d));
    where.meshes.push_back(w);
  });
  for_each_entry(j, "gwn_objects", [&](const json& e, const std::string& w) {
    object(e, w, "a GWN object");
    check_keys(e, w, {"file", "material", "mode", "level", "epsilon", "max_steps", "beta", "instances", "transform"});
    GwnObjectDesc d;
    const json* file = member(e, "file");
    if (!file) fail(w, "expected \"file\"");
    dvec3 origin(0.0);
    d.mesh = read_mesh(*file, base, at(w, "file"), s, origin);
    std::vector<Placement> placements;
    std::vector<std::string> instance_where_list;
    const auto place = [&](const glm::dmat4& t, const std::string& instance_where) {
      placements.push_back({t, origin});
      instance_where_list.push_back(instance_where);
    };
    d.source = file->get<std::string>();
    if (const json* mode = member(e, "mode")) {
      const std::string m = mode->is_string() ? mode->get<std::string>() : "";
      if (m == "gwn")
        d.options.mode = TraceMode::kWindingNumber;
      else if (m == "solid-angle")
        d.options.mode = TraceMode::kSolidAngle;
      else
        fail(at(w, "mode"), "expected \"gwn\" or \"solid-angle\"");
    }
    if (const json* v = member(e, "level")) d.options.level = number(*v, at(w, "level"));
    if (const json* v = member(e, "epsilon")) d.options.epsilon = number(*v, at(w, "epsilon"));
    if (const json* v = member(e, "max_steps"))
      d.options.max_steps = uint32_t(integer(*v, at(w, "max_steps"), 1, 1 << 30));
    if (const json* v = member(e, "beta")) d.options.beta = number(*v, at(w, "beta"));
    if (Status st = validate_trace_options(d.options); !st.ok()) fail(w, st.message());
    note_level_out_of_reach(d, member(e, "level") ? at(w, "level") : w, s);
    const json* instances = member(e, "instances");
    if (instances && member(e, "transform")) fail(w, "give \"instances\" or \"transform\", not both");
    if (instances) {
      const std::string iw = at(w, "instances");
      if (!instances->is_array())
        fail(iw, std::string("expected an array of transforms, got ") + instances->type_name());
      for (size_t k = 0; k < instances->size(); ++k) place(transform((*instances)[k], at(iw, k)), at(iw, k));
    } else if (const json* t = member(e, "transform")) {
      place(transform(*t, at(w, "transform")), at(w, "transform"));
    } else {
      place(glm::dmat4(1.0), w);
    }
    d.material = member(e, "material") ? material_index(e["material"], at(w, "material"), s) : 0;
    s.gwn_objects.push_back(std::move(d));
    where.instances.push_back(std::move(instance_where_list));
    instance_placements.push_back(std::move(placements));
  });
  if (const json* e = member(j, "environment")) read_environment(*e, base, s.environment);
  if (const json* e = member(j, "sun")) read_sun(*e, s.sun);
  // A scene without geometry would render the sky alone, and exit 0: `{}` or a file whose
  // sections were left out is a mistake far more often than a picture of the sky (scene.h).
  if (s.meshes.empty() && s.gwn_objects.empty())
    fail("", "the scene has nothing to render: give \"meshes\" or \"gwn_objects\" (or both)");

  // The box of the scene's geometry and eye in the file's world, in double: a scene far from the
  // origin for its size (a site of georeferenced scans in UTM metres, its camera among them) is
  // moved about its own centre, as a mesh is when loaded, or float's step there (0.25 at 4e6)
  // shows in the image. Only for its size: a scene beyond the coordinate limit that is as large
  // as its distance from the origin is refused (check_geometry), moved or not.
  // What is drawn counts (drawn_box): a stray unused vertex (at the file's 0, say) would keep a
  // far-off scene from moving.
  Box world;
  for (size_t i = 0; i < s.meshes.size(); ++i)
    world.extend(drawn_box(s.meshes[i].mesh, mesh_placements[i].world_from_object()));
  for (size_t i = 0; i < s.gwn_objects.size(); ++i) {
    const Box object = drawn_box(s.gwn_objects[i].mesh);
    if (!object.valid()) continue;  // no triangles: the plugin refuses the mesh, naming it
    for (const Placement& placement : instance_placements[i]) {
      const glm::dmat4 t = placement.world_from_object();
      for (int c = 0; c < 8; ++c) world.extend(dvec3(t * glm::dvec4(object.corner(c), 1.0)));
    }
  }
  if (world.valid()) {
    world.extend(camera.eye);
    s.origin = recentring_origin(world.lo, world.hi, std::numeric_limits<double>::infinity());
  }
  for (size_t i = 0; i < s.meshes.size(); ++i) apply(mesh_placements[i], s.origin, s.meshes[i].mesh);
  for (size_t i = 0; i < s.gwn_objects.size(); ++i)
    for (size_t k = 0; k < instance_placements[i].size(); ++k)
      s.gwn_objects[i].instances.push_back(
          instance_transform(instance_placements[i][k], s.origin, where.instances[i][k]));
  s.camera = camera.make(s.origin, where.camera);
  check_geometry(s, where);
}

// Where parsing stopped, for errors whose message has no position (a number beyond double's
// range: nlohmann's out_of_range.406): the SAX interface reports the byte offset of every error.
struct ErrorPosition : nlohmann::json_sax<json> {
  size_t position = 0;
  bool null() override { return true; }
  bool boolean(bool) override { return true; }
  bool number_integer(number_integer_t) override { return true; }
  bool number_unsigned(number_unsigned_t) override { return true; }
  bool number_float(number_float_t, const string_t&) override { return true; }
  bool string(string_t&) override { return true; }
  bool binary(binary_t&) override { return true; }
  bool start_object(size_t) override { return true; }
  bool key(string_t&) override { return true; }
  bool end_object() override { return true; }
  bool start_array(size_t) override { return true; }
  bool end_array() override { return true; }
  bool parse_error(size_t p, const std::string&, const json::exception&) override {
    position = p;
    return false;
  }
};

// nlohmann's message without its "[json.exception.parse_error.101] " prefix, with the line and
// column of the error where the message does not say them.
std::string json_error_text(const std::string& text, const json::exception& e) {
  std::string what = e.what();
  if (const size_t end = what.find("] "); what.rfind("[json.exception.", 0) == 0 && end != std::string::npos)
    what.erase(0, end + 2);
  if (dynamic_cast<const json::parse_error*>(&e)) return what;  // "parse error at line 3, column 7: ..."
  ErrorPosition locator;
  json::sax_parse(text, &locator);
  const size_t p = std::min(locator.position, text.size());
  const size_t line = 1 + size_t(std::count(text.begin(), text.begin() + std::ptrdiff_t(p), '\n'));
  const size_t line_start = text.rfind('\n', p == 0 ? 0 : p - 1);
  const size_t column = line_start == std::string::npos || p == 0 ? p : p - line_start - 1;
  return "at line " + std::to_string(line) + ", column " + std::to_string(column) + ": " + what;
}

}  // namespace

Status parse_scene(const std::string& text, const std::string& path, SceneDesc& out) {
  return guard_status(path.c_str(), [&]() -> Status {
    json j;
    try {
      DuplicateKeyCheck duplicates;
      j = json::parse(
          text, [&](int depth, json::parse_event_t event, json& parsed) { return duplicates(depth, event, parsed); });
    } catch (const json::exception& e) {
      // parse_error (malformed text, invalid UTF-8) and out_of_range (a number beyond double).
      return {StatusCode::kParseError, path + ": not valid JSON: " + json_error_text(text, e)};
    } catch (const SceneError& e) {  // a key given twice
      return {StatusCode::kInvalidArgument, path + ": " + e.what()};
    }
    SceneDesc scene;
    try {
      read_scene(j, std::filesystem::path(path).parent_path(), scene);
    } catch (const SceneError& e) {
      return {StatusCode::kInvalidArgument, path + ": " + e.what()};
    }
    for (std::string& warning : scene.warnings) warning = path + ": " + warning;
    out = std::move(scene);
    return Status::Ok();
  });
}

Status load_scene(const std::string& path, SceneDesc& out) {
  std::string text;
  ReadLimits limits;
  limits.max_bytes = kMaxSceneFileBytes;
  limits.max_line_bytes = kMaxSceneFileBytes;  // minified JSON is one line
  if (Status s = read_file(path, text, limits); !s.ok()) return s;
  return parse_scene(text, path, out);
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
  return guard_status(mesh_path.c_str(), [&]() -> Status {
    SceneDesc s;
    GwnObjectDesc object;
    object.source = mesh_path;
    MeshLoadReport report;
    // Recentred when far off: the default scene stands the mesh on the ground wherever it was.
    if (Status st = load_mesh(mesh_path, object.mesh, &report, MeshLoadOptions{.recentre = true}); !st.ok()) return st;
    s.loaded_meshes.push_back({mesh_path, report});
    if (object.mesh.positions.empty()) return {StatusCode::kInvalidMesh, mesh_path + ": the mesh has no vertices"};
    // The framing in double, whatever the mesh's units: the float of a tiny mesh's squared
    // extent would underflow (and a huge one's overflow), which check_geometry then reports.
    Box box = drawn_box(object.mesh);
    if (!box.valid())  // no triangles: the plugin refuses the mesh, saying so
      for (const vec3& p : object.mesh.positions) box.extend(dvec3(p));
    const dvec3 extent = box.hi - box.lo;
    const double size = std::max({extent.x, extent.y, extent.z});
    try {
      if (!(size >= kMinSceneSize)) {
        fail("the mesh", "below the 1e-12 across that ray tracing in float can resolve; scale it up");
      }
      // The ground plane, 20 times the mesh's size, must fit too (and its size be a float).
      if (!(10.0 * size <= kMaxCoordinate)) {
        fail("the ground plane (20 times the mesh's size)",
             "it would reach " + number_text(10.0 * size) + ", " + kCoordinateLimit);
      }
      // Stand the mesh on the ground (y = 0), centred.
      const dvec3 centre = 0.5 * (box.lo + box.hi);
      object.instances.push_back(glm::translate(glm::mat4(1.0f), vec3(dvec3(-centre.x, -box.lo.y, -centre.z))));
      object.material = 0;
      s.materials = {Material{MaterialKind::kDiffuse, Spectrum(0.8f)},
                     Material{MaterialKind::kDiffuse, Spectrum(0.5f)}};
      s.material_names = {"object", "ground"};
      note_level_out_of_reach(object, mesh_path, s);
      s.gwn_objects.push_back(std::move(object));
      MeshDesc ground;
      ground.source = "plane";
      ground.mesh = plane_mesh(float(20.0 * size));
      ground.material = 1;
      s.meshes.push_back(std::move(ground));
      s.environment.radiance = Spectrum(0.45f, 0.55f, 0.7f);
      s.sun.direction = glm::normalize(vec3(0.4f, 0.8f, 0.45f));
      // The disc subtends π·r² ≈ 6.8e-5 sr: irradiance about 1.3, like the sky's π · 0.55.
      s.sun.radiance = Spectrum(2.0e4f, 1.9e4f, 1.7e4f);
      // Frame the object's bounding sphere from the front-right, slightly above.
      const double radius = 0.5 * glm::length(extent);
      const dvec3 look(0.0, 0.5 * extent.y, 0.0);
      const double fov_degrees = 35.0;
      const double distance = 1.3 * radius / std::tan(0.5 * glm::radians(fov_degrees));
      const dvec3 eye = look + distance * glm::normalize(dvec3(0.55, 0.35, 0.9));
      Locations where;
      where.scene = "the mesh";
      where.camera = "camera";
      where.meshes = {"the ground plane (20 times the mesh's size)"};
      where.instances = {{"the mesh"}};
      if (!within_coordinates(eye)) {
        fail("the mesh", "the camera that frames it would stand at " + number_text(largest_magnitude(eye)) + ", " +
                             kCoordinateLimit);
      }
      s.camera = make_camera(vec3(eye), vec3(look), vec3(0.0f, 1.0f, 0.0f), float(fov_degrees), 640, 480, where.camera);
      check_transform(glm::dmat4(s.gwn_objects[0].instances[0]), "the mesh's placement on the ground");
      check_geometry(s, where);
    } catch (const SceneError& e) {
      return {StatusCode::kInvalidArgument,
              mesh_path + ": the default scene for a mesh " + number_text(size) + " across: " + e.what()};
    }
    out = std::move(s);
    return Status::Ok();
  });
}

}  // namespace gwnrt::render
