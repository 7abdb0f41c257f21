// A kernel run by the CPU launcher only on runs of pixels with a key >= 0: the split signal's
// specular passes, whose images hold nothing where the lobe is not kept apart (their object IDs
// and filter keys are -1 there, DetailSplitKernel). Those pixels' outputs are left as they were:
// every reader of them masks them out by those IDs and keys. The CUDA device runs the kernels
// themselves (every pixel; the same results where a key is >= 0).
#pragma once

#include <cstdint>

#include "kernels/detail.h"
#include "kernels/launch_traits.h"
#include "kernels/svgf.h"
#include "kernels/window_sums.h"

namespace rtd {

// Reach: rows above and below whose keys count too (a pass whose outputs are read that far up
// and down by the keyed pixels, the window sums' row pass). A kernel's own active() (a
// block-sparse one) must hold as well.
template <class Kernel, int Reach = 0>
struct WhereKeyed {
    Kernel kernel;
    Layout layout;
    const std::int32_t* key;

    bool active(int x, int y) const {
        bool keyed = false;
        for (int dy = -Reach; dy <= Reach; ++dy) keyed |= key[layout.index(x, y + dy)] >= 0;
        if constexpr (requires(const Kernel& k) { k.active(0, 0); })
            return keyed && kernel.active(x, y);
        else
            return keyed;
    }
    RTD_INLINE void operator()(int x, int y) const { kernel(x, y); }
    int tapRowStride() const requires kHasTapRowStride<Kernel> { return kernel.tapRowStride(); }
    std::int32_t runKey(int x, int y) const requires requires(const Kernel& k) { k.runKey(0, 0); }
    { return kernel.runKey(x, y); }
    template <bool KnownKey>
    RTD_INLINE void pixel(int x, int y, std::int32_t runKey) const requires
        requires(const Kernel& k) {
        k.runKey(0, 0);
    }
    { kernel.template pixel<KnownKey>(x, y, runKey); }
};

// The rows whose keys count for each kernel (WhereKeyed's Reach): the clamp's window sums are
// read by DetailClamp's column sums, kRadius rows up and down.
template <class Kernel>
inline constexpr int kKeyedReach = 0;
template <>
inline constexpr int kKeyedReach<ColorRowSumsKernel> = DetailClampKernel::kRadius;
template <>
inline constexpr int kKeyedReach<LuminanceRowSumsKernel> = DetailClampKernel::kRadius;

using DetailReprojectWhereKeyedKernel = WhereKeyed<DetailReprojectKernel>;
using DetailSpecularReprojectWhereKeyedKernel = WhereKeyed<DetailSpecularReprojectKernel>;
using DetailSpecularFollowWhereKeyedKernel = WhereKeyed<DetailSpecularFollowKernel>;
using DetailAccumulateWhereKeyedKernel = WhereKeyed<DetailAccumulateKernel>;
using DetailAccumulateConfidenceWhereKeyedKernel = WhereKeyed<DetailAccumulateConfidenceKernel>;
using DetailClampWhereKeyedKernel = WhereKeyed<DetailClampKernel>;
using DetailScaleWhereKeyedKernel = WhereKeyed<DetailScaleKernel>;
using SvgfAtrousWhereKeyedKernel = WhereKeyed<SvgfAtrousKernel>;
using SvgfAtrousNormal128WhereKeyedKernel = WhereKeyed<SvgfAtrousNormal128Kernel>;
using AddToOutputWhereKeyedKernel = WhereKeyed<AddToOutputKernel>;
using DetailHistoryFixWhereKeyedKernel = WhereKeyed<DetailHistoryFixKernel>;
using ColorRowSumsWhereKeyedKernel =
    WhereKeyed<ColorRowSumsKernel, kKeyedReach<ColorRowSumsKernel>>;
using LuminanceRowSumsWhereKeyedKernel =
    WhereKeyed<LuminanceRowSumsKernel, kKeyedReach<LuminanceRowSumsKernel>>;

}  // namespace rtd
