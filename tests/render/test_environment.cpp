// Distant lights: the environment (constant and lat-long image) and the sun.
//
// The references here do not use the code under test: integrals over the sphere are quadratures
// in the test's own spherical coordinates (pole +y, azimuth from +x toward +z, shifted by an
// arbitrary offset so that no grid line falls on a pixel edge), pixel solid angles come from the
// closed form (2π / W)(cos θ_top - cos θ_bottom), and directions of pixels and bins are written
// from the mapping documented in environment.h, not taken from latlong_direction.
//
// Statistical checks use fixed seeds (deterministic) and bounds of about five standard deviations,
// so that a correct implementation passes with a wide margin whatever the seed, while the errors
// they guard against (a missing sin θ, a mismatched pixel, a biased cone) exceed them many times.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>

#include "render/environment.h"

namespace gwnrt::render {
namespace {

constexpr double kPiD = 3.14159265358979323846;

// --- references -------------------------------------------------------------------------------

// The mapping of environment.h, written out: θ = π v from +y, φ = 2π u - π,
// direction = (sin θ sin φ, cos θ, -sin θ cos φ).
dvec3 documented_direction(double u, double v) {
  const double theta = kPiD * v, phi = 2.0 * kPiD * u - kPiD;
  return {std::sin(theta) * std::sin(phi), std::cos(theta), -std::sin(theta) * std::cos(phi)};
}

// u, v of a direction by the documented formulas (u = atan2(x, -z)/(2π) + 1/2, v = acos(y)/π).
void documented_uv(const vec3& d, double& u, double& v) {
  const dvec3 n = glm::normalize(dvec3(d));
  u = std::atan2(n.x, -n.z) / (2.0 * kPiD) + 0.5;
  v = std::acos(std::clamp(n.y, -1.0, 1.0)) / kPiD;
}

// Quadrature over the sphere in the test's own coordinates: θ from +y, azimuth ψ with
// x = sin θ cos ψ, z = sin θ sin ψ, shifted by `offset`; f(direction) returns a double or dvec3.
// The nodes are a rank-1 (Fibonacci) lattice on the (θ, ψ) rectangle: N = F(m) points (832040 or
// 2178309), point k at θ = π (k + 1/2) / N, ψ = offset + 2π frac(k F(m-1) / N), weight
// sin θ · 2π² / N.
// Unlike a product grid (whose lines can coincide with pixel edges, or cross every edge at one
// fraction of a cell, errors that cancel or add up in ways that hide mistakes), each of its N
// points has its own θ and its own ψ: a pixel edge, a line of constant θ or ψ, is resolved to
// ~1/N of its extent, and the error of integrating a pixel-wise constant function is of order
// log N / N (the lattice's discrepancy) rather than 1/√N. Relative to one pixel's integral that
// is about 1 / (the lattice points inside it): ~400 for a 64 × 32 pixel at N = 832040.
enum class Lattice { kFine, kFiner };
template <class F>
auto sphere_quadrature(F&& f, Lattice lattice = Lattice::kFine, double offset = 0.1234567) {
  const long kN = lattice == Lattice::kFine ? 832040 : 2178309;
  const long kGenerator = lattice == Lattice::kFine ? 514229 : 1346269;
  using T = decltype(f(vec3(0.0f)));
  T sum(0.0);
  for (long k = 0; k < kN; ++k) {
    const double theta = kPiD * (k + 0.5) / kN;
    const double psi = offset + 2.0 * kPiD * double((k * kGenerator) % kN) / kN;
    const double s = std::sin(theta);
    sum += f(vec3(float(s * std::cos(psi)), float(std::cos(theta)), float(s * std::sin(psi)))) * s;
  }
  return sum * (2.0 * kPiD * kPiD / kN);
}

// ∫ L dω of a lat-long image in closed form: each pixel is constant over its solid angle.
dvec3 exact_radiance_integral(int w, int h, const std::vector<Spectrum>& pixels) {
  dvec3 sum(0.0);
  for (int i = 0; i < h; ++i) {
    const double omega = (2.0 * kPiD / w) * (std::cos(kPiD * i / h) - std::cos(kPiD * (i + 1) / h));
    for (int j = 0; j < w; ++j) sum += dvec3(pixels[std::size_t(i) * w + j]) * omega;
  }
  return sum;
}

double luminance_ref(const Spectrum& c) { return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z; }

// --- images -------------------------------------------------------------------------------------

struct TestImage {
  int w, h;
  std::vector<Spectrum> pixels;
  Environment env() const { return Environment::from_pixels(w, h, pixels); }
};

// Random colours in [0, 1) plus a few pixels thousands of times brighter (one in the last row, at
// the seam, where sin θ is small).
TestImage random_image(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  TestImage t{w, h, std::vector<Spectrum>(std::size_t(w) * h)};
  for (Spectrum& p : t.pixels) p = Spectrum(U(rng), U(rng), U(rng));
  auto at = [&](int row, int col) -> Spectrum& { return t.pixels[std::size_t(row) * w + col]; };
  at(3 * h / 32, 10 * w / 64) = Spectrum(5000.0f, 4000.0f, 3000.0f);
  at(20 * h / 32, 50 * w / 64) = Spectrum(0.0f, 0.0f, 20000.0f);  // blue only
  at(h - 1, 0) = Spectrum(1e4f);
  return t;
}

// Light only in the first and last rows: the rows where the pole guard matters.
TestImage polar_image(int w, int h) {
  TestImage t{w, h, std::vector<Spectrum>(std::size_t(w) * h, Spectrum(0.0f))};
  for (int j = 0; j < w; ++j) {
    t.pixels[j] = Spectrum(3.0f + j % 3, 1.0f, 2.0f);
    t.pixels[std::size_t(h - 1) * w + j] = Spectrum(1.0f, 7.0f, 0.5f);
  }
  return t;
}

// ∫ pdf dω on the finer lattice: ~1000 points per pixel of a 64 × 32 image, so that even a pdf
// with half its mass in one pixel integrates to within ~1e-3 (any valid pdf, not only this one).
double pdf_integral(const Environment& env) {
  return sphere_quadrature([&](const vec3& d) { return double(env.pdf(d)); }, Lattice::kFiner);
}

// --- the mapping --------------------------------------------------------------------------------

TEST(EnvironmentMapping, DirectionUvRoundTrip) {
  std::mt19937 rng(7);
  std::normal_distribution<float> N;
  double worst_dir = 0.0, worst_u = 0.0, worst_v = 0.0;
  for (int k = 0; k < 20000; ++k) {
    const vec3 d = glm::normalize(vec3(N(rng), N(rng), N(rng)));
    const glm::vec2 uv = latlong_uv(d);
    double u, v;
    documented_uv(d, u, v);
    worst_u = std::max(worst_u, std::abs(double(uv.x) - u));
    worst_v = std::max(worst_v, std::abs(double(uv.y) - v));
    worst_dir = std::max(worst_dir, double(glm::length(latlong_direction(uv.x, uv.y) - d)));
  }
  EXPECT_LT(worst_u, 2e-7);
  EXPECT_LT(worst_v, 2e-7);
  EXPECT_LT(worst_dir, 3e-6);  // float u, v: ~6e-8 · 2π each

  std::uniform_real_distribution<double> U(0.0, 1.0);
  double worst_uv = 0.0, worst_doc = 0.0;
  for (int k = 0; k < 20000; ++k) {
    const double u = U(rng), v = 0.01 + 0.98 * U(rng);  // away from the poles, where u is undefined
    const vec3 d = latlong_direction(float(u), float(v));
    worst_doc = std::max(worst_doc, glm::length(dvec3(d) - documented_direction(float(u), float(v))));
    const glm::vec2 back = latlong_uv(d);
    double du = std::abs(back.x - u);
    du = std::min(du, 1.0 - du);  // u = 0 and u = 1 are the same meridian
    worst_uv = std::max({worst_uv, du, std::abs(back.y - v)});
  }
  EXPECT_LT(worst_doc, 1e-6);
  EXPECT_LT(worst_uv, 2e-6);

  // The named directions of the header.
  EXPECT_NEAR(latlong_uv(vec3(0, 1, 0)).y, 0.0f, 1e-7f);   // +y: v = 0
  EXPECT_NEAR(latlong_uv(vec3(0, -1, 0)).y, 1.0f, 1e-7f);  // -y: v = 1
  EXPECT_NEAR(latlong_uv(vec3(0, 0, -1)).x, 0.5f, 1e-7f);  // -z: u = 1/2
  EXPECT_NEAR(latlong_uv(vec3(1, 0, 0)).x, 0.75f, 1e-7f);  // +x: u = 3/4
  EXPECT_NEAR(latlong_uv(vec3(-1, 0, 0)).x, 0.25f, 1e-7f);
  EXPECT_NEAR(latlong_uv(vec3(1, 0, 0)).y, 0.5f, 1e-7f);
}

TEST(EnvironmentMapping, RowZeroLooksUpAndPixelsAreWhereDocumented) {
  // 5 × 3, every pixel distinct: (row, column, 1). Odd sizes put u = 1/2 and v = 1/2 inside pixels.
  const int w = 5, h = 3;
  std::vector<Spectrum> pixels;
  for (int i = 0; i < h; ++i)
    for (int j = 0; j < w; ++j) pixels.emplace_back(float(i), float(j), 1.0f);
  const Environment env = Environment::from_pixels(w, h, pixels);
  EXPECT_FALSE(env.is_constant());
  EXPECT_EQ(env.radiance(vec3(0, 1, 0)).x, 0.0f);  // +y: row 0 (u is moot at a pole)
  EXPECT_EQ(env.radiance(vec3(0.1f, 1, 0.1f)).x, 0.0f);
  EXPECT_EQ(env.radiance(vec3(0, -1, 0)).x, 2.0f);                      // -y: the last row
  EXPECT_EQ(env.radiance(vec3(0, 0, -1)), Spectrum(1, 2, 1));           // -z: the centre pixel
  EXPECT_EQ(env.radiance(vec3(1, 0, 0)), Spectrum(1, 3, 1));            // +x: u = 3/4
  EXPECT_EQ(env.radiance(vec3(-1, 0, 0)), Spectrum(1, 1, 1));           // -x: u = 1/4
  EXPECT_EQ(env.radiance(vec3(0.01f, 0, 1)).y, 4.0f);                   // just past +z on the +x side: u ≈ 1
  EXPECT_EQ(env.radiance(vec3(-0.01f, 0, 1)).y, 0.0f);                  // on the -x side: u ≈ 0
  EXPECT_EQ(env.radiance(vec3(0, 2, 0)), env.radiance(vec3(0, 1, 0)));  // direction need not be unit
  // Every pixel at its documented centre, and near its corners.
  for (int i = 0; i < h; ++i) {
    for (int j = 0; j < w; ++j) {
      for (double a : {0.5, 0.02, 0.98}) {
        for (double b : {0.5, 0.02, 0.98}) {
          const vec3 d(documented_direction((j + a) / w, (i + b) / h));
          ASSERT_EQ(env.radiance(d), Spectrum(float(i), float(j), 1.0f)) << "pixel " << i << ", " << j;
        }
      }
    }
  }
}

TEST(EnvironmentMapping, RadianceIntegralMatchesPixelSolidAngles) {
  // The quadrature of radiance() on the test's lattice against the closed-form pixel sum:
  // radiance() looks up the documented pixel everywhere, not just at centres. One blue pixel holds
  // ~97% of the blue channel's integral and ~1000 lattice points (N = 2.2e6), hence the bound.
  const TestImage t = random_image(64, 32, 11);
  const Environment env = t.env();
  const dvec3 exact = exact_radiance_integral(t.w, t.h, t.pixels);
  const dvec3 quad = sphere_quadrature([&](const vec3& d) { return dvec3(env.radiance(d)); }, Lattice::kFiner);
  for (int c = 0; c < 3; ++c) {
    const double rel = std::abs(quad[c] - exact[c]) / exact[c];
    std::printf("  channel %d: ∫L quadrature %.6f, closed form %.6f, relative error %.2e\n", c, quad[c], exact[c], rel);
    EXPECT_LT(rel, 2e-3);
  }
  // A mapping off by one row or one column moves the bright pixels' light to neighbours of other
  // latitude: the integral changes by far more (checked here so that the bound means something).
  std::vector<Spectrum> shifted(t.pixels.size());
  for (int i = 0; i < t.h; ++i)
    for (int j = 0; j < t.w; ++j)
      shifted[std::size_t(i) * t.w + j] = t.pixels[std::size_t(std::min(i + 1, t.h - 1)) * t.w + j];
  const dvec3 wrong = exact_radiance_integral(t.w, t.h, shifted);
  for (int c = 0; c < 3; ++c) EXPECT_GT(std::abs(wrong[c] - exact[c]) / exact[c], 1e-2);
}

// --- normalisation ------------------------------------------------------------------------------

TEST(EnvironmentConstant, UniformAndNormalised) {
  const Environment env = Environment::constant(Spectrum(0.5f, 1.0f, 2.0f));
  EXPECT_TRUE(env.is_constant());
  EXPECT_EQ(env.radiance(vec3(0.3f, -0.2f, 0.9f)), Spectrum(0.5f, 1.0f, 2.0f));
  EXPECT_FLOAT_EQ(env.pdf(vec3(0, 1, 0)), float(0.25 / kPiD));
  const double integral = pdf_integral(env);
  std::printf("  constant: ∫pdf dω - 1 = %.2e\n", integral - 1.0);
  EXPECT_NEAR(integral, 1.0, 1e-5);
}

TEST(EnvironmentImage, PdfIntegratesToOne) {
  struct Case {
    const char* name;
    TestImage image;
  };
  const Case cases[] = {
      {"random 64x32 with bright pixels", random_image(64, 32, 1)},
      {"random 5x7 (taller than wide)", random_image(5, 7, 2)},
      {"light only in the polar rows, 16x8", polar_image(16, 8)},
  };
  for (const Case& c : cases) {
    // Bound: the lattice's error on the bright pixels (see sphere_quadrature), ~1e-4 here.
    const double integral = pdf_integral(c.image.env());
    std::printf("  %s: ∫pdf dω - 1 = %.2e\n", c.name, integral - 1.0);
    EXPECT_NEAR(integral, 1.0, 1e-3) << c.name;
  }
}

TEST(EnvironmentImage, RowsWeightedBySinTheta) {
  // Pixels of one luminance in two colours (so not a constant environment): with rows weighted
  // by sin θ the image distribution is uniform over the sphere up to the row discretisation. At
  // row centres pdf = H / (2π² Σ_i sin θ_i) and Σ_i sin θ_i = 1 / sin(π/2H), so
  // 4π pdf = sin(π/2H) / (π/2H) ≈ 1 - 1.6e-3 for H = 16. Without the sin θ weight, 4π pdf would be
  // 1 / (sin θ · 2/π · …), 10 times too large in the first row.
  const int w = 16, h = 16;
  const Spectrum grey(1.0f), pink((1.0f - 0.7152f * 0.5f - 0.0722f * 0.5f) / 0.2126f, 0.5f, 0.5f);  // Rec. 709 Y = 1
  std::vector<Spectrum> pixels;
  for (int k = 0; k < w * h; ++k) pixels.push_back(k % 2 ? grey : pink);
  const Environment env = Environment::from_pixels(w, h, pixels);
  ASSERT_FALSE(env.is_constant());
  double worst = 0.0;
  for (int i = 0; i < h; ++i) {
    for (int j = 0; j < w; ++j) {
      const double p = env.pdf(vec3(documented_direction((j + 0.5) / w, (i + 0.5) / h)));
      worst = std::max(worst, std::abs(p * 4.0 * kPiD - 1.0));
    }
  }
  std::printf("  equal luminance 16x16: max |4π pdf - 1| at pixel centres = %.1e\n", worst);
  EXPECT_LT(worst, 2e-3);
}

TEST(EnvironmentImage, BlackImageFallsBackToUniform) {
  const Environment env = Environment::from_pixels(8, 4, std::vector<Spectrum>(32, Spectrum(0.0f)));
  EXPECT_TRUE(env.is_constant());
  EXPECT_EQ(env.radiance(vec3(0.2f, 0.5f, -0.3f)), Spectrum(0.0f));
  float pdf = 0.0f;
  for (float u : {0.0f, 0.3f, 0.999f}) {
    const vec3 d = env.sample(u, 1.0f - u - 1e-3f, pdf);
    EXPECT_NEAR(glm::length(d), 1.0f, 1e-6f);
    EXPECT_FLOAT_EQ(pdf, float(0.25 / kPiD));
    EXPECT_FLOAT_EQ(env.pdf(d), float(0.25 / kPiD));
  }
  // Non-finite and negative values are black too.
  const Environment odd = Environment::from_pixels(2, 1, {Spectrum(NAN, -1.0f, 0.0f), Spectrum(INFINITY, 0.0f, -0.0f)});
  EXPECT_TRUE(odd.is_constant());
  EXPECT_EQ(odd.radiance(vec3(1, 0, 0)), Spectrum(0.0f));
  EXPECT_THROW(Environment::from_pixels(3, 2, std::vector<Spectrum>(5)), std::invalid_argument);
}

// --- sampling -----------------------------------------------------------------------------------

// Histogram of `n` samples over bins_u × bins_v bins of the documented (u, v) (i.e. of φ and θ)
// against the integral of pdf() over each bin. The integral is a midpoint rule on a grid whose
// lines include every bin edge and every pixel edge (lcm), on which pdf · 2π² sin θ is constant
// per cell for a correct implementation, so the expected counts carry no quadrature error
// beyond rounding. Returns the chi-square statistic and its degrees of freedom (bins with an
// expected count below 5 pooled into one). Also checks that sample() returns pdf(direction).
struct ChiSquare {
  double statistic = 0.0, dof = 0.0, worst_sigma = 0.0, expected_total = 0.0;
  long pdf_mismatches = 0, zero_pdf = 0;
};

ChiSquare histogram_test(const Environment& env, int image_w, int image_h, int bins_u, int bins_v, int n,
                         unsigned seed) {
  // 4 × the lcm: still exact for piecewise-constant integrands, and finer for smooth ones.
  const int grid_u = 4 * std::lcm(image_w, bins_u), grid_v = 4 * std::lcm(image_h, bins_v);
  std::vector<double> expected(std::size_t(bins_u) * bins_v, 0.0);
  ChiSquare r;
  for (int l = 0; l < grid_v; ++l) {
    const double v = (l + 0.5) / grid_v, jacobian = 2.0 * kPiD * kPiD * std::sin(kPiD * v);
    for (int k = 0; k < grid_u; ++k) {
      const double u = (k + 0.5) / grid_u;
      const double p = double(env.pdf(vec3(documented_direction(u, v)))) * jacobian / (double(grid_u) * grid_v);
      expected[std::size_t(l * bins_v / grid_v) * bins_u + std::size_t(k * bins_u / grid_u)] += p;
      r.expected_total += p;
    }
  }
  std::vector<long> observed(expected.size(), 0);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  for (int s = 0; s < n; ++s) {
    float pdf = -1.0f;
    const vec3 d = env.sample(U(rng), U(rng), pdf);
    if (pdf != env.pdf(d)) ++r.pdf_mismatches;
    if (!(pdf > 0.0f)) ++r.zero_pdf;
    double u, v;
    documented_uv(d, u, v);
    const int bu = std::clamp(int(u * bins_u), 0, bins_u - 1), bv = std::clamp(int(v * bins_v), 0, bins_v - 1);
    ++observed[std::size_t(bv) * bins_u + bu];
  }
  double pooled_expected = 0.0, pooled_observed = 0.0;
  int used = 0;
  for (std::size_t b = 0; b < expected.size(); ++b) {
    const double e = expected[b] * n;
    if (e < 5.0) {
      pooled_expected += e;
      pooled_observed += double(observed[b]);
      continue;
    }
    r.statistic += (observed[b] - e) * (observed[b] - e) / e;
    r.worst_sigma = std::max(r.worst_sigma, std::abs(observed[b] - e) / std::sqrt(e));
    ++used;
  }
  if (pooled_expected >= 5.0) {
    r.statistic += (pooled_observed - pooled_expected) * (pooled_observed - pooled_expected) / pooled_expected;
    ++used;
  } else {
    // Too little expected mass to test as a bin: it must then hold (almost) no samples.
    EXPECT_LE(pooled_observed, 10.0);
  }
  r.dof = used - 1;
  return r;
}

void expect_histogram_matches(const char* name, const Environment& env, int image_w, int image_h, unsigned seed) {
  const ChiSquare r = histogram_test(env, image_w, image_h, 40, 24, 400000, seed);
  // χ² with k degrees of freedom: mean k, standard deviation √(2k). Bound: k + 6√(2k).
  const double bound = r.dof + 6.0 * std::sqrt(2.0 * r.dof);
  std::printf("  %s: chi2 = %.1f for %.0f dof (bound %.1f), worst bin %.2f sigma, ∫pdf over bins - 1 = %.1e\n", name,
              r.statistic, r.dof, bound, r.worst_sigma, r.expected_total - 1.0);
  EXPECT_EQ(r.pdf_mismatches, 0) << name << ": sample()'s pdf differs from pdf(direction)";
  // A sample may land in the guard cap around a pole (sin θ < 1e-6, pdf 0): a fraction
  // ≈ 3.2e-7 · H of a polar row's probability, under 1e-5 of all samples here.
  EXPECT_LE(r.zero_pdf, 4) << name;
  EXPECT_NEAR(r.expected_total, 1.0, 1e-5) << name;  // exact quadrature: only rounding
  EXPECT_LT(r.statistic, bound) << name;
  EXPECT_LT(r.worst_sigma, 6.0) << name;
}

TEST(EnvironmentImage, SamplesFollowPdf) {
  const TestImage t = random_image(64, 32, 3);
  expect_histogram_matches("random 64x32", t.env(), t.w, t.h, 100);
  const TestImage p = polar_image(16, 8);
  expect_histogram_matches("polar 16x8", p.env(), p.w, p.h, 101);
  const TestImage s = random_image(5, 7, 4);
  expect_histogram_matches("random 5x7", s.env(), s.w, s.h, 102);
}

TEST(EnvironmentConstant, SamplesFollowPdf) {
  // Uniform pdf: the bins' integrals are their solid angles; the midpoint rule on 96 sub-rows
  // errs by ~5e-5 relative there, far below the counts' noise (~5%).
  const Environment env = Environment::constant(Spectrum(1.0f));
  const ChiSquare r = histogram_test(env, 1, 1, 40, 24, 400000, 200);
  const double bound = r.dof + 6.0 * std::sqrt(2.0 * r.dof);
  std::printf("  constant: chi2 = %.1f for %.0f dof (bound %.1f), worst bin %.2f sigma\n", r.statistic, r.dof, bound,
              r.worst_sigma);
  EXPECT_EQ(r.pdf_mismatches, 0);
  EXPECT_LT(r.statistic, bound);
}

// E[L / pdf] over the samples against ∫ L dω in closed form: the estimator a light-sampling
// integrator forms, unbiased only if pdf is the density the samples have.
// Also against the lattice quadrature of ∫ radiance() dω, to the quadrature's own accuracy.
void expect_unbiased(const char* name, const Environment& env, const dvec3& reference, int n, unsigned seed) {
  const dvec3 quadrature = sphere_quadrature([&](const vec3& d) { return dvec3(env.radiance(d)); });
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  dvec3 sum(0.0), sum_sq(0.0);
  for (int s = 0; s < n; ++s) {
    float pdf;
    const vec3 d = env.sample(U(rng), U(rng), pdf);
    if (!(pdf > 0.0f)) continue;
    const dvec3 x = dvec3(env.radiance(d)) / double(pdf);
    sum += x;
    sum_sq += x * x;
  }
  const dvec3 mean = sum / double(n);
  for (int c = 0; c < 3; ++c) {
    const double stderr_ = std::sqrt(std::max(0.0, sum_sq[c] / n - mean[c] * mean[c]) / n);
    std::printf("  %s, channel %d: E[L/pdf] = %.5f, ∫L dω = %.5f, relative error %.1e (%.1f standard errors)\n", name,
                c, mean[c], reference[c], (mean[c] - reference[c]) / reference[c],
                std::abs(mean[c] - reference[c]) / std::max(stderr_, 1e-300));
    EXPECT_NEAR(mean[c], reference[c], 5.0 * stderr_ + 1e-6 * reference[c]) << name << " channel " << c;
    EXPECT_NEAR(mean[c], quadrature[c], 5.0 * stderr_ + 5e-3 * reference[c]) << name << " channel " << c;
  }
}

TEST(EnvironmentImage, MonteCarloEstimateMatchesIntegral) {
  const TestImage t = random_image(64, 32, 5);
  expect_unbiased("random 64x32", t.env(), exact_radiance_integral(t.w, t.h, t.pixels), 200000, 300);
  const TestImage p = polar_image(16, 8);
  expect_unbiased("polar 16x8", p.env(), exact_radiance_integral(p.w, p.h, p.pixels), 200000, 301);
  const Spectrum c(0.5f, 1.0f, 2.0f);
  expect_unbiased("constant", Environment::constant(c), dvec3(c) * (4.0 * kPiD), 100000, 302);
}

TEST(EnvironmentImage, BrightPixelTakesNearlyAllSamples) {
  const int w = 64, h = 32, row = 9, col = 41;
  std::vector<Spectrum> pixels(std::size_t(w) * h, Spectrum(0.1f));
  pixels[std::size_t(row) * w + col] = Spectrum(1e5f);
  const Environment env = Environment::from_pixels(w, h, pixels);
  // The pixel's probability by the construction's rule (luminance · sin θ of the row centre).
  double total = 0.0;
  for (int i = 0; i < h; ++i)
    for (int j = 0; j < w; ++j) total += luminance_ref(pixels[std::size_t(i) * w + j]) * std::sin(kPiD * (i + 0.5) / h);
  const double p_bright = luminance_ref(pixels[std::size_t(row) * w + col]) * std::sin(kPiD * (row + 0.5) / h) / total;

  const int n = 20000;
  std::mt19937 rng(400);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  int outside = 0;
  for (int s = 0; s < n; ++s) {
    float pdf;
    const vec3 d = env.sample(U(rng), U(rng), pdf);
    // In the pixel's solid angle: θ in [π row / h, π (row + 1) / h], φ in its column's range.
    double u, v;
    documented_uv(d, u, v);
    if (!(u >= double(col) / w && u <= double(col + 1) / w && v >= double(row) / h && v <= double(row + 1) / h))
      ++outside;
  }
  const double expected_outside = n * (1.0 - p_bright);
  std::printf("  bright pixel: %d of %d samples outside it, %.1f expected (pixel probability %.6f)\n", outside, n,
              expected_outside, p_bright);
  EXPECT_GT(1.0 - double(outside) / n, 0.99);
  EXPECT_NEAR(outside, expected_outside, 5.0 * std::sqrt(expected_outside) + 1.0);
}

TEST(EnvironmentImage, PoleGuard) {
  // Samples at the extremes of u1 (the row) in an image lit only at the poles: finite, unit, pdf
  // finite, and equal to pdf(direction); pdf > 0 except at the pole itself.
  const TestImage t = polar_image(16, 8);
  const Environment env = t.env();
  // u1 = 0 and the float below 1 land within ~1e-7 rad of a pole, where pdf may be 0 (the guard
  // cap of sin θ < 1e-6: its radiance integral, ~3e-12 L, is what a caller that drops such
  // samples loses); from 1e-4 on the pdf must be positive.
  const float extremes[] = {0.0f, 1e-7f, 1e-4f, 0.25f, 0.5f, 0.75f, 1.0f - 1e-4f, std::nextafter(1.0f, 0.0f)};
  float max_pdf = 0.0f;
  for (float u1 : extremes) {
    for (float u0 : {0.0f, 0.37f, std::nextafter(1.0f, 0.0f)}) {
      float pdf = -1.0f;
      const vec3 d = env.sample(u0, u1, pdf);
      ASSERT_TRUE(std::isfinite(d.x) && std::isfinite(d.y) && std::isfinite(d.z));
      EXPECT_NEAR(glm::length(d), 1.0f, 1e-6f);
      ASSERT_TRUE(std::isfinite(pdf) && pdf >= 0.0f) << "u0 " << u0 << " u1 " << u1;
      EXPECT_EQ(pdf, env.pdf(d));
      if (u1 >= 1e-4f && u1 <= 1.0f - 1e-4f) {
        EXPECT_GT(pdf, 0.0f) << "u0 " << u0 << " u1 " << u1;
      }
      max_pdf = std::max(max_pdf, pdf);
    }
  }
  std::printf("  largest pdf near the poles: %.3g\n", max_pdf);
  EXPECT_EQ(env.pdf(vec3(0, 1, 0)), 0.0f);  // the pole itself
  EXPECT_EQ(env.pdf(vec3(0, -1, 0)), 0.0f);
  EXPECT_GT(env.pdf(vec3(0.01f, 1, 0)), 0.0f);
  EXPECT_GT(env.pdf(vec3(1e-5f, -1, 0)), 0.0f);  // the guard cap is far smaller than 1e-5 rad
  EXPECT_EQ(env.pdf(vec3(0.0f)), 0.0f);          // no direction
  EXPECT_EQ(env.radiance(vec3(NAN, 0, 1)), Spectrum(0.0f));
}

// --- the sun ------------------------------------------------------------------------------------

double angle_between(const dvec3& a, const dvec3& b) {
  return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

// 2π (1 - cos r), evaluated without cancellation.
double cone_solid_angle(double r) { return 4.0 * kPiD * std::sin(0.5 * r) * std::sin(0.5 * r); }

Sun make_sun(double radius) {
  Sun sun;
  sun.direction = glm::normalize(vec3(0.3f, 0.8f, -0.5f));
  sun.radiance = Spectrum(2e4f, 1.8e4f, 1.5e4f);
  sun.angular_radius = float(radius);
  return sun;
}

TEST(SunLight, SamplesInsideConeUniformAndNormalised) {
  for (double radius : {0.00465, 0.3, 2.0}) {
    const Sun sun = make_sun(radius);
    const double r = sun.angular_radius;  // the float the sun holds
    const dvec3 axis = glm::normalize(dvec3(sun.direction));
    const dvec3 t = glm::normalize(glm::cross(axis, dvec3(0, 0, 1))), b = glm::cross(axis, t);
    const double omega = cone_solid_angle(r);
    // Joint histogram of (1 - cos γ) / (1 - cos r) (uniform in [0, 1] for uniform solid angle) and
    // the azimuth around the axis: 20 × 16 bins.
    const int nh = 20, na = 16, n = 64000;
    std::vector<long> counts(nh * na, 0);
    std::mt19937 rng(500);
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    double worst_angle = 0.0, worst_pdf = 0.0;
    long mismatches = 0;
    dvec3 estimate(0.0);
    for (int s = 0; s < n; ++s) {
      float pdf;
      const vec3 d = sun.sample(U(rng), U(rng), pdf);
      const dvec3 dd = glm::normalize(dvec3(d));
      worst_angle = std::max(worst_angle, angle_between(dd, axis) / r);
      worst_pdf = std::max(worst_pdf, std::abs(pdf * omega - 1.0));
      if (pdf != sun.pdf(d)) ++mismatches;
      estimate += dvec3(sun.radiance_toward(d)) / double(pdf);
      const dvec3 e = dd - axis;
      const double h = 0.5 * glm::dot(e, e) / (2.0 * std::sin(0.5 * r) * std::sin(0.5 * r));
      const double az = std::atan2(glm::dot(dd, b), glm::dot(dd, t)) / (2.0 * kPiD) + 0.5;
      ++counts[std::clamp(int(h * nh), 0, nh - 1) * na + std::clamp(int(az * na), 0, na - 1)];
    }
    estimate /= double(n);
    double chi2 = 0.0;
    const double e = double(n) / (nh * na);
    for (long c : counts) chi2 += (c - e) * (c - e) / e;
    const double dof = nh * na - 1, bound = dof + 6.0 * std::sqrt(2.0 * dof);
    const double est_err =
        glm::length(estimate - dvec3(sun.radiance) * omega) / glm::length(dvec3(sun.radiance) * omega);
    std::printf(
        "  r = %.5f: max angle / r = %.9f, max |pdf·Ω - 1| = %.1e, chi2 = %.1f (%.0f dof, bound %.1f), "
        "E[L/pdf] relative error %.1e\n",
        r, worst_angle, worst_pdf, chi2, dof, bound, est_err);
    EXPECT_LE(worst_angle, 1.0 + 1e-9) << r;
    EXPECT_LT(worst_pdf, 2e-7) << r;  // float rounding of 1/Ω
    EXPECT_EQ(mismatches, 0) << r;
    EXPECT_LT(chi2, bound) << r;
    // Every sample is inside, so every term is radiance · Ω exactly up to rounding.
    EXPECT_LT(est_err, 1e-6) << r;
  }
}

TEST(SunLight, ZeroOutsideTheCone) {
  for (double radius : {0.00465, 0.3}) {
    const Sun sun = make_sun(radius);
    const double r = sun.angular_radius;
    const dvec3 axis = glm::normalize(dvec3(sun.direction));
    const dvec3 t = glm::normalize(glm::cross(axis, dvec3(1, 0, 0)));
    auto at_angle = [&](double g) { return vec3(std::cos(g) * axis + std::sin(g) * t); };
    const float inside_pdf = float(1.0 / cone_solid_angle(r));
    for (double g : {0.0, 0.5 * r, 0.99 * r}) {
      EXPECT_EQ(sun.radiance_toward(at_angle(g)), sun.radiance) << "angle " << g / r << " r";
      EXPECT_NEAR(sun.pdf(at_angle(g)), inside_pdf, 1e-6 * inside_pdf) << "angle " << g / r << " r";
    }
    EXPECT_EQ(sun.radiance_toward(3.0f * at_angle(0.5 * r)), sun.radiance);  // need not be unit
    for (double g : {1.01 * r, 2.0 * r, 0.5 * kPiD, kPiD}) {
      EXPECT_EQ(sun.radiance_toward(at_angle(g)), Spectrum(0.0f)) << "angle " << g / r << " r";
      EXPECT_EQ(sun.pdf(at_angle(g)), 0.0f) << "angle " << g / r << " r";
    }
  }
  Sun none = make_sun(0.0);  // no cone: nothing to see or sample
  float pdf = 1.0f;
  none.sample(0.5f, 0.5f, pdf);
  EXPECT_EQ(pdf, 0.0f);
  EXPECT_EQ(none.pdf(none.direction), 0.0f);
  EXPECT_EQ(none.radiance_toward(none.direction), Spectrum(0.0f));
}

// --- loading ------------------------------------------------------------------------------------

class EnvironmentLoad : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("gwnrt_env_test_" + std::to_string(std::random_device{}()) + "_" +
                                                     ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  std::string write_exr(const std::string& name, int w, int h, int channels, const std::vector<float>& data) {
    const std::string path = (dir_ / name).string();
    std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(path);
    EXPECT_TRUE(out) << OIIO::geterror();
    if (!out) return path;
    OIIO::ImageSpec spec(w, h, channels, OIIO::TypeDesc::FLOAT);
    EXPECT_TRUE(out->open(path, spec)) << out->geterror();
    EXPECT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, data.data())) << out->geterror();
    EXPECT_TRUE(out->close()) << out->geterror();
    return path;
  }
  std::filesystem::path dir_;
};

Spectrum at_pixel(const Environment& env, int w, int h, int i, int j) {
  return env.radiance(vec3(documented_direction((j + 0.5) / w, (i + 0.5) / h)));
}

TEST_F(EnvironmentLoad, RgbExrRoundTrip) {
  const int w = 6, h = 3;
  std::vector<float> data;
  for (int i = 0; i < h; ++i)
    for (int j = 0; j < w; ++j)
      for (int c = 0; c < 3; ++c) data.push_back(0.25f * i + 0.01f * j + 1.5f * c + 0.125f);
  const std::string path = write_exr("rgb.exr", w, h, 3, data);
  Environment env;
  const Status s = Environment::load(path, 2.0f, env);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_FALSE(env.is_constant());
  for (int i = 0; i < h; ++i) {
    for (int j = 0; j < w; ++j) {
      const float* p = &data[(std::size_t(i) * w + j) * 3];
      EXPECT_EQ(at_pixel(env, w, h, i, j), 2.0f * Spectrum(p[0], p[1], p[2])) << i << ", " << j;
    }
  }
}

TEST_F(EnvironmentLoad, GreyReplicatedAlphaDropped) {
  const int w = 4, h = 2;
  std::vector<float> grey, rgba;
  for (int k = 0; k < w * h; ++k) {
    grey.push_back(0.5f + k);
    rgba.insert(rgba.end(), {1.0f + k, 2.0f + k, 3.0f + k, 0.25f});  // alpha well below the colours
  }
  Environment g, a;
  ASSERT_TRUE(Environment::load(write_exr("grey.exr", w, h, 1, grey), 1.0f, g).ok());
  ASSERT_TRUE(Environment::load(write_exr("rgba.exr", w, h, 4, rgba), 1.0f, a).ok());
  for (int i = 0; i < h; ++i) {
    for (int j = 0; j < w; ++j) {
      const int k = i * w + j;
      EXPECT_EQ(at_pixel(g, w, h, i, j), Spectrum(0.5f + k));
      EXPECT_EQ(at_pixel(a, w, h, i, j), Spectrum(1.0f + k, 2.0f + k, 3.0f + k));
    }
  }
}

TEST_F(EnvironmentLoad, FailuresNameThePath) {
  const std::string missing = (dir_ / "no_such_sky.exr").string();
  Environment env = Environment::constant(Spectrum(1.0f));
  const Status s = Environment::load(missing, 1.0f, env);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find(missing), std::string::npos) << s.message();
  std::printf("  missing file: %s\n", s.message().c_str());
  EXPECT_EQ(env.radiance(vec3(0, 1, 0)), Spectrum(1.0f));  // untouched on failure

