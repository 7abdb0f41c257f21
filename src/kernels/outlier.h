// Firefly removal (shared/seeds/002): a pixel's luminance is clamped to mean + k * stddev of the
// luminance of the object pixels in its (2r+1)^2 window; the colour is scaled, keeping its hue.
// Background passes through. Runs after LuminanceRowSumsKernel (the column half of the window).
#pragma once

#include "kernels/window_sums.h"

namespace rtd {

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
        Float3 c = in.load(i);
        float count = maxf(columnSum<MaxRadius>(rowSums, 0, i, L.pitch, radius), 1.0f);
        float mean = columnSum<MaxRadius>(rowSums, 1, i, L.pitch, radius) / count;
        float variance =
            maxf(columnSum<MaxRadius>(rowSums, 2, i, L.pitch, radius) / count - mean * mean, 0.0f);
        float limit = mean + k * std::sqrt(variance);
        float l = luminance(c);
        // Background keeps its value (its window statistics are not its own).
        float scale = g.objectId[i] >= 0 && l > limit && l > 0.0f ? limit / l : 1.0f;
        out.store(i, c * scale);
    }
};
using OutlierKernel = Outlier<kNarrowWindow>;
using OutlierWideKernel = Outlier<kWideWindow>;

}  // namespace rtd
