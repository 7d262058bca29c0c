// The grid kernels for AVX2 (compiled with -mavx2 -mfma).
#define CR_SIMD_NS avx2
#define CR_SIMD_WIDTH 8
#include "simd/grid_instance.inc"
