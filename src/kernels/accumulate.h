// Temporal accumulation (assignment formula): C_i = a C_i + (1 - a) Clamp(C_{i-1}), the history
// clamped per channel to mu +- k sigma of the current filtered frame's (2r+1)^2 neighbourhood
// (its object pixels: background and the border do not count); a = 1 where the history is
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
        const Layout& L = g.layout;
        PixelIndex i = L.index(x, y);
        Float3 c = current.load(i);
        // Branch-free (the CPU vectorises it): invalid history gets weight 0 (a = 1).
        float a = validity[i] == kReprojectionValid ? alpha : 1.0f;
        ColorWindowStats w = colorWindowStats<MaxRadius>(rowSums, i, L.pitch, radius);
        Float3 history =
            clamp3(reprojected.load(i), w.mean - w.sigma * clampK, w.mean + w.sigma * clampK);
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

}  // namespace rtd
