// Materials of the path tracer: Lambertian, Schlick/GGX conductor, smooth dielectric.
//
// Conventions (see bsdf.h): everything is in the local shading frame, z the surface normal, wo
// toward the viewer, wi toward the light, both unit. Of the three uniform numbers given to
// bsdf_sample, u0 chooses a lobe (the dielectric's reflection or refraction) and (u1, u2) draw the
// direction (cosine-weighted hemisphere, visible GGX normals).
//
// Rough conductor (GGX, α = roughness²), with the height-correlated Smith masking-shadowing
//   Λ(w)  = (√(1 + α² tan²θ) − 1) / 2,   G1(w) = 1 / (1 + Λ(w)),
//   G2    = 1 / (1 + Λ(wo) + Λ(wi)),
//   D(m)  = α² / (π (m_x² + m_y² + α² m_z²)²)            (m unit, m_z > 0),
//   f     = F(wo·m) D(m) G2 / (4 |wo_z| |wi_z|),           m = normalize(wo + wi),
//   pdf   = D_wo(m) / (4 |wo·m|) = G1(wo) D(m) / (4 wo_z)  (visible normals),
//   weight = f wi_z / pdf = F(wo·m) G2 / G1(wo).
// With R(w) = √(w_z² + α² (w_x² + w_y²)) these become, free of tan θ and of divisions by a
// vanishing cosine,
//   G1(w) = 2 w_z / (w_z + R(w)),   f = F D / (2 (R(wo) wi_z + R(wi) wo_z)),
//   pdf = D / (2 (wo_z + R(wo))),    weight = F wi_z (wo_z + R(wo)) / (R(wo) wi_z + R(wi) wo_z).
//
// The visible-normal sampler reflects wo about a normal m drawn from D_wo; a direction that lands
// below the horizon is rejected (bsdf_sample returns false). bsdf_pdf is the density of the
// directions that are produced, *not* renormalized: over the sphere it integrates to
// 1 − P(rejection) = ∫ D_wo(m) [reflect(wo, m)_z > 0] dm ≤ 1. A rejected sample counts as a
// zero-contribution sample, so E[weight · 1{accepted}] = ∫ f cos θi dωi exactly, and the same pdf
// is the right one for multiple importance sampling.
#include "render/bsdf.h"

#include <cmath>