  const std::string garbage = (dir_ / "garbage.exr").string();
  {
    std::FILE* f = std::fopen(garbage.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    std::fputs("this is not an image", f);
    std::fclose(f);
  }
  const Status g = Environment::load(garbage, 1.0f, env);
  EXPECT_FALSE(g.ok());
  EXPECT_NE(g.message().find(garbage), std::string::npos) << g.message();
  std::printf("  garbage file: %s\n", g.message().c_str());
}

// An image's pixels times its scale beyond float (a radiance of 1e39 read
// as inf, then zeroed as non-finite) or beyond what a pixel's sum of samples carries
// (kMaxRadiance) are refused, naming the file; at the limit the image loads unchanged.
TEST_F(EnvironmentLoad, RadianceBeyondTheLimitIsRefused) {
  const int w = 4, h = 2;
  std::vector<float> data(std::size_t(w) * h * 3, 0.5f);
  data[5] = 1e19f;  // one pixel's blue
  const std::string path = write_exr("bright.exr", w, h, 3, data);
  for (const float scale : {11.0f, 1e20f, 3e38f}) {
    Environment env;
    const Status s = Environment::load(path, scale, env);
    EXPECT_FALSE(s.ok()) << scale;
    EXPECT_NE(s.message().find(path + ": its brightest pixel (1e+19) times the scale"), std::string::npos)
        << s.message();
  }
  Environment env;
  const Status s = Environment::load(path, 10.0f, env);  // 1e20: the limit itself
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(at_pixel(env, w, h, 0, 1).z, 1e20f);
  EXPECT_EQ(at_pixel(env, w, h, 0, 0), Spectrum(5.0f));
}

}  // namespace
}  // namespace gwnrt::render
