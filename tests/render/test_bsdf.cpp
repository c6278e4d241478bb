// The path tracer's materials (render/bsdf.h) against references of their own:
//   - GGX, Smith and Fresnel written again here in double precision from their textbook forms
//     (tan θ, Λ, angles), not from the implementation's rearranged ones;
//   - integrals over the hemisphere by Gauss–Legendre quadrature (3 × 3 points per cell) on a
//     (θ, φ) grid whose cells crowd around the lobe (the mirror direction of wo, with the lobe's
//     width), so that the narrow GGX lobes at roughness 0.1 (α = 0.01), thinner still at grazing
//     wo, are resolved; the horizon is a cell boundary;
//   - the GGX acceptance probability (what ∫ pdf equals) over the microfacet normals, with the
//     azimuth integrated in closed form;
//   - sample statistics with tolerances derived from the samples' own spread.
// All random numbers come from fixed seeds: the suite is deterministic.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "render/bsdf.h"
#include "test_util.h"

namespace gwnrt::render {
namespace {

using dvec3 = glm::dvec3;

constexpr double kTwoPi = 2.0 * kPi;

struct Rng {
  explicit Rng(uint32_t seed) : g(seed) {}
  std::mt19937 g;
  float uniform() { return float(g() >> 8) * 0x1p-24f; }  // [0, 1), 24 bits
};

vec3 spherical(double theta, double phi) {
  return vec3(float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)), float(std::cos(theta)));
}

dvec3 to_d(const vec3& v) { return dvec3(v.x, v.y, v.z); }

Material diffuse(const Spectrum& albedo) {
  Material m;
  m.kind = MaterialKind::kDiffuse;
  m.albedo = albedo;
  return m;
}
Material conductor(const Spectrum& f0, float roughness) {
  Material m;
  m.kind = MaterialKind::kConductor;
  m.albedo = f0;
  m.roughness = roughness;
  return m;
}
Material dielectric(float ior) {
  Material m;
  m.kind = MaterialKind::kDielectric;
  m.ior = ior;
  return m;
}

double rel_err(double a, double b) { return std::abs(a - b) / std::max(std::abs(b), 1e-30); }

// ---- References in double precision ------------------------------------------------------------

double ref_schlick(double f0, double c) { return f0 + (1.0 - f0) * std::pow(1.0 - c, 5.0); }

// GGX with α: D(m) = 1 / (π α² cos⁴θm (1 + tan²θm / α²)²).
double ref_ggx_d(const dvec3& m, double alpha) {
  if (m.z <= 0.0) return 0.0;
  const double c2 = m.z * m.z, tan2 = (m.x * m.x + m.y * m.y) / c2;
  const double k = 1.0 + tan2 / (alpha * alpha);
  return 1.0 / (kPi * alpha * alpha * c2 * c2 * k * k);
}
// Smith Λ for GGX: (−1 + √(1 + α² tan²θ)) / 2.
double ref_lambda(const dvec3& w, double alpha) {
  const double tan2 = (w.x * w.x + w.y * w.y) / (w.z * w.z);
  return 0.5 * (-1.0 + std::sqrt(1.0 + alpha * alpha * tan2));
}
double ref_g1(const dvec3& w, double alpha) { return 1.0 / (1.0 + ref_lambda(w, alpha)); }
// Distribution of normals visible from wo: G1(wo) max(0, wo·m) D(m) / wo_z.
double ref_visible_d(const dvec3& wo, const dvec3& m, double alpha) {
  return ref_g1(wo, alpha) * std::max(0.0, glm::dot(wo, m)) * ref_ggx_d(m, alpha) / wo.z;
}
// f = F D G2 / (4 wo_z wi_z) with the height-correlated G2 = 1 / (1 + Λ(wo) + Λ(wi)).
double ref_ggx_f(const dvec3& wo, const dvec3& wi, double alpha, double f0) {
  if (wo.z <= 0.0 || wi.z <= 0.0) return 0.0;
  const dvec3 m = glm::normalize(wo + wi);
  const double g2 = 1.0 / (1.0 + ref_lambda(wo, alpha) + ref_lambda(wi, alpha));
  return ref_schlick(f0, glm::dot(wo, m)) * ref_ggx_d(m, alpha) * g2 / (4.0 * wo.z * wi.z);
}
// pdf = D_wo(m) / (4 |wo·m|).
double ref_ggx_pdf(const dvec3& wo, const dvec3& wi, double alpha) {
  if (wo.z <= 0.0 || wi.z <= 0.0) return 0.0;
  const dvec3 m = glm::normalize(wo + wi);
  return ref_visible_d(wo, m, alpha) / (4.0 * std::abs(glm::dot(wo, m)));
}

// Exact Fresnel reflectance by angles: r_s = sin(θi − θt) / sin(θi + θt),
// r_p = tan(θi − θt) / tan(θi + θt). eta_i on the incident side.
double ref_fresnel(double cos_i, double eta_i, double eta_t) {
  const double ti = std::acos(std::clamp(cos_i, 0.0, 1.0));
  const double st = eta_i / eta_t * std::sin(ti);
  if (st >= 1.0) return 1.0;
  if (ti == 0.0) return std::pow((eta_i - eta_t) / (eta_i + eta_t), 2.0);
  const double tt = std::asin(st);
  const double rs = std::sin(ti - tt) / std::sin(ti + tt);
  const double rp = std::tan(ti - tt) / std::tan(ti + tt);
  return 0.5 * (rs * rs + rp * rp);
}

// ---- Quadrature over the hemisphere ------------------------------------------------------------

