// The two-level grid's kernels of one ISA: every type set x precision x
// statistics, one ray at a time (simd/grid2_single.h), which also serves as
// its packet kernel until it has a packet walk. Compiled once per ISA
// (simd/CMakeLists.txt).
#include "simd/grid2_single.h"

namespace cr::simd::CR_SIMD_NS {

PacketOrder Grid2PacketOrder() { return PacketOrder::Input; }

KernelFn SelectGrid2Kernel(const KernelKey& key)
{
  constexpr int N = CR_SIMD_WIDTH;
  return SelectKernel(key, [&](auto types, auto flags) -> KernelFn {
    constexpr unsigned kTypes = decltype(types)::kValue;
    constexpr bool kFast = decltype(flags)::kFastValue, kStats = decltype(flags)::kStatsValue;
    return &Grid2Single_TraceRange<N, kTypes, kFast, kStats>;
  });
}

}  // namespace cr::simd::CR_SIMD_NS
