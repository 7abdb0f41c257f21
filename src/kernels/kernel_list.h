// Every kernel a device must be able to launch. Adding a kernel: write its per-pixel functor in
// src/kernels/, add it here; each back end instantiates its launcher from this list.
#pragma once

#include "kernels/accumulate.h"
#include "kernels/atrous.h"
#include "kernels/ingest.h"
#include "kernels/jbf.h"
#include "kernels/modulate.h"
#include "kernels/outlier.h"
#include "kernels/reproject.h"
#include "kernels/svgf.h"
#include "kernels/window_sums.h"

#define RTD_FOR_EACH_KERNEL(X)            \
    X(IngestKernel)                       \
    X(LuminanceRowSumsKernel)             \
    X(LuminanceRowSumsWideKernel)         \
    X(ColorRowSumsKernel)                 \
    X(ColorRowSumsWideKernel)             \
    X(OutlierKernel)                      \
    X(OutlierWideKernel)                  \
    X(JbfKernel)                          \
    X(JbfNarrowNormalKernel)              \
    X(AtrousKernel)                       \
    X(AtrousNarrowNormalKernel)           \
    X(AtrousModulatedKernel)              \
    X(AtrousNarrowNormalModulatedKernel)  \
    X(GeometryDerivativesKernel)          \
    X(ReprojectKernel)                    \
    X(AccumulateKernel)                   \
    X(AccumulateWideKernel)               \
    X(AccumulateModulatedKernel)          \
    X(AccumulateModulatedWideKernel)      \
    X(SvgfReprojectKernel)                \
    X(SvgfReprojectSearchKernel)          \
    X(SvgfAccumulateKernel)               \
    X(SvgfVarianceKernel)                 \
    X(SvgfVarianceNormal128Kernel)        \
    X(SvgfAtrousKernel)                   \
    X(SvgfAtrousNormal128Kernel)          \
    X(SvgfAtrousModulatedKernel)          \
    X(SvgfAtrousNormal128ModulatedKernel) \
    X(ModulateKernel)
