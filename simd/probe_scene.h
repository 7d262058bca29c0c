// A scene for the probes of simd/simd_kernels.h (KernelProbes): the caller
// fills `scene`, then Finish() derives the cone rows and identity ids and
// points the KernelScene at them. Shared by tests/test_simd_intersect.cpp
// and bench/micro_simd.cpp.
#pragma once

#include <cstdint>
#include <numeric>
#include <vector>

#include "host/scene/scene.h"
#include "simd/bvh_wide_builder.h"
#include "simd/simd_kernels.h"

namespace cr::simd {

struct ProbeScene {
  Scene scene;
  std::vector<ConeData> cones;
  std::vector<std::uint32_t> ids;
  KernelScene sc;

  void Finish()
  {
    cones = MakeConeData(scene);
    ids.resize(scene.NumUnified());
    std::iota(ids.begin(), ids.end(), 0u);
    sc.spheres = scene.spheres.data();
    sc.triangles = scene.triangles.data();
    sc.cones = cones.data();
    sc.coneGeometry = scene.cones.data();
    sc.ranges = scene.Ranges();
    sc.primIds = ids.data();
  }
};

}  // namespace cr::simd
