// The fast kernels as C++. See kernel_instance.inc.
#define CR_KERNEL_NS k_fast
#define CR_FAST 1

#include "host/scalar/kernel_instance.inc"
