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

enum class RayKind { Primary, Shadow, Diffuse, Random, Soft, Path };
RayKind ParseRayKind(const std::string& s);  // InputError on unknown names
const char* RayKindName(RayKind k);
// Kinds traced as occlusion (any-hit) queries: shadow and soft.
inline bool IsOcclusionKind(RayKind k) { return k == RayKind::Shadow || k == RayKind::Soft; }

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
// normal on the viewer's side. Soft: soft-shadow rays of the distributed
// renderer, from primary hits to a point sampled on each area light the hit
// faces (a scene without area lights: on a sphere of radius 1% of the scene's
// diagonal around each point light, as render --area-lights makes them).
// Path: the rays of a path's second bounce, cosine-distributed from where a
// diffuse ray from a primary hit lands (the incoherent rays of the path
// tracer and of --diffuse's gather rays' successors). Random: origins uniform in the scene box,
// directions uniform on the sphere. Secondary kinds loop over jittered
// primary passes until `count` rays exist (at most 64 passes).
// A scene with motion (NFF `motion`) gives every primary sample a time,
// uniform in the shutter interval, which its secondary rays keep; they go to
// `times` (one per ray; left empty for a static scene, or when times is null:
// then every ray is at time 0).
std::vector<RayRecord> GenerateRays(const Scene& scene, const ref::ReferenceTracer& tracer, const RayGenOptions& opt,
                                    std::vector<float>* times = nullptr);

// Counter-based random numbers: the same (seed, stream, index) always gives
// the same value, whatever the thread schedule.
std::uint64_t HashRandom(std::uint64_t seed, std::uint64_t stream, std::uint64_t index);
inline double ToUnit(std::uint64_t x) { return double(x >> 11) * 0x1p-53; }

}  // namespace cr
