// A triangle mesh as Embree's own triangle geometry, and a scene of that mesh alone: what the
// renderer's triangle meshes, the tracing benchmark's baseline and the tests that compare with
// Embree's triangle intersection all build. Host-only.
#pragma once

#include <embree3/rtcore.h>

#include <chrono>
#include <cstddef>
#include <string>

#include "gwnrt/base/status.h"
#include "gwnrt/geometry/mesh.h"
#include "render/embree_ray.h"

namespace gwnrt::render {

// `mesh` as a committed Embree triangle geometry, or nullptr when Embree cannot make it (the
// device's error says why). The buffers are copies: Embree wants its vertex buffer padded,
// which a std::vector<vec3> is not. Every index must be below the vertex count.
inline RTCGeometry new_triangle_geometry(RTCDevice device, const Mesh& mesh) {
  RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  if (!geometry) return nullptr;
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                               3 * sizeof(float), mesh.positions.size()));
  auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                 3 * sizeof(unsigned), mesh.triangles.size()));
  if (!vertices || !indices) {
    rtcReleaseGeometry(geometry);
    return nullptr;
  }
  for (std::size_t i = 0; i < mesh.positions.size(); ++i)
    for (int k = 0; k < 3; ++k) vertices[3 * i + k] = mesh.positions[i][k];
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
    for (int k = 0; k < 3; ++k) indices[3 * i + k] = mesh.triangles[i][k];
  rtcCommitGeometry(geometry);
  return geometry;
}

// One triangle mesh alone in an Embree scene, on a device of its own. The scene flags and build
// quality are Embree's defaults unless given (the tests ask for robust, watertight traversal).
class TriangleScene {
 public:
  // `threads`: Embree's worker threads (0: its default, all cores).
  explicit TriangleScene(const Mesh& mesh, int threads = 0, RTCSceneFlags flags = RTC_SCENE_FLAG_NONE,
                         RTCBuildQuality quality = RTC_BUILD_QUALITY_MEDIUM) {
    const std::string config = threads > 0 ? "threads=" + std::to_string(threads) : std::string();
    device_ = rtcNewDevice(config.empty() ? nullptr : config.c_str());
    if (!device_) {
      status_ = {StatusCode::kUnavailable,
                 "rtcNewDevice failed (error " + std::to_string(int(rtcGetDeviceError(nullptr))) + ")"};
      return;
    }
    scene_ = rtcNewScene(device_);
    rtcSetSceneFlags(scene_, flags);
    rtcSetSceneBuildQuality(scene_, quality);
    RTCGeometry geometry = new_triangle_geometry(device_, mesh);
    if (!geometry) {
      status_ = {StatusCode::kOutOfMemory, "Embree could not allocate the geometry buffers"};
      return;
    }
    rtcAttachGeometry(scene_, geometry);
    rtcReleaseGeometry(geometry);
    const auto t0 = std::chrono::steady_clock::now();
    rtcCommitScene(scene_);
    build_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (const RTCError e = rtcGetDeviceError(device_); e != RTC_ERROR_NONE)
      status_ = {StatusCode::kInternal, "Embree error " + std::to_string(int(e)) + " while building the scene"};
  }
  ~TriangleScene() {
    if (scene_) rtcReleaseScene(scene_);
    if (device_) rtcReleaseDevice(device_);
  }
  TriangleScene(const TriangleScene&) = delete;
  TriangleScene& operator=(const TriangleScene&) = delete;

  // Whether the scene was built, and if not why (nothing may be traced then).
  Status status() const { return status_; }
  double build_seconds() const { return build_seconds_; }  // rtcCommitScene's

  // The nearest hit on `r` (geomID RTC_INVALID_GEOMETRY_ID: none); tfar is its t.
  RTCRayHit intersect(const Ray& r, RTCIntersectContext& context) const {
    RTCRayHit rh = embree_ray_hit(r);
    rtcIntersect1(scene_, &context, &rh);
    return rh;
  }

 private:
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  Status status_;
  double build_seconds_ = 0;
};

}  // namespace gwnrt::render
