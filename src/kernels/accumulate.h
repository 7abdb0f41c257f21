// Temporal accumulation (assignment formula): C_i = a C_i + (1 - a) Clamp(C_{i-1}), the history
// clamped per channel to mu +- k sigma of the current filtered frame's neighbourhood; a = 1
// where the history is invalid.
#pragma once

#include "kernels/reproject.h"
#include "kernels/views.h"

namespace rtd {

struct AccumulateKernel {
    int width, height;
    Planes3 current;      // this frame, spatially filtered
    Planes3 reprojected;  // history at this pixel
    const std::uint8_t* validity;
    Planes3 out;
    float alpha;
    float clampK;
    int radius;

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        std::size_t i = std::size_t(y) * width + x;
        Float3 c = current.load(i);
        if (validity[i] != kReprojectionValid) {
            out.store(i, c);
            return;
        }
        Float3 sum, sum2;
        float count = 0.0f;
        int x0 = maxi(x - radius, 0), x1 = mini(x + radius, width - 1);
        int y0 = maxi(y - radius, 0), y1 = mini(y + radius, height - 1);
        for (int yy = y0; yy <= y1; ++yy) {
            for (int xx = x0; xx <= x1; ++xx) {
                Float3 v = current.load(std::size_t(yy) * width + xx);
                sum += v;
                sum2 += v * v;
                count += 1.0f;
            }
        }
        float inv = 1.0f / count;
        Float3 mean = sum * inv;
        Float3 variance = sum2 * inv - mean * mean;
        Float3 sigma = make3(std::sqrt(maxf(variance.x, 0.0f)), std::sqrt(maxf(variance.y, 0.0f)),
                             std::sqrt(maxf(variance.z, 0.0f)));
        Float3 history = clamp3(reprojected.load(i), mean - sigma * clampK, mean + sigma * clampK);
        out.store(i, c * alpha + history * (1.0f - alpha));
    }
};

}  // namespace rtd
