// Spatiotemporal variance-guided filtering (Schied et al., HPG 2017; reference: Falcor's
// SVGFPass). Its kernels in one header (~600 lines): they share the centre, weight and history
// helpers, and each has a CPU and a GPU form over the same arithmetic. Albedo demodulation happens
// in the ingest and modulation in ModulateKernel, for every method. Passes: temporal (reproject,
// accumulate illumination and the luminance moments with a per-pixel history length), variance
// (temporal from the moments, or a 7x7 edge-aware spatial estimate where the history is short),
// A-Trous iterations guided by the variance.
//
// The moments are kept as (mean, variance) of the luminance rather than the paper's (m1, m2):
// the same exponential averages (var = m2 - m1^2 exactly), updated in the stable form
//   mean' = mean + a d,  var' = (1 - a)(var + a d^2),  d = l - mean,
// because m2 - m1^2 in float cancels catastrophically for bright pixels with small variance,
// which made results depend on the rounding of each instruction set and back end.
#pragma once

#include "kernels/b3_spline.h"
#include "kernels/modulate.h"
#include "kernels/reproject.h"
#include "kernels/views.h"
#include "kernels/window_sums.h"

namespace rtd {

struct SvgfTerms {
    float sigmaDepth;      // sigma_z: depth tolerance relative to the local depth slope
    float sigmaNormal;     // sigma_n: exponent of max(0, n.n')
    float sigmaLuminance;  // sigma_l: luminance tolerance in standard deviations
};

// What the SVGF weight needs of the centre pixel, shared by all its taps.
struct SvgfCentre {
    float depth;
    Float3 normal;
    float luminance;
    float luminanceScale;  // log2(e) / phi_l: the luminance term in base 2
    float normalWeight;    // 1, or 0 for a centre without a normal (views.h: guideNormalWeight)
};

// The depth term's denominator for a tap `offset` pixels away, sigma_z |grad z . offset| + eps
// (depthAlongOffset: grad z . offset).
RTD_HOST_DEVICE RTD_INLINE float svgfDepthDenominator(const SvgfTerms& t, float depthAlongOffset) {
    return t.sigmaDepth * absf(depthAlongOffset) + 1e-3f;
}
// Its scale, log2(e) / denominator: one division serves the taps at +offset and -offset (the
// slope's magnitude is the same).
RTD_HOST_DEVICE RTD_INLINE float svgfDepthScale(const SvgfTerms& t, float depthAlongOffset) {
    return divideApprox(kLog2e, svgfDepthDenominator(t, depthAlongOffset));
}

// The SVGF edge-stopping weight between a centre and a tap (before the tap mask), times the
// filter kernel's value k at the tap:
//   k exp(-|dz| / (sigma_z |grad z . offset| + eps) - |dl| / phi_l) max(0, n.n')^sigma_n
// evaluated as 2^(log2 k - |dz| depthScale - |dl| luminanceScale) with both scales precomputed
// (k costs no multiplication there).
// FixedSigmaNormal < 0: any sigma_n, the normal factor folded into the exponent as
// sigma_n log2(n.n') (the GPU's form: log2 is one instruction there). FixedSigmaNormal = s > 0
// (the CPU's form for the paper's 128): sigma_n = s known at compile time, and -log2(n.n') =
// (1 - n.n') L(n.n') with L a polynomial fitted near n.n' = 1 (negLog2FactorNearOne): seven
// operations in the exponent, fewer than the CPU's log2 polynomial or seven squarings after exp2
// (the timings: docs/performance-cpu.md).
template <int FixedSigmaNormal>
RTD_HOST_DEVICE RTD_INLINE float svgfWeight(const SvgfTerms& t, const SvgfCentre& c,
                                            float depthScale, float depthJ, Float3 normalJ,
                                            float lumJ, float log2Kernel = 0.0f) {
    // Reassociated, clang turns the multiplication by the precomputed scales back into a vector
    // division per tap.
    RTD_NO_REASSOCIATION
    float dz = c.depth - depthJ;
    float dl = c.luminance - lumJ;
    float e = (absf(dz) * depthScale - log2Kernel) + absf(dl) * c.luminanceScale;
    float cosine = dot(c.normal, normalJ);
    // A centre without a normal (its taps are without one too: the same key) has the exponent
    // sigma_n times 0: a neutral normal factor.
    if constexpr (FixedSigmaNormal < 0) {
        // n.n' <= 0 gives sigma_n log2(1e-30): a weight of 0 (2^-126 on the CPU, exp2's floor).
        float wn = (t.sigmaNormal * c.normalWeight) * log2Positive(maxf(cosine, 1e-30f));
        return exp2Negative(minf(wn - e, 0.0f));
    } else {
        // The fit holds where the factor is over 2^-41 (n.n' > 0.8 for sigma_n = 128); below,
        // it keeps the exponent over 41 (opposite normals included): a weight of nothing next
        // to the centre's. n.n' is capped at 1 (normals a little longer than 1).
        static_assert(FixedSigmaNormal * kNegLog2NearOneFloor >= 41.0f,
                      "sigma_n too small for negLog2FactorNearOne's interval");
        const float sigma = float(FixedSigmaNormal) * c.normalWeight;
        float cc = atMostOneOrSaturated(cosine);
        return exp2Negative(-((sigma - sigma * cc) * negLog2FactorNearOne(cc) + e));
    }
}

// The 7x7 windows of SVGF: the short-history variance estimate and the anti-lag statistics.
constexpr int kSvgfWindowRadius = 3;
static_assert(kSvgfWindowRadius <= kNarrowWindow, "the window sums' narrow instantiation");

// The paper's (and the default) sigma_n = 128: the CPU's kernels with it fixed (svgfWeight).
constexpr int kPaperSigmaNormal = 128;
RTD_HOST_DEVICE RTD_INLINE bool hasPaperSigmaNormal(const SvgfTerms& t) {
    return t.sigmaNormal == float(kPaperSigmaNormal);
}

// SVGF's anti-lag: history outside what the current frame's neighbourhood allows (a light
// switched, a shadow moved) is pulled into mu +- k sigma of the current noisy window (rowSums:
// ColorRowSumsKernel's), grown to hold the pixel's own current value (a small light's history
// lies far above its window's box, and its light is its own); ordinary history, inside the wide
// 1-spp spread, is untouched. Where
// the history is further from the neighbourhood's mean than that mean's own noise allows (3
// standard errors, the mean of `count` samples), the history length is scaled by
// (1 - relative change beyond that)^4 (the power chosen on the rendered scenes), so alpha = 1/h
// rises and the new lighting is taken up within a frame or two: a cheap stand-in for A-SVGF's
// temporal gradients.
struct AntiLag {
    Float3 history;     // clamped
    float lengthScale;  // the history length's factor, in [0, 1]
};
RTD_HOST_DEVICE RTD_INLINE AntiLag antiLagOf(const PlaneSet& rowSums, PixelIndex i, int pitch,
                                             int radius, float k, Float3 history, Float3 current) {
    ColorWindowStats w = colorWindowStats<kNarrowWindow>(rowSums, i, pitch, radius);
    float meanL = luminance(w.mean);
    float standardError = luminance(w.sigma) / std::sqrt(w.count);
    float historyL = luminance(history);
    float gap =
        maxf((historyL > meanL ? historyL - meanL : meanL - historyL) - 3.0f * standardError, 0.0f);
    float change = minf(gap / maxf(maxf(historyL, meanL), 1e-4f), 1.0f);
    return {clampToBoxHolding(history, w.mean - w.sigma * k, w.mean + w.sigma * k, current),
            square(square(1.0f - change))};
}

// The temporal stage is three passes: reprojection (every pixel, bilinear taps), its 3x3 search
// (sparse), then accumulation (every pixel). The split keeps the gathers at data-dependent
// addresses in a kernel of their own: the accumulation, with its 7x7 window statistics, then
// vectorises at the full width on the CPU (one kernel doing both ran at half width, spilling).
// The reprojection hands the history to the accumulation in kSvgfHistoryPlanes planes.
constexpr int kSvgfHistoryPlanes = 6;  // rgb, luminance mean, luminance variance, length

// One pixel's reprojected history (SvgfReproject's output, in registers or planes).
struct SvgfHistorySample {
    Float3 rgb;
    float mean = 0.0f, variance = 0.0f, length = 0.0f;
};

// Reprojection: the previous frame's illumination, moments and history length sampled at each
// pixel's back-projected position (all 0 where the history test fails). Search3x3 = false runs on
// every pixel with the bilinear taps (branch-free, vectorised on the CPU); Search3x3 = true then
// revisits only the object pixels whose bilinear taps all failed (code kReprojectionOtherObject)
// and redoes them with the 3x3 search. Those are few (disocclusion edges), so the second pass is
// a cheap sparse one and the first does not pay for nine taps everywhere.
template <bool Search3x3>
struct SvgfReproject {
    static constexpr bool kSparse = Search3x3;  // the CPU launcher keeps it scalar
    GBufferView g;
    PreviousGeometry previous;
    const ObjectReprojection* objects;
    int objectCount;
    PlaneSet derivatives;
    HistoryTest test;
    PlaneSet previousIllumination;  // rgb (+ variance, unused here): last frame's feedback
    PlaneSet previousMoments;       // 2 planes: luminance mean, variance
    const float* previousLength;
    PlaneSet history;  // out: kSvgfHistoryPlanes
    std::uint8_t* validity;
    int hasHistory;

