// `cellray rays`: deterministic ray sets of four kinds for benchmarks and
// conformance. Secondary kinds start at primary hits found by the fp64
// reference, offset robustly (scene/surface.h).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "kernels/types.h"
#include "host/reference/reference.h"
#include "host/scene/scene.h"

namespace cr {

enum class RayKind { Primary, Shadow, Diffuse, Random };
RayKind ParseRayKind(const std::string& s);  // InputError on unknown names
const char* RayKindName(RayKind k);

struct RayGenOptions {
  RayKind kind = RayKind::Primary;
  int width = 0, height = 0;  // 0: the scene camera's resolution
  bool spdCorners = false;    // (width+1) x (height+1) pixel-corner rays
  std::uint64_t seed = 1;
  std::uint64_t count = 0;    // secondary/random: number of rays (0: width * height)
};

// Primary: one ray per pixel centre (or corner), row-major from the top-left.
// Shadow: from primary hits to each light the shading normal faces.
// Diffuse: one cosine-distributed ray per primary hit about the geometric
// normal on the viewer's side. Random: origins uniform in the scene box,
// directions uniform on the sphere. Secondary kinds loop over jittered
// primary passes until `count` rays exist (at most 64 passes).
std::vector<RayRecord> GenerateRays(const Scene& scene, const ref::ReferenceTracer& tracer, const RayGenOptions& opt);

// Counter-based random numbers: the same (seed, stream, index) always gives
// the same value, whatever the thread schedule.
std::uint64_t HashRandom(std::uint64_t seed, std::uint64_t stream, std::uint64_t index);
inline double ToUnit(std::uint64_t x) { return double(x >> 11) * 0x1p-53; }

}  // namespace cr
