// The plugin's intersection and occlusion filters, of the geometry and of the context, also inside
// instances, against the complete list of triangle crossings that Embree's triangles report; and
// geometry masks against ray masks.
#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "gwnrt/embree.h"
#include "plugin_fixtures.h"
#include "render/embree_triangles.h"
#include "test_util.h"

namespace gwnrt {
namespace {

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

}  // namespace
}  // namespace gwnrt
