// The detail method's own kernels (methods/detail.cpp). Its history is the accumulated,
// unfiltered illumination, kept twice as in NVIDIA NRD's ReLAX: a long "slow" history (up to
// maxHistory frames) that holds the detail, and a short "fast" one (up to fastHistory frames)
// that follows lighting changes and bounds the slow one (DetailClamp). The variance, the
// short-history estimate and the A-Trous iterations are SVGF's kernels (svgf.h); what they are
// given differs: the variance of the accumulated mean rather than of one sample, so that the
// filter's luminance tolerance narrows as the history grows.
#pragma once

#include "kernels/convert.h"
#include "kernels/reproject.h"
#include "kernels/svgf.h"
#include "kernels/views.h"
#include "kernels/window_sums.h"

namespace rtd {

// The reprojected history handed from DetailReproject to DetailAccumulate in planes: slow rgb,
// fast rgb, luminance mean, luminance variance, length, stabilised output rgb, bright share.
constexpr int kDetailHistoryPlanes = 13;

struct DetailHistorySample {
    Float3 slow, fast;
    float mean = 0.0f, variance = 0.0f, length = 0.0f;
    Float3 stable;        // the previous frame's stabilised output (DetailStabilise); 0 without one
    float bright = 0.0f;  // the share of frames it was far above its firefly limit (aboveLimit)
};

// The previous frame's histories, weighted over the taps (the moments' variance includes the
// spread of the taps' means). WithStable: also the stabilised output (else stable stays 0), a
// kernel's compile-time choice: a run-time branch here stopped the CPU vectorising the
// reprojection.
template <bool WithStable = true, int kTaps>
RTD_HOST_DEVICE RTD_INLINE DetailHistorySample
gatherDetailHistory(const HistoryTaps<kTaps>& taps, const Planes3& previousSlow,
                    const Planes3& previousFast, const PlaneSet& previousMoments,
                    const float* previousLength, const Planes3& previousStable = {}) {
    float sr[kTaps], sg[kTaps], sb[kTaps], fr[kTaps], fg[kTaps], fb[kTaps];
    float means[kTaps], variances[kTaps], lengths[kTaps], brights[kTaps];
    loadTaps(previousSlow, taps, sr, sg, sb);
    loadTaps(previousFast, taps, fr, fg, fb);
    loadTaps(previousMoments.data, taps, means);
    loadTaps(&previousMoments.at(1, 0), taps, variances);
    loadTaps(&previousMoments.at(2, 0), taps, brights);
    loadTaps(previousLength, taps, lengths);
    DetailHistorySample s;
    RTD_UNROLL
    for (int t = 0; t < kTaps; ++t) {
        float w = taps.weight[t];
        s.slow += make3(sr[t], sg[t], sb[t]) * w;
        s.fast += make3(fr[t], fg[t], fb[t]) * w;
        s.mean += means[t] * w;
        s.length += lengths[t] * w;
        s.bright += brights[t] * w;
    }
    RTD_UNROLL
    for (int t = 0; t < kTaps; ++t)
        s.variance += (variances[t] + square(means[t] - s.mean)) * taps.weight[t];
    if constexpr (WithStable) {
        float r[kTaps], g[kTaps], b[kTaps];
        loadTaps(previousStable, taps, r, g, b);
        RTD_UNROLL
        for (int t = 0; t < kTaps; ++t) s.stable += make3(r[t], g[t], b[t]) * taps.weight[t];
    }
    return s;
}

// The previous frame's slow and fast colour, moments and history length at each pixel's
// back-projected position (0 where the history test fails). As SvgfReproject: Search3x3 = false
// runs on every pixel with the bilinear taps, Search3x3 = true then redoes the object pixels
// whose taps all failed with the 3x3 search (sparse).
template <bool Search3x3>
struct DetailReproject {
    static constexpr bool kSparse = Search3x3;  // the CPU launcher keeps it scalar
    GBufferView g;
    PreviousGeometry previous;
    const ObjectReprojection* objects;
    int objectCount;
    PlaneSet derivatives;
    HistoryTest test;
    Planes3 previousSlow, previousFast;
    PlaneSet previousMoments;  // 3 planes: luminance mean, variance, bright share
    const float* previousLength;
    PlaneSet history;  // out: kDetailHistoryPlanes
    std::uint8_t* validity;
    int hasHistory;
    // DetailStabilise's history (a signal without one: any 3 planes, e.g. previousSlow).
    Planes3 previousStable = {};

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
        DetailHistorySample s = sample<KnownId>(i, id, code);
        validity[i] = code;
        store(history, i, s);
    }
    RTD_HOST_DEVICE RTD_INLINE static void store(const PlaneSet& h, PixelIndex i,
                                                 const DetailHistorySample& s) {
        h.rgb().store(i, s.slow);
        h.rgb(3).store(i, s.fast);
        h.at(6, i) = s.mean;
        h.at(7, i) = s.variance;
        h.at(8, i) = s.length;
        h.rgb(9).store(i, s.stable);
        h.at(12, i) = s.bright;
    }
    RTD_HOST_DEVICE RTD_INLINE static DetailHistorySample load(const PlaneSet& h, PixelIndex i) {
        return {h.rgb().load(i), h.rgb(3).load(i), h.at(6, i), h.at(7, i),
                h.at(8, i),      h.rgb(9).load(i), h.at(12, i)};
    }
    // Search: the 3x3 search's taps rather than the bilinear ones.
    template <bool KnownId, bool Search = Search3x3>
    RTD_HOST_DEVICE RTD_INLINE DetailHistorySample sample(PixelIndex i, std::int32_t id,
                                                          std::uint8_t& code) const {
        auto taps = findHistory<Search, KnownId>(g, i, previous, objects, objectCount,
                                                 slopesAt(derivatives, i), test, hasHistory, id);
        code = taps.code;
        DetailHistorySample s = gatherDetailHistory(
            taps, previousSlow, previousFast, previousMoments, previousLength, previousStable);
        // The search's taps are a disocclusion's neighbours, not its own past: no output is
        // held there (DetailStabilise; its values are otherwise >= 0).
        if constexpr (Search) s.stable = make3(-1.0f, -1.0f, -1.0f);
        return s;
    }
};
using DetailReprojectKernel = DetailReproject<false>;
using DetailReprojectSearchKernel = DetailReproject<true>;

