// The robust kernels as C++. See kernel_instance.inc.
#define CR_KERNEL_NS k_robust


#include "host/scalar/kernel_instance.inc"
