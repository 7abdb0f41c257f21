// The kernel launchers for one instruction set, included by cpu_kernels_<set>.cpp, each compiled
// with its own -march flag (see CMakeLists.txt). Everything it defines has internal linkage
// (anonymous namespace, always-inlined kernels), so the copies built for different instruction
// sets never stand in for one another at link time. No include guard: one inclusion per file.
#include "devices/cpu/cpu_kernels.h"
#include "devices/cpu/parallel_for.h"

#ifndef RTD_CPU_ISA_SUFFIX
#error "define RTD_CPU_ISA_SUFFIX (Scalar, Sse2, Avx2 or Avx512) before including this file"
#endif

#define RTD_CONCAT_(a, b) a##b
#define RTD_CONCAT(a, b) RTD_CONCAT_(a, b)

namespace rtd {
namespace {

#define RTD_DEFINE_RUN(K)                                                      \
    void run##K(const K& kernel, int width, int height, CpuScratch& scratch) { \
        parallelFor2D(width, height, kernel, &scratch);                        \
    }
RTD_FOR_EACH_CPU_KERNEL(RTD_DEFINE_RUN)
#undef RTD_DEFINE_RUN

#define RTD_TABLE_VALUE(K) &run##K,
const CpuKernelTable kTable = {CpuIsa::RTD_CPU_ISA_SUFFIX,
                               RTD_FOR_EACH_CPU_KERNEL(RTD_TABLE_VALUE)};
#undef RTD_TABLE_VALUE

}  // namespace

const CpuKernelTable* RTD_CONCAT(cpuKernels, RTD_CPU_ISA_SUFFIX)() {
    return &kTable;
}

}  // namespace rtd
