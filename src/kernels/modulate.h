// Final modulation: the filtered illumination times the albedo factor the ingest divided by
// (1 without an albedo, and for background, which was never demodulated).
#pragma once

#include "kernels/views.h"

namespace rtd {

struct ModulateKernel {
    Layout layout;
    Planes3 illumination;
    Planes3 albedo;  // the factor, already floored at epsilon by the ingest
    Planes3 out;     // may be `illumination` itself

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        PixelIndex i = layout.index(x, y);
        out.store(i, illumination.load(i) * albedo.load(i));
    }
};

}  // namespace rtd
