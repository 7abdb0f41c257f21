// One level of the edge-avoiding A-Trous wavelet transform (Dammertz et al. 2010): 5x5 B3-spline
// taps (1/16, 1/4, 3/8, 1/4, 1/16) spaced `stride` = 2^level pixels apart, weighted by the JBF's
// edge-stopping terms. Each level filters the previous level's output.
#pragma once

#include "kernels/edge_stopping.h"
#include "kernels/views.h"

namespace rtd {

template <bool OppositeNormalsVanish>
struct Atrous {
    GBufferView g;
    Planes3 in, out;
    int stride;  // 2 * stride <= layout.padding
    EdgeStoppingTerms edges;
    // The rows it reads are `stride` apart (the CPU launcher's row order, parallel_for.h).
    RTD_HOST_DEVICE int tapRowStride() const { return stride; }

    // Branch-free body (border and background taps get weight 0) so the CPU launcher can
    // vectorise across neighbouring pixels: their taps are neighbours too (contiguous loads).
    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        // log2 of the B3 spline's taps 1/16, 1/4, 3/8, 1/4, 1/16.
        constexpr float kLog2B3[5] = {-4.0f, -2.0f, -1.4150375f, -2.0f, -4.0f};
        const Layout& L = g.layout;
        PixelIndex i = L.index(x, y);
        Float3 ci = in.load(i);
        Float3 ni = g.normal.load(i), pi = g.position.load(i);
        std::int32_t idI = g.objectId[i];
        // Taps from the centre's object, or any object (a background centre's result is unused).
        AcceptedIds accepted = acceptedIds(edges.separateObjects, idI);
        Float3 sum;
        float sumW = 0.0f;
        RTD_UNROLL
        for (int ty = 0; ty < 5; ++ty) {
            RTD_UNROLL
            for (int tx = 0; tx < 5; ++tx) {
                PixelIndex j = i + L.offset((tx - 2) * stride, (ty - 2) * stride);
                Float3 cj = in.load(j);
                float exponent = edgeStoppingExponent<OppositeNormalsVanish>(
                    edges, ci, cj, ni, g.normal.load(j), pi, g.position.load(j));
                // The kernel value k = 2^log2k enters the exponent: no multiplication.
                float w = exp2Negative((kLog2B3[ty] + kLog2B3[tx]) - exponent * kLog2e);
                w = accepted.contains(g.objectId[j]) ? w : 0.0f;
                sum += cj * w;
                sumW += w;
            }
        }
        // Foreground: sumW >= (3/8)^2, the centre tap. Background passes through.
        float keep = 1.0f - foregroundMask(idI);
        float scale = (1.0f - keep) / maxf(sumW, 1e-20f);
        out.store(i, sum * scale + ci * keep);
    }
};
using AtrousKernel = Atrous<false>;  // any sigma_normal
// sigma_normal <= 0.118 (the assignment's 0.1): no square root per tap (edge_stopping.h).
using AtrousNarrowNormalKernel = Atrous<true>;

}  // namespace rtd
