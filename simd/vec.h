// Width-templated SIMD wrappers in the style of Embree's vfloat<N>, vint<N>,
// vbool<N>: N = 4 (SSE4.1) and N = 8 (AVX2; AVX-512, the same wrappers). The only place besides the
// kernels of simd/ where intrinsics appear.
//
// Every translation unit that includes this header is compiled for one ISA,
// and the ISA's namespace (CR_SIMD_NS: sse4 or avx2) and vector width
// (CR_SIMD_WIDTH) follow from its flags, as in Embree's kernels/common/isa.h:
// one source, compiled once per ISA (simd/CMakeLists.txt). All wrappers and
// kernels live in cr::simd::CR_SIMD_NS, so the same inline function compiled
// with different -m flags in two units has two different names and the
// linker can never hand the SSE4 path an AVX2 copy (an ODR trap of per-ISA
// builds).
//
// Semantics are those of the scalar kernels, lane by lane, and nothing else:
// no FMA, no approximate reciprocals. Min/Max are the raw instructions
// (NaN in either operand gives the second operand), FMin/FMax are C's
// fminf/fmaxf (a NaN operand is ignored).
#pragma once

#if defined(__AVX512F__) && defined(__AVX512VL__) && defined(__AVX512DQ__) && defined(__AVX512BW__)
// The AVX2 wrappers, eight lanes, compiled with AVX-512VL: EVEX encodings
// with 32 vector registers (the single-ray BVH walk spilled its ray with
// 16) and mask-register compares where the compiler picks them; no 512-bit
// vectors (-mprefer-vector-width=256, simd/CMakeLists.txt). Same answers.
#define CR_SIMD_NS avx512
#define CR_SIMD_WIDTH 8
#elif defined(__AVX2__) && defined(__FMA__)
#define CR_SIMD_NS avx2
#define CR_SIMD_WIDTH 8
#elif defined(__SSE4_1__)
#define CR_SIMD_NS sse4
#define CR_SIMD_WIDTH 4
#else
#error "simd/vec.h needs -msse4.1, -mavx2 -mfma or the AVX-512 flags (the ISA units of simd/CMakeLists.txt)"
#endif
// Primitives per pack of the wide BVH's leaves (K): the ISA's width (AVX2
// 8, SSE4 4). AVX2 packs of 8 against 4: 0.967 of the time over 10 scenes x
// 3 ray kinds, bumpy 10^6 diffuse rays 0.88 (docs/SIMD.md `single`).
#define CR_SIMD_PACK_WIDTH CR_SIMD_WIDTH

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