// Accumulation of the current (demodulated, despeckled) frame into both histories: equal weights
// up to each one's cap, then exponential. Where the caller gives a confidence c in [0, 1], the
// history length is scaled by c first (c = 0: the history is dropped), as NRD does.
// WithConfidence: the form that reads it (its per-pixel type switch keeps the CPU's loop
// scalar, so the form without it, for frames without one, vectorises).
template <bool WithConfidence>
struct DetailAccumulate {
    GBufferView g;
    Planes3 radiance;
    PlaneSet history;  // DetailReproject's output
    const std::uint8_t* validity;
    InputSpan confidence;  // data null: none
    Planes3 slow, fast;    // out (histories)
    PlaneSet moments;      // out (history), 3 planes: luminance mean, variance, bright share
    float* length;         // out (history): frames in the slow history, 1 after a disocclusion
    float maxHistory, fastHistory, momentsAlpha;
    Planes3 heldStable = {};  // out: the reprojected stabilised output (DetailStabilise); or null
    // The frame before the firefly removal, and where that saw a pixel far above its limit (1,
    // else 0: aboveLimit; all 0 without the removal, whose `raw` is then `radiance`). Out:
    // `radiance` holds the value accumulated (the raw one at a light), for the passes after.
    Planes3 raw = {};
    const float* above = nullptr;
    // A light seen directly is far above its firefly limit frame after frame; a firefly seldom
    // hits a pixel twice running. The share of frames above (an average with kAboveWeight for
    // the current frame) reaching kLightShare (the last frame above, or two of the last three)
    // makes the pixel a light: its raw value is accumulated (lights a pixel or two wide were
    // lost as fireflies: docs/energy.md). The luminance moments stay the despeckled
    // value's: a light's swing (a pixel it half covers) would widen its neighbours' filter.
    static constexpr float kAboveWeight = 0.5f, kLightShare = 0.4f;

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        PixelIndex i = g.layout.index(x, y);
        DetailHistorySample s = DetailReprojectKernel::load(history, i);
        float h = validity[i] == kReprojectionValid ? s.length : 0.0f;
        if constexpr (WithConfidence) h *= loadConfidence(confidence, x, y);
        accumulate(i, s, h);
    }
    RTD_HOST_DEVICE RTD_INLINE void accumulate(PixelIndex i, const DetailHistorySample& s,
                                               float h) const {
        const bool object = g.objectId[i] >= 0;
        const Float3 despeckled = radiance.load(i);
        const float heldBright = h > 0.0f ? s.bright : 0.0f;  // dropped with the history
        const Float3 current = select3(heldBright >= kLightShare, raw.load(i), despeckled);
        radiance.store(i, current);
        moments.at(2, i) = object ? heldBright + kAboveWeight * (above[i] - heldBright) : 0.0f;
        float hs = minf(h + 1.0f, maxHistory), hf = minf(h + 1.0f, fastHistory);
        float as = 1.0f / hs, af = 1.0f / hf, am = maxf(momentsAlpha, as);
        float d = luminance(despeckled) - s.mean;
        slow.store(i, s.slow * (1.0f - as) + current * as);
        fast.store(i, s.fast * (1.0f - af) + current * af);
        moments.at(0, i) = object ? s.mean + am * d : 0.0f;
        moments.at(1, i) = object ? (1.0f - am) * (s.variance + am * d * d) : 0.0f;
        length[i] = object ? hs : 0.0f;
        if (heldStable.data) heldStable.store(i, s.stable);
    }
};
using DetailAccumulateKernel = DetailAccumulate<false>;
using DetailAccumulateConfidenceKernel = DetailAccumulate<true>;