    // Runs of pixels on one object (the CPU launcher, parallel_for.h; the search is scalar and
    // needs none): see findHistory.
    RTD_HOST_DEVICE RTD_INLINE std::int32_t runKey(int x, int y) const {
        return g.objectId[g.layout.index(x, y)];
    }
    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const { pixel<false>(x, y, 0); }
    template <bool KnownId>
    RTD_HOST_DEVICE RTD_INLINE void pixel(int x, int y, std::int32_t id) const {
        PixelIndex i = g.layout.index(x, y);
        if constexpr (Search3x3) {
            if (validity[i] != kReprojectionOtherObject || g.objectId[i] < 0) return;
        }
        std::uint8_t code;
        SvgfHistorySample s = sample<KnownId>(i, id, code);
        validity[i] = code;
        history.rgb().store(i, s.rgb);
        history.at(3, i) = s.mean;
        history.at(4, i) = s.variance;
        history.at(5, i) = s.length;
    }
    // The history at pixel i and its validity code (reads only the previous frame's data).
    // Interleaved: normals and depths from the interleaved copies (findHistory). Search: with
    // the 3x3 search or not (the one-pass stage runs both forms from one kernel's fields).
    template <bool KnownId, bool Interleaved = false, bool Search = Search3x3>
    RTD_HOST_DEVICE RTD_INLINE SvgfHistorySample sample(PixelIndex i, std::int32_t id,
                                                        std::uint8_t& code) const {
        auto taps = findHistory<Search, KnownId, Interleaved>(
            g, i, previous, objects, objectCount, slopesAt(derivatives, i), test, hasHistory, id);
        code = taps.code;
        constexpr int kTaps = decltype(taps)::kCount;
        float r[kTaps], gr[kTaps], b[kTaps], means[kTaps], variances[kTaps], lengths[kTaps];
        loadTaps(previousIllumination.rgb(), taps, r, gr, b);
        loadTaps(previousMoments.data, taps, means);
        loadTaps(&previousMoments.at(1, 0), taps, variances);
        loadTaps(previousLength, taps, lengths);
        Float3 rgb;
        float mean = 0.0f, h = 0.0f;
        RTD_UNROLL
        for (int t = 0; t < kTaps; ++t) {
            float w = taps.weight[t];
            rgb += make3(r[t], gr[t], b[t]) * w;
            mean += means[t] * w;
            h += lengths[t] * w;
        }
        // The taps' mixture: its variance is their mean variance plus the spread of their means.
        float variance = 0.0f;
        RTD_UNROLL
        for (int t = 0; t < kTaps; ++t)
            variance += (variances[t] + square(means[t] - mean)) * taps.weight[t];
        return {rgb, mean, variance, h};
    }
};
using SvgfReprojectKernel = SvgfReproject<false>;
using SvgfReprojectSearchKernel = SvgfReproject<true>;

// Accumulation: the reprojected history, clamped against lighting changes, blended with the
// current frame; the luminance moments and the history length updated.
struct SvgfAccumulateKernel {
    GBufferView g;
    Planes3 radiance;  // noisy input, demodulated by the ingest, after firefly removal
    PlaneSet rowSums;  // ColorRowSumsKernel over `radiance`: the anti-lag clamp's window
    int clampRadius;   // <= kNarrowWindow
    float clampK;      // 0: no clamp (the paper); else history clamped to mu +- k sigma
    PlaneSet history;  // SvgfReproject's output
    const std::uint8_t* validity;
    Planes3 illumination;  // out
    PlaneSet moments;      // out, 2 planes: luminance mean, variance
    float* length;         // out: frames of history, 1 after a disocclusion
    // out: rgb + the moments' variance, the A-Trous input; written here rather than copied by
    // the variance pass (one pass less over 4 planes), which revises only short histories.
    PlaneSet filterInput;
    float alpha, momentsAlpha, maxHistory;

