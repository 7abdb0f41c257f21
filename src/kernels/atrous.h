// One level of the edge-avoiding A-Trous wavelet transform (Dammertz et al. 2010): 5x5 B3-spline
// taps (1/16, 1/4, 3/8, 1/4, 1/16) spaced `stride` = 2^level pixels apart, weighted by the JBF's
// edge-stopping terms. Each level filters the previous level's output.
#pragma once

#include "kernels/edge_stopping.h"
#include "kernels/views.h"

namespace rtd {

RTD_HOST_DEVICE RTD_INLINE float b3SplineTap(int offset) {
    // offset in -2..2
    return offset == 0 ? 0.375f : (offset == 1 || offset == -1) ? 0.25f : 0.0625f;
}

struct AtrousKernel {
    GBufferView g;
    Planes3 in, out;
    int stride;
    EdgeStoppingTerms edges;

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        std::size_t i = g.index(x, y);
        Float3 ci = in.load(i);
        if (g.objectId[i] < 0) {
            out.store(i, ci);
            return;
        }
        Float3 ni = g.normal.load(i), pi = g.position.load(i);
        Float3 sum;
        float sumW = 0.0f;
        for (int ty = -2; ty <= 2; ++ty) {
            int yy = y + ty * stride;
            if (yy < 0 || yy >= g.height) continue;  // taps outside the image are dropped
            float hy = b3SplineTap(ty);
            for (int tx = -2; tx <= 2; ++tx) {
                int xx = x + tx * stride;
                if (xx < 0 || xx >= g.width) continue;
                std::size_t j = g.index(xx, yy);
                if (g.objectId[j] < 0) continue;
                Float3 cj = in.load(j);
                float exponent = edgeStoppingExponent(edges, ci, cj, ni, g.normal.load(j), pi,
                                                      g.position.load(j));
                float w = hy * b3SplineTap(tx) * expNegative(-exponent);
                sum += cj * w;
                sumW += w;
            }
        }
        out.store(i, sum * (1.0f / sumW));  // sumW >= 9/64: the centre tap
    }
};

}  // namespace rtd
