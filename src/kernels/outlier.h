// Firefly removal (shared/seeds/002): a pixel's luminance is clamped to mean + k * stddev of the
// luminance in its window; the colour is scaled, keeping its hue. Background passes through.
#pragma once

#include "kernels/views.h"

namespace rtd {

struct OutlierKernel {
    GBufferView g;
    Planes3 in, out;
    int radius;
    float k;

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        std::size_t i = g.index(x, y);
        Float3 c = in.load(i);
        if (g.objectId[i] < 0) {
            out.store(i, c);
            return;
        }
        float sum = 0.0f, sum2 = 0.0f, count = 0.0f;
        int x0 = maxi(x - radius, 0), x1 = mini(x + radius, g.width - 1);
        int y0 = maxi(y - radius, 0), y1 = mini(y + radius, g.height - 1);
        for (int yy = y0; yy <= y1; ++yy) {
            for (int xx = x0; xx <= x1; ++xx) {
                std::size_t j = g.index(xx, yy);
                float use = g.objectId[j] >= 0 ? 1.0f : 0.0f;
                float l = luminance(in.load(j));
                sum += use * l;
                sum2 += use * l * l;
                count += use;
            }
        }
        float mean = sum / count;  // count >= 1: the centre is foreground
        float variance = maxf(sum2 / count - mean * mean, 0.0f);
        float limit = mean + k * std::sqrt(variance);
        float l = luminance(c);
        float scale = l > limit && l > 0.0f ? limit / l : 1.0f;
        out.store(i, c * scale);
    }
};

}  // namespace rtd
