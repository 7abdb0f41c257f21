// Separable window statistics: a row pass sums, over the 2r+1 pixels of each pixel's row window,
// the count of object pixels and their first and second moments; a column pass (the consumer:
// firefly removal, history clamp) sums those over 2r+1 rows. O(r) per pixel instead of O(r^2).
// Background and border pixels do not count. The border rows of the sums stay 0.
#pragma once

#include "kernels/views.h"

namespace rtd {

// Planes: 0 count, 1 sum of luminance, 2 sum of luminance^2.
struct LuminanceRowSumsKernel {
    GBufferView g;
    Planes3 color;
    PlaneSet sums;
    int radius;  // <= layout.padding

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        PixelIndex i = g.layout.index(x, y);
        float count = 0.0f, sum = 0.0f, sum2 = 0.0f;
        for (int dx = -radius; dx <= radius; ++dx) {
            float use = foregroundMask(g.objectId[i + dx]);
            float l = luminance(color.load(i + dx));
            count += use;
            sum += use * l;
            sum2 += use * l * l;
        }
        sums.at(0, i) = count;
        sums.at(1, i) = sum;
        sums.at(2, i) = sum2;
    }
};

// Planes: 0 count, 1-3 sum of R, G, B, 4-6 sum of R^2, G^2, B^2.
struct ColorRowSumsKernel {
    GBufferView g;
    Planes3 color;
    PlaneSet sums;
    int radius;  // <= layout.padding

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        PixelIndex i = g.layout.index(x, y);
        float s[7] = {0, 0, 0, 0, 0, 0, 0};
        for (int dx = -radius; dx <= radius; ++dx) {
            float use = foregroundMask(g.objectId[i + dx]);
            Float3 c = color.load(i + dx) * use;
            s[0] += use;
            s[1] += c.x;
            s[2] += c.y;
            s[3] += c.z;
            s[4] += c.x * c.x;
            s[5] += c.y * c.y;
            s[6] += c.z * c.z;
        }
        for (int k = 0; k < 7; ++k) sums.at(k, i) = s[k];
    }
};

// Column pass helper: sums plane `plane` over rows y-r..y+r at pixel index i.
RTD_HOST_DEVICE RTD_INLINE float columnSum(const PlaneSet& sums, int plane, PixelIndex i, PixelIndex pitch,
                                           int radius) {
    float total = 0.0f;
    for (int dy = -radius; dy <= radius; ++dy) total += sums.at(plane, i + dy * pitch);
    return total;
}

// Per-channel mean and standard deviation of the object pixels in pixel i's (2r+1)^2 window,
// from ColorRowSumsKernel's planes.
struct ColorWindowStats {
    Float3 mean, sigma;
    float count;  // object pixels in the window (at least 1 reported, to divide by)
};

RTD_HOST_DEVICE RTD_INLINE ColorWindowStats colorWindowStats(const PlaneSet& rowSums, PixelIndex i,
                                                             int pitch, int radius) {
    ColorWindowStats s;
    s.count = maxf(columnSum(rowSums, 0, i, pitch, radius), 1.0f);
    float inv = 1.0f / s.count;
    float m[3], sd[3];
    for (int ch = 0; ch < 3; ++ch) {
        m[ch] = columnSum(rowSums, 1 + ch, i, pitch, radius) * inv;
        float meanSquare = columnSum(rowSums, 4 + ch, i, pitch, radius) * inv;
        sd[ch] = std::sqrt(maxf(meanSquare - m[ch] * m[ch], 0.0f));
    }
    s.mean = make3(m[0], m[1], m[2]);
    s.sigma = make3(sd[0], sd[1], sd[2]);
    return s;
}

}  // namespace rtd