// Cell boundaries on [a, b]: n/2 equal cells merged with n/2 cells that crowd around c with a Cauchy
// profile of width w (x = c + w tan t, t uniform; like the tails of GGX). The uniform half bounds
// every cell by 2 (b − a)/n wherever the lobe's guessed centre and width are off.
struct Axis {
  std::vector<double> nodes;  // sorted, from a to b
  Axis(double a, double b, double c, double w, int n) {
    const int h = n / 2;
    for (int k = 0; k <= h; ++k) nodes.push_back(a + (b - a) * k / h);
    const double t0 = std::atan((a - c) / w), t1 = std::atan((b - c) / w);
    for (int k = 1; k < h; ++k) nodes.push_back(c + w * std::tan(t0 + (t1 - t0) * k / h));
    std::sort(nodes.begin(), nodes.end());
    std::vector<double> kept{nodes.front()};
    for (double x : nodes)
      if (x > kept.back() + 1e-12 * (b - a)) kept.push_back(x);
    kept.back() = b;
    nodes.swap(kept);
  }
  int cells() const { return int(nodes.size()) - 1; }
  int cell_of(double x) const {
    const int k = int(std::upper_bound(nodes.begin(), nodes.end(), x) - nodes.begin()) - 1;
    return std::clamp(k, 0, cells() - 1);
  }
};

// The upper hemisphere in spherical coordinates about the normal, θ in [0, π/2] (the horizon is a
// cell boundary, so the pdf's jump there costs the midpoint rule nothing) and φ in
// [φc − π, φc + π], both refined around a lobe's centre (θc, φc) with widths wθ, wφ.
struct HemiGrid {
  double phi_c;
  Axis theta, phi;
  HemiGrid(double theta_c, double w_theta, double phi_c_, double w_phi, int n)
      : phi_c(phi_c_), theta(0.0, 0.5 * kPi, theta_c, w_theta, n), phi(phi_c - kPi, phi_c + kPi, phi_c, w_phi, n) {}
  // Gauss–Legendre with q = 1..3 points per cell and axis: fn(it, ip, direction, weight), the
  // weights (sin θ dθ dφ) of a cell's points summing to its solid angle.
  template <class Fn>
  void for_each_point(int q, Fn&& fn) const {
    static const double kX[3][3] = {
        {0.0}, {-0.5773502691896258, 0.5773502691896258}, {-0.7745966692414834, 0.0, 0.7745966692414834}};
    static const double kW[3][3] = {{2.0}, {1.0, 1.0}, {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0}};
    const int nt = theta.cells(), np = phi.cells();
    std::vector<double> cp(np * q), sp(np * q), wp(np * q);
    for (int j = 0; j < np; ++j) {
      const double mid = 0.5 * (phi.nodes[j] + phi.nodes[j + 1]), half = 0.5 * (phi.nodes[j + 1] - phi.nodes[j]);
      for (int k = 0; k < q; ++k) {
        cp[j * q + k] = std::cos(mid + half * kX[q - 1][k]);
        sp[j * q + k] = std::sin(mid + half * kX[q - 1][k]);
        wp[j * q + k] = half * kW[q - 1][k];
      }
    }
    for (int i = 0; i < nt; ++i) {
      const double mid = 0.5 * (theta.nodes[i] + theta.nodes[i + 1]),
                   half = 0.5 * (theta.nodes[i + 1] - theta.nodes[i]);
      for (int a = 0; a < q; ++a) {
        const double th = mid + half * kX[q - 1][a];
        const double st = std::sin(th), ct = std::cos(th), wt = st * half * kW[q - 1][a];
        for (int j = 0; j < np; ++j)
          for (int k = 0; k < q; ++k) fn(i, j, dvec3(st * cp[j * q + k], st * sp[j * q + k], ct), wt * wp[j * q + k]);
      }
    }
  }
  void cell_of(const dvec3& d, int& it, int& ip) const {
    it = theta.cell_of(std::acos(std::clamp(d.z, -1.0, 1.0)));
    double p = std::atan2(d.y, d.x);
    while (p < phi_c - kPi) p += kTwoPi;
    while (p >= phi_c + kPi) p -= kTwoPi;
    ip = phi.cell_of(p);
  }
};

constexpr double kUniform = 1e3;  // an Axis width that is as good as uniform

// A grid suited to a material and wo. Diffuse: uniform. GGX: around the mirror direction; the
// reflected lobe is ~2α wide in the plane of incidence and ~2α (cos θo + α) across it (a normal
// tilted across the plane turns wi by only 2 (wo·m) times the tilt), which at grazing wo is thin.
HemiGrid grid_for(const Material& m, const vec3& wo, int n) {
  if (m.kind == MaterialKind::kDiffuse) return HemiGrid(0.25 * kPi, kUniform, 0.0, kUniform, n);
  const double alpha = double(m.roughness) * m.roughness;
  const double theta_r = std::acos(std::clamp(double(wo.z), -1.0, 1.0));
  const double phi_r = std::atan2(-double(wo.y), -double(wo.x));
  const double sin_r = std::sin(theta_r);
  const double w_phi = sin_r > 2.0 * alpha ? 2.0 * alpha * (wo.z + alpha) / sin_r : kUniform;
  return HemiGrid(theta_r, 2.0 * alpha, phi_r, w_phi, n);
}

// Albedo ∫ f cos θi dωi of channel 0 and ∫ pdf dω, by quadrature over the upper hemisphere (the
// only part where the non-delta materials are non-zero; BsdfPdf checks the lower one separately).
// n cells per axis, 3 Gauss–Legendre points per cell and axis.
void integrate(const Material& m, const vec3& wo, int n, double& albedo, double& pdf_integral) {
  albedo = 0.0;
  pdf_integral = 0.0;
  grid_for(m, wo, n).for_each_point(3, [&](int, int, const dvec3& d, double dw) {
    const vec3 wi(d);
    albedo += double(bsdf_eval(m, wo, wi).x) * std::max(0.0, d.z) * dw;
    pdf_integral += double(bsdf_pdf(m, wo, wi)) * dw;
  });
}

// Wilson–Hilferty: a chi-square statistic with k degrees of freedom as an approximately standard
// normal z. z > 5 (one-sided p ≈ 3e-7) rejects.
double chi_square_z(double stat, int k) {
  const double h = 2.0 / (9.0 * k);
  return (std::cbrt(stat / k) - (1.0 - h)) / std::sqrt(h);
}

