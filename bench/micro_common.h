// Shared set-up of the micro benchmarks: generated scenes (no scene files
// needed), seeded ray sets, and the check that a tracer answers them
// correctly before it is timed.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "kernels/types.h"
#include "host/rays/raygen.h"
#include "host/reference/reference.h"
#include "host/scene/scene.h"
#include "host/trace/tracer.h"

namespace cr::micro {

// Scenes built once per process: "flake" (sphereflake depth 4, 7381 spheres
// and a ground quad) and "mesh" (a bumpy sphere of about 10^5 triangles).
const Scene& BenchScene(const std::string& name);
const ref::ReferenceTracer& BenchReference(const std::string& name);
// 2^14 rays of a kind (primary: 128 x 128), cached per scene and kind.
const std::vector<RayRecord>& BenchRays(const std::string& scene, RayKind kind);

// Seeded rays from a sphere of radius `dist` around the origin towards
// points in the box [-r, r]^3: about half hit a primitive of size r there.
std::vector<RayRecord> RaysAtOrigin(int n, float r, float dist, std::uint64_t seed);

}  // namespace cr::micro
