// The uniform and hierarchical grids' kernels of a moving scene
// (simd/motion.h): the type set kAllTypes | kMotionBit x precision x
// statistics, packet and single-ray. A unit of their own, so
// that the static scenes' units compile what they compiled before.
// Compiled once per ISA (simd/CMakeLists.txt).
#include "simd/grid_packet.h"
#include "simd/grid_single.h"
#include "simd/hgrid_packet.h"

namespace cr::simd::CR_SIMD_NS {

KernelFn SelectMotionGridKernel(const KernelKey& key)
{
  constexpr int N = CR_SIMD_WIDTH;
  return SelectMotionKernel(key, [&](auto types, auto flags) -> KernelFn {
    constexpr unsigned kTypes = decltype(types)::kValue;
    constexpr bool kFast = decltype(flags)::kFastValue, kStats = decltype(flags)::kStatsValue;
    if (key.packet) return &GridPacket_TraceRange<N, kTypes, kFast, kStats>;
    return &GridSingle_TraceRange<N, kTypes, kFast, kStats>;
  });
}

KernelFn SelectMotionHGridKernel(const KernelKey& key)
{
  constexpr int N = CR_SIMD_WIDTH;
  return SelectMotionKernel(key, [&](auto types, auto flags) -> KernelFn {
    constexpr unsigned kTypes = decltype(types)::kValue;
    constexpr bool kFast = decltype(flags)::kFastValue, kStats = decltype(flags)::kStatsValue;
    if (key.packet) return &HGridPacket_TraceRange<N, kTypes, kFast, kStats>;
    return &HGridSingle_TraceRange<N, kTypes, kFast, kStats>;
  });
}

}  // namespace cr::simd::CR_SIMD_NS
