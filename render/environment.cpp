// Distant lights: the environment (constant, or a lat-long image sampled by luminance) and the sun.
//
// The image distribution. With θ = π v and φ = 2π u - π, a solid angle element is
//   dω = sin θ dθ dφ = 2π² sin θ du dv,
// so a density p(u, v) on the unit square is the solid-angle density p(u, v) / (2π² sin θ). The
// pixel (row i, column j) is chosen with probability ∝ L(i, j) · sin θ_i (L the luminance, θ_i the
// row centre's polar angle): the sin θ term makes pixels near the poles, which cover little solid
// angle, correspondingly unlikely. Inside the pixel (u, v) is uniform, so p(u, v) = P(i, j) · W · H,
// and P(i, j) is read back from the very CDF entries the sampler inverts (their differences), so
// that pdf() is the density sample() draws from, not a recomputation of it.
//
// No bilinear filtering: radiance() returns the pixel containing (u, v). With a filtered lookup the
// radiance would no longer be constant where the pdf is, and radiance / pdf would vary inside a
// pixel; nearest-pixel lookup keeps the two piecewise constant on the same cells.

#include "render/environment.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <utility>

#include <OpenImageIO/imageio.h>

#include "gwnrt/base/memory.h"
#include "render/image_output.h"

namespace gwnrt::render {

namespace {

constexpr double kTwoPiSquared = 2.0 * kPi * kPi;
// Below this sin θ (within ~1e-6 rad of a pole) the image pdf is 0: p / (2π² sin θ) would grow
// without bound (to infinity at the pole itself). The cap holds a fraction ≈ 3e-7 · H of the
// first (last) row's probability; a sample that lands there is dropped by the caller.
constexpr double kMinSinTheta = 1e-6;

// Rec. 709 luminance, in double: no overflow for the largest floats, no underflow for the smallest.
double luminance(const Spectrum& c) { return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z; }

// Non-finite or negative channels become 0: the distribution needs weights ≥ 0, and every pixel
// with some positive channel then has positive luminance, hence positive probability.
Spectrum sanitize(const Spectrum& c) {
  auto f = [](float x) { return is_finite(x) && x > 0.0f ? x : 0.0f; };
  return {f(c.x), f(c.y), f(c.z)};
}

// The mapping of the header, in double. ok is false for a zero or non-finite direction.
struct LatLong {
  double u = 0.0, v = 0.0, sin_theta = 0.0;
  bool ok = false;
};

LatLong to_latlong(const vec3& d) {
  LatLong r;
  if (!is_finite(d.x) || !is_finite(d.y) || !is_finite(d.z)) return r;
  const double x = d.x, y = d.y, z = d.z;
  const double rho = std::sqrt(x * x + z * z);  // distance from the y axis
  const double len = std::sqrt(rho * rho + y * y);
  if (!(len > 0.0)) return r;
  // θ from atan2 rather than acos(y / len): accurate near the poles, where acos loses digits.
  r.v = std::atan2(rho, y) / kPi;
  r.u = std::atan2(x, -z) / (2.0 * kPi) + 0.5;
  r.sin_theta = rho / len;
  r.ok = true;
  return r;
}

dvec3 from_latlong(double u, double v) {
  const double theta = kPi * v, phi = 2.0 * kPi * u - kPi;
  const double s = std::sin(theta);
  return {s * std::sin(phi), std::cos(theta), -s * std::cos(phi)};
}

// Index of the interval [cdf[k], cdf[k + 1]) that holds x, for cdf[0] = 0 ≤ … ≤ cdf[n] = 1 and
// x in [0, 1): the last k with cdf[k] ≤ x, which skips zero-width intervals.
int find_interval(const float* cdf, int n, float x) {
  const float* it = std::upper_bound(cdf, cdf + n + 1, x);
  return std::clamp(int(it - cdf) - 1, 0, n - 1);
}

// The position in [0, 1) of x inside [lo, hi).
double fraction_in(float lo, float hi, float x) {
  const double t = hi > lo ? (double(x) - double(lo)) / (double(hi) - double(lo)) : 0.5;
  return std::clamp(t, 0.0, std::nextafter(1.0, 0.0));
}

// Normalised running sums of `w` (n ≥ 1 entries) into cdf[0 … n]: 0, …, 1 exactly; a uniform CDF
// when the sum is 0. Monotone, because rounding to float is.
void fill_cdf(const double* w, int n, float* cdf) {
  double total = 0.0;
  for (int k = 0; k < n; ++k) total += w[k];
  cdf[0] = 0.0f;
  double running = 0.0;
  for (int k = 0; k < n; ++k) {
    running += w[k];
    cdf[k + 1] = total > 0.0 ? float(running / total) : float(double(k + 1) / n);
  }
  cdf[n] = 1.0f;
}

}  // namespace

glm::vec2 latlong_uv(const vec3& direction) {
  const LatLong ll = to_latlong(direction);
  return {float(ll.u), float(ll.v)};
}

vec3 latlong_direction(float u, float v) { return vec3(from_latlong(u, v)); }

Environment Environment::constant(const Spectrum& radiance) {
  Environment env;
  env.pixels_ = {sanitize(radiance)};
  env.constant_ = true;
  return env;
}

Environment Environment::from_pixels(int width, int height, std::vector<Spectrum> pixels, float scale) {
  if (width <= 0 || height <= 0 || pixels.size() != std::size_t(width) * std::size_t(height)) {
    throw std::invalid_argument("Environment::from_pixels: " + std::to_string(pixels.size()) + " pixels for a " +
                                std::to_string(width) + " x " + std::to_string(height) + " image");
  }
  for (Spectrum& p : pixels) p = sanitize(p * scale);
  // An image with one value everywhere (all black included) is a constant environment: uniform
  // sampling is exact for it, while the image distribution would only approximate uniform.
  const bool uniform = std::all_of(pixels.begin(), pixels.end(), [&](const Spectrum& p) { return p == pixels[0]; });
  if (uniform) return constant(pixels[0]);

  Environment env;
  env.width_ = width;
  env.height_ = height;
  env.pixels_ = std::move(pixels);
  env.constant_ = false;
  env.build_distribution();
  return env;
}

void Environment::build_distribution() {
  const int w = width_, h = height_;
  row_cdf_.assign(std::size_t(h) + 1, 0.0f);
  column_cdf_.assign(std::size_t(h) * std::size_t(w + 1), 0.0f);
  std::vector<double> row_weight(h), weight(w);
  double total = 0.0;
  for (int i = 0; i < h; ++i) {
    // sin θ at the row centre: positive for every row, also the first and the last.
    const double sin_theta = std::sin(kPi * (i + 0.5) / h);
    double sum = 0.0;
    for (int j = 0; j < w; ++j) {
      weight[j] = luminance(pixels_[std::size_t(i) * w + j]) * sin_theta;
      sum += weight[j];
    }
    fill_cdf(weight.data(), w, column_cdf_.data() + std::size_t(i) * (w + 1));
    row_weight[i] = sum;
    total += sum;
  }
  fill_cdf(row_weight.data(), h, row_cdf_.data());
  // total > 0: the image is not uniform (from_pixels made those constant), so some pixel has a
  // positive channel, hence (in double, no underflow) positive luminance and weight.
  total_ = float(total);
}

Status Environment::load(const std::string& path, float scale, Environment& out) {
  std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(path);
  if (!in) return oiio_error(path, "cannot open the environment image", OIIO::geterror());
  const OIIO::ImageSpec spec = in->spec();
  const int w = spec.width, h = spec.height, channels = spec.nchannels;
  if (spec.deep) return {StatusCode::kInvalidArgument, path + ": deep images are not supported as environments"};
  if (w <= 0 || h <= 0 || channels <= 0) {
    return {StatusCode::kInvalidArgument, path + ": empty image (" + std::to_string(w) + " x " + std::to_string(h) +
                                              ", " + std::to_string(channels) + " channels)"};
  }
  // Checked before allocating: a header may claim any size. Held at once: the
  // file's channels, the RGB pixels and the column CDFs, in floats.
  const uint64_t pixel_count = saturating_product(uint64_t(w), uint64_t(h));
  if (Status s = check_memory(saturating_product(pixel_count, 4 * (uint64_t(channels) + 3 + 1)),
                              path + ": the environment image (" + std::to_string(w) + " x " + std::to_string(h) +
                                  ", " + std::to_string(channels) + " channels)");
      !s.ok())
    return s;
  std::vector<float> data(std::size_t(w) * std::size_t(h) * std::size_t(channels));
  if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, data.data())) {
    return oiio_error(path, "cannot read the environment image", in->geterror());
  }
  in->close();

  // RGB from the first three channels (alpha and anything after it dropped); one or two channels
  // (grey, grey + alpha) give grey replicated to RGB.
  std::vector<Spectrum> pixels(std::size_t(w) * std::size_t(h));
  for (std::size_t k = 0; k < pixels.size(); ++k) {
    const float* p = data.data() + k * std::size_t(channels);
    pixels[k] = channels >= 3 ? Spectrum(p[0], p[1], p[2]) : Spectrum(p[0]);
  }
  // Non-finite pixels are dropped (from_pixels); finite ones times the scale must stay a radiance
  // the path tracer can sum (kMaxRadiance), where float would overflow them to inf and drop them.
  double brightest = 0.0;
  for (const Spectrum& p : pixels)
    for (int c = 0; c < 3; ++c)
      if (std::isfinite(p[c])) brightest = std::max(brightest, double(p[c]));
  if (brightest * double(scale) > double(kMaxRadiance)) {
    char text[96];
    std::snprintf(text, sizeof text, "its brightest pixel (%g) times the scale (%g) is above %g", brightest,
                  double(scale), double(kMaxRadiance));
    return {StatusCode::kInvalidArgument,
            path + ": " + text + ", the largest radiance whose paths' sums stay finite in float"};
  }
  out = from_pixels(w, h, std::move(pixels), scale);
  return Status::Ok();
}

