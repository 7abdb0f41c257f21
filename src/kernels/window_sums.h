// Separable window statistics: a row pass sums, over the 2r+1 pixels of each pixel's row window,
// the count of object pixels and their first and second moments; a column pass (the consumer:
// firefly removal, history clamp) sums those over 2r+1 rows. O(r) per pixel instead of O(r^2).
// Background and border pixels do not count. The border rows of the sums stay 0.
//
// The window loops run over a compile-time MaxRadius, fully unrolled, with the taps beyond the
// run-time radius masked out: a loop with a run-time trip count inside the pixel function stops
// the CPU compiler vectorising across pixels (it vectorised the short inner loop instead, many
// times slower). Two widths are built: kNarrowWindow (3, a 7x7 window: every default) and
// kWideWindow (15, the settings' maximum). Taps reach MaxRadius pixels: padding >= MaxRadius.
#pragma once

#include "kernels/views.h"

namespace rtd {

constexpr int kNarrowWindow = 3;
constexpr int kWideWindow = 15;

// 1 for window offsets within the run-time radius, 0 beyond.
RTD_HOST_DEVICE RTD_INLINE float withinRadius(int offset, int radius) {
    return (offset < 0 ? -offset : offset) <= radius ? 1.0f : 0.0f;
}

// The sums over one row window, taps dx in [-radius, radius] (radius <= MaxRadius): maskAt(dx),
// 1 for an object pixel and 0 for background or border; luminanceAt(dx) or colorAt(dx), its
// value. The row passes below and the tile pass (OutlierTile) sum through these.
struct LuminanceSums {
    float count = 0.0f, sum = 0.0f, sumSquares = 0.0f;
    // As planes 0 count, 1 sum, 2 sum of squares at i.
    RTD_HOST_DEVICE RTD_INLINE void storeTo(const PlaneSet& planes, PixelIndex i) const {
        planes.at(0, i) = count;
        planes.at(1, i) = sum;
        planes.at(2, i) = sumSquares;
    }
};
template <int MaxRadius, class MaskAt, class LuminanceAt>
RTD_HOST_DEVICE RTD_INLINE LuminanceSums luminanceRowSums(int radius, MaskAt maskAt,
                                                          LuminanceAt luminanceAt) {
    LuminanceSums s;
    RTD_UNROLL
    for (int dx = -MaxRadius; dx <= MaxRadius; ++dx) {
        float use = maskAt(dx) * withinRadius(dx, radius);
        float l = luminanceAt(dx);
        s.count += use;
        s.sum += use * l;
        s.sumSquares += use * l * l;
    }
    return s;
}
struct ColorSums {
    float count = 0.0f;
    Float3 sum = {0.0f, 0.0f, 0.0f}, sumSquares = {0.0f, 0.0f, 0.0f};
    // As planes 0 count, 1-3 sum, 4-6 sum of squares at i.
    RTD_HOST_DEVICE RTD_INLINE void storeTo(const PlaneSet& planes, PixelIndex i) const {
        planes.at(0, i) = count;
        planes.rgb(1).store(i, sum);
        planes.rgb(4).store(i, sumSquares);
    }
};
template <int MaxRadius, class MaskAt, class ColorAt>
RTD_HOST_DEVICE RTD_INLINE ColorSums colorRowSums(int radius, MaskAt maskAt, ColorAt colorAt) {
    ColorSums s;
    RTD_UNROLL
    for (int dx = -MaxRadius; dx <= MaxRadius; ++dx) {
        float use = maskAt(dx) * withinRadius(dx, radius);
        Float3 c = colorAt(dx) * use;
        s.count += use;
        s.sum += c;
        s.sumSquares += c * c;
    }
    return s;
}

// Planes: 0 count, 1 sum of luminance, 2 sum of luminance^2.
template <int MaxRadius>
struct LuminanceRowSums {
    GBufferView g;
    Planes3 color;
    PlaneSet sums;
    int radius;  // <= MaxRadius

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        PixelIndex i = g.layout.index(x, y);
        luminanceRowSums<MaxRadius>(
            radius, [&](int dx) { return foregroundMask(g.objectId[i + dx]); },
            [&](int dx) { return luminance(color.load(i + dx)); })
            .storeTo(sums, i);
    }
};
using LuminanceRowSumsKernel = LuminanceRowSums<kNarrowWindow>;
using LuminanceRowSumsWideKernel = LuminanceRowSums<kWideWindow>;

// Planes: 0 count, 1-3 sum of R, G, B, 4-6 sum of R^2, G^2, B^2.
template <int MaxRadius>
struct ColorRowSums {
    GBufferView g;
    Planes3 color;
    PlaneSet sums;
    int radius;  // <= MaxRadius

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        PixelIndex i = g.layout.index(x, y);
        colorRowSums<MaxRadius>(
            radius, [&](int dx) { return foregroundMask(g.objectId[i + dx]); },
            [&](int dx) { return color.load(i + dx); })
            .storeTo(sums, i);
    }
};
using ColorRowSumsKernel = ColorRowSums<kNarrowWindow>;
using ColorRowSumsWideKernel = ColorRowSums<kWideWindow>;

// Column pass helper: sums plane `plane` over rows y-r..y+r at pixel index i.
template <int MaxRadius>
RTD_HOST_DEVICE RTD_INLINE float columnSum(const PlaneSet& sums, int plane, PixelIndex i,
                                           PixelIndex pitch, int radius) {
    float total = 0.0f;
    RTD_UNROLL
    for (int dy = -MaxRadius; dy <= MaxRadius; ++dy)
        total += sums.at(plane, i + dy * pitch) * withinRadius(dy, radius);
    return total;
}

// Per-channel mean and standard deviation of the object pixels in pixel i's (2r+1)^2 window,
// from ColorRowSums' planes.
struct ColorWindowStats {
    Float3 mean, sigma;
    float count;  // object pixels in the window (at least 1 reported, to divide by)
};

template <int MaxRadius>
RTD_HOST_DEVICE RTD_INLINE ColorWindowStats colorWindowStats(const PlaneSet& rowSums, PixelIndex i,
                                                             PixelIndex pitch, int radius) {
    ColorWindowStats s;
    s.count = maxf(columnSum<MaxRadius>(rowSums, 0, i, pitch, radius), 1.0f);
    float inv = 1.0f / s.count;
    Float3 mean = make3(columnSum<MaxRadius>(rowSums, 1, i, pitch, radius),
                        columnSum<MaxRadius>(rowSums, 2, i, pitch, radius),
                        columnSum<MaxRadius>(rowSums, 3, i, pitch, radius)) *
                  inv;
    Float3 meanSquare = make3(columnSum<MaxRadius>(rowSums, 4, i, pitch, radius),
                              columnSum<MaxRadius>(rowSums, 5, i, pitch, radius),
                              columnSum<MaxRadius>(rowSums, 6, i, pitch, radius)) *
                        inv;
    s.mean = mean;
    s.sigma = make3(std::sqrt(maxf(meanSquare.x - mean.x * mean.x, 0.0f)),
                    std::sqrt(maxf(meanSquare.y - mean.y * mean.y, 0.0f)),
                    std::sqrt(maxf(meanSquare.z - mean.z * mean.z, 0.0f)));
    return s;
}

}  // namespace rtd
