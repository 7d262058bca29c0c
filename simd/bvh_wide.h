// Derived CPU layouts of the BVH for the SIMD paths, single-ray and packet
// (only a moving scene's packets walk the binary BVHNode array of
// kernels/types.h).
//
// BVH4_CPU / BVH8_CPU: the binary BVH of host/accel/bvh_builder.cpp collapsed
// into N-wide nodes whose child boxes are stored structure-of-arrays across
// children (Embree's AABBNode: lower_x .. upper_z as N floats each), so one
// ray tests all N child boxes with a few vector instructions. A leaf is a
// binary leaf or a small binary subtree merged by the collapse
// (bvh_wide_builder.cpp); its primitives are repacked into K-wide
// structure-of-arrays packs per type, so one ray tests K primitives at once. Everything here is plain data: no code, no intrinsics, safe to
// include from every translation unit whatever its ISA flags.
#pragma once

#include <cstdint>

#include "kernels/types.h"

namespace cr::simd {

// A child slot is child[i] and meta[i]. Interior: meta = 0, child = the
// wide node's index. Leaf: child = kWideLeafFlag | p, and meta tells what p
// is. A leaf of one primitive type (nearly all): meta = (type + 1) << 16 |
// packs, p the first of its `packs` consecutive packs of that type, read
// without going through a WideLeaf record (one dependent load fewer per
// leaf, where incoherent rays miss the cache). A leaf of several types:
// meta = kWideMixedLeaf, p a WideLeaf index.
inline constexpr std::uint32_t kWideLeafFlag = 0x80000000u;
inline constexpr std::uint32_t kWideMixedLeaf = 0xffff0000u;
// Unused child slots point at leaf 0, which holds nothing, and have an empty
// box, which no slab test accepts; so the traversal needs no slot mask (a ray
// with a NaN component, which every slab test accepts, visits the empty leaf).
inline constexpr std::uint32_t kWideEmptyLeaf = kWideLeafFlag | 0u;
inline constexpr std::uint32_t WideLeafMeta(std::uint32_t type, std::uint32_t packs)
{
  return (type + 1u) << 16 | packs;
}

// N-wide node: 32 N bytes (128 for BVH4, 256 for BVH8: whole cache lines).
// Unused slots have lower = +inf, upper = -inf, child = kWideEmptyLeaf and
// meta = kWideMixedLeaf.
template <int N>
struct alignas(64) WideNode {
  float lower[3][N];
  float upper[3][N];
  std::uint32_t child[N];
  std::uint32_t meta[N];
};
static_assert(sizeof(WideNode<4>) == 128 && sizeof(WideNode<8>) == 256);

// A leaf of several types: its packs per type (SimdPrim<T>::Pack<K>,
// simd/<type>.h), contiguous in each type's pack array.
struct alignas(4) WideLeaf {
  std::uint32_t first[CR_NUM_PRIM_TYPES];  // first pack of each type
  std::uint8_t count[CR_NUM_PRIM_TYPES];   // packs of each type
};
static_assert(sizeof(WideLeaf) % 4 == 0);

}  // namespace cr::simd