bool Environment::is_constant() const { return constant_; }

int Environment::pixel_index(double u, double v) const {
  int column = int(std::floor(u * width_));
  if (column >= width_) column -= width_;  // u = 1 is the meridian of u = 0
  column = std::clamp(column, 0, width_ - 1);
  const int row = std::clamp(int(std::floor(v * height_)), 0, height_ - 1);
  return row * width_ + column;
}

Spectrum Environment::radiance(const vec3& direction) const {
  if (constant_) return pixels_.empty() ? Spectrum(0.0f) : pixels_[0];  // empty: a default-made one
  const LatLong ll = to_latlong(direction);
  if (!ll.ok) return Spectrum(0.0f);
  return pixels_[std::size_t(pixel_index(ll.u, ll.v))];  // nearest pixel, no bilinear filtering
}

float Environment::pdf(const vec3& direction) const {
  if (constant_) return kInv4Pi;
  const LatLong ll = to_latlong(direction);
  if (!ll.ok || ll.sin_theta < kMinSinTheta) return 0.0f;
  const int index = pixel_index(ll.u, ll.v);
  const int row = index / width_, column = index % width_;
  const float* cdf = column_cdf_.data() + std::size_t(row) * (width_ + 1);
  // The probabilities the sampler realises: differences of the CDF entries it searches.
  const double p_row = double(row_cdf_[row + 1]) - double(row_cdf_[row]);
  const double p_column = double(cdf[column + 1]) - double(cdf[column]);
  const double p_uv = p_row * p_column * double(width_) * double(height_);
  return float(p_uv / (kTwoPiSquared * ll.sin_theta));
}

