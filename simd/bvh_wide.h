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

// One binary leaf: its packs per type, contiguous in the pack arrays. 16 bytes.
struct WideLeaf {
  std::uint32_t first[3];  // first sphere, triangle, cone pack
  std::uint8_t count[3];   // packs of each type
  std::uint8_t pad;
};
static_assert(sizeof(WideLeaf) == 16);

// K primitives of one type, structure-of-arrays. Unused lanes have
// g = CR_NO_HIT and zero geometry; kernels mask them by g.
template <int K>
struct SpherePack {  // 20 K bytes
  float center[3][K];
  float radius[K];
  std::uint32_t g[K];
};

template <int K>
struct TrianglePack {  // 44 K bytes
  float v[3][3][K];    // [vertex][axis][lane]
  std::uint32_t g[K];
  std::uint32_t flags[K];  // Triangle.flags (the CR_TRI_LONG_* bits are read)
};

// Cone with the ray-independent terms of Cone_Intersect (kernels/intersect.h)
// computed once, in float, in the kernel's operation order, so the SIMD
// kernels reproduce its rounding bit for bit: w = (apex - base) / H,
// H = |apex - base|, r0 = base radius, k = (apex radius - r0) / H.
struct ConeData {  // 48 bytes
  float base[3];
  float H;
  float w[3];
  float r0;
  float k;
  float pad[3];
};
static_assert(sizeof(ConeData) == 48);

template <int K>
struct ConePack {  // 40 K bytes
  float base[3][K];
  float w[3][K];
  float H[K];
  float r0[K];
  float k[K];
  std::uint32_t g[K];
};

}  // namespace cr::simd
