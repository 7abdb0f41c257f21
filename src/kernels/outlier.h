// Firefly removal (shared/seeds/002): a pixel's luminance is clamped to mean + k * stddev of the
// luminance of the other object pixels in its (2r+1)^2 window; the colour is scaled, keeping its
// hue. A light seen directly is kept (brightLikeItsObject).
// Background passes through. Runs after LuminanceRowSumsKernel (the column half of the window).
#pragma once

#include "kernels/window_sums.h"

namespace rtd {

// Colour c with its luminance clamped to mean + k * stddev of the luminance of the other object
// pixels of its window (their count, sum and sum of squares: the window's less c's own), its hue
// kept. Leaving the pixel out matters: with it, a lone bright pixel widens its own limit to about
// (1 + k sqrt(n - 1)) / n of itself (0.31 for a 7x7 window, k 2) and survives. Where it dominates
// the float sums, the differences keep their rounding of it: a looser limit, still far below it,
// and finite. Background, a pixel with no other object pixel around, and one `kept`
// (brightLikeItsObject) keep their value.
RTD_HOST_DEVICE RTD_INLINE Float3 despeckle(Float3 c, bool foreground, float count, float sum,
                                            float sumSquares, float k, bool kept = false) {
    const float l = luminance(c);
    const float others = count - 1.0f;
    const float n = maxf(others, 1.0f);
    const float mean = maxf(sum - l, 0.0f) / n;
    const float variance = maxf(maxf(sumSquares - l * l, 0.0f) / n - mean * mean, 0.0f);
    const float limit = mean + k * std::sqrt(variance);
    const float scale =
        foreground && !kept && others >= 0.5f && l > limit && l > 0.0f ? limit / l : 1.0f;
    return c * scale;
}

// Whether the pixel at i is bright like its object rather than a firefly on it: no other pixel
// of its object is in its 5x5 (a light a pixel wide), or one in its 3x3 is at least half as
// bright (a wider light or highlight). A light seen directly is the frame's brightest and, to the
// window's statistics, a firefly: small lights lost up to 60 % of their light (issue 38). A lone
// noise sample on a surface is rarely beside one of its own size. Allowing objects of up to 4
// pixels kept 0.3 % more light on the train set for 3 % more relMSE (docs/energy.md). Reads the
// border (ID -1; padding >= 3) at the image's edge.
RTD_HOST_DEVICE RTD_INLINE bool brightLikeItsObject(const GBufferView& g, const Planes3& in,
                                                    PixelIndex i) {
    const std::int32_t id = g.objectId[i];
    const float half = 0.5f * luminance(in.load(i));
    bool alone = true, asBright = false;
    RTD_UNROLL
    for (int dy = -2; dy <= 2; ++dy) {
        RTD_UNROLL
        for (int dx = -2; dx <= 2; ++dx) {
            if (dx == 0 && dy == 0) continue;
            const PixelIndex j = i + g.layout.offset(dx, dy);
            const bool same = g.objectId[j] == id;
            alone = alone & !same;
            if (dx >= -1 && dx <= 1 && dy >= -1 && dy <= 1)
                asBright = asBright | (same & (luminance(in.load(j)) >= half));
        }
    }
    return alone | asBright;
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
                               columnSum<MaxRadius>(rowSums, 2, i, L.pitch, radius), k,
                               brightLikeItsObject(g, in, i)));
    }
};
using OutlierKernel = Outlier<kNarrowWindow>;
using OutlierWideKernel = Outlier<kWideWindow>;

}  // namespace rtd
