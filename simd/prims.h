// The primitive types of the SIMD kernels, one header each (the same list as
// kernels/types.h CR_PRIM_TYPES, in its order): each defines SimdPrim<T>
// (its rows, its pack of the single-ray BVH, how a pack lane is filled) for
// every unit, and, in the ISA units (simd/vec.h defines CR_SIMD_NS),
// SimdTest<T>, its lane-wise test in the three forms the traversals call:
//   Packet<N, kFast>(sc, g, P, tmax, t, u, v)   primitive g, N rays (packets)
//   Pack<K, kFast>(sc, pack, valid, pr, ...)    K primitives of a pack, 1 ray
//   Gather<kFast>(sc, g[4], pr, ...)            4 primitives gathered from
//                                               their rows (cell walks)
// Each returns the lanes that hit in [tmin, tmax] with their t (u, v where
// the type reports them); the traversals keep the closest (Hit_Closer).
#pragma once

#include "simd/simd_kernels.h"

#ifdef CR_SIMD_NS
namespace cr::simd::CR_SIMD_NS {
template <class T>
struct SimdTest;
}  // namespace cr::simd::CR_SIMD_NS
#endif

#include "simd/sphere.h"
#include "simd/triangle.h"
#include "simd/cone.h"
#include "simd/box.h"
#include "simd/quadric.h"
#include "simd/polyhedron.h"
#include "simd/sdf.h"
#include "simd/csg.h"
