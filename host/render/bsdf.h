// The scattering of an NFF `f` material (colour, Kd, Ks, Phong exponent,
// transmittance T, index of refraction) as the distributed integrators use
// it (docs/RENDERING.md):
//   diffuse   Kd colour / pi (Lambert);
//   glossy    Ks (n + 2) / (2 pi) cos^n(alpha), alpha the angle between the
//             outgoing direction and the mirror direction (the normalised
//             Phong lobe, n the Phong exponent), when 0 < n < 1000;
//   mirror    a perfect mirror of weight Ks when n >= 1000 or n = 0;
//   glass     weight T: a dielectric of the given index, reflecting or
//             refracting by its exact Fresnel factor, the refracted share
//             tinted by the colour (as the Whitted renderer tints it).
// A sample picks one lobe with probability proportional to its weight
// (Kd times the colour's mean, Ks, T); the non-delta lobes' density is their
// mixture, so that multiple importance sampling sees one density.
#pragma once

#include <glm/glm.hpp>

#include "host/scene/scene.h"

namespace cr {

struct Bsdf {
  glm::dvec3 n{0.0};        // shading normal on the side the light leaves towards (wo)
  glm::dvec3 outward{0.0};  // outward geometric normal (glass: entering or leaving)
  glm::vec3 diffuse{0.0f};  // Kd colour
  glm::vec3 tint{1.0f};     // glass's refracted share
  double ks = 0.0, shine = 0.0, transmit = 0.0, ior = 1.0;
  bool mirror = false;
  double pD = 0.0, pS = 0.0, pT = 0.0;  // lobe probabilities
  bool Black() const { return pD + pS + pT <= 0.0; }
  bool HasSmooth() const { return pD > 0.0 || (pS > 0.0 && !mirror); }
};

Bsdf MakeBsdf(const Material& m, const glm::dvec3& n, const glm::dvec3& outward);
// The non-delta lobes: f(wo, wi) and the density of sampling wi (wo, wi
// unit, pointing away from the surface).
glm::vec3 EvalBsdf(const Bsdf& b, const glm::dvec3& wo, const glm::dvec3& wi);
double PdfBsdf(const Bsdf& b, const glm::dvec3& wo, const glm::dvec3& wi);

struct BsdfSample {
  glm::dvec3 wi{0.0};
  glm::vec3 weight{0.0f};  // f |cos| / pdf
  double pdf = 0.0;        // of the non-delta mixture (0 for a delta lobe)
  bool delta = false;
};
// u0 picks the lobe, (u1, u2) the direction; false: no direction (absorbed).
bool SampleBsdf(const Bsdf& b, const glm::dvec3& wo, double u0, double u1, double u2, BsdfSample& s);

// Fresnel reflectance of a dielectric interface for incidence cosine cosi
// (> 0) and eta = n_incident / n_transmitted; 1 at total internal reflection.
double FresnelDielectric(double cosi, double eta);

}  // namespace cr
