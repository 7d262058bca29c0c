// The fp64 kernels as C++, with per-ray statistics. See kernel_instance.inc.
#define CR_KERNEL_NS k_fp64_stats
#define CR_FP64 1
#define CR_STATS 1
#include "host/scalar/kernel_instance.inc"
