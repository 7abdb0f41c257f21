// One level of the edge-avoiding A-Trous wavelet transform (Dammertz et al. 2010): 5x5 B3-spline
// taps (1/16, 1/4, 3/8, 1/4, 1/16) spaced `stride` = 2^level pixels apart, weighted by the JBF's
// edge-stopping terms. Each level filters the previous level's output.
#pragma once

#include "kernels/b3_spline.h"
#include "kernels/edge_stopping.h"
#include "kernels/modulate.h"
#include "kernels/views.h"

namespace rtd {

// The memory between rows of the CPU's form (Atrous::filterSharingPairs, run by the CPU
// launcher, parallel_for.h): for each pixel of a row, the weight it has as a tap of each of its
// kForwardTaps taps in the rows below (those taps as centres). Tap k lies at (dx, dy) = (k % 5 - 2,
// k / 5 + 1) strides; its plane starts at `row + k * planeStride`, indexed by x from -2 strides.
constexpr int kForwardTaps = 10;
struct PartnerWeightRows {
    float* own = nullptr;           // row y's: written for x in [0, width)
    const float* above1 = nullptr;  // row y - stride's
    const float* above2 = nullptr;  // row y - 2 strides'
    long planeStride = 0;
};

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

    // The per-pixel form: the reference the other forms are tested against, and the GPU's for a
    // pixel without a partner row (the CPU's device runs filterSharingPairs). Branch-free
    // (border and background taps get weight 0), so a CPU loop over a row vectorises it: the
    // pixels' taps are neighbours too (contiguous loads).
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
        // The key, not the object ID (-1 alike on background): one buffer of IDs read, not two.
        std::int32_t idI = g.filterKey[i];
        // Taps whose filter key is the centre's (views.h; a background centre's result is unused).
        const std::int32_t keyI = g.filterKey[i];
        const float centreW = centreWeight(terms, ni);
        Float3 sum = ci * centreW;
        float sumW = centreW;
        // The other 24 taps as 12 pairs at +offset and -offset.
        RTD_UNROLL
        for (int pair = 0; pair < 12; ++pair) {
            int tx = pair % 5, ty = pair / 5;  // the taps before the centre, raster order
            addOppositeTaps(terms, centre, i, keyI, L.offset((tx - 2) * step, (ty - 2) * step),
                            log2B3(tx - 2, ty - 2), sum, sumW);
        }
        finish(x, y, i, ci, sum, sumW, idI);
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
        const std::int32_t idA = g.filterKey[iA], idB = g.filterKey[iB];
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

    // The CPU's form. J(i, j) and J(j, i) share all but their plane term's numerator
    // (edgeStoppingPairParts), so each pair of pixels is evaluated once for both. A pixel
    // evaluates its 10 taps in the rows below (+1 and +2 strides), keeps their weights and stores
    // for each the weight it has as that tap's tap (rows.own); its 10 taps in the rows above then
    // cost a load of that weight (rows.above1/2, stored when those rows ran) and of their colour.
    // Its 4 taps in its own row are evaluated both ways, as in filter: a store and a load in one
    // row would make the vector lanes depend on one another. Each pixel gets filter's result up
    // to rounding. WithResult false: only the stored weights (for the rows above a run of rows).
    template <bool WithResult>
    RTD_HOST_DEVICE RTD_INLINE void filterSharingPairs(int x, int y,
                                                       const PartnerWeightRows& rows) const {
        const int step = stride;
        const Layout& L = g.layout;
        const PixelIndex i = L.index(x, y);
        const Float3 ci = in.load(i), ni = g.normal.load(i);
        const EdgeStoppingTerms terms = base2(edges);
        const Float3 pi = g.position.load(i);
        // For the taps below, the plane term's normal unscaled, as the taps' own: both directions
        // then take the scale with their shared reciprocal (and no scaled copy stays live).
        const EdgeStoppingCentre unscaled{ci, ni, pi, ni,
                                          terms.normalScale * guideNormalWeight(ni)};
        const std::int32_t keyI = g.filterKey[i];
        Float3 sum = {};
        float sumW = 0.0f;
        // The taps below, two at a time sharing one division.
        RTD_UNROLL
        for (int k = 0; k < kForwardTaps; k += 2) {
            const PixelIndex ja = i + forwardOffset(k), jb = i + forwardOffset(k + 1);
            const Float3 ca = in.load(ja), cb = in.load(jb);
            EdgeStoppingPairParts a = edgeStoppingPairParts<OppositeNormalsVanish>(
                terms, unscaled, ca, g.normal.load(ja), g.position.load(ja),
                log2B3(forwardDx(k), forwardDy(k)));
            EdgeStoppingPairParts b = edgeStoppingPairParts<OppositeNormalsVanish>(
                terms, unscaled, cb, g.normal.load(jb), g.position.load(jb),
                log2B3(forwardDx(k + 1), forwardDy(k + 1)));
            const float inverseProduct =
                divideApprox(1.0f, a.centre.planeDenominator * b.centre.planeDenominator);
            // 1 / (2 sp^2 |dp|^2) for each.
            const float scaleA = b.centre.planeDenominator * inverseProduct * terms.planeScale;
            const float scaleB = a.centre.planeDenominator * inverseProduct * terms.planeScale;
            const bool sameA = g.filterKey[ja] == keyI, sameB = g.filterKey[jb] == keyI;
            // As the taps' centres.
            float partnerA = exp2Negative(-(a.centre.colorAndNormal + a.tapNumerator * scaleA));
            float partnerB = exp2Negative(-(b.centre.colorAndNormal + b.tapNumerator * scaleB));
            rows.own[k * rows.planeStride + x] = sameA ? partnerA : 0.0f;
            rows.own[(k + 1) * rows.planeStride + x] = sameB ? partnerB : 0.0f;
            if constexpr (WithResult) {
                float wa =
                    exp2Negative(-(a.centre.colorAndNormal + a.centre.planeNumerator * scaleA));
                float wb =
                    exp2Negative(-(b.centre.colorAndNormal + b.centre.planeNumerator * scaleB));
                wa = sameA ? wa : 0.0f;
                wb = sameB ? wb : 0.0f;
                sum += ca * wa + cb * wb;
                sumW += wa + wb;
            }
        }
        if constexpr (WithResult) {
            // The taps in this row, at +/- 1 and 2 strides, both ways (as filter's pairs).
            const EdgeStoppingCentre centre = edgeStoppingCentre(terms, ci, ni, pi);
            RTD_UNROLL
            for (int dx = 1; dx <= 2; ++dx)
                addOppositeTaps(terms, centre, i, keyI, L.offset(dx * step, 0), log2B3(dx, 0), sum,
                                sumW);
            // The taps above: their weights were stored when their rows ran.
            RTD_UNROLL
            for (int k = 0; k < kForwardTaps; ++k) {
                const float* above = forwardDy(k) == 1 ? rows.above1 : rows.above2;
                const float w = above[k * rows.planeStride + x - forwardDx(k) * step];
                sum += in.load(i - forwardOffset(k)) * w;
                sumW += w;
            }
            const float centreW = centreWeight(terms, ni);
            sum += ci * centreW;
            sumW += centreW;
            finish(x, y, i, ci, sum, sumW, g.filterKey[i]);
        }
    }

