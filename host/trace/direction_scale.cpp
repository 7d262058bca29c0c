#include "host/trace/direction_scale.h"

#include <cmath>

#include <tbb/parallel_reduce.h>
#include <tbb/blocked_range.h>

namespace cr {

namespace {

// e with the direction's largest component in [2^e, 2^(e + 1)) when it lies
// outside the range, else 0: d' = d 2^-e has its largest component in
// [1, 2).
int ScaleExponent(const RayRecord& r)
{
  const float m = std::fmax(std::fabs(r.dir[0]), std::fmax(std::fabs(r.dir[1]), std::fabs(r.dir[2])));
  if (!(m > 0.0f) || !std::isfinite(m)) return 0;  // zero, NaN or infinite: as they are
  int e = 0;
  std::frexp(m, &e);  // m = f 2^e, f in [0.5, 1)
  const int lead = e - 1;  // m in [2^lead, 2^(lead + 1))
  return (lead < -kDirectionScaleBits || lead > kDirectionScaleBits) ? lead : 0;
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
