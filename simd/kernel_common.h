// What every per-ISA kernel unit includes first: the wrappers, the scalar
// ray and hit code of kernels/ (Ray, Hit, Hit_Init, Hit_Closer, Hit_ToRecord)
// compiled inside the ISA namespace (CR_SIMD_NS, from the unit's flags:
// simd/vec.h), the rays (simd/rays.h) and each primitive type's lane-wise
// test (simd/prims.h). (Ray_Init itself is replaced by the
// vectorised RayPacket_Init, which also keeps libstdc++'s out-of-line
// std::fabs of a -O0 build out of these units.)
#pragma once

#include "kernels/types.h"
#include "simd/simd_kernels.h"
#include "simd/vec.h"

namespace cr::simd::CR_SIMD_NS {
// The scalar kernel helpers, so that hits are kept and reported exactly as
// the scalar backend does (only the ray and hit parts are used; the scalar
// intersectors compile to nothing).
#include "kernels/intersect.h"
}  // namespace cr::simd::CR_SIMD_NS

#include "simd/intersect_simd.h"
#include "simd/rays.h"
#include "simd/motion.h"
#include "simd/prims.h"

namespace cr::simd::CR_SIMD_NS {

// Binary BVH depth bound of host/accel/bvh_builder.cpp (CR_BVH_STACK).
inline constexpr int kBVHStack = 64;

// Whether type k is the last of kTypes (unified indices past the earlier
// types' ranges are then of type k without a comparison).
template <unsigned kTypes>
inline constexpr bool IsLastType(unsigned k)
{
  return ((kTypes & kAllTypes) >> (k + 1u)) == 0u;
}

// Whether a kernel of type set kTypes serves a moving scene (kMotionBit).
template <unsigned kTypes>
inline constexpr bool kHasMotion = (kTypes & kMotionBit) != 0u;

// The scene's arrays as the scalar kernels' PrimView (Hit_ToRecord).
inline PrimView MakePrimView(const KernelScene& sc)
{
  PrimView pv;
#define CR_SIMD_PV_ARRAY_(T, U, a) pv.a = ScenePrims<T>(sc);
  CR_PRIM_TYPES(CR_SIMD_PV_ARRAY_)
#undef CR_SIMD_PV_ARRAY_
  pv.ranges = sc.ranges;
  pv.motion = sc.motion;
  return pv;
}

// A kernel's sums (host/trace/stats.h) into the job's, with its ray count.
inline void AddJobStats(TraceStatsSum* out, TraceStatsSum s, std::size_t rays)
{
  if (!out) return;
  s.rays = rays;
  AddStats(*out, s);
}

// Ray_PlaneT of kernels/ray.h: (p - org) * inv, and 0 where that is NaN (a
// ray lying in the plane).
CR_SIMD_INLINE float PlaneT(float p, float org, float inv)
{
  const float t = (p - org) * inv;
  return t != t ? 0.0f : t;
}
template <int N>
CR_SIMD_INLINE vfloat<N> PlaneTN(vfloat<N> p, vfloat<N> org, vfloat<N> inv)
{
  const vfloat<N> t = (p - org) * inv;
  return Select(IsNaN(t), vfloat<N>(0.0f), t);
}

inline std::uint32_t RayIndex(const KernelJob& job, std::size_t p)
{
  return job.order ? job.order[p] : static_cast<std::uint32_t>(p);
}

// Kernel selection: pick(TypesTag<kTypes>{}, FlagsTag<kFast, kStats>{})
// instantiated for the type set of the key and its flags. The type sets
// compiled grow linearly, not with the subsets of the types: all spheres
// and all triangles (the hot cases, where a scene of one type never asks a
// reference its type), and every type (kAllTypes) for any other scene. A
// leaf or cell holds its references sorted by unified index, so each type's
// run is found once per leaf (prim_range.h); a type the scene lacks has an
// empty run, one comparison per leaf. A moving scene, whatever its types,
// takes kAllTypes | kMotionBit instead (SelectMotionKernel). With
// CELLRAY_SIMD_ALL_TYPES_ONLY (CMake option CELLRAY_SIMD_TYPE_SETS=all, the
// sanitizer preset's: 12-39% of each ISA unit's compile time) every scene
// runs kAllTypes, whose code holds every type's test and gives the same
// answers; the ci preset compiles and tests the one-type sets.
template <unsigned kTypes>
struct TypesTag {
  static constexpr unsigned kValue = kTypes;
};
template <bool kFast, bool kStats>
struct FlagsTag {
  static constexpr bool kFastValue = kFast, kStatsValue = kStats;
};
template <class Pick, unsigned kTypes>
KernelFn SelectFlags(const KernelKey& key, Pick pick)
{
  if (key.fast) return key.stats ? pick(TypesTag<kTypes>{}, FlagsTag<true, true>{}) : pick(TypesTag<kTypes>{}, FlagsTag<true, false>{});
  return key.stats ? pick(TypesTag<kTypes>{}, FlagsTag<false, true>{}) : pick(TypesTag<kTypes>{}, FlagsTag<false, false>{});
}
template <class Pick>
KernelFn SelectKernel(const KernelKey& key, Pick pick)
{
  if (key.types == 0) return nullptr;  // no primitives: the tracer answers misses itself
#if !CELLRAY_SIMD_ALL_TYPES_ONLY
  if (key.types == kSphereBit) return SelectFlags<Pick, kSphereBit>(key, pick);
  if (key.types == kTriangleBit) return SelectFlags<Pick, kTriangleBit>(key, pick);
#endif
  return SelectFlags<Pick, kAllTypes>(key, pick);
}
// The same for a moving scene (key.motion): kAllTypes | kMotionBit, the only
// type set whose primitive tests shift the rays (simd/motion.h). Called from
// the motion units only (kernels_motion_*.cpp), so that the units of the
// static kernels compile exactly what they compiled before motion existed.
template <class Pick>
KernelFn SelectMotionKernel(const KernelKey& key, Pick pick)
{
  if (key.types == 0) return nullptr;
  return SelectFlags<Pick, kAllTypes | kMotionBit>(key, pick);
}

}  // namespace cr::simd::CR_SIMD_NS