// ---- Sampling consistency ----------------------------------------------------------------------

struct SamplingCase {
  Material m;
  vec3 wo;
  const char* name;
};

std::vector<vec3> test_wos() {
  // θo = 0°, 30°, 60°, 80°, 89° (the last two grazing), at an azimuth off the axes.
  std::vector<vec3> wos;
  for (double deg : {0.0, 30.0, 60.0, 80.0, 89.0}) wos.push_back(spherical(deg * kPi / 180.0, 0.7));
  return wos;
}

std::vector<Material> non_delta_materials() {
  const Spectrum f0(0.95f, 0.64f, 0.54f);  // copper-ish: exercises Schlick per channel
  return {diffuse(Spectrum(0.8f, 0.5f, 0.2f)), conductor(f0, 0.1f), conductor(f0, 0.3f), conductor(f0, 0.7f),
          conductor(f0, 1.0f)};
}

// For every non-delta material and several wo:
//   (1) each sample: wi unit and above the surface, pdf == bsdf_pdf(wo, wi) and
//       weight == eval · cos / pdf;
//   (2) the mean weight (rejected samples counting 0) equals the quadrature albedo;
//   (3) a chi-square test of the sampled directions (plus a cell for rejections) against the
//       probabilities that quadrature of bsdf_pdf gives each cell;
//   (4) the rejection frequency equals 1 − ∫ pdf.
TEST(BsdfSampling, MatchesEvalPdfAndQuadrature) {
  constexpr int kSamples = 100000;
  constexpr int kBinsT = 16, kBinsPhi = 16, kCells = 256;  // chi-square bins: groups of ~16 × 16 cells
  Rng rng(12345);
  double worst_mean_sigma = 0.0, worst_mean_abs = 0.0, worst_chi_z = -1e9, worst_reject_sigma = 0.0;
  double worst_pdf_rel = 0.0, worst_weight_rel = 0.0;
  for (const Material& m : non_delta_materials()) {
    for (const vec3& wo : test_wos()) {
      SCOPED_TRACE(::testing::Message() << "kind " << int(m.kind) << " roughness " << m.roughness << " wo_z " << wo.z);
      const HemiGrid grid = grid_for(m, wo, kCells);
      const int nt = grid.theta.cells(), np = grid.phi.cells();
      const int nb = kBinsT * kBinsPhi;
      std::vector<double> expected(nb + 1, 0.0);  // the last cell: rejection
      dvec3 albedo(0.0);
      double pdf_integral = 0.0;
      grid.for_each_point(3, [&](int i, int j, const dvec3& d, double dw) {
        const vec3 wi(d);
        const Spectrum f = bsdf_eval(m, wo, wi);
        albedo += to_d(f) * std::max(0.0, d.z) * dw;
        const double p = double(bsdf_pdf(m, wo, wi)) * dw;
        pdf_integral += p;
        expected[(i * kBinsT / nt) * kBinsPhi + j * kBinsPhi / np] += p;
      });
      expected[nb] = std::max(0.0, 1.0 - pdf_integral);

      std::vector<double> observed(nb + 1, 0.0);
      dvec3 sum(0.0), sum2(0.0);
      int bad_samples = 0;
      for (int s = 0; s < kSamples; ++s) {
        BsdfSample bs;
        const float u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
        if (!bsdf_sample(m, wo, u0, u1, u2, bs)) {
          observed[nb] += 1.0;
          continue;
        }
        const double len = glm::length(to_d(bs.wi));
        const float pdf = bsdf_pdf(m, wo, bs.wi);
        const Spectrum expect_w = bsdf_eval(m, wo, bs.wi) * std::abs(bs.wi.z) / bs.pdf;
        double wrel = 0.0;
        for (int c = 0; c < 3; ++c)
          wrel = std::max(wrel, double(std::abs(bs.weight[c] - expect_w[c]) / std::max(1e-6f, expect_w[c])));
        const double prel = rel_err(bs.pdf, pdf);
        worst_pdf_rel = std::max(worst_pdf_rel, prel);
        worst_weight_rel = std::max(worst_weight_rel, wrel);
        // Float rounding only: 1e-5 on the length, 1e-4 relative on pdf and weight.
        if (bs.delta || !(bs.wi.z > 0.0f) || std::abs(len - 1.0) > 1e-5 || !(bs.pdf > 0.0f) || prel > 1e-4 ||
            wrel > 1e-4) {
          if (++bad_samples <= 3)
            ADD_FAILURE() << "sample " << s << ": wi (" << bs.wi.x << ", " << bs.wi.y << ", " << bs.wi.z << ") pdf "
                          << bs.pdf << " vs bsdf_pdf " << pdf << ", weight " << bs.weight.x << " vs eval·cos/pdf "
                          << expect_w.x << ", delta " << bs.delta;
        }
        sum += to_d(bs.weight);
        sum2 += to_d(bs.weight) * to_d(bs.weight);
        int it, ip;
        grid.cell_of(to_d(bs.wi), it, ip);
        observed[(it * kBinsT / nt) * kBinsPhi + ip * kBinsPhi / np] += 1.0;
      }
      EXPECT_EQ(bad_samples, 0);

      // (2) Mean weight vs albedo: 5 standard errors of the mean, plus 5e-5 for the quadrature
      // (error below 1e-5: BsdfSampling.QuadratureConverged).
      for (int c = 0; c < 3; ++c) {
        const double mean = sum[c] / kSamples;
        const double var = std::max(0.0, sum2[c] / kSamples - mean * mean);
        const double se = std::sqrt(var / kSamples);
        const double err = std::abs(mean - albedo[c]);
        EXPECT_LE(err, 5.0 * se + 5e-5) << "channel " << c << ": mean weight " << mean << ", albedo " << albedo[c];
        worst_mean_abs = std::max(worst_mean_abs, err);
        if (se > 0.0) worst_mean_sigma = std::max(worst_mean_sigma, err / se);
      }

      // (4) Rejections: binomial, 5σ plus 5e-5 for the quadrature of ∫ pdf.
      const double p_reject = expected[nb];
      const double f_reject = observed[nb] / kSamples;
      const double sigma = std::sqrt(std::max(p_reject * (1.0 - p_reject), 1e-12) / kSamples);
      EXPECT_LE(std::abs(f_reject - p_reject), 5.0 * sigma + 5e-5)
          << "rejected " << f_reject << ", 1 − ∫pdf " << p_reject;
      worst_reject_sigma = std::max(worst_reject_sigma, std::abs(f_reject - p_reject) / sigma);

      // (3) Chi-square: cells expecting fewer than 5 samples are pooled.
      double stat = 0.0, pool_e = 0.0, pool_o = 0.0;
      int cells = 0;
      for (int k = 0; k <= nb; ++k) {
        const double e = expected[k] * kSamples;
        if (e < 5.0) {
          pool_e += e;
          pool_o += observed[k];
          continue;
        }
        stat += (observed[k] - e) * (observed[k] - e) / e;
        ++cells;
      }
      if (pool_e >= 5.0) {
        stat += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        ++cells;
      } else {
        // Too few expected for a cell of its own: a Poisson count of mean < 5 exceeds 25 with
        // probability < 1e-9.
        EXPECT_LE(pool_o, 25.0) << "samples where the pdf expects almost none";
      }
      ASSERT_GE(cells, 2);
      const double z = chi_square_z(stat, cells - 1);
      EXPECT_LT(z, 5.0) << "chi-square " << stat << " over " << cells - 1 << " degrees of freedom";
      worst_chi_z = std::max(worst_chi_z, z);
    }
  }
  std::printf(
      "[ measured ] mean weight vs albedo: worst %.2e abs, %.2f standard errors; chi-square worst z %.2f; "
      "rejection worst %.2f sigma; pdf vs bsdf_pdf worst rel %.1e; weight vs eval·cos/pdf worst rel %.1e\n",
      worst_mean_abs, worst_mean_sigma, worst_chi_z, worst_reject_sigma, worst_pdf_rel, worst_weight_rel);
}

