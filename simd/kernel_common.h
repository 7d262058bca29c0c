// What every per-ISA kernel unit includes first: the wrappers, the scalar
// ray and hit code of kernels/ (Ray, Hit, Hit_Init, Hit_Closer, Hit_ToRecord)
// compiled inside the ISA namespace (CR_SIMD_NS, from the unit's flags:
// simd/vec.h), and the lane-wise intersectors. (Ray_Init itself is replaced by the
// vectorised RayPacket_Init, which also keeps libstdc++'s out-of-line
// std::fabs of a -O0 build out of these units.)
#pragma once

#include "kernels/types.h"
#include "simd/simd_kernels.h"
#include "simd/vec.h"

namespace cr::simd::CR_SIMD_NS {
typedef float real;
// The scalar kernel helpers, so that hits are kept and reported exactly as
// the scalar backend does (only the ray and hit parts are used; the scalar
// intersectors compile to nothing).
#include "kernels/intersect.h"
}  // namespace cr::simd::CR_SIMD_NS

#include "simd/intersect_simd.h"

namespace cr::simd::CR_SIMD_NS {

// Binary BVH depth bound of host/accel/bvh_builder.cpp (CR_BVH_STACK).
inline constexpr int kBVHStack = 64;

// Type of unified index g, decided only among the types in kTypes, so a scene
// with one type never branches.
enum class PrimType { Sphere, Triangle, Cone };
template <unsigned kTypes>
inline PrimType TypeOf(std::uint32_t g, const PrimRanges& c)
{
  constexpr bool hasS = kTypes & kSphereBit, hasT = kTypes & kTriangleBit, hasC = kTypes & kConeBit;
  if constexpr (hasS) {
    if constexpr (!hasT && !hasC) return PrimType::Sphere;
    if (g < Prim_End(&c, CR_PRIM_SPHERE)) return PrimType::Sphere;
  }
  if constexpr (hasT) {
    if constexpr (!hasC) return PrimType::Triangle;
    if (g < Prim_End(&c, CR_PRIM_TRIANGLE)) return PrimType::Triangle;
  }
  return PrimType::Cone;
}

inline PrimView MakePrimView(const KernelScene& sc)
{
  PrimView pv;
  pv.spheres = sc.spheres;
  pv.triangles = sc.triangles;
  pv.cones = nullptr;  // Hit_ToRecord reads triangles only
  pv.ranges = sc.ranges;
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
// instantiated for the type set and flags of the key, so each kernel is
// compiled for exactly the primitive types a scene has.
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
  switch (key.types) {
    case 1: return SelectFlags<Pick, 1>(key, pick);
    case 2: return SelectFlags<Pick, 2>(key, pick);
    case 3: return SelectFlags<Pick, 3>(key, pick);
    case 4: return SelectFlags<Pick, 4>(key, pick);
    case 5: return SelectFlags<Pick, 5>(key, pick);
    case 6: return SelectFlags<Pick, 6>(key, pick);
    case 7: return SelectFlags<Pick, 7>(key, pick);
  }
  return nullptr;  // no primitives: the tracer answers misses itself
}

}  // namespace cr::simd::CR_SIMD_NS
