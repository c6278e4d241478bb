// Materials of the path tracer and their BSDFs: evaluation, pdf and importance sampling, all in
// the local shading frame (z = the surface normal on the side the light arrives from; wo points
// toward the viewer, wi toward the light, both unit). Linear RGB throughout.
#pragma once

#include "gwnrt/base/hd.h"

namespace gwnrt::render {

using Spectrum = vec3;

enum class MaterialKind {
  kDiffuse,     // Lambertian: f = albedo / π
  kConductor,   // metal: Schlick Fresnel with F0 = albedo; roughness 0 a perfect mirror, else
                // GGX (α = roughness²) with Smith masking, sampled by visible normals
  kDielectric,  // smooth glass: Fresnel-weighted choice of reflection and refraction (ior).
                // Its z is the outward normal (wo_z < 0: the viewer inside); albedo is ignored.
  kEmissive,    // emits `emission` (radiance) from both sides, reflects nothing
};

struct Material {
  MaterialKind kind = MaterialKind::kDiffuse;
  Spectrum albedo{0.8f};
  float roughness = 0.0f;
  float ior = 1.5f;
  Spectrum emission{0.0f};
};

// True for materials whose sampled directions are single directions (mirror, smooth glass):
// light sampling cannot reach them and eval/pdf return 0.
bool is_delta(const Material& m);

// An orthonormal frame around a unit normal.
struct Frame {
  vec3 t, b, n;
  static Frame from_normal(const vec3& n);
  vec3 to_local(const vec3& v) const { return {glm::dot(v, t), glm::dot(v, b), glm::dot(v, n)}; }
  vec3 to_world(const vec3& v) const { return v.x * t + v.y * b + v.z * n; }
};

// f(wo, wi), without the cosine. Zero for delta materials and for wi below the surface (except
// dielectrics, which are delta anyway).
Spectrum bsdf_eval(const Material& m, const vec3& wo, const vec3& wi);

// The solid-angle density bsdf_sample draws wi with (0 for delta materials). For GGX it is not
// renormalized for the samples rejected below the horizon: it integrates to P(accepted) ≤ 1.
float bsdf_pdf(const Material& m, const vec3& wo, const vec3& wi);

struct BsdfSample {
  vec3 wi{0.0f};
  Spectrum weight{0.0f};  // f · |cos θi| / pdf (for delta lobes: the lobe's throughput over pdf;
                          // glass: 1 reflected, (η_viewer/η_light side)² refracted, radiance)
  float pdf = 0.0f;       // solid-angle density; for a delta lobe the probability of choosing it
  bool delta = false;
};

// Draws wi from three uniform numbers in [0, 1); false when no direction is produced (e.g. wo
// below the surface of an opaque material, or a GGX sample below it).
bool bsdf_sample(const Material& m, const vec3& wo, float u0, float u1, float u2, BsdfSample& out);

}  // namespace gwnrt::render