vec3 Environment::sample(float u0, float u1, float& pdf) const {
  if (constant_) {
    // Uniform on the sphere: y uniform in [-1, 1], azimuth uniform.
    const double y = 1.0 - 2.0 * double(u1);
    const double r = std::sqrt(std::max(0.0, 1.0 - y * y));
    const double phi = 2.0 * kPi * double(u0);
    pdf = kInv4Pi;
    return vec3(dvec3(r * std::cos(phi), y, r * std::sin(phi)));
  }
  // u1 picks the row from the marginal, u0 the column from that row's conditional; each leaves a
  // uniform position inside the chosen interval.
  const int row = find_interval(row_cdf_.data(), height_, u1);
  const double v = (row + fraction_in(row_cdf_[row], row_cdf_[row + 1], u1)) / height_;
  const float* cdf = column_cdf_.data() + std::size_t(row) * (width_ + 1);
  const int column = find_interval(cdf, width_, u0);
  const double u = (column + fraction_in(cdf[column], cdf[column + 1], u0)) / width_;
  const vec3 direction(from_latlong(u, v));
  // The density of the direction as pdf() computes it (the same pixel save where rounding moves
  // the direction across a pixel edge), so that the two agree exactly.
  pdf = this->pdf(direction);
  return direction;
}

// ---------------------------------------------------------------------------------------------
// Sun

