// The robust kernels as C++. See kernel_instance.inc.
#define CR_KERNEL_NS k_robust
#define CR_KERNEL_REAL float


#include "host/scalar/kernel_instance.inc"
