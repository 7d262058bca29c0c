// The octree kernels of one ISA, packet and single-ray: every type set x
// precision x statistics. Compiled once per ISA (simd/CMakeLists.txt), with
// the ISA namespace and width of simd/vec.h.
#include "simd/octree_packet.h"
#include "simd/octree_single.h"

namespace cr::simd::CR_SIMD_NS {

// A packet is traced once per class of direction signs among its lanes
// (octree_packet.h): packets of one class.
PacketOrder OctreePacketOrder() { return PacketOrder::DirectionClasses; }

KernelFn SelectOctreeKernel(const KernelKey& key)
{
  constexpr int N = CR_SIMD_WIDTH;
  return SelectKernel(key, [&](auto types, auto flags) -> KernelFn {
    constexpr unsigned kTypes = decltype(types)::kValue;
    constexpr bool kFast = decltype(flags)::kFastValue, kStats = decltype(flags)::kStatsValue;
    if (key.packet) return &OctreePacket_TraceRange<N, kTypes, kFast, kStats>;
    return &OctreeSingle_TraceRange<N, kTypes, kFast, kStats>;
  });
}

}  // namespace cr::simd::CR_SIMD_NS
