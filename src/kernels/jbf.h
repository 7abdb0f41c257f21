// Brute-force joint bilateral filter (assignment formula):
//   J(i,j) = exp(-|i-j|^2/2sp^2 - |C_i-C_j|^2/2sc^2 - D_normal^2/2sn^2 - D_plane^2/2sd^2)
// over a (2r+1)^2 window; background pixels pass through and never contribute; with
// separateObjects (default) neither do pixels of another object (GBufferView::filterKey).
#pragma once

#include "kernels/edge_stopping.h"
#include "kernels/views.h"

namespace rtd {

template <bool OppositeNormalsVanish>
struct Jbf {
    GBufferView g;
    Planes3 in, out;
    int radius;        // <= layout.padding
    float coordScale;  // 1 / (2 sigma_coord^2)
    EdgeStoppingTerms edges;

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        const Layout& L = g.layout;
        PixelIndex i = L.index(x, y);
        Float3 ci = in.load(i);
        if (g.filterKey[i] < 0) {  // background (the key: one buffer of IDs read, not two)
            out.store(i, ci);
            return;
        }
        // Exponents in base 2, the position term inside them: exp2 of each tap's sum.
        const EdgeStoppingTerms terms = base2(edges);
        const float coordScale2 = coordScale * kLog2e;
        EdgeStoppingCentre centre =
            edgeStoppingCentre(terms, ci, g.normal.load(i), g.position.load(i));
        const std::int32_t keyI = g.filterKey[i];  // taps with the same key (views.h)
        float sumR = 0.0f, sumG = 0.0f, sumB = 0.0f, sumW = 0.0f;
        for (int dy = -radius; dy <= radius; ++dy) {
            PixelIndex row = i + L.offset(0, dy);
            float dy2 = float(dy * dy);
            // Branch-free inner loop (border and background taps get weight 0): vectorises.
            RTD_SHORT_VECTOR_LOOP
            for (int dx = -radius; dx <= radius; ++dx) {
                PixelIndex j = row + dx;
                Float3 cj = in.load(j);
                float exponent = edgeStoppingExponent<OppositeNormalsVanish>(
                    terms, centre, cj, g.normal.load(j), g.position.load(j),
                    -(float(dx * dx) + dy2) * coordScale2);
                float w = exp2Negative(-exponent);  // then selected: no branch around it
                w = g.filterKey[j] == keyI ? w : 0.0f;
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

using JbfKernel = Jbf<false>;  // any sigma_normal
// sigma_normal <= 0.118 (the assignment's 0.1 included): no square root per tap.
using JbfNarrowNormalKernel = Jbf<true>;

}  // namespace rtd