// History clamping, anti-lag and the A-Trous input, over each pixel's 5x5 window of object
// pixels (window sums of the fast history and of the current frame's luminance):
// - anti-lag (antiLag): where the current frame's mean differs from the fast history's by more
//   than 2 standard errors of the current mean, the lighting changed. The history length is
//   cut by (1 - change)^8 (SVGF's cut, squared: the slow history is 32 frames, not 5), the slow
//   history blended again with the current frame for that length, and both histories scaled
//   towards the current level by the ratio of the means to the power min(1, 3 change);
// - the clamp: the slow history into the fast one's mean +- clampSigma standard deviations, per
//   channel, a box grown to hold this frame's own value (a small light's history lies far above
//   its window's box, and its light is its own); where that moved it, the history length is cut
//   towards the fast history's in proportion to the move over the box's half width.
// Writes the slow history and the length in place, the ratio for the fast history
// (DetailScaleKernel) and the filter input: rgb + the variance of the accumulated mean (the
// luminance moments' variance over the history length).
struct DetailClampKernel {
    GBufferView g;
    Planes3 current;       // this frame's (demodulated, despeckled) radiance
    PlaneSet fastSums;     // ColorRowSumsKernel over the fast history, radius kRadius
    PlaneSet currentSums;  // LuminanceRowSumsKernel over this frame's radiance, radius kRadius
    Planes3 slow;          // in and out
    PlaneSet moments;      // in and out
    float* length;         // in and out
    PlaneSet filterIn;     // out: rgb + variance
    float* lagScale;       // out: the anti-lag's colour ratio (1: none), for the fast history
    float clampSigma;      // 0: no clamp
    float fastHistory;
    float momentsAlpha;  // DetailAccumulate's
    int antiLag;         // 1: on
    // The anti-lag's threshold in standard errors of the current 5x5 mean: 3 missed most of a
    // light switched on (a bright 1-spp frame's noise hid the jump; docs/quality.md).
    static constexpr float kLagStandardErrors = 2.0f;
    static constexpr int kRadius = 2;

