// The kernel launchers, not vectorised: the baseline for speed-ups (flags in CMakeLists.txt).
#define RTD_CPU_ISA_SUFFIX Scalar
#include "devices/cpu/cpu_kernels_impl.h"
