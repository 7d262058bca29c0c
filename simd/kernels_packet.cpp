// The packet kernels of one ISA: every type set x precision x statistics.
// Compiled once per ISA (simd/CMakeLists.txt), with the ISA namespace and
// width of simd/vec.h.
#include "simd/bvh_packet.h"

namespace cr::simd::CR_SIMD_NS {

namespace {

template <unsigned kTypes>
KernelFn PickPacket(bool fast, bool stats)
{
  constexpr int N = CR_SIMD_WIDTH;
  if (fast) return stats ? &BVHPacket_TraceRange<N, kTypes, true, true> : &BVHPacket_TraceRange<N, kTypes, true, false>;
  return stats ? &BVHPacket_TraceRange<N, kTypes, false, true> : &BVHPacket_TraceRange<N, kTypes, false, false>;
}

}  // namespace

KernelFn SelectPacketKernel(const KernelKey& key)
{
  switch (key.types) {
    case 1: return PickPacket<1>(key.fast, key.stats);
    case 2: return PickPacket<2>(key.fast, key.stats);
    case 3: return PickPacket<3>(key.fast, key.stats);
    case 4: return PickPacket<4>(key.fast, key.stats);
    case 5: return PickPacket<5>(key.fast, key.stats);
    case 6: return PickPacket<6>(key.fast, key.stats);
    case 7: return PickPacket<7>(key.fast, key.stats);
  }
  return nullptr;  // no primitives: the tracer answers misses itself
}

}  // namespace cr::simd::CR_SIMD_NS
