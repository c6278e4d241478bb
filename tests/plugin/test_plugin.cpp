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
// The other files here: instances (test_instances.cpp), filters and masks (test_filters.cpp),
// bad input, errors and reference counting (test_c_api.cpp); plugin_fixtures.h what they share.
#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "gwnrt/embree.h"
#include "gwnrt/trace/surface_trace.h"
#include "plugin_fixtures.h"
#include "reference/first_crossing.h"
#include "render/embree_triangles.h"
#include "test_util.h"

namespace gwnrt {
namespace {

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

TEST(EmbreePlugin, OpenMeshMatchesTraceSurface) {
  const Mesh mesh = load_test_mesh("bunny_holes.obj");
  const GwnModel model = build_model(mesh);
  ASSERT_GT(model.boundary().segment_count(), 0u) << "the mesh must have holes";
  // With the level-free cells the plugin's meshes have (for w* = 1/2): the same computation.
  ASSERT_TRUE(model.prepare(kPartLevelFreeCells).ok());
  const ModelView view = model.view();
  const TraceOptions options{};
  Device device;
  Scene scene(device);
  const unsigned id = scene.attach(gwn_geometry(device.get(), mesh));
  scene.commit();
  ASSERT_EQ(device.error(), RTC_ERROR_NONE);

  const std::vector<Ray> rays = bunny_holes_rays(model, test::lattice_side(40));
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
  ASSERT_TRUE(model.prepare(kPartLevelFreeCells).ok());  // as the plugin's mesh has them
  const std::vector<Ray> rays = hole_rays(model, test::lattice_side(20));
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
  ASSERT_TRUE(model.prepare(kPartLevelFreeCells).ok());  // as the plugin's mesh has them
  const ModelView view = model.view();
  const Aabb box = model.bounds();
  const double diag = diagonal(box);
  Device device;
  Scene scene(device);
  const unsigned id = scene.attach(gwn_geometry(device.get(), soup));
  scene.commit();
  ASSERT_EQ(device.error(), RTC_ERROR_NONE);
  const Aabb padded = grown(box, float(1e-3 * diag));
  const std::vector<Ray> rays = soup_rays(test::kThreadSanitizer ? 250 : 1000, 31);
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
