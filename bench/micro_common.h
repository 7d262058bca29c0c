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

// The shapes of the intersector benchmarks (bench/micro_intersect.inc).
inline constexpr int kRays = 1024;

inline const Sphere kSphere{{0.0f, 0.0f, 0.0f}, 1.0f};
inline const Triangle kTriangle{{-1.0f, -1.0f, 0.0f}, CR_TRI_REPORT_UV, {1.0f, -1.0f, 0.0f}, 0u, {0.0f, 1.0f, 0.0f}, 0u};
inline const Cone kCone{{0.0f, 0.0f, -1.0f}, 1.0f, {0.0f, 0.0f, 1.0f}, 0.5f};
inline const float kBoxLo[3] = {-1.0f, -1.0f, -1.0f}, kBoxHi[3] = {1.0f, 1.0f, 1.0f};

enum class Shape { Sphere, Triangle, Cone, Box };


// The middle ray and its exact distance: from (-5, 0, 0) along +x for the
// cone (radius 0.75 at z = 0), from (0, 0, -5) along +z otherwise.
inline RayRecord MiddleRay(Shape shape, double& tExpected)
{
  if (shape == Shape::Cone) {
    tExpected = 4.25;
    return RayRecord{{-5.0f, 0.0f, 0.0f}, 0.0f, {1.0f, 0.0f, 0.0f}, INFINITY};
  }
  tExpected = shape == Shape::Triangle ? 5.0 : 4.0;
  return RayRecord{{0.0f, 0.0f, -5.0f}, 0.0f, {0.0f, 0.0f, 1.0f}, INFINITY};
}

// Hits of the fp64 mode on `rays` (micro_intersect_fp64.cpp): the count each
// mode is validated against.
int MicroFp64Hits(Shape shape, const std::vector<RayRecord>& rays);

}  // namespace cr::micro
