// The grid kernels of one ISA, packet and single-ray: every type set x
// precision x statistics. Compiled once per ISA (simd/CMakeLists.txt), with
// the ISA namespace and width of simd/vec.h.
#include "simd/grid_packet.h"
#include "simd/grid_single.h"

namespace cr::simd::CR_SIMD_NS {

// Direction classes pay on long walks (GridClassOrderPays).
PacketOrder GridPacketOrder() { return PacketOrder::DirectionClassesWhenPays; }

KernelFn SelectGridKernel(const KernelKey& key)
{
  constexpr int N = CR_SIMD_WIDTH;
  return SelectKernel(key, [&](auto types, auto flags) -> KernelFn {
    constexpr unsigned kTypes = decltype(types)::kValue;
    constexpr bool kFast = decltype(flags)::kFastValue, kStats = decltype(flags)::kStatsValue;
    if (key.packet) return &GridPacket_TraceRange<N, kTypes, kFast, kStats>;
    return &GridSingle_TraceRange<N, kTypes, kFast, kStats>;
  });
}

}  // namespace cr::simd::CR_SIMD_NS
