// The hierarchical grid's kernels of one ISA: every type set x precision x
// statistics, N rays at once (simd/hgrid_packet.h) or one at a time
// (simd/hgrid_single.h). Compiled once per ISA (simd/CMakeLists.txt).
#include "simd/hgrid_packet.h"

namespace cr::simd::CR_SIMD_NS {

PacketOrder HGridPacketOrder() { return PacketOrder::DirectionClassesWhenPays; }

KernelFn SelectHGridKernel(const KernelKey& key)
{
  constexpr int N = CR_SIMD_WIDTH;
  return SelectKernel(key, [&](auto types, auto flags) -> KernelFn {
    constexpr unsigned kTypes = decltype(types)::kValue;
    constexpr bool kFast = decltype(flags)::kFastValue, kStats = decltype(flags)::kStatsValue;
    if (key.packet) return &HGridPacket_TraceRange<N, kTypes, kFast, kStats>;
    return &HGridSingle_TraceRange<N, kTypes, kFast, kStats>;
  });
}

}  // namespace cr::simd::CR_SIMD_NS
