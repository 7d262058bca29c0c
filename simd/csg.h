// The CSG solid in the SIMD kernels: tested lane by lane (simd/lanewise.h)
// with the scalar kernels' classification (kernels/csg.h Csg_Test), so
// every lane gets the scalar kernel's bits, the leaf (u) and the normal's
// side (v) included. The leaves' tests are the robust ones in every mode:
// the SIMD units compile the scalar kernels once, in robust mode (fast mode
// gets robust CSG answers, at robust speed).
#pragma once

#include "simd/lanewise.h"

namespace cr::simd {

template <>
struct SimdPrim<Csg> : LanewisePrim<Csg> {
};

}  // namespace cr::simd

#ifdef CR_SIMD_NS
namespace cr::simd::CR_SIMD_NS {

struct CsgScalar {
  template <bool>
  CR_SIMD_INLINE static bool Run(const float o[3], const float d[3], const Csg& p, float tmin, float tmax, float* th,
                                 float* tu, float* tv)
  {
    Ray r{};
    for (int a = 0; a < 3; ++a) {
      r.org[a] = o[a];
      r.dir[a] = d[a];
      r.inv[a] = 1.0f / d[a];
    }
    r.tmin = tmin;
    r.tmax = tmax;
    return Csg_Test(&r, &p, tmin, tmax, th, tu, tv) != 0;
  }
};

template <>
struct SimdTest<Csg> : LanewiseTest<Csg, CR_PRIM_CSG, CsgScalar> {
};

}  // namespace cr::simd::CR_SIMD_NS
#endif
