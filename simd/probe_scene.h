// A scene for the probes of simd/simd_kernels.h (KernelProbes): the caller
// fills `scene`, then Finish() derives the types' rows and identity ids and
// points the KernelScene at them. Shared by tests/test_simd_intersect.cpp
// and bench/micro_simd.cpp.
#pragma once

#include <cstdint>
#include <memory>
#include <numeric>
#include <vector>

#include "host/scene/scene.h"
#include "simd/bvh_wide_builder.h"
#include "simd/simd_kernels.h"

namespace cr::simd {

struct ProbeScene {
  Scene scene;
  std::unique_ptr<SimdPrimData> rows;
  std::vector<std::uint32_t> ids;
  KernelScene sc;

  void Finish()
  {
    rows = std::make_unique<SimdPrimData>(scene);
    rows->Bind(sc);
    ids.resize(scene.NumUnified());
    std::iota(ids.begin(), ids.end(), 0u);
    sc.primIds = ids.data();
  }
};

}  // namespace cr::simd