    // Branch-free (every pixel computes every term; selects pick the outputs) so the CPU
    // vectorises it across pixels.
    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        const Layout& L = g.layout;
        PixelIndex i = L.index(x, y);
        const bool object = g.objectId[i] >= 0;
        const Float3 c0 = slow.load(i);
        const float h0 = length[i];
        ColorWindowStats fastWindow =
            colorWindowStats<kNarrowWindow>(fastSums, i, L.pitch, kRadius);
        const float n = maxf(columnSum<kNarrowWindow>(currentSums, 0, i, L.pitch, kRadius), 1.0f);
        const float currentMean = columnSum<kNarrowWindow>(currentSums, 1, i, L.pitch, kRadius) / n;
        const float currentSquares =
            columnSum<kNarrowWindow>(currentSums, 2, i, L.pitch, kRadius) / n;
        Float3 mean = fastWindow.mean;
        float h = h0;
        // Anti-lag: the change beyond kLagStandardErrors standard errors of the current mean,
        // relative.
        float currentSigma = std::sqrt(maxf(currentSquares - square(currentMean), 0.0f));
        float fastMean = luminance(mean);
        float gap = maxf(
            absf(currentMean - fastMean) - kLagStandardErrors * currentSigma / std::sqrt(n), 0.0f);
        float change = antiLag ? minf(gap / maxf(maxf(currentMean, fastMean), 1e-4f), 1.0f) : 0.0f;
        // (current / fast)^min(1, 3 change) as 2^(e log2 r): exp2Negative of -|e| and, for a
        // positive e, its reciprocal.
        float e = minf(1.0f, 3.0f * change) *
                  log2Positive(maxf(currentMean, 1e-6f) / maxf(fastMean, 1e-6f));
        float p = exp2Negative(-absf(e));
        float ratio = change > 0.0f ? (e <= 0.0f ? p : 1.0f / p) : 1.0f;
        h *= square(square(square(1.0f - change)));
        Float3 c = c0 * ratio;
        // The slow history was accumulated with weight 1 - 1/h0 (DetailAccumulate); the anti-lag
        // blends it again with 1 - 1/h for the cut length h, so that the current frame carries
        // the new lighting's pattern at once (a scaled history only keeps the old one's level).
        const float hNew = maxf(h, 1.0f);
        const float keep = h0 > 1.0f ? (1.0f - 1.0f / hNew) / (1.0f - 1.0f / h0) : 0.0f;
        const Float3 now = current.load(i);
        const Float3 reblended =
            now * (1.0f / hNew) + (c0 - now * (1.0f / maxf(h0, 1.0f))) * (ratio * keep);
        c = select3(change > 0.0f, reblended, c);
        // The luminance moments likewise: those from before this frame's accumulation (whose
        // weight was am0) are recovered, scaled to the new level and accumulated again with the
        // cut length's weight. Kept as they were, they hold the change itself as variance, and
        // the next frames' filter blurs over edges by it.
        const float lum = luminance(now);
        const float m1 = moments.at(0, i), v1 = moments.at(1, i);
        const float am0 = maxf(momentsAlpha, 1.0f / maxf(h0, 1.0f));
        const float keepMoments = maxf(1.0f - am0, 1e-3f);
        const float m0Before = (m1 - am0 * lum) / keepMoments;
        const float v0Before = maxf(v1 / keepMoments - am0 * square(lum - m0Before), 0.0f);
        const float m0 = m0Before * ratio, v0 = v0Before * (ratio * ratio);
        const float am1 = maxf(momentsAlpha, 1.0f / hNew), dm = lum - m0;
        // (At am0 = 1 the accumulation kept nothing of them, and m1, v1 are already lum, 0.)
        const bool recover = change > 0.0f && 1.0f - am0 > 1e-3f;
        const float meanAfter = recover ? m0 + am1 * dm : m1;
        const float varianceAfter = recover ? (1.0f - am1) * (v0 + am1 * dm * dm) : v1;
        mean = mean * ratio;
        // The clamp to the fast history's box.
        Float3 half = fastWindow.sigma * (ratio * clampSigma);
        Float3 clamped = clampToBoxHolding(c, mean - half, mean + half, now);
        float moved = absf(luminance(clamped) - luminance(c));
        float t = clampSigma > 0.0f ? minf(moved / (luminance(half) + 1e-6f), 1.0f) : 0.0f;
        h = minf(h, h + (minf(h, fastHistory) - h) * t);
        const bool clamp = clampSigma > 0.0f;
        c = select3(clamp, clamped, c);
        c = select3(object, c, c0);
        h = object ? maxf(h, 1.0f) : h0;
        slow.store(i, c);
        length[i] = h;
        lagScale[i] = object ? ratio : 1.0f;
        filterIn.rgb().store(i, c);
        moments.at(0, i) = object ? meanAfter : m1;
        moments.at(1, i) = object ? varianceAfter : v1;
        filterIn.at(3, i) = object ? varianceAfter / h : 0.0f;
    }
};

// The anti-lag's ratio applied to the fast history (after DetailClamp, which reads it around
// each pixel).
struct DetailScaleKernel {
    Layout layout;
    Planes3 fast;
    const float* lagScale;
    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        PixelIndex i = layout.index(x, y);
        fast.store(i, fast.load(i) * lagScale[i]);
    }
};

// The short-history estimate (SvgfVariance's colour, the temporal one elsewhere) written back
// into the slow history, as ReLAX's history fix does: the next frames accumulate onto a
// denoised start rather than onto one or two raw samples. Block-sparse on the CPU (pixels whose
// history is shorter than `below`); elsewhere the two are equal, so every pixel may copy.
struct DetailHistoryFixKernel {
    Layout layout;
    PlaneSet estimate;  // rgb + variance
    Planes3 slow;       // out; data null: no history fix
    const float* length;
    float below;  // SvgfVariance's fadeUntil
    RTD_HOST_DEVICE RTD_INLINE bool active(int x, int y) const {
        return length[layout.index(x, y)] < below;
    }
    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        PixelIndex i = layout.index(x, y);
        slow.store(i, estimate.rgb().load(i));
    }
};

