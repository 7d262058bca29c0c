/* cellray kernel prelude: the few things that differ between OpenCL C 1.2 and
 * C++20, so that every file in kernels/ compiles as both. The C++ build of the
 * kernels is the `scalar` backend and the test oracle for the OpenCL build.
 *
 * Rules for code in kernels/ (the portable subset):
 *  - no vector types (float3 is 16 bytes in OpenCL, 12 in C++): use float[3];
 *  - no unsuffixed floating literals (they are double in both languages and
 *    would need cl_khr_fp64): write 0.5f, or CR_R(0.5) for the `real` type;
 *  - functions are CR_FUNC, pointers into buffers are CR_GLOBAL;
 *  - no recursion, no function pointers, no dynamic allocation.
 */
#ifndef CELLRAY_KERNELS_PRELUDE_H
#define CELLRAY_KERNELS_PRELUDE_H

#if defined(__OPENCL_C_VERSION__) || defined(__OPENCL_VERSION__)
#define CR_OPENCL 1
#define CR_FUNC static inline
#define CR_GLOBAL __global
#define CR_LOCAL __local
#define CR_NS_BEGIN
#define CR_NS_END
#pragma OPENCL FP_CONTRACT OFF
#ifdef CR_FP64
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#endif
typedef ulong cr_u64;
#define CR_ASSERT(x)
#define CR_FLT_MAX FLT_MAX
#define CR_INF INFINITY
CR_FUNC uint cr_popcount(uint x) { return popcount(x); }
CR_FUNC uint cr_float_bits(float x) { return as_uint(x); }
CR_FUNC float cr_bits_float(uint x) { return as_float(x); }
#define cr_isnan(x) isnan(x)
#define CR_SQRTF(x) sqrt(x)
/* Cold paths are calls (PoCL: inlined, they slowed the hot loops and one
 * form crashed its compiler), except under CR_COLD_INLINE
 * (CELLRAY_CL_COLD=inline, for GPUs: a call's frame and arguments take
 * scratch memory there; docs/OPENCL.md, the GPU compile table). */
#ifdef CR_COLD_INLINE
#define CR_COLD
#else
#define CR_COLD __attribute__((noinline))
#endif
#define CR_FUNC_HOT static inline

#else /* C++ */
#include <bit>
#include <cassert>
#include <cfloat>
#include <cmath>
#include <cstdint>
#define CR_FUNC inline
#define CR_GLOBAL
#define CR_LOCAL
#define CR_NS_BEGIN namespace cr {
#define CR_NS_END }
#define CR_ASSERT(x) assert(x)
#define CR_FLT_MAX FLT_MAX
#define CR_INF INFINITY
namespace cr {
typedef std::uint32_t uint;
typedef std::uint64_t cr_u64;
using std::copysign;
using std::fabs;
using std::floor;
using std::rint;
/* fmin and fmax as C99 and OpenCL define them (a NaN operand gives the
 * other operand), on a tie the second operand, as minss / maxss and the
 * SIMD backend's FMin / FMax (simd/vec*.h: Select(IsNaN(b), a, Min(a, b))),
 * and glibc's x86-64 fminf (so that the scalar and SIMD kernels agree on
 * the sign of a zero result), written out: GCC compiles std::fmin to a call
 * into libm, and the scalar kernels and the fp64 reference (host/reference,
 * cr::fmin) call them in every slab test (inline, the same answers: the
 * scalar BVH in 0.75 of the time, the fp64 reference in 0.79). */
template <class T>
inline T cr_fmin_(T x, T y)
{
  return x < y ? x : (y != y ? x : y);
}
template <class T>
inline T cr_fmax_(T x, T y)
{
  return x > y ? x : (y != y ? x : y);
}
inline float fmin(float x, float y) { return cr_fmin_(x, y); }
inline double fmin(double x, double y) { return cr_fmin_(x, y); }
inline float fmax(float x, float y) { return cr_fmax_(x, y); }
inline double fmax(double x, double y) { return cr_fmax_(x, y); }
using std::nextafter;
using std::sqrt;
inline uint cr_popcount(uint x) { return static_cast<uint>(std::popcount(x)); }
inline uint cr_float_bits(float x) { return std::bit_cast<uint>(x); }
inline float cr_bits_float(uint x) { return std::bit_cast<float>(x); }
inline int cr_isnan(float x) { return std::isnan(x) ? 1 : 0; }
inline int cr_isnan(double x) { return std::isnan(x) ? 1 : 0; }
inline int cr_min(int a, int b) { return a < b ? a : b; }
inline int cr_max(int a, int b) { return a > b ? a : b; }
inline uint cr_minu(uint a, uint b) { return a < b ? a : b; }
}  // namespace cr
/* A float square root that is never an out-of-line std:: function: code
 * that the SIMD units compile (with their own -m flags) must not define a
 * weak symbol outside their ISA namespace (docs/SIMD.md). */
#define CR_SQRTF(x) __builtin_sqrtf(x)
/* Rarely taken work kept out of the hot loops it is called from, and the
 * per-primitive step kept inside them (GCC's size heuristics would
 * otherwise outline it from the grid walk). */
#define CR_COLD __attribute__((noinline, cold))
#define CR_FUNC_HOT inline __attribute__((always_inline))
#endif

/* Before a loop of fixed small trip count (the three axes): unrolled in
 * OpenCL, where PoCL compiles with -unroll-threshold=1, so that a rolled
 * loop would stay a loop inside the work-item loop and keep PoCL from
 * vectorising it. C++ compilers unroll such loops by themselves. */
/* CR_ROLLED: before a group-sized loop run by one work-item (the packet
 * traversals' reductions over the lanes' verdicts): kept a loop. PoCL rolls
 * it anyway; clang for a GPU unrolled the 64 lanes' loads into registers
 * (gfx906: 77 VGPRs for the BVH packet kernel in fast mode, 36 rolled:
 * docs/OPENCL.md, the GPU compile table). */
#ifdef CR_OPENCL
#define CR_UNROLL _Pragma("unroll")
#define CR_ROLLED _Pragma("unroll 1")
#else
#define CR_UNROLL
#define CR_ROLLED
#endif

/* v[k] for an axis k in {0, 1, 2} computed at run time: selects in OpenCL,
 * so that the array is not indexed by a value, which would keep it in
 * private memory, where the OpenCL compiler's SLP vectoriser packs its
 * stores into 2-wide vectors and PoCL's work-item loop vectoriser then
 * refuses the region ("instruction return type cannot be vectorized").
 * Plain indexing in C++: the same value either way. */
#ifdef CR_OPENCL
#define CR_PICK3(v, k) ((k) == 0 ? (v)[0] : (k) == 1 ? (v)[1] : (v)[2])
#else
#define CR_PICK3(v, k) ((v)[k])
#endif

#ifdef CR_OPENCL
#define cr_min(a, b) min((int)(a), (int)(b))
#define cr_max(a, b) max((int)(a), (int)(b))
#define cr_minu(a, b) min((uint)(a), (uint)(b))
#endif

#endif /* CELLRAY_KERNELS_PRELUDE_H */
