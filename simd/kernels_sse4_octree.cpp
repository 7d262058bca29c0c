// The octree kernels for SSE4.1 (compiled with -msse4.1).
#define CR_SIMD_NS sse4
#define CR_SIMD_WIDTH 4
#include "simd/octree_instance.inc"