// The output's stabilisation (NVIDIA NRD ReBLUR's temporal stabilisation, simplified): the
// filtered illumination blended with the previous frame's stabilised one, clamped first to the
// current 3x3 neighbourhood's mean +- clampSigma standard deviations (same filter key; the box
// grown to hold the pixel's own value), so
// that the residual noise of a narrowed filter does not flicker from frame to frame. Only where
// a history was found and kept and the anti-lag did not fire (a change passes at once). Writes the
// stabilised illumination (its history) and the output, times the albedo.
struct DetailStabiliseKernel {
    GBufferView g;
    PlaneSet current;              // the last A-Trous iteration's rgb (+ variance)
    Planes3 held;                  // DetailAccumulate's heldStable (< 0: none)
    const std::uint8_t* validity;  // DetailReproject's codes
    const float* lagScale;         // DetailClamp's: 1 where the anti-lag did not fire
    const float* length;           // the history's length: 1 where none was kept (a caller's
                                   // confidence of 0 too)
    Planes3 stable;                // out (history)
    Planes3 albedo;
    float* rgbOut;     // interleaved, 3 floats per pixel
    float blend;       // [0, 1) share of the previous frame's
    float clampSigma;  // [> 0] the clamp's half width, standard deviations
    // Where the pixel moved, the share falls: blend / (1 + motionFalloff * pixels moved).
    PreviousGeometry previous;
    const ObjectReprojection* objects;
    int objectCount;
    float motionFalloff;  // [>= 0] per pixel of motion

    // How far the pixel moved since the previous frame, in pixels (previousPixel, as
    // findHistory finds it).
    RTD_HOST_DEVICE RTD_INLINE float motionAt(int x, int y, PixelIndex i) const {
        if (objectCount <= 0) return 0.0f;  // no matrices: no history either (nothing held)
        const std::int32_t id = g.objectId[i];
        const bool covered = id >= 0 && id < objectCount;
        const PreviousPixel before =
            previousPixel(g, i, previous, objectEntry(objects, id, covered, previous));
        const float d = std::sqrt(square(before.x - float(x)) + square(before.y - float(y)));
        return d < 3.0e38f ? d : 3.0e38f;  // NaN: far
    }

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        const Layout& L = g.layout;
        const PixelIndex i = L.index(x, y);
        const std::int32_t key = g.filterKey[i];
        const Float3 c = current.rgb().load(i);
        Float3 sum, squares;
        float n = 0.0f;
        RTD_UNROLL
        for (int dy = -1; dy <= 1; ++dy) {
            RTD_UNROLL
            for (int dx = -1; dx <= 1; ++dx) {
                const PixelIndex j = i + L.offset(dx, dy);
                const float m = g.filterKey[j] == key ? 1.0f : 0.0f;
                const Float3 v = current.rgb().load(j) * m;
                sum += v;
                squares += v * v;
                n += m;
            }
        }
        const float inverse = 1.0f / maxf(n, 1.0f);
        const Float3 mean = sum * inverse;
        const Float3 variance = squares * inverse - mean * mean;
        const Float3 half =
            make3(std::sqrt(maxf(variance.x, 0.0f)), std::sqrt(maxf(variance.y, 0.0f)),
                  std::sqrt(maxf(variance.z, 0.0f))) *
            clampSigma;
        const Float3 heldHere = held.load(i);
        const Float3 previousValue = clampToBoxHolding(heldHere, mean - half, mean + half, c);
        const bool holds = key >= 0 && validity[i] == kReprojectionValid && length[i] > 1.0f &&
                           lagScale[i] == 1.0f && heldHere.x >= 0.0f;
        const float share = blend / (1.0f + motionFalloff * motionAt(x, y, i));
        const Float3 out = select3(holds, c + (previousValue - c) * share, c);
        stable.store(i, out);
        storeModulated(L, rgbOut, x, y, out * albedo.load(i));
    }
};

// ---- the split signal (FrameBinding::specular) ----

// A finite, non-negative value of the caller's (NaN, Inf and negatives read as 0).
RTD_HOST_DEVICE RTD_INLINE float finiteNonNegative(float v) {
    return v >= 0.0f && v < 3.0e38f ? v : 0.0f;
}