namespace {

struct Cone {
  dvec3 axis{0.0, 1.0, 0.0};
  double one_minus_cos = 0.0;  // 1 - cos r = 2 sin²(r/2)
  float pdf = 0.0f;            // 1 / (2π (1 - cos r))
  bool ok = false;
};

Cone cone_of(const Sun& sun) {
  Cone c;
  const dvec3 d(sun.direction);
  const double len = glm::length(d);
  const double r = sun.angular_radius;
  if (!(len > 0.0) || !std::isfinite(len) || !(r > 0.0) || !std::isfinite(r)) return c;
  const double s = std::sin(0.5 * std::min(r, kPi));
  c.axis = d / len;
  c.one_minus_cos = 2.0 * s * s;
  c.pdf = float(1.0 / (2.0 * kPi * c.one_minus_cos));
  c.ok = true;
  return c;
}

// Angle to the axis ≤ r, as |d̂ - â|² = 2 (1 - cos angle) ≤ 2 (1 - cos r): no cancellation.
bool inside(const Cone& c, const vec3& direction) {
  if (!c.ok || !is_finite(direction.x) || !is_finite(direction.y) || !is_finite(direction.z)) return false;
  const dvec3 d(direction);
  const double len = glm::length(d);
  if (!(len > 0.0)) return false;
  const dvec3 e = d / len - c.axis;
  return glm::dot(e, e) <= 2.0 * c.one_minus_cos;
}

}  // namespace

vec3 Sun::sample(float u0, float u1, float& pdf) const {
  const Cone c = cone_of(*this);
  if (!c.ok) {
    pdf = 0.0f;
    return vec3(c.axis);
  }
  // Orthonormal tangents around the axis.
  const dvec3 helper = std::abs(c.axis.x) < 0.9 ? dvec3(1.0, 0.0, 0.0) : dvec3(0.0, 1.0, 0.0);
  const dvec3 t = glm::normalize(glm::cross(helper, c.axis));
  const dvec3 b = glm::cross(c.axis, t);
  // 1 - cos γ uniform in [0, 1 - cos r] is cos γ uniform in [cos r, 1]: uniform in solid angle.
  double h = double(u0) * c.one_minus_cos;
  const double phi = 2.0 * kPi * double(u1);
  vec3 direction;
  for (int attempt = 0; attempt < 4; ++attempt) {
    const double sin_gamma = std::sqrt(std::max(0.0, h * (2.0 - h)));
    direction = vec3(c.axis * (1.0 - h) + sin_gamma * (std::cos(phi) * t + std::sin(phi) * b));
    if (inside(c, direction)) break;
    // Rounding the direction to float put it just outside the rim (a fraction ~1e-5 of samples at
    // the real sun's radius): move it inward by a negligible amount rather than return a sample
    // that pdf() and radiance_toward() would not see.
    h *= 1.0 - 1e-3;
    if (attempt == 3) direction = vec3(c.axis);
  }
  pdf = c.pdf;
  return direction;
}

float Sun::pdf(const vec3& direction) const {
  const Cone c = cone_of(*this);
  return inside(c, direction) ? c.pdf : 0.0f;
}

Spectrum Sun::radiance_toward(const vec3& direction) const {
  return inside(cone_of(*this), direction) ? radiance : Spectrum(0.0f);
}

}  // namespace gwnrt::render
