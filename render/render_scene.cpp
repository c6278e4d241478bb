#include "render/render_scene.h"

#include "render/embree_ray.h"
#include "render/embree_triangles.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>

namespace gwnrt::render {
namespace {

// Embree reports errors through a callback; the scene builder checks rtcGetDeviceError instead.
Status embree_status(RTCDevice device, const std::string& what) {
  const RTCError e = rtcGetDeviceError(device);
  if (e == RTC_ERROR_NONE) return Status::Ok();
  return {StatusCode::kInternal, what + ": Embree error " + std::to_string(int(e))};
}

// Embree's ray.valid() (an assertion that aborts) takes origins and directions whose components
// are within FLT_LARGE = 1.844e18, and tnear, tfar that are not NaN.
constexpr float kEmbreeLarge = 1.844e18f;

bool within_embree(const vec3& v) {
  return std::fabs(v.x) <= kEmbreeLarge && std::fabs(v.y) <= kEmbreeLarge && std::fabs(v.z) <= kEmbreeLarge;
}

// v / |v|, scaled by its largest component first so that neither tiny vectors (a normal of a
// triangle 1e-20 across, whose squared length underflows float) nor large ones (an instance's
// normal matrix with scale factors near 1e-12) lose their direction; zero for a zero or
// non-finite v.
vec3 unit(vec3 v) {
  const float m = std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)});
  if (!(m > 0.0f) || !std::isfinite(m)) return vec3(0.0f);
  v /= m;
  return v / glm::length(v);
}

}  // namespace

bool RenderScene::valid_ray(const vec3& o, const vec3& d, float tnear, float tfar) const {
  // Embree's own test, and a direction that is not zero (which Embree would take, but which no
  // ray of the path tracer can mean).
  const bool ok = within_embree(o) && within_embree(d) && (d.x != 0.0f || d.y != 0.0f || d.z != 0.0f) &&
                  !std::isnan(tnear) && !std::isnan(tfar);
  if (!ok) invalid_rays_.fetch_add(1, std::memory_order_relaxed);
  return ok;
}

RenderScene::~RenderScene() {
  if (scene_) rtcReleaseScene(scene_);
  for (RTCScene s : object_scenes_) rtcReleaseScene(s);
  for (GWNRTMesh m : gwn_meshes_) gwnrtReleaseMesh(m);
  if (device_) rtcReleaseDevice(device_);
}

