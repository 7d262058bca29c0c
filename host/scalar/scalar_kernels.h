// The kernels of kernels/ compiled as C++: one namespace per precision mode
// (and a statistics-gathering twin of each), all with the same entry point.
// This is the `scalar` backend and the oracle the OpenCL build is checked
// against.
#pragma once

#include <cstddef>

#include "host/accel/accel.h"
#include "kernels/types.h"
#include "host/trace/tracer.h"

namespace cr {

struct KernelArgs {
  AccelKind accel = AccelKind::BVH;
  const AccelData* data = nullptr;
  PrimRanges ranges{};
#define CR_KERNEL_ARGS_ARRAY_(T, U, array) const T* array = nullptr;  // the scene's array of each type
  CR_PRIM_TYPES(CR_KERNEL_ARGS_ARRAY_)
#undef CR_KERNEL_ARGS_ARRAY_
  const std::uint32_t* primIds = nullptr;  // by unified index
  const RayRecord* rays = nullptr;
  const float* times = nullptr;   // per ray, or null: every ray at time 0
  const float* motion = nullptr;  // Scene::UnifiedMotion, or null: a static scene
  HitRecord* hits = nullptr;
  bool unifiedHits = false;  // TraceConfig::unifiedHits
};

// Per precision mode: TraceRange traces rays [begin, end); IntersectPiece
// tests unified piece g alone against one ray from a fresh hit
// (Prim_Intersect), 1 on a hit, with its t, u, v as the hit holds them (an
// any-hit query when anyHit: a hit certainly in range may keep its float t);
// IntersectBounds the slab test of a bounding box (Box_Intersect) over the
// ray's [tmin, tmax], with its entry. The last two are the unit tests'
// scalar oracle.
#define CR_DECLARE_KERNEL_NS(ns)                                                                              \
  namespace ns {                                                                                              \
  void TraceRange(const KernelArgs& args, std::size_t begin, std::size_t end, bool occlusion, TraceStatsSum* sum); \
  int IntersectPiece(const KernelArgs& args, std::uint32_t g, const RayRecord& ray, float* t, float* u, float* v, \
                     bool anyHit = false);                                                                     \
  int IntersectBounds(const float lo[3], const float hi[3], const RayRecord& ray, float* tEnter);             \
  }
CR_DECLARE_KERNEL_NS(k_robust)
CR_DECLARE_KERNEL_NS(k_robust_stats)
CR_DECLARE_KERNEL_NS(k_fast)
CR_DECLARE_KERNEL_NS(k_fast_stats)
CR_DECLARE_KERNEL_NS(k_fp64)
CR_DECLARE_KERNEL_NS(k_fp64_stats)
#undef CR_DECLARE_KERNEL_NS

}  // namespace cr
