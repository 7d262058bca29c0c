#include "host/trace/direction_scale.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

#include <tbb/parallel_reduce.h>
#include <tbb/blocked_range.h>

namespace cr {

namespace {

// e with the direction's largest component in [2^e, 2^(e + 1)) when it lies
// outside the range, else 0 (also for a zero, infinite or NaN direction:
// traced as they are): d' = d 2^-e has its largest component in [1, 2).
// Bit operations only (the scan runs over every ray of every trace): the
// largest |component|'s bits are the largest as integers.
int ScaleExponent(const RayRecord& r)
{
  const auto absBits = [](float f) { return std::bit_cast<std::uint32_t>(f) & 0x7fffffffu; };
  const std::uint32_t m = std::max(absBits(r.dir[0]), std::max(absBits(r.dir[1]), absBits(r.dir[2])));
  const int biased = static_cast<int>(m >> 23);
  if (biased >= 127 - kDirectionScaleBits && biased <= 127 + kDirectionScaleBits) return 0;
  if (m == 0u || biased == 255) return 0;
  // Subnormal: the value is m 2^-149.
  return biased > 0 ? biased - 127 : (31 - std::countl_zero(m)) - 149;
}

}  // namespace

DirectionScale::DirectionScale(std::span<const RayRecord> rays) : rays_(rays)
{
  // Most sets have no such ray: one parallel scan, no copy.
  const bool any = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, rays.size(), 4096), false,
      [&](const tbb::blocked_range<std::size_t>& r, bool found) {
        for (std::size_t i = r.begin(); i < r.end() && !found; ++i) found = ScaleExponent(rays[i]) != 0;
        return found;
      },
      [](bool a, bool b) { return a || b; });
  if (!any) return;
  scaled_.assign(rays.begin(), rays.end());
  for (std::size_t i = 0; i < scaled_.size(); ++i) {
    const int e = ScaleExponent(scaled_[i]);
    if (e == 0) continue;
    RayRecord& r = scaled_[i];
    // d' = d 2^-e, and t' = t 2^e for the same points o + t d = o + t' d':
    // tmin and tmax too
    // (an overflow to inf or an underflow stands for a bound beyond the
    // float range either way).
    for (float& c : r.dir) c = std::ldexp(c, -e);
    r.tmin = std::ldexp(r.tmin, e);
    r.tmax = std::ldexp(r.tmax, e);
    which_.push_back(static_cast<std::uint32_t>(i));
    exponent_.push_back(static_cast<std::int16_t>(e));
  }
  rays_ = scaled_;
}

void DirectionScale::Unscale(std::vector<HitRecord>& hits, bool occlusion) const
{
  if (occlusion) return;
  for (std::size_t k = 0; k < which_.size(); ++k) {
    HitRecord& h = hits[which_[k]];
    if (h.prim != CR_NO_HIT) h.t = std::ldexp(h.t, -exponent_[k]);  // t = t' 2^-e
  }
}

}  // namespace cr
