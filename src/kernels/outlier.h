// Firefly removal (shared/seeds/002): a pixel's luminance is clamped to mean + k * stddev of the
// luminance of the object pixels in its window; the colour is scaled, keeping its hue.
// Background passes through.
#pragma once

#include "kernels/views.h"

namespace rtd {

struct OutlierKernel {
    GBufferView g;
    Planes3 in, out;
    int radius;  // <= layout.padding
    float k;

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        const Layout& L = g.layout;
        int i = L.index(x, y);
        Float3 c = in.load(i);
        float sum = 0.0f, sum2 = 0.0f, count = 0.0f;
        for (int dy = -radius; dy <= radius; ++dy) {
            int row = i + L.offset(0, dy);
            RTD_VECTORIZE
            for (int dx = -radius; dx <= radius; ++dx) {
                int j = row + dx;
                float use = foregroundMask(g.objectId[j]);
                float l = luminance(in.load(j));
                sum += use * l;
                sum2 += use * l * l;
                count += use;
            }
        }
        float mean = sum / maxf(count, 1.0f);
        float variance = maxf(sum2 / maxf(count, 1.0f) - mean * mean, 0.0f);
        float limit = mean + k * std::sqrt(variance);
        float l = luminance(c);
        // Background: count may be 0 and the pixel is not an object: keep it.
        float scale = g.objectId[i] >= 0 && l > limit && l > 0.0f ? limit / l : 1.0f;
        out.store(i, c * scale);
    }
};

}  // namespace rtd
