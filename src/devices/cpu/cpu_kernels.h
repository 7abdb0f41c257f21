// The CPU kernel launchers, compiled once per instruction set (cpu_kernels_<set>.cpp: scalar,
// SSE2 = x86-64, AVX2 = x86-64-v3, AVX-512 = x86-64-v4) and chosen at run time for the processor
// at hand, as OIDN and ISPC do: one binary runs everywhere and uses AVX-512 where the processor
// has it. The scalar copy (the same kernels, not vectorised) is the baseline speed-ups are
// measured against.
#pragma once

#include "devices/cpu/cpu_scratch.h"
#include "devices/cpu/where_keyed.h"
#include "devices/steps.h"
#include "rtdenoise/settings.h"

namespace rtd {

// The kernel forms the CPU device runs (cpu_device.cpp maps the logical steps onto them): planar,
// split into passes that each vectorise. The GPU's forms (interleaved guide, fused passes) are
// run on the CPU by the tests only, through parallelFor2D itself.
#define RTD_FOR_EACH_CPU_KERNEL(X)                \
    X(IngestKernel)                               \
    X(MotionIngestKernel)                         \
    X(ConvertInputKernel)                         \
    X(ViewDepthFromPositionKernel)                \
    X(WriteOutputKernel)                          \
    X(LuminanceRowSumsKernel)                     \
    X(LuminanceRowSumsWideKernel)                 \
    X(ColorRowSumsKernel)                         \
    X(ColorRowSumsWideKernel)                     \
    X(OutlierKernel)                              \
    X(OutlierWideKernel)                          \
    X(OutlierTileKernel)                          \
    X(OutlierClampTileKernel)                     \
    X(JbfKernel)                                  \
    X(JbfNarrowNormalKernel)                      \
    X(AtrousKernel)                               \
    X(AtrousNarrowNormalKernel)                   \
    X(AtrousModulatedKernel)                      \
    X(AtrousNarrowNormalModulatedKernel)          \
    X(GeometryDerivativesKernel)                  \
    X(ReprojectKernel)                            \
    X(AccumulateModulatedKernel)                  \
    X(AccumulateModulatedWideKernel)              \
    X(SvgfReprojectKernel)                        \
    X(SvgfReprojectSearchKernel)                  \
    X(SvgfAccumulateKernel)                       \
    X(SvgfVarianceKernel)                         \
    X(SvgfVarianceNormal128Kernel)                \
    X(SvgfAtrousKernel)                           \
    X(SvgfAtrousNormal128Kernel)                  \
    X(SvgfAtrousModulatedKernel)                  \
    X(SvgfAtrousNormal128ModulatedKernel)         \
    X(DetailReprojectKernel)                      \
    X(DetailReprojectSearchKernel)                \
    X(DetailAccumulateKernel)                     \
    X(DetailAccumulateConfidenceKernel)           \
    X(DetailClampKernel)                          \
    X(DetailScaleKernel)                          \
    X(DetailHistoryFixKernel)                     \
    X(DetailSpecularReprojectKernel)              \
    X(DetailSpecularFollowKernel)                 \
    X(DetailSpecularSurfaceKernel)                \
    X(DetailSplitKernel)                          \
    X(DetailStabiliseKernel)                      \
    X(AddToOutputKernel)                          \
    X(DetailReprojectWhereKeyedKernel)            \
    X(DetailSpecularReprojectWhereKeyedKernel)    \
    X(DetailSpecularFollowWhereKeyedKernel)       \
    X(DetailAccumulateWhereKeyedKernel)           \
    X(DetailAccumulateConfidenceWhereKeyedKernel) \
    X(DetailClampWhereKeyedKernel)                \
    X(DetailScaleWhereKeyedKernel)                \
    X(SvgfAtrousWhereKeyedKernel)                 \
    X(SvgfAtrousNormal128WhereKeyedKernel)        \
    X(AddToOutputWhereKeyedKernel)                \
    X(DetailHistoryFixWhereKeyedKernel)           \
    X(ColorRowSumsWhereKeyedKernel)               \
    X(LuminanceRowSumsWhereKeyedKernel)           \
    X(ModulateKernel)                             \
    X(EnergyInputKernel)                          \
    X(EnergyOutputSumsKernel)                     \
    X(EnergyAccumulateKernel)                     \
    X(EnergyFrameCapKernel)                       \
    X(EnergyTailKernel)                           \
    X(EnergyGainKernel)                           \
    X(EnergyFrameGainKernel)                      \
    X(EnergyApplyKernel)                          \
    X(LearnedMixKernel)

// One entry per kernel: runs it over a width x height grid of pixels on all cores, with the
// device's scratch memory.
struct CpuKernelTable {
    CpuIsa isa;
#define RTD_TABLE_ENTRY(K) \
    void (*run##K)(const K& kernel, int width, int height, CpuScratch& scratch);
    RTD_FOR_EACH_CPU_KERNEL(RTD_TABLE_ENTRY)
#undef RTD_TABLE_ENTRY
};

// The tables this build holds (null where the compiler could not target the instruction set).
const CpuKernelTable* cpuKernelsScalar();
const CpuKernelTable* cpuKernelsSse2();
const CpuKernelTable* cpuKernelsAvx2();
const CpuKernelTable* cpuKernelsAvx512();

// The widest instruction set both this build and this processor support.
CpuIsa bestCpuIsa();
// The table for `isa` (Auto: bestCpuIsa()); throws rtd::Error(DeviceFailure) if the processor
// or this build lacks it.
const CpuKernelTable& cpuKernels(CpuIsa isa);

}  // namespace rtd
