// The BVH kernels of a moving scene (simd/motion.h), packet and single-ray:
// the type set kAllTypes | kMotionBit x precision x statistics. A unit of
// their own, so that the static scenes' units (kernels_packet.cpp,
// kernels_single.cpp) compile what they compiled before. Compiled once per
// ISA (simd/CMakeLists.txt), with the ISA namespace and widths of
// simd/vec.h.
#include "simd/bvh_packet.h"
#include "simd/bvh_single.h"

namespace cr::simd::CR_SIMD_NS {

KernelFn SelectMotionBVHKernel(const KernelKey& key)
{
  constexpr int N = CR_SIMD_WIDTH, K = CR_SIMD_PACK_WIDTH;
  return SelectMotionKernel(key, [&](auto types, auto flags) -> KernelFn {
    constexpr unsigned kTypes = decltype(types)::kValue;
    constexpr bool kFast = decltype(flags)::kFastValue, kStats = decltype(flags)::kStatsValue;
    if (key.packet) return &BVHPacket_TraceRange<N, kTypes, kFast, kStats>;
    return &BVHSingle_TraceRange<N, K, kTypes, kFast, kStats>;
  });
}

}  // namespace cr::simd::CR_SIMD_NS
