// Final modulation: the filtered illumination times the albedo factor the ingest divided by
// (1 without an albedo, and for background, which was never demodulated), written out.
#pragma once

#include "kernels/views.h"

namespace rtd {

// One pixel of the caller's interleaved RGB (rows of `width` pixels).
RTD_HOST_DEVICE RTD_INLINE void storeModulated(const Layout& layout, float* rgbOut, int x, int y,
                                               Float3 c) {
    PixelIndex s = PixelIndex(y) * layout.width + x;
    rgbOut[3 * s] = c.x;
    rgbOut[3 * s + 1] = c.y;
    rgbOut[3 * s + 2] = c.z;
}

// Fused with the output: writes the caller's interleaved RGB (rows of `width` pixels) directly,
// one pass over the result instead of a modulate pass and a packing pass.
struct ModulateKernel {
    Layout layout;
    Planes3 illumination;
    Planes3 albedo;  // the factor, already floored at epsilon by the ingest
    float* rgbOut;   // interleaved, 3 floats per pixel

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        PixelIndex i = layout.index(x, y);
        storeModulated(layout, rgbOut, x, y, illumination.load(i) * albedo.load(i));
    }
};

}  // namespace rtd
