// The boundary between the SIMD tracer (plain C++, no ISA flags) and the
// kernels compiled once per ISA (kernels_sse4*.cpp with -msse4.1,
// kernels_avx2*.cpp with -mavx2 -mfma). Only plain data crosses it: no
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

// Primitive types present in a scene; traversals are instantiated per set.
enum PrimTypeBits : unsigned { kSphereBit = 1u, kTriangleBit = 2u, kConeBit = 4u };

// The structure a kernel walks.
enum class KernelAccel { BVH, Grid, Octree };

// Everything a kernel reads, as raw pointers into arrays the tracer owns.
struct KernelScene {
  // Binary BVH (packet path), kernels/types.h layout.
  const BVHNode* nodes = nullptr;
  const std::uint32_t* refs = nullptr;
  // Uniform grid (GridHeader, nCells + 1 cell offsets, references).
  const GridHeader* grid = nullptr;
  const std::uint32_t* cellStart = nullptr;
  const std::uint32_t* gridRefs = nullptr;
  // Octree (OctreeHeader, nodes, references).
  const OctreeHeader* octree = nullptr;
  const OctreeNode* octreeNodes = nullptr;
  const std::uint32_t* octreeRefs = nullptr;
  // N-wide BVH (single-ray path) of the ISA's width, and its K-wide leaf packs.
  const void* wideNodes = nullptr;  // WideNode<N>
  const WideLeaf* wideLeaves = nullptr;
  const void* spherePacks = nullptr;    // SpherePack<K>
  const void* trianglePacks = nullptr;  // TrianglePack<K>
  const void* conePacks = nullptr;      // ConePack<K>
  // Primitives by type (unified index g as in kernels/types.h).
  const Sphere* spheres = nullptr;
  const Triangle* triangles = nullptr;
  const ConeData* cones = nullptr;
  const Cone* coneGeometry = nullptr;  // the scene's cones (Cone_IntersectN's double-float cold path)
  PrimRanges ranges{};
  const std::uint32_t* primIds = nullptr;  // scene id of every g
  int unifiedHits = 0;                     // TraceConfig::unifiedHits
};

// Rays at positions [begin, end) of the ray order: ray order[p] (p itself
// without an order) is traced and its answer written to hits[order[p]].
// Packet kernels take positions in groups of their width, so begin must be a
// multiple of it.
struct KernelJob {
  const RayRecord* rays = nullptr;
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

using KernelFn = void (*)(const KernelScene&, const KernelJob&);

struct KernelKey {
  KernelAccel accel = KernelAccel::BVH;
  unsigned types = 0;   // PrimTypeBits, 1..7
  bool fast = false;    // Precision::Fast (else robust)
  bool stats = false;   // counts Havran's measures
  bool packet = false;  // ray packets (else one ray at a time)
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

// Each ISA's kernels: Probes() also tells its widths (SSE4: N = 4, K = 4;
// AVX2: N = 8, K = 4), from which the tracer builds the matching wide BVH.
// SelectPacketKernel and SelectSingleKernel are the BVH's; SelectGridKernel
// and SelectOctreeKernel give either variant (key.packet). nullptr when the
// scene has no primitives.
#define CR_DECLARE_SIMD_ISA(ns)                      \
  namespace ns {                                     \
  KernelFn SelectPacketKernel(const KernelKey& key); \
  KernelFn SelectSingleKernel(const KernelKey& key); \
  KernelFn SelectGridKernel(const KernelKey& key);   \
  KernelFn SelectOctreeKernel(const KernelKey& key); \
  KernelProbes Probes();                             \
  }
CR_DECLARE_SIMD_ISA(sse4)
CR_DECLARE_SIMD_ISA(avx2)
#undef CR_DECLARE_SIMD_ISA

}  // namespace cr::simd