    // Branch-free (every pixel computes every term; selects pick the outputs) so the CPU
    // vectorises it across pixels.
    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        PixelIndex i = g.layout.index(x, y);
        accumulate(i, {history.rgb().load(i), history.at(3, i), history.at(4, i), history.at(5, i)},
                   validity[i] == kReprojectionValid);
    }
    // Pixel i with its reprojected history `s` (valid: the history test passed).
    RTD_HOST_DEVICE RTD_INLINE void accumulate(PixelIndex i, SvgfHistorySample s,
                                               bool valid) const {
        const Layout& L = g.layout;
        Float3 current = radiance.load(i);
        bool object = g.objectId[i] >= 0;
        float l = luminance(current);
        Float3 previous = s.rgb;
        float mean = s.mean, variance = s.variance, h = s.length;
        // Anti-lag (clampK > 0). Selects, not an `if`, so the kernel stays vectorisable (the
        // window sums exist whenever clampK > 0).
        const bool antiLag = clampK > 0.0f;
        const AntiLag lag = antiLagOf(rowSums, i, L.pitch, clampRadius, clampK, previous, current);
        h *= antiLag ? lag.lengthScale : 1.0f;
        previous.x = antiLag ? lag.history.x : previous.x;
        previous.y = antiLag ? lag.history.y : previous.y;
        previous.z = antiLag ? lag.history.z : previous.z;
        // A new history (disocclusion, first frame) starts at 1 frame: alpha 1, the current
        // sample alone. Background: passed through, no history.
        h = valid ? minf(h + 1.0f, maxHistory) : 1.0f;
        // Equal weights for the first frames of a history, then the exponential average.
        float a1 = maxf(alpha, 1.0f / h), a2 = maxf(momentsAlpha, 1.0f / h);
        float d = l - mean;
        Float3 result = previous * (1.0f - a1) + current * a1;
        float newVariance = object ? (1.0f - a2) * (variance + a2 * d * d) : 0.0f;
        illumination.store(i, result);
        moments.at(0, i) = object ? mean + a2 * d : 0.0f;
        moments.at(1, i) = newVariance;
        length[i] = object ? h : 0.0f;
        filterInput.rgb().store(i, result);
        filterInput.at(3, i) = newVariance;
    }
};