// The quadrature itself, where it is hardest (roughness 0.1, the narrowest lobes, thinnest at
// grazing wo): doubling the cells moves the albedo and ∫ pdf by less than 1e-5, so the 5e-5 allowed
// for the quadrature above is generous.
TEST(BsdfSampling, QuadratureConverged) {
  double worst = 0.0;
  const Material m = conductor(Spectrum(0.95f, 0.64f, 0.54f), 0.1f);
  for (const vec3& wo : test_wos()) {
    double a1, p1, a2, p2;
    integrate(m, wo, 256, a1, p1);
    integrate(m, wo, 512, a2, p2);
    EXPECT_NEAR(a1, a2, 1e-5) << "wo_z " << wo.z;
    EXPECT_NEAR(p1, p2, 1e-5) << "wo_z " << wo.z;
    worst = std::max({worst, std::abs(a1 - a2), std::abs(p1 - p2)});
  }
  std::printf("[ measured ] quadrature 256² vs 512² cells at roughness 0.1: worst change %.1e\n", worst);
}

// The reference for ∫ pdf of GGX: the probability that a normal m drawn from D_wo reflects wo above
// the horizon, P = ∫ D_wo(m) [2 (wo·m) m_z > wo_z] dm, over the normals' (θ, Δφ) with Δφ the
// azimuth from wo's. With wo = (s_o, 0, c_o) and A = s_o sin θ, B = c_o cos θ:
//   wo·m = A cos Δφ + B, and 2 (wo·m) m_z > c_o  ⟺  cos Δφ > −c_o cos 2θ / (s_o sin 2θ),
// so each ring of normals is accepted for |Δφ| < φ1(θ), where A cos Δφ + B > 0 too, and the
// integral over Δφ is closed-form, 2 (A sin φ1 + B φ1). What remains is a 1D integral over θ,
// with kinks where φ1 reaches π or 0 (θ = π/4 ∓ θo/2) and where the full ring stops being visible
// (θ = π/2 − θo): Gauss–Legendre on cells split there and crowded around θ = 0. With
// accepted = false it integrates D_wo over all normals (1 for a distribution of visible normals).
double ref_visible_integral(const vec3& wo_f, double alpha, bool accepted_only) {
  const double c_o = wo_f.z, s_o = std::sqrt(double(wo_f.x) * wo_f.x + double(wo_f.y) * wo_f.y);
  const double theta_o = std::atan2(s_o, c_o);
  const double g1 = ref_g1(dvec3(s_o, 0.0, c_o), alpha);
  std::vector<double> nodes = Axis(0.0, 0.5 * kPi, 0.0, alpha, 2048).nodes;
  for (double k : {0.25 * kPi - 0.5 * theta_o, 0.25 * kPi + 0.5 * theta_o, 0.5 * kPi - theta_o})
    if (k > 0.0 && k < 0.5 * kPi) nodes.push_back(k);
  std::sort(nodes.begin(), nodes.end());
  static const double kX[3] = {-0.7745966692414834, 0.0, 0.7745966692414834};
  static const double kW[3] = {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};
  double sum = 0.0;
  for (size_t i = 0; i + 1 < nodes.size(); ++i) {
    const double mid = 0.5 * (nodes[i] + nodes[i + 1]), half = 0.5 * (nodes[i + 1] - nodes[i]);
    for (int k = 0; k < 3; ++k) {
      const double th = mid + half * kX[k];
      const double a = s_o * std::sin(th), b = c_o * std::cos(th);
      // Visible part of the ring: A cos Δφ + B > 0.
      double phi1 = a <= b ? kPi : std::acos(-b / a);
      if (accepted_only) {
        const double den = s_o * std::sin(2.0 * th), num = -c_o * std::cos(2.0 * th);
        const double phi_acc = den > 0.0 ? std::acos(std::clamp(num / den, -1.0, 1.0)) : (num < 0.0 ? kPi : 0.0);
        phi1 = std::min(phi1, phi_acc);
      }
      const double ring = 2.0 * (a * std::sin(phi1) + b * phi1);  // ∫ (wo·m) dΔφ over |Δφ| < φ1
      const double d = ref_ggx_d(dvec3(std::sin(th), 0.0, std::cos(th)), alpha);
      sum += half * kW[k] * std::sin(th) * g1 * d * ring / c_o;
    }
  }
  return sum;
}

