// The convex polyhedron in the SIMD kernels. Its planes vary in number from
// one polyhedron to the next (up to 32, 528 bytes a record), so it is tested
// lane by lane (simd/lanewise.h) with the scalar kernels' test
// (kernels/polyhedron.h: Polyhedron_IntersectR in fast mode,
// Polyhedron_IntersectRobust in robust mode): every lane gets the scalar
// kernel's bits. Not vectorised across lanes: a first form, measured in
// docs/BENCHMARKS.md.
#pragma once

#include "simd/lanewise.h"

namespace cr::simd {

template <>
struct SimdPrim<Polyhedron> : LanewisePrim<Polyhedron> {
};

}  // namespace cr::simd

#ifdef CR_SIMD_NS
namespace cr::simd::CR_SIMD_NS {

struct PolyhedronScalar {
  template <bool kFast>
  CR_SIMD_INLINE static bool Run(const float o[3], const float d[3], const Polyhedron& p, float tmin, float tmax,
                                 float* th, float*, float*)
  {
    if constexpr (kFast)
      return Polyhedron_IntersectR(o, d, &p, tmin, tmax, th) != 0;
    else
      return Polyhedron_IntersectRobust(o, d, &p, tmin, tmax, th) != 0;
  }
};

template <>
struct SimdTest<Polyhedron> : LanewiseTest<Polyhedron, CR_PRIM_POLYHEDRON, PolyhedronScalar> {
};

}  // namespace cr::simd::CR_SIMD_NS
#endif