// The temporal stage in one pass (the GPU's): reprojection, the 3x3 search where the bilinear
// taps all failed, and accumulation, the history kept in registers (no history planes written
// and read back). Its parts are the three kernels' own code; `accumulate.history` and
// `.validity` are unused, `reproject.history` too. The CPU runs the three passes instead: there
// the search's branch would stop the vectorisation of the whole pass. Interleaved: normals and
// depths from the interleaved copies (views.h).
template <bool Interleaved = false>
struct SvgfTemporal {
    SvgfReprojectKernel reproject;
    SvgfAccumulateKernel accumulate;

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        const GBufferView& g = reproject.g;
        PixelIndex i = g.layout.index(x, y);
        std::uint8_t code;
        SvgfHistorySample s = reproject.template sample<false, Interleaved>(i, 0, code);
        if (code == kReprojectionOtherObject && g.objectId[i] >= 0)
            s = reproject.template sample<false, Interleaved, true>(i, 0, code);
        reproject.validity[i] = code;
        accumulate.accumulate(i, s, code == kReprojectionValid);
    }
};
using SvgfTemporalKernel = SvgfTemporal<false>;
using SvgfTemporalInterleavedKernel = SvgfTemporal<true>;

// Variance where fewer than `shortHistory` frames are accumulated: from the moments of a 7x7
// edge-aware neighbourhood (which also filters the illumination), boosted by shortHistory / h
// for the first frames as in the paper. Elsewhere the accumulation's output (the moments'
// variance) stands. Block-sparse (active()): after the first frames few pixels have a short
// history, and those lie together (disocclusions), so the CPU launcher runs the vectorised body
// only on runs of pixels with at least one active.
// InterleavedGuide: the taps' normal and depth from g.normalDepth (views.h), the GPU's layout.
// SkipsInactive: inactive pixels return at once (the GPU's form, with either guide layout).
template <int FixedSigmaNormal, bool InterleavedGuide = false,
          bool SkipsInactive = InterleavedGuide>
