// Ray sets of a bench run: generated once per scene x kind and kept in the
// output directory (DIR/rays/), so that every configuration, and a later run,
// traces the identical .rays file. A set is reused only when its sidecar
// (.json: generator version, scene file size and time, kind, size, seed)
// matches what would be generated now; otherwise it is generated again.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "host/bench/bench_scenes.h"
#include "kernels/types.h"
#include "host/rays/raygen.h"
#include "host/reference/reference.h"

namespace cr::bench {

struct RaySetSpec {
  RayKind kind = RayKind::Primary;
  std::uint64_t count = 0;  // rays wanted (primary: about this many pixels)
  std::uint64_t seed = 1;
};

struct RaySet {
  std::vector<RayRecord> rays;
  std::vector<float> times;  // a scene with motion: one per ray (CRRAYS02), else empty
  std::string path;    // the cached .rays file
  int width = 0, height = 0;  // image of the primary pass
  bool fromCache = false;
  std::string why;  // empty set: why the generator made none (its error)
};

// Image size of about `count` pixels with the camera's aspect ratio.
void PrimaryImageSize(const Scene& scene, std::uint64_t count, int& width, int& height);

RaySet GetRaySet(const std::string& dir, const SceneRef& ref, const Scene& scene, const ref::ReferenceTracer& tracer,
                 const RaySetSpec& spec);

}  // namespace cr::bench