  private:
    // The centre tap's weight: all distances 0 but the normal's (n.n rounds to 1 - a few ulp),
    // 2^log2k exp(-D_normal^2 / 2sn^2); 2^log2k without a normal (a neutral normal term).
    RTD_HOST_DEVICE RTD_INLINE static float centreWeight(const EdgeStoppingTerms& terms,
                                                         Float3 normal) {
        return exp2Negative(log2B3(0, 0) -
                            normalAngleSquared<OppositeNormalsVanish>(dot(normal, normal)) *
                                (terms.normalScale * guideNormalWeight(normal)));
    }
    // The taps at +o and -o of centre i (those whose filter key is keyI mix in) added to its
    // sums: they share their kernel value, 2^log2Kernel inside the exponent (no multiplication),
    // and one division for their plane terms (pairExponents).
    RTD_HOST_DEVICE RTD_INLINE void addOppositeTaps(const EdgeStoppingTerms& terms,
                                                    const EdgeStoppingCentre& centre, PixelIndex i,
                                                    std::int32_t keyI, PixelIndex o,
                                                    float log2Kernel, Float3& sum,
                                                    float& sumW) const {
        const PixelIndex ja = i + o, jb = i - o;
        const Float3 ca = in.load(ja), cb = in.load(jb);
        EdgeStoppingParts a = edgeStoppingParts<OppositeNormalsVanish>(
            terms, centre, ca, g.normal.load(ja), g.position.load(ja), log2Kernel);
        EdgeStoppingParts b = edgeStoppingParts<OppositeNormalsVanish>(
            terms, centre, cb, g.normal.load(jb), g.position.load(jb), log2Kernel);
        float exponentA, exponentB;
        pairExponents(a, b, exponentA, exponentB);
        float wa = exp2Negative(-exponentA), wb = exp2Negative(-exponentB);
        wa = g.filterKey[ja] == keyI ? wa : 0.0f;
        wb = g.filterKey[jb] == keyI ? wb : 0.0f;
        sum += ca * wa + cb * wb;
        sumW += wa + wb;
    }
    // filterSharingPairs' taps below the centre, k in [0, kForwardTaps).
    RTD_HOST_DEVICE static constexpr int forwardDx(int k) { return k % 5 - 2; }
    RTD_HOST_DEVICE static constexpr int forwardDy(int k) { return k / 5 + 1; }
    RTD_HOST_DEVICE RTD_INLINE PixelIndex forwardOffset(int k) const {
        return g.layout.offset(forwardDx(k) * stride, forwardDy(k) * stride);
    }

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
        const float w = centreWeight(terms, c.normal);
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
    // The result from the sums (foreground: sumW is at least about (3/8)^2, the centre tap's);
    // background passes through.
    RTD_HOST_DEVICE RTD_INLINE void finish(int x, int y, PixelIndex i, Float3 ci, Float3 sum,
                                           float sumW, std::int32_t key) const {
        float keep = 1.0f - foregroundMask(key);  // background: the key -1
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
