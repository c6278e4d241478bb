// What the plugin's tests share: Embree's objects (RAII), GWN geometry and instances of it,
// rays (views of a mesh's holes, random ones), single rays and packets through plain Embree
// calls, and the geometry of the meshes for the references.
#pragma once

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <initializer_list>
#include <limits>
#include <string>
#include <vector>

#include "gwnrt/embree.h"
#include "gwnrt/field/distance.h"
#include "render/camera.h"
#include "render/embree_ray.h"
#include "test_util.h"

namespace gwnrt {

using test::build_model;
using test::load_test_mesh;

inline constexpr unsigned kInvalidId = RTC_INVALID_GEOMETRY_ID;
inline constexpr float kInfF = std::numeric_limits<float>::infinity();

// ---------------------------------------------------------------------------------------------
// Embree objects (RAII) and geometry.
// ---------------------------------------------------------------------------------------------

class Device {
 public:
  explicit Device(const char* config = nullptr) : device_(rtcNewDevice(config)) {
    EXPECT_NE(device_, nullptr) << "rtcNewDevice failed";
  }
  ~Device() {
    if (device_) rtcReleaseDevice(device_);
  }
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;
  RTCDevice get() const { return device_; }
  // The first error since the last call (RTC_ERROR_NONE when none).
  RTCError error() const { return rtcGetDeviceError(device_); }

 private:
  RTCDevice device_;
};

class Scene {
 public:
  explicit Scene(const Device& device, RTCSceneFlags flags = RTC_SCENE_FLAG_ROBUST)
      : scene_(rtcNewScene(device.get())) {
    rtcSetSceneFlags(scene_, flags);
  }
  ~Scene() { rtcReleaseScene(scene_); }
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  // Commits `geometry`, attaches it (with ID `id` when given) and drops the caller's reference.
  unsigned attach(RTCGeometry geometry, unsigned id = kInvalidId) {
    if (!geometry) {
      ADD_FAILURE() << "no geometry to attach";
      return kInvalidId;
    }
    rtcCommitGeometry(geometry);
    if (id == kInvalidId) {
      id = rtcAttachGeometry(scene_, geometry);
    } else {
      rtcAttachGeometryByID(scene_, geometry, id);
    }
    rtcReleaseGeometry(geometry);
    return id;
  }
  void commit() { rtcCommitScene(scene_); }
  RTCScene get() const { return scene_; }

 private:
  RTCScene scene_;
};

inline const float* xyz_of(const Mesh& m) { return reinterpret_cast<const float*>(m.positions.data()); }
inline const uint32_t* indices_of(const Mesh& m) { return reinterpret_cast<const uint32_t*>(m.triangles.data()); }

inline GWNRTMesh new_mesh(const Mesh& m) {
  GWNRTMesh mesh = gwnrtNewMesh(xyz_of(m), m.positions.size(), indices_of(m), m.triangles.size());
  EXPECT_NE(mesh, nullptr) << gwnrtGetLastError();
  return mesh;
}

// A GWN object of `m`; the application's mesh reference is dropped at once (the geometry keeps it).
inline RTCGeometry gwn_geometry(RTCDevice device, const Mesh& m, const GWNRTOptions* options = nullptr) {
  GWNRTMesh mesh = new_mesh(m);
  if (!mesh) return nullptr;
  RTCGeometry g = gwnrtNewGeometry(device, mesh, options);
  EXPECT_NE(g, nullptr) << gwnrtGetLastError();
  gwnrtReleaseMesh(mesh);
  return g;
}

// x -> L x + T.
struct Affine {
  glm::dmat3 L{1.0};
  dvec3 T{0.0};
  dvec3 apply(const dvec3& x) const { return L * x + T; }
  // Object-space normal to world space (the normal matrix L^-T), unit.
  dvec3 normal(const dvec3& n) const { return glm::normalize(glm::transpose(glm::inverse(L)) * n); }
};

// Rotation by `degrees` about `axis` (Rodrigues), scaled by `scale`, then moved by `move`.
inline Affine similarity(dvec3 axis, double degrees, double scale, dvec3 move) {
  axis = glm::normalize(axis);
  const double a = degrees * kPi / 180.0, c = std::cos(a), s = std::sin(a);
  const glm::dmat3 K(0, axis.z, -axis.y, -axis.z, 0, axis.x, axis.y, -axis.x, 0);  // columns: K x = axis × x
  Affine f;
  f.L = scale * (glm::dmat3(1.0) + s * K + (1 - c) * K * K);
  f.T = move;
  return f;
}

inline RTCGeometry instance_geometry(RTCDevice device, RTCScene object, const Affine& f) {
  RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
  rtcSetGeometryInstancedScene(g, object);
  float xfm[12];  // column-major 3x4: the columns of L, then T
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) xfm[3 * c + r] = float(f.L[c][r]);
  for (int r = 0; r < 3; ++r) xfm[9 + r] = float(f.T[r]);
  rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xfm);
  return g;
}

