// The boundary between the SIMD tracer (plain C++, no ISA flags) and the
// kernels compiled once per ISA (kernels_*.cpp with -msse4.1, with
// -mavx2 -mfma, and with the AVX-512 flags). Only plain data crosses it: no
// standard-library templates are instantiated on the ISA side, so no inline
// function compiled with AVX2 can be picked by the linker for the rest of the
// program.
#pragma once

#include <cstddef>
#include <cstdint>

#include "host/trace/stats.h"
#include "kernels/types.h"
#include "simd/bvh_wide.h"

namespace cr::simd {

// Primitive types present in a scene (bit k: type k of kernels/types.h);
// traversals are instantiated for the sets of kernel_common.h SelectKernel.
inline constexpr unsigned kSphereBit = 1u << CR_PRIM_SPHERE, kTriangleBit = 1u << CR_PRIM_TRIANGLE;
inline constexpr unsigned kAllTypes = (1u << CR_NUM_PRIM_TYPES) - 1u;
// A bit of a kernel's type set past the types: the scene moves (NFF
// `motion`, kernels/motion.h), and every primitive test shifts the ray into
// the rest frame of a moving piece (simd/motion.h). Static scenes run kernels
// without it, which compile nothing of motion.
inline constexpr unsigned kMotionBit = 1u << 31;
static_assert(CR_NUM_PRIM_TYPES < 31, "kMotionBit lies past the type bits");

// A type's index k (CR_PRIM_*) from its layout.
template <class T>
inline constexpr unsigned kPrimIndex = ~0u;
#define CR_SIMD_PRIM_INDEX_(T, U, a) \
  template <>                        \
  inline constexpr unsigned kPrimIndex<T> = CR_PRIM_##U;
CR_PRIM_TYPES(CR_SIMD_PRIM_INDEX_)
#undef CR_SIMD_PRIM_INDEX_

// Each type's SIMD form (simd/<type>.h, listed in simd/prims.h): the rows
// its kernels read (Data: the scene's own layout, or ray-independent terms
// computed once), its K-wide pack of the single-ray BVH (Pack<K>), how a
// pack lane is filled (Fill), and whether exact ties in t between two of
// its primitives are ordered by distance (kDistanceTies, robust mode).
template <class T>
struct SimdPrim;

// The structure a kernel walks: the order of kernels/types.h
// CR_ACCEL_TYPES (and of the host's AccelKind).
#define CR_SIMD_ACCEL_ENUM_(N, U, l, H, Nd) N,
enum class KernelAccel { CR_ACCEL_TYPES(CR_SIMD_ACCEL_ENUM_) };
#undef CR_SIMD_ACCEL_ENUM_

// The ray-margin octree's packet walk searches lazily (simd/octree_packet.h
// OctreePacket_SearchSigns) where the tree's heaviest path has a chain of at
// least this many levels (OctreeChainLength, host/accel/accel.h): a factor
// of 256 between the space and the detail most rays go to. The stadiums'
// trees have 11; the SPD scenes' and meshes' 0 to 5.
inline constexpr std::uint32_t kOctreeLazyChain = 8;

// Everything a kernel reads, as raw pointers into arrays the tracer owns.
struct KernelScene {
  // Each structure's flat layout (kernels/types.h): header, nodes and
  // references, as gridHeader, gridNodes (the cell offsets), gridRefs, ...
#define CR_SIMD_ACCEL_ARRAYS_(N, U, l, H, Nd) \
  const H* l##Header = nullptr;               \
  const Nd* l##Nodes = nullptr;               \
  const std::uint32_t* l##Refs = nullptr;
  CR_ACCEL_TYPES(CR_SIMD_ACCEL_ARRAYS_)
#undef CR_SIMD_ACCEL_ARRAYS_
  // N-wide BVH (single-ray path) of the ISA's width, and its K-wide leaf packs.
  const void* wideNodes = nullptr;  // WideNode<N>
  const WideLeaf* wideLeaves = nullptr;
  const void* packs[CR_NUM_PRIM_TYPES] = {};  // SimdPrim<T>::Pack<K> of type k
  // Primitives by type (unified index g as in kernels/types.h): the scene's
  // arrays (the double-float cold paths start from them) and the rows the
  // kernels read (SimdPrim<T>::Data; the scene's array where that is T).
  const void* prims[CR_NUM_PRIM_TYPES] = {};
  const void* data[CR_NUM_PRIM_TYPES] = {};
  PrimRanges ranges{};
  const std::uint32_t* primIds = nullptr;  // scene id of every g
  int unifiedHits = 0;                     // TraceConfig::unifiedHits
  int octreeLazy = 0;                      // the ray-margin octree's packets search lazily (simd/octree_packet.h)
  // Motion of every g (kernels/motion.h: 4 floats each), null for a static
  // scene.
  const float* motion = nullptr;
};

// Rays at positions [begin, end) of the ray order: ray order[p] (p itself
// without an order) is traced and its answer written to hits[order[p]].
// Packet kernels take positions in groups of their width, so begin must be a
// multiple of it.
struct KernelJob {
  const RayRecord* rays = nullptr;
  const float* times = nullptr;  // per ray (by ray index), or null: every ray at time 0
  HitRecord* hits = nullptr;
  const std::uint32_t* order = nullptr;
  // Packet kernels, without an order: imageWidth > 0 says the rays are a
  // row-major image of that width, whose width is a multiple of N / 2 and
  // height a multiple of 2, and positions run through it in (N/2) x 2 tiles,
  // tile rows top to bottom: position p is lane p % N of tile p / N.
  std::uint32_t imageWidth = 0;
  std::size_t begin = 0, end = 0;
  int occlusion = 0;
  TraceStatsSum* stats = nullptr;  // non-null for statistics kernels
};

// Type T's arrays of `sc`. Always inlined: the ISA units call them, and no
// function of theirs may be emitted outside their ISA namespace.
#define CR_SIMD_HOST_INLINE inline __attribute__((always_inline))
template <class T>
CR_SIMD_HOST_INLINE const T* ScenePrims(const KernelScene& sc)
{
  return static_cast<const T*>(sc.prims[kPrimIndex<T>]);
}
template <class T>
CR_SIMD_HOST_INLINE const typename SimdPrim<T>::Data* PrimData(const KernelScene& sc)
{
  return static_cast<const typename SimdPrim<T>::Data*>(sc.data[kPrimIndex<T>]);
}

using KernelFn = void (*)(const KernelScene&, const KernelJob&);

struct KernelKey {
  KernelAccel accel = KernelAccel::BVH;
  unsigned types = 0;   // PrimTypeBits of the scene's types
  bool fast = false;    // Precision::Fast (else robust)
  bool stats = false;   // counts Havran's measures
  bool packet = false;  // ray packets (else one ray at a time)
  bool motion = false;  // the scene moves (KernelScene::motion): SelectMotion<Name>Kernel
};

// Answer of one ray-primitive test, for the lane-by-lane unit tests.
struct ProbeResult {
  int hit = 0;
  float t = 0.0f, u = 0.0f, v = 0.0f;
};

// Ray-primitive and ray-box tests exposed for tests: the packet form (one
// primitive g against `width` rays in the lanes) and the single-ray form (one
// ray against `width` primitives gs[] in one pack; g = CR_NO_HIT pads).
// tmax is each ray's tmax. Box probes test box (lo, hi) against the ray(s).
struct KernelProbes {
  int width = 0;      // N of the packet and wide-node forms
  int packWidth = 0;  // K of the primitive packs
  void (*packetPrim)(const KernelScene&, const RayRecord* rays, std::uint32_t g, bool fast, ProbeResult* out) = nullptr;
  void (*singlePrims)(const KernelScene&, const RayRecord& ray, const std::uint32_t* gs, bool fast,
                      ProbeResult* out) = nullptr;
  void (*packetBox)(const float lo[3], const float hi[3], const RayRecord* rays, bool fast, ProbeResult* out) = nullptr;
  void (*singleBoxes)(const float* lo /* [3][width] */, const float* hi, const RayRecord& ray, bool fast,
                      ProbeResult* out) = nullptr;
};

// How the tracer forms packets for a structure's packet kernels from an
// incoherent ray set: in input order, or grouped by direction class
// (simd/ray_order.h DirectionClassOrder) always or where the tracer's
// measure says it pays (simd_tracer.cpp GridClassOrderPays).
enum class PacketOrder { Input, DirectionClasses, DirectionClassesWhenPays };

// Each ISA's kernels: Probes() also tells its widths (SSE4: N = 4, K = 4;
// AVX2 and AVX-512: N = 8, K = 8), from which the tracer builds the matching wide BVH.
// Select<Name>Kernel for each structure of CR_ACCEL_TYPES gives either
// variant (key.packet; the BVH's from SelectPacketKernel and
// SelectSingleKernel, which walk different layouts), nullptr when the scene
// has no primitives; <Name>PacketOrder its packets' order.
// SelectMotion<Name>Kernel gives a moving scene's kernels (key.motion; the
// type set kAllTypes | kMotionBit, in units of their own,
// kernels_motion_*.cpp).
#define CR_DECLARE_SIMD_SELECT_(N, U, l, H, Nd)           \
  KernelFn Select##N##Kernel(const KernelKey& key);       \
  KernelFn SelectMotion##N##Kernel(const KernelKey& key); \
  PacketOrder N##PacketOrder();
#define CR_DECLARE_SIMD_ISA(ns)                      \
  namespace ns {                                     \
  CR_ACCEL_TYPES(CR_DECLARE_SIMD_SELECT_)            \
  KernelFn SelectPacketKernel(const KernelKey& key); \
  KernelFn SelectSingleKernel(const KernelKey& key); \
  KernelProbes Probes();                             \
  }
CR_DECLARE_SIMD_ISA(sse4)
CR_DECLARE_SIMD_ISA(avx2)
CR_DECLARE_SIMD_ISA(avx512)
#undef CR_DECLARE_SIMD_SELECT_
#undef CR_DECLARE_SIMD_ISA

// The probes of an ISA's kernels (simd_tracer.cpp), for tests and
// micro benchmarks; RuntimeError where this build lacks the ISA's kernels.
enum class Isa;
KernelProbes IsaProbes(Isa isa);

}  // namespace cr::simd
