// How much marching a ray set costs on SDF blocks (kernels/sdf.h): the
// kernels count no steps (their statistics are per structure), so this
// replays, on the host and in float as the kernels run it, every march a
// ray needs: each block whose bound the ray's segment [tmin, end] meets,
// `end` being its reported hit (the ray's tmax for a miss or an occlusion
// query). `trace --stats` reports it for scenes with blocks.
#pragma once

#include <cstdint>
#include <vector>

#include "host/scene/scene.h"

namespace cr {

struct SdfMarchCount {
  std::uint64_t rays = 0, marches = 0, evals = 0;  // evals: distance evaluations (march steps)
};

SdfMarchCount CountSdfMarches(const Scene& scene, const std::vector<RayRecord>& rays,
                              const std::vector<HitRecord>& hits, bool occlusion, bool fast);

}  // namespace cr
