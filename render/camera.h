// The one pinhole camera of the programs: gwnrt-render's path tracer and first-hit integrator,
// the tracing benchmark and the tests all shoot their rays through it, so that a camera placed
// the same way shoots exactly the same rays.
#pragma once

#include <cmath>

#include "gwnrt/base/hd.h"
#include "gwnrt/geometry/bvh.h"
#include "gwnrt/geometry/ray.h"

namespace gwnrt::render {

struct PinholeCamera {
  vec3 eye{0.0f}, forward{0.0f, 0.0f, -1.0f}, right{1.0f, 0.0f, 0.0f}, up{0.0f, 1.0f, 0.0f};
  float tan_half_fov = 0.5f;
  int width = 1, height = 1;

  // The ray through the point (x + u, y + v) of the image plane (row 0 at the top), unit
  // direction; the default is the centre of pixel (x, y). Host and device (first-hit on the GPU).
  GWNRT_HD Ray ray(int x, int y, float u = 0.5f, float v = 0.5f) const {
    const float aspect = float(width) / float(height);
    const float sx = (2.0f * (float(x) + u) / float(width) - 1.0f) * tan_half_fov * aspect;
    const float sy = (1.0f - 2.0f * (float(y) + v) / float(height)) * tan_half_fov;
    Ray r;
    r.origin = eye;
    r.direction = glm::normalize(forward + sx * right + sy * up);
    return r;
  }
};

// The camera at `eye` looking along the unit `forward`, `up` upward on the image (not parallel to
// `forward`), with the vertical field of view `fov_degrees`.
inline PinholeCamera look_along(const vec3& eye, const vec3& forward, const vec3& up, float fov_degrees, int width,
                                int height) {
  PinholeCamera cam;
  cam.width = width;
  cam.height = height;
  cam.tan_half_fov = std::tan(0.5f * fov_degrees * kDegree);
  cam.eye = eye;
  cam.forward = forward;
  cam.right = glm::normalize(glm::cross(forward, up));
  cam.up = glm::cross(cam.right, forward);
  return cam;
}

// The camera at `eye` looking at `target` (a scene file's camera).
inline PinholeCamera look_at(const vec3& eye, const vec3& target, const vec3& up, float fov_degrees, int width,
                             int height) {
  return look_along(eye, glm::normalize(target - eye), up, fov_degrees, width, height);
}

// Looks at the centre of `box` from the direction given by azimuth (about +y, degrees; 0 looks
// along -z) and elevation (degrees above the horizon), far enough that the box's bounding
// sphere fills the vertical field of view `fov_degrees` with a small margin.
inline PinholeCamera frame_box(const Aabb& box, int width, int height, float azimuth = 30.0f, float elevation = 20.0f,
                               float fov_degrees = 40.0f) {
  const vec3 centre = box.centre();
  const float radius = 0.5f * glm::length(box.hi - box.lo);
  const float az = azimuth * kDegree, el = elevation * kDegree;
  const vec3 back(std::sin(az) * std::cos(el), std::sin(el), std::cos(az) * std::cos(el));  // centre -> eye
  const float distance = 1.1f * radius / std::sin(0.5f * fov_degrees * kDegree);
  // Straight up or down, +y cannot be the image's up.
  const vec3 up = std::fabs(back.y) > 0.999f ? vec3(0.0f, 0.0f, 1.0f) : vec3(0.0f, 1.0f, 0.0f);
  return look_along(centre + distance * back, -back, up, fov_degrees, width, height);
}

}  // namespace gwnrt::render
