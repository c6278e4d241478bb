// The Embree plugin (gwnrt/embree.h) driven only through plain Embree 3 calls, against
// independent references:
//  - on a closed mesh, S is the mesh itself, so Embree's own triangles are the reference;
//  - on open meshes, trace_surface called directly (the plugin must add nothing and lose
//    nothing: Embree's culling by the reported bounds, packets, instances, filters, masks);
//  - inside instances, trace_surface on the mesh transformed in world space;
//  - for filters, the complete list of triangle crossings that Embree's triangles report;
//  - for the bounds, a soup whose S reaches far outside the mesh's box, checked against the
//    exact winding number of test_util.h (as are the open mesh's hits).
// Each test prints one summary line with the worst differences it measured.
#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "cli_util.h"
#include "gwnrt/embree.h"
#include "gwnrt/field/distance.h"
#include "gwnrt/trace/surface_trace.h"
#include "reference/first_crossing.h"
#include "render/camera.h"
#include "render/embree_ray.h"
#include "render/embree_triangles.h"
#include "test_util.h"

namespace gwnrt {
namespace {

using test::build_model;
using test::load_test_mesh;

constexpr unsigned kInvalidId = RTC_INVALID_GEOMETRY_ID;
constexpr float kInfF = std::numeric_limits<float>::infinity();

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

const float* xyz_of(const Mesh& m) { return reinterpret_cast<const float*>(m.positions.data()); }
const uint32_t* indices_of(const Mesh& m) { return reinterpret_cast<const uint32_t*>(m.triangles.data()); }

GWNRTMesh new_mesh(const Mesh& m) {
  GWNRTMesh mesh = gwnrtNewMesh(xyz_of(m), m.positions.size(), indices_of(m), m.triangles.size());
  EXPECT_NE(mesh, nullptr) << gwnrtGetLastError();
  return mesh;
}

// A GWN object of `m`; the application's mesh reference is dropped at once (the geometry keeps it).
RTCGeometry gwn_geometry(RTCDevice device, const Mesh& m, const GWNRTOptions* options = nullptr) {
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
Affine similarity(dvec3 axis, double degrees, double scale, dvec3 move) {
  axis = glm::normalize(axis);
  const double a = degrees * kPi / 180.0, c = std::cos(a), s = std::sin(a);
  const glm::dmat3 K(0, axis.z, -axis.y, -axis.z, 0, axis.x, axis.y, -axis.x, 0);  // columns: K x = axis × x
  Affine f;
  f.L = scale * (glm::dmat3(1.0) + s * K + (1 - c) * K * K);
  f.T = move;
  return f;
}

RTCGeometry instance_geometry(RTCDevice device, RTCScene object, const Affine& f) {
  RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
  rtcSetGeometryInstancedScene(g, object);
  float xfm[12];  // column-major 3x4: the columns of L, then T
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) xfm[3 * c + r] = float(f.L[c][r]);
  for (int r = 0; r < 3; ++r) xfm[9 + r] = float(f.T[r]);
  rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xfm);
  return g;
}

Mesh transformed(const Mesh& m, const Affine& f) {
  Mesh out = m;
  for (vec3& p : out.positions) p = vec3(f.apply(dvec3(p)));
  return out;
}

// ---------------------------------------------------------------------------------------------
// Rays.
// ---------------------------------------------------------------------------------------------

using test::Random;

double diagonal(const Aabb& b) { return glm::length(dvec3(b.hi) - dvec3(b.lo)); }
Aabb grown(const Aabb& b, float by) { return Aabb{b.lo - vec3(by), b.hi + vec3(by)}; }

struct View {
  float azimuth, elevation;
};

// res x res camera rays framing `box` from each view.
std::vector<Ray> camera_rays(const Aabb& box, int res, std::initializer_list<View> views) {
  std::vector<Ray> rays;
  for (const View& v : views) {
    const render::PinholeCamera cam = render::frame_box(box, res, res, v.azimuth, v.elevation);
    for (int y = 0; y < res; ++y)
      for (int x = 0; x < res; ++x) rays.push_back(cam.ray(x, y));
  }
  return rays;
}

// `box` scaled about its centre: framing a shrunk box, the mesh fills the picture.
Aabb scaled(const Aabb& box, float by) {
  const vec3 c = box.centre(), h = 0.5f * by * (box.hi - box.lo);
  return Aabb{c - h, c + h};
}

// Views of each hole of an open mesh: a camera on the line from the box's centre through the
// hole's centre, framing the hole's box grown by its own size.
std::vector<Ray> hole_rays(const GwnModel& model, int res) {
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
std::vector<Ray> random_rays(const Aabb& box, size_t count, uint32_t seed) {
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

std::string describe(const Ray& r) {
  char buf[320];
  std::snprintf(buf, sizeof buf, "ray origin (%.9g, %.9g, %.9g) direction (%.9g, %.9g, %.9g) tnear %.9g tfar %.9g",
                r.origin.x, r.origin.y, r.origin.z, r.direction.x, r.direction.y, r.direction.z, r.tnear, r.tfar);
  return buf;
}

std::string describe(const RTCRayHit& h) {
  char buf[320];
  std::snprintf(buf, sizeof buf, "embree: tfar %.9g geomID %d primID %d instID %d Ng (%.7g, %.7g, %.7g) u %.7g v %.7g",
                h.ray.tfar, int(h.hit.geomID), int(h.hit.primID), int(h.hit.instID[0]), h.hit.Ng_x, h.hit.Ng_y,
                h.hit.Ng_z, h.hit.u, h.hit.v);
  return buf;
}

RTCRayHit make_rayhit(const Ray& r, unsigned id = 0, unsigned mask = ~0u) {
  return render::embree_ray_hit(r, mask, id);
}

class Context {
 public:
  Context() { rtcInitIntersectContext(&context_); }
  RTCIntersectContext* get() { return &context_; }

 private:
  RTCIntersectContext context_;
};

RTCRayHit intersect1(RTCScene scene, const Ray& r, RTCIntersectContext* context = nullptr, unsigned id = 0,
                     unsigned mask = ~0u) {
  Context local;
  RTCRayHit rh = make_rayhit(r, id, mask);
  rtcIntersect1(scene, context ? context : local.get(), &rh);
  return rh;
}

// The ray after rtcOccluded1 (tfar = -inf when occluded).
RTCRay occluded1(RTCScene scene, const Ray& r, RTCIntersectContext* context = nullptr, unsigned id = 0,
                 unsigned mask = ~0u) {
  Context local;
  RTCRay ray = make_rayhit(r, id, mask).ray;
  rtcOccluded1(scene, context ? context : local.get(), &ray);
  return ray;
}

bool is_hit(const RTCRayHit& h) { return h.hit.geomID != kInvalidId; }
bool is_occluded(const RTCRay& r) { return r.tfar == -kInfF; }

// RTCRay and RTCHit are all 4-byte words (no padding): equal bits, equal results.
template <class T>
bool same_bits(const T& a, const T& b) {
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

void set_ray_lane(RTCRayN* p, unsigned n, unsigned i, const RTCRay& r) {
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
RTCRayHit inactive_lane(RTCRayHit h) {
  h.hit.Ng_x = h.hit.Ng_y = h.hit.Ng_z = h.hit.u = h.hit.v = 123.25f;
  h.hit.primID = h.hit.geomID = 0xDEADBEEFu;
  h.hit.instID[0] = 0xCAFEF00Du;
  return h;
}

// Active lanes: active(i) for ray i. Returns every lane after the call (inactive ones as given).
template <int N, class Active>
std::vector<RTCRayHit> intersect_packets(RTCScene scene, std::vector<RTCRayHit> in, Active active,
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
std::vector<RTCRay> occluded_packets(RTCScene scene, std::vector<RTCRay> in, Active active,
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

dvec3 corner(const Mesh& m, uint32_t t, int k) { return dvec3(m.positions[m.triangles[t][k]]); }

dvec3 triangle_normal(const Mesh& m, uint32_t t) {
  return glm::normalize(glm::cross(corner(m, t, 1) - corner(m, t, 0), corner(m, t, 2) - corner(m, t, 0)));
}

double distance_to_triangle(const Mesh& m, uint32_t t, const dvec3& x) {
  return glm::length(closest_point_on_triangle(corner(m, t, 0), corner(m, t, 1), corner(m, t, 2), x).point - x);
}

double distance_to_boundary(const BoundaryCurve& curve, const dvec3& x) {
  double d = std::numeric_limits<double>::infinity();
  for (size_t s = 0; s < curve.segment_count(); ++s) {
    const dvec3 a(curve.endpoints[2 * s]), b(curve.endpoints[2 * s + 1]);
    const double u = std::clamp(glm::dot(x - a, b - a) / glm::dot(b - a, b - a), 0.0, 1.0);
    d = std::min(d, glm::length(a + u * (b - a) - x));
  }
  return d;
}

dvec3 hit_point(const Ray& r, float t) { return dvec3(r.origin) + double(t) * dvec3(r.direction); }
dvec3 normal_of(const RTCRayHit& h) { return dvec3(h.hit.Ng_x, h.hit.Ng_y, h.hit.Ng_z); }

// The worst value seen, for the summary each test prints.
struct Worst {
  double value = 0;
  void see(double v) { value = std::max(value, v); }
};

// ---------------------------------------------------------------------------------------------
// 1. A watertight mesh side by side with Embree's triangles.
// ---------------------------------------------------------------------------------------------

TEST(EmbreePlugin, WatertightMatchesEmbreeTriangles) {
  const Mesh mesh = load_test_mesh("bunny.obj");
  const Aabb box = test::mesh_bounds(mesh);
  const double diag = diagonal(box);
  Device device;
  Scene a(device), b(device);
  constexpr unsigned kGwnId = 5;  // not 0: the reported geomID must be the attached one
  ASSERT_EQ(a.attach(gwn_geometry(device.get(), mesh), kGwnId), kGwnId);
  const unsigned tri_id = b.attach(render::new_triangle_geometry(device.get(), mesh));
  a.commit();
  b.commit();
  ASSERT_EQ(device.error(), RTC_ERROR_NONE);

  std::vector<Ray> rays = camera_rays(scaled(box, 0.6f), 40, {{30, 20}, {150, -10}, {260, 40}, {0, 85}});
  const std::vector<Ray> random = random_rays(box, 4000, 11);
  rays.insert(rays.end(), random.begin(), random.end());

  // Both intersect the same float ray with the same float triangles; each t carries a few float
  // ulps of the coordinates (|x| <= ~2 diagonals: ~1e-7 of the diagonal). 1e-5 of the diagonal
  // leaves two orders of magnitude of slack and is far below the spacing of distinct surfaces
  // along a ray (bunny: mean edge ~2% of the diagonal).
  const double tol = 1e-5 * diag;
  Worst dt, bary, ng_unit, ng_tri, ng_embree;
  size_t hits = 0, shared_edge = 0, limited = 0;
  std::vector<RTCRayHit> single(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) {
    const Ray& r = rays[i];
    const RTCRayHit ha = intersect1(a.get(), r, nullptr, unsigned(i));
    const RTCRayHit hb = intersect1(b.get(), r, nullptr, unsigned(i));
    single[i] = ha;
    SCOPED_TRACE(describe(r) + "\nA " + describe(ha) + "\nB " + describe(hb));
    ASSERT_EQ(is_hit(ha), is_hit(hb));
    if (!is_hit(ha)) {
      EXPECT_TRUE(same_bits(ha, make_rayhit(r, unsigned(i)))) << "a miss leaves the ray and hit untouched";
      continue;
    }
    ++hits;
    limited += r.tnear > 0 || r.tfar < kInfF;
    const double len = glm::length(dvec3(r.direction));
    dt.see(std::fabs(double(ha.ray.tfar) - double(hb.ray.tfar)) * len / diag);
    ASSERT_LE(std::fabs(double(ha.ray.tfar) - double(hb.ray.tfar)) * len, tol);
    EXPECT_GT(ha.ray.tfar, r.tnear);  // strictly inside (tnear, tfar)
    EXPECT_LT(ha.ray.tfar, r.tfar);
    EXPECT_EQ(ha.hit.geomID, kGwnId);
    EXPECT_EQ(hb.hit.geomID, tri_id);
    EXPECT_EQ(ha.hit.instID[0], kInvalidId);
    ASSERT_LT(ha.hit.primID, mesh.triangles.size());
    const dvec3 p = hit_point(r, ha.ray.tfar);
    if (ha.hit.primID != hb.hit.primID) {
      // The same t but neighbouring triangles: the ray passes through their shared edge, so
      // the point lies on both (to the same round-off as t).
      ++shared_edge;
      EXPECT_LE(distance_to_triangle(mesh, ha.hit.primID, p), tol);
      EXPECT_LE(distance_to_triangle(mesh, hb.hit.primID, p), tol);
    } else {
      const double c = std::fabs(glm::dot(normal_of(ha), glm::normalize(normal_of(hb))));
      ng_embree.see(1 - c);
      EXPECT_GE(c, 1 - 1e-5);
    }
    // u, v are barycentrics on primID, in Embree's convention: they rebuild the hit point.
    const uint32_t t = ha.hit.primID;
    const double u = ha.hit.u, v = ha.hit.v;
    const dvec3 q = (1 - u - v) * corner(mesh, t, 0) + u * corner(mesh, t, 1) + v * corner(mesh, t, 2);
    bary.see(glm::length(q - p) / diag);
    EXPECT_LE(glm::length(q - p), tol) << "u, v do not rebuild the hit point";
    // Ng: unit (float round-off), outward, i.e. the outward-oriented bunny's triangle normal.
    ng_unit.see(std::fabs(glm::length(normal_of(ha)) - 1));
    EXPECT_NEAR(glm::length(normal_of(ha)), 1.0, 1e-5);
    const double along = glm::dot(normal_of(ha), triangle_normal(mesh, t));
    ng_tri.see(1 - along);
    EXPECT_GE(along, 1 - 1e-5);
  }
  EXPECT_GT(hits, rays.size() / 3);
  EXPECT_GT(limited, rays.size() / 20) << "rays with tnear > 0 or finite tfar must hit too";
  EXPECT_LT(shared_edge, hits / 100) << "shared-edge hits are rare for these rays";

  // Packets: exactly the single-ray results lane by lane; inactive lanes untouched.
  std::vector<RTCRayHit> in(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) in[i] = make_rayhit(rays[i], unsigned(i));
  // Debian's Embree 3.13 on a CPU without AVX-512 traces some inactive lanes of rtcIntersect16
  // (measured: 1011 of 2000 on an AVX2 EPYC, on its own triangle geometry just as on ours), so
  // what the plugin owes is what Embree's triangles do: an inactive lane they leave untouched stays
  // untouched, one that Embree traces anyway gets the single-ray answer.
  auto check_packets = [&](const std::vector<RTCRayHit>& out, SomeLanes lanes, int n,
                           const std::vector<RTCRayHit>& triangles_out) {
    size_t active = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
      if (!lanes(i) && !same_bits(triangles_out[i], inactive_lane(in[i]))) {
        EXPECT_TRUE(same_bits(out[i], single[i]))
            << "rtcIntersect" << n << " inactive lane " << i << " traced by Embree as on its triangles\n"
            << describe(out[i]) << "\n"
            << describe(single[i]);
      } else if (lanes(i)) {
        ++active;
        EXPECT_TRUE(same_bits(out[i], single[i])) << "rtcIntersect" << n << " lane " << i << "\n"
                                                  << describe(out[i]) << "\n"
                                                  << describe(single[i]);
      } else {
        EXPECT_TRUE(same_bits(out[i], inactive_lane(in[i]))) << "rtcIntersect" << n << " touched inactive lane " << i;
      }
    }
    EXPECT_GT(active, rays.size() / 2);
    EXPECT_LT(active, rays.size());
  };
  check_packets(intersect_packets<4>(a.get(), in, SomeLanes{1}), SomeLanes{1}, 4,
                intersect_packets<4>(b.get(), in, SomeLanes{1}));
  check_packets(intersect_packets<8>(a.get(), in, SomeLanes{2}), SomeLanes{2}, 8,
                intersect_packets<8>(b.get(), in, SomeLanes{2}));
  check_packets(intersect_packets<16>(a.get(), in, SomeLanes{3}), SomeLanes{3}, 16,
                intersect_packets<16>(b.get(), in, SomeLanes{3}));

  // Occlusion: occluded exactly when rtcIntersect found a hit; otherwise the ray is untouched.
  std::vector<RTCRay> rin(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) rin[i] = in[i].ray;
  // As for rtcIntersect16: an inactive lane that Embree traces on its triangles is checked as an
  // active one.
  auto check_occluded = [&](const std::vector<RTCRay>& out, SomeLanes lanes, int n,
                            const std::vector<RTCRay>& triangles_out) {
    for (size_t i = 0; i < rays.size(); ++i) {
      if (!lanes(i) && same_bits(triangles_out[i], rin[i])) {
        EXPECT_TRUE(same_bits(out[i], rin[i])) << "rtcOccluded" << n << " touched inactive lane " << i;
      } else if (is_hit(single[i])) {
        EXPECT_TRUE(is_occluded(out[i])) << "rtcOccluded" << n << " ray " << i << " " << describe(rays[i]);
      } else {
        EXPECT_TRUE(same_bits(out[i], rin[i])) << "rtcOccluded" << n << " ray " << i << " " << describe(rays[i]);
      }
    }
  };
  std::vector<RTCRay> one(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) one[i] = occluded1(a.get(), rays[i], nullptr, unsigned(i));
  check_occluded(occluded_packets<4>(a.get(), rin, SomeLanes{4}), SomeLanes{4}, 4,
                 occluded_packets<4>(b.get(), rin, SomeLanes{4}));
  check_occluded(occluded_packets<8>(a.get(), rin, SomeLanes{5}), SomeLanes{5}, 8,
                 occluded_packets<8>(b.get(), rin, SomeLanes{5}));
  check_occluded(occluded_packets<16>(a.get(), rin, SomeLanes{6}), SomeLanes{6}, 16,
                 occluded_packets<16>(b.get(), rin, SomeLanes{6}));
  for (size_t i = 0; i < rays.size(); ++i) {
    EXPECT_EQ(is_occluded(one[i]), is_hit(single[i])) << "rtcOccluded1 ray " << i << " " << describe(rays[i]);
    if (!is_hit(single[i])) {
      EXPECT_TRUE(same_bits(one[i], rin[i])) << "rtcOccluded1 changed a ray it did not occlude";
    }
    EXPECT_EQ(is_occluded(occluded1(b.get(), rays[i])), is_hit(single[i])) << "triangles, ray " << i;
  }
  ASSERT_EQ(device.error(), RTC_ERROR_NONE);
  std::printf(
      "[watertight] %zu rays, %zu hits (%zu with tnear > 0 or finite tfar), %zu shared-edge primID "
      "differences; worst |dt|/diag %.3g, u,v point error/diag %.3g, | |Ng|-1 | %.3g, 1-Ng.n_tri %.3g, "
      "1-|Ng.Ng_embree| %.3g\n",
      rays.size(), hits, limited, shared_edge, dt.value, bary.value, ng_unit.value, ng_tri.value, ng_embree.value);
}

// Whether the exact w (double, test_util.h) crosses 1/2 at the hit the right way: the ray enters
// {w > 1/2} where Ng (outward) faces it, and leaves it elsewhere. Sampled at `delta` before and
// after the hit along the ray; returns the two values.
std::pair<double, double> w_around(const reference::ReferenceMesh& ref, const Ray& r, float t, double delta) {
  const dvec3 p = hit_point(r, t), step = delta * glm::normalize(dvec3(r.direction));
  return {reference::reference_w(ref, p - step), reference::reference_w(ref, p + step)};
}
bool crosses_half(const std::pair<double, double>& w, bool entering) {
  return entering ? w.first < 0.5 && w.second > 0.5 : w.first > 0.5 && w.second < 0.5;
}

// ---------------------------------------------------------------------------------------------
// 2. An open mesh: the plugin against trace_surface called directly.
// ---------------------------------------------------------------------------------------------

// Views of bunny_holes: of each hole, and of the whole from around.
std::vector<Ray> bunny_holes_rays(const GwnModel& model, int res) {
  std::vector<Ray> rays = hole_rays(model, res);
  const std::vector<Ray> around = camera_rays(scaled(model.bounds(), 0.6f), res, {{30, -60}, {200, -35}, {110, 15}});
  rays.insert(rays.end(), around.begin(), around.end());
  return rays;
}

TEST(EmbreePlugin, OpenMeshMatchesTraceSurface) {
  const Mesh mesh = load_test_mesh("bunny_holes.obj");
  const GwnModel model = build_model(mesh);
  ASSERT_GT(model.boundary().segment_count(), 0u) << "the mesh must have holes";
  const ModelView view = model.view();
  const TraceOptions options{};
  Device device;
  Scene scene(device);
  const unsigned id = scene.attach(gwn_geometry(device.get(), mesh));
  scene.commit();
  ASSERT_EQ(device.error(), RTC_ERROR_NONE);

  const std::vector<Ray> rays = bunny_holes_rays(model, 40);
  const reference::ReferenceMesh exact = reference::reference_mesh(mesh);
  const double diag = diagonal(model.bounds());
  size_t sheet = 0, smooth = 0, limited = 0, off_surface = 0;
  Worst dt;
  for (size_t i = 0; i < rays.size(); ++i) {
    const Ray& r = rays[i];
    const RayHit ref = trace_surface(view, r, options);
    const RTCRayHit h = intersect1(scene.get(), r);
    SCOPED_TRACE(describe(r) + "\n" + describe(h));
    ASSERT_EQ(is_hit(h), ref.hit) << "reference t " << ref.t;
    EXPECT_EQ(is_occluded(occluded1(scene.get(), r)), ref.hit);
    if (!ref.hit) continue;
    // The same computation on the same floats: 1e-6 relative leaves room only for a change of
    // evaluation order, nothing of the size of the stopping distance (1e-5 of the diagonal).
    dt.see(std::fabs(h.ray.tfar - ref.t) / ref.t);
    EXPECT_LE(std::fabs(h.ray.tfar - ref.t), 1e-6f * ref.t) << "reference t " << ref.t;
    EXPECT_EQ(h.hit.geomID, id);
    EXPECT_LE(glm::length(normal_of(h) - dvec3(ref.normal)), 1e-6);
    if (ref.kind == HitKind::kSmooth) {
      ++smooth;
      EXPECT_EQ(h.hit.primID, GWNRT_SMOOTH_PRIM_ID);
      EXPECT_EQ(h.hit.u, 0.0f);
      EXPECT_EQ(h.hit.v, 0.0f);
    } else {
      ++sheet;
      EXPECT_EQ(h.hit.primID, ref.triangle);
    }
    // Independently of the tracer: the exact w crosses 1/2 there, the way Ng says. 2e-4 of the
    // diagonal on either side is 20 stopping distances (smooth hits stop within one, plus the
    // multipole error of φ), and closer than any two sheets of the bunny along these rays.
    const bool entering = glm::dot(normal_of(h), dvec3(r.direction)) < 0;
    const auto w = w_around(exact, r, h.ray.tfar, 2e-4 * diag);
    if (!crosses_half(w, entering)) {
      ++off_surface;
      ADD_FAILURE() << "w " << w.first << " -> " << w.second << " around the hit, entering " << entering << ", kind "
                    << int(ref.kind);
    }
    // Embree's open interval: with tfar at the hit there is nothing before it; with tnear at
    // the hit, the next hit after it (trace_surface with the same rule as an accept functor).
    if (i % 4 == 0) {
      ++limited;
      Ray before = r;
      before.tfar = h.ray.tfar;
      EXPECT_FALSE(is_hit(intersect1(scene.get(), before))) << "a hit at t = tfar counts";
      EXPECT_FALSE(is_occluded(occluded1(scene.get(), before))) << "a hit at t = tfar occludes";
      Ray after = r;
      after.tnear = h.ray.tfar;
      const RayHit next = trace_surface(view, after, options, [&](const RayHit& x) { return x.t > after.tnear; });
      const RTCRayHit hn = intersect1(scene.get(), after);
      ASSERT_EQ(is_hit(hn), next.hit) << "after the hit: " << describe(hn);
      if (next.hit) {
        EXPECT_GT(hn.ray.tfar, after.tnear);
        EXPECT_LE(std::fabs(hn.ray.tfar - next.t), 1e-6f * next.t);
      }
    }
  }
  // The views must see both kinds, the holes' caps in numbers.
  EXPECT_GT(sheet, rays.size() / 4);
  EXPECT_GT(smooth, rays.size() / 50);
  std::printf(
      "[open mesh] %zu rays: %zu sheet hits, %zu smooth hits, %zu off S by the exact w; %zu rays cut at the hit; "
      "worst |dt|/t %.3g\n",
      rays.size(), sheet, smooth, off_surface, limited, dt.value);
}

// Non-default options reach the tracer unchanged: each geometry against trace_surface with the
// same TraceOptions (levels other than 1/2, solid-angle mode, other epsilon, caps and beta).
TEST(EmbreePlugin, OptionsReachTheTracer) {
  const Mesh mesh = load_test_mesh("bunny_holes.obj");
  const GwnModel model = build_model(mesh);
  const std::vector<Ray> rays = hole_rays(model, 20);
  Device device;
  struct Case {
    GWNRTMode mode;
    float level, epsilon;
    unsigned max_steps, max_crossings;
    float beta;
    bool caps_bite;  // the caps are small enough to end some traces (a capped trace is a miss)
  };
  for (const Case& c : {Case{GWNRT_MODE_GWN, 0.7f, 3e-5f, 300, 1000, 3.0f, false},
                        Case{GWNRT_MODE_SOLID_ANGLE, 0.5f, 1e-5f, 4096, 65536, 2.0f, false},
                        Case{GWNRT_MODE_SOLID_ANGLE, 0.3f, 2e-4f, 8, 65536, 1.5f, true},
                        Case{GWNRT_MODE_GWN, 1.5f, 1e-5f, 4096, 1, 2.0f, true}}) {
    GWNRTOptions o;
    gwnrtInitOptions(&o);
    o.mode = c.mode;
    o.level = c.level;
    o.epsilon = c.epsilon;
    o.max_steps = c.max_steps;
    o.max_crossings = c.max_crossings;
    o.beta = c.beta;
    TraceOptions t;
    t.mode = c.mode == GWNRT_MODE_SOLID_ANGLE ? TraceMode::kSolidAngle : TraceMode::kWindingNumber;
    t.level = c.level;
    t.epsilon = c.epsilon;
    t.max_steps = c.max_steps;
    t.max_crossings = c.max_crossings;
    t.beta = c.beta;
    Scene scene(device);
    scene.attach(gwn_geometry(device.get(), mesh, &o));
    scene.commit();
    size_t hits = 0, capped = 0;
    for (const Ray& r : rays) {
      const RayHit ref = trace_surface(model.view(), r, t);
      const RTCRayHit h = intersect1(scene.get(), r);
      capped += ref.capped;
      ASSERT_EQ(is_hit(h), ref.hit) << "mode " << c.mode << " level " << c.level << "\n" << describe(r);
      if (!ref.hit) continue;
      ++hits;
      EXPECT_LE(std::fabs(h.ray.tfar - ref.t), 1e-6f * ref.t);  // the same computation (see above)
      EXPECT_EQ(h.hit.primID, ref.kind == HitKind::kSmooth ? GWNRT_SMOOTH_PRIM_ID : ref.triangle);
    }
    if (c.caps_bite) {
      EXPECT_GT(capped, rays.size() / 20) << "mode " << c.mode << " level " << c.level;
    } else {
      EXPECT_GT(hits, rays.size() / 20) << "mode " << c.mode << " level " << c.level;
    }
  }
  ASSERT_EQ(device.error(), RTC_ERROR_NONE);
}

// ---------------------------------------------------------------------------------------------
// 3. Instances: the transformed mesh traced directly in world space.
// ---------------------------------------------------------------------------------------------

struct InstanceCase {
  Affine f;
  GwnModel model;  // of the transformed mesh
  Mesh mesh;
  unsigned id = kInvalidId;  // in the top scene
};

TEST(EmbreePlugin, InstancesMatchTransformedMesh) {
  const Mesh mesh = load_test_mesh("bunny_holes.obj");
  const Aabb box = test::mesh_bounds(mesh);
  const dvec3 centre(box.centre());
  Device device;
  Scene object(device);
  constexpr unsigned kGwnId = 3;
  object.attach(gwn_geometry(device.get(), mesh), kGwnId);
  object.commit();
  // Rigid motions with uniform scales (w, hence S, is invariant under them): one enlarging, one
  // shrinking, side by side and overlapping in depth for some views.
  InstanceCase cases[2];
  cases[0].f = similarity({0.3, 1.0, 0.2}, 40.0, 1.7, dvec3(-6.0, 1.0, 0.5) - 1.7 * centre);
  cases[1].f = similarity({-1.0, 0.4, 0.7}, -115.0, 0.6, dvec3(5.0, -0.5, -1.0) - 0.6 * centre);
  Scene top(device);
  Aabb world;
  for (InstanceCase& c : cases) {
    c.mesh = transformed(mesh, c.f);
    c.model = build_model(c.mesh);
    world.extend(c.model.bounds());
  }
  cases[0].id = top.attach(instance_geometry(device.get(), object.get(), cases[0].f), 8);
  cases[1].id = top.attach(instance_geometry(device.get(), object.get(), cases[1].f), 2);
  top.commit();
  ASSERT_EQ(device.error(), RTC_ERROR_NONE);

  // World cameras, and each instance's views of its holes (object-space rays moved to world).
  std::vector<Ray> rays = camera_rays(scaled(world, 0.7f), 36, {{10, -40}, {190, -20}, {95, 60}});
  const std::vector<Ray> holes = hole_rays(build_model(mesh), 28);
  for (const InstanceCase& c : cases) {
    for (const Ray& o : holes) rays.push_back(Ray{vec3(c.f.apply(dvec3(o.origin))), vec3(c.f.L * dvec3(o.direction))});
  }
  const TraceOptions options{};
  size_t hits = 0, smooth = 0, near_boundary = 0, per_instance[2] = {0, 0};
  Worst dt_sheet, dt_smooth, n_sheet, n_smooth;
  for (size_t i = 0; i < rays.size(); ++i) {
    const Ray& r = rays[i];
    RayHit ref;
    int which = -1;
    double other_t = kInfF;
    for (int k = 0; k < 2; ++k) {
      const RayHit h = trace_surface(cases[k].model.view(), r, options);
      if (!h.hit) continue;
      if (h.t < ref.t) {
        other_t = ref.t;
        ref = h;
        which = k;
      } else {
        other_t = std::min(other_t, double(h.t));
      }
    }
    const RTCRayHit h = intersect1(top.get(), r);
    SCOPED_TRACE(describe(r) + "\n" + describe(h) + "\nreference t " + std::to_string(ref.t) + " kind " +
                 std::to_string(int(ref.kind)));
    ASSERT_EQ(is_hit(h), ref.hit);
    EXPECT_EQ(is_occluded(occluded1(top.get(), r)), ref.hit);
    if (!ref.hit) continue;
    ++hits;
    const InstanceCase& c = cases[which];
    const double diag = diagonal(c.model.bounds());
    const double len = glm::length(dvec3(r.direction));
    const double dt = std::fabs(double(h.ray.tfar) - double(ref.t)) * len / diag;
    const double dn = 1 - glm::dot(c.f.normal(normal_of(h)), dvec3(ref.normal));
    // Which instance: unambiguous unless the other one's hit is as near.
    if ((other_t - ref.t) * len > 1e-3 * diag) {
      EXPECT_EQ(h.hit.instID[0], c.id);
    }
    ++per_instance[which];
    EXPECT_EQ(h.hit.geomID, kGwnId);
    if (ref.kind == HitKind::kSheet) {
      // Both intersect the same triangle; the object-space ray and the world-space triangle
      // differ by float round-off of the transform (~1e-7 of the diagonal each).
      dt_sheet.see(dt);
      n_sheet.see(dn);
      EXPECT_LE(dt, 1e-5);
      EXPECT_LE(dn, 1e-5);
      if (h.hit.primID != ref.triangle) {  // a shared edge: the point lies on both
        const dvec3 p = hit_point(r, ref.t);
        EXPECT_LE(distance_to_triangle(c.mesh, h.hit.primID, p), 1e-5 * diag);
        EXPECT_LE(distance_to_triangle(c.mesh, ref.triangle, p), 1e-5 * diag);
      }
    } else {
      ++smooth;
      EXPECT_EQ(h.hit.primID, GWNRT_SMOOTH_PRIM_ID);
      // A smooth hit stops within the stopping distance (epsilon 1e-5 of each model's own
      // diagonal: the rotated box's differs from the object box's) of S, and the two trees
      // approximate φ differently (beta 2); along a slanted ray both grow by 1/cos. 2e-4 of
      // the diagonal is 20 stopping distances (measured: ~2).
      dt_smooth.see(dt);
      EXPECT_LE(dt, 2e-4);
      // The normal is ∇w's direction at two points that close; it turns at a rate 1/ρ at
      // distance ρ from ∂M. Beyond 1e-3 of the diagonal from ∂M that is at most ~1e-2 rad
      // (1 - cos: 5e-5; measured 1e-5); nearer, ∇w's direction is all but undefined and only
      // the side is checked.
      const double rho = distance_to_boundary(c.model.boundary(), hit_point(r, ref.t));
      if (rho > 1e-3 * diag) {
        n_smooth.see(dn);
        EXPECT_LE(dn, 1e-4) << "at " << rho / diag << " diagonals from the boundary";
      } else {
        ++near_boundary;
        EXPECT_LT(dn, 1.0) << "the normal points to the wrong side";
      }
    }
  }
  EXPECT_GT(per_instance[0], rays.size() / 10);
  EXPECT_GT(per_instance[1], rays.size() / 10);
  EXPECT_GT(smooth, hits / 50);

  // Packets through the instances: exactly the single-ray results.
  std::vector<RTCRayHit> in(rays.size()), single(rays.size());
  for (size_t i = 0; i < rays.size(); i += 3) {  // a third of them: enough lanes, a third of the time
    in[i] = make_rayhit(rays[i], unsigned(i));
    single[i] = intersect1(top.get(), rays[i], nullptr, unsigned(i));
  }
  const auto every_third = [](size_t i) { return i % 3 == 0; };
  const std::vector<RTCRayHit> out = intersect_packets<8>(top.get(), in, every_third);
  for (size_t i = 0; i < rays.size(); i += 3) EXPECT_TRUE(same_bits(out[i], single[i])) << "rtcIntersect8 lane " << i;
  ASSERT_EQ(device.error(), RTC_ERROR_NONE);
  std::printf(
      "[instances] %zu rays, %zu hits (%zu / %zu per instance, %zu smooth, %zu of them near the boundary); worst "
      "|dt|/diag sheet %.3g smooth %.3g, 1-n.n_ref sheet %.3g smooth %.3g\n",
      rays.size(), hits, per_instance[0], per_instance[1], smooth, near_boundary, dt_sheet.value, dt_smooth.value,
      n_sheet.value, n_smooth.value);
}

// ---------------------------------------------------------------------------------------------
// 4. Filters.
// ---------------------------------------------------------------------------------------------

struct Candidate {
  float t;
  uint32_t prim;
  float u, v;
  unsigned geom, inst;
};

enum class Policy { kRejectFirst, kRejectAll };

// What filters see, per ray id; reached from the context (Embree's own idiom: the filter gets
// the context pointer the application passed).
struct FilterState {
  Policy policy = Policy::kRejectAll;
  std::vector<std::vector<Candidate>> seen;
  void reset(size_t rays, Policy p) {
    policy = p;
    seen.assign(rays, {});
  }
};

struct FilterContext {
  RTCIntersectContext context;  // first: Embree hands its address to the filter
  FilterState* state;
};

void record_filter(const RTCFilterFunctionNArguments* args) {
  FilterState* state = reinterpret_cast<const FilterContext*>(args->context)->state;
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    const unsigned id = RTCRayN_id(args->ray, args->N, i);
    // Embree sets the ray's tfar to the candidate's t while the filter runs.
    const Candidate c{RTCRayN_tfar(args->ray, args->N, i),   RTCHitN_primID(args->hit, args->N, i),
                      RTCHitN_u(args->hit, args->N, i),      RTCHitN_v(args->hit, args->N, i),
                      RTCHitN_geomID(args->hit, args->N, i), RTCHitN_instID(args->hit, args->N, i, 0)};
    std::vector<Candidate>& seen = state->seen.at(id);
    seen.push_back(c);
    if (state->policy == Policy::kRejectAll || seen.size() == 1) args->valid[i] = 0;
  }
}

FilterContext filter_context(FilterState& state, bool as_context_filter) {
  FilterContext c;
  rtcInitIntersectContext(&c.context);
  if (as_context_filter) c.context.filter = record_filter;
  c.state = &state;
  return c;
}

// Every crossing of the ray with the triangles, sorted by t: Embree's triangles with a filter
// that records and rejects all. Sets `ambiguous` where the list is not well defined: the ray
// passes near an edge (Embree may report both triangles, or either) or two crossings coincide.
std::vector<Candidate> all_crossings(RTCScene triangles, const Ray& r, double diag, bool& ambiguous) {
  FilterState state;
  state.reset(1, Policy::kRejectAll);
  FilterContext context = filter_context(state, false);
  intersect1(triangles, r, &context.context, 0);
  std::vector<Candidate> c = state.seen[0];
  std::sort(c.begin(), c.end(), [](const Candidate& a, const Candidate& b) { return a.t < b.t; });
  c.erase(std::unique(c.begin(), c.end(), [](const Candidate& a, const Candidate& b) { return a.prim == b.prim; }),
          c.end());
  const double len = glm::length(dvec3(r.direction));
  ambiguous = false;
  for (size_t k = 0; k < c.size(); ++k) {
    if (std::min({c[k].u, c[k].v, 1 - c[k].u - c[k].v}) < 1e-4f) ambiguous = true;
    if (k > 0 && double(c[k].t - c[k - 1].t) * len < 1e-5 * diag) ambiguous = true;
  }
  return c;
}

void check_filters(bool as_context_filter) {
  const Mesh mesh = load_test_mesh("bunny.obj");
  const Aabb box = test::mesh_bounds(mesh);
  const double diag = diagonal(box);
  Device device;
  Scene triangles(device);
  triangles.attach([&] {
    RTCGeometry g = render::new_triangle_geometry(device.get(), mesh);
    rtcSetGeometryIntersectFilterFunction(g, record_filter);
    return g;
  }());
  triangles.commit();
  Scene gwn(device, as_context_filter ? RTCSceneFlags(RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION)
                                      : RTC_SCENE_FLAG_ROBUST);
  RTCGeometry g = gwn_geometry(device.get(), mesh);
  if (!as_context_filter) {
    rtcSetGeometryIntersectFilterFunction(g, record_filter);
    rtcSetGeometryOccludedFilterFunction(g, record_filter);
  }
  const unsigned gwn_id = gwn.attach(g);
  gwn.commit();
  ASSERT_EQ(device.error(), RTC_ERROR_NONE);

  std::vector<Ray> rays = camera_rays(scaled(box, 0.6f), 32, {{45, 10}, {220, 30}});
  const std::vector<Ray> random = random_rays(box, 2000, 21);
  rays.insert(rays.end(), random.begin(), random.end());
  const double tol = 1e-5 * diag;  // the same float crossings as in WatertightMatchesEmbreeTriangles

  FilterState state;
  FilterContext context = filter_context(state, as_context_filter);
  size_t checked = 0, ambiguous_rays = 0, two_or_more = 0;
  std::vector<RTCRayHit> first_rejected(rays.size());
  state.reset(rays.size(), Policy::kRejectFirst);
  for (size_t i = 0; i < rays.size(); ++i)
    first_rejected[i] = intersect1(gwn.get(), rays[i], &context.context, unsigned(i));
  const std::vector<std::vector<Candidate>> seen_first = state.seen;
  state.reset(rays.size(), Policy::kRejectAll);
  std::vector<RTCRayHit> all_rejected(rays.size());
  for (size_t i = 0; i < rays.size(); ++i)
    all_rejected[i] = intersect1(gwn.get(), rays[i], &context.context, unsigned(i));
  const std::vector<std::vector<Candidate>> seen_all = state.seen;

  for (size_t i = 0; i < rays.size(); ++i) {
    const Ray& r = rays[i];
    const double len = glm::length(dvec3(r.direction));
    bool ambiguous;
    const std::vector<Candidate> crossings = all_crossings(triangles.get(), r, diag, ambiguous);
    SCOPED_TRACE(describe(r) + "\nreject first: " + describe(first_rejected[i]) +
                 "\ncrossings: " + std::to_string(crossings.size()));
    // Rejecting everything: a miss, the ray untouched (tfar restored after each rejection).
    EXPECT_TRUE(same_bits(all_rejected[i], make_rayhit(r, unsigned(i)))) << describe(all_rejected[i]);
    if (ambiguous) {
      ++ambiguous_rays;
      continue;
    }
    ++checked;
    // The filter was offered every crossing, each once, in increasing t, with its hit data.
    const std::vector<Candidate>& all = seen_all[i];
    ASSERT_EQ(all.size(), crossings.size());
    for (size_t k = 0; k < all.size(); ++k) {
      EXPECT_LE(std::fabs(all[k].t - crossings[k].t) * len, tol) << "candidate " << k;
      EXPECT_EQ(all[k].prim, crossings[k].prim) << "candidate " << k;
      EXPECT_EQ(all[k].geom, gwn_id);
      EXPECT_EQ(all[k].inst, kInvalidId);
      if (k > 0) {
        EXPECT_GT(all[k].t, all[k - 1].t) << "candidates out of order";
      }
    }
    // Rejecting the first: the second crossing, after exactly two offers.
    const RTCRayHit& h = first_rejected[i];
    EXPECT_EQ(seen_first[i].size(), std::min<size_t>(crossings.size(), 2));
    if (crossings.size() < 2) {
      EXPECT_FALSE(is_hit(h));
      continue;
    }
    ++two_or_more;
    ASSERT_TRUE(is_hit(h));
    EXPECT_LE(std::fabs(h.ray.tfar - crossings[1].t) * len, tol);
    EXPECT_EQ(h.hit.primID, crossings[1].prim);
    EXPECT_EQ(h.hit.geomID, gwn_id);
  }
  EXPECT_LT(ambiguous_rays, rays.size() / 50);
  EXPECT_GT(two_or_more, checked / 4);

  // Packets with the filter: the same as one ray at a time.
  std::vector<RTCRayHit> in(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) in[i] = make_rayhit(rays[i], unsigned(i));
  state.reset(rays.size(), Policy::kRejectFirst);
  const std::vector<RTCRayHit> out = intersect_packets<8>(gwn.get(), in, SomeLanes{7}, &context.context);
  for (size_t i = 0; i < rays.size(); ++i)
    if (SomeLanes{7}(i)) {
      EXPECT_TRUE(same_bits(out[i], first_rejected[i])) << "rtcIntersect8 lane " << i;
    }

  // Occlusion with the filters: rejecting all is never occluded; rejecting the first is occluded
  // exactly when there is a second crossing.
  for (Policy p : {Policy::kRejectAll, Policy::kRejectFirst}) {
    state.reset(rays.size(), p);
    for (size_t i = 0; i < rays.size(); ++i) {
      const RTCRay o = occluded1(gwn.get(), rays[i], &context.context, unsigned(i));
      if (p == Policy::kRejectAll) {
        EXPECT_TRUE(same_bits(o, make_rayhit(rays[i], unsigned(i)).ray)) << "ray " << i;
      } else {
        EXPECT_EQ(is_occluded(o), is_hit(first_rejected[i])) << "ray " << i << " " << describe(rays[i]);
      }
      EXPECT_EQ(state.seen[i].size(), p == Policy::kRejectAll ? seen_all[i].size() : seen_first[i].size());
    }
  }
  ASSERT_EQ(device.error(), RTC_ERROR_NONE);
  std::printf("[filters, %s] %zu rays, %zu checked (%zu near an edge skipped), %zu with a second crossing\n",
              as_context_filter ? "context filter" : "geometry filter", rays.size(), checked, ambiguous_rays,
              two_or_more);
}

TEST(EmbreePlugin, GeometryFilterSeesEveryCrossingInOrder) { check_filters(false); }

TEST(EmbreePlugin, ContextFilterSeesEveryCrossingInOrder) { check_filters(true); }

// Inside an instance a filter sees the instance's ID in the candidate's instID, for occlusion
// as for intersection, as it does for Embree's own triangles in the same place.
TEST(EmbreePlugin, FiltersInsideInstancesSeeInstanceId) {
  const Mesh mesh = test::make_sphere(2);
  Device device;
  Scene gwn_object(device), tri_object(device);
  for (auto [scene, g] : {std::pair{&gwn_object, gwn_geometry(device.get(), mesh)},
                          std::pair{&tri_object, render::new_triangle_geometry(device.get(), mesh)}}) {
    rtcSetGeometryIntersectFilterFunction(g, record_filter);
    rtcSetGeometryOccludedFilterFunction(g, record_filter);
    scene->attach(g);
    scene->commit();
  }
  Scene gwn_top(device), tri_top(device);
  const Affine f = similarity({1, 2, 3}, 30, 1.5, {0.5, -0.25, 2});
  constexpr unsigned kInstanceId = 6;
  gwn_top.attach(instance_geometry(device.get(), gwn_object.get(), f), kInstanceId);
  tri_top.attach(instance_geometry(device.get(), tri_object.get(), f), kInstanceId);
  gwn_top.commit();
  tri_top.commit();
  const Ray r{vec3(f.T) + vec3(0.1f, 0.2f, -10.0f), vec3(0, 0, 1)};
  for (bool occlusion : {false, true}) {
    for (RTCScene top : {tri_top.get(), gwn_top.get()}) {
      FilterState state;
      state.reset(1, Policy::kRejectFirst);
      FilterContext context = filter_context(state, false);
      if (occlusion) {
        EXPECT_TRUE(is_occluded(occluded1(top, r, &context.context)));
      } else {
        const RTCRayHit h = intersect1(top, r, &context.context);
        ASSERT_TRUE(is_hit(h));
        EXPECT_EQ(h.hit.instID[0], kInstanceId);
      }
      ASSERT_EQ(state.seen[0].size(), 2u);
      const char* what = top == gwn_top.get() ? "GWN" : "triangles";
      for (const Candidate& c : state.seen[0])
        EXPECT_EQ(c.inst, kInstanceId) << what << (occlusion ? " occlusion" : " intersection") << " filter";
    }
  }
  ASSERT_EQ(device.error(), RTC_ERROR_NONE);
}

// ---------------------------------------------------------------------------------------------
// 5. Masks.
// ---------------------------------------------------------------------------------------------

TEST(EmbreePlugin, GeometryMaskAgainstRayMask) {
  Device device;
  if (rtcGetDeviceProperty(device.get(), RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED) == 0)
    GTEST_SKIP() << "this Embree build has ray masks disabled";
  const Mesh mesh = load_test_mesh("bunny_holes.obj");
  Scene scene(device);
  RTCGeometry g = gwn_geometry(device.get(), mesh);
  rtcSetGeometryMask(g, 0x6u);
  scene.attach(g);
  scene.commit();
  const std::vector<Ray> rays = hole_rays(build_model(mesh), 8);
  std::vector<RTCRayHit> in(rays.size());
  size_t hits = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    const RTCRayHit all = intersect1(scene.get(), rays[i], nullptr, 0, ~0u);
    hits += is_hit(all);
    for (unsigned mask : {0x2u, 0x4u, 0x7u})
      EXPECT_TRUE(same_bits(intersect1(scene.get(), rays[i], nullptr, 0, mask).hit, all.hit)) << "mask " << mask;
    for (unsigned mask : {0x1u, 0x8u, 0x0u}) {
      EXPECT_FALSE(is_hit(intersect1(scene.get(), rays[i], nullptr, 0, mask))) << "mask " << mask;
      EXPECT_FALSE(is_occluded(occluded1(scene.get(), rays[i], nullptr, 0, mask))) << "mask " << mask;
    }
    // For packets: odd lanes do not match (they come back untouched), even ones do.
    in[i] = make_rayhit(rays[i], 0, i % 2 ? 0x1u : 0x4u);
    if (i % 2 == 0) {
      in[i].hit = all.hit;
      in[i].ray.tfar = all.ray.tfar;
    }
  }
  EXPECT_GT(hits, rays.size() / 3);
  // Packets mixing matching and non-matching lanes.
  std::vector<RTCRayHit> start(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) start[i] = make_rayhit(rays[i], 0, in[i].ray.mask);
  const std::vector<RTCRayHit> out = intersect_packets<8>(scene.get(), start, [](size_t) { return true; });
  for (size_t i = 0; i < rays.size(); ++i) EXPECT_TRUE(same_bits(out[i], in[i])) << "rtcIntersect8 lane " << i;
  ASSERT_EQ(device.error(), RTC_ERROR_NONE);
}

// ---------------------------------------------------------------------------------------------
// 6. Many threads.
// ---------------------------------------------------------------------------------------------

TEST(EmbreePlugin, ThreadsGiveIdenticalResults) {
  const Mesh holes = load_test_mesh("bunny_holes.obj");
  const Aabb box = test::mesh_bounds(holes);
  const double diag = diagonal(box);
  Device device;
  Scene scene(device);
  scene.attach(gwn_geometry(device.get(), holes));
  // A sphere cutting through the bunny's side, beside the GWN object in the same scene.
  Mesh sphere = test::make_sphere(2, float(0.2 * diag));
  for (vec3& p : sphere.positions) p += vec3(box.hi.x, box.centre().y, box.centre().z);
  scene.attach(render::new_triangle_geometry(device.get(), sphere));
  scene.commit();
  Aabb both = box;
  both.extend(test::mesh_bounds(sphere));
  std::vector<Ray> rays = hole_rays(build_model(holes), 16);
  const std::vector<Ray> more = camera_rays(scaled(both, 0.7f), 16, {{30, -60}, {200, -35}});
  rays.insert(rays.end(), more.begin(), more.end());
  std::vector<RTCRayHit> in(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) in[i] = make_rayhit(rays[i], unsigned(i));
  auto pass = [&](std::vector<RTCRayHit>& one, std::vector<RTCRayHit>& eight) {
    one.resize(rays.size());
    for (size_t i = 0; i < rays.size(); ++i) one[i] = intersect1(scene.get(), rays[i], nullptr, unsigned(i));
    eight = intersect_packets<8>(scene.get(), in, [](size_t) { return true; });
  };
  std::vector<RTCRayHit> one, eight;
  pass(one, eight);
  size_t hits = 0, geoms[2] = {0, 0};
  for (const RTCRayHit& h : one)
    if (is_hit(h)) ++hits, ++geoms[std::min(h.hit.geomID, 1u)];
  EXPECT_GT(geoms[0], rays.size() / 10);
  EXPECT_GT(geoms[1], rays.size() / 50);
  for (size_t i = 0; i < rays.size(); ++i) EXPECT_TRUE(same_bits(one[i], eight[i])) << "ray " << i;
  constexpr int kThreads = 8;
  std::vector<std::vector<RTCRayHit>> ones(kThreads), eights(kThreads);
  std::vector<std::thread> threads;
  for (int k = 0; k < kThreads; ++k) threads.emplace_back([&, k] { pass(ones[k], eights[k]); });
  for (std::thread& t : threads) t.join();
  for (int k = 0; k < kThreads; ++k) {
    size_t differ = 0;
    for (size_t i = 0; i < rays.size(); ++i)
      differ += !same_bits(ones[k][i], one[i]) + !same_bits(eights[k][i], eight[i]);
    EXPECT_EQ(differ, 0u) << "thread " << k;
  }
  ASSERT_EQ(device.error(), RTC_ERROR_NONE);
}

// ---------------------------------------------------------------------------------------------
// 7. Bad input, errors, reference counting.
// ---------------------------------------------------------------------------------------------

bool mentions(const char* message, const std::string& what) {
  return std::string(message).find(what) != std::string::npos;
}

TEST(EmbreePlugin, BadMeshesAreRefusedWithAReason) {
  const float xyz[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const uint32_t tri[] = {0, 1, 2};
  const uint32_t out_of_range[] = {0, 1, 3};
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float with_nan[] = {0, 0, 0, 1, nan, 0, 0, 1, 0};
  // Each case is made right before its message is read (the message is the last failure's).
  auto check = [](const char* name, GWNRTMesh mesh, const char* mention) {
    EXPECT_EQ(mesh, nullptr) << name;
    EXPECT_TRUE(mentions(gwnrtGetLastError(), mention)) << name << ": \"" << gwnrtGetLastError() << "\"";
    gwnrtReleaseMesh(mesh);  // NULL is accepted
  };
  check("NULL vertices", gwnrtNewMesh(nullptr, 3, tri, 1), "NULL");
  check("NULL triangles", gwnrtNewMesh(xyz, 3, nullptr, 1), "NULL");
  check("index out of range", gwnrtNewMesh(xyz, 3, out_of_range, 1), "refers to vertex 3");
  check("NaN coordinate", gwnrtNewMesh(with_nan, 3, tri, 1), "non-finite");
  check("no triangles", gwnrtNewMesh(xyz, 3, tri, 0), "no triangles");
  check("no triangles, NULL", gwnrtNewMesh(xyz, 3, nullptr, 0), "no triangles");
  check("no vertices", gwnrtNewMesh(nullptr, 0, tri, 1), "refers to vertex 0");
  const std::string missing = test::data_path("no_such_mesh.obj");
  EXPECT_EQ(gwnrtLoadMesh(missing.c_str()), nullptr);
  EXPECT_TRUE(mentions(gwnrtGetLastError(), missing)) << gwnrtGetLastError();
  EXPECT_EQ(gwnrtLoadMesh(nullptr), nullptr);
  EXPECT_STRNE(gwnrtGetLastError(), "");
  EXPECT_EQ(gwnrtGetMeshTriangleCount(nullptr), 0u);
}

TEST(EmbreePlugin, BadGeometryArgumentsAreRefused) {
  Device device;
  const Mesh sphere = test::make_sphere(1);
  GWNRTMesh mesh = new_mesh(sphere);
  ASSERT_NE(mesh, nullptr);
  EXPECT_EQ(gwnrtGetMeshTriangleCount(mesh), sphere.triangles.size());
  EXPECT_EQ(gwnrtGetMeshVertexCount(mesh), sphere.positions.size());
  EXPECT_EQ(gwnrtNewGeometry(device.get(), nullptr, nullptr), nullptr);
  EXPECT_TRUE(mentions(gwnrtGetLastError(), "mesh")) << gwnrtGetLastError();
  EXPECT_EQ(gwnrtNewGeometry(nullptr, mesh, nullptr), nullptr);
  EXPECT_TRUE(mentions(gwnrtGetLastError(), "device")) << gwnrtGetLastError();
  GWNRTOptions defaults;
  gwnrtInitOptions(&defaults);
  EXPECT_EQ(defaults.mode, GWNRT_MODE_GWN);
  EXPECT_EQ(defaults.level, 0.5f);
  EXPECT_EQ(defaults.epsilon, 1e-5f);
  EXPECT_EQ(defaults.beta, 2.0f);
  struct Case {
    const char* name;
    void (*change)(GWNRTOptions&);
    const char* mention;
  };
  const Case cases[] = {
      {"epsilon 0", [](GWNRTOptions& o) { o.epsilon = 0; }, "epsilon"},
      {"epsilon < 0", [](GWNRTOptions& o) { o.epsilon = -1e-5f; }, "epsilon"},
      {"beta NaN", [](GWNRTOptions& o) { o.beta = std::numeric_limits<float>::quiet_NaN(); }, "beta"},
      {"level NaN", [](GWNRTOptions& o) { o.level = std::numeric_limits<float>::quiet_NaN(); }, "level"},
      {"mode 7", [](GWNRTOptions& o) { o.mode = static_cast<GWNRTMode>(7); }, "mode"},
      {"max_steps 0", [](GWNRTOptions& o) { o.max_steps = 0; }, "cap"},
  };
  for (const Case& c : cases) {
    GWNRTOptions o = defaults;
    c.change(o);
    EXPECT_EQ(gwnrtNewGeometry(device.get(), mesh, &o), nullptr) << c.name;
    EXPECT_TRUE(mentions(gwnrtGetLastError(), c.mention)) << c.name << ": \"" << gwnrtGetLastError() << "\"";
  }
  gwnrtReleaseMesh(mesh);
  // None of that is Embree's business.
  EXPECT_EQ(device.error(), RTC_ERROR_NONE);
}

TEST(EmbreePlugin, LastErrorIsPerThread) {
  EXPECT_EQ(gwnrtNewGeometry(nullptr, nullptr, nullptr), nullptr);
  const std::string mine = gwnrtGetLastError();
  ASSERT_FALSE(mine.empty());
  const std::string missing = test::data_path("missing_in_thread.ply");
  std::string fresh, theirs;
  std::thread t([&] {
    fresh = gwnrtGetLastError();
    EXPECT_EQ(gwnrtLoadMesh(missing.c_str()), nullptr);
    theirs = gwnrtGetLastError();
  });
  t.join();
  EXPECT_EQ(fresh, "") << "a new thread has no error";
  EXPECT_TRUE(mentions(theirs.c_str(), missing)) << theirs;
  EXPECT_EQ(gwnrtGetLastError(), mine) << "another thread's failure changed this thread's message";
}

TEST(EmbreePlugin, InvalidRaysMissWithoutCrashing) {
  Device device;
  Scene scene(device);
  scene.attach(gwn_geometry(device.get(), load_test_mesh("bunny_holes.obj")));
  scene.attach(gwn_geometry(device.get(), load_test_mesh("bunny.obj")));
  scene.commit();
  // Embree itself asserts on rays with NaN or infinite numbers (Debian's build keeps its
  // assertions: "bvh_intersector1.cpp:59: Assertion `ray.valid()' failed") before any geometry
  // sees them, so through Embree only finite rays can reach the plugin; what the callbacks do
  // with NaN is trace_surface's rejection, checked directly below.
  const vec3 inside(-0.5f, 4.0f, 0.0f);  // within both bunnies' boxes
  const std::vector<Ray> bad = {
      Ray{inside, vec3(0.0f)}, Ray{vec3(0.0f), vec3(0.0f)},
      Ray{inside, vec3(1e-45f, 0.0f, 0.0f)},  // a denormal direction: |d|² underflows in float
  };
  std::vector<RTCRayHit> in;
  for (const Ray& r : bad) {
    const RTCRayHit h = intersect1(scene.get(), r);
    EXPECT_FALSE(is_hit(h)) << describe(r) << "\n" << describe(h);
    EXPECT_FALSE(is_occluded(occluded1(scene.get(), r))) << describe(r);
    in.push_back(make_rayhit(r));
  }
  for (const RTCRayHit& h : intersect_packets<4>(scene.get(), in, [](size_t) { return true; }))
    EXPECT_FALSE(is_hit(h)) << describe(h);
  // What the callbacks run on rays Embree would pass on: rejected, no hit.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const GwnModel model = build_model(load_test_mesh("bunny_holes.obj"));
  for (const Ray& r : {Ray{vec3(nan, 4.0f, 0.0f), vec3(0, 0, 1)}, Ray{vec3(nan), vec3(0, 0, 1)},
                       Ray{inside, vec3(nan, 0.0f, 1.0f)}, Ray{inside, vec3(0.0f)}}) {
    const RayHit h = trace_surface(model.view(), r, TraceOptions{});
    EXPECT_TRUE(h.invalid) << describe(r);
    EXPECT_FALSE(h.hit) << describe(r);
  }
  ASSERT_EQ(device.error(), RTC_ERROR_NONE);
}

// The documented use (gwnrt/embree.h's top comment): the application drops its mesh reference
// right after making the geometry, and the geometry keeps the mesh alive; retain and release
// balance.
TEST(EmbreePlugin, MeshOutlivesApplicationReference) {
  Device device;
  const Mesh sphere = test::make_sphere(3);
  GWNRTMesh mesh = new_mesh(sphere);
  ASSERT_NE(mesh, nullptr);
  gwnrtRetainMesh(mesh);
  gwnrtReleaseMesh(mesh);  // balanced: still alive
  EXPECT_EQ(gwnrtGetMeshTriangleCount(mesh), sphere.triangles.size());
  RTCGeometry g1 = gwnrtNewGeometry(device.get(), mesh, nullptr);
  RTCGeometry g2 = gwnrtNewGeometry(device.get(), mesh, nullptr);
  ASSERT_NE(g1, nullptr);
  ASSERT_NE(g2, nullptr);
  gwnrtReleaseMesh(mesh);  // the application's reference
  Scene scene(device);
  scene.attach(g1);
  scene.attach(g2);
  scene.commit();
  // Fill freed memory, if any, with other data before tracing.
  std::vector<std::vector<float>> churn;
  for (int i = 0; i < 64; ++i) churn.emplace_back(4096, 1e30f);
  Random rng(77);
  for (int i = 0; i < 200; ++i) {
    const vec3 d = rng.unit();
    const RTCRayHit h = intersect1(scene.get(), Ray{-3.0f * d, d});
    ASSERT_TRUE(is_hit(h));
    // The icosphere's facets lie within 1 - cos(their angular circumradius, ~0.08) < 0.4% of the sphere.
    EXPECT_NEAR(h.ray.tfar, 2.0f, 0.005f);
    EXPECT_LT(h.hit.primID, sphere.triangles.size());
  }
  ASSERT_EQ(device.error(), RTC_ERROR_NONE);
}

// The sequence in gwnrt/embree.h's top comment, verbatim: attach, release, commit the scene.
TEST(EmbreePlugin, HeaderExampleSequenceWorks) {
  Device device;
  RTCScene scene = rtcNewScene(device.get());
  GWNRTMesh mesh = gwnrtLoadMesh(test::data_path("bunny.obj").c_str());
  ASSERT_NE(mesh, nullptr) << gwnrtGetLastError();
  RTCGeometry geom = gwnrtNewGeometry(device.get(), mesh, nullptr);
  ASSERT_NE(geom, nullptr) << gwnrtGetLastError();
  rtcAttachGeometry(scene, geom);
  rtcReleaseGeometry(geom);
  gwnrtReleaseMesh(mesh);
  rtcCommitScene(scene);
  const RTCError error = device.error();
  EXPECT_EQ(error, RTC_ERROR_NONE) << "rtcCommitScene failed (Embree 3 requires rtcCommitGeometry before it)";
  // A ray down through the bunny's box centre hits it (a ray known to hit, see the other tests).
  const Aabb box = test::mesh_bounds(load_test_mesh("bunny.obj"));
  const Ray r{vec3(box.centre().x, box.centre().y, box.hi.z + 1.0f), vec3(0, 0, -1)};
  EXPECT_TRUE(is_hit(intersect1(scene, r)));
  rtcReleaseScene(scene);
}

// A georeferenced scan (bunny_holes moved to UTM metres): gwnrtLoadMesh refuses it, naming the
// file; gwnrtLoadMeshRecentred loads it about its own centre and returns the origin, and rays
// moved by the file's offset minus origin (in double) then see what the bunny at the origin shows. The two models
// differ by float rounding about the centre (1e-8 of the diagonal), below the tracer's stopping distance (1e-5 of the
// diagonal): hit or miss agree on at least 99.9% of rays (the CUDA image's criterion), and t to 2 stopping distances on
// 99% of the hits (exact sheet crossings far closer).
TEST(EmbreePlugin, FarOffScanLoadsRecentred) {
  const std::string near_path = test::data_path("bunny_holes.obj"), far_path = test::temp_path("utm_plugin.obj");
  test::write_translated(near_path, far_path, test::kUtm, true);
  EXPECT_EQ(gwnrtLoadMesh(far_path.c_str()), nullptr);
  EXPECT_TRUE(mentions(gwnrtGetLastError(), far_path)) << gwnrtGetLastError();
  double origin[3] = {1, 2, 3};
  GWNRTMesh near_mesh = gwnrtLoadMeshRecentred(near_path.c_str(), origin);
  ASSERT_NE(near_mesh, nullptr) << gwnrtGetLastError();
  EXPECT_EQ(dvec3(origin[0], origin[1], origin[2]), dvec3(0.0));  // near the origin: not moved
  GWNRTMesh far_mesh = gwnrtLoadMeshRecentred(far_path.c_str(), origin);
  ASSERT_NE(far_mesh, nullptr) << gwnrtGetLastError();
  const dvec3 shift = dvec3(test::kUtm[0], test::kUtm[1], test::kUtm[2]) - dvec3(origin[0], origin[1], origin[2]);
  const GwnModel model = build_model(load_test_mesh("bunny_holes.obj"));
  const double diag = glm::length(dvec3(model.bounds().hi) - dvec3(model.bounds().lo));
  EXPECT_LT(glm::length(shift), diag);  // the origin is the box's centre, rounded
  EXPECT_EQ(gwnrtLoadMeshRecentred(far_path.c_str(), nullptr), nullptr);
  EXPECT_TRUE(mentions(gwnrtGetLastError(), "NULL origin")) << gwnrtGetLastError();
  double untouched[3] = {1, 2, 3};  // a failed call leaves no stale origin behind
  EXPECT_EQ(gwnrtLoadMeshRecentred(nullptr, untouched), nullptr);
  EXPECT_EQ(dvec3(untouched[0], untouched[1], untouched[2]), dvec3(0.0));

  Device device;
  RTCScene scenes[2];
  for (int k = 0; k < 2; ++k) {
    scenes[k] = rtcNewScene(device.get());
    RTCGeometry g = gwnrtNewGeometry(device.get(), k ? far_mesh : near_mesh, nullptr);
    ASSERT_NE(g, nullptr) << gwnrtGetLastError();
    rtcAttachGeometry(scenes[k], g);
    rtcReleaseGeometry(g);
    rtcCommitScene(scenes[k]);
  }
  gwnrtReleaseMesh(near_mesh);
  gwnrtReleaseMesh(far_mesh);
  const std::vector<Ray> rays = bunny_holes_rays(model, 24);
  size_t agree = 0, hits = 0, close = 0;
  for (const Ray& r : rays) {
    Ray moved = r;
    moved.origin = vec3(dvec3(r.origin) + shift);  // the model holds file - origin = bunny + shift
    const RTCRayHit a = intersect1(scenes[0], r), b = intersect1(scenes[1], moved);
    agree += is_hit(a) == is_hit(b);
    if (is_hit(a) && is_hit(b)) {
      ++hits;
      close += std::fabs(double(a.ray.tfar) - double(b.ray.tfar)) <= 2e-5 * diag;
    }
  }
  for (RTCScene s : scenes) rtcReleaseScene(s);
  std::remove(far_path.c_str());
  EXPECT_GT(hits, rays.size() / 4);
  EXPECT_GE(double(agree), 0.999 * double(rays.size()));
  EXPECT_GE(double(close), 0.99 * double(hits));
}

// ---------------------------------------------------------------------------------------------
// 8. The bounds: S far outside the mesh's box.
// ---------------------------------------------------------------------------------------------

// k stacked copies of one triangle in the plane z = 0 (normal +z): w = k·Ω/4π reaches 1/2 at
// Ω = 4π/2k, a bulge on the z < 0 side reaching about 2.3 triangle radii from the plane for
// k = 12, while the mesh's box is flat.
Mesh stacked_soup(int k) {
  Mesh m;
  m.positions = {{-1.0f, -0.8f, 0.0f}, {1.1f, -0.7f, 0.0f}, {0.1f, 1.2f, 0.0f}};
  for (int i = 0; i < k; ++i) m.triangles.push_back({0u, 1u, 2u});
  return m;
}

// Whether the ray meets `box` at all (its whole line from tnear).
bool ray_meets_box(const Ray& r, const Aabb& box) {
  double s0, s1;
  reference::clip_ray_to_box(r, box, s0, s1);
  return s0 <= s1;
}

// Rays parallel to the triangle's plane, at heights -3..3 (the bulge is at z < 0), in random
// horizontal directions through points over the triangle, from far away: they never meet the
// mesh's box (checked), only the bulge and the w < 0 side's levels.
std::vector<Ray> soup_rays(size_t count, uint32_t seed) {
  Random rng(seed);
  std::vector<Ray> rays;
  while (rays.size() < count) {
    const float z = rng.uniform(-3.0f, 3.0f);
    if (std::fabs(z) < 0.05f) continue;
    const float a = rng.uniform(0.0f, float(2 * kPi));
    const vec3 d(std::cos(a), std::sin(a), 0.0f);
    const vec3 through = rng.in_box(Aabb{vec3(-0.6f, -0.6f, z), vec3(0.6f, 0.8f, z)});
    rays.push_back(Ray{through - 10.0f * d, d * rng.uniform(0.5f, 2.0f)});
  }
  return rays;
}

TEST(EmbreePlugin, BoundsHoldSurfaceFarOutsideTheBox) {
  const Mesh soup = stacked_soup(12);
  const GwnModel model = build_model(soup);
  const ModelView view = model.view();
  const Aabb box = model.bounds();
  const double diag = diagonal(box);
  Device device;
  Scene scene(device);
  const unsigned id = scene.attach(gwn_geometry(device.get(), soup));
  scene.commit();
  ASSERT_EQ(device.error(), RTC_ERROR_NONE);
  const Aabb padded = grown(box, float(1e-3 * diag));
  const std::vector<Ray> rays = soup_rays(1000, 31);
  size_t hits = 0, far_hits = 0;
  Worst dt;
  for (const Ray& r : rays) {
    ASSERT_FALSE(ray_meets_box(r, padded)) << describe(r);
    const RayHit direct = trace_surface(view, r, TraceOptions{});
    const RTCRayHit h = intersect1(scene.get(), r);
    SCOPED_TRACE(describe(r) + "\n" + describe(h) + "\ndirect t " + std::to_string(direct.t));
    ASSERT_FALSE(direct.capped);
    ASSERT_EQ(is_hit(h), direct.hit);
    if (!direct.hit) continue;
    ++hits;
    EXPECT_EQ(direct.kind, HitKind::kSmooth);
    EXPECT_EQ(h.hit.primID, GWNRT_SMOOTH_PRIM_ID);
    EXPECT_EQ(h.hit.geomID, id);
    dt.see(std::fabs(h.ray.tfar - direct.t) / direct.t);
    EXPECT_LE(std::fabs(h.ray.tfar - direct.t), 1e-6f * direct.t);  // the same computation (see the open mesh)
    EXPECT_TRUE(is_occluded(occluded1(scene.get(), r)));
    const dvec3 p = hit_point(r, direct.t);
    const dvec3 q = glm::clamp(p, dvec3(box.lo), dvec3(box.hi));
    if (glm::length(p - q) > 0.3 * diag) ++far_hits;
  }
  EXPECT_GT(hits, rays.size() / 4);
  EXPECT_GT(far_hits, hits / 4) << "hits far (more than 0.3 diagonals) outside the mesh's box";
  std::printf(
      "[bounds] %zu rays missing the mesh's box: %zu hits, %zu more than 0.3 diagonals out; worst |dt|/t %.3g\n",
      rays.size(), hits, far_hits, dt.value);
}

// The soup's hits, independently of the tracer: the exact w crosses 1/2 there, upward along the
// ray (off the plane, S is the bulge's boundary, entered from outside). The plugin reports
// exactly trace_surface's hits (above), so a failure here is the core tracer's.
TEST(EmbreePlugin, SoupHitsLieOnTheSurface) {
  const Mesh soup = stacked_soup(12);
  const reference::ReferenceMesh exact = reference::reference_mesh(soup);
  const double diag = diagonal(test::mesh_bounds(soup));
  Device device;
  Scene scene(device);
  scene.attach(gwn_geometry(device.get(), soup));
  scene.commit();
  size_t hits = 0, off_surface = 0;
  for (const Ray& r : soup_rays(1000, 31)) {
    const RTCRayHit h = intersect1(scene.get(), r);
    if (!is_hit(h)) continue;
    ++hits;
    // ±1e-3 of the diagonal along the ray: 100 stopping distances; the bulge is ~2 diagonals wide.
    const auto w = w_around(exact, r, h.ray.tfar, 1e-3 * diag);
    if (!crosses_half(w, true)) {
      ++off_surface;
      ADD_FAILURE() << describe(r) << "\n"
                    << describe(h) << "\nexact w " << w.first << " -> " << w.second
                    << " around the hit: not a crossing of 1/2";
    }
  }
  EXPECT_GT(hits, 50u);
  std::printf("[soup, exact w] %zu hits, %zu not on S\n", hits, off_surface);
}

}  // namespace
}  // namespace gwnrt
