// Brute-force joint bilateral filter (assignment formula):
//   J(i,j) = exp(-|i-j|^2/2sp^2 - |C_i-C_j|^2/2sc^2 - D_normal^2/2sn^2 - D_plane^2/2sd^2)
// over a (2r+1)^2 window; background pixels pass through and never contribute.
#pragma once

#include "kernels/edge_stopping.h"
#include "kernels/views.h"

namespace rtd {

struct JbfKernel {
    GBufferView g;
    Planes3 in, out;
    int radius;
    float coordScale;  // 1 / (2 sigma_coord^2)
    EdgeStoppingTerms edges;

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        std::size_t i = g.index(x, y);
        Float3 ci = in.load(i);
        if (g.objectId[i] < 0) {
            out.store(i, ci);
            return;
        }
        Float3 ni = g.normal.load(i), pi = g.position.load(i);
        // Bounds are resolved before the loops so the inner loop is branch-free.
        int x0 = maxi(x - radius, 0), x1 = mini(x + radius, g.width - 1);
        int y0 = maxi(y - radius, 0), y1 = mini(y + radius, g.height - 1);
        float sumR = 0.0f, sumG = 0.0f, sumB = 0.0f, sumW = 0.0f;
        for (int yy = y0; yy <= y1; ++yy) {
            float dy2 = float((yy - y) * (yy - y));
            for (int xx = x0; xx <= x1; ++xx) {
                std::size_t j = g.index(xx, yy);
                Float3 cj = in.load(j);
                float dx = float(xx - x);
                float exponent = (dx * dx + dy2) * coordScale +
                                 edgeStoppingExponent(edges, ci, cj, ni, g.normal.load(j), pi,
                                                      g.position.load(j));
                float w = g.objectId[j] >= 0 ? expNegative(-exponent) : 0.0f;
                sumR += w * cj.x;
                sumG += w * cj.y;
                sumB += w * cj.z;
                sumW += w;
            }
        }
        // sumW >= 1: the centre tap has weight exp(0).
        float inv = 1.0f / sumW;
        out.store(i, make3(sumR * inv, sumG * inv, sumB * inv));
    }
};

}  // namespace rtd
