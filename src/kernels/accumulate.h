// Temporal accumulation (assignment formula): C_i = a C_i + (1 - a) Clamp(C_{i-1}), the history
// clamped per channel to mu +- k sigma of the current filtered frame's (2r+1)^2 neighbourhood
// (its object pixels: background and the border do not count), grown to hold the pixel's own
// value (a small light's history lies far above its window's box); a = 1 where the history is
// invalid. Runs after ColorRowSumsKernel (the column half of the window).
#pragma once

#include "kernels/modulate.h"
#include "kernels/reproject.h"
#include "kernels/window_sums.h"

namespace rtd {

// Modulated: also writes the result times the albedo factor into the caller's interleaved RGB
// (ModulateKernel's job, fused: the result is not read back from memory).
template <int MaxRadius, bool Modulated = false>
struct Accumulate {
    GBufferView g;
    PlaneSet rowSums;     // from ColorRowSums<MaxRadius> over `current`
    Planes3 current;      // this frame, spatially filtered
    Planes3 reprojected;  // history at this pixel
    const std::uint8_t* validity;
    Planes3 out;
    float alpha;
    float clampK;
    int radius;               // <= MaxRadius
    Planes3 albedo = {};      // Modulated only
    float* rgbOut = nullptr;  // Modulated only: interleaved, 3 floats per pixel

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        PixelIndex i = g.layout.index(x, y);
        blend(x, y, i, reprojected.load(i), validity[i] == kReprojectionValid);
    }
    // The blend with pixel i's reprojected history given (ReprojectAccumulate: in registers).
    RTD_HOST_DEVICE RTD_INLINE void blend(int x, int y, PixelIndex i, Float3 reprojectedHistory,
                                          bool valid) const {
        const Layout& L = g.layout;
        Float3 c = current.load(i);
        // Branch-free (the CPU vectorises it): invalid history gets weight 0 (a = 1).
        float a = valid ? alpha : 1.0f;
        ColorWindowStats w = colorWindowStats<MaxRadius>(rowSums, i, L.pitch, radius);
        Float3 history = clampToBoxHolding(reprojectedHistory, w.mean - w.sigma * clampK,
                                           w.mean + w.sigma * clampK, c);
        Float3 result = c * a + history * (1.0f - a);
        out.store(i, result);
        if constexpr (Modulated) storeModulated(L, rgbOut, x, y, result * albedo.load(i));
    }
};
using AccumulateKernel = Accumulate<kNarrowWindow>;
using AccumulateWideKernel = Accumulate<kWideWindow>;
template <int MaxRadius>
using AccumulateModulated = Accumulate<MaxRadius, true>;
using AccumulateModulatedKernel = AccumulateModulated<kNarrowWindow>;
using AccumulateModulatedWideKernel = AccumulateModulated<kWideWindow>;

// The reprojection and the (modulated) accumulation as one pass, the temporal stage's fused form
// (a GPU's, cuda_device.cu): the history stays in registers instead of going through the
// reprojected planes and back (as SvgfTemporal does for SVGF), and the depth slopes and normal
// change the history test needs are computed here from the neighbours (GeometryDerivatives)
// instead of read from a geometry pass's planes. Its `reproject.derivatives` and
// `reproject.reprojected`, `accumulate.reprojected` and `accumulate.validity` are unused.
template <int MaxRadius>
struct ReprojectAccumulate {
    ReprojectKernel reproject;
    AccumulateModulated<MaxRadius> accumulate;

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        PixelIndex i = reproject.g.layout.index(x, y);
        std::uint8_t code;
        GeometrySlopes slopes = GeometryDerivativesKernel{reproject.g, {}}.slopes(i);
        Float3 history = reproject.sample<false>(i, 0, code, slopes);
        reproject.validity[i] = code;
        accumulate.blend(x, y, i, history, code == kReprojectionValid);
    }
};
using ReprojectAccumulateKernel = ReprojectAccumulate<kNarrowWindow>;
using ReprojectAccumulateWideKernel = ReprojectAccumulate<kWideWindow>;

}  // namespace rtd
