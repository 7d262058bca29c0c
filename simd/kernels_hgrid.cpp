// The hierarchical grid's kernels of one ISA: every type set x precision x
// statistics, one ray at a time (simd/hgrid_single.h), which also serves as
// its packet kernel until it has a packet walk. Compiled once per ISA
// (simd/CMakeLists.txt).
#include "simd/hgrid_single.h"

namespace cr::simd::CR_SIMD_NS {

PacketOrder HGridPacketOrder() { return PacketOrder::Input; }

KernelFn SelectHGridKernel(const KernelKey& key)
{
  constexpr int N = CR_SIMD_WIDTH;
  return SelectKernel(key, [&](auto types, auto flags) -> KernelFn {
    constexpr unsigned kTypes = decltype(types)::kValue;
    constexpr bool kFast = decltype(flags)::kFastValue, kStats = decltype(flags)::kStatsValue;
    return &HGridSingle_TraceRange<N, kTypes, kFast, kStats>;
  });
}

}  // namespace cr::simd::CR_SIMD_NS
