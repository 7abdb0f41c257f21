// Firefly removal (shared/seeds/002): a pixel's luminance is clamped to mean + k * stddev of the
// luminance of the object pixels in its (2r+1)^2 window; the colour is scaled, keeping its hue.
// Background passes through. Runs after LuminanceRowSumsKernel (the column half of the window).
#pragma once

#include "kernels/window_sums.h"

namespace rtd {

// Colour c with its luminance clamped to mean + k * stddev of its window's luminance (the window's
// object pixels: their count, sum and sum of squares), its hue kept. Background keeps its value
// (its window statistics are not its own).
RTD_HOST_DEVICE RTD_INLINE Float3 despeckle(Float3 c, bool foreground, float count, float sum,
                                            float sumSquares, float k) {
    count = maxf(count, 1.0f);
    float mean = sum / count;
    float variance = maxf(sumSquares / count - mean * mean, 0.0f);
    float limit = mean + k * std::sqrt(variance);
    float l = luminance(c);
    float scale = foreground && l > limit && l > 0.0f ? limit / l : 1.0f;
    return c * scale;
}

template <int MaxRadius>
struct Outlier {
    GBufferView g;
    PlaneSet rowSums;  // from LuminanceRowSums<MaxRadius>
    Planes3 in, out;
    int radius;  // <= MaxRadius
    float k;

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        const Layout& L = g.layout;
        PixelIndex i = L.index(x, y);
        out.store(i, despeckle(in.load(i), g.objectId[i] >= 0,
                               columnSum<MaxRadius>(rowSums, 0, i, L.pitch, radius),
                               columnSum<MaxRadius>(rowSums, 1, i, L.pitch, radius),
                               columnSum<MaxRadius>(rowSums, 2, i, L.pitch, radius), k));
    }
};
using OutlierKernel = Outlier<kNarrowWindow>;
using OutlierWideKernel = Outlier<kWideWindow>;

}  // namespace rtd
