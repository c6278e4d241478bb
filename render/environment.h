// Distant light of the path tracer: an environment (constant, or a lat-long image importance
// sampled by its luminance) and a sun (a directional light with a small angular radius).
#pragma once

#include <string>
#include <vector>

#include "gwnrt/base/status.h"
#include "render/bsdf.h"

namespace gwnrt::render {

// The largest radiance a light may have (an emissive material, the environment, its image times
// its scale, the sun). A pixel sums up to 2^20 samples (spp), each a light's radiance times the
// path's BSDF-over-pdf ratios; at 1e20 the sum of radiances stays below 1e26, which leaves float
// (3.4e38) a factor of 1e12 for those ratios. Far above any physical light in any unit (the sun's
// disc: 1.6e9 cd/m²); beyond it a sample would overflow to inf and be dropped, darkening the image.
inline constexpr float kMaxRadiance = 1e20f;

// Lat-long mapping: direction (x, y, z), y up; u = atan2(x, -z)/(2π) + 1/2 across, v = acos(y)/π
// down (row 0 looks straight up).
//
// Helpers: the mapping and its inverse. latlong_uv takes any nonzero direction (it need not be
// unit) and gives u, v in [0, 1] (u = 0 and u = 1 are the same meridian, the seam toward +z);
// latlong_direction(u, v) = (sin θ sin φ, cos θ, -sin θ cos φ) with θ = π v, φ = 2π u - π, unit.
glm::vec2 latlong_uv(const vec3& direction);
vec3 latlong_direction(float u, float v);

// Environment: radiance() is the image's pixel that contains (u, v) (nearest neighbour, no
// bilinear filtering), so that radiance and pdf are constant on the same pixels. Pixels are
// sanitised once: non-finite or negative channels become 0. sample() picks a pixel with
// probability ∝ luminance · sin θ(row centre) (u1 the row, u0 the column within it), then a point
// uniform in (u, v) inside it: pdf(ω) = p(u, v) / (2π² sin θ), and sample() returns exactly
// pdf(direction). pdf is 0 within ~1e-6 rad of a pole (sin θ < 1e-6): sample() may (very rarely)
// return such a direction with pdf 0, which a caller drops. A constant or all-black environment
// (or an image whose pixels are all equal) is sampled uniformly, pdf 1/(4π), and is_constant().
class Environment {
 public:
  static Environment constant(const Spectrum& radiance);
  // Row-major, `width` × `height` RGB pixels, linear; `scale` multiplies them. Throws
  // std::invalid_argument unless width, height > 0 and pixels.size() == width · height.
  static Environment from_pixels(int width, int height, std::vector<Spectrum> pixels, float scale = 1.0f);
  // Any image OpenImageIO reads (EXR, HDR, PNG, ...); a missing file or a bad image fails with
  // the path and OpenImageIO's message, an image larger than the memory available or whose
  // brightest pixel times `scale` exceeds kMaxRadiance with the path and the numbers.
  static Status load(const std::string& path, float scale, Environment& out);

  Spectrum radiance(const vec3& direction) const;  // toward which a ray escapes
  // A direction with density pdf (solid angle) proportional to luminance; u0, u1 uniform in [0, 1).
  vec3 sample(float u0, float u1, float& pdf) const;
  float pdf(const vec3& direction) const;
  bool is_constant() const;

 private:
  int width_ = 1, height_ = 1;
  std::vector<Spectrum> pixels_;
  std::vector<float> row_cdf_, column_cdf_;  // the piecewise-constant 2D distribution
  float total_ = 0.0f;
  // row_cdf_: height_ + 1 entries, 0 … 1, the marginal over rows; column_cdf_: height_ rows of
  // width_ + 1 entries, 0 … 1, each row's conditional. total_: Σ luminance · sin θ (0: uniform).
  bool constant_ = true;  // the same radiance everywhere: pixels_ holds one pixel, uniform sampling

  void build_distribution();
  int pixel_index(double u, double v) const;
};

// Sun: the cone of half-angle r = angular_radius (clamped to π) around `direction` (normalised
// here, so it need not be exactly unit). Its solid angle 2π(1 - cos r) is computed as 4π sin²(r/2)
// (no cancellation at the real sun's radius). "Inside" means the angle to the axis is ≤ r, tested
// in double; sample() returns only directions that pass that test, with pdf equal to pdf() there.
// A non-positive or non-finite radius or a zero direction makes a sun that pdf() and
// radiance_toward() never see (0 everywhere); its sample() gives the axis with pdf 0.
struct Sun {
  vec3 direction{0.0f, 1.0f, 0.0f};  // toward the sun, unit
  Spectrum radiance{0.0f};           // of its disc
  float angular_radius = 0.00465f;   // radians (the real sun's)
  bool enabled() const { return radiance.x > 0.0f || radiance.y > 0.0f || radiance.z > 0.0f; }
  // A direction inside the disc, uniform in solid angle (pdf = 1 / cone solid angle).
  vec3 sample(float u0, float u1, float& pdf) const;
  float pdf(const vec3& direction) const;                 // 1 / cone solid angle inside, else 0
  Spectrum radiance_toward(const vec3& direction) const;  // radiance inside the disc, else 0
};

}  // namespace gwnrt::render