// ∫ pdf over the sphere. Diffuse: 1. GGX: the visible-normal sampler's reflected directions below
// the horizon are rejected and bsdf_pdf is not renormalized, so the integral is the acceptance
// probability P above (< 1), computed over the microfacet normals (no Jacobian involved). Over the
// lower hemisphere bsdf_pdf must integrate to exactly 0.
TEST(BsdfPdf, IntegratesToAcceptanceProbability) {
  double worst = 0.0, worst_norm = 0.0;
  for (const Material& m : non_delta_materials()) {
    for (const vec3& wo : test_wos()) {
      SCOPED_TRACE(::testing::Message() << "roughness " << m.roughness << " wo_z " << wo.z);
      double albedo, pdf_integral;
      integrate(m, wo, 256, albedo, pdf_integral);
      double below = 0.0;
      HemiGrid(0.25 * kPi, kUniform, 0.0, kUniform, 128).for_each_point(1, [&](int, int, const dvec3& d, double dw) {
        below += double(bsdf_pdf(m, wo, vec3(float(d.x), float(d.y), -float(d.z)))) * dw;
      });
      EXPECT_EQ(below, 0.0);
      double reference = 1.0;
      if (m.kind == MaterialKind::kConductor) {
        const double alpha = double(m.roughness) * m.roughness;
        const double norm = ref_visible_integral(wo, alpha, false);
        EXPECT_NEAR(norm, 1.0, 1e-9) << "the reference's D_wo is not normalized";
        worst_norm = std::max(worst_norm, std::abs(norm - 1.0));
        reference = ref_visible_integral(wo, alpha, true);
        if (wo.z < 0.05f) {
          EXPECT_LT(reference, 0.999) << "at grazing wo some reflected directions fall below the horizon";
        }
      }
      // Quadrature error below 1e-5 (BsdfSampling.QuadratureConverged).
      EXPECT_NEAR(pdf_integral, reference, 2e-5);
      worst = std::max(worst, std::abs(pdf_integral - reference));
    }
  }
  // An anchor in closed form: α = 1 makes D = 1/π, so at normal incidence D_wo = cos θm / π and
  // m reflects wo above the horizon iff θm < π/4: P = sin²(π/4) = 1/2.
  double albedo, pdf_integral;
  integrate(conductor(Spectrum(1.0f), 1.0f), vec3(0, 0, 1), 256, albedo, pdf_integral);
  EXPECT_NEAR(pdf_integral, 0.5, 1e-6);
  std::printf("[ measured ] ∫pdf vs reference: worst abs error %.1e (reference's ∫D_wo − 1: %.1e)\n", worst,
              worst_norm);
}

// ---- Pointwise references ----------------------------------------------------------------------

TEST(BsdfConductor, EvalAndPdfMatchReferenceGgx) {
  Rng rng(7);
  const Spectrum f0(0.9f, 0.5f, 0.1f);
  double worst_f = 0.0, worst_p = 0.0;
  for (float roughness : {0.05f, 0.1f, 0.3f, 0.7f, 1.0f}) {
    const Material m = conductor(f0, roughness);
    const double alpha = double(roughness) * roughness;
    for (int k = 0; k < 2000; ++k) {
      // Uniform over the upper hemisphere, cos θ ≥ 0.01.
      const vec3 wo = spherical(std::acos(0.01 + 0.99 * rng.uniform()), kTwoPi * rng.uniform());
      const vec3 wi = spherical(std::acos(0.01 + 0.99 * rng.uniform()), kTwoPi * rng.uniform());
      const Spectrum f = bsdf_eval(m, wo, wi);
      for (int c = 0; c < 3; ++c) {
        const double ref = ref_ggx_f(to_d(wo), to_d(wi), alpha, f0[c]);
        // Float rounding of the half vector moves D by up to ~4e-7 / α relative (2e-4 at α = 0.0025).
        EXPECT_LE(rel_err(f[c], ref), 1e-3) << "roughness " << roughness << " channel " << c;
        worst_f = std::max(worst_f, rel_err(f[c], ref));
      }
      const double pref = ref_ggx_pdf(to_d(wo), to_d(wi), alpha);
      EXPECT_LE(rel_err(bsdf_pdf(m, wo, wi), pref), 1e-3) << "roughness " << roughness;
      worst_p = std::max(worst_p, rel_err(bsdf_pdf(m, wo, wi), pref));
    }
  }
  std::printf("[ measured ] GGX eval vs double reference: worst rel %.1e; pdf: %.1e\n", worst_f, worst_p);
}

TEST(BsdfDiffuse, EvalAndPdf) {
  const Material m = diffuse(Spectrum(0.8f, 0.5f, 0.2f));
  const vec3 wo = spherical(0.4, 1.0), wi = spherical(1.1, -2.0);
  const Spectrum f = bsdf_eval(m, wo, wi);
  EXPECT_NEAR(f.x, 0.8 / kPi, 1e-7);
  EXPECT_NEAR(f.z, 0.2 / kPi, 1e-7);
  EXPECT_NEAR(bsdf_pdf(m, wo, wi), std::cos(1.1) / kPi, 1e-6);
  EXPECT_FALSE(is_delta(m));
}

