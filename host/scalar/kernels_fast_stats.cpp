// The fast kernels as C++, with per-ray statistics. See kernel_instance.inc.
#define CR_KERNEL_NS k_fast_stats
#define CR_FAST 1
#define CR_STATS 1
#include "host/scalar/kernel_instance.inc"
