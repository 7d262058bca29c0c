// The SDF block in the SIMD kernels: tested lane by lane (simd/lanewise.h)
// with the scalar kernels' sphere tracing (kernels/sdf.h Sdf_March, refined
// in robust mode), so every lane gets the scalar kernel's bits. Not
// vectorised across lanes: a march's step count differs from ray to ray.
#pragma once

#include "simd/lanewise.h"

namespace cr::simd {

template <>
struct SimdPrim<Sdf> : LanewisePrim<Sdf> {
};

}  // namespace cr::simd

#ifdef CR_SIMD_NS
namespace cr::simd::CR_SIMD_NS {

struct SdfScalar {
  template <bool kFast>
  CR_SIMD_INLINE static bool Run(const float o[3], const float d[3], const Sdf& p, float tmin, float tmax, float* th,
                                 float*, float*)
  {
    return Sdf_March(o, d, &p, tmin, tmax, kFast ? 0 : CR_SDF_REFINE, th) != 0;
  }
};

template <>
struct SimdTest<Sdf> : LanewiseTest<Sdf, CR_PRIM_SDF, SdfScalar> {
};

}  // namespace cr::simd::CR_SIMD_NS
#endif
