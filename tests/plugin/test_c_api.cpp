// The plugin's C API: the meshes and geometry arguments it refuses with a reason, the last error
// per thread, invalid rays, the mesh's reference counting, the sequence of gwnrt/embree.h's top
// comment, and gwnrtLoadMesh on a far-off scan.
#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "cli_util.h"
#include "gwnrt/embree.h"
#include "plugin_fixtures.h"
#include "test_util.h"

namespace gwnrt {
namespace {

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
      // Below 1 a cluster is expanded inside its own ball: wrong hits, once accepted.
      {"beta 0.1", [](GWNRTOptions& o) { o.beta = 0.1f; }, "beta must be a finite number >= 1"},
      {"beta 0.999", [](GWNRTOptions& o) { o.beta = 0.999f; }, "beta"},
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

// An STL soup loads as the mesh it describes: its repeated corners one vertex each.
TEST(EmbreePlugin, LoadsStl) {
  GWNRTMesh mesh = gwnrtLoadMesh(test::data_path("realworld/motoman_motomini_visual_link_1_s.stl").c_str());
  ASSERT_NE(mesh, nullptr) << gwnrtGetLastError();
  EXPECT_EQ(gwnrtGetMeshTriangleCount(mesh), 2462u);
  EXPECT_EQ(gwnrtGetMeshVertexCount(mesh), 1182u);
  gwnrtReleaseMesh(mesh);
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
  const std::vector<Ray> rays = bunny_holes_rays(model, test::lattice_side(24));
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

}  // namespace
}  // namespace gwnrt