inline Mesh transformed(const Mesh& m, const Affine& f) {
  Mesh out = m;
  for (vec3& p : out.positions) p = vec3(f.apply(dvec3(p)));
  return out;
}

// ---------------------------------------------------------------------------------------------
// Rays.
// ---------------------------------------------------------------------------------------------

using test::Random;

inline double diagonal(const Aabb& b) { return glm::length(dvec3(b.hi) - dvec3(b.lo)); }
inline Aabb grown(const Aabb& b, float by) { return Aabb{b.lo - vec3(by), b.hi + vec3(by)}; }

struct View {
  float azimuth, elevation;
};

// res x res camera rays framing `box` from each view.
inline std::vector<Ray> camera_rays(const Aabb& box, int res, std::initializer_list<View> views) {
  std::vector<Ray> rays;
  for (const View& v : views) {
    const render::PinholeCamera cam = render::frame_box(box, res, res, v.azimuth, v.elevation);
    for (int y = 0; y < res; ++y)
      for (int x = 0; x < res; ++x) rays.push_back(cam.ray(x, y));
  }
  return rays;
}

// `box` scaled about its centre: framing a shrunk box, the mesh fills the picture.
inline Aabb scaled(const Aabb& box, float by) {
  const vec3 c = box.centre(), h = 0.5f * by * (box.hi - box.lo);
  return Aabb{c - h, c + h};
}

// Views of each hole of an open mesh: a camera on the line from the box's centre through the
// hole's centre, framing the hole's box grown by its own size.
inline std::vector<Ray> hole_rays(const GwnModel& model, int res) {
  uint32_t loops = 0;
  const std::vector<uint32_t> loop_of = boundary_loops(model.boundary(), loops);
  std::vector<Aabb> hole(loops);
  for (size_t s = 0; s < loop_of.size(); ++s) {
    hole[loop_of[s]].extend(model.boundary().endpoints[2 * s]);
    hole[loop_of[s]].extend(model.boundary().endpoints[2 * s + 1]);
  }
  std::vector<Ray> rays;
  for (const Aabb& h : hole) {
    const vec3 back = glm::normalize(h.centre() - model.bounds().centre());  // centre -> eye
    constexpr float kDegrees = float(180.0 / kPi);
    const float elevation = std::asin(back.y) * kDegrees, azimuth = std::atan2(back.x, back.z) * kDegrees;
    const std::vector<Ray> more = camera_rays(scaled(h, 2.0f), res, {{azimuth, elevation}});
    rays.insert(rays.end(), more.begin(), more.end());
  }
  return rays;
}

// Origins in `box` grown by half its diagonal (inside and outside M), directions of length 0.1
// to 10 (t is in their units), two in three aimed at a point of the box, the others uniform;
// every third ray has tnear > 0 and a finite tfar, every third after it only a finite tfar.
inline std::vector<Ray> random_rays(const Aabb& box, size_t count, uint32_t seed) {
  Random rng(seed);
  const float diag = float(diagonal(box));
  const Aabb around = grown(box, 0.5f * diag);
  std::vector<Ray> rays(count);
  for (size_t i = 0; i < count; ++i) {
    Ray& r = rays[i];
    r.origin = rng.in_box(around);
    const vec3 to = rng.in_box(box) - r.origin;
    const float len = std::pow(10.0f, rng.uniform(-1.0f, 1.0f));
    r.direction = (i % 9 < 6 ? glm::normalize(to) : rng.unit()) * len;
    const float distance = glm::length(to);
    if (i % 3 == 1) {
      r.tnear = rng.uniform(0.0f, 1.0f) * distance / len;
      r.tfar = r.tnear + rng.uniform(0.05f, 1.0f) * diag / len;
    } else if (i % 3 == 2) {
      r.tfar = rng.uniform(0.5f, 1.5f) * distance / len;
    }
  }
  return rays;
}

inline std::string describe(const Ray& r) {
  char buf[320];
  std::snprintf(buf, sizeof buf, "ray origin (%.9g, %.9g, %.9g) direction (%.9g, %.9g, %.9g) tnear %.9g tfar %.9g",
                r.origin.x, r.origin.y, r.origin.z, r.direction.x, r.direction.y, r.direction.z, r.tnear, r.tfar);
  return buf;
}

