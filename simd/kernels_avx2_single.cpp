// The single kernels for AVX2 (compiled with -mavx2 -mfma).
#define CR_SIMD_NS avx2
#define CR_SIMD_WIDTH 8
#define CR_SIMD_PACK_WIDTH 4
#include "simd/single_instance.inc"
