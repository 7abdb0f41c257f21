// The kernel launchers built for sse2 (flags in CMakeLists.txt).
#define RTD_CPU_ISA_SUFFIX Sse2
#include "devices/cpu/cpu_kernels_impl.h"