struct SvgfVariance {
    GBufferView g;
    PlaneSet derivatives;
    Planes3 illumination;
    PlaneSet moments;
    const float* length;
    PlaneSet out;  // rgb + variance (SvgfAccumulate's filterInput), revised in place
    SvgfTerms terms;
    float shortHistory;
    // Above shortHistory: up to here the estimate is mixed with the temporal one, its share
    // falling linearly to 0 (a spatial estimate switched off at once shows as a step of noise).
    float fadeUntil = 0.0f;
    static constexpr int kRadius = kSvgfWindowRadius;  // unrolled

    // The history length is a bilinear mix of the taps' lengths: a pixel with 4 frames
    // everywhere may hold 3.9999998, depending on how each back end rounds. The tolerance keeps
    // the decision the same on every back end.
    RTD_HOST_DEVICE RTD_INLINE bool active(int x, int y) const {
        PixelIndex i = g.layout.index(x, y);
        return g.filterKey[i] >= 0 && length[i] < maxf(shortHistory, fadeUntil) - 1e-3f;
    }
    // temporal + (spatial - temporal) share, exact at the ends.
    RTD_HOST_DEVICE RTD_INLINE static float mixByShare(float temporal, float spatial, float share) {
        return share >= 1.0f   ? spatial
               : share <= 0.0f ? temporal
                               : temporal + (spatial - temporal) * share;
    }
    // The spatial estimate's share at history length h (1 below shortHistory).
    RTD_HOST_DEVICE RTD_INLINE float spatialShare(float h) const {
        return h < shortHistory - 1e-3f
                   ? 1.0f
                   : maxf(0.0f,
                          minf(1.0f, (fadeUntil - h) / maxf(fadeUntil - shortHistory, 1e-3f)));
    }

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        // As in SvgfAtrous: the GPU's form (SkipsInactive) skips inactive pixels by a branch;
        // the CPU's computes every lane of an active run and keeps the inactive lanes' values
        // (a branch would mask every tap load).
        const bool isActive = active(x, y);
        if constexpr (SkipsInactive) {
            if (!isActive) return;
        }
        const Layout& L = g.layout;
        PixelIndex i = L.index(x, y);
        Float3 c = illumination.load(i);
        float h = length[i];
        const std::int32_t keyI = g.filterKey[i];  // taps with the same key (views.h)
        float dzdx = derivatives.at(0, i), dzdy = derivatives.at(1, i);
        // No variance yet: phi_l = sigma_l.
        Float3 normalI;
        float depthI;
        loadNormalDepth<InterleavedGuide>(g, i, normalI, depthI);
        SvgfCentre centre{depthI, normalI, luminance(c), kLog2e / terms.sigmaLuminance,
                          guideNormalWeight(normalI)};
        // The neighbourhood's luminance variance, with each tap's mean taken relative to the
        // centre's (shifted data: no cancellation). The centre: weight 1, shifted mean 0.
        float centreMean = moments.at(0, i);
        Float3 sum = c;
        float m1 = 0.0f, m2 = moments.at(1, i), sumW = 1.0f;
        // The other 48 taps in +/- offset pairs sharing their depth scale (as in SvgfAtrous).
        constexpr int kWidth = 2 * kRadius + 1;
        RTD_UNROLL
        for (int pair = 0; pair < kWidth * kRadius + kRadius; ++pair) {
            int ax = pair % kWidth - kRadius, ay = pair / kWidth - kRadius;
            float depthScale = svgfDepthScale(terms, dzdx * float(ax) + dzdy * float(ay));
            PixelIndex o = L.offset(ax, ay);
            RTD_UNROLL
            for (int side = 0; side < 2; ++side) {
                PixelIndex j = side == 0 ? i + o : i - o;
                Float3 cj = illumination.load(j), nj;
                float zj;
                loadNormalDepth<InterleavedGuide>(g, j, nj, zj);
                float w =
                    svgfWeight<FixedSigmaNormal>(terms, centre, depthScale, zj, nj, luminance(cj));
                w = g.filterKey[j] == keyI ? w : 0.0f;
                float shifted = moments.at(0, j) - centreMean;
                sum += cj * w;
                m1 += shifted * w;
                m2 += (moments.at(1, j) + shifted * shifted) * w;
                sumW += w;
            }
        }
        float inv = 1.0f / sumW;  // >= 1, the centre's
        Float3 filtered = sum * inv;
        float variance = maxf(m2 * inv - square(m1 * inv), 0.0f) * (shortHistory / maxf(h, 1.0f));
        // Per component, by selects (a branch or a selected vector would stop the CPU
        // vectorising the kernel). Inactive lanes (CPU) keep the temporal estimate: share 0.
        const float share = isActive ? spatialShare(h) : 0.0f;
        const Float3 kept = out.rgb().load(i);
        filtered =
            make3(mixByShare(kept.x, filtered.x, share), mixByShare(kept.y, filtered.y, share),
                  mixByShare(kept.z, filtered.z, share));
        variance = mixByShare(out.at(3, i), variance, share);
        out.rgb().store(i, filtered);
        out.at(3, i) = variance;
    }
};
using SvgfVarianceKernel = SvgfVariance<-1>;  // any sigma_n
using SvgfVarianceNormal128Kernel = SvgfVariance<kPaperSigmaNormal>;
using SvgfVarianceInterleavedKernel = SvgfVariance<-1, true>;

