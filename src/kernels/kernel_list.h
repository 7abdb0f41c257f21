// Every kernel a device must be able to launch. Adding a kernel: write its per-pixel functor in
// src/kernels/, add it here; each back end instantiates its launcher from this list.
#pragma once

#include <type_traits>
#include <utility>

#include "kernels/accumulate.h"
#include "kernels/atrous.h"
#include "kernels/ingest.h"
#include "kernels/jbf.h"
#include "kernels/modulate.h"
#include "kernels/outlier.h"
#include "kernels/outlier_tile.h"
#include "kernels/reproject.h"
#include "kernels/svgf.h"
#include "kernels/window_sums.h"

namespace rtd {

// A kernel with `int tapRowStride() const` reads rows y + k * stride, |k| <= 2 (an A-Trous
// level); launchers order or shape their work by it. In C++17 form: the CUDA back end's
// translation unit is C++17.
template <class Kernel, class = void>
inline constexpr bool kHasTapRowStride = false;
template <class Kernel>
inline constexpr bool
    kHasTapRowStride<Kernel, std::void_t<decltype(std::declval<const Kernel&>().tapRowStride())>> =
        true;

}  // namespace rtd

#define RTD_FOR_EACH_KERNEL(X)              \
    X(IngestKernel)                         \
    X(IngestInterleavedKernel)              \
    X(LuminanceRowSumsKernel)               \
    X(LuminanceRowSumsWideKernel)           \
    X(ColorRowSumsKernel)                   \
    X(ColorRowSumsWideKernel)               \
    X(OutlierKernel)                        \
    X(OutlierWideKernel)                    \
    X(OutlierTileKernel)                    \
    X(OutlierClampTileKernel)               \
    X(JbfKernel)                            \
    X(JbfNarrowNormalKernel)                \
    X(AtrousKernel)                         \
    X(AtrousNarrowNormalKernel)             \
    X(AtrousModulatedKernel)                \
    X(AtrousNarrowNormalModulatedKernel)    \
    X(GeometryDerivativesKernel)            \
    X(GeometryDerivativesInterleavedKernel) \
    X(ReprojectKernel)                      \
    X(AccumulateKernel)                     \
    X(AccumulateWideKernel)                 \
    X(AccumulateModulatedKernel)            \
    X(AccumulateModulatedWideKernel)        \
    X(ReprojectAccumulateKernel)            \
    X(ReprojectAccumulateWideKernel)        \
    X(SvgfReprojectKernel)                  \
    X(SvgfReprojectSearchKernel)            \
    X(SvgfAccumulateKernel)                 \
    X(SvgfTemporalKernel)                   \
    X(SvgfTemporalInterleavedKernel)        \
    X(SvgfVarianceKernel)                   \
    X(SvgfVarianceNormal128Kernel)          \
    X(SvgfVarianceInterleavedKernel)        \
    X(SvgfAtrousKernel)                     \
    X(SvgfAtrousNormal128Kernel)            \
    X(SvgfAtrousModulatedKernel)            \
    X(SvgfAtrousNormal128ModulatedKernel)   \
    X(SvgfAtrousInterleavedKernel)          \
    X(SvgfAtrousInterleavedModulatedKernel) \
    X(ModulateKernel)