// The ingest's demodulated beauty into its two signals: the diffuse one (beauty - specular,
// demodulated: noisy - specular / albedo, written in place) and the specular one (not
// demodulated: its colour is the lobe's, not the texture's).
// Also the lobe's roughness and hit distance, read once here into planes (lobe) for
// DetailSpecularReproject (a caller's buffer's per-pixel type switch would keep that kernel's
// CPU loop scalar), and the specular passes' object IDs and filter keys: the frame's where the
// lobe is kept apart, -1 elsewhere. Those pixels' specular signal is 0: its passes skip them
// (WhereKeyed on the CPU), and neither the reprojection nor the filters take them in.
struct DetailSplitKernel {
    Layout layout;
    Planes3 noisy;   // in: beauty / albedo; out: the diffuse signal
    Planes3 albedo;  // the ingest's factor (floored at its epsilon, 1 on background)
    InputSpan specular;
    InputSpan roughness;    // NaN: rough (the lobe goes to the diffuse signal)
    InputSpan hitDistance;  // data null: none
    const std::int32_t* objectId;
    const std::int32_t* filterKey;
    Planes3 specularOut;
    PlaneSet lobe;  // out: roughness in [0, 1] (NaN: 1), hit distance (0: none or not finite)
    std::int32_t* lobeId;   // out: objectId where the lobe is kept apart, else -1
    std::int32_t* lobeKey;  // out: filterKey likewise
    // A rough lobe's reflection is as blurred as the diffuse light: between these roughnesses it
    // goes over into the diffuse signal, whose history and filter it then shares (filtered
    // apart, a rough lobe's 1-spp samples add noise: docs/quality.md).
    static constexpr float kSpecularUpTo = 0.3f, kDiffuseFrom = 0.45f;

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        PixelIndex i = layout.index(x, y);
        const float r = unitNanAsOne(roughness.load(x, y, 0));
        const float keep =
            r > kSpecularUpTo
                ? maxf(0.0f, minf(1.0f, (kDiffuseFrom - r) / (kDiffuseFrom - kSpecularUpTo)))
                : 1.0f;
        Float3 s = make3(finiteNonNegative(specular.load(x, y, 0)),
                         finiteNonNegative(specular.load(x, y, 1)),
                         finiteNonNegative(specular.load(x, y, 2))) *
                   keep;
        Float3 n = noisy.load(i), a = albedo.load(i);
        noisy.store(i, make3(maxf(n.x - s.x / a.x, 0.0f), maxf(n.y - s.y / a.y, 0.0f),
                             maxf(n.z - s.z / a.z, 0.0f)));
        specularOut.store(i, s);
        lobe.at(0, i) = r;
        lobe.at(1, i) = hitDistance.data ? finiteNonNegative(hitDistance.load(x, y, 0)) : 0.0f;
        const bool kept = keep > 0.0f;
        lobeId[i] = kept ? objectId[i] : -1;
        lobeKey[i] = kept ? filterKey[i] : -1;
    }
};

// The specular signal's history, after DetailReproject has followed the surface (NVIDIA NRD's
// specular reprojection, simplified): where the caller gives the specular ray's hit distance
// (and matrices), the reflection is followed instead: its virtual point, the hit distance
// behind the surface along the view ray, is projected into the previous frame with the
// object's matrix, and the history taken there where the previous frame shows the same object
// with a like normal ("virtual motion", exact for a planar mirror). Elsewhere the surface's
// history stays, its length capped by the parallax: a reflection drifts over its surface as the
// view moves, the less so the rougher the lobe. Run where the frame has a history and objects.
// Branch-free (every pixel computes both ways; selects pick what is stored) over runs of one
// object (KeyedRuns, as DetailReproject), so the CPU vectorises it.
// SurfaceAfter (frames with a hit distance, where the reflection is followed almost everywhere):
// the surface's history is not read; where the reflection is not followed the pixel is marked
// kReprojectionPending, and DetailSpecularSurface finds the surface's history there alone.
template <bool SurfaceAfter>
struct DetailSpecularReproject {
    GBufferView g;
    PreviousGeometry previous;
    const ObjectReprojection* objects;
    int objectCount;
    Planes3 previousSlow, previousFast;
    PlaneSet previousMoments;
    const float* previousLength;
    PlaneSet history;  // in: DetailReproject's; out: the reflection's where it holds, capped
    std::uint8_t* validity;
    PlaneSet lobe;  // DetailSplit's: roughness, hit distance (0: none)
    Float3 cameraPosition;
    float maxHistory;
    // Surface history frames kept per pixel of parallax at roughness 0 (x (1 - r)^2).
    static constexpr float kParallaxFrames = 8.0f;
    static constexpr float kNormalAgreement = 0.9f;  // cosine between now and then