namespace gwnrt::render {
namespace {

constexpr float kPiF = float(kPi);
// Below this roughness the conductor is a perfect mirror: α = roughness² < 1e-6 would make D a
// spike too narrow for float directions to resolve.
constexpr float kMirrorRoughness = 1e-3f;

float clamp01(float x) { return fminf(fmaxf(x, 0.0f), 1.0f); }

// Schlick's approximation, per channel, for a cosine in [0, 1].
Spectrum schlick(const Spectrum& f0, float cos_theta) {
  const float m = 1.0f - clamp01(cos_theta);
  const float m2 = m * m;
  const float m5 = m2 * m2 * m;
  return f0 + (Spectrum(1.0f) - f0) * m5;
}

// Exact Fresnel reflectance of unpolarized light for a smooth interface, the incident side of
// index eta_i and the other of eta_t, |cos θi| = cos_i. Total internal reflection gives 1.
// Also the cosine of the transmitted direction (0 under total internal reflection).
float fresnel_dielectric(float cos_i, float eta_i, float eta_t, float& cos_t) {
  cos_i = clamp01(cos_i);
  const float eta = eta_i / eta_t;
  const float sin2_t = eta * eta * fmaxf(0.0f, 1.0f - cos_i * cos_i);
  if (sin2_t >= 1.0f) {
    cos_t = 0.0f;
    return 1.0f;
  }
  cos_t = sqrtf(1.0f - sin2_t);
  // Both denominators are positive here: cos_i = cos_t = 0 needs sin2_t = 1 (handled above).
  const float rs = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
  const float rp = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t);
  return clamp01(0.5f * (rs * rs + rp * rp));
}

float ior_of(const Material& m) { return m.ior > 0.0f && is_finite(m.ior) ? m.ior : 1.0f; }

bool is_mirror(const Material& m) { return !(m.roughness >= kMirrorRoughness); }  // NaN: mirror

float ggx_alpha(const Material& m) { return m.roughness * m.roughness; }

// R(w) = √(w_z² + α² (w_x² + w_y²)) = w_z √(1 + α² tan²θ) for w_z > 0.
float ggx_r(const vec3& w, float a2) { return sqrtf(w.z * w.z + a2 * (w.x * w.x + w.y * w.y)); }

// GGX normal distribution for a unit m with m_z > 0.
float ggx_d(const vec3& m, float a2) {
  const float t = m.x * m.x + m.y * m.y + a2 * m.z * m.z;
  if (!(t > 0.0f)) return 0.0f;
  return a2 / (kPiF * t * t);
}

// f, pdf and weight of the rough conductor for wo_z, wi_z > 0 (zero otherwise).
struct GgxValue {
  Spectrum f{0.0f};
  float pdf = 0.0f;
  Spectrum weight{0.0f};
};

GgxValue ggx_eval(const Material& mat, const vec3& wo, const vec3& wi) {
  GgxValue v;
  if (!(wo.z > 0.0f) || !(wi.z > 0.0f)) return v;
  const float alpha = ggx_alpha(mat);
  const float a2 = alpha * alpha;
  const vec3 h = wo + wi;  // h_z > 0, so h is not zero
  const float len = glm::length(h);
  if (!(len > 0.0f)) return v;
  const vec3 m = h / len;
  const float d = ggx_d(m, a2);
  const float ro = ggx_r(wo, a2), ri = ggx_r(wi, a2);
  const float vis_den = ro * wi.z + ri * wo.z;  // > 0
  const float pdf_den = wo.z + ro;              // > 0
  if (!(d > 0.0f) || !(vis_den > 0.0f) || !is_finite(d)) return v;
  const Spectrum fr = schlick(mat.albedo, glm::dot(wo, m));
  v.f = fr * (d / (2.0f * vis_den));
  v.pdf = d / (2.0f * pdf_den);
  v.weight = fr * (wi.z * pdf_den / vis_den);  // G2 / G1(wo) ≤ 1 (R(wi) ≥ wi_z)
  return v;
}

// A visible normal of the GGX distribution seen from wo (wo_z > 0), by the construction of Heitz
// (2018): stretch wo to the configuration α = 1, where the visible normals are the projected area
// of a hemisphere seen from that direction, draw a point uniformly on that projection (a disk
// whose half hidden behind the hemisphere's edge is folded over with the linear blend `s`), lift
// it onto the hemisphere and unstretch the normal.
vec3 sample_ggx_visible_normal(const vec3& wo, float alpha, float u1, float u2) {
  const vec3 v = glm::normalize(vec3(alpha * wo.x, alpha * wo.y, wo.z));
  const float len2 = v.x * v.x + v.y * v.y;
  const vec3 t1 = len2 > 0.0f ? vec3(-v.y, v.x, 0.0f) / sqrtf(len2) : vec3(1.0f, 0.0f, 0.0f);
  const vec3 t2 = glm::cross(v, t1);
  // A uniform point on the unit disk, polar.
  const float r = sqrtf(clamp01(u1));
  const float phi = 2.0f * kPiF * u2;
  const float p1 = r * cosf(phi);
  float p2 = r * sinf(phi);
  const float s = 0.5f * (1.0f + v.z);
  p2 = (1.0f - s) * sqrtf(fmaxf(0.0f, 1.0f - p1 * p1)) + s * p2;
  const float p3 = sqrtf(fmaxf(0.0f, 1.0f - p1 * p1 - p2 * p2));
  const vec3 n = p1 * t1 + p2 * t2 + p3 * v;
  return glm::normalize(vec3(alpha * n.x, alpha * n.y, fmaxf(n.z, 0.0f)));
}

}  // namespace

bool is_delta(const Material& m) {
  switch (m.kind) {
    case MaterialKind::kConductor:
      return is_mirror(m);
    case MaterialKind::kDielectric:
      return true;
    default:
      return false;
  }
}