inline std::string describe(const RTCRayHit& h) {
  char buf[320];
  std::snprintf(buf, sizeof buf, "embree: tfar %.9g geomID %d primID %d instID %d Ng (%.7g, %.7g, %.7g) u %.7g v %.7g",
                h.ray.tfar, int(h.hit.geomID), int(h.hit.primID), int(h.hit.instID[0]), h.hit.Ng_x, h.hit.Ng_y,
                h.hit.Ng_z, h.hit.u, h.hit.v);
  return buf;
}

inline RTCRayHit make_rayhit(const Ray& r, unsigned id = 0, unsigned mask = ~0u) {
  return render::embree_ray_hit(r, mask, id);
}

class Context {
 public:
  Context() { rtcInitIntersectContext(&context_); }
  RTCIntersectContext* get() { return &context_; }

 private:
  RTCIntersectContext context_;
};

inline RTCRayHit intersect1(RTCScene scene, const Ray& r, RTCIntersectContext* context = nullptr, unsigned id = 0,
                            unsigned mask = ~0u) {
  Context local;
  RTCRayHit rh = make_rayhit(r, id, mask);
  rtcIntersect1(scene, context ? context : local.get(), &rh);
  return rh;
}

// The ray after rtcOccluded1 (tfar = -inf when occluded).
inline RTCRay occluded1(RTCScene scene, const Ray& r, RTCIntersectContext* context = nullptr, unsigned id = 0,
                        unsigned mask = ~0u) {
  Context local;
  RTCRay ray = make_rayhit(r, id, mask).ray;
  rtcOccluded1(scene, context ? context : local.get(), &ray);
  return ray;
}

inline bool is_hit(const RTCRayHit& h) { return h.hit.geomID != kInvalidId; }
inline bool is_occluded(const RTCRay& r) { return r.tfar == -kInfF; }

// RTCRay and RTCHit are all 4-byte words (no padding): equal bits, equal results.
template <class T>
inline bool same_bits(const T& a, const T& b) {
  return std::memcmp(&a, &b, sizeof(T)) == 0;
}

// Packets of N rays: lane k of packet p is ray N p + k.
template <int N>
struct Packet;
template <>
struct Packet<4> {
  using RayHitN = RTCRayHit4;
  using RayN = RTCRay4;
  static void intersect(const int* v, RTCScene s, RTCIntersectContext* c, RayHitN* r) { rtcIntersect4(v, s, c, r); }
  static void occluded(const int* v, RTCScene s, RTCIntersectContext* c, RayN* r) { rtcOccluded4(v, s, c, r); }
};
template <>
struct Packet<8> {
  using RayHitN = RTCRayHit8;
  using RayN = RTCRay8;
  static void intersect(const int* v, RTCScene s, RTCIntersectContext* c, RayHitN* r) { rtcIntersect8(v, s, c, r); }
  static void occluded(const int* v, RTCScene s, RTCIntersectContext* c, RayN* r) { rtcOccluded8(v, s, c, r); }
};
template <>
struct Packet<16> {
  using RayHitN = RTCRayHit16;
  using RayN = RTCRay16;
  static void intersect(const int* v, RTCScene s, RTCIntersectContext* c, RayHitN* r) { rtcIntersect16(v, s, c, r); }
  static void occluded(const int* v, RTCScene s, RTCIntersectContext* c, RayN* r) { rtcOccluded16(v, s, c, r); }
};

inline void set_ray_lane(RTCRayN* p, unsigned n, unsigned i, const RTCRay& r) {
  RTCRayN_org_x(p, n, i) = r.org_x;
  RTCRayN_org_y(p, n, i) = r.org_y;
  RTCRayN_org_z(p, n, i) = r.org_z;
  RTCRayN_tnear(p, n, i) = r.tnear;
  RTCRayN_dir_x(p, n, i) = r.dir_x;
  RTCRayN_dir_y(p, n, i) = r.dir_y;
  RTCRayN_dir_z(p, n, i) = r.dir_z;
  RTCRayN_time(p, n, i) = r.time;
  RTCRayN_tfar(p, n, i) = r.tfar;
  RTCRayN_mask(p, n, i) = r.mask;
  RTCRayN_id(p, n, i) = r.id;
  RTCRayN_flags(p, n, i) = r.flags;
}

// An inactive lane: a real ray with a sentinel hit, all of which must come back unchanged.
inline RTCRayHit inactive_lane(RTCRayHit h) {
  h.hit.Ng_x = h.hit.Ng_y = h.hit.Ng_z = h.hit.u = h.hit.v = 123.25f;
  h.hit.primID = h.hit.geomID = 0xDEADBEEFu;
  h.hit.instID[0] = 0xCAFEF00Du;
  return h;
}