// One variance-guided A-Trous iteration: 5x5 B3-spline taps at `stride`, luminance tolerance
// sigma_l times the 3x3-Gaussian-prefiltered standard deviation; the variance is carried with
// squared weights, var' = sum w^2 var / (sum w)^2. Modulated (the last iteration, unless it is
// also the feedback one): writes the result times the albedo factor into the caller's
// interleaved RGB instead of `out` (ModulateKernel's job, fused: nothing reads the last
// iteration's planes, so they are not written). InterleavedGuide: as in SvgfVariance.
template <int FixedSigmaNormal, bool Modulated = false, bool InterleavedGuide = false>
struct SvgfAtrous {
    GBufferView g;
    PlaneSet derivatives;
    PlaneSet in, out;  // rgb + variance; out unused when Modulated
    int stride;
    SvgfTerms terms;
    Planes3 albedo = {};      // Modulated only
    float* rgbOut = nullptr;  // Modulated only: interleaved, 3 floats per pixel

    RTD_HOST_DEVICE RTD_INLINE void store(int x, int y, PixelIndex i, Float3 color,
                                          float variance) const {
        if constexpr (Modulated) {
            storeModulated(g.layout, rgbOut, x, y, color * albedo.load(i));
        } else {
            out.rgb().store(i, color);
            out.at(3, i) = variance;
        }
    }
    // The rows it reads are `stride` apart (the CPU launcher's row order, parallel_for.h).
    RTD_HOST_DEVICE int tapRowStride() const { return stride; }

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const { filter<0>(x, y); }

