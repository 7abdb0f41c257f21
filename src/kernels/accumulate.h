// Temporal accumulation (assignment formula): C_i = a C_i + (1 - a) Clamp(C_{i-1}), the history
// clamped per channel to mu +- k sigma of the current filtered frame's neighbourhood (its object
// pixels: background and the border do not count); a = 1 where the history is invalid.
#pragma once

#include "kernels/reproject.h"
#include "kernels/views.h"

namespace rtd {

struct AccumulateKernel {
    GBufferView g;
    Planes3 current;      // this frame, spatially filtered
    Planes3 reprojected;  // history at this pixel
    const std::uint8_t* validity;
    Planes3 out;
    float alpha;
    float clampK;
    int radius;  // <= layout.padding

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        const Layout& L = g.layout;
        int i = L.index(x, y);
        Float3 c = current.load(i);
        if (validity[i] != kReprojectionValid) {
            out.store(i, c);
            return;
        }
        float sumR = 0.0f, sumG = 0.0f, sumB = 0.0f, sum2R = 0.0f, sum2G = 0.0f, sum2B = 0.0f;
        float count = 0.0f;
        for (int dy = -radius; dy <= radius; ++dy) {
            int row = i + L.offset(0, dy);
            RTD_VECTORIZE
            for (int dx = -radius; dx <= radius; ++dx) {
                int j = row + dx;
                float use = foregroundMask(g.objectId[j]);
                Float3 v = current.load(j);
                sumR += use * v.x;
                sumG += use * v.y;
                sumB += use * v.z;
                sum2R += use * v.x * v.x;
                sum2G += use * v.y * v.y;
                sum2B += use * v.z * v.z;
                count += use;
            }
        }
        float inv = 1.0f / count;  // count >= 1: a valid pixel is an object pixel
        Float3 mean = make3(sumR, sumG, sumB) * inv;
        Float3 variance = make3(sum2R, sum2G, sum2B) * inv - mean * mean;
        Float3 sigma = make3(std::sqrt(maxf(variance.x, 0.0f)), std::sqrt(maxf(variance.y, 0.0f)),
                             std::sqrt(maxf(variance.z, 0.0f)));
        Float3 history = clamp3(reprojected.load(i), mean - sigma * clampK, mean + sigma * clampK);
        out.store(i, c * alpha + history * (1.0f - alpha));
    }
};

}  // namespace rtd
