#include "host/render/bsdf.h"

#include <algorithm>
#include <cmath>

#include "host/render/sampling.h"

namespace cr {

namespace {

glm::dvec3 Reflect(const glm::dvec3& wo, const glm::dvec3& n) { return 2.0 * glm::dot(n, wo) * n - wo; }

}  // namespace

Bsdf MakeBsdf(const Material& m, const glm::dvec3& n, const glm::dvec3& outward)
{
  Bsdf b;
  b.n = n;
  b.outward = outward;
  b.diffuse = m.color * std::max(0.0f, m.kd);
  b.tint = m.color;
  b.ks = std::max(0.0f, m.ks);
  b.shine = m.shine;
  b.mirror = m.shine >= 1000.0f || m.shine <= 0.0f;
  b.transmit = std::max(0.0f, m.transmittance);
  b.ior = m.ior > 0.0f ? m.ior : 1.0;
  const double wD = Luminance(b.diffuse), wS = b.ks, wT = b.transmit;
  const double sum = wD + wS + wT;
  if (sum > 0.0) {
    b.pD = wD / sum;
    b.pS = wS / sum;
    b.pT = wT / sum;
  }
  return b;
}

glm::vec3 EvalBsdf(const Bsdf& b, const glm::dvec3& wo, const glm::dvec3& wi)
{
  const double cosI = glm::dot(b.n, wi), cosO = glm::dot(b.n, wo);
  if (!(cosI > 0.0) || !(cosO > 0.0)) return glm::vec3(0.0f);
  glm::vec3 f = b.diffuse * float(1.0 / kPi);
  if (b.ks > 0.0 && !b.mirror) {
    const double ca = glm::dot(Reflect(wo, b.n), wi);
    if (ca > 0.0) f += glm::vec3(float(b.ks * (b.shine + 2.0) / (2.0 * kPi) * std::pow(ca, b.shine)));
  }
  return f;
}

double PdfBsdf(const Bsdf& b, const glm::dvec3& wo, const glm::dvec3& wi)
{
  const double cosI = glm::dot(b.n, wi);
  if (!(cosI > 0.0) || !(glm::dot(b.n, wo) > 0.0)) return 0.0;
  double pdf = b.pD * cosI / kPi;
  if (b.pS > 0.0 && !b.mirror) {
    const double ca = glm::dot(Reflect(wo, b.n), wi);
    if (ca > 0.0) pdf += b.pS * (b.shine + 1.0) / (2.0 * kPi) * std::pow(ca, b.shine);
  }
  return pdf;
}

double FresnelDielectric(double cosi, double eta)
{
  const double sin2t = eta * eta * std::max(0.0, 1.0 - cosi * cosi);
  if (sin2t >= 1.0) return 1.0;
  const double cost = std::sqrt(1.0 - sin2t);
  const double rs = (eta * cosi - cost) / (eta * cosi + cost);
  const double rp = (cosi - eta * cost) / (cosi + eta * cost);
  return 0.5 * (rs * rs + rp * rp);
}

bool SampleBsdf(const Bsdf& b, const glm::dvec3& wo, double u0, double u1, double u2, BsdfSample& s)
{
  s = BsdfSample{};
  if (b.Black()) return false;
  if (u0 < b.pT) {
    // Glass: Fresnel decides between reflection and refraction (u1 reused).
    double cosi = glm::dot(wo, b.outward);
    glm::dvec3 n = b.outward;
    double eta = 1.0 / b.ior;  // entering: outside over inside
    if (cosi < 0.0) {
      cosi = -cosi;
      n = -n;
      eta = b.ior;
    }
    const double F = FresnelDielectric(cosi, eta);
    s.delta = true;
    const float w = float(b.transmit / b.pT);
    if (u1 < F) {
      s.wi = Reflect(wo, n);
      s.weight = glm::vec3(w);
    } else {
      const double cost = std::sqrt(std::max(0.0, 1.0 - eta * eta * (1.0 - cosi * cosi)));
      s.wi = glm::normalize(-eta * wo + (eta * cosi - cost) * n);
      s.weight = w * b.tint;
    }
    return true;
  }
  u0 -= b.pT;
  if (u0 < b.pS && b.mirror) {
    if (!(glm::dot(b.n, wo) > 0.0)) return false;
    s.wi = Reflect(wo, b.n);
    s.delta = true;
    s.weight = glm::vec3(float(b.ks / b.pS));
    return true;
  }
  if (u0 < b.pS)
    s.wi = PhongLobeDirection(glm::normalize(Reflect(wo, b.n)), b.shine, u1, u2);
  else
    s.wi = CosineDirection(b.n, u1, u2);
  s.pdf = PdfBsdf(b, wo, s.wi);
  if (!(s.pdf > 0.0)) return false;
  const glm::vec3 f = EvalBsdf(b, wo, s.wi);
  s.weight = f * float(glm::dot(b.n, s.wi) / s.pdf);
  return true;
}

}  // namespace cr
