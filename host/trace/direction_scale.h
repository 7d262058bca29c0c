// Rays whose direction is so short or so long that float products of it
// under- or overflow (|d|^2 of a direction of length 1e-30 is 0 in float:
// the quadratic of every sphere, cone and quadric test degenerates) are
// traced with the direction scaled by a power of two and their hits' t
// scaled back. A power of two scales every float operation of a test
// exactly (away from the float range's ends), so p = o + t d is the same
// point for the scaled ray d' = d 2^-e at t' = t 2^e, and t = t' 2^-e again;
// rays inside the range are traced as they are, bit for bit.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "kernels/types.h"

namespace cr {

// The direction's largest component is scaled into [1, 2) when it lies
// outside [2^-kDirectionScaleBits, 2^kDirectionScaleBits].
inline constexpr int kDirectionScaleBits = 32;

class DirectionScale {
 public:
  // Scans `rays`; when some need scaling, Rays() is a scaled copy, else the
  // rays themselves.
  explicit DirectionScale(std::span<const RayRecord> rays);
  std::span<const RayRecord> Rays() const { return rays_; }
  // Puts the t of every closest hit of a scaled ray back into the ray's
  // own parameter (occlusion answers carry t = 0 or +inf: unchanged).
  void Unscale(std::vector<HitRecord>& hits, bool occlusion) const;

 private:
  std::span<const RayRecord> rays_;
  std::vector<RayRecord> scaled_;
  std::vector<std::uint32_t> which_;  // the scaled rays' positions
  std::vector<std::int16_t> exponent_;  // their e: d' = d 2^-e, t = t' 2^-e
};

}  // namespace cr