Status RenderScene::build(const SceneDesc& desc) {
  desc_ = &desc;
  device_ = rtcNewDevice(nullptr);
  if (!device_) return {StatusCode::kUnavailable, "Embree: cannot create a device"};
  scene_ = rtcNewScene(device_);
  for (const MeshDesc& m : desc.meshes) {
    if (m.mesh.triangles.empty()) continue;
    for (const uvec3& t : m.mesh.triangles)
      if (t.x >= m.mesh.positions.size() || t.y >= m.mesh.positions.size() || t.z >= m.mesh.positions.size())
        return {StatusCode::kInvalidMesh, m.source + ": a triangle index is out of range"};
    RTCGeometry g = render::new_triangle_geometry(device_, m.mesh);
    if (!g) {
      return {StatusCode::kInternal, m.source + ": Embree cannot make its triangle geometry (error " +
                                         std::to_string(int(rtcGetDeviceError(device_))) + ")"};
    }
    const unsigned id = rtcAttachGeometry(scene_, g);
    rtcReleaseGeometry(g);
    if (top_.size() <= id) top_.resize(id + 1);
    top_[id] = {false, m.material, &m.mesh, glm::mat3(1.0f)};
    // An emissive mesh is an area light.
    const Material& mat = desc.materials[size_t(m.material)];
    if (mat.kind == MaterialKind::kEmissive) {
      for (const uvec3& t : m.mesh.triangles) {
        const vec3 a = m.mesh.positions[t.x], b = m.mesh.positions[t.y], c = m.mesh.positions[t.z];
        const float area = 0.5f * glm::length(glm::cross(b - a, c - a));
        if (!(area > 0.0f)) continue;
        lights_.vertices.insert(lights_.vertices.end(), {a, b, c});
        lights_.emission.push_back(mat.emission);
        lights_.total_area += area;
        lights_.cdf.push_back(lights_.total_area);
      }
    }
  }
  for (float& c : lights_.cdf) c /= lights_.total_area;
  if (!lights_.cdf.empty()) lights_.cdf.back() = 1.0f;

  for (const GwnObjectDesc& g : desc.gwn_objects) {
    GWNRTMesh mesh =
        gwnrtNewMesh(&g.mesh.positions[0].x, g.mesh.positions.size(), &g.mesh.triangles[0].x, g.mesh.triangles.size());
    if (!mesh) return {StatusCode::kInvalidMesh, g.source + ": " + gwnrtGetLastError()};
    gwn_meshes_.push_back(mesh);
    GWNRTOptions options;
    gwnrtInitOptions(&options);
    options.mode = g.options.mode == TraceMode::kSolidAngle ? GWNRT_MODE_SOLID_ANGLE : GWNRT_MODE_GWN;
    options.level = g.options.level;
    options.epsilon = g.options.epsilon;
    options.max_steps = g.options.max_steps;
    options.max_crossings = g.options.max_crossings;
    options.beta = g.options.beta;
    RTCGeometry geometry = gwnrtNewGeometry(device_, mesh, &options);
    if (!geometry) return {StatusCode::kInvalidArgument, g.source + ": " + gwnrtGetLastError()};
    RTCScene object = rtcNewScene(device_);
    rtcAttachGeometry(object, geometry);
    rtcReleaseGeometry(geometry);
    rtcCommitScene(object);
    object_scenes_.push_back(object);
    for (const glm::mat4& transform : g.instances) {
      RTCGeometry instance = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_INSTANCE);
      rtcSetGeometryInstancedScene(instance, object);
      rtcSetGeometryTransform(instance, 0, RTC_FORMAT_FLOAT4X4_COLUMN_MAJOR, &transform[0][0]);
      rtcCommitGeometry(instance);
      const unsigned id = rtcAttachGeometry(scene_, instance);
      rtcReleaseGeometry(instance);
      if (top_.size() <= id) top_.resize(id + 1);
      // The inverse in double (the scene reader bounds the transform's scale factors and
      // condition), scaled to entries of order 1: only the normal's direction is wanted.
      glm::dmat3 normal = glm::transpose(glm::inverse(glm::dmat3(glm::mat3(transform))));
      double largest = 0.0;
      for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) largest = std::max(largest, std::fabs(normal[c][r]));
      if (largest > 0.0) normal /= largest;
      top_[id] = {true, g.material, nullptr, glm::mat3(normal)};
    }
  }
  rtcCommitScene(scene_);
  if (Status s = embree_status(device_, "building the scene"); !s.ok()) return s;

  if (desc.environment.file.empty()) {
    environment_ = Environment::constant(desc.environment.radiance);
  } else if (Status s = Environment::load(desc.environment.file, desc.environment.scale, environment_); !s.ok()) {
    return s;
  }
  const Spectrum up = environment_.radiance(vec3(0.0f, 1.0f, 0.0f));
  environment_emits_ = !environment_.is_constant() || up.x > 0.0f || up.y > 0.0f || up.z > 0.0f;
  const Aabb box = scene_bounds(desc);
  // In double: the squared diagonal of a tiny (or huge) scene would underflow (overflow) float.
  radius_ =
      box.valid() ? float(std::min(0.5 * glm::length(glm::dvec3(box.hi) - glm::dvec3(box.lo)), double(FLT_MAX))) : 1.0f;
  return Status::Ok();
}

bool RenderScene::intersect(const vec3& o, const vec3& d, float tnear, float tfar, SurfaceHit& hit) const {
  if (!valid_ray(o, d, tnear, tfar)) return false;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh = render::embree_ray_hit(o, d, tnear, tfar);
  rtcIntersect1(scene_, &context, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
  const bool via_instance = rh.hit.instID[0] != RTC_INVALID_GEOMETRY_ID;
  const TopGeometry& top = top_[via_instance ? rh.hit.instID[0] : rh.hit.geomID];
  vec3 n;
  if (top.instance) {
    n = top.normal_matrix * vec3(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);  // Ng arrives in the object's space
  } else {
    const uvec3 t = top.mesh->triangles[rh.hit.primID];
    const vec3 a = top.mesh->positions[t.x], b = top.mesh->positions[t.y], c = top.mesh->positions[t.z];
    n = glm::cross(b - a, c - a);
  }
  n = unit(n);
  // A normal that cannot be normalised (a triangle too small for float): taken as facing the ray.
  if (n == vec3(0.0f)) n = -d;
  hit.t = rh.ray.tfar;
  hit.position = o + rh.ray.tfar * d;
  hit.normal = n;
  hit.material = top.material;
  hit.gwn = top.instance;
  return true;
}

bool RenderScene::occluded(const vec3& o, const vec3& d, float tnear, float tfar) const {
  if (!valid_ray(o, d, tnear, tfar)) return false;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay ray = render::embree_ray_hit(o, d, tnear, tfar).ray;
  rtcOccluded1(scene_, &context, &ray);
  return ray.tfar == -std::numeric_limits<float>::infinity();
}

}  // namespace gwnrt::render