TEST(BsdfReciprocity, DiffuseAndConductor) {
  Rng rng(99);
  double worst = 0.0;
  std::vector<Material> mats = non_delta_materials();
  mats.push_back(conductor(Spectrum(0.3f, 0.6f, 0.9f), 0.05f));
  for (const Material& m : mats) {
    for (int k = 0; k < 2000; ++k) {
      const vec3 a = spherical(std::acos(std::max(1e-3f, rng.uniform())), kTwoPi * rng.uniform());
      const vec3 b = spherical(std::acos(std::max(1e-3f, rng.uniform())), kTwoPi * rng.uniform());
      const Spectrum fab = bsdf_eval(m, a, b), fba = bsdf_eval(m, b, a);
      for (int c = 0; c < 3; ++c) {
        // The two evaluations differ only in rounding (wo·h vs wi·h in the Fresnel term).
        EXPECT_LE(rel_err(fab[c], fba[c]), 1e-5) << "roughness " << m.roughness;
        worst = std::max(worst, rel_err(fab[c], fba[c]));
      }
    }
  }
  std::printf("[ measured ] reciprocity: worst rel %.1e\n", worst);
}

// ---- Energy ------------------------------------------------------------------------------------

TEST(BsdfEnergy, WhiteDiffuseHasAlbedoOne) {
  const Material m = diffuse(Spectrum(1.0f));
  for (const vec3& wo : test_wos()) {
    double albedo, pdf_integral;
    integrate(m, wo, 32, albedo, pdf_integral);
    // (albedo/π) cos θ is smooth: 3-point Gauss–Legendre on 32² cells is exact but for 1/π
    // rounded to float (4e-8).
    EXPECT_NEAR(albedo, 1.0, 1e-6);
    EXPECT_NEAR(pdf_integral, 1.0, 1e-6);
    for (float u : {0.0f, 0.3f, 0.99999994f}) {
      BsdfSample s;
      ASSERT_TRUE(bsdf_sample(m, wo, 0.5f, u, 0.25f, s));
      EXPECT_EQ(s.weight, Spectrum(1.0f));
    }
  }
}

// Two checks. Exact, for every roughness and wo: a white conductor's sample weight is
// F G2 / G1(wo) ≤ 1, and E[weight] is the albedo (BsdfSampling), so the albedo is at most 1. By
// quadrature (128² cells), where float directions resolve the lobe: ≤ 1 + 5e-4 (the quadrature's
// error here is below 2e-4: largest at roughness 1 and θo = 89.9°), and above 0.9 at roughness 0.1
// near normal incidence. (Roughness 0.002 at 89.9° is a lobe ~1e-8 rad thin, finer than the float
// directions that bsdf_eval takes: no quadrature with them can integrate it.)
TEST(BsdfEnergy, WhiteConductorNeverGains) {
  Rng rng(11);
  float max_weight = 0.0f;
  for (float roughness : {0.0f, 0.001f, 0.002f, 0.01f, 0.03f, 0.1f, 0.3f, 0.7f, 1.0f}) {
    const Material m = conductor(Spectrum(1.0f), roughness);
    for (double deg : {0.0, 20.0, 45.0, 70.0, 85.0, 89.0, 89.9, 89.99}) {
      const vec3 wo = spherical(deg * kPi / 180.0, 0.3);
      for (int k = 0; k < 1000; ++k) {
        BsdfSample s;
        if (!bsdf_sample(m, wo, rng.uniform(), rng.uniform(), rng.uniform(), s)) continue;
        max_weight = std::max({max_weight, s.weight.x, s.weight.y, s.weight.z});
      }
    }
  }
  EXPECT_LE(max_weight, 1.0f + 1e-6f);  // float rounding of the ratio G2 / G1

  double max_albedo = 0.0, min_near_normal = 2.0;
  for (float roughness : {0.03f, 0.1f, 0.2f, 0.3f, 0.5f, 0.7f, 0.85f, 1.0f}) {
    const Material m = conductor(Spectrum(1.0f), roughness);
    for (double deg : {0.0, 10.0, 20.0, 45.0, 70.0, 85.0, 89.0, 89.9}) {
      if (deg > 80.0 && roughness < 0.2f) continue;  // too thin for 128² cells
      const vec3 wo = spherical(deg * kPi / 180.0, 0.3);
      double albedo, pdf_integral;
      integrate(m, wo, 128, albedo, pdf_integral);
      EXPECT_LE(albedo, 1.0 + 5e-4) << "roughness " << roughness << " θo " << deg;
      max_albedo = std::max(max_albedo, albedo);
      if (roughness == 0.1f && deg <= 20.0) {
        EXPECT_GT(albedo, 0.9) << "θo " << deg;
        min_near_normal = std::min(min_near_normal, albedo);
      }
    }
  }
  std::printf(
      "[ measured ] white conductor: max sample weight %.7f; max albedo %.6f; at roughness 0.1, θo ≤ 20°: "
      "min albedo %.6f\n",
      max_weight, max_albedo, min_near_normal);
}

// ---- Mirror ------------------------------------------------------------------------------------

TEST(BsdfConductor, MirrorReflectsWithSchlickWeight) {
  Rng rng(3);
  const Spectrum f0(0.9f, 0.5f, 0.04f);
  for (float roughness : {0.0f, 5e-4f}) {
    const Material m = conductor(f0, roughness);
    EXPECT_TRUE(is_delta(m));
    for (int k = 0; k < 500; ++k) {
      const vec3 wo = spherical(std::acos(std::max(1e-4f, rng.uniform())), kTwoPi * rng.uniform());
      BsdfSample s;
      ASSERT_TRUE(bsdf_sample(m, wo, rng.uniform(), rng.uniform(), rng.uniform(), s));
      const dvec3 r = 2.0 * double(wo.z) * dvec3(0, 0, 1) - to_d(wo);  // reflect about the normal
      EXPECT_LT(glm::length(to_d(s.wi) - r), 1e-6);
      EXPECT_TRUE(s.delta);
      EXPECT_EQ(s.pdf, 1.0f);
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(s.weight[c], ref_schlick(f0[c], wo.z), 1e-6);
      EXPECT_EQ(bsdf_eval(m, wo, s.wi), Spectrum(0.0f));
      EXPECT_EQ(bsdf_pdf(m, wo, s.wi), 0.0f);
    }
  }
  EXPECT_FALSE(is_delta(conductor(f0, 0.01f)));
}

