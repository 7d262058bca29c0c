// Width-templated SIMD wrappers in the style of Embree's vfloat<N>, vint<N>,
// vbool<N>: N = 4 (SSE4.1) and N = 8 (AVX2). The only place besides the
// kernels of simd/ where intrinsics appear.
//
// Every translation unit that includes this header is compiled for one ISA
// and defines CR_SIMD_NS (sse4 or avx2) first: all wrappers and kernels then
// live in cr::simd::CR_SIMD_NS, so the same inline function compiled with
// different -m flags in two units has two different names and the linker can
// never hand the SSE4 path an AVX2 copy (an ODR trap of per-ISA builds).
//
// Semantics are those of the scalar kernels, lane by lane, and nothing else:
// no FMA, no approximate reciprocals. Min/Max are the raw instructions
// (NaN in either operand gives the second operand), FMin/FMax are C's
// fminf/fmaxf (a NaN operand is ignored).
#pragma once

#ifndef CR_SIMD_NS
#error "define CR_SIMD_NS (the ISA namespace) before including simd/vec.h"
#endif
#if !defined(__SSE4_1__)
#error "simd/vec.h needs -msse4.1 (or -mavx2)"
#endif

#include <immintrin.h>

#include <cstdint>

// The wrappers and the lane-wise kernels are small and hot: always inline
// them (GCC otherwise keeps some intersectors out of line in the traversal).
#define CR_SIMD_INLINE inline __attribute__((always_inline))

namespace cr::simd::CR_SIMD_NS {

template <int N>
struct vfloat;
template <int N>
struct vint;
template <int N>
struct vbool;

// Count of set bits of a lane mask.
inline int PopCount(unsigned bits) { return __builtin_popcount(bits); }
// Index of the lowest set bit; bits != 0.
inline int LowestBit(unsigned bits) { return __builtin_ctz(bits); }

}  // namespace cr::simd::CR_SIMD_NS

#include "simd/vec4_sse4.h"
#ifdef __AVX2__
#include "simd/vec8_avx2.h"
#endif
