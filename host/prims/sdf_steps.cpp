#include "host/prims/sdf_steps.h"

#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

namespace cr {
namespace sdf_fp32 {
#include "kernels/ray.h"
#include "kernels/sdf.h"
}  // namespace sdf_fp32

SdfMarchCount CountSdfMarches(const Scene& scene, const std::vector<RayRecord>& rays,
                              const std::vector<HitRecord>& hits, bool occlusion, bool fast)
{
  SdfMarchCount total;
  total.rays = rays.size();
  if (scene.sdfs.empty()) return total;
  tbb::combinable<SdfMarchCount> part;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), 256), [&](const tbb::blocked_range<std::size_t>& br) {
    SdfMarchCount& c = part.local();
    for (std::size_t i = br.begin(); i != br.end(); ++i) {
      const RayRecord& r = rays[i];
      float end = r.tmax;
      if (!occlusion && i < hits.size() && hits[i].prim != CR_NO_HIT) end = hits[i].t;
      for (const Sdf& s : scene.sdfs) {
        // The bound's slabs, as the march opens (its first evaluation is
        // inside the bound).
        float t0 = r.tmin, t1 = end;
        for (int a = 0; a < 3; ++a) {
          const float ta = (s.lo[a] - r.org[a]) / r.dir[a], tb = (s.hi[a] - r.org[a]) / r.dir[a];
          t0 = cr::fmax(t0, cr::fmin(ta, tb));
          t1 = cr::fmin(t1, cr::fmax(ta, tb));
        }
        if (!(t0 <= t1)) continue;
        float th = 0.0f;
        std::uint32_t evals = 0;
        sdf_fp32::Sdf_MarchCounted(r.org, r.dir, &s, r.tmin, end, fast ? 0 : CR_SDF_REFINE, &th, &evals);
        ++c.marches;
        c.evals += evals;
      }
    }
  });
  part.combine_each([&](const SdfMarchCount& c) {
    total.marches += c.marches;
    total.evals += c.evals;
  });
  return total;
}

}  // namespace cr
