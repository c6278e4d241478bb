// The README's "A GWN object in an Embree scene" example as a whole program: the bunny with holes
// as a GWN object in an Embree scene, one ray through a hole (smooth cap) and one onto the mesh.
// CI builds it in the tree and against the installed package (tests/downstream).
#include <cstdio>

#include <embree3/rtcore.h>

#include "gwnrt/embree.h"

namespace {

RTCRayHit make_ray(float ox, float oy, float oz, float dx, float dy, float dz) {
  RTCRayHit rayhit{};
  rayhit.ray.org_x = ox, rayhit.ray.org_y = oy, rayhit.ray.org_z = oz;
  rayhit.ray.dir_x = dx, rayhit.ray.dir_y = dy, rayhit.ray.dir_z = dz;
  rayhit.ray.tnear = 0.0f;
  rayhit.ray.tfar = 1e30f;
  rayhit.ray.mask = 0xFFFFFFFFu;
  rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rayhit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  return rayhit;
}

}  // namespace

int main(int argc, char** argv) {
  const char* path = argc > 1 ? argv[1] : "bunny_holes.obj";
  // Released on every way out, the early error returns included (LeakSanitizer found them kept).
  struct EmbreeScene {
    RTCDevice device = rtcNewDevice(nullptr);
    RTCScene scene = rtcNewScene(device);
    ~EmbreeScene() {
      rtcReleaseScene(scene);
      rtcReleaseDevice(device);
    }
  } embree;
  RTCDevice device = embree.device;
  RTCScene scene = embree.scene;
  // [readme-embree-begin]
  GWNRTMesh mesh = gwnrtLoadMesh(path);  // OBJ, PLY or STL; builds the tree once
  if (!mesh) {
    std::fprintf(stderr, "%s\n", gwnrtGetLastError());
    return 1;
  }

  GWNRTOptions options;
  gwnrtInitOptions(&options);  // S = ∂{w > 1/2}
  options.level = 0.5f;        // or GWNRT_MODE_SOLID_ANGLE, epsilon, ...

  RTCGeometry geom = gwnrtNewGeometry(device, mesh, &options);
  if (!geom) {
    std::fprintf(stderr, "%s\n", gwnrtGetLastError());
    return 1;
  }
  const unsigned geomID = rtcAttachGeometry(scene, geom);
  rtcReleaseGeometry(geom);
  gwnrtReleaseMesh(mesh);  // the geometry keeps the mesh alive
  rtcCommitScene(scene);

  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rayhit = make_ray(-1.0f, 0.5f, 10.0f, 0.0f, 0.0f, -1.0f);
  rtcIntersect1(scene, &context, &rayhit);  // plain Embree from here on
  if (rayhit.hit.geomID == geomID) {
    // Ng: unit, outward (in the GWN object's own space inside an instance).
    // primID: the mesh triangle for a hit on the mesh (u, v its barycentrics), or
    // GWNRT_SMOOTH_PRIM_ID for a hit on a smooth cap over a hole.
  }
  // [readme-embree-end]
  std::printf("ray %s at t = %.6f (%s)\n", rayhit.hit.geomID == geomID ? "hit S" : "missed S", rayhit.ray.tfar,
              rayhit.hit.primID == GWNRT_SMOOTH_PRIM_ID ? "a smooth cap" : "on the mesh");
  return rayhit.hit.geomID == geomID ? 0 : 2;
}
