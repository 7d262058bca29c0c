// Sampling helpers of the distributed integrators (host/render/): bases,
// cosine-weighted directions, stratum permutations and the power heuristic.
#pragma once

#include <cmath>
#include <cstdint>

#include <glm/glm.hpp>

namespace cr {

inline constexpr double kPi = 3.14159265358979323846;

// An orthonormal basis (a, b) completing unit w (Duff et al. 2017).
inline void OrthoBasis(const glm::dvec3& w, glm::dvec3& a, glm::dvec3& b)
{
  const double sign = std::copysign(1.0, w.z);
  const double p = -1.0 / (sign + w.z), q = w.x * w.y * p;
  a = glm::dvec3(1.0 + sign * w.x * w.x * p, sign * q, -sign * w.x);
  b = glm::dvec3(q, sign + w.y * w.y * p, -w.y);
}

// A direction about unit w with density cos(theta) / pi (Malley's method).
inline glm::dvec3 CosineDirection(const glm::dvec3& w, double s1, double s2)
{
  glm::dvec3 a, b;
  OrthoBasis(w, a, b);
  const double r = std::sqrt(s1), phi = 2.0 * kPi * s2;
  const double z = std::sqrt(std::max(0.0, 1.0 - s1));
  return r * std::cos(phi) * a + r * std::sin(phi) * b + z * w;
}

// A direction about unit w with density (n + 1) / (2 pi) cos^n(alpha).
inline glm::dvec3 PhongLobeDirection(const glm::dvec3& w, double n, double s1, double s2)
{
  glm::dvec3 a, b;
  OrthoBasis(w, a, b);
  const double c = std::pow(s1, 1.0 / (n + 1.0));
  const double s = std::sqrt(std::max(0.0, 1.0 - c * c)), phi = 2.0 * kPi * s2;
  return s * std::cos(phi) * a + s * std::sin(phi) * b + c * w;
}

// Kensler's hashed permutation of 0..n-1 ("Correlated Multi-Jittered
// Sampling", 2013): element i of the permutation numbered p.
inline std::uint32_t Permute(std::uint32_t i, std::uint32_t n, std::uint32_t p)
{
  std::uint32_t w = n - 1;
  w |= w >> 1;
  w |= w >> 2;
  w |= w >> 4;
  w |= w >> 8;
  w |= w >> 16;
  do {
    i ^= p;
    i *= 0xe170893d;
    i ^= p >> 16;
    i ^= (i & w) >> 4;
    i ^= p >> 8;
    i *= 0x0929eb3f;
    i ^= p >> 23;
    i ^= (i & w) >> 1;
    i *= 1 | p >> 27;
    i *= 0x6935fa69;
    i ^= (i & w) >> 11;
    i *= 0x74dcb303;
    i ^= (i & w) >> 2;
    i *= 0x9e501cc3;
    i ^= (i & w) >> 2;
    i *= 0xc860a3df;
    i &= w;
    i ^= i >> 5;
  } while (i >= n);
  return (i + p) % n;
}

inline double PowerHeuristic(double a, double b)
{
  if (std::isinf(a)) return 1.0;
  const double a2 = a * a, b2 = b * b;
  return a2 + b2 > 0.0 ? a2 / (a2 + b2) : 0.0;
}

inline float Luminance(const glm::vec3& c) { return (c.r + c.g + c.b) / 3.0f; }

}  // namespace cr
