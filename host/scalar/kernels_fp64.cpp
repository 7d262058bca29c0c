// The fp64 kernels as C++. See kernel_instance.inc.
#define CR_KERNEL_NS k_fp64
#define CR_FP64 1

#include "host/scalar/kernel_instance.inc"
