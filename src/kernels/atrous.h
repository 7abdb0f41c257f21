// One level of the edge-avoiding A-Trous wavelet transform (Dammertz et al. 2010): 5x5 B3-spline
// taps (1/16, 1/4, 3/8, 1/4, 1/16) spaced `stride` = 2^level pixels apart, weighted by the JBF's
// edge-stopping terms. Each level filters the previous level's output.
#pragma once

#include "kernels/edge_stopping.h"
#include "kernels/modulate.h"
#include "kernels/views.h"

namespace rtd {

// Modulated (the atrous method's last level): writes the result times the albedo factor into the
// caller's interleaved RGB instead of `out` (ModulateKernel's job, fused: nothing reads the
// last level's planes, so they are not written).
template <bool OppositeNormalsVanish, bool Modulated = false>
struct Atrous {
    GBufferView g;
    Planes3 in, out;  // out: unused when Modulated
    int stride;       // 2 * stride <= layout.padding
    EdgeStoppingTerms edges;
    Planes3 albedo = {};      // Modulated only
    float* rgbOut = nullptr;  // Modulated only: interleaved, 3 floats per pixel
    // The rows it reads are `stride` apart (the CPU launcher's row order, parallel_for.h).
    RTD_HOST_DEVICE int tapRowStride() const { return stride; }

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const { filter<0>(x, y); }

    // Branch-free body (border and background taps get weight 0) so the CPU launcher can
    // vectorise across neighbouring pixels: their taps are neighbours too (contiguous loads).
    // FixedStride > 0: the stride as a compile-time constant (the CUDA launcher's choice for
    // some strides): the taps' column offsets then become immediate operands of the GPU's loads.
    template <int FixedStride>
    RTD_HOST_DEVICE RTD_INLINE void filter(int x, int y) const {
        const int step = FixedStride > 0 ? FixedStride : stride;
        // log2 of the B3 spline's taps 1/16, 1/4, 3/8, 1/4, 1/16.
        constexpr float kLog2B3[5] = {-4.0f, -2.0f, -1.4150375f, -2.0f, -4.0f};
        const Layout& L = g.layout;
        PixelIndex i = L.index(x, y);
        Float3 ci = in.load(i);
        Float3 ni = g.normal.load(i);
        // Exponents in base 2, the spline's log2 weight inside them: exp2 of each tap's sum.
        const EdgeStoppingTerms terms = base2(edges);
        EdgeStoppingCentre centre = edgeStoppingCentre(terms, ci, ni, g.position.load(i));
        std::int32_t idI = g.objectId[i];
        // Taps whose filter key is the centre's (views.h; a background centre's result is unused).
        const std::int32_t keyI = g.filterKey[i];
        // The centre: all distances 0 but the normal's (n.n rounds to 1 - a few ulp), weight
        // 2^log2k exp(-D_normal^2 / 2sn^2).
        float centreW = exp2Negative(2.0f * kLog2B3[2] -
                                     normalAngleSquared<OppositeNormalsVanish>(dot(ni, ni)) *
                                         terms.normalScale);
        Float3 sum = ci * centreW;
        float sumW = centreW;
        // The other 24 taps as 12 pairs at +offset and -offset, which share their kernel value
        // and one division for their plane terms.
        RTD_UNROLL
        for (int pair = 0; pair < 12; ++pair) {
            int tx = pair % 5, ty = pair / 5;  // the taps before the centre, raster order
            PixelIndex o = L.offset((tx - 2) * step, (ty - 2) * step);
            PixelIndex ja = i + o, jb = i - o;
            // The kernel value k = 2^log2k enters the exponent: no multiplication.
            const float log2Kernel = kLog2B3[ty] + kLog2B3[tx];
            Float3 ca = in.load(ja), cb = in.load(jb);
            EdgeStoppingParts a = edgeStoppingParts<OppositeNormalsVanish>(
                terms, centre, ca, g.normal.load(ja), g.position.load(ja), log2Kernel);
            EdgeStoppingParts b = edgeStoppingParts<OppositeNormalsVanish>(
                terms, centre, cb, g.normal.load(jb), g.position.load(jb), log2Kernel);
            float exponentA, exponentB;
            pairExponents(a, b, exponentA, exponentB);
            float wa = exp2Negative(-exponentA);
            float wb = exp2Negative(-exponentB);
            wa = g.filterKey[ja] == keyI ? wa : 0.0f;
            wb = g.filterKey[jb] == keyI ? wb : 0.0f;
            sum += ca * wa + cb * wb;
            sumW += wa + wb;
        }
        // Foreground: sumW is at least about (3/8)^2, the centre tap. Background passes through.
        float keep = 1.0f - foregroundMask(idI);
        float scale = (1.0f - keep) / maxf(sumW, 1e-20f);
        Float3 result = sum * scale + ci * keep;
        if constexpr (Modulated)
            storeModulated(L, rgbOut, x, y, result * albedo.load(i));
        else
            out.store(i, result);
    }
};
using AtrousKernel = Atrous<false>;  // any sigma_normal
// sigma_normal <= 0.118 (the assignment's 0.1): no square root per tap (edge_stopping.h).
using AtrousNarrowNormalKernel = Atrous<true>;
using AtrousModulatedKernel = Atrous<false, true>;
using AtrousNarrowNormalModulatedKernel = Atrous<true, true>;

}  // namespace rtd
