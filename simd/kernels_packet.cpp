// The packet kernels of one ISA: every type set x precision x statistics.
// Compiled once per ISA (simd/CMakeLists.txt), with the ISA namespace and
// width of simd/vec.h.
#include "simd/bvh_wide_packet.h"

namespace cr::simd::CR_SIMD_NS {

KernelFn SelectPacketKernel(const KernelKey& key)
{
  return SelectKernel(key, [](auto types, auto flags) -> KernelFn {
    return &BVHWidePacket_TraceRange<CR_SIMD_WIDTH, CR_SIMD_PACK_WIDTH, decltype(types)::kValue, decltype(flags)::kFastValue, decltype(flags)::kStatsValue>;
  });
}

}  // namespace cr::simd::CR_SIMD_NS
