// One level of the edge-avoiding A-Trous wavelet transform (Dammertz et al. 2010): 5x5 B3-spline
// taps (1/16, 1/4, 3/8, 1/4, 1/16) spaced `stride` = 2^level pixels apart, weighted by the JBF's
// edge-stopping terms. Each level filters the previous level's output.
#pragma once

#include "kernels/b3_spline.h"
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
        float centreW =
            exp2Negative(log2B3(0, 0) - normalAngleSquared<OppositeNormalsVanish>(dot(ni, ni)) *
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
            const float log2Kernel = log2B3(tx - 2, ty - 2);
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

    // Two pixels of a column a stride apart, (x, y) and (x, y + Stride), y + Stride inside the
    // image (the GPU's form): their 5x5 taps share 20 places, so the pair loads 30 taps where two
    // pixels alone load 50. Every tap is evaluated in a couple that shares one division
    // (pairExponents): a shared tap for both centres; A's row -2 with B's row +2; the two
    // centres, each a tap of the other. Each pixel gets filter's result up to rounding.
    template <int Stride>
    RTD_HOST_DEVICE RTD_INLINE void filterPair(int x, int y) const {
        const Layout& L = g.layout;
        const PixelIndex iA = L.index(x, y), iB = iA + L.offset(0, Stride);
        const std::int32_t idA = g.objectId[iA], idB = g.objectId[iB];
        const EdgeStoppingTerms terms = base2(edges);
        Tap centreA = tap(iA), centreB = tap(iB);
        if (idA < 0 && idB < 0) {  // background passes through; a warp of it runs no taps
            finish(x, y, iA, centreA.color, {}, 1.0f, idA);
            finish(x, y + Stride, iB, centreB.color, {}, 1.0f, idB);
            return;
        }
        Sums a = centreSums(terms, centreA), b = centreSums(terms, centreB);
        // A's row -2 with B's row +2 (rows -2 and 3 of A's).
        RTD_UNROLL
        for (int dx = -2; dx <= 2; ++dx)
            addCouple(terms, a, tap(iA + L.offset(dx * Stride, -2 * Stride)), log2B3(dx, -2), b,
                      tap(iA + L.offset(dx * Stride, 3 * Stride)), log2B3(dx, 2));
        // Rows -1..2 of A's (-2..1 of B's), but for the centres.
        RTD_UNROLL
        for (int row = -1; row <= 2; ++row) {
            RTD_UNROLL
            for (int dx = -2; dx <= 2; ++dx) {
                if (dx == 0 && (row == 0 || row == 1)) continue;
                Tap t = tap(iA + L.offset(dx * Stride, row * Stride));
                addCouple(terms, a, t, log2B3(dx, row), b, t, log2B3(dx, row - 1));
            }
        }
        addCouple(terms, a, centreB, log2B3(0, 1), b, centreA, log2B3(0, -1));
        finish(x, y, iA, centreA.color, a.sum, a.sumW, idA);
        finish(x, y + Stride, iB, centreB.color, b.sum, b.sumW, idB);
    }

  private:
    // filterPair's pieces.
    struct Tap {
        Float3 color, normal, position;
        std::int32_t key;
    };
    RTD_HOST_DEVICE RTD_INLINE Tap tap(PixelIndex j) const {
        return {in.load(j), g.normal.load(j), g.position.load(j), g.filterKey[j]};
    }
    struct Sums {
        EdgeStoppingCentre centre;
        std::int32_t key;
        Float3 sum;
        float sumW;
    };
    // The centre tap alone (as in filter).
    RTD_HOST_DEVICE RTD_INLINE Sums centreSums(const EdgeStoppingTerms& terms, const Tap& c) const {
        float w = exp2Negative(log2B3(0, 0) -
                               normalAngleSquared<OppositeNormalsVanish>(dot(c.normal, c.normal)) *
                                   terms.normalScale);
        return {edgeStoppingCentre(terms, c.color, c.normal, c.position), c.key, c.color * w, w};
    }
    // Tap ta for centre a and tap tb for centre b, with one division between them.
    RTD_HOST_DEVICE RTD_INLINE void addCouple(const EdgeStoppingTerms& terms, Sums& a,
                                              const Tap& ta, float log2KernelA, Sums& b,
                                              const Tap& tb, float log2KernelB) const {
        EdgeStoppingParts pa = edgeStoppingParts<OppositeNormalsVanish>(
            terms, a.centre, ta.color, ta.normal, ta.position, log2KernelA);
        EdgeStoppingParts pb = edgeStoppingParts<OppositeNormalsVanish>(
            terms, b.centre, tb.color, tb.normal, tb.position, log2KernelB);
        float exponentA, exponentB;
        pairExponents(pa, pb, exponentA, exponentB);
        float wa = exp2Negative(-exponentA), wb = exp2Negative(-exponentB);
        wa = ta.key == a.key ? wa : 0.0f;
        wb = tb.key == b.key ? wb : 0.0f;
        a.sum += ta.color * wa;
        a.sumW += wa;
        b.sum += tb.color * wb;
        b.sumW += wb;
    }
    // As filter ends: background passes through.
    RTD_HOST_DEVICE RTD_INLINE void finish(int x, int y, PixelIndex i, Float3 ci, Float3 sum,
                                           float sumW, std::int32_t id) const {
        float keep = 1.0f - foregroundMask(id);
        float scale = (1.0f - keep) / maxf(sumW, 1e-20f);
        Float3 result = sum * scale + ci * keep;
        if constexpr (Modulated)
            storeModulated(g.layout, rgbOut, x, y, result * albedo.load(i));
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