// ---- Dielectric --------------------------------------------------------------------------------

// Viewer outside (wo_z > 0, index 1) or inside (wo_z < 0, index ior).
struct Sides {
  double eta_o, eta_t;
};
Sides sides(const Material& m, const vec3& wo) { return wo.z > 0 ? Sides{1.0, m.ior} : Sides{m.ior, 1.0}; }

TEST(BsdfDielectric, RefractionObeysSnell) {
  double worst_snell = 0.0;
  for (float ior : {1.5f, 1.33f, 2.4f, 0.75f}) {
    const Material m = dielectric(ior);
    EXPECT_TRUE(is_delta(m));
    for (double deg : {0.0, 10.0, 25.0, 40.0, 60.0, 80.0, 89.5}) {
      for (double side : {1.0, -1.0}) {
        vec3 wo = spherical(deg * kPi / 180.0, 2.2);
        wo.z *= float(side);
        const Sides s = sides(m, wo);
        const double sin_o = std::sqrt(double(wo.x) * wo.x + double(wo.y) * wo.y);
        if (s.eta_o / s.eta_t * sin_o >= 0.999) continue;  // total internal reflection (or nearly)
        BsdfSample bs;
        ASSERT_TRUE(bsdf_sample(m, wo, 0.99999994f, 0.5f, 0.5f, bs)) << "ior " << ior << " θ " << deg;
        ASSERT_LT(double(wo.z) * bs.wi.z, 0.0) << "refraction goes to the other side";
        const double sin_i = std::sqrt(double(bs.wi.x) * bs.wi.x + double(bs.wi.y) * bs.wi.y);
        EXPECT_NEAR(glm::length(to_d(bs.wi)), 1.0, 1e-6);
        EXPECT_NEAR(s.eta_o * sin_o, s.eta_t * sin_i, 1e-6) << "ior " << ior << " θ " << deg << " side " << side;
        worst_snell = std::max(worst_snell, std::abs(s.eta_o * sin_o - s.eta_t * sin_i));
        // In the plane of incidence, on the opposite side of the normal.
        EXPECT_NEAR(double(wo.x) * bs.wi.y - double(wo.y) * bs.wi.x, 0.0, 1e-6);
        EXPECT_LE(double(wo.x) * bs.wi.x + double(wo.y) * bs.wi.y, 1e-7);
        // Weight: radiance scaled by (η_o/η_t)², the choice probability 1 − F cancels (1 − F)'s throughput.
        EXPECT_NEAR(bs.weight.x, std::pow(s.eta_o / s.eta_t, 2.0), 1e-5);
        EXPECT_NEAR(bs.pdf, 1.0 - ref_fresnel(std::abs(wo.z), s.eta_o, s.eta_t), 1e-5);
        EXPECT_TRUE(bs.delta);
        EXPECT_EQ(bsdf_eval(m, wo, bs.wi), Spectrum(0.0f));
        EXPECT_EQ(bsdf_pdf(m, wo, bs.wi), 0.0f);
      }
    }
  }
  std::printf("[ measured ] Snell: worst |η_o sin θo − η_t sin θt| %.1e\n", worst_snell);
}

TEST(BsdfDielectric, ReflectionFrequencyIsFresnel) {
  constexpr int kSamples = 20000;
  Rng rng(2024);
  double worst_sigma = 0.0;
  for (float ior : {1.5f, 2.4f}) {
    const Material m = dielectric(ior);
    for (double deg : {0.0, 30.0, 56.3, 75.0, 88.0}) {
      for (double side : {1.0, -1.0}) {
        vec3 wo = spherical(deg * kPi / 180.0, -0.4);
        wo.z *= float(side);
        const Sides s = sides(m, wo);
        const double fr = ref_fresnel(std::abs(wo.z), s.eta_o, s.eta_t);
        int reflected = 0;
        for (int k = 0; k < kSamples; ++k) {
          BsdfSample bs;
          ASSERT_TRUE(bsdf_sample(m, wo, rng.uniform(), rng.uniform(), rng.uniform(), bs));
          if (double(bs.wi.z) * wo.z > 0.0) {
            ++reflected;
            EXPECT_LT(glm::length(to_d(bs.wi) - dvec3(-wo.x, -wo.y, wo.z)), 1e-7);
            EXPECT_NEAR(bs.pdf, fr, 1e-5);
            EXPECT_EQ(bs.weight, Spectrum(1.0f));  // throughput F over probability F
          }
        }
        const double freq = double(reflected) / kSamples;
        // Binomial: 5 standard deviations (plus a floor for F = 0 or 1, where the count is exact).
        const double sigma = std::sqrt(fr * (1.0 - fr) / kSamples);
        EXPECT_NEAR(freq, fr, 5.0 * sigma + 1e-9) << "ior " << ior << " θ " << deg << " side " << side;
        if (sigma > 0.0) worst_sigma = std::max(worst_sigma, std::abs(freq - fr) / sigma);
      }
    }
  }
  // Normal incidence on glass: ((n − 1)/(n + 1))² = 0.04.
  BsdfSample bs;
  ASSERT_TRUE(bsdf_sample(dielectric(1.5f), vec3(0, 0, 1), 0.0f, 0.0f, 0.0f, bs));
  EXPECT_NEAR(bs.pdf, 0.04, 1e-6);
  std::printf("[ measured ] dielectric reflection frequency vs F: worst %.2f sigma\n", worst_sigma);
}

