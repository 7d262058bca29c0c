// Derived CPU layouts of the BVH for the single-ray SIMD path (the packet
// path walks the binary BVHNode array of kernels/types.h unchanged).
//
// BVH4_CPU / BVH8_CPU: the binary BVH of host/accel/bvh_builder.cpp collapsed
// into N-wide nodes whose child boxes are stored structure-of-arrays across
// children (Embree's AABBNode: lower_x .. upper_z as N floats each), so one
// ray tests all N child boxes with a few vector instructions. Leaves are the
// binary leaves, unchanged in content; their primitives are repacked into
// K-wide structure-of-arrays packs per type, so one ray tests K primitives at
// once. Everything here is plain data: no code, no intrinsics, safe to
// include from every translation unit whatever its ISA flags.
#pragma once

#include <cstdint>

#include "kernels/types.h"

namespace cr::simd {

inline constexpr std::uint32_t kWideLeafFlag = 0x80000000u;  // child = kWideLeafFlag | leaf index
// Unused child slots point at leaf 0, which holds nothing, and have an empty
// box, which no slab test accepts; so the traversal needs no slot mask (a ray
// with a NaN component, which every slab test accepts, visits the empty leaf).
inline constexpr std::uint32_t kWideEmptyLeaf = kWideLeafFlag | 0u;

// N-wide node: 28 N bytes (112 for BVH4, 224 for BVH8). Unused slots have
// lower = +inf, upper = -inf and child = kWideEmptyLeaf.
template <int N>
struct alignas(4 * N) WideNode {
  float lower[3][N];
  float upper[3][N];
  std::uint32_t child[N];
};
static_assert(sizeof(WideNode<4>) == 112 && sizeof(WideNode<8>) == 224);

// One binary leaf: its packs per type (SimdPrim<T>::Pack<K>, simd/<type>.h),
// contiguous in each type's pack array. 16 bytes for 3 types.
struct alignas(4) WideLeaf {
  std::uint32_t first[CR_NUM_PRIM_TYPES];  // first pack of each type
  std::uint8_t count[CR_NUM_PRIM_TYPES];   // packs of each type
};
static_assert(sizeof(WideLeaf) % 4 == 0);

}  // namespace cr::simd
