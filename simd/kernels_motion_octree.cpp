// The octree kernels of a moving scene (simd/motion.h), packet and
// single-ray: the type set kAllTypes | kMotionBit x precision x statistics.
// A unit of their own, so that the static scenes' unit (kernels_octree.cpp)
// compiles what it compiled before. Compiled once per ISA
// (simd/CMakeLists.txt).
#include "simd/octree_packet.h"
#include "simd/octree_single.h"

namespace cr::simd::CR_SIMD_NS {

KernelFn SelectMotionOctreeKernel(const KernelKey& key)
{
  constexpr int N = CR_SIMD_WIDTH;
  return SelectMotionKernel(key, [&](auto types, auto flags) -> KernelFn {
    constexpr unsigned kTypes = decltype(types)::kValue;
    constexpr bool kFast = decltype(flags)::kFastValue, kStats = decltype(flags)::kStatsValue;
    if (key.packet) return &OctreePacket_TraceRange<N, kTypes, kFast, kStats>;
    return &OctreeSingle_TraceRange<N, kTypes, kFast, kStats>;
  });
}

}  // namespace cr::simd::CR_SIMD_NS