    // The surface's curvature at i (1 / radius), from the normal's and the position's change to
    // the neighbours on the same object: a convex mirror's virtual image is nearer than the hit.
    // Both neighbours are loaded and one picked (on the CPU contiguous loads, not gathers).
    RTD_HOST_DEVICE RTD_INLINE float curvatureAt(PixelIndex i, PixelIndex step, std::int32_t id,
                                                 Float3 normal, Float3 position) const {
        const bool forward = g.objectId[i + step] == id;
        const bool same = forward || g.objectId[i - step] == id;
        const Float3 dn =
            select3(forward, g.normal.load(i + step), g.normal.load(i - step)) - normal;
        const Float3 dp =
            select3(forward, g.position.load(i + step), g.position.load(i - step)) - position;
        const float dp2 = dot(dp, dp);
        return same && dp2 > 0.0f ? std::sqrt(dot(dn, dn) / maxf(dp2, 1e-30f)) : 0.0f;
    }

    // The surface history's length at (x, y), capped by the parallax where the object is live
    // (an ID the matrices do not cover reads object 0, then keeps its history).
    RTD_HOST_DEVICE RTD_INLINE float surfaceLength(int x, int y, PixelIndex i,
                                                   const ObjectReprojection& object, bool live,
                                                   float length) const {
        // Where the surface was (the parallax is measured against it).
        const Float4 s = transformPoint(object.currentWorldToPreviousScreen, g.position.load(i));
        const float inverseS = 1.0f / (s.w > 0.0f ? s.w : 1.0f);
        const float surfaceX = s.x * inverseS - 0.5f, surfaceY = s.y * inverseS - 0.5f;
        const float parallax = std::sqrt(square(surfaceX - float(x)) + square(surfaceY - float(y)));
        const float cap =
            maxHistory / (1.0f + kParallaxFrames * parallax * square(1.0f - lobe.at(0, i)));
        return live ? minf(length, maxf(cap - 1.0f, 0.0f)) : length;
    }
    RTD_HOST_DEVICE RTD_INLINE float surfaceLength(int x, int y, PixelIndex i, float length) const {
        const std::int32_t id = g.objectId[i];
        const bool covered = id >= 0 && id < objectCount;
        const ObjectReprojection& object = objectEntry(objects, id, covered, previous);
        return surfaceLength(x, y, i, object, covered && object.valid, length);
    }

