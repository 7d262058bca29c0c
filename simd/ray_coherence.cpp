#include "simd/ray_coherence.h"

#include <span>
#include <cmath>

namespace cr::simd {

namespace {

int Octant(const float d[3]) { return (d[0] < 0.0f ? 1 : 0) | (d[1] < 0.0f ? 2 : 0) | (d[2] < 0.0f ? 4 : 0); }

bool Unit(const float d[3], double u[3])
{
  const double len = std::sqrt(double(d[0]) * d[0] + double(d[1]) * d[1] + double(d[2]) * d[2]);
  if (!(len > 0.0) || !std::isfinite(len)) return false;
  for (int a = 0; a < 3; ++a) u[a] = d[a] / len;
  return true;
}

}  // namespace

CoherenceSample SampleCoherence(std::span<const RayRecord> rays, int width, std::size_t maxGroups, double cosLimit)
{
  CoherenceSample s;
  const std::size_t nGroups = rays.size() / std::size_t(width);
  if (nGroups == 0) return s;
  const std::size_t step = nGroups > maxGroups ? nGroups / maxGroups : 1;
  for (std::size_t gi = 0; gi < nGroups; gi += step) {
    const RayRecord* r = rays.data() + gi * std::size_t(width);
    ++s.groups;
    double u0[3];
    if (!Unit(r[0].dir, u0)) continue;
    const int oct = Octant(r[0].dir);
    bool ok = true;
    for (int l = 1; l < width && ok; ++l) {
      double u[3];
      ok = Unit(r[l].dir, u) && Octant(r[l].dir) == oct && u[0] * u0[0] + u[1] * u0[1] + u[2] * u0[2] >= cosLimit;
    }
    s.coherent += ok ? 1 : 0;
  }
  return s;
}

}  // namespace cr::simd