    // One centre pixel's weighting terms and its sums over the taps so far.
    struct Centre {
        SvgfCentre weight;
        float stepX, stepY;  // the depth change over one tap step
        std::int32_t key;    // taps with the same key mix in (views.h)
        Float3 sum;
        float sumVar, sumW;
    };
    // The centre's terms, its sums holding the centre tap. step: the stride.
    RTD_HOST_DEVICE RTD_INLINE Centre centre(PixelIndex i, Float3 cI, float varianceI,
                                             int step) const {
        constexpr float kGauss[2] = {0.25f, 0.125f};  // 3x3: 1/4 centre, 1/8 edges, 1/16 corners
        const Layout& L = g.layout;
        float prefiltered = 0.0f, prefilterW = 0.0f;
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                PixelIndex j = i + L.offset(dx, dy);
                float k = (dx == 0 && dy == 0)   ? kGauss[0]
                          : (dx == 0 || dy == 0) ? kGauss[1]
                                                 : 0.0625f;
                float m = g.filterKey[j] >= 0 ? k : 0.0f;  // an object's
                prefiltered += m * in.at(3, j);
                prefilterW += m;
            }
        Float3 normalI;
        float depthI;
        loadNormalDepth<InterleavedGuide>(g, i, normalI, depthI);
        SvgfCentre w{
            depthI, normalI, luminance(cI),
            kLog2e /
                (terms.sigmaLuminance * std::sqrt(maxf(prefiltered / prefilterW, 0.0f)) + 1e-10f),
            guideNormalWeight(normalI)};
        return {w,
                derivatives.at(0, i) * float(step),
                derivatives.at(1, i) * float(step),
                g.filterKey[i],
                cI * kB3Centre,
                kB3Centre * kB3Centre * varianceI,
                kB3Centre};
    }
    // The depth term's scale for the taps at (ax, ay) and (-ax, -ay) tap steps away (one
    // division serves both; svgfDepthScale).
    RTD_HOST_DEVICE RTD_INLINE float depthScale(const Centre& c, int ax, int ay) const {
        return svgfDepthScale(terms, c.stepX * float(ax) + c.stepY * float(ay));
    }
    // Adds the tap at (ax, ay) tap steps (colour cj, its variance, guide, key) to the centre's
    // sums.
    RTD_HOST_DEVICE RTD_INLINE void addTap(Centre& c, int ax, int ay, float scale, Float3 cj,
                                           float varianceJ, Float3 nj, float zj,
                                           std::int32_t keyJ) const {
        float w = svgfWeight<FixedSigmaNormal>(terms, c.weight, scale, zj, nj, luminance(cj),
                                               log2B3(ax, ay));
        w = keyJ == c.key ? w : 0.0f;
        c.sum += cj * w;
        c.sumVar += w * w * varianceJ;
        c.sumW += w;
    }
    // Writes the filtered colour and variance, or the input where the centre is background.
    RTD_HOST_DEVICE RTD_INLINE void finish(int x, int y, PixelIndex i, const Centre& c,
                                           bool foreground, Float3 cI, float varianceI) const {
        float inv = 1.0f / c.sumW;  // >= (3/8)^2, the centre's
        Float3 filtered = c.sum * inv;
        // Per component (a selected vector would stop the CPU vectorising the kernel).
        store(x, y, i,
              make3(foreground ? filtered.x : cI.x, foreground ? filtered.y : cI.y,
                    foreground ? filtered.z : cI.z),
              foreground ? c.sumVar * inv * inv : varianceI);
    }

    // FixedStride > 0: the stride as a compile-time constant (as in Atrous::filter).
    template <int FixedStride>
    RTD_HOST_DEVICE RTD_INLINE void filter(int x, int y) const {
        const int step = FixedStride > 0 ? FixedStride : stride;
        const Layout& L = g.layout;
        PixelIndex i = L.index(x, y);
        // The key, not the object ID (-1 alike on background): one buffer of IDs read, not two.
        std::int32_t id = g.filterKey[i];
        Float3 cI = in.rgb().load(i);
        float varianceI = in.at(3, i);
        // Background passes through. The GPU's form (InterleavedGuide) skips its work by a
        // branch: a warp of background pixels then runs no taps. The CPU's, vectorised across
        // pixels, computes every lane and selects at the end: there a branch would mask every
        // load and blend of the taps (slower: docs/performance-cpu.md).
        const bool foreground = id >= 0;
        if constexpr (InterleavedGuide) {
            if (!foreground) {
                store(x, y, i, cI, varianceI);
                return;
            }
        }
        Centre c = centre(i, cI, varianceI, step);
        // The other 24 taps as 12 pairs at +offset and -offset, which share their kernel value
        // and their depth scale (one division per pair).
        RTD_UNROLL
        for (int pair = 0; pair < 12; ++pair) {
            int ax = pair % 5 - 2, ay = pair / 5 - 2;  // the taps before the centre, raster order
            float scale = depthScale(c, ax, ay);
            PixelIndex o = L.offset(ax * step, ay * step);
            RTD_UNROLL
            for (int side = 0; side < 2; ++side) {
                PixelIndex j = side == 0 ? i + o : i - o;
                Float3 nj;
                float zj;
                loadNormalDepth<InterleavedGuide>(g, j, nj, zj);
                addTap(c, side == 0 ? ax : -ax, side == 0 ? ay : -ay, scale, in.rgb().load(j),
                       in.at(3, j), nj, zj, g.filterKey[j]);
            }
        }
        finish(x, y, i, c, foreground, cI, varianceI);
    }

    // Two pixels of a column a stride apart, (x, y) and (x, y + Stride) (the GPU's form,
    // InterleavedGuide; y + Stride inside the image): their 5x5 taps share 20 places, so the
    // pair loads 30 taps where two pixels alone load 50. Every tap is evaluated in a couple whose
    // depth scales share one division (addCouple): a shared tap for both centres; A's row -2 with
    // B's row +2; the two centres, each a tap of the other, so that no depth scale stays live
    // across the taps (the per-centre form's timing: docs/performance-gpu.md). Each pixel gets
    // filter's result up to rounding.
    template <int Stride>
    RTD_HOST_DEVICE RTD_INLINE void filterPair(int x, int y) const {
        static_assert(InterleavedGuide && Stride > 0, "the GPU's form, at a fixed stride");
        const Layout& L = g.layout;
        const PixelIndex iA = L.index(x, y), iB = iA + L.offset(0, Stride);
        const bool foregroundA = g.filterKey[iA] >= 0, foregroundB = g.filterKey[iB] >= 0;
        const Tap centreA = tap(iA), centreB = tap(iB);
        if (!foregroundA && !foregroundB) {  // background passes through (as in filter)
            store(x, y, iA, centreA.color, centreA.variance);
            store(x, y + Stride, iB, centreB.color, centreB.variance);
            return;
        }
        Centre a = centre(iA, centreA.color, centreA.variance, Stride),
               b = centre(iB, centreB.color, centreB.variance, Stride);
        // A's row -2 with B's row +2 (rows -2 and 3 of A's).
        RTD_UNROLL
        for (int dx = -2; dx <= 2; ++dx)
            addCouple(a, dx, -2, tap(iA + L.offset(dx * Stride, -2 * Stride)), b, dx, 2,
                      tap(iA + L.offset(dx * Stride, 3 * Stride)));
        // Rows -1..2 of A's (-2..1 of B's), but for the centres.
        RTD_UNROLL
        for (int row = -1; row <= 2; ++row) {
            RTD_UNROLL
            for (int dx = -2; dx <= 2; ++dx) {
                if (dx == 0 && (row == 0 || row == 1)) continue;
                const Tap t = tap(iA + L.offset(dx * Stride, row * Stride));
                addCouple(a, dx, row, t, b, dx, row - 1, t);
            }
        }
        addCouple(a, 0, 1, centreB, b, 0, -1, centreA);
        finish(x, y, iA, a, foregroundA, centreA.color, centreA.variance);
        finish(x, y + Stride, iB, b, foregroundB, centreB.color, centreB.variance);
    }

  private:
    // filterPair's pieces: a tap's values, and two taps evaluated with one division.
    struct Tap {
        Float3 color, normal;
        float depth, variance;
        std::int32_t key;
    };
    RTD_HOST_DEVICE RTD_INLINE Tap tap(PixelIndex j) const {
        Tap t;
        t.color = in.rgb().load(j);
        loadNormalDepth<InterleavedGuide>(g, j, t.normal, t.depth);
        t.variance = in.at(3, j);
        t.key = g.filterKey[j];
        return t;
    }
    // Tap ta at (ax, ay) tap steps for centre a and tb at (bx, by) for b, their depth scales
    // (svgfDepthScale) from one division: log2(e) / (d_a d_b) times d_b, then d_a (as
    // pairExponents does for the course's filter).
    RTD_HOST_DEVICE RTD_INLINE void addCouple(Centre& a, int ax, int ay, const Tap& ta, Centre& b,
                                              int bx, int by, const Tap& tb) const {
        float dA = svgfDepthDenominator(terms, a.stepX * float(ax) + a.stepY * float(ay));
        float dB = svgfDepthDenominator(terms, b.stepX * float(bx) + b.stepY * float(by));
        float inverse = divideApprox(kLog2e, dA * dB);
        addTap(a, ax, ay, dB * inverse, ta.color, ta.variance, ta.normal, ta.depth, ta.key);
        addTap(b, bx, by, dA * inverse, tb.color, tb.variance, tb.normal, tb.depth, tb.key);
    }
};
using SvgfAtrousKernel = SvgfAtrous<-1>;  // any sigma_n
// sigma_n = 128 (the paper's and the default): the normal factor with no logarithm (svgfWeight).
using SvgfAtrousNormal128Kernel = SvgfAtrous<kPaperSigmaNormal>;
using SvgfAtrousModulatedKernel = SvgfAtrous<-1, true>;
using SvgfAtrousNormal128ModulatedKernel = SvgfAtrous<kPaperSigmaNormal, true>;
// The GPU's: any sigma_n (its log2 is one instruction), normal and depth interleaved.
using SvgfAtrousInterleavedKernel = SvgfAtrous<-1, false, true>;
using SvgfAtrousInterleavedModulatedKernel = SvgfAtrous<-1, true, true>;

}  // namespace rtd
