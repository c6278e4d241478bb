// The scene as Embree sees it: triangle meshes as Embree triangle geometry (in world space), GWN
// objects through the gwnrt plugin, one Embree scene per object with an instance per transform,
// and the lights the path tracer samples (emissive triangle meshes, the environment, the sun).
// Only plain Embree calls after the plugin made the geometries: the renderer is an ordinary
// Embree application.
#pragma once

#include <embree3/rtcore.h>

#include <atomic>
#include <cstdint>
#include <vector>

#include "gwnrt/embree.h"
#include "render/environment.h"
#include "render/scene.h"

namespace gwnrt::render {

struct SurfaceHit {
  float t = 0.0f;
  vec3 position{0.0f};
  vec3 normal{0.0f};  // unit, world space, geometric and outward (triangles: by their winding;
                      // GWN objects: from {w > level} toward {w < level}), not turned to the ray
  int material = 0;
  bool gwn = false;  // on a GWN object (else a triangle mesh)
};

// Emissive triangles, sampled by area.
struct AreaLights {
  std::vector<vec3> vertices;      // 3 per triangle, world space
  std::vector<Spectrum> emission;  // per triangle
  std::vector<float> cdf;          // by area, last = 1
  float total_area = 0.0f;
  bool empty() const { return emission.empty(); }
};

class RenderScene {
 public:
  RenderScene() = default;
  ~RenderScene();
  RenderScene(const RenderScene&) = delete;
  RenderScene& operator=(const RenderScene&) = delete;

  Status build(const SceneDesc& desc);

  // The nearest hit on (origin, direction unit) within (tnear, tfar).
  bool intersect(const vec3& origin, const vec3& direction, float tnear, float tfar, SurfaceHit& hit) const;
  // Whether anything lies on the segment (tnear, tfar).
  bool occluded(const vec3& origin, const vec3& direction, float tnear, float tfar) const;
  // Rays intersect() and occluded() refused instead of handing them to Embree (a non-finite or
  // far-out origin, a non-finite or zero direction, a NaN tnear or tfar): counted as misses.
  // The scene reader keeps every ray valid, so this is a bug's trace if ever nonzero.
  uint64_t invalid_rays() const { return invalid_rays_.load(std::memory_order_relaxed); }

  const SceneDesc& desc() const { return *desc_; }
  const std::vector<Material>& materials() const { return desc_->materials; }
  const Environment& environment() const { return environment_; }
  bool environment_emits() const { return environment_emits_; }  // anything to sample in it
  const Sun& sun() const { return desc_->sun; }
  const AreaLights& area_lights() const { return lights_; }
  float scene_radius() const { return radius_; }  // for ray offsets

 private:
  // What a geomID of the top scene is: a triangle mesh, or an instance of a GWN object's scene.
  struct TopGeometry {
    bool instance = false;
    int material = 0;
    const Mesh* mesh = nullptr;     // triangle meshes: for their normals
    glm::mat3 normal_matrix{1.0f};  // instances: object to world for normals (inverse transpose)
  };

  const SceneDesc* desc_ = nullptr;
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  std::vector<RTCScene> object_scenes_;
  std::vector<GWNRTMesh> gwn_meshes_;
  std::vector<TopGeometry> top_;  // by geomID
  Environment environment_;
  bool environment_emits_ = false;
  AreaLights lights_;
  float radius_ = 1.0f;
  mutable std::atomic<uint64_t> invalid_rays_{0};

  bool valid_ray(const vec3& origin, const vec3& direction, float tnear, float tfar) const;
};

}  // namespace gwnrt::render
