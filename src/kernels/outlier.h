// Firefly removal (shared/seeds/002): a pixel's luminance is clamped to mean + k * stddev of the
// luminance of the other object pixels in its (2r+1)^2 window; the colour is scaled, keeping its
// hue. A light seen directly is kept (brightLikeItsObject).
// Background passes through. Runs after LuminanceRowSumsKernel (the column half of the window).
#pragma once

#include "kernels/window_sums.h"

namespace rtd {

// The firefly limit of a pixel of luminance l: mean + k * stddev of the luminance of the other
// object pixels of its window (their count, sum and sum of squares: the window's less its own).
// Leaving the pixel out matters: with it, a lone bright pixel widens its own limit to about
// (1 + k sqrt(n - 1)) / n of itself (0.31 for a 7x7 window, k 2) and survives. Where it dominates
// the float sums, the differences keep their rounding of it: a looser limit, still far below it,
// and finite.
struct FireflyLimit {
    float limit;
    float others;  // object pixels in the window besides this one
};
RTD_HOST_DEVICE RTD_INLINE FireflyLimit fireflyLimit(float l, float count, float sum,
                                                     float sumSquares, float k) {
    const float others = count - 1.0f;
    const float n = maxf(others, 1.0f);
    const float mean = maxf(sum - l, 0.0f) / n;
    const float variance = maxf(maxf(sumSquares - l * l, 0.0f) / n - mean * mean, 0.0f);
    return {mean + k * std::sqrt(variance), others};
}

// Whether luminance l is over `factor` times its firefly limit, where the removal applies at all
// (an object pixel with another object pixel in its window).
RTD_HOST_DEVICE RTD_INLINE bool overLimit(float l, bool foreground, FireflyLimit f, float factor) {
    return foreground & (f.others >= 0.5f) & (l > factor * f.limit) & (l > 0.0f);
}

// Colour c with its luminance clamped to its firefly limit, its hue kept. Background, a pixel
// with no other object pixel around, and a light (`kept`: brightLikeItsObject) keep their value.
RTD_HOST_DEVICE RTD_INLINE Float3 despeckle(Float3 c, bool foreground, FireflyLimit f, bool kept) {
    const float l = luminance(c);
    const bool clamp = overLimit(l, foreground, f, 1.0f) & !kept;
    return c * (clamp ? f.limit / l : 1.0f);
}

// 1 where c is over twice its firefly limit (kept as a light or not), else 0: the detail
// method's evidence of a light (DetailAccumulate). Twice, not once: in a dark area a sample just
// over its limit the frame before a firefly made that firefly a light (docs/energy.md).
constexpr float kAboveLimitFactor = 2.0f;
RTD_HOST_DEVICE RTD_INLINE float aboveLimit(Float3 c, bool foreground, FireflyLimit f) {
    return overLimit(luminance(c), foreground, f, kAboveLimitFactor) ? 1.0f : 0.0f;
}

// Whether the pixel at i, above its firefly limit, is bright like its object rather than a
// firefly on it: at least half of the other pixels of its object in its 5x5 are above the limit
// and half as bright, or none is there (a light a pixel wide). A light seen directly is the
// frame's brightest and, to the window's statistics, a firefly: small lights lost most of their
// light (issue 38). A light's pixels are bright together; noise above the limit is sparse on its
// surface, if at times side by side (a rule that kept a pixel beside one bright neighbour kept
// such noise: docs/energy.md). Reads the border (ID -1; padding >= 2) at the image's edge.
RTD_HOST_DEVICE RTD_INLINE bool brightLikeItsObject(const GBufferView& g, const Planes3& in,
                                                    PixelIndex i, float limit) {
    const std::int32_t id = g.objectId[i];
    const float threshold = maxf(0.5f * luminance(in.load(i)), limit);
    float own = 0.0f, bright = 0.0f;
    RTD_UNROLL
    for (int dy = -2; dy <= 2; ++dy) {
        RTD_UNROLL
        for (int dx = -2; dx <= 2; ++dx) {
            const PixelIndex j = i + g.layout.offset(dx, dy);
            const float same = static_cast<float>(g.objectId[j] == id);
            own += same;
            bright += same * static_cast<float>(luminance(in.load(j)) > threshold);
        }
    }
    // The pixel itself is counted in both (above the limit, it is above the threshold): of the
    // others, at least half bright, or none there.
    return 2.0f * bright >= own + 1.0f;
}

template <int MaxRadius>
struct Outlier {
    GBufferView g;
    PlaneSet rowSums;  // from LuminanceRowSums<MaxRadius>
    Planes3 in, out;
    int radius;  // <= MaxRadius
    float k;
    float* above = nullptr;  // out, optional: aboveLimit's mark (1 or 0)

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        const Layout& L = g.layout;
        PixelIndex i = L.index(x, y);
        const Float3 c = in.load(i);
        const FireflyLimit f =
            fireflyLimit(luminance(c), columnSum<MaxRadius>(rowSums, 0, i, L.pitch, radius),
                         columnSum<MaxRadius>(rowSums, 1, i, L.pitch, radius),
                         columnSum<MaxRadius>(rowSums, 2, i, L.pitch, radius), k);
        out.store(i, despeckle(c, g.objectId[i] >= 0, f, brightLikeItsObject(g, in, i, f.limit)));
        if (above) above[i] = aboveLimit(c, g.objectId[i] >= 0, f);
    }
};
using OutlierKernel = Outlier<kNarrowWindow>;
using OutlierWideKernel = Outlier<kWideWindow>;

}  // namespace rtd
