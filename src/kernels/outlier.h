// Firefly removal (shared/seeds/002): a pixel's luminance is clamped to mean + k * stddev of the
// luminance of the other object pixels in its (2r+1)^2 window; the colour is scaled, keeping its
// hue.
// Background passes through. Runs after LuminanceRowSumsKernel (the column half of the window).
#pragma once

#include "kernels/window_sums.h"

namespace rtd {

// Colour c with its luminance clamped to mean + k * stddev of the luminance of the other object
// pixels of its window (their count, sum and sum of squares: the window's less c's own), its hue
// kept. Leaving the pixel out matters: with it, a lone bright pixel widens its own limit to about
// (1 + k sqrt(n - 1)) / n of itself (0.31 for a 7x7 window, k 2) and survives. Where it dominates
// the float sums, the differences keep their rounding of it: a looser limit, still far below it,
// and finite. Background, and a pixel with no other object pixel around, keep their value.
RTD_HOST_DEVICE RTD_INLINE Float3 despeckle(Float3 c, bool foreground, float count, float sum,
                                            float sumSquares, float k) {
    const float l = luminance(c);
    const float others = count - 1.0f;
    const float n = maxf(others, 1.0f);
    const float mean = maxf(sum - l, 0.0f) / n;
    const float variance = maxf(maxf(sumSquares - l * l, 0.0f) / n - mean * mean, 0.0f);
    const float limit = mean + k * std::sqrt(variance);
    const float scale = foreground && others >= 0.5f && l > limit && l > 0.0f ? limit / l : 1.0f;
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