// Active lanes: active(i) for ray i. Returns every lane after the call (inactive ones as given).
template <int N, class Active>
inline std::vector<RTCRayHit> intersect_packets(RTCScene scene, std::vector<RTCRayHit> in, Active active,
                                                RTCIntersectContext* context = nullptr) {
  Context local;
  using P = Packet<N>;
  for (size_t first = 0; first < in.size(); first += N) {
    typename P::RayHitN packet;
    alignas(64) int valid[N];  // Embree needs the mask aligned like the packet
    auto* rh = reinterpret_cast<RTCRayHitN*>(&packet);
    for (unsigned k = 0; k < unsigned(N); ++k) {
      const bool real = first + k < in.size();  // lanes past the end: inactive copies of the last ray
      RTCRayHit lane = real ? in[first + k] : in.back();
      const bool on = real && active(first + k);
      if (!on) lane = inactive_lane(lane);
      if (real) in[first + k] = lane;
      valid[k] = on ? -1 : 0;
      set_ray_lane(RTCRayHitN_RayN(rh, N), N, k, lane.ray);
      rtcCopyHitToHitN(RTCRayHitN_HitN(rh, N), &lane.hit, N, k);
    }
    P::intersect(valid, scene, context ? context : local.get(), &packet);
    for (unsigned k = 0; k < unsigned(N) && first + k < in.size(); ++k)
      in[first + k] = rtcGetRayHitFromRayHitN(rh, N, k);
  }
  return in;
}

template <int N, class Active>
inline std::vector<RTCRay> occluded_packets(RTCScene scene, std::vector<RTCRay> in, Active active,
                                            RTCIntersectContext* context = nullptr) {
  Context local;
  using P = Packet<N>;
  for (size_t first = 0; first < in.size(); first += N) {
    typename P::RayN packet;
    alignas(64) int valid[N];  // Embree needs the mask aligned like the packet
    auto* r = reinterpret_cast<RTCRayN*>(&packet);
    for (unsigned k = 0; k < unsigned(N); ++k) {
      const bool real = first + k < in.size();
      valid[k] = real && active(first + k) ? -1 : 0;
      set_ray_lane(r, N, k, real ? in[first + k] : in.back());
    }
    P::occluded(valid, scene, context ? context : local.get(), &packet);
    for (unsigned k = 0; k < unsigned(N) && first + k < in.size(); ++k) in[first + k] = rtcGetRayFromRayN(r, N, k);
  }
  return in;
}

// About a quarter of the lanes inactive, in a pattern that differs between packet widths.
struct SomeLanes {
  unsigned salt;
  bool operator()(size_t i) const { return ((uint32_t(i) * 2654435761u + salt) >> 13) % 4 != 0; }
};

// ---------------------------------------------------------------------------------------------
// Geometry of the meshes.
// ---------------------------------------------------------------------------------------------

inline dvec3 corner(const Mesh& m, uint32_t t, int k) { return dvec3(m.positions[m.triangles[t][k]]); }

inline dvec3 triangle_normal(const Mesh& m, uint32_t t) {
  return glm::normalize(glm::cross(corner(m, t, 1) - corner(m, t, 0), corner(m, t, 2) - corner(m, t, 0)));
}

inline double distance_to_triangle(const Mesh& m, uint32_t t, const dvec3& x) {
  return glm::length(closest_point_on_triangle(corner(m, t, 0), corner(m, t, 1), corner(m, t, 2), x).point - x);
}

inline double distance_to_boundary(const BoundaryCurve& curve, const dvec3& x) {
  double d = std::numeric_limits<double>::infinity();
  for (size_t s = 0; s < curve.segment_count(); ++s) {
    const dvec3 a(curve.endpoints[2 * s]), b(curve.endpoints[2 * s + 1]);
    const double u = std::clamp(glm::dot(x - a, b - a) / glm::dot(b - a, b - a), 0.0, 1.0);
    d = std::min(d, glm::length(a + u * (b - a) - x));
  }
  return d;
}

inline dvec3 hit_point(const Ray& r, float t) { return dvec3(r.origin) + double(t) * dvec3(r.direction); }
inline dvec3 normal_of(const RTCRayHit& h) { return dvec3(h.hit.Ng_x, h.hit.Ng_y, h.hit.Ng_z); }

// The worst value seen, for the summary each test prints.
struct Worst {
  double value = 0;
  void see(double v) { value = std::max(value, v); }
};

// Views of bunny_holes: of each hole, and of the whole from around.
inline std::vector<Ray> bunny_holes_rays(const GwnModel& model, int res) {
  std::vector<Ray> rays = hole_rays(model, res);
  const std::vector<Ray> around = camera_rays(scaled(model.bounds(), 0.6f), res, {{30, -60}, {200, -35}, {110, 15}});
  rays.insert(rays.end(), around.begin(), around.end());
  return rays;
}

}  // namespace gwnrt