// Duff et al. (2017), "Building an orthonormal basis, revisited": t and b from n without a
// branch on |n_z| and without the precision loss at n_z = −1 (the sign flips the construction to
// the pole nearer n). Right-handed: t × b = n.
Frame Frame::from_normal(const vec3& n) {
  const float sign = copysignf(1.0f, n.z);
  const float a = -1.0f / (sign + n.z);
  const float c = n.x * n.y * a;
  Frame f;
  f.n = n;
  f.t = vec3(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
  f.b = vec3(c, sign + n.y * n.y * a, -n.y);
  return f;
}

Spectrum bsdf_eval(const Material& m, const vec3& wo, const vec3& wi) {
  switch (m.kind) {
    case MaterialKind::kDiffuse:
      if (!(wo.z > 0.0f) || !(wi.z > 0.0f)) return Spectrum(0.0f);
      return m.albedo * kInvPi;
    case MaterialKind::kConductor:
      if (is_mirror(m)) return Spectrum(0.0f);
      return ggx_eval(m, wo, wi).f;
    default:
      return Spectrum(0.0f);  // dielectric (delta), emissive
  }
}

float bsdf_pdf(const Material& m, const vec3& wo, const vec3& wi) {
  switch (m.kind) {
    case MaterialKind::kDiffuse:
      if (!(wo.z > 0.0f) || !(wi.z > 0.0f)) return 0.0f;
      return wi.z * kInvPi;
    case MaterialKind::kConductor:
      if (is_mirror(m)) return 0.0f;
      return ggx_eval(m, wo, wi).pdf;
    default:
      return 0.0f;
  }
}

bool bsdf_sample(const Material& m, const vec3& wo, float u0, float u1, float u2, BsdfSample& out) {
  out = BsdfSample{};
  switch (m.kind) {
    case MaterialKind::kDiffuse: {
      if (!(wo.z > 0.0f)) return false;
      // Cosine-weighted: a uniform point on the unit disk lifted onto the hemisphere.
      const float r2 = clamp01(u1);
      const float r = sqrtf(r2);
      const float phi = 2.0f * kPiF * u2;
      const float z = sqrtf(fmaxf(0.0f, 1.0f - r2));
      if (!(z > 0.0f)) return false;  // u1 = 1 (outside the documented range)
      out.wi = vec3(r * cosf(phi), r * sinf(phi), z);
      out.pdf = z * kInvPi;
      out.weight = m.albedo;  // (albedo/π) cos θ / (cos θ/π)
      return true;
    }
    case MaterialKind::kConductor: {
      if (!(wo.z > 0.0f)) return false;
      if (is_mirror(m)) {
        out.wi = vec3(-wo.x, -wo.y, wo.z);
        out.pdf = 1.0f;
        out.delta = true;
        out.weight = schlick(m.albedo, wo.z);
        return true;
      }
      const vec3 n = sample_ggx_visible_normal(wo, ggx_alpha(m), u1, u2);
      const vec3 wi = 2.0f * glm::dot(wo, n) * n - wo;
      if (!(wi.z > 0.0f)) return false;
      // pdf and weight from wo and wi alone, so that they equal bsdf_pdf and eval·cos/pdf.
      const GgxValue v = ggx_eval(m, wo, glm::normalize(wi));
      if (!(v.pdf > 0.0f)) return false;
      out.wi = glm::normalize(wi);
      out.pdf = v.pdf;
      out.weight = v.weight;
      return true;
    }
    case MaterialKind::kDielectric: {
      // z is the outward normal: wo_z > 0, the viewer outside (index 1); wo_z < 0, inside
      // (index ior). A viewer exactly in the tangent plane sees nothing.
      if (!(wo.z != 0.0f) || !is_finite(wo.z)) return false;
      const bool outside = wo.z > 0.0f;
      const float ior = ior_of(m);
      const float eta_o = outside ? 1.0f : ior;  // the viewer's side
      const float eta_t = outside ? ior : 1.0f;  // the other side
      const float cos_o = fabsf(wo.z);
      float cos_t = 0.0f;
      const float fr = fresnel_dielectric(cos_o, eta_o, eta_t, cos_t);
      out.delta = true;
      if (u0 < fr) {
        // Reflection: throughput F, chosen with probability F.
        out.wi = vec3(-wo.x, -wo.y, wo.z);
        out.pdf = fr;
        out.weight = Spectrum(1.0f);
        return true;
      }
      // Refraction (fr < 1 here, so cos_t > 0 unless cos_o is tiny enough to round it away):
      // Snell's law η_o sin θo = η_t sin θt, tangential part opposite to wo's, wi on the other side.
      // Radiance convention (paths traced from the camera): radiance crossing from the light's
      // side (η_t) to the viewer's (η_o) is scaled by (η_o / η_t)², i.e. 1/η² with η = η_t/η_o
      // (1/ior² looking into glass from outside, ior² looking out from inside). The throughput
      // (1 − F)(η_o/η_t)², chosen with probability 1 − F, leaves the weight (η_o/η_t)².
      // (Adjoint/importance transport, tracing from lights, would omit this factor.)
      const float eta = eta_o / eta_t;
      vec3 wi(-eta * wo.x, -eta * wo.y, outside ? -cos_t : cos_t);
      const float len = glm::length(wi);
      if (!(len > 0.0f) || wi.z == 0.0f) return false;
      out.wi = wi / len;
      out.pdf = 1.0f - fr;
      out.weight = Spectrum(eta * eta);
      return true;
    }
    default:
      return false;  // emissive: reflects nothing
  }
}

}  // namespace gwnrt::render
