// The kernel launchers built for avx512 (flags in CMakeLists.txt).
#define RTD_CPU_ISA_SUFFIX Avx512
#include "devices/cpu/cpu_kernels_impl.h"
