// The plugin's geometry inside instances (two of one object, rotated, scaled and moved) against
// trace_surface on the transformed mesh in world space.
#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "gwnrt/embree.h"
#include "gwnrt/trace/surface_trace.h"
#include "plugin_fixtures.h"
#include "test_util.h"

namespace gwnrt {
namespace {

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
  std::vector<Ray> rays = camera_rays(scaled(world, 0.7f), test::lattice_side(36), {{10, -40}, {190, -20}, {95, 60}});
  const std::vector<Ray> holes = hole_rays(build_model(mesh), test::lattice_side(28));
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

}  // namespace
}  // namespace gwnrt
