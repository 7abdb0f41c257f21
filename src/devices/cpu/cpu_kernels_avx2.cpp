// The kernel launchers built for avx2 (flags in CMakeLists.txt).
#define RTD_CPU_ISA_SUFFIX Avx2
#include "devices/cpu/cpu_kernels_impl.h"