    RTD_HOST_DEVICE RTD_INLINE std::int32_t runKey(int x, int y) const {
        return g.objectId[g.layout.index(x, y)];
    }
    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const { pixel<false>(x, y, 0); }
    template <bool KnownId>
    RTD_HOST_DEVICE RTD_INLINE void pixel(int x, int y, std::int32_t knownId) const {
        const Layout& L = g.layout;
        const PixelIndex i = L.index(x, y);
        const std::int32_t id = KnownId ? knownId : g.objectId[i];
        // An ID the matrices do not cover reads object 0, then keeps its history.
        const bool covered = id >= 0 && id < objectCount;
        const ObjectReprojection& object = objectEntry(objects, id, covered, previous);
        const bool live = covered && object.valid;
        const Float3 position = g.position.load(i);
        // A convex mirror of curvature k focuses at f = 1 / (2k): the image of a point at
        // distance d lies d f / (d + f) behind it (the thin-lens equation, as NRD applies it):
        // a sphere's reflection moves almost with its surface.
        float distance = lobe.at(1, i);
        const Float3 normal = g.normal.load(i);
        const float k = maxf(curvatureAt(i, 1, id, normal, position),
                             curvatureAt(i, L.pitch, id, normal, position));
        const float focal = 0.5f / maxf(k, 1e-6f);
        distance = distance * focal / (distance + focal);
        const Float3 view = normalize(position - cameraPosition);
        const Float4 v =
            transformPoint(object.currentWorldToPreviousScreen, position + view * distance);
        const float inverseV = 1.0f / (v.w > 0.0f ? v.w : 1.0f);
        float vx = v.x * inverseV - 0.5f, vy = v.y * inverseV - 0.5f;
        const bool onScreen = live && distance > 0.0f && !previous.fromMotion && v.w > 0.0f &&
                              vx > -1.0f && vx < float(L.width) && vy > -1.0f &&
                              vy < float(L.height);
        vx = onScreen ? vx : 0.0f;  // in range (NaN too) before the conversion to int
        vy = onScreen ? vy : 0.0f;
        const Float3 expectedNormal =
            normalize(transformVector(object.currentWorldToPreviousWorld, normal));
        const float fx = std::floor(vx), fy = std::floor(vy);
        const int x0 = int(fx), y0 = int(fy);
        const float ax = vx - fx, ay = vy - fy;
        HistoryTaps<4> taps;
        RTD_UNROLL
        for (int t = 0; t < 4; ++t) taps.index[t] = L.index(x0 + (t & 1), y0 + (t >> 1));
        std::int32_t previousId[4];
        float nx[4], ny[4], nz[4];
        loadTaps(previous.objectId, taps, previousId);  // in pairs of neighbours
        loadTaps(previous.normal, taps, nx, ny, nz);
        float total = 0.0f;
        RTD_UNROLL
        for (int t = 0; t < 4; ++t) {
            bool ok = onScreen && previousId[t] == id &&
                      dot(make3(nx[t], ny[t], nz[t]), expectedNormal) > kNormalAgreement;
            float w = ((t & 1) ? ax : 1.0f - ax) * ((t >> 1) ? ay : 1.0f - ay);
            taps.weight[t] = ok ? w : 0.0f;
            total += taps.weight[t];
        }
        const bool followed = total > 1e-3f;
        const float inverseTotal = 1.0f / maxf(total, 1e-3f);
        RTD_UNROLL
        for (int t = 0; t < 4; ++t) taps.weight[t] *= inverseTotal;
        const DetailHistorySample reflected = gatherDetailHistory<false>(
            taps, previousSlow, previousFast, previousMoments, previousLength);
        if constexpr (SurfaceAfter) {
            DetailReprojectKernel::store(history, i, reflected);
            validity[i] = followed  ? std::uint8_t(kReprojectionValid)
                          : id >= 0 ? std::uint8_t(kReprojectionPending)
                                    : validity[i];
            return;
        }
        DetailHistorySample surface = DetailReprojectKernel::load(history, i);
        surface.length = surfaceLength(x, y, i, object, live, surface.length);
        DetailHistorySample out;
        out.slow = select3(followed, reflected.slow, surface.slow);
        out.fast = select3(followed, reflected.fast, surface.fast);
        out.mean = followed ? reflected.mean : surface.mean;
        out.variance = followed ? reflected.variance : surface.variance;
        out.length = followed ? reflected.length : surface.length;
        out.bright = followed ? reflected.bright : surface.bright;
        DetailReprojectKernel::store(history, i, out);
        validity[i] = followed ? std::uint8_t(kReprojectionValid) : validity[i];
    }
};

using DetailSpecularReprojectKernel = DetailSpecularReproject<false>;
using DetailSpecularFollowKernel = DetailSpecularReproject<true>;

// After DetailSpecularFollow: the surface's history (the bilinear taps, else the 3x3 search)
// capped by the parallax, on the pixels whose reflection could not be followed
// (kReprojectionPending: disocclusions, the screen's edges; few, so sparse).
struct DetailSpecularSurfaceKernel {
    static constexpr bool kSparse = true;  // the CPU launcher keeps it scalar
    DetailReprojectKernel surface;         // its history and validity: the specular stage's
    DetailSpecularFollowKernel specular;   // the parallax cap

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        const PixelIndex i = surface.g.layout.index(x, y);
        if (surface.validity[i] != kReprojectionPending) return;
        std::uint8_t code;
        DetailHistorySample s = surface.sample<false>(i, 0, code);
        if (code == kReprojectionOtherObject) s = surface.sample<false, true>(i, 0, code);
        s.length = specular.surfaceLength(x, y, i, s.length);
        surface.validity[i] = code;
        DetailReprojectKernel::store(surface.history, i, s);
    }
};

// The filtered specular signal added to the output (where the diffuse one was written), where
// key >= 0 (DetailSplitKernel::lobeKey: elsewhere the specular passes left `add` unspecified).
struct AddToOutputKernel {
    Layout layout;
    Planes3 add;
    const std::int32_t* key;
    float* rgbOut;  // interleaved, 3 floats per pixel
    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        PixelIndex s = PixelIndex(y) * layout.width + x;
        const PixelIndex i = layout.index(x, y);
        const Float3 a = select3(key[i] >= 0, add.load(i), Float3{});
        rgbOut[3 * s] += a.x;
        rgbOut[3 * s + 1] += a.y;
        rgbOut[3 * s + 2] += a.z;
    }
};

}  // namespace rtd