TEST(BsdfDielectric, TotalInternalReflection) {
  const Material m = dielectric(1.5f);
  const double critical = std::asin(1.0 / 1.5);
  for (double theta = critical + 1e-3; theta < 0.5 * kPi; theta += 0.01) {
    vec3 wo = spherical(theta, 0.9);
    wo.z = -wo.z;  // inside
    for (float u0 : {0.0f, 0.5f, 0.99999994f}) {
      BsdfSample bs;
      ASSERT_TRUE(bsdf_sample(m, wo, u0, 0.3f, 0.6f, bs)) << "θ " << theta;
      EXPECT_LT(glm::length(to_d(bs.wi) - dvec3(-wo.x, -wo.y, wo.z)), 1e-7);
      EXPECT_EQ(bs.pdf, 1.0f);
      EXPECT_EQ(bs.weight, Spectrum(1.0f));
      EXPECT_TRUE(bs.delta);
    }
  }
  // Just inside the critical angle light still gets out.
  vec3 wo = spherical(critical - 0.01, 0.9);
  wo.z = -wo.z;
  BsdfSample bs;
  ASSERT_TRUE(bsdf_sample(m, wo, 0.99999994f, 0.3f, 0.6f, bs));
  EXPECT_GT(bs.wi.z, 0.0f);
}

// ---- Degenerate input --------------------------------------------------------------------------

using test::all_finite;

TEST(BsdfDegenerate, BelowOrTangentGivesZeroAndNoNan) {
  std::vector<Material> mats = non_delta_materials();
  mats.push_back(conductor(Spectrum(0.9f), 0.0f));
  mats.push_back(conductor(Spectrum(0.9f), 0.001f));
  Material lamp;
  lamp.kind = MaterialKind::kEmissive;
  lamp.emission = Spectrum(5.0f);
  mats.push_back(lamp);
  for (float ior : {1.0f, 1.5f, 0.5f, 10.0f, 0.0f}) mats.push_back(dielectric(ior));
  const float us[] = {0.0f, 0.5f, 0.99999994f};
  int checked = 0;
  for (const Material& m : mats) {
    for (float z : {1.0f, 0.5f, 1e-3f, 1e-7f, 1e-30f, 0.0f, -0.0f, -1e-30f, -1e-7f, -0.5f, -1.0f}) {
      const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
      const vec3 wo(r * 0.6f, r * 0.8f, z);
      const bool opaque = m.kind != MaterialKind::kDielectric;
      for (float zi : {0.7f, 1e-7f, 0.0f, -0.7f}) {
        const float ri = std::sqrt(1.0f - zi * zi);
        const vec3 wi(-ri, 0.0f, zi);
        const Spectrum f = bsdf_eval(m, wo, wi);
        const float p = bsdf_pdf(m, wo, wi);
        EXPECT_TRUE(all_finite(f) && std::isfinite(p));
        if (!(z > 0.0f) || !(zi > 0.0f) || is_delta(m)) {
          EXPECT_EQ(f, Spectrum(0.0f)) << "kind " << int(m.kind) << " wo_z " << z << " wi_z " << zi;
          EXPECT_EQ(p, 0.0f);
        }
      }
      for (float u0 : us)
        for (float u1 : us)
          for (float u2 : us) {
            BsdfSample s;
            const bool ok = bsdf_sample(m, wo, u0, u1, u2, s);
            ++checked;
            EXPECT_TRUE(all_finite(s.wi) && all_finite(s.weight) && std::isfinite(s.pdf));
            if (opaque && !(z > 0.0f)) {
              EXPECT_FALSE(ok) << "kind " << int(m.kind) << " wo_z " << z;
            }
            if (m.kind == MaterialKind::kEmissive || z == 0.0f) {
              EXPECT_FALSE(ok);
            }
            if (ok) {
              EXPECT_NEAR(glm::length(s.wi), 1.0f, 1e-5f);
              EXPECT_GT(s.pdf, 0.0f);
              EXPECT_GE(s.weight.x, 0.0f);
              EXPECT_NE(s.wi.z, 0.0f);
              if (opaque) {
                EXPECT_GT(s.wi.z, 0.0f);
              }
            }
          }
    }
  }
  EXPECT_FALSE(is_delta(lamp));
  EXPECT_GT(checked, 1000);
}

// ---- Frame -------------------------------------------------------------------------------------

TEST(BsdfFrame, OrthonormalIncludingPoles) {
  // The poles, the equator (with z = +0 and z = −0, which picks the other branch) and near-poles.
  std::vector<vec3> normals = {{0, 0, 1},  {0, 0, -1},    {1, 0, 0},     {0, 1, 0},           {-1, 0, 0},
                               {0, -1, 0}, {1, 0, -0.0f}, {0, 1, -0.0f}, {0.6f, -0.8f, -0.0f}};
  for (float e : {1e-8f, 1e-6f, 1e-4f, 1e-2f})
    for (float sz : {1.0f, -1.0f}) {
      normals.push_back(glm::normalize(vec3(e, -0.5f * e, sz)));
      normals.push_back(glm::normalize(vec3(-e, e, sz)));
    }
  Rng rng(5);
  for (int k = 0; k < 2000; ++k) {
    const double z = 2.0 * rng.uniform() - 1.0;
    normals.push_back(spherical(std::acos(z), kTwoPi * rng.uniform()));
  }
  double worst = 0.0;
  for (const vec3& n : normals) {
    const Frame f = Frame::from_normal(n);
    const dvec3 t = to_d(f.t), b = to_d(f.b), nn = to_d(f.n);
    const double errs[] = {std::abs(glm::length(t) - 1.0), std::abs(glm::length(b) - 1.0),
                           std::abs(glm::dot(t, b)),       std::abs(glm::dot(t, nn)),
                           std::abs(glm::dot(b, nn)),      glm::length(glm::cross(t, b) - nn),
                           glm::length(nn - to_d(n))};
    for (double e : errs) {
      EXPECT_LT(e, 1e-6) << "n = (" << n.x << ", " << n.y << ", " << n.z << ")";
      worst = std::max(worst, e);
    }
    const vec3 v = glm::normalize(vec3(0.3f, -0.7f, 0.2f));
    EXPECT_LT(glm::length(f.to_world(f.to_local(v)) - v), 1e-6f);
    EXPECT_NEAR(f.to_local(n).z, 1.0f, 1e-6f);
  }
  std::printf("[ measured ] frame: worst orthonormality error %.1e over %zu normals\n", worst, normals.size());
}

}  // namespace
}  // namespace gwnrt::render
