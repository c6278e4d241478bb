// A pinhole camera that frames a bounding box, shared by gwnrt-render and the tracing benchmark
// so that both shoot exactly the same rays.
#pragma once

#include <cmath>

#include "gwnrt/geometry/bvh.h"
#include "gwnrt/trace/ray.h"

namespace gwnrt::examples {

struct PinholeCamera {
  vec3 eye{0.0f}, forward{0.0f, 0.0f, -1.0f}, right{1.0f, 0.0f, 0.0f}, up{0.0f, 1.0f, 0.0f};
  float tan_half_fov = 0.5f;
  int width = 1, height = 1;

  // The ray through the centre of pixel (x, y) (row 0 at the top), unit direction.
  Ray ray(int x, int y) const {
    const float aspect = float(width) / float(height);
    const float sx = (2.0f * (float(x) + 0.5f) / float(width) - 1.0f) * tan_half_fov * aspect;
    const float sy = (1.0f - 2.0f * (float(y) + 0.5f) / float(height)) * tan_half_fov;
    Ray r;
    r.origin = eye;
    r.direction = glm::normalize(forward + sx * right + sy * up);
    return r;
  }
};

// Looks at the centre of `box` from the direction given by azimuth (about +y, degrees; 0 looks
// along -z) and elevation (degrees above the horizon), far enough that the box's bounding
// sphere fills the vertical field of view `fov_degrees` with a small margin.
inline PinholeCamera frame_box(const Aabb& box, int width, int height, float azimuth = 30.0f, float elevation = 20.0f,
                               float fov_degrees = 40.0f) {
  PinholeCamera cam;
  cam.width = width;
  cam.height = height;
  cam.tan_half_fov = std::tan(0.5f * fov_degrees * kDegree);
  const vec3 centre = box.centre();
  const float radius = 0.5f * glm::length(box.hi - box.lo);
  const float az = azimuth * kDegree, el = elevation * kDegree;
  const vec3 back(std::sin(az) * std::cos(el), std::sin(el), std::cos(az) * std::cos(el));  // centre -> eye
  const float distance = 1.1f * radius / std::sin(0.5f * fov_degrees * kDegree);
  cam.eye = centre + distance * back;
  cam.forward = -back;
  const vec3 world_up(0.0f, 1.0f, 0.0f);
  cam.right = glm::normalize(glm::cross(cam.forward, std::fabs(cam.forward.y) > 0.999f ? vec3(0, 0, 1) : world_up));
  cam.up = glm::cross(cam.right, cam.forward);
  return cam;
}

}  // namespace gwnrt::examples
